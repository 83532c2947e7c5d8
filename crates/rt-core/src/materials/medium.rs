//! What happens to light inside a translucent object: a homogeneous
//! participating medium (Chandrasekhar, *Radiative Transfer*, 1950; pbrt-v4
//! ch. 11), the material's `subsurface` field.
//!
//! Per colour channel, light travelling through the medium is absorbed or
//! scattered at rates (per unit length) `σa` and `σs`; their sum, the
//! extinction `σt = σa + σs`, is one over the *mean free path* ℓ, and
//! `α = σs/σt` is the single-scattering *albedo*. The fraction of light that
//! travels a distance d without meeting anything is `T(d) = exp(−σt·d)`
//! (Beer–Lambert). Where it scatters, it leaves in a new direction drawn from
//! the Henyey–Greenstein phase function with anisotropy g (the mean cosine of
//! the scattering angle: 0 scatters evenly, > 0 forwards, < 0 backwards).
//!
//! A *random walk* follows one path through the medium: it samples the
//! distance to the next scattering event, scatters there, and so on until it
//! reaches the object's surface. With chromatic coefficients the channels
//! have different free paths. The walk draws every distance with the
//! coefficients of one *hero* channel, chosen uniformly when it starts, and
//! weighs the whole walk by the one-sample multiple-importance-sampling
//! estimator over the three channels' strategies (hero wavelength spectral
//! sampling: Wilkie et al., "Hero Wavelength Spectral Sampling", 2014; as
//! pbrt-v4's volumetric path tracer does, §14.2): for channel λ the estimate
//! is `f_λ / (⅓·Σ_c p_c)`, with `f_λ` the product over the walk's events of
//! `σs,λ·T_λ(t)` (a scattering event at t) and `T_λ(t)` (reaching the
//! surface at t), and `p_c` the same products with channel c's densities
//! `σt,c·T_c(t)` and `T_c(t)`. Since `f_λ ≤ α_λⁿ·p_λ`, every channel's
//! weight stays below 3, however long the walk and however different the
//! channels: each channel's estimate is unbiased and its variance bounded.
//! (Weighing each event by the mixture of the channels' densities instead
//! multiplies per-event ratios along the walk and gives rare, huge weights on
//! long walks.)

use glam::DVec3;

use crate::math::color::Color;
use crate::math::real::{HG_ISOTROPIC_G, Real, Vec3, WALK_RESCALE_ABOVE, WALK_RESCALE_BELOW, to_f32, to_f64};

/// A homogeneous medium's coefficients, as the material gives them.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Subsurface {
    /// Single-scattering albedo α = σs/σt per channel, in [0, 1].
    pub albedo: Color,
    /// Mean free path ℓ = 1/σt per channel, in scene units, > 0 and finite.
    pub mean_free_path: Color,
    /// Henyey–Greenstein anisotropy g, in (−1, 1).
    pub anisotropy: f32,
}

impl Subsurface {
    /// The extinction coefficient σt = 1/ℓ per channel.
    pub fn sigma_t(&self) -> Color {
        Color::ONE / self.mean_free_path
    }

    /// The scattering coefficient σs = α·σt per channel.
    pub fn sigma_s(&self) -> Color {
        self.albedo * self.sigma_t()
    }

    /// The fraction of light crossing `distance` unscattered, per channel:
    /// `exp(−σt·d)`.
    pub fn transmittance(&self, distance: Real) -> Color {
        (-self.sigma_t() * to_f32(distance)).exp()
    }
}

/// The spectral weight of one walk ([`crate::materials::medium`]): the hero channel
/// that draws the distances, and, relative to the hero's density of the
/// walk so far, every channel's contribution `f_λ/p_hero` and density
/// `p_c/p_hero` (kept in f64 and rescaled together, so that long walks
/// neither overflow nor underflow; only their ratio matters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkWeight {
    hero: usize,
    contribution: DVec3,
    density: DVec3,
}

impl WalkWeight {
    /// A walk whose hero channel is drawn from `u` ∈ [0, 1), each channel
    /// with probability ⅓.
    pub fn new(u: Real) -> Self {
        Self { hero: ((u * 3.0) as usize).min(2), contribution: DVec3::ONE, density: DVec3::ONE }
    }

    /// A free-flight distance drawn with the hero channel's density
    /// `σt·exp(−σt·t)` from `u` ∈ [0, 1).
    pub fn sample_distance(&self, medium: &Subsurface, u: Real) -> Real {
        -(1.0 - u).ln() / medium.sigma_t()[self.hero] as Real
    }

    /// Takes in a scattering event at `t`.
    pub fn scatter(&mut self, medium: &Subsurface, t: Real) {
        let (sigma_t, sigma_s) = (medium.sigma_t().as_dvec3(), medium.sigma_s().as_dvec3());
        let hero = sigma_t[self.hero];
        // exp(−(σ_c − σ_hero)·t): each channel's transmittance over the hero's.
        let ratio = (-(sigma_t - DVec3::splat(hero)) * to_f64(t)).exp();
        self.contribution *= sigma_s / hero * ratio;
        self.density *= sigma_t / hero * ratio;
        self.rescale();
    }

    /// Takes in reaching the surface at `t` before the drawn distance.
    pub fn pass(&mut self, medium: &Subsurface, t: Real) {
        let sigma_t = medium.sigma_t().as_dvec3();
        let ratio = (-(sigma_t - DVec3::splat(sigma_t[self.hero])) * to_f64(t)).exp();
        self.contribution *= ratio;
        self.density *= ratio;
        self.rescale();
    }

    /// Multiplies every channel's contribution by `factor` (a boundary's
    /// BSDF weight, Russian roulette).
    pub fn scale(&mut self, factor: Color) {
        self.contribution *= factor.as_dvec3();
    }

    /// The walk's weight per channel: `f_λ / (⅓·Σ_c p_c)`.
    pub fn weight(&self) -> Color {
        let mean = self.density.element_sum() / 3.0;
        if mean > 0.0 && mean.is_finite() { (self.contribution / mean).as_vec3() } else { Color::ZERO }
    }

    /// Keeps the densities near 1 (the hero's stays the largest or not, it
    /// does not matter: both vectors are divided by the same number).
    fn rescale(&mut self) {
        let m = self.density.max_element();
        if m > WALK_RESCALE_ABOVE || (m < WALK_RESCALE_BELOW && m > 0.0) {
            self.density /= m;
            self.contribution /= m;
        }
    }
}

/// The Henyey–Greenstein phase function ("Diffuse radiation in the galaxy",
/// 1941) for the cosine of the angle between the direction light travelled
/// in and the one it leaves in: `(1 − g²) / (4π·(1 + g² − 2g·cos θ)^{3/2})`,
/// per steradian; it integrates to 1 over the sphere, and its mean cosine
/// is g.
pub fn henyey_greenstein(cos_theta: Real, g: Real) -> Real {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * std::f64::consts::PI as Real * denom * denom.max(0.0).sqrt())
}

/// A direction drawn from the Henyey–Greenstein phase function about the
/// direction of travel `w` (unit), from `(u, v)` ∈ [0, 1)² by inverting its
/// distribution of cos θ (pbrt-v4 §11.3.1): the sample's weight
/// `phase/pdf` is exactly 1.
pub fn sample_henyey_greenstein(w: Vec3, g: Real, (u, v): (Real, Real)) -> Vec3 {
    let cos_theta = if g.abs() < HG_ISOTROPIC_G {
        1.0 - 2.0 * u
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        (1.0 + g * g - s * s) / (2.0 * g)
    }
    .clamp(-1.0, 1.0);
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI as Real * v;
    let (a, b) = w.any_orthonormal_pair();
    (sin_theta * phi.cos() * a + sin_theta * phi.sin() * b + cos_theta * w).normalize_or(w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::widen;
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, Interval, SphereGrid};

    /// An f64 rounded to the nearest [`Real`].
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    fn real(x: f64) -> Real {
        x as Real
    }

    fn medium(albedo: [f32; 3], mfp: [f32; 3], g: f32) -> Subsurface {
        Subsurface { albedo: Color::from(albedo), mean_free_path: Color::from(mfp), anisotropy: g }
    }

    #[test]
    fn a_walk_whose_densities_would_overflow_keeps_a_finite_weight() {
        // Hero channel 0 with σt = 100, channel 1 with σt = 1: each scattering
        // at t = 1 multiplies channel 1's density relative to the hero's by
        // 0.01·e⁹⁹ ≈ e⁹⁴, past f64's range after four steps. Rescaled, the
        // weight stays finite, and channel 1's is its contribution over a
        // third of its density (the others' are negligible beside it):
        // 3·α₁ⁿ = 3·0.9¹⁰.
        let m = medium([0.5, 0.9, 0.5], [0.01, 1.0, 0.01], 0.0);
        let mut w = WalkWeight::new(0.0);
        for _ in 0..10 {
            w.scatter(&m, 1.0);
        }
        let weight = w.weight();
        assert!(weight.is_finite() && weight.min_element() >= 0.0, "{weight}");
        assert!((weight.y - 3.0 * 0.9f32.powi(10)).abs() < 1e-5, "{weight}");
    }

    #[test]
    fn coefficients_and_transmittance_follow_from_the_mean_free_paths() {
        // ℓ = (0.5, 1, 2), albedo (0.2, 0.5, 0.8): σt = 1/ℓ = (2, 1, 0.5),
        // σs = α·σt, and over distance 2, exp(−σt·2) = (e⁻⁴, e⁻², e⁻¹).
        let m = medium([0.2, 0.5, 0.8], [0.5, 1.0, 2.0], 0.0);
        assert_eq!(m.sigma_t(), Color::new(2.0, 1.0, 0.5));
        assert!((m.sigma_s() - Color::new(0.4, 0.5, 0.4)).abs().max_element() < 1e-6);
        let t = m.transmittance(2.0);
        let exact = Color::new((-4.0f32).exp(), (-2.0f32).exp(), (-1.0f32).exp());
        assert!((t - exact).abs().max_element() < 1e-6, "{t} vs {exact}");
    }

    #[test]
    fn henyey_greenstein_integrates_to_one_and_its_mean_cosine_is_g() {
        for g in [-0.9f64, -0.3, 0.0, 0.5, 0.95] {
            // Integrate over cos θ in [−1, 1] (times 2π for φ), midpoint rule.
            let n = 200_000;
            let (mut total, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                let p = henyey_greenstein(c as Real, g as Real) as f64 * 2.0 * std::f64::consts::PI * 2.0
                    / n as f64;
                total += p;
                mean += p * c;
            }
            assert!((total - 1.0).abs() < 1e-3, "g {g}: integral {total}");
            assert!((mean - g).abs() < 2e-3, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn sampled_directions_follow_the_phase_function() {
        // χ² of 2·10⁵ directions per g on a 20 × 40 equal-area grid of the
        // sphere about the direction of travel, against the phase function
        // as `henyey_greenstein` gives it (α ≈ 10⁻⁴, see `chi_square`).
        let w = Vec3::new(0.3, -0.5, 0.8).normalize();
        // cos θ in f64 about the exact unit axis: the f32 `w` is unit only
        // to 6·10⁻⁸, which near g = 0.95's forward peak (where the density
        // varies as (1 + g² − 2g·cos θ)^(−3/2), that base being 0.0025)
        // shifts the claimed density by 10⁻⁴, visible at 4·10⁶ draws.
        let axis = widen(w).normalize();
        for g in [-0.9, -0.3, 0.0, 0.5, 0.95] {
            let draw = |rng: &mut SampleRng| {
                let d = sample_henyey_greenstein(w, g, rng.next_pair());
                assert!((d.length() - 1.0).abs() < 1e-5);
                Draw::At(widen(d))
            };
            let grid = SphereGrid::sphere(axis, 20, 40);
            let phase = |d: DVec3| to_f64(henyey_greenstein(real(d.dot(axis)), g));
            chi_square::directions(&format!("Henyey–Greenstein g = {g}"), &grid, 200_000, draw, &phase);
        }
    }

    #[test]
    fn free_flights_follow_the_exponential_density_of_the_hero_channel() {
        // χ² of 2·10⁵ distances per hero channel in 40 bins over [0, 4ℓ)
        // (and the tail beyond), against σt·exp(−σt·t) with the hero's σt
        // (α ≈ 10⁻⁴).
        let m = medium([0.5, 0.5, 0.5], [0.25, 0.5, 1.0], 0.0);
        for (u, mfp) in [(0.1, 0.25), (0.5, 0.5), (0.9, 1.0)] {
            let w = WalkWeight::new(u);
            let draw = |rng: &mut SampleRng| Draw::At(to_f64(w.sample_distance(&m, rng.next_pair().0)));
            let bins = Interval { lo: 0.0, hi: 4.0 * mfp, n: 40 };
            let density = |t: f64| (-t / mfp).exp() / mfp;
            chi_square::line(&format!("free flights, ℓ = {mfp}"), bins, 200_000, draw, &density);
        }
    }

    #[test]
    fn each_channel_is_the_hero_a_third_of_the_time() {
        // χ² of 4·10⁵ heroes against ⅓ each (α ≈ 10⁻⁴): a 1 % bias gives χ² ≈ 80.
        let draw = |rng: &mut SampleRng| Some(WalkWeight::new(rng.next_pair().0).hero);
        chi_square::discrete("hero channel", &[1.0 / 3.0; 3], 400_000, draw);
    }

    #[test]
    fn free_flights_are_exponential_with_the_hero_channels_mean_free_path() {
        let m = medium([0.5, 0.5, 0.5], [0.25, 0.5, 1.0], 0.0);
        for (u, mfp) in [(0.1, 0.25), (0.5, 0.5), (0.9, 1.0)] {
            let w = WalkWeight::new(u);
            let mut rng = SampleRng::new(4, 5, 6);
            let n = 200_000;
            let mean: f64 =
                (0..n).map(|_| to_f64(w.sample_distance(&m, rng.next_pair().0))).sum::<f64>() / n as f64;
            // The mean is ℓ, with standard error ℓ/√n.
            assert!((mean - mfp).abs() < 5.0 * mfp / (n as f64).sqrt(), "mean free flight {mean}, ℓ {mfp}");
        }
    }

    /// Mean and standard error per channel of `n` walks' weights.
    fn estimate(n: usize, mut walk: impl FnMut(&mut SampleRng) -> Color) -> ([f64; 3], [f64; 3]) {
        let mut rng = SampleRng::new(7, 8, 9);
        let (mut sum, mut sq) = ([0.0f64; 3], [0.0f64; 3]);
        for _ in 0..n {
            let w = walk(&mut rng);
            for c in 0..3 {
                sum[c] += w[c] as f64;
                sq[c] += (w[c] as f64).powi(2);
            }
        }
        let mean = sum.map(|s| s / n as f64);
        let se = [0, 1, 2].map(|c| ((sq[c] / n as f64 - mean[c] * mean[c]) / n as f64).sqrt());
        (mean, se)
    }

    #[test]
    fn the_spectral_estimate_of_each_channels_transmittance_is_unbiased() {
        // The chance of crossing a slab of thickness d unscattered, estimated
        // as the walk does (the pass weight when the flight is longer than d,
        // else 0), is exp(−σt·d) in every channel even though one channel's
        // free path is 20 times another's.
        let m = medium([1.0, 1.0, 1.0], [0.05, 0.3, 1.0], 0.0);
        let d = 0.4;
        let (mean, se) = estimate(400_000, |rng| {
            let mut w = WalkWeight::new(rng.next_pair().0);
            if w.sample_distance(&m, rng.next_pair().0) < d {
                return Color::ZERO;
            }
            w.pass(&m, d);
            w.weight()
        });
        for c in 0..3 {
            let exact = (-to_f64(d) / m.mean_free_path[c] as f64).exp();
            assert!(
                (mean[c] - exact).abs() < 5.0 * se[c] + 1e-6,
                "channel {c}: {} against {exact} ± {}",
                mean[c],
                se[c]
            );
        }
    }

    #[test]
    fn spectral_weights_stay_bounded_on_long_walks_and_average_to_the_right_answer() {
        // A walk of n scattering events then a pass, in an infinite medium
        // with wildly different channels: every weight is below 3·αⁿ (so no
        // firefly), and the mean of each channel's weight over walks is the
        // probability that the hero-independent process does the same:
        // ∫…∫ Π σs·T(tᵢ) · T(d) = αⁿ·exp(−σt·d) when the last flight is
        // at least d.
        let m = medium([0.95, 0.9, 0.8], [0.02, 0.2, 1.0], 0.0);
        let (n, d) = (8, 0.1);
        let (mean, se) = estimate(400_000, |rng| {
            let mut w = WalkWeight::new(rng.next_pair().0);
            for _ in 0..n {
                let t = w.sample_distance(&m, rng.next_pair().0);
                w.scatter(&m, t);
            }
            if w.sample_distance(&m, rng.next_pair().0) < d {
                return Color::ZERO;
            }
            w.pass(&m, d);
            let weight = w.weight();
            for c in 0..3 {
                assert!(weight[c] <= 3.0 * m.albedo[c].powi(n) * 1.0001, "{weight}");
            }
            weight
        });
        for c in 0..3 {
            let exact = (m.albedo[c] as f64).powi(n) * (-to_f64(d) / m.mean_free_path[c] as f64).exp();
            assert!(
                (mean[c] - exact).abs() < 5.0 * se[c] + 1e-6,
                "channel {c}: {} against {exact} ± {}",
                mean[c],
                se[c]
            );
        }
    }
}
