//! Coverage: how much of a surface is there (glTF 2.0 §3.9.4, `alphaMode`).
//!
//! A material's alpha is its base colour's: the factor times the base
//! colour texture's alpha channel where it has one
//! ([`crate::materials::texture::Texture::sample_alpha`]). How it is used:
//!
//! - [`AlphaMode::Opaque`]: not at all; the surface is everywhere.
//! - [`AlphaMode::Mask`]: a cut-out. A point whose alpha is below the
//!   cutoff is not there, for every ray alike (camera, shadow, next-event
//!   and bounce rays, and the viewer's picking): the scene's ray queries
//!   go on past it ([`crate::scene::Scene::closest_hit`]).
//! - [`AlphaMode::Blend`]: *stochastic transparency* (Enderton, Sintorn,
//!   Shirley, Luebke, "Stochastic Transparency", I3D 2010): alpha is the
//!   probability that a ray finds the surface there, decided afresh for
//!   each ray by a hash of the ray and the hit ([`blend_coin`]). Averaged
//!   over a pixel's samples it converges to the alpha-weighted mix of the
//!   surface and what lies behind it, which is what alpha blending shows
//!   and what Cycles does with alpha (transparency by a random decision per
//!   path); unlike sorting and blending it needs no order, applies to
//!   shadows too, and costs nothing where alpha is 1 or 0. Blender's glTF
//!   importer maps `BLEND` to alpha blending, so its renders agree in the
//!   mean.

use crate::math::real::{Real, Vec3};
use crate::sampling::sampler::mix;

/// How a material's alpha decides where its surface is.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum AlphaMode {
    /// Alpha is ignored: the surface is everywhere (glTF's default).
    #[default]
    Opaque,
    /// The surface is there where alpha ≥ `cutoff` (glTF's `alphaCutoff`,
    /// default 0.5), and nowhere else.
    Mask {
        /// The least alpha that is there, in [0, 1].
        cutoff: f32,
    },
    /// Alpha is the probability that the surface is there (see the module
    /// documentation).
    Blend,
}

/// glTF's default `alphaCutoff`.
pub const DEFAULT_ALPHA_CUTOFF: f32 = 0.5;

impl AlphaMode {
    /// Whether the mode ever removes part of a surface.
    #[inline]
    pub fn cuts(self) -> bool {
        self != Self::Opaque
    }

    /// Whether a ray meets the surface at a point of alpha `alpha`; `coin`
    /// is a uniform number in [0, 1) for this ray and hit ([`blend_coin`]),
    /// used only by [`AlphaMode::Blend`] (there if `coin < alpha`).
    #[inline]
    pub fn is_there(self, alpha: f32, coin: impl FnOnce() -> f32) -> bool {
        match self {
            Self::Opaque => true,
            Self::Mask { cutoff } => alpha >= cutoff,
            Self::Blend => alpha >= 1.0 || (alpha > 0.0 && coin() < alpha),
        }
    }
}

/// A uniform number in [0, 1) for the ray from `origin` along `dir` meeting
/// triangle `primitive` of object `object` at `t`: a SplitMix64 hash of the
/// bits. Different rays (every pixel sample's camera ray has its own
/// origin or direction, every shadow ray its own origin) give independent
/// numbers; the same ray the same one, so a query repeated (a packet and
/// a single ray) agrees with itself.
pub fn blend_coin(origin: Vec3, dir: Vec3, t: Real, object: usize, primitive: usize) -> f32 {
    let bits = |x: Real| crate::math::real::to_f64(x).to_bits();
    let mut h = mix(object as u64 ^ ((primitive as u64) << 24) ^ 0x2545_F491_4F6C_DD1D);
    for x in [origin.x, origin.y, origin.z, dir.x, dir.y, dir.z, t] {
        h = mix(h ^ bits(x));
    }
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mask_keeps_alpha_at_or_above_the_cutoff_and_opaque_ignores_it() {
        let mask = AlphaMode::Mask { cutoff: 0.5 };
        assert!(mask.is_there(0.5, || unreachable!()) && !mask.is_there(0.49, || unreachable!()));
        assert!(AlphaMode::Opaque.is_there(0.0, || unreachable!()));
        assert!(!AlphaMode::Opaque.cuts() && mask.cuts() && AlphaMode::Blend.cuts());
    }

    #[test]
    fn blend_is_there_with_probability_alpha() {
        // 20 000 rays through one point: the share that meets the surface
        // is alpha, within 4 standard deviations.
        for alpha in [0.0f32, 0.1, 0.5, 0.9, 1.0] {
            let n = 20_000;
            let there = (0..n)
                .filter(|&k| {
                    let dir = Vec3::new(k as Real * 1e-4, 0.3, 1.0);
                    AlphaMode::Blend.is_there(alpha, || blend_coin(Vec3::ZERO, dir, 2.0, 1, 7))
                })
                .count() as f64
                / n as f64;
            let sigma = (f64::from(alpha) * (1.0 - f64::from(alpha)) / n as f64).sqrt();
            assert!((there - f64::from(alpha)).abs() <= 4.0 * sigma + 1e-12, "alpha {alpha}: {there}");
        }
    }
}
