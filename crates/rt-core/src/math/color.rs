//! Colours: linear RGB, and how they become 8-bit pixels.
//!
//! Colours are linear RGB (proportional to light), `f32` whatever
//! [`crate::math::real::Real`] is. Scene files give them linear; the output
//! [`ColorSpace`] decides how they are encoded into 8-bit pixels.

use serde::Deserialize;

/// A linear RGB colour; components ≥ 0, nominally in [0, 1] (lit scenes may
/// exceed 1 before the output clamps them).
pub type Color = glam::Vec3;

/// How linear colours are written to 8-bit images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum ColorSpace {
    /// Each component clamped to [0, 1] and scaled to 0..=255 as is: what
    /// flat-colour scenes always did, so a colour (0.5, …) in the file is
    /// pixel value 128.
    #[default]
    Linear,
    /// The sRGB transfer curve (IEC 61966-2-1) applied after clamping: what
    /// displays expect for physically linear light, so lit scenes look right.
    Srgb,
}

impl ColorSpace {
    /// `c` clamped to [0, 1], encoded, and rounded to 8 bits (NaN becomes 0).
    pub fn encode(self, c: Color) -> [u8; 3] {
        c.to_array().map(|v| {
            let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
            let v = match self {
                Self::Linear => v,
                Self::Srgb => srgb_encode(v),
            };
            (v * 255.0 + 0.5) as u8
        })
    }
}

/// The sRGB transfer function for a linear value in [0, 1]:
/// `12.92·v` below 0.0031308, else `1.055·v^(1/2.4) − 0.055`.
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_encoding_clamps_and_rounds() {
        assert_eq!(ColorSpace::Linear.encode(Color::new(-1.0, 0.5, 2.0)), [0, 128, 255]);
        assert_eq!(ColorSpace::Linear.encode(Color::new(f32::NAN, 0.0, 1.0)), [0, 0, 255]);
    }

    #[test]
    fn srgb_encoding_brightens_mid_greys_and_keeps_the_ends() {
        assert_eq!(ColorSpace::Srgb.encode(Color::new(0.0, 1.0, 0.216)), [0, 255, 128]);
        assert!((srgb_encode(0.003_130_8) - 0.040_45).abs() < 1e-5, "the two pieces meet");
    }
}
