//! Which light next-event estimation samples, under global illumination.
//!
//! Every source of light is a candidate: the scene file's `lights`, every
//! emissive object that can be sampled ([`crate::emitter`]), and the
//! background, which lights the scene as a constant environment (Mitsuba 3's
//! `constant` emitter). One is chosen per shaded point with probability
//! proportional to an estimate of the power Φ it gives off (pbrt-v4 §12.6.3,
//! `PowerLightSampler`), from the mean of its colour channels and the radius
//! R of a sphere around the scene's bounded objects:
//!
//! | light | Φ |
//! |---|---|
//! | point or sphere light of intensity I | 4π·I |
//! | directional light of irradiance E | π·R²·E |
//! | emitter of radiance L and area A | π·L·A |
//! | background of radiance L | 4π·π·R²·L |
//!
//! The choice only steers where samples go: any choice with a positive
//! probability for every light gives the same image in the mean.

use crate::color::Color;
use crate::emitter::Emitter;
use crate::light::{Light, LightKind};
use crate::real::Real;

/// A source of light that can be chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// `lights[i]` of the scene file.
    Light(usize),
    /// The scene's `i`-th emitter.
    Emitter(usize),
    /// The background, as a constant environment.
    Environment,
}

/// The candidates and the probability of choosing each.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightSampler {
    sources: Vec<Source>,
    /// Running sums of the candidates' powers.
    cumulative: Vec<Real>,
    /// Probability of choosing each object's emitter (0 for the others).
    object_probability: Vec<Real>,
    environment_probability: Real,
}

impl LightSampler {
    /// The sampler for `lights`, the `emitters` of a scene of `objects`
    /// objects, and `background`, in a scene of radius `radius`.
    pub fn new(
        lights: &[Light],
        emitters: &[Emitter],
        background: Color,
        objects: usize,
        radius: Real,
    ) -> Self {
        let pi = std::f64::consts::PI as Real;
        let mean = |c: Color| (c.element_sum() / 3.0) as Real;
        let mut candidates: Vec<(Source, Real)> = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            let power = match light.kind {
                LightKind::Point { .. } | LightKind::Sphere { .. } => 4.0 * pi * mean(light.power),
                LightKind::Directional { .. } => pi * radius * radius * mean(light.power),
            };
            candidates.push((Source::Light(i), power));
        }
        for (i, e) in emitters.iter().enumerate() {
            candidates.push((Source::Emitter(i), e.power()));
        }
        candidates.push((Source::Environment, 4.0 * pi * pi * radius * radius * mean(background)));
        candidates.retain(|&(_, power)| power > 0.0 && power.is_finite());

        let total: Real = candidates.iter().map(|c| c.1).sum();
        let mut sampler = Self { object_probability: vec![0.0; objects], ..Self::default() };
        let mut running = 0.0;
        for (source, power) in candidates {
            running += power;
            sampler.sources.push(source);
            sampler.cumulative.push(running);
            let p = power / total;
            match source {
                Source::Emitter(i) => sampler.object_probability[emitters[i].object] = p,
                Source::Environment => sampler.environment_probability = p,
                Source::Light(_) => {}
            }
        }
        sampler
    }

    /// Whether there is no light to sample.
    pub fn is_empty(&self) -> bool {
        self.sources.is_empty()
    }

    /// Chooses a source for `u` ∈ [0, 1): the source and its probability.
    pub fn choose(&self, u: Real) -> Option<(Source, Real)> {
        let total = *self.cumulative.last()?;
        let target = u * total;
        let i = self.cumulative.partition_point(|&c| c <= target).min(self.sources.len() - 1);
        let below = if i == 0 { 0.0 } else { self.cumulative[i - 1] };
        Some((self.sources[i], (self.cumulative[i] - below) / total))
    }

    /// The probability of choosing the emitter of object `object` (0 if it
    /// is not a sampled emitter).
    pub fn object_probability(&self, object: usize) -> Real {
        self.object_probability.get(object).copied().unwrap_or(0.0)
    }

    /// The probability of choosing the environment.
    pub fn environment_probability(&self) -> Real {
        self.environment_probability
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::chi_square;
    use crate::primitive::Primitive;
    use crate::real::{Vec3, to_f64};
    use crate::sampler::SampleRng;
    use crate::sphere::Sphere;
    use crate::triangle::Triangle;

    #[test]
    fn sources_are_chosen_in_proportion_to_their_power() {
        let point =
            Light { kind: LightKind::Point { position: Vec3::ZERO }, power: Color::ONE, shadows: true };
        let sphere = Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap());
        // Radiance 1, area 4π: power π·4π = 4π², against the point light's 4π.
        let emitter = Emitter::new(2, &sphere, Color::ONE).unwrap();
        let s = LightSampler::new(&[point], &[emitter], Color::ZERO, 3, 10.0);
        let pi = std::f64::consts::PI as Real;
        let p_point = 4.0 * pi / (4.0 * pi + 4.0 * pi * pi);
        let (source, p) = s.choose(0.0).unwrap();
        assert_eq!(source, Source::Light(0));
        assert!((p - p_point).abs() < 1e-6);
        let (source, p) = s.choose(0.99).unwrap();
        assert_eq!(source, Source::Emitter(0));
        assert!((p + p_point - 1.0).abs() < 1e-6);
        assert!((s.object_probability(2) - p).abs() < 1e-12);
        assert_eq!((s.object_probability(0), s.environment_probability()), (0.0, 0.0));
    }

    #[test]
    fn a_dark_scene_has_nothing_to_sample() {
        let s = LightSampler::new(&[], &[], Color::ZERO, 4, 1.0);
        assert!(s.is_empty());
        assert_eq!(s.choose(0.5), None);
        let lit = LightSampler::new(&[], &[], Color::splat(0.5), 4, 1.0);
        assert!(!lit.is_empty());
        assert_eq!(lit.choose(0.5).unwrap(), (Source::Environment, 1.0));
    }

    #[test]
    fn a_number_rounded_up_to_one_still_chooses_the_last_source() {
        // u is drawn from [0, 1), but a caller's arithmetic may round it up
        // to 1: u·total then equals the last cumulative power, which every
        // entry is ≤, and the choice must stay the last source, not run off.
        let light = |x: Real| Light {
            kind: LightKind::Point { position: Vec3::new(x, 0.0, 0.0) },
            power: Color::splat(1.0),
            shadows: true,
        };
        let s = LightSampler::new(&[light(0.0), light(1.0), light(2.0)], &[], Color::ZERO, 4, 1.0);
        assert_eq!(s.choose(1.0).unwrap().0, Source::Light(2));
        // The largest number below 1.
        assert_eq!(s.choose(1.0 - Real::EPSILON / 2.0).unwrap().0, Source::Light(2));
    }

    #[test]
    fn sources_are_chosen_as_often_as_their_share_of_the_power() {
        // Two lights, two emitters and the background, with the powers of
        // the table in the module's doc, worked out here: χ² of 2·10⁵
        // choices against Φᵢ/ΣΦ (α ≈ 10⁻⁴), and every reported probability
        // equal to it.
        let pi = std::f64::consts::PI;
        let radius = 3.0;
        let point = Light {
            kind: LightKind::Point { position: Vec3::ZERO },
            power: Color::new(1.0, 2.0, 3.0),
            shadows: true,
        };
        let sun = Light {
            kind: LightKind::Directional { direction: -Vec3::Y },
            power: Color::splat(0.5),
            shadows: true,
        };
        let sphere = Primitive::Sphere(Sphere::new(Vec3::ZERO, 0.5).unwrap());
        let triangle = Primitive::Triangle(
            Triangle::new(Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)).unwrap(),
        );
        let emitters = [
            Emitter::new(1, &sphere, Color::splat(2.0)).unwrap(),
            Emitter::new(3, &triangle, Color::new(0.5, 1.0, 1.5)).unwrap(),
        ];
        let background = Color::splat(0.01);
        let power = [
            4.0 * pi * 2.0,                         // point light, I = 2
            pi * radius * radius * 0.5,             // directional, E = 0.5
            pi * 2.0 * 4.0 * pi * 0.25,             // sphere emitter, L = 2, A = 4π·0.5²
            pi * 1.0 * 6.0,                         // triangle emitter, L = 1, A = 6
            4.0 * pi * pi * radius * radius * 0.01, // background, L = 0.01
        ];
        let total: f64 = power.iter().sum();
        let expected: Vec<f64> = power.iter().map(|p| p / total).collect();
        let s = LightSampler::new(&[point, sun], &emitters, background, 4, radius as Real);
        let index = |source: Source| match source {
            Source::Light(i) => i,
            Source::Emitter(i) => 2 + i,
            Source::Environment => 4,
        };
        let draw = |rng: &mut SampleRng| {
            let (source, p) = s.choose(rng.next_pair().0)?;
            let i = index(source);
            assert!((to_f64(p) - expected[i]).abs() < 1e-5, "{source:?}: {p} against {}", expected[i]);
            Some(i)
        };
        chi_square::discrete("light choice", &expected, 200_000, draw);
        assert!((to_f64(s.object_probability(1)) - expected[2]).abs() < 1e-6);
        assert!((to_f64(s.object_probability(3)) - expected[3]).abs() < 1e-6);
        assert!((to_f64(s.environment_probability()) - expected[4]).abs() < 1e-6);
        assert_eq!((s.object_probability(0), s.object_probability(2)), (0.0, 0.0));
    }
}
