//! Lights: point, spot, directional and spherical area lights.
//!
//! A light is not geometry: rays never hit it, and the camera does not see
//! it. Each one says, for a shaded point, from which direction and distance
//! light arrives and how much ([`Light::sample`]); an area light answers
//! differently for each sample, which is what makes its shadows soft.
//!
//! Units (pbrt-v4's and Mitsuba 3's, see [`crate::materials::bsdf`]): a point light has
//! radiant intensity I = `color·intensity` in W/sr, so the irradiance it
//! gives a surface facing it at distance r is `I/r²`; a directional light
//! gives irradiance E = `color·intensity` in W/m²; a sphere light of radius
//! R is a sphere of uniform radiance `I/(π·R²)`, whose intensity seen from
//! far away is I in every direction, like the point light it becomes as R
//! shrinks. A spot light is a point light of axial intensity I whose
//! intensity falls off away from its axis as glTF's `KHR_lights_punctual`
//! defines it ([`spot_falloff`]).

use crate::math::color::Color;
use crate::math::real::{Real, SMALL_CONE_SIN2, SPOT_CONE_MIN_WIDTH, Vec3, to_f32};
use crate::sampling::sampler::Strata;

/// One light of a scene.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Light {
    /// What kind and where.
    pub kind: LightKind,
    /// Colour times intensity: radiant intensity I (W/sr) for point and
    /// sphere lights, irradiance E (W/m²) for directional ones.
    pub power: Color,
    /// Whether objects between a point and this light shade it.
    pub shadows: bool,
}

/// The shape of a light.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum LightKind {
    /// All light from one point.
    Point {
        /// World position.
        position: Vec3,
    },
    /// A point light shining into a cone: intensity `power·`[`spot_falloff`]
    /// at angle θ from its axis (glTF's `KHR_lights_punctual` spot light).
    Spot {
        /// World position.
        position: Vec3,
        /// Unit direction of the cone's axis (the way the light shines).
        direction: Vec3,
        /// cos of the angle out to which the intensity is full.
        cos_inner: Real,
        /// cos of the angle beyond which there is no light, `< cos_inner`.
        cos_outer: Real,
    },
    /// Parallel light from infinitely far away.
    Directional {
        /// Unit direction the light travels in (e.g. −y shines downward).
        direction: Vec3,
    },
    /// A glowing sphere of radiance `power/(π·radius²)`, sampled `samples`
    /// times per shaded point by the directions it subtends.
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
    /// What arrives, over the density it was sampled with, divided by the
    /// number of samples: `I/r²` for a point light, `E` for a directional
    /// one, `L/pdf` for a sphere light (L its radiance, pdf the density of
    /// the direction over solid angle). Times `f·cos θ` it is the sample's
    /// share of the reflected radiance, so a light's samples add up.
    pub irradiance: Color,
}

impl Light {
    /// The power it gives off, for choosing among lights (the mean of the
    /// colour channels): `4π·I` for a point or sphere light of intensity I,
    /// `π·R²·E` for a directional light of irradiance E falling on a scene
    /// that fits in a sphere of radius `radius`; for a spot light the
    /// integral of its falloff over the sphere, `2π·I·(1 − cos θₒ − 2w/3)`
    /// with w = cos θᵢ − cos θₒ (at least [`SPOT_CONE_MIN_WIDTH`]): full from
    /// cos θₒ + w to 1, and the squared ramp over the width w below that
    /// integrates to w/3.
    pub fn power(&self, radius: Real) -> Real {
        let pi = std::f64::consts::PI as Real;
        let mean = (self.power.element_sum() / 3.0) as Real;
        match self.kind {
            LightKind::Point { .. } | LightKind::Sphere { .. } => 4.0 * pi * mean,
            LightKind::Spot { cos_inner, cos_outer, .. } => {
                let w = (cos_inner - cos_outer).max(SPOT_CONE_MIN_WIDTH);
                2.0 * pi * mean * (1.0 - cos_outer - 2.0 * w / 3.0)
            }
            LightKind::Directional { .. } => pi * radius * radius * mean,
        }
    }

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
        self.sample_in(&self.strata(), p, k, jitter)
    }

    /// The strata of its [`Light::sample_count`] samples ([`Strata`]): laid
    /// out once per shaded point for [`Light::sample_in`], not once per
    /// sample (the layout takes a square root, divisions and, for some
    /// counts, a search for the cell order's stride).
    pub fn strata(&self) -> Strata {
        Strata::new(self.sample_count())
    }

    /// [`Light::sample`] in `strata`, which must be [`Light::strata`].
    #[inline]
    pub fn sample_in(&self, strata: &Strata, p: Vec3, k: u32, jitter: (Real, Real)) -> Option<LightSample> {
        self.sample_stratum(p, k, strata, jitter)
    }

    /// One sample on its own, at `u` ∈ [0,1)² (a path's next-event estimate).
    pub fn sample_one(&self, p: Vec3, u: (Real, Real)) -> Option<LightSample> {
        self.sample_stratum(p, 0, &Strata::ONE, u)
    }

    /// Sample `k` of the stratified ones laid out as `strata`, at `jitter`
    /// in its stratum.
    fn sample_stratum(&self, p: Vec3, k: u32, strata: &Strata, jitter: (Real, Real)) -> Option<LightSample> {
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
            LightKind::Spot { position, direction, cos_inner, cos_outer } => {
                let v = p - position;
                let cos_theta = direction.dot(v) / v.length();
                towards(position, spot_falloff(cos_theta, cos_inner, cos_outer))
            }
            LightKind::Directional { direction } => {
                Some(LightSample { to_light: -direction, distance: Real::INFINITY, irradiance: self.power })
            }
            LightKind::Sphere { center, radius, .. } => {
                let axis = center - p;
                let distance = axis.length();
                let share = 1.0 / strata.count() as f32;
                // From inside the light (or at its centre) it is a point light.
                if !(distance > radius && distance.is_finite()) {
                    return towards(center, share);
                }
                let w = axis * distance.recip(); // As `normalize` computes it.
                let cone = SphereCone::new(distance, radius);
                let (u, v) = strata.point(k, jitter);
                let (to_light, along) = cone.sample(w, u, v);
                let radiance = self.power / to_f32(std::f64::consts::PI as Real * radius * radius);
                Some(LightSample {
                    to_light,
                    distance: along,
                    irradiance: radiance * (share / to_f32(cone.pdf())),
                })
            }
        }
    }
}

/// A spot light's intensity at angle θ from its axis, relative to the
/// axis's: `clamp((cos θ − cos θₒ)/(cos θᵢ − cos θₒ), 0, 1)²`, full inside
/// the inner cone θᵢ and nothing outside the outer one θₒ. This is the
/// falloff the `KHR_lights_punctual` specification gives in its
/// implementation note (`lightAngleScale`/`lightAngleOffset`, squared), with
/// its floor of 0.001 on `cos θᵢ − cos θₒ` so equal cones do not divide by
/// zero. A NaN `cos_theta` (a point at the light) gives 0.
pub fn spot_falloff(cos_theta: Real, cos_inner: Real, cos_outer: Real) -> f32 {
    let scale = 1.0 / (cos_inner - cos_outer).max(SPOT_CONE_MIN_WIDTH);
    let t = ((cos_theta - cos_outer) * scale).clamp(0.0, 1.0);
    if t.is_nan() { 0.0 } else { to_f32(t * t) }
}

/// The cone of directions a sphere of radius `r` subtends from a point at
/// distance `d > r` from its centre, sampled uniformly (pbrt-v4 §6.2.4,
/// `Sphere::Sample` for reference points outside the sphere).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereCone {
    /// Distance from the point to the sphere's centre.
    d: Real,
    /// The sphere's radius.
    r: Real,
    /// `sin²θ_max = r²/d²`.
    sin2_max: Real,
    /// `1 − cos θ_max`, without cancellation for small cones.
    one_minus_cos_max: Real,
}

impl SphereCone {
    /// The cone of a sphere of radius `r` seen from distance `d > r`.
    pub fn new(d: Real, r: Real) -> Self {
        let sin2_max = (r / d) * (r / d);
        // 1 − √(1 − s) loses s to rounding when it is small; its series
        // s/2 + s²/8 is exact to f32 there (pbrt-v4 uses the same switch).
        let one_minus_cos_max = if sin2_max < SMALL_CONE_SIN2 {
            sin2_max / 2.0 + sin2_max * sin2_max / 8.0
        } else {
            1.0 - (1.0 - sin2_max).sqrt()
        };
        Self { d, r, sin2_max, one_minus_cos_max }
    }

    /// The density of each direction in the cone over solid angle:
    /// `1/(2π·(1 − cos θ_max))`.
    pub fn pdf(&self) -> Real {
        1.0 / (2.0 * std::f64::consts::PI as Real * self.one_minus_cos_max)
    }

    /// The direction for (u, v) ∈ [0,1)² about the unit axis `w` towards the
    /// centre, and the distance along it to the sphere's near surface.
    pub fn sample(&self, w: Vec3, u: Real, v: Real) -> (Vec3, Real) {
        // cos θ uniform in [cos θ_max, 1]: 1 − cos θ = u·(1 − cos θ_max).
        let one_minus_cos = u * self.one_minus_cos_max;
        let cos_theta = 1.0 - one_minus_cos;
        let sin2 = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0);
        let sin_theta = sin2.sqrt();
        let phi = 2.0 * std::f64::consts::PI as Real * v;
        let (a, b) = w.any_orthonormal_pair();
        let dir = (cos_theta * w + sin_theta * (phi.cos() * a + phi.sin() * b)).normalize_or(w);
        // The near intersection of the ray with the sphere: d·cos θ − √(r² − d²·sin²θ).
        let h2 = (self.r * self.r - self.d * self.d * sin2).max(0.0);
        let along = (self.d * cos_theta - h2.sqrt()).max(0.0);
        debug_assert!(sin2 <= self.sin2_max * (1.0 + 1e-3) + 1e-12);
        (dir, along)
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::math::real::{to_f64, widen};
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, SphereGrid};

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() <= 1e-5 * b.length().max(1.0)
    }

    #[test]
    fn a_point_light_is_seen_along_the_line_to_it_with_inverse_square_falloff() {
        // Intensity (1, 2, 3) at (1, 5, −2), seen from (4, 1, −2): 5 away
        // along (−3, 4, 0)/5, irradiance I/25.
        let light = Light {
            kind: LightKind::Point { position: Vec3::new(1.0, 5.0, -2.0) },
            power: Color::new(1.0, 2.0, 3.0),
            shadows: true,
        };
        let s = light.sample_one(Vec3::new(4.0, 1.0, -2.0), (0.3, 0.7)).unwrap();
        assert!(close(s.to_light, Vec3::new(-0.6, 0.8, 0.0)) && (s.distance - 5.0).abs() < 1e-5, "{s:?}");
        assert!((s.irradiance - Color::new(1.0, 2.0, 3.0) / 25.0).abs().max_element() < 1e-6, "{s:?}");
        // At the light itself there is no direction: no sample, never NaN.
        assert_eq!(light.sample_one(Vec3::new(1.0, 5.0, -2.0), (0.3, 0.7)), None);
    }

    #[test]
    fn a_spot_light_is_full_inside_its_inner_cone_dark_outside_its_outer_and_squared_linear_in_cos_between() {
        // Inner 20°, outer 40°, shining down −y from (0, 4, 0).
        let (ci, co) = ((20.0 as Real).to_radians().cos(), (40.0 as Real).to_radians().cos());
        let light = Light {
            kind: LightKind::Spot {
                position: Vec3::new(0.0, 4.0, 0.0),
                direction: -Vec3::Y,
                cos_inner: ci,
                cos_outer: co,
            },
            power: Color::new(2.0, 4.0, 8.0),
            shadows: true,
        };
        let at = |degrees: Real| {
            let t = degrees.to_radians();
            // 2 away from the light at angle t from its axis.
            let p = Vec3::new(0.0, 4.0, 0.0) + 2.0 * Vec3::new(t.sin(), -t.cos(), 0.0);
            light.sample_one(p, (0.5, 0.5)).unwrap()
        };
        let s = at(0.0);
        assert!(close(s.to_light, Vec3::Y) && (s.distance - 2.0).abs() < 1e-5, "{s:?}");
        assert!((s.irradiance - Color::new(0.5, 1.0, 2.0)).abs().max_element() < 1e-5, "{s:?}");
        assert!((at(19.0).irradiance - Color::new(0.5, 1.0, 2.0)).abs().max_element() < 1e-5);
        assert_eq!(at(41.0).irradiance, Color::ZERO);
        assert_eq!(at(150.0).irradiance, Color::ZERO);
        // Halfway in cos between the cones: a quarter.
        let half = ((ci + co) / 2.0).acos().to_degrees();
        assert!((at(half).irradiance - Color::new(0.5, 1.0, 2.0) / 4.0).abs().max_element() < 1e-4);
        // Equal cones: a hard edge, never a division by zero.
        assert_eq!(spot_falloff(0.9, 0.8, 0.8), 1.0);
        assert_eq!(spot_falloff(0.7, 0.8, 0.8), 0.0);
        assert_eq!(spot_falloff(Real::NAN, 0.9, 0.8), 0.0);
    }

    #[test]
    fn a_spot_lights_power_is_its_falloff_integrated_over_the_sphere() {
        // Midpoint rule over cos θ in 10⁵ steps against the closed form.
        for (inner, outer) in [(0.0 as Real, 45.0 as Real), (10.0, 30.0), (30.0, 30.0), (60.0, 120.0)] {
            let (ci, co) = (inner.to_radians().cos(), outer.to_radians().cos());
            let light = Light {
                kind: LightKind::Spot {
                    position: Vec3::ZERO,
                    direction: Vec3::Z,
                    cos_inner: ci,
                    cos_outer: co,
                },
                power: Color::ONE,
                shadows: true,
            };
            let n = 100_000;
            let numeric: f64 = (0..n)
                .map(|k| {
                    let c = -1.0 + 2.0 * (k as f64 + 0.5) / n as f64;
                    2.0 * std::f64::consts::PI * f64::from(spot_falloff(c as Real, ci, co)) * 2.0 / n as f64
                })
                .sum();
            let closed = to_f64(light.power(1.0));
            assert!(
                (closed - numeric).abs() < 1e-3 * numeric.max(1e-3),
                "{inner}°/{outer}°: {closed} vs {numeric}"
            );
        }
    }

    #[test]
    fn a_sphere_light_is_a_point_light_from_inside_and_on_it_and_has_radiance_power_over_pi_r_squared() {
        // Radius 2 at (0, 1, 0), power Φ = (4π, 8π, 12π): radiance
        // Φ/(π·r²) = (1, 2, 3). Three samples, so each carries a third.
        let power = Color::new(4.0, 8.0, 12.0) * std::f32::consts::PI;
        let center = Vec3::new(0.0, 1.0, 0.0);
        let light =
            Light { kind: LightKind::Sphere { center, radius: 2.0, samples: 3 }, power, shadows: true };
        // From inside (1 from the centre) and from its surface (2 away):
        // towards the centre, what a point light of the same power gives.
        for p in [Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, -2.0)] {
            let s = light.sample(p, 1, (0.5, 0.5)).unwrap();
            let d = (center - p).length();
            assert!(close(s.to_light, (center - p) / d) && (s.distance - d).abs() < 1e-5, "from {p}: {s:?}");
            assert!(
                (s.irradiance - power / (3.0 * to_f32(d * d))).abs().max_element() < 1e-5,
                "from {p}: {s:?}"
            );
        }
        // From outside, every sample's irradiance is L/(pdf·n) with L = Φ/(π·r²).
        let p = Vec3::new(0.0, 1.0, -7.0);
        let cone = SphereCone::new(7.0, 2.0);
        for k in 0..3 {
            let s = light.sample(p, k, (0.25, 0.75)).unwrap();
            let radiance = s.irradiance * to_f32(cone.pdf()) * 3.0;
            assert!(
                (radiance - Color::new(1.0, 2.0, 3.0)).abs().max_element() < 1e-4,
                "sample {k}: {radiance}"
            );
            // It ends on the sphere's side that faces p.
            let on = p + s.to_light * s.distance - center;
            assert!((on.length() - 2.0).abs() < 1e-4 && on.dot(p - center) > 0.0, "sample {k} ends at {on}");
        }
    }

    #[test]
    fn sphere_light_samples_are_uniform_in_the_cone_the_sphere_subtends() {
        // From a point at distance d of a sphere light of radius r: a wide
        // cone (d/r = 1.05), a middling one, and a narrow one (d/r = 100,
        // where `SphereCone` switches to its series). χ² of 2·10⁵ directions
        // (stratum k of `samples` chosen at random, uniform jitter) on a
        // 20 × 40 equal-area grid of the cap 1.05·(1 − cos θ_max) about
        // the axis, against the uniform density 1/(2π·(1 − cos θ_max))
        // inside the cone, computed here in f64 (α ≈ 10⁻⁴). Each sample's
        // distance reaches the sphere, and its irradiance is L/pdf over the
        // sample count with L = I/(π·r²).
        let p = Vec3::new(0.2, -0.3, 0.5);
        for (d, r, samples) in [(1.05 as Real, 1.0 as Real, 4), (3.0, 1.0, 1), (100.0, 1.0, 9)] {
            let towards = Vec3::new(1.0, 2.0, -2.0) / 3.0;
            let center = p + d * towards;
            let light = Light {
                kind: LightKind::Sphere { center, radius: r, samples },
                power: Color::ONE,
                shadows: true,
            };
            let (d64, r64) = (to_f64(d), to_f64(r));
            let sin2 = (r64 / d64).powi(2);
            let one_minus_cos_max = sin2 / (1.0 + (1.0 - sin2).sqrt());
            let pdf = 1.0 / (std::f64::consts::TAU * one_minus_cos_max);
            let irradiance = 1.0 / (std::f64::consts::PI * r64 * r64) / pdf / samples as f64;
            let draw = |rng: &mut SampleRng| {
                let k = ((rng.next_pair().0 * samples as Real) as u32).min(samples - 1);
                let s = light.sample(p, k, rng.next_pair()).unwrap();
                let hit = widen(p) + to_f64(s.distance) * widen(s.to_light);
                let off = (hit - widen(center)).length() - r64;
                assert!(off.abs() < 1e-4 * (d64 + r64), "d/r = {d}/{r}: the sample is {off} off the sphere");
                let error = (s.irradiance.as_dvec3() - DVec3::splat(irradiance)).abs().max_element();
                assert!(
                    error < 1e-4 * irradiance,
                    "d/r = {d}/{r}: irradiance {} against {irradiance}",
                    s.irradiance
                );
                Draw::At(widen(s.to_light))
            };
            let axis = widen(towards).normalize();
            let grid = SphereGrid::cap(axis, 1.05 * one_minus_cos_max, 20, 40);
            let density = |w: DVec3| {
                let (x, y, z) = (w.cross(axis).length_squared(), 0.0, w.dot(axis));
                let u = if z > 0.0 { (x + y) / (1.0 + z) } else { 1.0 - z };
                if u <= one_minus_cos_max { pdf } else { 0.0 }
            };
            chi_square::directions(&format!("sphere light at d/r = {d}/{r}"), &grid, 200_000, draw, &density);
        }
    }
}
