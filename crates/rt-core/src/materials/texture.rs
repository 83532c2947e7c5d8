//! Image textures: a base colour that varies over a surface.
//!
//! A texture is an image file (PNG or JPEG) read with the `image` crate. Its
//! 8-bit values are sRGB-encoded, as base-colour textures are by the
//! conventions of OBJ/MTL `map_Kd` and glTF's `baseColorTexture`: they are
//! decoded to linear RGB once, at load, with the IEC 61966-2-1 curve
//! ([`srgb_decode`]), so that filtering and shading happen on linear values.
//! Alpha, where the image has it, is kept apart as it is (alpha is linear
//! coverage, never sRGB-encoded) and filtered the same way
//! ([`Texture::sample_alpha`]). Normal maps hold linear values and are made
//! with [`Texture::from_linear`].
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

use std::path::{Path, PathBuf};

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

/// How texel indices outside the image are brought back into it: glTF's
/// sampler wrap modes (glTF 2.0 §3.8.4.3), for one axis.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Index `i` is `i mod n`: the image tiles the plane.
    #[default]
    Repeat,
    /// Index `i` is clamped to `[0, n − 1]`: the border texels extend.
    ClampToEdge,
    /// The image tiles the plane mirrored every other time: index `i` is
    /// `i mod 2n` folded back into `[0, n − 1]`.
    MirroredRepeat,
}

impl Wrap {
    /// Texel index `i` on an axis of `n` texels.
    fn index(self, i: i64, n: i64) -> i64 {
        match self {
            Self::Repeat => i.rem_euclid(n),
            Self::ClampToEdge => i.clamp(0, n - 1),
            Self::MirroredRepeat => {
                let j = i.rem_euclid(2 * n);
                if j < n { j } else { 2 * n - 1 - j }
            }
        }
    }
}

/// An image of linear RGB texels, row by row from the top, and how it wraps.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    width: u32,
    height: u32,
    texels: Vec<Color>,
    /// The alpha channel, one value per texel, or empty when the image has
    /// none (alpha 1 everywhere).
    alpha: Vec<f32>,
    wrap: [Wrap; 2],
}

impl Texture {
    /// A texture of `width × height` linear colours given row by row from
    /// the top. `None` if the sizes disagree or either side is 0.
    pub fn new(width: u32, height: u32, texels: Vec<Color>) -> Option<Self> {
        (width > 0 && height > 0 && texels.len() as u64 == u64::from(width) * u64::from(height))
            .then_some(Self { width, height, texels, alpha: Vec::new(), wrap: [Wrap::Repeat; 2] })
    }

    /// The texture with an alpha channel (one value in [0, 1] per texel, row
    /// by row from the top); `None` if the count differs from the texels'.
    pub fn with_alpha(self, alpha: Vec<f32>) -> Option<Self> {
        if alpha.len() == self.texels.len() { Some(Self { alpha, ..self }) } else { None }
    }

    /// A texture from linear values in [0, 1] (a normal map's), `channels`
    /// (1 to 4) per texel, row by row from the top, grey for 1 or 2
    /// channels; a fourth channel is dropped. `None` if the sizes disagree.
    pub fn from_linear(width: u32, height: u32, channels: usize, values: &[f32]) -> Option<Self> {
        Self::from_values(width, height, channels, values, |v| v).map(|t| Self { alpha: Vec::new(), ..t })
    }

    /// A texture from 8- or 16-bit sRGB-encoded values in [0, 1], `channels`
    /// (1 to 4) per texel, row by row from the top: grey (1 or 2 channels)
    /// or RGB (3 or 4), the second or fourth channel being alpha (kept
    /// linear). `None` if the sizes disagree.
    pub fn from_srgb(width: u32, height: u32, channels: usize, values: &[f32]) -> Option<Self> {
        Self::from_values(width, height, channels, values, srgb_decode)
    }

    fn from_values(
        width: u32,
        height: u32,
        channels: usize,
        values: &[f32],
        decode: fn(f32) -> f32,
    ) -> Option<Self> {
        if !(1..=4).contains(&channels) || values.len() != channels * width as usize * height as usize {
            return None;
        }
        let texels = values
            .chunks_exact(channels)
            .map(|t| {
                let rgb = if channels < 3 { [t[0]; 3] } else { [t[0], t[1], t[2]] };
                Color::from_array(rgb.map(|v| decode(v.clamp(0.0, 1.0))))
            })
            .collect();
        let texture = Self::new(width, height, texels)?;
        if channels % 2 == 1 {
            return Some(texture);
        }
        texture.with_alpha(values.chunks_exact(channels).map(|t| t[channels - 1].clamp(0.0, 1.0)).collect())
    }

    /// The texture with wrap modes `[u, v]`.
    pub fn with_wrap(self, wrap: [Wrap; 2]) -> Self {
        Self { wrap, ..self }
    }

    /// Reads an sRGB-encoded image file and decodes it to linear colour.
    pub fn load(path: &Path) -> Result<Self, TextureError> {
        Self::load_decoded(path, srgb_decode)
    }

    /// Reads an image file of linear values (a normal map), as they are.
    pub fn load_linear(path: &Path) -> Result<Self, TextureError> {
        Self::load_decoded(path, |v| v)
    }

    fn load_decoded(path: &Path, decode: fn(f32) -> f32) -> Result<Self, TextureError> {
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
        let table: Vec<f32> = (0..=255u8).map(|b| decode(f32::from(b) / 255.0)).collect();
        let texels = image
            .pixels()
            .map(|p| Color::new(table[p[0] as usize], table[p[1] as usize], table[p[2] as usize]));
        let alpha =
            if has_alpha { image.pixels().map(|p| f32::from(p[3]) / 255.0).collect() } else { Vec::new() };
        Ok(Self { width, height, texels: texels.collect(), alpha, wrap: [Wrap::Repeat; 2] })
    }

    /// Width and height in texels.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Bytes of texel storage.
    pub fn memory_bytes(&self) -> usize {
        self.texels.len() * size_of::<Color>() + self.alpha.len() * size_of::<f32>()
    }

    /// Whether the image has an alpha channel.
    pub fn has_alpha(&self) -> bool {
        !self.alpha.is_empty()
    }

    /// The bilinearly filtered colour at `(u, v)` (see the module
    /// documentation), wrapped by the texture's [`Wrap`] modes. Non-finite
    /// coordinates give the texel at (0, 0).
    pub fn sample(&self, u: Real, v: Real) -> Color {
        self.filter(u, v, &self.texels)
    }

    /// The alpha at `(u, v)`, filtered and wrapped as [`Texture::sample`]
    /// filters colour; 1 for an image without alpha.
    pub fn sample_alpha(&self, u: Real, v: Real) -> f32 {
        if self.alpha.is_empty() { 1.0 } else { self.filter(u, v, &self.alpha) }
    }

    /// The bilinear filter over `values` (one per texel).
    fn filter<T>(&self, u: Real, v: Real, values: &[T]) -> T
    where
        T: Copy + std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
    {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = to_f64(u) * w as f64 - 0.5;
        let y = to_f64(v) * h as f64 - 0.5;
        if !(x.is_finite() && y.is_finite()) {
            return values[0];
        }
        // Reduce far coordinates first (by a whole mirrored period), so the
        // integer part stays exact.
        let (x, y) = (x.rem_euclid(2.0 * w as f64), y.rem_euclid(2.0 * h as f64));
        let (x, y) = (
            if self.wrap[0] == Wrap::ClampToEdge {
                (to_f64(u) * w as f64 - 0.5).clamp(-1.0, w as f64)
            } else {
                x
            },
            if self.wrap[1] == Wrap::ClampToEdge {
                (to_f64(v) * h as f64 - 0.5).clamp(-1.0, h as f64)
            } else {
                y
            },
        );
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let [wrap_u, wrap_v] = self.wrap;
        let texel = |i: i64, j: i64| values[(wrap_v.index(j, h) * w + wrap_u.index(i, w)) as usize];
        let (i, j) = (x0 as i64, y0 as i64);
        let top = texel(i, j) * (1.0 - fx) + texel(i + 1, j) * fx;
        let bottom = texel(i, j + 1) * (1.0 - fx) + texel(i + 1, j + 1) * fx;
        top * (1.0 - fy) + bottom * fy
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
}
