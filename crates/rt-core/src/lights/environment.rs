//! The environment: the light that arrives along rays that leave the scene.
//!
//! Either one constant radiance in every direction (a scene file's
//! `background`; Mitsuba 3's `constant` emitter) or an image of it, an
//! environment map, perhaps with a sun ([`crate::lights::environment_map`];
//! a sky is a map made from a sky model, [`crate::lights::sky`]). It is
//! what a camera ray that hits nothing shows, and, under global
//! illumination, a light that next-event estimation samples like any other
//! ([`crate::lights::light_source`]).

use std::sync::Arc;

use crate::lights::environment_map::EnvironmentMap;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3};
use crate::sampling::sampler::{uniform_sphere, uniform_sphere_pdf};

/// The light arriving from outside the scene.
#[derive(Clone, Debug, PartialEq)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Color),
    /// An equirectangular image of the radiance, perhaps with a sun; shared,
    /// since a map can be large.
    Map(Arc<EnvironmentMap>),
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
    pub fn radiance(&self, dir: Vec3) -> Color {
        match self {
            Self::Constant(c) => *c,
            Self::Map(map) => map.radiance(dir),
        }
    }

    /// A unit direction for `u` ∈ [0,1)² and its density over solid angle,
    /// or `None` where there is none: for a constant environment, uniform
    /// over the sphere ([`uniform_sphere`]); for a map, by its brightness
    /// ([`EnvironmentMap::sample`]).
    #[inline]
    pub fn sample(&self, u: (Real, Real)) -> Option<(Vec3, Real)> {
        match self {
            Self::Constant(_) => Some((uniform_sphere(u), uniform_sphere_pdf())),
            Self::Map(map) => map.sample(u),
        }
    }

    /// The density over solid angle with which [`Environment::sample`] picks unit `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> Real {
        match self {
            Self::Constant(_) => uniform_sphere_pdf(),
            Self::Map(map) => map.pdf(wi),
        }
    }

    /// The power it sends into a scene that fits in a sphere of radius
    /// `radius`, for choosing among lights: `4π·π·R²·L` (radiance L from
    /// every direction through the sphere's cross-section πR²; the mean of
    /// the colour channels); for a map, `πR²·∫L dω`.
    pub fn power(&self, radius: Real) -> Real {
        let pi = std::f64::consts::PI as Real;
        match self {
            Self::Constant(c) => 4.0 * pi * pi * radius * radius * (c.element_sum() / 3.0) as Real,
            Self::Map(map) => pi * radius * radius * map.radiance_integral() as Real,
        }
    }
}
