//! From scene radiance to display pixels: an exposure in stops, then a view
//! transform, then the 8-bit encoding. Pure functions of one pixel, so the
//! viewer can apply them to an image it already has; an EXR output stays
//! linear scene radiance and gets none of this.
//!
//! ```text
//! c' = c · 2^exposure
//! Standard: pixel = color_space.encode(c')        (clamp to [0,1], then linear or sRGB)
//! AgX:      pixel = sRGB(agx(c'))                  (rolls highlights off, never clips to a flat colour)
//! ```
//!
//! `Standard` at exposure 0 is exactly the encoding without a view
//! transform (2⁰ = 1 multiplies exactly), so existing PNGs stay the same bit
//! for bit.
//!
//! # AgX
//!
//! Troy Sobotka's AgX, the view transform Blender uses by default since 4.0,
//! in Benjamin Wrensch's minimal form ("Minimal AgX Implementation",
//! iolite engine blog, 2023): the colour is taken into AgX's inset primaries
//! by a 3 × 3 matrix (which desaturates what is very bright, so it goes to
//! white instead of a clipped hue), encoded as log₂ between −12.47393 and
//! +4.026069 stops around 1 (mid grey 0.18 lands at 10/16.5 of the way),
//! shaped by a 6th-order polynomial fit of AgX's default contrast curve
//! (the author gives its mean squared error over [0, 1] as 3.67·10⁻⁶),
//! taken back by the inverse inset matrix, and raised to 2.2 to give
//! display-linear light, which is then sRGB-encoded. Mid grey 0.18 becomes
//! 0.2145 display-linear, pixel value 128; 1.0 becomes 0.590 (202); the
//! curve reaches 0.997 (255) near 100. Blender's own AgX adds a look
//! transform and a different outset; this is the base curve.

use serde::Deserialize;

use crate::math::color::{Color, ColorSpace, srgb_encode};

/// How linear colours become display colours.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum ViewTransform {
    /// Clamp to [0, 1] and encode in the scene's colour space: what images
    /// always were.
    #[default]
    Standard,
    /// AgX's base curve (see the module's documentation), sRGB-encoded.
    AgX,
}

impl ViewTransform {
    /// Its name as the command line and the scene file write it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Standard => "standard",
            Self::AgX => "agx",
        }
    }
}

impl std::str::FromStr for ViewTransform {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "standard" => Ok(Self::Standard),
            "agx" => Ok(Self::AgX),
            _ => Err(format!("unknown view transform \"{s}\": standard or agx")),
        }
    }
}

/// The exposure and view transform an image is shown or saved with.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Display {
    /// Stops: each +1 doubles the light (finite).
    pub exposure: f32,
    /// The curve from scene light to display light.
    pub view_transform: ViewTransform,
}

/// The most stops of exposure either way: 2⁶⁴ covers any scene's light.
pub const MAX_EXPOSURE_STOPS: f32 = 64.0;

impl Display {
    /// `c` exposed, transformed and encoded into 8 bits (see the module's
    /// documentation). NaN components become 0.
    #[inline]
    pub fn encode(&self, c: Color, color_space: ColorSpace) -> [u8; 3] {
        let c = if self.exposure == 0.0 { c } else { c * self.exposure.exp2() };
        match self.view_transform {
            ViewTransform::Standard => color_space.encode(c),
            ViewTransform::AgX => ColorSpace::Srgb.encode(agx(c)),
        }
    }
}

/// Linear Rec. 709 into AgX's inset primaries (Wrensch's `agx_mat`, rows).
const AGX_INSET: [[f32; 3]; 3] = [
    [0.842_479_06, 0.078_433_6, 0.079_223_745],
    [0.042_328_242, 0.878_468_6, 0.079_166_13],
    [0.042_375_655, 0.078_433_6, 0.879_143],
];
/// Back from the inset primaries (Wrensch's `agx_mat_inv`, rows).
const AGX_OUTSET: [[f32; 3]; 3] = [
    [1.196_879, -0.098_020_88, -0.099_029_74],
    [-0.052_896_85, 1.151_903_1, -0.098_961_18],
    [-0.052_971_635, -0.098_043_45, 1.151_073_7],
];
/// The log₂ range encoded, in stops relative to 1.
const AGX_MIN_EV: f32 = -12.473_93;
const AGX_MAX_EV: f32 = 4.026_069;

fn times(m: &[[f32; 3]; 3], c: Color) -> Color {
    Color::new(
        m[0].iter().zip(c.to_array()).map(|(a, b)| a * b).sum(),
        m[1].iter().zip(c.to_array()).map(|(a, b)| a * b).sum(),
        m[2].iter().zip(c.to_array()).map(|(a, b)| a * b).sum(),
    )
}

/// Wrensch's 6th-order fit of AgX's default contrast curve on [0, 1].
fn agx_contrast(x: f32) -> f32 {
    let (x2, x4) = (x * x, x * x * x * x);
    15.5 * x4 * x2 - 40.14 * x4 * x + 31.96 * x4 - 6.868 * x2 * x + 0.4298 * x2 + 0.1191 * x - 0.00232
}

/// AgX of linear `c` (≥ 0; negative and NaN count as 0): display-linear
/// light in [0, 1], to be sRGB-encoded.
pub fn agx(c: Color) -> Color {
    let inset = times(&AGX_INSET, c);
    let shaped = inset.to_array().map(|v| {
        let ev = if v > 0.0 { v.log2().clamp(AGX_MIN_EV, AGX_MAX_EV) } else { AGX_MIN_EV };
        agx_contrast((ev - AGX_MIN_EV) / (AGX_MAX_EV - AGX_MIN_EV))
    });
    times(&AGX_OUTSET, Color::from_array(shaped)).max(Color::ZERO).powf(2.2).min(Color::ONE)
}

/// The sRGB code value (0 to 1) AgX gives a grey of linear value `v`:
/// for documentation and tests.
pub fn agx_grey(v: f32) -> f32 {
    srgb_encode(agx(Color::splat(v)).y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_at_exposure_zero_is_the_plain_encoding_bit_for_bit() {
        let d = Display::default();
        for k in 0..2000 {
            let v = k as f32 * 0.0007 - 0.1;
            let c = Color::new(v, v * 3.0, f32::NAN);
            for space in [ColorSpace::Linear, ColorSpace::Srgb] {
                assert_eq!(d.encode(c, space), space.encode(c));
            }
        }
    }

    #[test]
    fn one_stop_of_exposure_doubles_the_light() {
        let d = Display { exposure: 1.0, view_transform: ViewTransform::Standard };
        assert_eq!(d.encode(Color::splat(0.25), ColorSpace::Linear), [128; 3]);
        let d = Display { exposure: -2.0, ..d };
        assert_eq!(d.encode(Color::splat(1.0), ColorSpace::Linear), [64; 3]);
    }

    #[test]
    fn agx_maps_mid_grey_to_half_and_rolls_highlights_off_without_clipping() {
        // Mid grey 0.18 → display 0.2145 → sRGB 0.5 (pixel 128).
        assert!((agx(Color::splat(0.18)).y - 0.2145).abs() < 5e-4);
        assert_eq!(
            Display { exposure: 0.0, view_transform: ViewTransform::AgX }
                .encode(Color::splat(0.18), ColorSpace::Linear),
            [128; 3]
        );
        // 1.0 is 202, not white; 16 is almost white; black stays black.
        assert!((agx_grey(1.0) * 255.0 - 202.0).abs() < 1.0);
        assert!(agx_grey(16.0) > 0.99 && agx_grey(0.0) == 0.0);
    }

    #[test]
    fn agx_is_monotone_in_grey_and_in_each_channel() {
        let mut last = -1.0;
        for k in 0..=4000 {
            let v = (k as f32 / 4000.0 * 20.0 - 14.0).exp2();
            let g = agx_grey(v);
            assert!(g >= last, "{v}: {g} after {last}");
            last = g;
        }
        let mut last = Color::splat(-1.0);
        for k in 0..=400 {
            let c = agx(Color::new(0.3, (k as f32 / 400.0 * 12.0 - 8.0).exp2(), 0.05));
            assert!(c.y >= last.y, "{c} after {last}");
            last = c;
        }
    }

    #[test]
    fn a_bright_saturated_colour_keeps_its_hue_order_below_white() {
        // The plain clamp turns (4, 0.5, 0.05) into (255, 188, 63): red
        // clipped, the hue shifted to orange. AgX keeps r > g > b, unclipped.
        let c = agx(Color::new(4.0, 0.5, 0.05));
        assert!(c.x > c.y && c.y > c.z && c.x < 1.0, "{c}");
    }

    #[test]
    fn view_transforms_are_named_and_parsed() {
        for t in [ViewTransform::Standard, ViewTransform::AgX] {
            assert_eq!(t.name().parse::<ViewTransform>(), Ok(t));
        }
        assert!("filmic".parse::<ViewTransform>().unwrap_err().contains("standard or agx"));
    }
}
