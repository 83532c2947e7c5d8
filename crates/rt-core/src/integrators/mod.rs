//! The light transport a render runs: one integrator, chosen by what the
//! render asks for ([`EffectPlan`]).
//!
//! - [`Tracer`], direct lighting (Whitted): flat colours without lights;
//!   else lights, shadows, mirror and glass recursion, ambient occlusion.
//! - [`PathTracer`], global illumination: path tracing with next-event
//!   estimation and multiple importance sampling, random walks through
//!   translucent objects.
//!
//! Both turn a camera ray that was already cast (packets of primary rays
//! are cast together) into the radiance arriving along it, and cast only
//! the kinds of rays the plan allows, counted in [`RayCounts`].

pub mod interaction;
pub mod path_tracer;
pub(crate) mod random_walk;
pub mod tracer;

use crate::explain::recorder::{NoRecorder, Recorder};
use crate::geometry::hit::Hit;
use crate::integrators::path_tracer::PathTracer;
use crate::integrators::tracer::Tracer;
use crate::materials::texture_lod::RayCone;
use crate::math::color::Color;
use crate::math::ray::Ray;
use crate::sampling::sampler::Sampler;
use crate::scene::Scene;
use crate::scene::effects::{EffectPlan, RayCounts};

/// The integrator of one render.
#[derive(Clone, Copy, Debug)]
pub enum Integrator<'s> {
    /// Direct lighting ([`crate::integrators::tracer`]).
    Direct(Tracer<'s>),
    /// Path tracing ([`crate::integrators::path_tracer`]).
    Path(PathTracer<'s>),
}

impl<'s> Integrator<'s> {
    /// The integrator for `plan` in `scene`: path tracing under global
    /// illumination, else direct lighting.
    pub fn new(scene: &'s Scene, plan: EffectPlan) -> Self {
        match plan.global_illumination {
            Some(gi) => Self::Path(PathTracer::new(scene, gi, plan.subsurface)),
            None => Self::Direct(Tracer::new(scene, plan)),
        }
    }

    /// This integrator with camera rays of cone `cone`, for texture level
    /// of detail ([`crate::materials::texture_lod`]).
    pub fn with_cone(self, cone: RayCone) -> Self {
        match self {
            Self::Direct(tracer) => Self::Direct(tracer.with_cone(cone)),
            Self::Path(path_tracer) => Self::Path(path_tracer.with_cone(cone)),
        }
    }

    /// The radiance arriving along the camera ray `ray`, whose hit was found
    /// already (`hit`, by [`Scene::cast`]); `sampler` hands out this pixel
    /// sample's random numbers.
    #[inline]
    pub fn radiance(
        &self,
        ray: &Ray,
        hit: Option<Hit>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> Color {
        self.radiance_recorded(ray, hit, sampler, counts, &mut NoRecorder)
    }

    /// [`Integrator::radiance`], telling `rec` every ray cast and every term
    /// added ([`crate::explain`]): the same computation, bit for bit.
    #[inline]
    pub fn radiance_recorded<R: Recorder>(
        &self,
        ray: &Ray,
        hit: Option<Hit>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        match self {
            Self::Direct(tracer) => tracer.trace_primary_hit(ray, hit, sampler, counts, rec),
            Self::Path(path_tracer) => path_tracer.trace_primary_hit(ray, hit, sampler, counts, rec),
        }
    }
}
