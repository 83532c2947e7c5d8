//! The display transform: how the canvas's linear image becomes the 8-bit
//! texels on screen.
//!
//! A pixel's linear (scene-referred) colour is, in order:
//!
//! 1. compared with the reference image, if an error view is chosen
//!    ([`ErrorView`]: `|a − b|` or `|a − b| / (b + ε)` per channel);
//! 2. multiplied by the exposure, `2^stops`;
//! 3. reduced to what the [`Channel`] view shows: the colour, one channel
//!    as grey, the luminance as grey, or the luminance's log2 through the
//!    Turbo colour map (false colour);
//! 4. encoded in the scene's colour space ([`ColorSpace::encode`]): clamped
//!    to [0, 1], sRGB transfer curve or not, rounded to 8 bits; or, with the
//!    AgX view transform, through rt-core's [`view_transform::Display::encode`]
//!    (the curve PNG output uses, so the window shows what a saved PNG
//!    holds). False colour is already a display colour and is not encoded
//!    again.
//!
//! At exposure 0 in the RGB view the texels are bit for bit what the
//! viewer always showed (`ColorSpace::encode` of the mean): the encoding
//! here goes through a table ([`Encoder`]) that is exact, not an
//! approximation, and a multiplier of `2^0 = 1` changes no value.

use std::sync::{Arc, OnceLock};

use egui::Color32;
use rt_core::math::color::{Color, ColorSpace};
use rt_core::render::view_transform::{self, ViewTransform};

use super::reference::Reference;

/// Relative luminance of linear RGB with the Rec. 709 / sRGB primaries and
/// D65 white: the `Y` row of the RGB → XYZ matrix of IEC 61966-2-1 (sRGB),
/// the same weights as ITU-R BT.709-6, Part 2, item 3.2.
pub const LUMINANCE_WEIGHTS: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// The ε of the relative error `|a − b| / (b + ε)`: keeps black reference
/// pixels from dividing by zero, and makes errors of values far below ε
/// count as absolute ones. 0.01 as tev uses it.
pub const RELATIVE_EPSILON: f32 = 0.01;

/// The relative luminance of linear `c` ([`LUMINANCE_WEIGHTS`]).
pub fn luminance([r, g, b]: [f32; 3]) -> f32 {
    let [wr, wg, wb] = LUMINANCE_WEIGHTS;
    wr * r + wg * g + wb * b
}

/// What of the colour is shown.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Channel {
    /// The colour.
    #[default]
    Rgb,
    /// The red channel, as grey.
    R,
    /// The green channel, as grey.
    G,
    /// The blue channel, as grey.
    B,
    /// The luminance ([`LUMINANCE_WEIGHTS`]), as grey.
    Luminance,
    /// log2 of the luminance through the Turbo colour map ([`turbo`]),
    /// over the display's `false_colour_range`.
    FalseColour,
}

impl Channel {
    /// Every view, in the order the panel lists them, with its label.
    pub const ALL: [(Channel, &'static str); 6] = [
        (Channel::Rgb, "RGB"),
        (Channel::R, "R"),
        (Channel::G, "G"),
        (Channel::B, "B"),
        (Channel::Luminance, "Y"),
        (Channel::FalseColour, "false colour"),
    ];
}

/// How the render is compared with the reference image, pixel by pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// `|a − b|` per channel (a: the render, b: the reference).
    Absolute,
    /// `|a − b| / (b + ε)` per channel, ε = [`RELATIVE_EPSILON`].
    Relative,
}

impl ErrorKind {
    /// The error of render value `a` against reference value `b`.
    pub fn error(self, a: f32, b: f32) -> f32 {
        match self {
            Self::Absolute => (a - b).abs(),
            Self::Relative => (a - b).abs() / (b + RELATIVE_EPSILON),
        }
    }
}

/// An error view: the render compared with `reference`.
#[derive(Clone, Debug)]
pub struct ErrorView {
    /// Which error is shown.
    pub kind: ErrorKind,
    /// The image compared with; the same size as the render, or the error
    /// view does not apply (a preview is shown as it is).
    pub reference: Arc<Reference>,
}

impl PartialEq for ErrorView {
    fn eq(&self, other: &Self) -> bool {
        self.kind == other.kind && Arc::ptr_eq(&self.reference, &other.reference)
    }
}

/// The display transform's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct Display {
    /// Exposure in stops: the linear colour is multiplied by `2^exposure`.
    pub exposure: f32,
    /// The curve from scene light to display light (after exposure).
    pub view_transform: ViewTransform,
    /// What of the colour is shown.
    pub channel: Channel,
    /// log2 luminances shown at the two ends of the false colour map
    /// (after exposure); outside, the ends' colours.
    pub false_colour_range: [f32; 2],
    /// How colours are encoded into 8 bits: the scene's colour space.
    pub color_space: ColorSpace,
    /// The render compared with a reference, if chosen.
    pub error: Option<ErrorView>,
}

impl Default for Display {
    /// Exposure 0, RGB, linear encoding, no comparison.
    fn default() -> Self {
        Self {
            exposure: 0.0,
            view_transform: ViewTransform::Standard,
            channel: Channel::Rgb,
            false_colour_range: [-10.0, 2.0],
            color_space: ColorSpace::Linear,
            error: None,
        }
    }
}

impl Display {
    /// Whether the texels are exactly the colour-space encoding of the
    /// pixels (exposure 0, Standard, RGB, no comparison): the rows' own
    /// encoded colours can then be shown as they are.
    pub fn is_plain(&self) -> bool {
        self.exposure == 0.0
            && self.view_transform == ViewTransform::Standard
            && self.channel == Channel::Rgb
            && self.error.is_none()
    }

    /// The error view for an image of `size`, if one is chosen and its
    /// reference has that size.
    pub fn error_for(&self, size: [usize; 2]) -> Option<&ErrorView> {
        self.error.as_ref().filter(|e| e.reference.size() == size)
    }

    /// The texel showing linear colour `c` (already compared with the
    /// reference, if at all).
    pub fn texel(&self, c: [f32; 3]) -> Color32 {
        Prepared::new(self).texel(c)
    }

    /// Transforms every `step`-th pixel of linear row `pixels` into
    /// `texels`, each compared with the same pixel of `reference` (the
    /// reference's row) under `error`.
    pub fn row(
        &self,
        pixels: &[[f32; 3]],
        step: usize,
        compare: Option<(ErrorKind, &[[f32; 3]])>,
        texels: &mut [Color32],
    ) {
        let p = Prepared::new(self);
        match compare {
            None => {
                for (t, c) in texels.iter_mut().zip(pixels.iter().step_by(step)) {
                    *t = p.texel(*c);
                }
            }
            Some((kind, reference)) => {
                let pairs = pixels.iter().zip(reference).step_by(step);
                for (t, (a, b)) in texels.iter_mut().zip(pairs) {
                    *t = p.texel([0, 1, 2].map(|i| kind.error(a[i], b[i])));
                }
            }
        }
    }
}

/// A display transform with what every texel needs worked out once: the
/// multiplier, the encoder, the false colour scale.
struct Prepared {
    multiplier: f32,
    encoder: &'static Encoder,
    /// The view transform with its exposure, when it is not Standard (the
    /// table encoder is for the plain clamp only).
    curve: Option<(view_transform::Display, ColorSpace)>,
    channel: Channel,
    /// log2 luminance at the false colour map's low end, and 1 / the range.
    low: f32,
    per_stop: f32,
}

impl Prepared {
    fn new(d: &Display) -> Self {
        let [lo, hi] = d.false_colour_range;
        Self {
            multiplier: d.exposure.exp2(),
            encoder: Encoder::for_space(d.color_space),
            curve: (d.view_transform != ViewTransform::Standard).then_some((
                view_transform::Display { exposure: d.exposure, view_transform: d.view_transform },
                d.color_space,
            )),
            channel: d.channel,
            low: lo,
            per_stop: 1.0 / (hi - lo).max(1e-6),
        }
    }

    #[inline]
    fn texel(&self, c: [f32; 3]) -> Color32 {
        let (m, encoder) = (self.multiplier, self.encoder);
        if self.channel != Channel::FalseColour
            && let Some((curve, space)) = &self.curve
        {
            return self.curve_texel(curve, *space, c);
        }
        let grey = |v: f32| {
            let e = encoder.encode(v * m);
            Color32::from_rgb(e, e, e)
        };
        match self.channel {
            Channel::Rgb => {
                let [r, g, b] = c.map(|v| encoder.encode(v * m));
                Color32::from_rgb(r, g, b)
            }
            Channel::R => grey(c[0]),
            Channel::G => grey(c[1]),
            Channel::B => grey(c[2]),
            Channel::Luminance => grey(luminance(c)),
            Channel::FalseColour => {
                let y = luminance(c) * m;
                let t = if y > 0.0 { (y.log2() - self.low) * self.per_stop } else { 0.0 };
                turbo(t)
            }
        }
    }
}

impl Prepared {
    /// The texel of linear `c` through a view transform other than
    /// Standard: exposure and curve are rt-core's, exactly as PNG output
    /// applies them; a one-channel view sends that channel as a grey.
    /// (False colour maps luminance itself and never comes here.)
    #[cold]
    fn curve_texel(&self, curve: &view_transform::Display, space: ColorSpace, c: [f32; 3]) -> Color32 {
        let grey = |v: f32| Color32::from_gray(curve.encode(Color::splat(v), space)[0]);
        match self.channel {
            Channel::Rgb => {
                let [r, g, b] = curve.encode(Color::from_array(c), space);
                Color32::from_rgb(r, g, b)
            }
            Channel::R => grey(c[0]),
            Channel::G => grey(c[1]),
            Channel::B => grey(c[2]),
            Channel::Luminance | Channel::FalseColour => grey(luminance(c)),
        }
    }
}

/// Turbo, Google's improved rainbow colour map (Anton Mikhailov, "Turbo, An
/// Improved Rainbow Colormap for Visualization", Google AI Blog, 2019), in
/// Ruofei Du's polynomial approximation (Apache-2.0): `t` in [0, 1] (clamped;
/// NaN as 0) from dark blue through green and yellow to dark red. Its values
/// are display (sRGB) colours.
pub fn turbo(t: f32) -> Color32 {
    const R: [f32; 6] = [0.135_721_38, 4.615_392_6, -42.660_323, 132.131_08, -152.942_39, 59.286_38];
    const G: [f32; 6] = [0.091_402_61, 2.194_188_4, 4.842_966_6, -14.185_033, 4.277_298_6, 2.829_566];
    const B: [f32; 6] = [0.106_673_3, 12.641_946, -60.582_05, 110.362_77, -89.903_11, 27.348_25];
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let poly = |k: &[f32; 6]| k.iter().rev().fold(0.0, |acc, &c| acc * t + c);
    let byte = |v: f32| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8;
    Color32::from_rgb(byte(poly(&R)), byte(poly(&G)), byte(poly(&B)))
}

/// [`ColorSpace::encode`] of one component, exactly, through tables: a
/// first guess from the float's top 16 bits, then the thresholds where the
/// 8-bit value steps up. Exact because the encoding is monotonic in its
/// input (the tests check it against `encode`).
pub struct Encoder {
    /// `thresholds[v]`: the smallest input encoded as `v` or more (v ≥ 1).
    thresholds: [f32; 256],
    /// The encoding of the smallest float of each 16-bit prefix in [0, 1).
    guess: Vec<u8>,
}

/// The 16-bit prefix of 1.0: prefixes below it are the floats in [0, 1).
const ONE_PREFIX: usize = (0x3F80_0000u32 >> 16) as usize;

impl Encoder {
    /// The encoder of `space`, built on first use.
    pub fn for_space(space: ColorSpace) -> &'static Encoder {
        static LINEAR: OnceLock<Encoder> = OnceLock::new();
        static SRGB: OnceLock<Encoder> = OnceLock::new();
        match space {
            ColorSpace::Linear => LINEAR.get_or_init(|| Encoder::new(space)),
            ColorSpace::Srgb => SRGB.get_or_init(|| Encoder::new(space)),
        }
    }

    fn new(space: ColorSpace) -> Self {
        let exact = |v: f32| space.encode(Color::splat(v))[0];
        let mut thresholds = [0.0; 256];
        for (v, threshold) in thresholds.iter_mut().enumerate().skip(1) {
            // The smallest non-negative float encoded as v or more: a
            // binary search over bit patterns (ordered as the floats are).
            let (mut lo, mut hi) = (0u32, 1.0f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if exact(f32::from_bits(mid)) as usize >= v { hi = mid } else { lo = mid + 1 }
            }
            *threshold = f32::from_bits(lo);
        }
        let guess = (0..ONE_PREFIX).map(|p| exact(f32::from_bits((p as u32) << 16))).collect();
        Self { thresholds, guess }
    }

    /// `space.encode` of `v` alone: clamped to [0, 1] (NaN as 0), encoded,
    /// rounded to 8 bits.
    #[inline]
    pub fn encode(&self, v: f32) -> u8 {
        if v.is_nan() || v <= 0.0 {
            return 0;
        }
        if v >= 1.0 {
            return 255;
        }
        let mut e = self.guess[(v.to_bits() >> 16) as usize];
        while e < 255 && v >= self.thresholds[e as usize + 1] {
            e += 1;
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floats from 0 to past 1: a dense spread of bit patterns, the
    /// encoders' thresholds and their neighbours, and the odd ones.
    fn samples() -> Vec<f32> {
        let mut v: Vec<f32> = (0..0x3F90_0000u32).step_by(4099).map(f32::from_bits).collect();
        for space in [ColorSpace::Linear, ColorSpace::Srgb] {
            for &t in &Encoder::for_space(space).thresholds[1..] {
                v.extend([f32::from_bits(t.to_bits() - 1), t, f32::from_bits(t.to_bits() + 1)]);
            }
        }
        v.extend([-0.0, -1.0, 1.0, 2.0, 1e30, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, 0.5, 0.216]);
        v
    }

    #[test]
    fn exposure_zero_in_the_rgb_view_is_bit_for_bit_the_colour_space_encoding() {
        for space in [ColorSpace::Linear, ColorSpace::Srgb] {
            let d = Display { color_space: space, ..Display::default() };
            assert!(d.is_plain());
            let s = samples();
            for (i, &r) in s.iter().enumerate() {
                let c = [r, s[(i * 7 + 3) % s.len()], s[(i * 13 + 5) % s.len()]];
                let [er, eg, eb] = space.encode(Color::from_array(c));
                assert_eq!(d.texel(c), Color32::from_rgb(er, eg, eb), "{space:?} {c:?}");
            }
        }
    }

    #[test]
    fn exposure_multiplies_by_two_to_the_stops() {
        let d = Display { exposure: 1.0, ..Display::default() };
        assert_eq!(d.texel([0.25, 0.5, 0.75]), Color32::from_rgb(128, 255, 255));
        let d = Display { exposure: -2.0, ..Display::default() };
        assert_eq!(d.texel([2.0, 1.0, 0.0]), Color32::from_rgb(128, 64, 0));
    }

    #[test]
    fn channel_views_show_one_channel_or_the_rec_709_luminance_as_grey() {
        let c = [0.2, 0.4, 0.8];
        let view = |channel| Display { channel, ..Display::default() }.texel(c);
        assert_eq!(view(Channel::R), Color32::from_gray(51));
        assert_eq!(view(Channel::G), Color32::from_gray(102));
        assert_eq!(view(Channel::B), Color32::from_gray(204));
        // 0.2126·0.2 + 0.7152·0.4 + 0.0722·0.8 = 0.38656 → 98.57 → 99.
        assert_eq!(view(Channel::Luminance), Color32::from_gray(99));
        assert!((luminance([1.0, 1.0, 1.0]) - 1.0).abs() < 1e-6, "the weights sum to one");
        assert_eq!(luminance([0.0, 1.0, 0.0]), 0.7152);
    }

    #[test]
    fn false_colour_maps_the_range_ends_to_turbos_ends() {
        let d =
            Display { channel: Channel::FalseColour, false_colour_range: [-4.0, 4.0], ..Display::default() };
        let (low, high) = (turbo(0.0), turbo(1.0));
        // Turbo runs from near black through green to dark red; the
        // polynomial's ends are #23171B and #900D00.
        assert_eq!((low, high), (Color32::from_rgb(0x23, 0x17, 0x1B), Color32::from_rgb(0x90, 0x0D, 0x00)));
        let middle = turbo(0.5);
        assert!(middle.g() > middle.r() && middle.g() > middle.b(), "{middle:?}");
        assert_eq!(d.texel([1.0 / 16.0; 3]), low, "log2 = −4: the low end");
        assert_eq!(d.texel([16.0; 3]), high, "log2 = 4: the high end");
        assert_eq!(d.texel([0.0; 3]), low, "black is below every range");
        assert_eq!(d.texel([1e9; 3]), high, "clamped above");
        assert_eq!(d.texel([1.0; 3]), turbo(0.5), "log2 = 0: the middle");
        // Exposure shifts the luminance before the map.
        let brighter = Display { exposure: 4.0, ..d.clone() };
        assert_eq!(brighter.texel([1.0; 3]), high);
        assert_ne!(turbo(0.5), low);
    }

    #[test]
    fn errors_are_absolute_or_relative_to_the_reference_plus_epsilon() {
        assert_eq!(ErrorKind::Absolute.error(0.25, 0.75), 0.5);
        assert_eq!(ErrorKind::Relative.error(0.25, 0.75), 0.5 / (0.75 + RELATIVE_EPSILON));
        assert_eq!(ErrorKind::Relative.error(0.01, 0.0), 1.0, "ε keeps black references finite");
        let d = Display::default();
        let mut texels = [Color32::BLACK; 2];
        let (a, b) = ([[0.5, 0.5, 0.5], [1.0, 0.0, 0.25]], [[0.25, 0.5, 1.0], [0.0, 0.0, 0.0]]);
        d.row(&a, 1, Some((ErrorKind::Absolute, &b)), &mut texels);
        assert_eq!(texels, [Color32::from_rgb(64, 0, 128), Color32::from_rgb(255, 0, 64)]);
    }

    #[test]
    fn agx_texels_are_the_png_outputs_bytes_at_the_same_exposure() {
        let values =
            [[0.0, 0.0, 0.0], [0.18, 0.18, 0.18], [1.0, 0.5, 0.25], [40.0, 3.0, 0.01], [1e4, 1e4, 1e4]];
        for space in [ColorSpace::Linear, ColorSpace::Srgb] {
            for exposure in [0.0, 1.5, -3.0] {
                let view_transform = ViewTransform::AgX;
                let d = Display { exposure, view_transform, color_space: space, ..Display::default() };
                assert!(!d.is_plain(), "AgX is never the rows' own encoding");
                let png = view_transform::Display { exposure, view_transform };
                for c in values {
                    let [r, g, b] = png.encode(Color::from_array(c), space);
                    assert_eq!(d.texel(c), Color32::from_rgb(r, g, b), "{space:?} {exposure} {c:?}");
                }
            }
        }
        // Not the clamp: AgX rolls 1.0 off to 202 where Standard gives 255.
        let agx = Display { view_transform: ViewTransform::AgX, ..Display::default() };
        assert_eq!(agx.texel([1.0; 3]), Color32::from_gray(202));
        let grey = Display { channel: Channel::G, ..agx };
        assert_eq!(
            grey.texel([0.0, 1.0, 0.0]),
            Color32::from_gray(202),
            "a channel goes through AgX as a grey"
        );
    }

    #[test]
    fn the_encoder_steps_exactly_where_the_encoding_does() {
        for space in [ColorSpace::Linear, ColorSpace::Srgb] {
            let e = Encoder::for_space(space);
            for v in samples() {
                assert_eq!(e.encode(v), space.encode(Color::splat(v))[0], "{space:?} {v}");
            }
        }
    }
}
