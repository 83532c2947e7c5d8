//! Lights: point, directional and spherical area lights.
//!
//! A light is not geometry: rays never hit it. Each one says, for a shaded
//! point, from which direction and distance light arrives and how much
//! ([`Light::sample`]); an area light answers differently for each sample,
//! which is what makes its shadows soft.

use crate::material::Color;
use crate::real::{Real, Vec3, to_f32};
use crate::sampler::{concentric_disk, stratified};

/// One light of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// What kind and where.
    pub kind: LightKind,
    /// Colour times intensity: radiant intensity for point and sphere lights
    /// (irradiance at distance r is `power / r²`), irradiance for directional ones.
    pub power: Color,
    /// Whether objects between a point and this light shade it.
    pub shadows: bool,
}

/// The shape of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// All light from one point.
    Point {
        /// World position.
        position: Vec3,
    },
    /// Parallel light from infinitely far away.
    Directional {
        /// Unit direction the light travels in (e.g. −y shines downward).
        direction: Vec3,
    },
    /// A glowing sphere: the point light's intensity spread over the disk the
    /// sphere shows to the shaded point, sampled `samples` times.
    Sphere {
        /// Centre, world units.
        center: Vec3,
        /// Radius, world units, > 0.
        radius: Real,
        /// Shadow samples per shaded point, ≥ 1.
        samples: u32,
    },
}

/// Light arriving at a point from one sample of a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub to_light: Vec3,
    /// Distance to the light along `to_light`; ∞ for directional lights.
    pub distance: Real,
    /// Irradiance on a surface facing the light, already divided by the
    /// number of samples, so a light's samples add up.
    pub irradiance: Color,
}

impl Light {
    /// How many samples [`Light::sample`] takes per shaded point.
    pub fn sample_count(&self) -> u32 {
        match self.kind {
            LightKind::Sphere { samples, .. } => samples,
            _ => 1,
        }
    }

    /// Sample `k` of [`Light::sample_count`] seen from `p`; `jitter` ∈ [0,1)²
    /// places it inside its stratum. `None` if `p` is at the light itself.
    pub fn sample(&self, p: Vec3, k: u32, jitter: (Real, Real)) -> Option<LightSample> {
        let towards = |target: Vec3, share: f32| {
            let v = target - p;
            let distance = v.length();
            (distance > 0.0 && distance.is_finite()).then(|| LightSample {
                to_light: v / distance,
                distance,
                irradiance: self.power * (share / to_f32(distance * distance)),
            })
        };
        match self.kind {
            LightKind::Point { position } => towards(position, 1.0),
            LightKind::Directional { direction } => {
                Some(LightSample { to_light: -direction, distance: Real::INFINITY, irradiance: self.power })
            }
            LightKind::Sphere { center, radius, samples } => {
                let axis = center - p;
                let distance = axis.length();
                let share = 1.0 / samples as f32;
                // From inside the light (or at its centre) it is a point light.
                if !(distance > radius && distance.is_finite()) {
                    return towards(center, share);
                }
                let w = axis * distance.recip(); // As `normalize` computes it.
                // The disk through the centre facing p (Shirley & Chiu's
                // concentric map keeps the strata compact).
                let (u, v) = w.any_orthonormal_pair();
                let (dx, dy) = concentric_disk(stratified(k, samples, jitter));
                towards(center + radius * (dx * u + dy * v), share)
            }
        }
    }
}
