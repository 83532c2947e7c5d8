//! A clear sky with a sun: Preetham, Shirley and Smits, "A Practical
//! Analytic Model for Daylight" (SIGGRAPH 1999), baked at load time into an
//! environment map ([`EnvironmentMap`]) with the sun as its own disc
//! ([`Sun`]), sampled apart from the sky.
//!
//! # Why Preetham
//!
//! Its luminance and chromaticity are five Perez coefficients each, linear
//! in the turbidity T, and a zenith value, all printed in the paper's
//! appendix: about forty numbers that can be checked against it by eye,
//! where Hosek–Wilkie (2012) needs several thousand fitted coefficients
//! (and the `hw-skymodel` crate for them) and Nishita a numerical
//! integration through the atmosphere. Its known faults (too bright near
//! the horizon at high turbidity, not meant for a sun below ~5°; Zotti,
//! Wilkie and Purgathofer 2007) are fine for lighting product and outdoor
//! scenes. Mitsuba 3's `sunsky` is Hosek–Wilkie, so a comparison with it
//! is of looks only, not per block.
//!
//! # The model
//!
//! For a view direction at zenith angle θ and angle γ from the sun (at
//! zenith angle θs), each of Y (luminance, kcd/m²) and the chromaticities
//! x, y is its zenith value times the Perez distribution's ratio
//!
//! ```text
//! F(θ, γ) = (1 + A e^(B / cos θ)) (1 + C e^(D γ) + E cos²γ)
//! value(θ, γ) = value_zenith · F(θ, γ) / F(0, θs)
//! ```
//!
//! with A…E from the appendix's table (linear in T), the zenith luminance
//! `Yz = (4.0453 T − 4.9710) tan χ − 0.2155 T + 2.4192`,
//! `χ = (4/9 − T/120)(π − 2θs)`, and the zenith chromaticities from the
//! appendix's cubic in θs and quadratic in T. xyY becomes XYZ and then
//! linear sRGB (Rec. 709 primaries, D65). Scene radiance is
//! `strength · Y / 10` with Y in kcd/m² (a clear zenith, T = 3, sun at 45°,
//! is about 0.7).
//!
//! Below the horizon is a Lambertian ground of albedo `ground_albedo` lit
//! by the sky and the sun, unshadowed: `L = ρ/π · (E_sky + E_sun cos θs)`,
//! the same in every downward direction. The sun is a disc of the real
//! sun's angular radius with the irradiance `sun_irradiance` at normal
//! incidence (the model's own sun, an attenuated black body, is left out:
//! the irradiance is given instead, so it can be stated and tested).

use crate::lights::environment_map::EnvironmentMap;
use crate::lights::sun::{SUN_ANGULAR_RADIUS_DEGREES, Sun};
use crate::math::color::Color;
use crate::math::real::{PEREZ_MIN_COS, Real, Vec3, to_f32, to_f64};

/// The baked sky's width in texels (its height is half): the model is
/// smooth, and 512 × 256 texels (0.7° each) resolve the glow around the sun.
pub const SKY_MAP_WIDTH: usize = 512;

/// What a sky is made from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyParameters {
    /// Unit direction towards the sun (y > 0: above the horizon).
    pub sun_direction: Vec3,
    /// Atmospheric turbidity T, 1.7 (very clear) to 10 (hazy).
    pub turbidity: Real,
    /// Factor on the sky's radiance (not the sun's).
    pub strength: f32,
    /// The sun's irradiance at normal incidence; 0 for no sun.
    pub sun_irradiance: Color,
    /// The ground's albedo below the horizon.
    pub ground_albedo: f32,
}

/// The lowest and highest accepted turbidity (the range Preetham et al. fitted).
pub const TURBIDITY_RANGE: (Real, Real) = (1.7, 10.0);

/// Perez coefficients (A, B, C, D, E) of Y, x and y as `a·T + b` (the
/// paper's appendix).
const PEREZ: [[(f64, f64); 5]; 3] = [
    [(0.1787, -1.4630), (-0.3554, 0.4275), (-0.0227, 5.3251), (0.1206, -2.5771), (-0.0670, 0.3703)],
    [(-0.0193, -0.2592), (-0.0665, 0.0008), (-0.0004, 0.2125), (-0.0641, -0.8989), (-0.0033, 0.0452)],
    [(-0.0167, -0.2608), (-0.0950, 0.0092), (-0.0079, 0.2102), (-0.0441, -1.6537), (-0.0109, 0.0529)],
];

/// Zenith chromaticity x: rows T², T, 1; columns θs³, θs², θs, 1.
const ZENITH_X: [[f64; 4]; 3] = [
    [0.00166, -0.00375, 0.00209, 0.0],
    [-0.02903, 0.06377, -0.03202, 0.00394],
    [0.11693, -0.21196, 0.06052, 0.25886],
];
/// Zenith chromaticity y, laid out as [`ZENITH_X`].
const ZENITH_Y: [[f64; 4]; 3] = [
    [0.00275, -0.00610, 0.00317, 0.0],
    [-0.04214, 0.08970, -0.04153, 0.00516],
    [0.15346, -0.26756, 0.06670, 0.26688],
];

/// Preetham's sky for one sun position and turbidity.
#[derive(Clone, Debug)]
pub struct PreethamSky {
    /// Perez coefficients of Y, x, y.
    coefficients: [[f64; 5]; 3],
    /// Zenith Y (kcd/m²), x, y, each over its `F(0, θs)`.
    zenith_over_f0: [f64; 3],
    sun: Vec3,
}

/// The Perez distribution F(θ, γ) for coefficients `c` (A…E); cos θ is
/// kept above [`PEREZ_MIN_COS`].
fn perez(c: &[f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    let [a, b, cc, d, e] = *c;
    let cos_gamma = gamma.cos();
    (1.0 + a * (b / cos_theta.max(PEREZ_MIN_COS)).exp())
        * (1.0 + cc * (d * gamma).exp() + e * cos_gamma * cos_gamma)
}

impl PreethamSky {
    /// The sky for a sun towards unit `sun` (above the horizon) at turbidity `t`.
    pub fn new(sun: Vec3, t: f64) -> Self {
        let sun = sun.normalize();
        let theta_s = to_f64(sun.y).clamp(-1.0, 1.0).acos();
        let coefficients = PEREZ.map(|row| row.map(|(a, b)| a * t + b));
        let chi = (4.0 / 9.0 - t / 120.0) * (std::f64::consts::PI - 2.0 * theta_s);
        let y_zenith = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
        let chroma = |m: &[[f64; 4]; 3]| {
            let th = [theta_s.powi(3), theta_s.powi(2), theta_s, 1.0];
            let tt = [t * t, t, 1.0];
            (0..3).map(|r| tt[r] * (0..4).map(|c| m[r][c] * th[c]).sum::<f64>()).sum::<f64>()
        };
        let zenith = [y_zenith, chroma(&ZENITH_X), chroma(&ZENITH_Y)];
        let zenith_over_f0 = [0, 1, 2].map(|k| zenith[k] / perez(&coefficients[k], 1.0, theta_s));
        Self { coefficients, zenith_over_f0, sun }
    }

    /// Y (kcd/m²), x, y towards unit `dir` above the horizon.
    pub fn xyy(&self, dir: Vec3) -> [f64; 3] {
        let cos_theta = to_f64(dir.y).clamp(0.0, 1.0);
        let gamma = to_f64(dir.dot(self.sun)).clamp(-1.0, 1.0).acos();
        [0, 1, 2].map(|k| self.zenith_over_f0[k] * perez(&self.coefficients[k], cos_theta, gamma))
    }

    /// Linear sRGB radiance towards unit `dir` above the horizon, in
    /// scene units (Y/10, Y in kcd/m²).
    pub fn radiance(&self, dir: Vec3) -> Color {
        let [lum, x, y] = self.xyy(dir);
        xyy_to_linear_srgb(lum / 10.0, x, y)
    }
}

/// CIE xyY to linear sRGB (IEC 61966-2-1's XYZ → RGB matrix), negative
/// components (outside the gamut) clamped to 0.
pub fn xyy_to_linear_srgb(lum: f64, x: f64, y: f64) -> Color {
    if y <= 0.0 {
        return Color::ZERO;
    }
    let (cx, cz) = (x * lum / y, (1.0 - x - y) * lum / y);
    let r = 3.2406 * cx - 1.5372 * lum - 0.4986 * cz;
    let g = -0.9689 * cx + 1.8758 * lum + 0.0415 * cz;
    let b = 0.0557 * cx - 0.2040 * lum + 1.0570 * cz;
    Color::new(r.max(0.0) as f32, g.max(0.0) as f32, b.max(0.0) as f32)
}

/// The sky of `p` baked into an environment map of [`SKY_MAP_WIDTH`] ×
/// half that texels, with its sun (see the module's documentation).
pub fn sky_map(p: &SkyParameters) -> EnvironmentMap {
    let (w, h) = (SKY_MAP_WIDTH, SKY_MAP_WIDTH / 2);
    let sky = PreethamSky::new(p.sun_direction, to_f64(p.turbidity));
    let probe = EnvironmentMap::new(1, 1, vec![Color::ZERO], 1.0, 0.0);
    let mut texels = vec![Color::ZERO; w * h];
    // E_sky on the ground: ∫ L cos θ dω over the upper rows.
    let mut e_sky = Color::ZERO;
    for j in 0..h / 2 {
        for i in 0..w {
            let uv = ((i as Real + 0.5) / w as Real, (j as Real + 0.5) / h as Real);
            let (d, sin_theta) = probe.uv_to_direction(uv);
            let l = sky.radiance(d) * p.strength;
            texels[j * w + i] = l;
            let d_omega = 2.0 * std::f32::consts::PI.powi(2) * to_f32(sin_theta) / (w * h) as f32;
            e_sky += l * to_f32(d.y.max(0.0)) * d_omega;
        }
    }
    let sun_dir = p.sun_direction.normalize();
    let e_sun = p.sun_irradiance * to_f32(sun_dir.y.max(0.0));
    let ground = (e_sky + e_sun) * (p.ground_albedo / std::f32::consts::PI);
    texels[w * h / 2..].fill(ground);
    let map = EnvironmentMap::new(w, h, texels, 1.0, 0.0);
    if p.sun_irradiance.max_element() > 0.0 {
        map.with_sun(Sun::new(sun_dir, SUN_ANGULAR_RADIUS_DEGREES, p.sun_irradiance))
    } else {
        map
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_zenith_luminance_follows_the_papers_formula() {
        // T = 3, sun at 45°: χ = (4/9 − 1/40)(π/2) = 0.65886, tan χ = 0.77428,
        // Yz = 7.1649·0.77428 − 0.6465 + 2.4192 = 7.3204 kcd/m².
        let sun = Vec3::new(0.0, 1.0, 1.0).normalize();
        let sky = PreethamSky::new(sun, 3.0);
        let [lum, x, y] = sky.xyy(Vec3::Y);
        assert!((lum - 7.3204).abs() < 2e-4, "{lum}");
        // A clear zenith is bluish white: x, y a little below D65's (0.3127, 0.3290).
        assert!((0.22..0.31).contains(&x) && (0.23..0.33).contains(&y), "{x}, {y}");
    }

    #[test]
    fn the_sky_is_brightest_near_the_sun_and_bluer_overhead_than_at_the_horizon() {
        let sun = Vec3::new(0.0, 0.5, 1.0).normalize();
        let sky = PreethamSky::new(sun, 3.0);
        let near_sun = sky.radiance(Vec3::new(0.05, 0.5, 1.0).normalize());
        let away = sky.radiance(Vec3::new(0.0, 0.5, -1.0).normalize());
        assert!(near_sun.y > 2.0 * away.y, "{near_sun} against {away}");
        let zenith = sky.radiance(Vec3::Y);
        let horizon = sky.radiance(Vec3::new(-1.0, 0.02, 0.0).normalize());
        assert!(zenith.z / zenith.x > horizon.z / horizon.x, "{zenith} against {horizon}");
    }

    #[test]
    fn the_baked_sky_has_the_sun_with_its_irradiance_and_a_lit_ground() {
        let p = SkyParameters {
            sun_direction: Vec3::new(0.3, 0.6, 0.5),
            turbidity: 3.0,
            strength: 1.0,
            sun_irradiance: Color::new(10.0, 9.0, 8.0),
            ground_albedo: 0.3,
        };
        let map = sky_map(&p);
        let sun = map.sun().unwrap();
        assert_eq!(sun.irradiance(), Color::new(10.0, 9.0, 8.0));
        assert!((sun.direction() - p.sun_direction.normalize()).length() < 1e-6);
        // Straight down is the ground: ρ/π (E_sky + E_sun cos θs), at least the sun's part.
        let down = map.radiance(-Vec3::Y);
        let sun_part = 0.3 / std::f32::consts::PI * 10.0 * to_f32(p.sun_direction.normalize().y);
        assert!(down.x > sun_part && down.x < 2.0 * sun_part, "{down}");
        // No sun: nothing bright to sample.
        let dark = sky_map(&SkyParameters { sun_irradiance: Color::ZERO, ..p });
        assert!(dark.sun().is_none());
    }
}
