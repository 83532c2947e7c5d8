//! Image textures: a parameter that varies over a surface.
//!
//! A texture is an image file (PNG or JPEG) read with the `image` crate, or
//! an image inside a glTF file. It is decoded once, at load, by the
//! [`Encoding`] its use needs: colours (base colour, emissive; OBJ/MTL
//! `map_Kd`, glTF's `baseColorTexture`) are sRGB-encoded and decoded to
//! linear RGB with the IEC 61966-2-1 curve ([`srgb_decode`]); data
//! (metallic-roughness, occlusion, normals) are read as stored, `b/255`.
//! Filtering and shading then happen on linear values. One image used both
//! ways is decoded twice; one decoding is shared (`Arc`) by every material
//! and sampler that uses it ([`crate::materials::texture_slot`]). Alpha,
//! where the image has it, is kept apart as it is (alpha is linear
//! coverage, never sRGB-encoded), mip-mapped with the colour and filtered
//! the same way ([`Texture::sample_alpha`], [`Texture::lookup_alpha`]).
//!
//! **Coordinates.** `(u, v)` with `u` to the right and `v` *down* the image:
//! `(0, 0)` is the upper-left corner of the upper-left texel, `(1, 1)` the
//! lower-right corner of the lower-right one (glTF's convention; an OBJ file's
//! `vt` has `v` up and is flipped when the mesh is loaded, [`crate::geometry::mesh`]).
//!
//! **Filtering.** Bilinear between the four texel centres around the point:
//! with `x = u·W − ½` and `y = v·H − ½`, the texels `⌊x⌋, ⌊x⌋+1` and
//! `⌊y⌋, ⌊y⌋+1` are weighted by the fractional parts (pbrt-v4 §10.4.3,
//! `Bilerp`). **Wrapping** is by default glTF's `REPEAT`: texel indices are
//! taken modulo the size, so `u = 1.25` is `u = 0.25` and the filter wraps
//! across the border. glTF's other modes are there too ([`Wrap`]), per axis.
//! glTF's `NEAREST` filter reads the texel the point falls in.
//!
//! **Mip-maps.** A texture seen from afar covers many texels per pixel, and
//! one bilinear lookup per ray would alias (moiré). Each texture keeps a
//! mip-map pyramid (Williams, "Pyramidal Parametrics", 1983), built once in
//! linear space: each level halves the one above by a box filter that is
//! exact for odd sizes too (an odd side n halves to ⌊n/2⌋ texels, each the
//! mean of a span of n/⌊n/2⌋ source texels). [`Texture::lookup`] reads
//! the level the ray's footprint asks for
//! ([`crate::materials::texture_lod`]), blending the two around it
//! (trilinear). The pyramid costs a third more memory than the image.

use std::path::{Path, PathBuf};

use crate::materials::texture_slot::{Encoding, Filter, Sampler, Wrap};
use crate::math::color::Color;
use crate::math::real::{Real, to_f64};

/// Largest texture side accepted, in texels: the decoder refuses a larger
/// image before allocating it (and the `image` crate's own limit on one
/// decode's allocation, 512 MiB, applies too).
pub const MAX_TEXTURE_SIDE: u32 = 16384;

/// Why a texture could not be read.
#[derive(Debug, thiserror::Error)]
pub enum TextureError {
    /// The file could not be opened or decoded.
    #[error("cannot read texture {path}: {reason}")]
    Read {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        reason: String,
    },
    /// The image has no texels.
    #[error("texture {path} is {width}×{height}: it has no texels")]
    Size {
        /// The image file.
        path: PathBuf,
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
}

/// One level of a mip-map pyramid: `width × height` linear texels, row by
/// row from the top.
#[derive(Clone, Debug, PartialEq)]
struct Level {
    width: u32,
    height: u32,
    texels: Vec<Color>,
    /// The alpha channel, one value per texel, or empty when the image has
    /// none (alpha 1 everywhere).
    alpha: Vec<f32>,
}

/// The value at integer coordinates `(i, j)` of a `w × h` grid of `values`
/// (row by row from the top), wrapped.
#[inline]
fn wrapped<T: Copy>(values: &[T], w: i64, h: i64, wrap: [Wrap; 2], i: i64, j: i64) -> T {
    values[(wrap[1].index(j, h) * w + wrap[0].index(i, w)) as usize]
}

/// A far coordinate brought back by whole mirrored periods (`n` texels on
/// its axis), so its integer part stays exact; clamped under `ClampToEdge`.
fn reduce(x: f64, n: f64, wrap: Wrap) -> f64 {
    match wrap {
        Wrap::ClampToEdge => x.clamp(-1.0, n),
        _ => x.rem_euclid(2.0 * n),
    }
}

impl Level {
    /// The value in `values` (this level's texels or alpha) that `(u, v)`
    /// falls in (glTF's `NEAREST`).
    fn nearest<T: Copy>(&self, values: &[T], wrap: [Wrap; 2], u: f64, v: f64) -> T {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (x, y) = ((u * w).floor(), (v * h).floor());
        if !(x.is_finite() && y.is_finite()) {
            return values[0];
        }
        let (i, j) = (reduce(x, w, wrap[0]) as i64, reduce(y, h, wrap[1]) as i64);
        wrapped(values, i64::from(self.width), i64::from(self.height), wrap, i, j)
    }

    /// The bilinear filter over `values` (this level's texels or alpha) at
    /// `(u, v)` (see the module documentation).
    fn bilinear<T>(&self, values: &[T], wrap: [Wrap; 2], u: f64, v: f64) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        let (x, y) = (u * w - 0.5, v * h - 0.5);
        if !(x.is_finite() && y.is_finite()) {
            return values[0];
        }
        let (x, y) = (reduce(x, w, wrap[0]), reduce(y, h, wrap[1]));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (i, j) = (x0 as i64, y0 as i64);
        let at = |i, j| wrapped(values, i64::from(self.width), i64::from(self.height), wrap, i, j);
        let top = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
        let bottom = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The next level down: each side halved (rounded down, at least 1) by
    /// a box filter — `2×2` texels averaged for even sides; for an odd side
    /// n, output texel `i` averages the source span `[i·n/m, (i+1)·n/m)`
    /// (m = ⌊n/2⌋), the texels at its ends weighted by how much of them it
    /// covers, so no texel is dropped and the mean is kept exactly. Alpha,
    /// where there is some, is halved the same way.
    fn halved(&self) -> Level {
        let (w2, h2) = ((self.width / 2).max(1), (self.height / 2).max(1));
        Level {
            width: w2,
            height: h2,
            texels: halve(&self.texels, self.width as usize, self.height as usize, Color::ZERO),
            alpha: if self.alpha.is_empty() {
                Vec::new()
            } else {
                halve(&self.alpha, self.width as usize, self.height as usize, 0.0)
            },
        }
    }
}

/// A `w × h` grid of `values` box-filtered to `max(w/2, 1) × max(h/2, 1)`
/// ([`Level::halved`]), rows first, then columns.
fn halve<T>(values: &[T], w: usize, h: usize, zero: T) -> Vec<T>
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let (w2, h2) = ((w / 2).max(1), (h / 2).max(1));
    let rows: Vec<T> = (0..h).flat_map(|j| box_resample(&values[j * w..(j + 1) * w], w2, zero)).collect();
    let mut out = vec![zero; w2 * h2];
    for i in 0..w2 {
        let column: Vec<T> = (0..h).map(|j| rows[j * w2 + i]).collect();
        for (j, c) in box_resample(&column, h2, zero).into_iter().enumerate() {
            out[j * w2 + i] = c;
        }
    }
    out
}

/// `values` box-filtered down to `m` values: output `i` is the mean over
/// the span `[i·s, (i+1)·s)`, `s = n/m`, each source value weighted by its
/// overlap with the span.
fn box_resample<T>(values: &[T], m: usize, zero: T) -> Vec<T>
where
    T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let n = values.len();
    if n == m {
        return values.to_vec();
    }
    let s = n as f64 / m as f64;
    (0..m)
        .map(|i| {
            let (a, b) = (i as f64 * s, (i + 1) as f64 * s);
            let mut sum = zero;
            let (first, end) = (a.floor() as usize, (b.ceil() as usize).min(n));
            for (k, &value) in values.iter().enumerate().take(end).skip(first) {
                let overlap = (b.min(k as f64 + 1.0) - a.max(k as f64)).max(0.0);
                sum = sum + value * (overlap / s) as f32;
            }
            sum
        })
        .collect()
}

/// An image of linear RGB texels (and alpha, where it has some) with its
/// mip-map pyramid (built when it is made, in linear space), and how it
/// wraps when read without a sampler ([`Texture::sample`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Level 0 is the image; each next level is the previous one halved
    /// ([`Level::halved`]), down to 1×1.
    levels: Vec<Level>,
    wrap: [Wrap; 2],
}

/// One level of a texture's pyramid, borrowed as stored: what a scene
/// cache writes, and [`Texture::from_levels`] takes back.
#[derive(Clone, Copy, Debug)]
pub struct TextureLevel<'a> {
    /// Texels across.
    pub width: u32,
    /// Texels down.
    pub height: u32,
    /// `width × height` linear colours, row by row from the top.
    pub texels: &'a [Color],
    /// One alpha per texel, or empty (alpha 1 everywhere).
    pub alpha: &'a [f32],
}

impl Texture {
    /// The pyramid's levels as stored (level 0 the image), for a scene cache.
    pub fn levels(&self) -> impl ExactSizeIterator<Item = TextureLevel<'_>> {
        self.levels.iter().map(|l| TextureLevel {
            width: l.width,
            height: l.height,
            texels: &l.texels,
            alpha: &l.alpha,
        })
    }

    /// How the texture wraps when read without a sampler.
    pub fn wrap(&self) -> [Wrap; 2] {
        self.wrap
    }

    /// A texture from the levels [`Texture::levels`] gave, `(width, height,
    /// texels, alpha)` each, taken as they are (the pyramid is not rebuilt,
    /// so it is the one stored bit for bit). `None` unless level 0 is not
    /// empty, each next level is the previous one halved (each side
    /// `max(1, side / 2)`) down to 1×1, and every level has `width × height`
    /// texels and no alpha or one per texel, all levels alike.
    pub fn from_levels(levels: Vec<(u32, u32, Vec<Color>, Vec<f32>)>, wrap: [Wrap; 2]) -> Option<Self> {
        let first = levels.first()?;
        let has_alpha = !first.3.is_empty();
        let (mut w, mut h) = (first.0, first.1);
        for (i, (lw, lh, texels, alpha)) in levels.iter().enumerate() {
            if i > 0 {
                if w == 1 && h == 1 {
                    return None;
                }
                (w, h) = ((w / 2).max(1), (h / 2).max(1));
            }
            let count = u64::from(*lw) * u64::from(*lh);
            if (*lw, *lh) != (w, h)
                || w == 0
                || h == 0
                || texels.len() as u64 != count
                || alpha.len() != if has_alpha { texels.len() } else { 0 }
            {
                return None;
            }
        }
        if (w, h) != (1, 1) {
            return None;
        }
        let levels = levels
            .into_iter()
            .map(|(width, height, texels, alpha)| Level { width, height, texels, alpha })
            .collect();
        Some(Self { levels, wrap })
    }

    /// A texture of `width × height` linear colours given row by row from
    /// the top. `None` if the sizes disagree or either side is 0.
    pub fn new(width: u32, height: u32, texels: Vec<Color>) -> Option<Self> {
        Self::build(width, height, texels, Vec::new())
    }

    /// The pyramid over `texels` and `alpha` (empty, or one per texel).
    fn build(width: u32, height: u32, texels: Vec<Color>, alpha: Vec<f32>) -> Option<Self> {
        let count = u64::from(width) * u64::from(height);
        (width > 0
            && height > 0
            && texels.len() as u64 == count
            && (alpha.is_empty() || alpha.len() == texels.len()))
        .then(|| {
            let mut levels = vec![Level { width, height, texels, alpha }];
            while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
                let next = last.halved();
                levels.push(next);
            }
            Self { levels, wrap: [Wrap::Repeat; 2] }
        })
    }

    /// The texture with an alpha channel (one value in [0, 1] per texel, row
    /// by row from the top), mip-mapped as the colour is; `None` if the
    /// count differs from the texels'.
    pub fn with_alpha(mut self, alpha: Vec<f32>) -> Option<Self> {
        let (width, height) = self.size();
        if alpha.len() != self.levels[0].texels.len() {
            return None;
        }
        let texels = std::mem::take(&mut self.levels[0].texels);
        Self::build(width, height, texels, alpha).map(|t| t.with_wrap(self.wrap))
    }

    /// A texture from linear values in [0, 1] (a normal map's), `channels`
    /// (1 to 4) per texel, row by row from the top, grey for 1 or 2
    /// channels; a fourth channel is dropped. `None` if the sizes disagree.
    pub fn from_linear(width: u32, height: u32, channels: usize, values: &[f32]) -> Option<Self> {
        Self::decode_values(width, height, channels, values, Encoding::Linear, false)
    }

    /// A texture from 8- or 16-bit sRGB-encoded values in [0, 1], `channels`
    /// (1 to 4) per texel, row by row from the top: grey (1 or 2 channels)
    /// or RGB (3 or 4), the second or fourth channel being alpha (kept
    /// linear). `None` if the sizes disagree.
    pub fn from_srgb(width: u32, height: u32, channels: usize, values: &[f32]) -> Option<Self> {
        Self::from_values(width, height, channels, values, Encoding::Srgb)
    }

    /// A texture from values in [0, 1] as [`Texture::from_srgb`] reads
    /// them (alpha included), decoded by `encoding`: sRGB colour to linear,
    /// or linear data as it is. Alpha is linear either way.
    pub fn from_values(
        width: u32,
        height: u32,
        channels: usize,
        values: &[f32],
        encoding: Encoding,
    ) -> Option<Self> {
        Self::decode_values(width, height, channels, values, encoding, true)
    }

    /// [`Texture::from_values`], its alpha kept or dropped.
    fn decode_values(
        width: u32,
        height: u32,
        channels: usize,
        values: &[f32],
        encoding: Encoding,
        keep_alpha: bool,
    ) -> Option<Self> {
        if !(1..=4).contains(&channels) || values.len() != channels * width as usize * height as usize {
            return None;
        }
        let decode = |v: f32| {
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            match encoding {
                Encoding::Srgb => srgb_decode(v),
                Encoding::Linear => v,
            }
        };
        let texels = values
            .chunks_exact(channels)
            .map(|t| {
                let rgb = if channels < 3 { [t[0]; 3] } else { [t[0], t[1], t[2]] };
                Color::from_array(rgb.map(decode))
            })
            .collect();
        let alpha = if channels % 2 == 1 || !keep_alpha {
            Vec::new()
        } else {
            let linear = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            values.chunks_exact(channels).map(|t| linear(t[channels - 1])).collect()
        };
        Self::build(width, height, texels, alpha)
    }

    /// One metallic-roughness texture in glTF's layout (green: roughness,
    /// blue: metallic, red: 1) from separate grey ones (their red channel),
    /// as MTL's `map_Pr` and `map_Pm` give them: as large as the larger of
    /// the two, the other read bilinearly at its texel centres; a missing
    /// one reads 1 (its factor unchanged). `None` when both are missing.
    pub fn metallic_roughness(roughness: Option<&Texture>, metallic: Option<&Texture>) -> Option<Self> {
        let (w, h) = match (roughness, metallic) {
            (None, None) => return None,
            (Some(t), None) | (None, Some(t)) => t.size(),
            (Some(a), Some(b)) => (a.size().0.max(b.size().0), a.size().1.max(b.size().1)),
        };
        let at = |t: Option<&Texture>, u: Real, v: Real| t.map_or(1.0, |t| t.sample(u, v).x);
        let texels = (0..h)
            .flat_map(|j| (0..w).map(move |i| (i, j)))
            .map(|(i, j)| {
                let (u, v) = ((f64::from(i) + 0.5) / f64::from(w), (f64::from(j) + 0.5) / f64::from(h));
                let (u, v) = (u as Real, v as Real);
                Color::new(1.0, at(roughness, u, v), at(metallic, u, v))
            })
            .collect();
        Self::new(w, h, texels)
    }

    /// The texture with wrap modes `[u, v]`.
    pub fn with_wrap(self, wrap: [Wrap; 2]) -> Self {
        Self { wrap, ..self }
    }

    /// Reads an sRGB-encoded image file and decodes it to linear colour.
    pub fn load(path: &Path) -> Result<Self, TextureError> {
        Self::load_as(path, Encoding::Srgb)
    }

    /// Reads an image file of linear values (a normal map), as they are.
    pub fn load_linear(path: &Path) -> Result<Self, TextureError> {
        Self::load_as(path, Encoding::Linear)
    }

    /// Reads an image file and decodes it by `encoding`, alpha (linear)
    /// kept where the image has it.
    pub fn load_as(path: &Path, encoding: Encoding) -> Result<Self, TextureError> {
        let read = |reason: String| TextureError::Read { path: path.to_owned(), reason };
        let mut reader = image::ImageReader::open(path)
            .map_err(|e| read(e.to_string()))?
            .with_guessed_format()
            .map_err(|e| read(e.to_string()))?;
        let mut limits = image::Limits::default();
        limits.max_image_width = Some(MAX_TEXTURE_SIDE);
        limits.max_image_height = Some(MAX_TEXTURE_SIDE);
        reader.limits(limits);
        let decoded = reader.decode().map_err(|e| read(e.to_string()))?;
        let has_alpha = decoded.color().has_alpha();
        let image = decoded.into_rgba8();
        let (width, height) = image.dimensions();
        if width == 0 || height == 0 {
            return Err(TextureError::Size { path: path.to_owned(), width, height });
        }
        // One table lookup per channel value.
        let table: Vec<f32> = (0..=255u8)
            .map(|b| match encoding {
                Encoding::Srgb => srgb_decode(f32::from(b) / 255.0),
                Encoding::Linear => f32::from(b) / 255.0,
            })
            .collect();
        let texels = image
            .pixels()
            .map(|p| Color::new(table[p[0] as usize], table[p[1] as usize], table[p[2] as usize]));
        let alpha =
            if has_alpha { image.pixels().map(|p| f32::from(p[3]) / 255.0).collect() } else { Vec::new() };
        Self::build(width, height, texels.collect(), alpha).ok_or_else(|| TextureError::Size {
            path: path.to_owned(),
            width,
            height,
        })
    }

    /// Width and height in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// How many mip-map levels it has, the image included: `⌊log₂ max(W, H)⌋ + 1`.
    pub fn level_count(&self) -> usize {
        self.levels.len()
    }

    /// Width and height of mip-map level `level` (0 is the image).
    pub fn level_size(&self, level: usize) -> (u32, u32) {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        (l.width, l.height)
    }

    /// Bytes of texel storage, every level.
    pub fn memory_bytes(&self) -> usize {
        self.levels
            .iter()
            .map(|l| l.texels.len() * size_of::<Color>() + l.alpha.len() * size_of::<f32>())
            .sum()
    }

    /// Whether the image has an alpha channel.
    pub fn has_alpha(&self) -> bool {
        !self.levels[0].alpha.is_empty()
    }

    /// The bilinearly filtered colour of the full-size image at `(u, v)`
    /// (see the module documentation), wrapped by the texture's [`Wrap`]
    /// modes. Non-finite coordinates give the texel at (0, 0).
    pub fn sample(&self, u: Real, v: Real) -> Color {
        let l = &self.levels[0];
        l.bilinear(&l.texels, self.wrap, to_f64(u), to_f64(v))
    }

    /// The alpha of the full-size image at `(u, v)`, filtered and wrapped
    /// as [`Texture::sample`] filters colour; 1 for an image without alpha.
    pub fn sample_alpha(&self, u: Real, v: Real) -> f32 {
        let l = &self.levels[0];
        if l.alpha.is_empty() { 1.0 } else { l.bilinear(&l.alpha, self.wrap, to_f64(u), to_f64(v)) }
    }

    /// The colour at `(u, v)` through `sampler`, for a footprint whose
    /// level of detail is `lod` (mip-map level, fractional:
    /// [`crate::materials::texture_lod`]). At `lod ≤ 0` the image is
    /// magnified: `sampler.mag` on level 0. Above, `sampler.min` within a
    /// level, and between levels `sampler.mip`: none reads level 0, nearest
    /// the level `lod` rounds to, linear blends levels `⌊lod⌋` and `⌊lod⌋ + 1`
    /// by the fraction (trilinear filtering; continuous in `lod`). A NaN
    /// `lod` reads level 0.
    pub fn lookup(&self, u: Real, v: Real, lod: f32, sampler: &Sampler) -> Color {
        self.lookup_in(u, v, lod, sampler, |l| &l.texels)
    }

    /// The alpha at `(u, v)` through `sampler` at level of detail `lod`,
    /// filtered exactly as [`Texture::lookup`] filters colour (the same
    /// levels, weights and wrap); 1 for an image without alpha.
    pub fn lookup_alpha(&self, u: Real, v: Real, lod: f32, sampler: &Sampler) -> f32 {
        if self.has_alpha() { self.lookup_in(u, v, lod, sampler, |l| &l.alpha) } else { 1.0 }
    }

    /// [`Texture::lookup`] over the values `pick` takes from each level.
    #[inline]
    fn lookup_in<T>(&self, u: Real, v: Real, lod: f32, sampler: &Sampler, pick: impl Fn(&Level) -> &[T]) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let (u, v) = (to_f64(u), to_f64(v));
        let read = |level: usize, filter: Filter| {
            let l = &self.levels[level.min(self.levels.len() - 1)];
            match filter {
                Filter::Nearest => l.nearest(pick(l), sampler.wrap, u, v),
                Filter::Linear => l.bilinear(pick(l), sampler.wrap, u, v),
            }
        };
        if lod.is_nan() || lod <= 0.0 {
            return read(0, sampler.mag);
        }
        let top = (self.levels.len() - 1) as f32;
        let lod = lod.min(top);
        match sampler.mip {
            None => read(0, sampler.min),
            Some(Filter::Nearest) => read(lod.round() as usize, sampler.min),
            Some(Filter::Linear) => {
                let (l0, f) = (lod.floor(), lod.fract());
                let a = read(l0 as usize, sampler.min);
                if f == 0.0 { a } else { a * (1.0 - f) + read(l0 as usize + 1, sampler.min) * f }
            }
        }
    }
}

/// The sRGB transfer curve inverted: an encoded value in [0, 1] to linear
/// (IEC 61966-2-1: `v/12.92` up to 0.04045, else `((v + 0.055)/1.055)^2.4`).
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::color::srgb_encode;

    fn checker() -> Texture {
        // 2×2: black, white / red, green.
        Texture::new(2, 2, vec![Color::ZERO, Color::ONE, Color::X, Color::Y]).unwrap()
    }

    #[test]
    fn texel_centres_give_their_texel_exactly() {
        let t = checker();
        assert_eq!(t.sample(0.25, 0.25), Color::ZERO);
        assert_eq!(t.sample(0.75, 0.25), Color::ONE);
        assert_eq!(t.sample(0.25, 0.75), Color::X);
        assert_eq!(t.sample(0.75, 0.75), Color::Y);
    }

    #[test]
    fn between_texel_centres_the_filter_is_bilinear() {
        let t = checker();
        assert_eq!(t.sample(0.5, 0.25), Color::splat(0.5));
        let centre = t.sample(0.5, 0.5);
        assert!((centre - Color::new(0.5, 0.5, 0.25)).abs().max_element() < 1e-6, "{centre}");
    }

    #[test]
    fn coordinates_repeat_and_the_filter_wraps_across_the_border() {
        let t = checker();
        for (u, v) in [(0.1, 0.3), (0.8, 0.6), (0.5, 0.5)] {
            for (du, dv) in [(1.0, 0.0), (-3.0, 2.0), (1000.0, -1000.0)] {
                let (a, b) = (t.sample(u, v), t.sample(u + du, v + dv));
                assert!((a - b).abs().max_element() < 1e-4, "({u}, {v}) + ({du}, {dv}): {a} vs {b}");
            }
        }
        // At u = 0 the filter is halfway between the last column and the first.
        assert_eq!(t.sample(0.0, 0.25), Color::splat(0.5));
        assert_eq!(t.sample(Real::NAN, 0.5), Color::ZERO);
    }

    #[test]
    fn clamp_and_mirrored_repeat_wrap_as_gltf_defines_them() {
        // One row: 0, 1, 2, 3 (red channel).
        let row = |wrap| {
            Texture::new(4, 1, (0..4).map(|i| Color::splat(i as f32)).collect())
                .unwrap()
                .with_wrap([wrap, Wrap::Repeat])
        };
        let at = |t: &Texture, x: f64| t.sample(((x + 0.5) / 4.0) as Real, 0.5).x;
        let clamp = row(Wrap::ClampToEdge);
        assert_eq!(
            [at(&clamp, -3.0), at(&clamp, -0.5), at(&clamp, 3.5), at(&clamp, 9.0)],
            [0.0, 0.0, 3.0, 3.0]
        );
        let mirror = row(Wrap::MirroredRepeat);
        // Texels 4..8 are 3, 2, 1, 0; −1 is 0; 8 is 0 again.
        assert_eq!(
            [at(&mirror, 4.0), at(&mirror, 7.0), at(&mirror, -1.0), at(&mirror, 8.0)],
            [3.0, 0.0, 0.0, 0.0]
        );
        assert_eq!(at(&mirror, 3.5), 3.0); // between texel 3 and its mirror image
        let repeat = row(Wrap::Repeat);
        assert_eq!([at(&repeat, 4.0), at(&repeat, -1.0), at(&repeat, 3.5)], [0.0, 3.0, 1.5]);
    }

    #[test]
    fn alpha_is_mip_mapped_and_looked_up_with_the_colours_levels_filter_and_weights() {
        // A 5×3 image (odd sides) whose alpha equals its red channel: every
        // lookup's alpha must be the lookup's red, at every level of detail
        // and for every sampler.
        let red = |k: usize| ((k * 7919) % 13) as f32 / 12.0;
        let texels = (0..15).map(|k| Color::new(red(k), 0.5, 0.25)).collect();
        let t = Texture::new(5, 3, texels).unwrap().with_alpha((0..15).map(red).collect()).unwrap();
        assert_eq!(t.level_count(), 3);
        let samplers = [
            Sampler::DEFAULT,
            Sampler {
                mag: Filter::Nearest,
                min: Filter::Nearest,
                mip: Some(Filter::Nearest),
                ..Sampler::DEFAULT
            },
            Sampler { mip: None, wrap: [Wrap::MirroredRepeat, Wrap::ClampToEdge], ..Sampler::DEFAULT },
        ];
        for s in &samplers {
            for lod in [-1.0, 0.0, 0.4, 1.0, 1.7, 2.0, 9.0] {
                for (u, v) in [(0.1, 0.2), (0.55, 0.5), (0.93, 0.81), (-0.3, 1.4)] {
                    let (c, a) = (t.lookup(u, v, lod, s), t.lookup_alpha(u, v, lod, s));
                    assert!((c.x - a).abs() < 1e-6, "lod {lod} at ({u}, {v}): {} vs {a}", c.x);
                }
            }
        }
        // The top level's alpha is the image's mean, as its colour is.
        let mean = (0..15).map(red).sum::<f32>() / 15.0;
        assert!((t.lookup_alpha(0.5, 0.5, 9.0, &Sampler::DEFAULT) - mean).abs() < 1e-6);
        // Without alpha: 1 everywhere.
        let opaque = Texture::new(1, 1, vec![Color::ONE]).unwrap();
        assert_eq!(opaque.lookup_alpha(0.5, 0.5, 3.0, &Sampler::DEFAULT), 1.0);
    }

    #[test]
    fn alpha_is_kept_linear_and_filtered_where_the_image_has_it() {
        // 2×1 RGBA: alpha 0 and 1, colours sRGB-decoded, alpha not.
        let t = Texture::from_srgb(2, 1, 4, &[0.5, 0.5, 0.5, 0.0, 1.0, 1.0, 1.0, 1.0]).unwrap();
        assert!(t.has_alpha());
        assert_eq!(
            (t.sample_alpha(0.25, 0.5), t.sample_alpha(0.75, 0.5), t.sample_alpha(0.5, 0.5)),
            (0.0, 1.0, 0.5)
        );
        assert!((t.sample(0.25, 0.5).x - srgb_decode(0.5)).abs() < 1e-6);
        // Grey with alpha (2 channels); none without.
        let g = Texture::from_srgb(1, 1, 2, &[1.0, 0.25]).unwrap();
        assert_eq!(g.sample_alpha(0.3, 0.3), 0.25);
        let rgb = Texture::from_srgb(1, 1, 3, &[1.0, 0.5, 0.0]).unwrap();
        assert!(!rgb.has_alpha() && rgb.sample_alpha(0.5, 0.5) == 1.0);
        // A normal map is linear and has no alpha.
        let n = Texture::from_linear(1, 1, 4, &[0.5, 0.25, 1.0, 0.0]).unwrap();
        assert_eq!((n.sample(0.5, 0.5), n.has_alpha()), (Color::new(0.5, 0.25, 1.0), false));
        // An RGBA file keeps its alpha; an RGB one has none.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.png");
        image::RgbaImage::from_pixel(1, 1, image::Rgba([255, 255, 255, 51])).save(&path).unwrap();
        let t = Texture::load(&path).unwrap();
        assert!((t.sample_alpha(0.5, 0.5) - 0.2).abs() < 1e-6);
        assert_eq!(t.memory_bytes(), size_of::<Color>() + size_of::<f32>());
        image::RgbImage::from_pixel(1, 1, image::Rgb([255, 128, 0])).save(&path).unwrap();
        assert!(!Texture::load(&path).unwrap().has_alpha());
        let linear = Texture::load_linear(&path).unwrap().sample(0.5, 0.5);
        assert!((linear - Color::new(1.0, 128.0 / 255.0, 0.0)).abs().max_element() < 1e-6, "{linear}");
    }

    #[test]
    fn srgb_decoding_inverts_the_encoding() {
        for i in 0..=255 {
            let v = i as f32 / 255.0;
            assert!((srgb_encode(srgb_decode(v)) - v).abs() < 1e-5, "{v}");
        }
        assert!((srgb_decode(128.0 / 255.0) - 0.2158605).abs() < 1e-6);
    }

    #[test]
    fn an_image_file_is_read_as_linear_colour_and_bad_files_are_errors_naming_them() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.png");
        image::RgbImage::from_fn(3, 2, |x, y| image::Rgb([(x * 100) as u8, (y * 255) as u8, 128]))
            .save(&path)
            .unwrap();
        let t = Texture::load(&path).unwrap();
        assert_eq!(t.size(), (3, 2));
        let c = t.sample(0.5, 0.75); // the centre of texel (1, 1)
        assert!(
            (c - Color::new(srgb_decode(100.0 / 255.0), 1.0, srgb_decode(128.0 / 255.0))).abs().max_element()
                < 1e-6
        );

        let missing = dir.path().join("missing.png");
        let e = Texture::load(&missing).unwrap_err().to_string();
        assert!(e.starts_with("cannot read texture ") && e.contains("missing.png"), "{e}");
        // One texel too wide: refused before its pixels are allocated.
        let wide = dir.path().join("wide.png");
        image::GrayImage::new(MAX_TEXTURE_SIDE + 1, 1).save(&wide).unwrap();
        let e = Texture::load(&wide).unwrap_err().to_string();
        assert!(
            e.starts_with("cannot read texture ") && e.contains("wide.png") && e.contains("limit"),
            "{e}"
        );
        let junk = dir.path().join("junk.png");
        std::fs::write(&junk, b"\x89PNG\r\n\x1a\nnot really").unwrap();
        let e = Texture::load(&junk).unwrap_err().to_string();
        assert!(e.contains("junk.png"), "{e}");
    }

    #[test]
    fn mip_levels_halve_each_side_down_to_one_texel_and_odd_sizes_keep_the_mean() {
        let (w, h) = (5u32, 3u32);
        let texels: Vec<Color> = (0..w * h).map(|i| Color::splat((i * 7 % 11) as f32)).collect();
        let mean = |t: &Texture, l: usize| {
            let (w, h) = t.level_size(l);
            t.levels[l].texels.iter().map(|c| c.x as f64).sum::<f64>() / f64::from(w * h)
        };
        let t = Texture::new(w, h, texels).unwrap();
        assert_eq!(t.level_count(), 3);
        assert_eq!([t.level_size(0), t.level_size(1), t.level_size(2)], [(5, 3), (2, 1), (1, 1)]);
        for l in 1..3 {
            assert!(
                (mean(&t, l) - mean(&t, 0)).abs() < 1e-5,
                "level {l}: {} vs {}",
                mean(&t, l),
                mean(&t, 0)
            );
        }
        // Odd: output 0 of 3 → 1 covers all three.
        let row = Texture::new(3, 1, vec![Color::splat(0.0), Color::splat(3.0), Color::splat(6.0)]).unwrap();
        assert!((row.levels[1].texels[0].x - 3.0).abs() < 1e-6);
        // Even: the 2×2 box, exactly.
        let t = checker();
        assert_eq!(t.level_count(), 2);
        assert_eq!(t.levels[1].texels[0], (Color::ZERO + Color::ONE + Color::X + Color::Y) / 4.0);
        assert_eq!(t.memory_bytes(), 5 * size_of::<Color>());
    }

    #[test]
    fn trilinear_lookups_are_continuous_in_the_level_of_detail() {
        let texels: Vec<Color> = (0..64).map(|i| Color::splat(((i * 13) % 7) as f32)).collect();
        let t = Texture::new(8, 8, texels).unwrap();
        let s = Sampler::DEFAULT;
        let (u, v) = (0.37, 0.61);
        for k in 0..=3 {
            let k = k as f32;
            let at = t.lookup(u, v, k, &s);
            // At a whole level: that level's bilinear filter.
            let exact =
                t.levels[k as usize].bilinear(&t.levels[k as usize].texels, s.wrap, to_f64(u), to_f64(v));
            assert!((at - exact).abs().max_element() < 1e-6, "level {k}");
            for e in [1e-3, -1e-3] {
                let near = t.lookup(u, v, k + e, &s);
                assert!((near - at).abs().max_element() < 0.02, "lod {k} ± {e}: {near} vs {at}");
            }
        }
        // Magnified (lod ≤ 0) and past the last level: the ends.
        assert_eq!(t.lookup(u, v, -5.0, &s), t.sample(u, v));
        // (The 1×1 level's bilinear weights sum to 1 within rounding.)
        assert!((t.lookup(u, v, 50.0, &s) - t.levels[3].texels[0]).abs().max_element() < 1e-5);
        assert_eq!(t.lookup(u, v, f32::NAN, &s), t.sample(u, v));
        // Without mip-maps every lod reads the image.
        let flat = Sampler { mip: None, ..s };
        assert_eq!(t.lookup(u, v, 2.5, &flat), t.sample(u, v));
        let nearest_mip = Sampler { mip: Some(Filter::Nearest), ..s };
        assert_eq!(t.lookup(u, v, 1.4, &nearest_mip), t.lookup(u, v, 1.0, &s));
    }

    #[test]
    fn nearest_filtering_reads_the_texel_the_point_falls_in() {
        let t = checker();
        let s = Sampler { mag: Filter::Nearest, min: Filter::Nearest, mip: None, wrap: [Wrap::Repeat; 2] };
        assert_eq!(t.lookup(0.49, 0.1, 0.0, &s), Color::ZERO);
        assert_eq!(t.lookup(0.51, 0.1, 0.0, &s), Color::ONE);
        assert_eq!(t.lookup(1.51, -0.9, 0.0, &s), Color::ONE);
        let clamp = Sampler { wrap: [Wrap::ClampToEdge; 2], ..s };
        assert_eq!(t.lookup(7.0, 0.9, 0.0, &clamp), Color::Y);
        assert_eq!(t.lookup(-7.0, 0.9, 0.0, &clamp), Color::X);
    }

    #[test]
    fn colour_is_decoded_from_srgb_and_data_is_read_as_stored() {
        let values = [128.0 / 255.0, 0.0, 1.0];
        let srgb = Texture::from_values(1, 1, 3, &values, Encoding::Srgb).unwrap();
        let linear = Texture::from_values(1, 1, 3, &values, Encoding::Linear).unwrap();
        assert!((srgb.sample(0.5, 0.5).x - 0.2158605).abs() < 1e-6);
        assert_eq!(linear.sample(0.5, 0.5), Color::new(128.0 / 255.0, 0.0, 1.0));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("mr.png");
        image::RgbImage::from_pixel(1, 1, image::Rgb([0, 64, 255])).save(&path).unwrap();
        let data = Texture::load_as(&path, Encoding::Linear).unwrap();
        assert_eq!(data.sample(0.5, 0.5), Color::new(0.0, 64.0 / 255.0, 1.0));
        assert!(Texture::load(&path).unwrap().sample(0.5, 0.5).y < 0.06);
    }
}
