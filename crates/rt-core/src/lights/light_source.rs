//! One interface for every light a path can sample: the scene file's point,
//! directional and sphere lights ([`crate::lights::light`]), emissive objects
//! ([`crate::lights::emitter`]) and the environment ([`crate::lights::environment`]).
//!
//! From a shading point, a light gives a direction towards it with what
//! arrives along it ([`LightSource::sample`], Mitsuba 3's
//! `Emitter::sample_direction`, pbrt-v4's `Light::SampleLi`), and says with
//! what density it would have picked a direction that a ray found it along
//! ([`LightSource::pdf`], `pdf_direction`, `PDF_Li`). The path tracer's
//! next-event estimation and its multiple importance sampling go through
//! these two calls alone, so a new kind of light (an environment map) plugs
//! in here without touching the integrator.
//!
//! Point, directional and sphere lights are not geometry: no ray ever finds
//! them, so their samples carry no density for MIS (`pdf: None`, weight 1),
//! and their directions are the same as [`crate::lights::light::Light::sample`]'s.

use crate::lights::emitter::Emitter;
use crate::lights::environment::Environment;
use crate::lights::light::Light;
use crate::math::color::Color;
use crate::math::real::{Real, SHADOW_SHORTEN, Vec3, to_f32};

/// A direction towards a light from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the point towards the light.
    pub wi: Vec3,
    /// How far a shadow ray along `wi` must find nothing for the light to
    /// arrive: just short of the sampled point on an emitter, the distance
    /// to a point or sphere light, ∞ for the environment and directional lights.
    pub distance: Real,
    /// What arrives along `wi` over the density it was sampled with
    /// (`L/pdf`; `I/r²` or `E` for a point or directional light): times
    /// `f·cos θ` it is the sample's estimate of the reflected radiance.
    pub weight: Color,
    /// The density over solid angle `wi` was sampled with, for multiple
    /// importance sampling; `None` for a light no ray can find.
    pub pdf: Option<Real>,
    /// Whether a shadow ray decides if the light arrives (a light of the
    /// scene file may cast no shadows).
    pub shadows: bool,
}

/// One light of a scene, whatever its kind.
#[derive(Clone, Copy, Debug)]
pub enum LightSource<'s> {
    /// A point, directional or sphere light of the scene file.
    Light(&'s Light),
    /// An emissive object.
    Emitter(&'s Emitter),
    /// The environment.
    Environment(&'s Environment),
}

impl LightSource<'_> {
    /// A direction towards the light from `p` for `u` ∈ [0,1)², or `None`
    /// if no light arrives at `p` from it this way (the back of an emitter,
    /// `p` inside a sphere emitter or at a point light).
    #[inline(always)]
    pub fn sample(&self, p: Vec3, u: (Real, Real)) -> Option<LightSample> {
        match self {
            Self::Light(light) => {
                let s = light.sample_one(p, u)?;
                let (weight, shadows) = (s.irradiance, light.shadows);
                Some(LightSample { wi: s.to_light, distance: s.distance, weight, pdf: None, shadows })
            }
            Self::Emitter(e) => {
                let s = e.sample(p, u)?;
                let distance = s.distance * (1.0 - SHADOW_SHORTEN);
                let weight = over(s.radiance, to_f32(s.pdf));
                Some(LightSample { wi: s.wi, distance, weight, pdf: Some(s.pdf), shadows: true })
            }
            Self::Environment(env) => {
                let (wi, pdf) = env.sample(u)?;
                let weight = over(env.radiance(wi), to_f32(pdf));
                Some(LightSample { wi, distance: Real::INFINITY, weight, pdf: Some(pdf), shadows: true })
            }
        }
    }

    /// The density over solid angle with which [`LightSource::sample`]
    /// picks `wi` from `p`, where a ray along it finds the light at
    /// `distance` with unit geometric normal `normal` (both unused for the
    /// environment); 0 for a light no ray can find.
    #[inline]
    pub fn pdf(&self, p: Vec3, wi: Vec3, distance: Real, normal: Vec3) -> Real {
        match self {
            Self::Light(_) => 0.0,
            Self::Emitter(e) => e.pdf(p, wi, distance, normal),
            Self::Environment(env) => env.pdf(wi),
        }
    }
}

/// `c / d`, channel by channel, as one 4-lane division: each quotient
/// correctly rounded, the very bits of `c / d`'s three scalar divisions,
/// which would wait on each other's divider.
#[inline(always)]
fn over(c: Color, d: f32) -> Color {
    (glam::Vec3A::from(c) / d).into()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::primitive::Primitive;
    use crate::geometry::triangle::Triangle;
    use crate::lights::light::LightKind;
    use crate::math::ray::{Interval, Ray};
    use crate::sampling::sampler::SampleRng;

    #[test]
    fn a_sampled_direction_has_the_density_pdf_gives_where_a_ray_finds_the_light() {
        // From a point below a glowing triangle and inside a constant
        // environment: each sample's weight is the radiance over its
        // density, the ray along it finds the light (the triangle at the
        // sample's distance, within the shortening), and `pdf` there gives
        // the sample's density back.
        let corners = [Vec3::new(-1.0, 2.0, -1.0), Vec3::new(1.0, 2.0, -1.0), Vec3::new(0.0, 2.0, 1.5)];
        let triangle = Triangle::new(corners[0], corners[1], corners[2]).unwrap();
        let emitter = Emitter::new(0, &Primitive::Triangle(triangle), Color::new(2.0, 1.0, 0.5)).unwrap();
        let environment = Environment::Constant(Color::splat(0.25));
        let p = Vec3::new(0.2, 0.0, 0.1);
        for k in 0..200u32 {
            let u = SampleRng::new(k, 3, 5).next_pair();
            let s = LightSource::Emitter(&emitter).sample(p, u).expect("the glowing side faces p");
            let pdf = s.pdf.unwrap();
            assert!((s.weight - Color::new(2.0, 1.0, 0.5) / to_f32(pdf)).abs().max_element() < 1e-6);
            let hit = triangle.intersect(&Ray::new(p, s.wi), Interval::new(0.0, Real::INFINITY)).unwrap();
            assert!(hit.t >= s.distance && hit.t <= s.distance * (1.0 + 2.0 * SHADOW_SHORTEN), "sample {k}");
            let found = LightSource::Emitter(&emitter).pdf(p, s.wi, hit.t, hit.normal);
            assert!((found - pdf).abs() <= 1e-4 * pdf, "sample {k}: {found} against {pdf}");

            let s = LightSource::Environment(&environment).sample(p, u).unwrap();
            let pdf = s.pdf.unwrap();
            assert_eq!((s.distance, s.weight), (Real::INFINITY, Color::splat(0.25) / to_f32(pdf)));
            assert_eq!(LightSource::Environment(&environment).pdf(p, s.wi, Real::INFINITY, -s.wi), pdf);
        }
    }

    #[test]
    fn a_colour_over_a_density_has_the_bits_of_three_scalar_divisions() {
        let mut rng = SampleRng::new(4, 4, 2);
        for _ in 0..4096 {
            let (a, b) = rng.next_pair();
            let (c, d) = rng.next_pair();
            let colour = Color::new(to_f32(a) * 1e3, to_f32(b) * 1e-3, to_f32(c)) * 7.0;
            let d = to_f32(d) * to_f32(d) * 1e4 + 1e-30;
            let (simd, scalar) = (over(colour, d), colour / d);
            assert_eq!(
                simd.to_array().map(f32::to_bits),
                scalar.to_array().map(f32::to_bits),
                "{colour} / {d}"
            );
        }
    }

    #[test]
    fn lights_no_ray_can_find_have_no_density_and_keep_their_shadow_setting() {
        let point = Light {
            kind: LightKind::Point { position: Vec3::new(0.0, 4.0, 0.0) },
            power: Color::splat(8.0),
            shadows: false,
        };
        let s = LightSource::Light(&point).sample(Vec3::ZERO, (0.5, 0.5)).unwrap();
        assert_eq!(
            (s.wi, s.distance, s.weight, s.pdf, s.shadows),
            (Vec3::Y, 4.0, Color::splat(0.5), None, false)
        );
        assert_eq!(LightSource::Light(&point).pdf(Vec3::ZERO, Vec3::Y, 4.0, -Vec3::Y), 0.0);
    }
}
