//! Which light next-event estimation samples, under global illumination.
//!
//! Every source of light is a candidate: the scene file's `lights`, every
//! emissive object that can be sampled ([`crate::lights::emitter`]), and the
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

use crate::lights::emitter::Emitter;
use crate::lights::environment::Environment;
use crate::lights::light::Light;
use crate::math::real::Real;

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
    /// Running sums of the candidates' powers from 0 (one more than the
    /// candidates: candidate `i` spans `cumulative[i]` to `cumulative[i + 1]`,
    /// with no branch for the first); empty when there are none.
    cumulative: Vec<Real>,
    /// Probability of choosing each light of the scene file.
    light_probability: Vec<Real>,
    /// Probability of choosing each emitter (0 for one that gives off nothing).
    emitter_probability: Vec<Real>,
    environment_probability: Real,
}

impl LightSampler {
    /// The sampler for `lights`, `emitters` and the `environment`, in a
    /// scene that fits in a sphere of radius `radius`.
    pub fn new(lights: &[Light], emitters: &[Emitter], environment: &Environment, radius: Real) -> Self {
        let mut candidates: Vec<(Source, Real)> = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            candidates.push((Source::Light(i), light.power(radius)));
        }
        for (i, e) in emitters.iter().enumerate() {
            candidates.push((Source::Emitter(i), e.power()));
        }
        candidates.push((Source::Environment, environment.power(radius)));
        candidates.retain(|&(_, power)| power > 0.0 && power.is_finite());

        let total: Real = candidates.iter().map(|c| c.1).sum();
        let mut sampler = Self {
            light_probability: vec![0.0; lights.len()],
            emitter_probability: vec![0.0; emitters.len()],
            ..Self::default()
        };
        let mut running = 0.0;
        if !candidates.is_empty() {
            sampler.cumulative.push(running);
        }
        for (source, power) in candidates {
            running += power;
            sampler.sources.push(source);
            sampler.cumulative.push(running);
            let p = power / total;
            match source {
                Source::Light(i) => sampler.light_probability[i] = p,
                Source::Emitter(i) => sampler.emitter_probability[i] = p,
                Source::Environment => sampler.environment_probability = p,
            }
        }
        sampler
    }

    /// Whether there is no light to sample.
    pub fn is_empty(&self) -> bool {
        self.sources.is_empty()
    }

    /// Chooses a source for `u` ∈ [0, 1): the source and its probability.
    #[inline]
    pub fn choose(&self, u: Real) -> Option<(Source, Real)> {
        let total = *self.cumulative.last()?;
        let target = u * total;
        let i = self.cumulative[1..].partition_point(|&c| c <= target).min(self.sources.len() - 1);
        let (below, above) = (self.cumulative[i], self.cumulative[i + 1]);
        Some((self.sources[i], (above - below) / total))
    }

    /// The probability of choosing `source` (0 for one that gives off nothing).
    #[inline]
    pub fn probability(&self, source: Source) -> Real {
        match source {
            Source::Light(i) => self.light_probability.get(i).copied().unwrap_or(0.0),
            Source::Emitter(i) => self.emitter_probability.get(i).copied().unwrap_or(0.0),
            Source::Environment => self.environment_probability,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::primitive::Primitive;
    use crate::geometry::sphere::Sphere;
    use crate::geometry::triangle::Triangle;
    use crate::lights::light::LightKind;
    use crate::math::color::Color;
    use crate::math::real::{Vec3, to_f64};
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square;

    #[test]
    fn sources_are_chosen_in_proportion_to_their_power() {
        let point =
            Light { kind: LightKind::Point { position: Vec3::ZERO }, power: Color::ONE, shadows: true };
        let sphere = Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap());
        // Radiance 1, area 4π: power π·4π = 4π², against the point light's 4π.
        let emitter = Emitter::new(2, &sphere, Color::ONE).unwrap();
        let s = LightSampler::new(&[point], &[emitter], &Environment::default(), 10.0);
        let pi = std::f64::consts::PI as Real;
        let p_point = 4.0 * pi / (4.0 * pi + 4.0 * pi * pi);
        let (source, p) = s.choose(0.0).unwrap();
        assert_eq!(source, Source::Light(0));
        assert!((p - p_point).abs() < 1e-6);
        let (source, p) = s.choose(0.99).unwrap();
        assert_eq!(source, Source::Emitter(0));
        assert!((p + p_point - 1.0).abs() < 1e-6);
        assert!((s.probability(Source::Emitter(0)) - p).abs() < 1e-12);
        assert!((s.probability(Source::Light(0)) - p_point).abs() < 1e-6);
        assert_eq!((s.probability(Source::Environment), s.probability(Source::Emitter(1))), (0.0, 0.0));
    }

    #[test]
    fn a_dark_scene_has_nothing_to_sample() {
        let s = LightSampler::new(&[], &[], &Environment::default(), 1.0);
        assert!(s.is_empty());
        assert_eq!(s.choose(0.5), None);
        let lit = LightSampler::new(&[], &[], &Environment::Constant(Color::splat(0.5)), 1.0);
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
        let s = LightSampler::new(&[light(0.0), light(1.0), light(2.0)], &[], &Environment::default(), 1.0);
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
        let s =
            LightSampler::new(&[point, sun], &emitters, &Environment::Constant(background), radius as Real);
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
        for (i, source) in
            [Source::Light(0), Source::Light(1), Source::Emitter(0), Source::Emitter(1), Source::Environment]
                .into_iter()
                .enumerate()
        {
            assert!((to_f64(s.probability(source)) - expected[i]).abs() < 1e-6, "{source:?}");
        }
    }
}
