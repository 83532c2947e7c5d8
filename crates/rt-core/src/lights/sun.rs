//! The sun: a small disc of constant radiance in the sky, sampled
//! uniformly over its cone of directions (pbrt-v4 §A.5.6 `SampleUniformCone`).
//!
//! A disc of angular radius α and radiance L gives, on a surface facing
//! it, the irradiance `E = ∫ L cos θ dω = L·π·sin²α` (the cone's projected
//! solid angle). A sun is specified by E (what a light meter facing it
//! reads) and α; its radiance is `L = E / (π sin²α)`. The real sun's α is
//! 0.2667° (half of its 0.533° diameter as seen from the Earth).

use crate::math::color::Color;
use crate::math::real::{Real, SUN_RIM_SLACK, Vec3, to_f32, to_f64};

/// The real sun's angular radius in degrees.
pub const SUN_ANGULAR_RADIUS_DEGREES: Real = 0.2667;

/// A disc light at infinity.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sun {
    /// Unit direction towards the sun's centre.
    direction: Vec3,
    /// Two unit vectors across `direction`.
    across: (Vec3, Vec3),
    /// `1 − cos α`, computed as `2 sin²(α/2)` (no cancellation for small α).
    one_minus_cos: Real,
    /// `sin²α·(1 + SUN_RIM_SLACK)`: what a direction's `|d × axis|²` is
    /// compared with (the cross product keeps small angles exact).
    sin2_limit: Real,
    /// The disc's radiance L.
    radiance: Color,
    /// The irradiance E it was given.
    irradiance: Color,
}

impl Sun {
    /// A sun towards unit `direction`, of angular radius `radius_degrees`
    /// (in (0, 90)) and irradiance `irradiance` at normal incidence.
    pub fn new(direction: Vec3, radius_degrees: Real, irradiance: Color) -> Self {
        let direction = direction.normalize();
        let alpha = radius_degrees.to_radians();
        let half_sine = (0.5 * alpha).sin();
        let sin_alpha = alpha.sin();
        let radiance = irradiance / (std::f32::consts::PI * to_f32(sin_alpha * sin_alpha));
        Self {
            direction,
            across: direction.any_orthonormal_pair(),
            one_minus_cos: 2.0 * half_sine * half_sine,
            sin2_limit: sin_alpha * sin_alpha * (1.0 + SUN_RIM_SLACK),
            radiance,
            irradiance,
        }
    }

    /// The unit direction towards the sun's centre.
    pub fn direction(&self) -> Vec3 {
        self.direction
    }

    /// The irradiance at normal incidence, E.
    pub fn irradiance(&self) -> Color {
        self.irradiance
    }

    /// The angular radius α in degrees.
    pub fn radius_degrees(&self) -> Real {
        // 1 − cos α = 2 sin²(α/2).
        (2.0 * (0.5 * self.one_minus_cos).sqrt().asin()).to_degrees()
    }

    /// Whether unit `dir` lies within the disc (α < 90°): in front, and
    /// `sin²θ = |dir × axis|²` at most sin²α, with a slack of
    /// [`SUN_RIM_SLACK`] for the rounding of samples on the rim.
    #[inline]
    fn contains(&self, dir: Vec3) -> bool {
        dir.dot(self.direction) > 0.0 && dir.cross(self.direction).length_squared() <= self.sin2_limit
    }

    /// The radiance along unit `dir`: L inside the disc, 0 outside.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Color {
        if self.contains(dir) { self.radiance } else { Color::ZERO }
    }

    /// A direction in the disc for `u` ∈ [0,1)², uniform over its solid
    /// angle `2π(1 − cos α)`: `1 − cos θ = u₀(1 − cos α)`, φ = 2πu₁, with
    /// `sin θ = √(t(2 − t))` for `t = 1 − cos θ`, exact for small angles.
    pub fn sample(&self, u: (Real, Real)) -> Vec3 {
        let t = u.0 * self.one_minus_cos;
        let sin_theta = (t * (2.0 - t)).max(0.0).sqrt();
        let phi = 2.0 * std::f64::consts::PI as Real * u.1;
        let (b1, b2) = self.across;
        ((1.0 - t) * self.direction + sin_theta * (phi.cos() * b1 + phi.sin() * b2)).normalize()
    }

    /// The density of [`Sun::sample`] over solid angle at unit `dir`:
    /// `1/(2π(1 − cos α))` inside the disc, 0 outside.
    #[inline]
    pub fn pdf(&self, dir: Vec3) -> Real {
        if self.contains(dir) { 1.0 / (2.0 * std::f64::consts::PI as Real * self.one_minus_cos) } else { 0.0 }
    }

    /// `∫ L̄ dω = 2π(1 − cos α)·L̄` over the disc, L̄ the mean of the colour
    /// channels: for choosing between the sun and the sky.
    pub fn radiance_integral(&self) -> f64 {
        2.0 * std::f64::consts::PI * to_f64(self.one_minus_cos) * (self.radiance.element_sum() / 3.0) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::widen;
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, Frame, Interval, Rectangle};

    #[test]
    fn the_sun_gives_its_stated_irradiance_on_a_surface_facing_it() {
        // E = ∫ L cos θ dω, estimated with the sun's own samples
        // (L cos θ / pdf), on a surface facing the sun and on one tilted by
        // 60° (E·cos 60°, the disc being small).
        let dir = Vec3::new(0.3, 0.8, -0.2).normalize();
        let sun = Sun::new(dir, SUN_ANGULAR_RADIUS_DEGREES, Color::new(3.0, 2.0, 1.0));
        let tilted = (dir + dir.any_orthonormal_vector() * (3.0 as Real).sqrt()).normalize();
        for (normal, expected) in [(dir, 1.0), (tilted, 0.5)] {
            let mut rng = SampleRng::new(1, 2, 3);
            let n = 20_000;
            let mut sum = Color::ZERO;
            for _ in 0..n {
                let wi = sun.sample(rng.next_pair());
                let pdf = sun.pdf(wi);
                assert!(pdf > 0.0, "a sample lies in the disc");
                sum += sun.radiance(wi) * to_f32(wi.dot(normal).max(0.0) / pdf);
            }
            let e = sum / n as f32;
            let want = Color::new(3.0, 2.0, 1.0) * expected;
            assert!((e - want).abs().max_element() < 2e-3 * want.max_element(), "{e} against {want}");
        }
        assert!((sun.radius_degrees() - SUN_ANGULAR_RADIUS_DEGREES).abs() < 1e-4);
    }

    #[test]
    fn sampled_directions_are_uniform_over_the_disc() {
        // Uniform over the disc's solid angle is uniform in
        // `(1 − cos θ)/(1 − cos α)` and `φ/2π` (dω = d(1 − cos θ)·dφ): χ² of
        // the samples' coordinates against the constant density 1, in f64
        // about the sun's axis, for the real sun's disc and wider ones. A
        // sample on the rim can round a relative 10⁻⁵ or so outward (what
        // `SUN_RIM_SLACK` covers); it is counted in the rim's bins.
        let dir = Vec3::new(0.3, 0.8, -0.2).normalize();
        for degrees in [SUN_ANGULAR_RADIUS_DEGREES, 5.0, 40.0] {
            let sun = Sun::new(dir, degrees, Color::ONE);
            let disc = to_f64(sun.one_minus_cos);
            let frame = Frame::new(widen(dir));
            let draw = |rng: &mut SampleRng| {
                let (u, phi) = frame.coordinates(widen(sun.sample(rng.next_pair())));
                let (u, phi) = (u / disc, phi / std::f64::consts::TAU);
                assert!(u < 1.0 + 1e-4, "sun of {degrees}°: a sample {u} of the way out");
                Draw::At((u.min(1.0 - 1e-12), phi.min(1.0 - 1e-12)))
            };
            let grid =
                Rectangle { s: Interval { lo: 0.0, hi: 1.0, n: 8 }, t: Interval { lo: 0.0, hi: 1.0, n: 12 } };
            chi_square::plane(&format!("sun of {degrees}°"), grid, 200_000, draw, &|_, _| 1.0);
            // And `pdf` gives that density over solid angle inside the disc.
            let inside = sun.sample((0.5, 0.25));
            assert_eq!(sun.pdf(inside), 1.0 / (2.0 * std::f64::consts::PI as Real * sun.one_minus_cos));
        }
    }

    #[test]
    fn directions_outside_the_disc_carry_nothing() {
        let sun = Sun::new(Vec3::Y, 1.0, Color::ONE);
        let off = Vec3::new((1.01 as Real).to_radians().sin(), (1.01 as Real).to_radians().cos(), 0.0);
        assert_eq!((sun.radiance(off), sun.pdf(off)), (Color::ZERO, 0.0));
        let on = Vec3::new((0.99 as Real).to_radians().sin(), (0.99 as Real).to_radians().cos(), 0.0);
        assert!(sun.radiance(on).x > 0.0 && sun.pdf(on) > 0.0);
    }
}
