//! An environment map: an equirectangular (latitude–longitude) image of
//! the radiance arriving from every direction, optionally with a sun
//! ([`crate::lights::sun`]), importance-sampled by its own brightness
//! (pbrt-v3 §14.2.4 `InfiniteAreaLight`, pbrt-v4 §12.5; Mitsuba 3's `envmap`).
//!
//! # Direction ↔ image
//!
//! The world is left-handed with +y up. A world direction d is first
//! turned into the map's frame by the map's `rotation` ρ (degrees about +y,
//! turning the map so that what it shows straight ahead, along +z, moves
//! towards +x for ρ = 90°): `m = R_y(−ρ)·d` with
//! `R_y(ρ)·(x, y, z) = (x cos ρ + z sin ρ, y, −x sin ρ + z cos ρ)`. Then
//!
//! ```text
//! u = atan2(−m.x, −m.z) / 2π   (wrapped into [0,1))   image column, left to right
//! v = acos(m.y) / π                                     image row, top (up) to bottom
//! m = (−sin θ sin φ, cos θ, −sin θ cos φ)  with θ = πv, φ = 2πu
//! ```
//!
//! so the top row is straight up, u = 0 (the image's left and right edges)
//! is −z, u = 1/4 is −x, u = 1/2 (the image's centre) is +z, straight ahead
//! of the default camera, and u = 3/4 is +x: seen from inside, the image
//! is not mirrored. This is Mitsuba 3's `envmap` convention
//! (`u = atan2(d.x, −d.z)/2π`, `v = acos(d.y)/π`) after the x mirror that
//! takes our world to Mitsuba's right-handed one, so the same image file
//! lights both alike; our rotation ρ is Mitsuba's `to_world` rotation about
//! +y by −ρ.
//!
//! # Lookup and sampling
//!
//! Radiance is interpolated bilinearly between texel centres
//! (`((i + ½)/W, (j + ½)/H)`), wrapping around in u and clamped at the
//! poles in v. Directions are sampled from a piecewise-constant density
//! over the texels ([`Distribution2D`]) proportional to `f_ij · sin θ_j`,
//! where f is the mean over the texel's cell of the bilinear radiance's
//! channel mean (9/16 of the texel, 3/32 of each edge neighbour, 1/64 of
//! each corner one: every direction whose radiance is not zero has a
//! density above zero) and `sin θ_j`, at the row's centre, accounts for
//! the rows' shrinking solid angle. The Jacobian of (u, v) → ω is
//! `dω = 2π² sin θ du dv`, so `p(ω) = p(u, v) / (2π² sin θ)`.

use crate::lights::distribution::Distribution2D;
use crate::lights::sun::Sun;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, to_f32, to_f64};

/// The largest accepted map side, in texels (a 16K × 8K panorama).
pub const MAX_MAP_SIDE: u32 = 1 << 14;
/// The largest accepted map, in texels: 2²⁷ (1.5 GiB as f32 RGB with its
/// distribution), so an absurd header is refused before anything is allocated.
pub const MAX_MAP_TEXELS: u64 = 1 << 27;

/// An equirectangular environment map (see the module's documentation).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnvironmentMap {
    width: usize,
    height: usize,
    /// Texels row by row from the top, times the strength.
    texels: Vec<Color>,
    strength: f32,
    rotation_degrees: Real,
    /// `(sin ρ, cos ρ)`.
    rotation: (Real, Real),
    distribution: Distribution2D,
    /// `∫ L̄ dω` of the map (channel mean), for the light sampler and the sun.
    map_integral: f64,
    sun: Option<Sun>,
    /// The probability of sampling the sun rather than the map.
    sun_probability: Real,
}

impl EnvironmentMap {
    /// The map of `width × height` texels `texels` (row by row from the top;
    /// finite and ≥ 0: the loader refuses or clamps others), scaled by
    /// `strength` and turned by `rotation_degrees` about +y.
    ///
    /// # Panics
    /// If the sizes do not match or are 0 (a loader checks them first).
    pub fn new(
        width: usize,
        height: usize,
        texels: Vec<Color>,
        strength: f32,
        rotation_degrees: Real,
    ) -> Self {
        assert!(width >= 1 && height >= 1 && texels.len() == width * height);
        let texels: Vec<Color> = texels.into_iter().map(|t| t * strength).collect();
        let mean = |c: Color| (c.element_sum() / 3.0) as f64;
        let mut weights = Vec::with_capacity(width * height);
        let mut map_integral = 0.0;
        let pi = std::f64::consts::PI;
        for j in 0..height {
            let sin_theta = (pi * (j as f64 + 0.5) / height as f64).sin();
            for i in 0..width {
                // ∫ of the bilinear radiance over the texel's cell, over its
                // area: 9/16 of the texel, 3/32 of each edge neighbour, 1/64
                // of each corner one (rows clamped at the poles, as the
                // lookup does). Every weight is positive, so the density is
                // above 0 wherever the radiance is.
                let mut cell = 0.0;
                for dj in -1..=1i64 {
                    let jj = (j as i64 + dj).clamp(0, height as i64 - 1) as usize;
                    for di in -1..=1i64 {
                        let ii = (i as i64 + di).rem_euclid(width as i64) as usize;
                        let weight =
                            [0.25, 0.75, 0.25][(di + 1) as usize] * [0.25, 0.75, 0.25][(dj + 1) as usize];
                        cell += weight * mean(texels[jj * width + ii]);
                    }
                }
                weights.push(cell * sin_theta);
                map_integral += mean(texels[j * width + i]) * sin_theta;
            }
        }
        // Each texel spans dω ≈ sin θ · (2π/W)(π/H).
        map_integral *= 2.0 * pi * pi / (width * height) as f64;
        let rad = rotation_degrees.to_radians();
        Self {
            width,
            height,
            texels,
            strength,
            rotation_degrees,
            rotation: (rad.sin(), rad.cos()),
            distribution: Distribution2D::new(&weights, width, height),
            map_integral,
            sun: None,
            sun_probability: 0.0,
        }
    }

    /// The same map with a sun in it, sampled in proportion to its share of
    /// `∫ L̄ dω` (map and sun together).
    pub fn with_sun(mut self, sun: Sun) -> Self {
        let s = sun.radiance_integral();
        let total = s + self.map_integral;
        self.sun_probability = if total > 0.0 { (s / total) as Real } else { 0.5 };
        self.sun = Some(sun);
        self
    }

    /// `(width, height)` in texels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }
    /// The factor the image's texels were scaled by.
    pub fn strength(&self) -> f32 {
        self.strength
    }
    /// The rotation about +y, degrees.
    pub fn rotation_degrees(&self) -> Real {
        self.rotation_degrees
    }
    /// The sun, if there is one.
    pub fn sun(&self) -> Option<&Sun> {
        self.sun.as_ref()
    }
    /// The texels, row by row from the top, times the strength.
    pub fn texels(&self) -> &[Color] {
        &self.texels
    }

    /// `∫ L̄ dω` over the sphere, L̄ the mean of the channels, sun included.
    pub fn radiance_integral(&self) -> f64 {
        self.map_integral + self.sun.as_ref().map_or(0.0, Sun::radiance_integral)
    }

    /// The map's (u, v) of world direction `d` (any length but zero) and
    /// `sin θ` there (see the module's documentation).
    #[inline]
    pub fn direction_to_uv(&self, d: Vec3) -> ((Real, Real), Real) {
        let d = d.normalize();
        let (s, c) = self.rotation;
        // m = R_y(−ρ)·d.
        let m = Vec3::new(d.x * c - d.z * s, d.y, d.x * s + d.z * c);
        let tau = 2.0 * std::f64::consts::PI as Real;
        let mut u = (-m.x).atan2(-m.z) / tau;
        if u < 0.0 {
            u += 1.0;
        }
        let u = if u >= 1.0 { 0.0 } else { u };
        let v = m.y.clamp(-1.0, 1.0).acos() / std::f64::consts::PI as Real;
        let sin_theta = (m.x * m.x + m.z * m.z).sqrt();
        ((u, v), sin_theta)
    }

    /// The unit world direction of the map's (u, v) ∈ [0, 1]², and `sin θ`.
    #[inline]
    pub fn uv_to_direction(&self, (u, v): (Real, Real)) -> (Vec3, Real) {
        let pi = std::f64::consts::PI as Real;
        let (theta, phi) = (pi * v, 2.0 * pi * u);
        let sin_theta = theta.sin();
        let m = Vec3::new(-sin_theta * phi.sin(), theta.cos(), -sin_theta * phi.cos());
        let (s, c) = self.rotation;
        // d = R_y(ρ)·m.
        (Vec3::new(m.x * c + m.z * s, m.y, -m.x * s + m.z * c), sin_theta)
    }

    /// The map's own radiance at (u, v), bilinear between texel centres.
    fn lookup(&self, (u, v): (Real, Real)) -> Color {
        let (w, h) = (self.width as Real, self.height as Real);
        let (x, y) = (u * w - 0.5, v * h - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (to_f32(x - x0), to_f32(y - y0));
        let col = |i: Real| (i as i64).rem_euclid(self.width as i64) as usize;
        let row = |j: Real| (j as i64).clamp(0, self.height as i64 - 1) as usize;
        let at = |i: Real, j: Real| self.texels[row(j) * self.width + col(i)];
        let top = at(x0, y0) * (1.0 - fx) + at(x0 + 1.0, y0) * fx;
        let bottom = at(x0, y0 + 1.0) * (1.0 - fx) + at(x0 + 1.0, y0 + 1.0) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// The radiance arriving along a ray leaving the scene in direction `dir`.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Color {
        let (uv, _) = self.direction_to_uv(dir);
        let sky = self.lookup(uv);
        match &self.sun {
            Some(sun) => sky + sun.radiance(dir.normalize()),
            None => sky,
        }
    }

    /// The density over solid angle of the map's own part at unit `dir`.
    fn map_pdf(&self, dir: Vec3) -> Real {
        let ((u, v), sin_theta) = self.direction_to_uv(dir);
        if sin_theta <= 0.0 {
            return 0.0;
        }
        let p = self.distribution.pdf((to_f64(u), to_f64(v)));
        let pi = std::f64::consts::PI;
        (p / (2.0 * pi * pi * to_f64(sin_theta))) as Real
    }

    /// A unit direction for `u` ∈ [0,1)² and its density over solid angle,
    /// or `None` where that density would be 0 (a pole).
    pub fn sample(&self, u: (Real, Real)) -> Option<(Vec3, Real)> {
        let dir = match &self.sun {
            Some(sun) if u.0 < self.sun_probability => {
                // Reuse u₀ within the sun's share.
                sun.sample((u.0 / self.sun_probability, u.1))
            }
            _ => {
                let p_sun = self.sun_probability;
                let u0 = if p_sun > 0.0 {
                    ((u.0 - p_sun) / (1.0 - p_sun)).clamp(0.0, 1.0 - Real::EPSILON)
                } else {
                    u.0
                };
                let ((su, sv), p) = self.distribution.sample((u0, u.1));
                if p <= 0.0 {
                    return None;
                }
                self.uv_to_direction((su as Real, sv as Real)).0
            }
        };
        let pdf = self.pdf(dir);
        (pdf > 0.0 && pdf.is_finite()).then_some((dir, pdf))
    }

    /// The density over solid angle with which [`EnvironmentMap::sample`]
    /// picks unit `dir`: the sun's and the map's, mixed by the sun's share.
    pub fn pdf(&self, dir: Vec3) -> Real {
        let map = self.map_pdf(dir);
        match &self.sun {
            Some(sun) => self.sun_probability * sun.pdf(dir) + (1.0 - self.sun_probability) * map,
            None => map,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::lights::sun::SUN_ANGULAR_RADIUS_DEGREES;
    use crate::math::real::{narrow, to_f64};
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, Interval, Rectangle};

    /// A small map with bright rectangles on a dim ground: the kind the
    /// studio-map script makes.
    pub(crate) fn studio(width: usize, height: usize) -> Vec<Color> {
        (0..width * height)
            .map(|k| {
                let (i, j) = (k % width, k / width);
                let (u, v) = ((i as f32 + 0.5) / width as f32, (j as f32 + 0.5) / height as f32);
                if (0.2..0.35).contains(&u) && (0.15..0.3).contains(&v) {
                    Color::new(20.0, 18.0, 16.0)
                } else if (0.6..0.7).contains(&u) && (0.35..0.55).contains(&v) {
                    Color::new(5.0, 6.0, 8.0)
                } else {
                    Color::splat(0.05 + 0.1 * (1.0 - v))
                }
            })
            .collect()
    }

    #[test]
    fn directions_and_image_coordinates_follow_the_documented_convention() {
        let map = EnvironmentMap::new(4, 2, vec![Color::ONE; 8], 1.0, 0.0);
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        for (uv, d) in
            [((0.5, 0.5), Vec3::Z), ((0.25, 0.5), -Vec3::X), ((0.75, 0.5), Vec3::X), ((0.0, 0.5), -Vec3::Z)]
        {
            assert!(close(map.uv_to_direction(uv).0, d), "{uv:?}");
            let (back, _) = map.direction_to_uv(d);
            assert!((back.0 - uv.0).abs() < 1e-5 && (back.1 - uv.1).abs() < 1e-5, "{d}: {back:?}");
        }
        assert!(close(map.uv_to_direction((0.3, 0.0)).0, Vec3::Y));
        // A rotation of 90° moves what was straight ahead to +x.
        let turned = EnvironmentMap::new(4, 2, vec![Color::ONE; 8], 1.0, 90.0);
        assert!(close(turned.uv_to_direction((0.5, 0.5)).0, Vec3::X));
        for k in 0..50 {
            let uv = ((k as Real * 0.137).fract(), (k as Real * 0.071).fract() * 0.98 + 0.01);
            let (d, _) = turned.uv_to_direction(uv);
            let (back, _) = turned.direction_to_uv(d);
            let du = (back.0 - uv.0).abs();
            assert!(du.min(1.0 - du) < 1e-4 && (back.1 - uv.1).abs() < 1e-4, "{uv:?} → {back:?}");
        }
    }

    #[test]
    fn the_sampling_density_integrates_to_one_over_the_sphere() {
        // Riemann sum over a fine (cos θ, φ) grid, which has equal solid angles.
        for sun in [false, true] {
            let mut map = EnvironmentMap::new(32, 16, studio(32, 16), 1.0, 30.0);
            if sun {
                map = map.with_sun(Sun::new(Vec3::new(0.3, 0.5, 0.2), 10.0, Color::splat(4.0)));
            }
            let (nz, nphi) = (1000, 1000);
            let mut sum = 0.0;
            for a in 0..nz {
                let z = 1.0 - 2.0 * (a as f64 + 0.5) / nz as f64;
                let r = (1.0 - z * z).sqrt();
                for b in 0..nphi {
                    let phi = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / nphi as f64;
                    sum += to_f64(map.pdf(narrow(DVec3::new(r * phi.cos(), z, r * phi.sin()))));
                }
            }
            let integral = sum * 4.0 * std::f64::consts::PI / (nz * nphi) as f64;
            assert!((integral - 1.0).abs() < 5e-3, "sun {sun}: {integral}");
        }
    }

    #[test]
    fn sampled_directions_follow_the_density_pdf_gives() {
        // Binned in the map's (u, v), two bins per texel each way, where the
        // density over the image, `p(ω)·2π² sin θ`, is constant in each bin
        // (so the bins' probabilities are exact): this checks the sampling
        // against `pdf`, the Jacobian of (u, v) → ω included. That `pdf`
        // integrates to 1 over the sphere is the test above.
        let map = EnvironmentMap::new(16, 8, studio(16, 8), 1.0, 30.0);
        let grid =
            Rectangle { s: Interval { lo: 0.0, hi: 1.0, n: 32 }, t: Interval { lo: 0.0, hi: 1.0, n: 16 } };
        let draw = |rng: &mut SampleRng| match map.sample(rng.next_pair()) {
            Some((d, _)) => {
                let ((u, v), _) = map.direction_to_uv(d);
                // Straight down rounds to v = 1 exactly: the last row's.
                Draw::At((to_f64(u), to_f64(v).min(1.0 - 1e-12)))
            }
            None => Draw::Nothing,
        };
        let pdf = |u: f64, v: f64| {
            let (d, sin_theta) = map.uv_to_direction((u as Real, v as Real));
            to_f64(map.pdf(d)) * 2.0 * std::f64::consts::PI.powi(2) * to_f64(sin_theta)
        };
        chi_square::plane("environment map", grid, 400_000, draw, &pdf);
    }

    #[test]
    fn a_sample_has_the_density_pdf_gives_back_and_carries_the_map_radiance() {
        let map = EnvironmentMap::new(32, 16, studio(32, 16), 2.0, -45.0).with_sun(Sun::new(
            Vec3::new(-0.2, 0.7, 0.4),
            SUN_ANGULAR_RADIUS_DEGREES,
            Color::splat(10.0),
        ));
        let mut rng = SampleRng::new(4, 5, 6);
        let mut suns = 0;
        for _ in 0..2000 {
            let (d, pdf) = map.sample(rng.next_pair()).unwrap();
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert!((map.pdf(d) - pdf).abs() <= 1e-5 * pdf);
            suns += usize::from(map.sun().unwrap().pdf(d) > 0.0);
        }
        // The sun holds much of the light: many samples go to it.
        assert!(suns > 500, "{suns}");
    }

    #[test]
    fn the_radiance_at_a_texel_centre_is_the_texel_times_the_strength() {
        let texels = studio(8, 4);
        let map = EnvironmentMap::new(8, 4, texels.clone(), 3.0, 0.0);
        for (k, texel) in texels.iter().enumerate() {
            let (i, j) = (k % 8, k / 8);
            let (d, _) = map.uv_to_direction(((i as Real + 0.5) / 8.0, (j as Real + 0.5) / 4.0));
            assert!((map.radiance(d) - *texel * 3.0).abs().max_element() < 1e-4, "texel {i},{j}");
        }
    }

    #[test]
    fn importance_sampling_finds_a_small_bright_source_far_sooner_than_cosine_sampling() {
        // The irradiance on an upward surface under a dim map with one small
        // bright patch (2 × 1 texels of 64 × 32, 2000 times the rest): the
        // estimate `L cos θ / p` from the map's own samples against
        // `π L` from cosine-weighted (diffuse BSDF) samples, each RMSE over
        // 200 runs of 64 samples against a fine numerical reference.
        // Importance sampling must be at least 10 times closer (it is about
        // 17 times: 300 times fewer samples for the same error; printed with
        // the time per sample, `docs/environment-and-lens.md`).
        let (w, h) = (64, 32);
        let mut texels = vec![Color::splat(0.05); w * h];
        texels[9 * w + 40] = Color::splat(2000.0);
        texels[9 * w + 41] = Color::splat(2000.0);
        let map = EnvironmentMap::new(w, h, texels, 1.0, 0.0);
        let (nt, np) = (1500, 3000);
        let mut reference = 0.0;
        for a in 0..nt {
            let cos = (a as f64 + 0.5) / nt as f64; // upper hemisphere, uniform in cos θ
            let sin = (1.0 - cos * cos).sqrt();
            for b in 0..np {
                let phi = 2.0 * std::f64::consts::PI * (b as f64 + 0.5) / np as f64;
                let d = narrow(DVec3::new(sin * phi.cos(), cos, sin * phi.sin()));
                reference += map.radiance(d).x as f64 * cos;
            }
        }
        reference *= 2.0 * std::f64::consts::PI / (nt * np) as f64;
        let (runs, n) = (200, 64);
        let (mut se_is, mut se_cos) = (0.0, 0.0);
        let mut rng = SampleRng::new(9, 9, 9);
        let (mut time_is, mut time_cos) = (std::time::Duration::ZERO, std::time::Duration::ZERO);
        for _ in 0..runs {
            let (mut e_is, mut e_cos) = (0.0, 0.0);
            let start = std::time::Instant::now();
            for _ in 0..n {
                if let Some((d, pdf)) = map.sample(rng.next_pair()) {
                    e_is += map.radiance(d).x as f64 * to_f64(d.y.max(0.0)) / to_f64(pdf);
                }
            }
            time_is += start.elapsed();
            let start = std::time::Instant::now();
            for _ in 0..n {
                let d = crate::sampling::sampler::cosine_hemisphere(Vec3::Y, rng.next_pair());
                e_cos += std::f64::consts::PI * map.radiance(d).x as f64;
            }
            time_cos += start.elapsed();
            se_is += (e_is / n as f64 - reference).powi(2);
            se_cos += (e_cos / n as f64 - reference).powi(2);
        }
        println!(
            "time per sample (sample and look up, no ray): importance {:.0} ns, cosine {:.0} ns",
            time_is.as_nanos() as f64 / (runs * n) as f64,
            time_cos.as_nanos() as f64 / (runs * n) as f64
        );
        let (rmse_is, rmse_cos) = ((se_is / runs as f64).sqrt(), (se_cos / runs as f64).sqrt());
        println!(
            "irradiance {reference:.4}: RMSE importance {rmse_is:.5}, cosine {rmse_cos:.5} at {n} samples"
        );
        assert!(rmse_cos > 10.0 * rmse_is, "importance {rmse_is} against cosine {rmse_cos}");
    }
}
