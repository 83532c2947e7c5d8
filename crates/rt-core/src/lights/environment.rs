//! The environment: the light that arrives along rays that leave the scene.
//!
//! Today it is one constant radiance in every direction (a scene file's
//! `background`; Mitsuba 3's `constant` emitter): what a camera ray that
//! hits nothing shows, and, under global illumination, a light that
//! next-event estimation samples like any other ([`crate::lights::light_source`]).

use crate::math::color::Color;
use crate::math::real::{Real, Vec3};
use crate::sampling::sampler::{uniform_sphere, uniform_sphere_pdf};

/// The light arriving from outside the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Color),
}

impl Default for Environment {
    /// Black: no light from outside.
    fn default() -> Self {
        Self::Constant(Color::ZERO)
    }
}

impl Environment {
    /// The radiance arriving along a ray that leaves the scene in direction `_dir`.
    #[inline]
    pub fn radiance(&self, _dir: Vec3) -> Color {
        match self {
            Self::Constant(c) => *c,
        }
    }

    /// A direction for `u` ∈ [0,1)² and its density over solid angle: for
    /// a constant environment, uniform over the sphere ([`uniform_sphere`]).
    #[inline]
    pub fn sample(&self, u: (Real, Real)) -> (Vec3, Real) {
        match self {
            Self::Constant(_) => (uniform_sphere(u), uniform_sphere_pdf()),
        }
    }

    /// The density over solid angle with which [`Environment::sample`] picks `_wi`.
    #[inline]
    pub fn pdf(&self, _wi: Vec3) -> Real {
        match self {
            Self::Constant(_) => uniform_sphere_pdf(),
        }
    }

    /// The power it sends into a scene that fits in a sphere of radius
    /// `radius`, for choosing among lights: `4π·π·R²·L` (radiance L from
    /// every direction through the sphere's cross-section πR²; the mean of
    /// the colour channels).
    pub fn power(&self, radius: Real) -> Real {
        let pi = std::f64::consts::PI as Real;
        match self {
            Self::Constant(c) => 4.0 * pi * pi * radius * radius * (c.element_sum() / 3.0) as Real,
        }
    }
}
