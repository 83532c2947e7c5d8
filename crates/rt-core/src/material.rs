//! Materials: how a surface answers light, and how colours become pixels.
//!
//! Colours are linear RGB (proportional to light), `f32` whatever
//! [`crate::real::Real`] is. Scene files give them linear; the output
//! [`ColorSpace`] decides how they are encoded into 8-bit pixels.

use serde::Deserialize;

/// A linear RGB colour; components ≥ 0, nominally in [0, 1] (lit scenes may
/// exceed 1 before the output clamps them).
pub type Color = glam::Vec3;

/// A surface's appearance.
///
/// Without lights (pure ray casting) a hit shows `color` flat and every other
/// field is unused. With lights it is shaded by its BSDF ([`crate::bsdf`]),
/// the mixture
///
/// `f = (1 − kr − kt)·[(1 − ks)·kd·color/π + ks·f_ggx(shininess)] + kr·mirror + kt·glass(ior, color)`
///
/// with `kr = reflectivity`, `kt = transparency`, `ks = specular`,
/// `kd = diffuse`, and it gives off radiance `emission` from the side its
/// geometric normal points to. Every weight is in [0, 1] and kr + kt ≤ 1,
/// so no material reflects more light than arrives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base colour, each component in [0, 1]: the flat colour, the diffuse
    /// albedo and the glass tint.
    pub color: Color,
    /// Diffuse (Lambert) weight kd in [0, 1].
    pub diffuse: f32,
    /// Glossy (GGX) weight ks in [0, 1]; the Lambert lobe gets the rest.
    pub specular: f32,
    /// Blinn–Phong exponent giving the glossy lobe's roughness
    /// ([`Material::roughness`]); larger is a smaller, sharper highlight.
    pub shininess: f32,
    /// Mirror reflection weight kr in [0, 1].
    pub reflectivity: f32,
    /// Transmission weight kt in [0, 1], kr + kt ≤ 1.
    pub transparency: f32,
    /// Index of refraction of the inside (the side the normal points away from), > 0.
    pub ior: f32,
    /// Radiance the surface gives off (W·m⁻²·sr⁻¹) from the side its
    /// geometric normal points to. It is seen directly; under global
    /// illumination it also lights the scene.
    pub emission: Color,
}

impl Material {
    /// A plain diffuse material of `color`, as old (flat-colour) scene files get.
    pub const fn flat(color: Color) -> Self {
        Self {
            color,
            diffuse: 1.0,
            specular: 0.0,
            shininess: 32.0,
            reflectivity: 0.0,
            transparency: 0.0,
            ior: 1.5,
            emission: Color::ZERO,
        }
    }

    /// The GGX roughness α of the glossy lobe, from the Blinn–Phong exponent
    /// s by Walter et al.'s correspondence `α = √(2/(s + 2))` ("Microfacet
    /// Models for Refraction through Rough Surfaces", 2007, eq. 33): 1 for
    /// s = 0, 0.2 for s = 48, 0.014 for s = 10 000.
    pub fn roughness(&self) -> f32 {
        (2.0 / (self.shininess + 2.0)).sqrt()
    }

    /// Whether the surface gives off light.
    pub fn is_emissive(&self) -> bool {
        self.emission != Color::ZERO
    }
}

/// How linear colours are written to 8-bit images.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
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
