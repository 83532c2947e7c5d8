//! The chi-square goodness-of-fit test of a sampling routine against the
//! density it claims (test-only): the harness of Mitsuba 3's
//! `src/python/python/chi2.py` and pbrt-v4's `src/pbrt/bsdfs_test.cpp`
//! (both descended from Mitsuba 0.5's `chisquare.h`, by Wenzel Jakob).
//!
//! # The test
//!
//! The domain of the samples is cut into bins: the sphere of directions
//! into an equal-area grid in (1 − cos θ, φ) about an axis
//! ([`SphereGrid`], dω = d(1 − cos θ)·dφ, so the density over the grid's
//! coordinates *is* the density over solid angle), an interval into equal
//! segments ([`Interval`]), a rectangle into equal cells ([`Rectangle`]).
//! N samples are drawn and counted per bin (`O_i`). The claimed density is
//! integrated over each bin in f64 by adaptive Simpson quadrature (nested
//! for two dimensions, as pbrt-v4's `AdaptiveSimpson2D`) to give the
//! expected counts `E_i = N·∫_bin pdf`. More bins close the books, so
//! that the expected counts sum to N and a density of the wrong total is
//! caught: the δ lobes a sample can pick (expected `N·p`, with `p` the
//! probability the routine says it chose the lobe with), and one for
//! "nothing or outside the grid" (expected `N·(1 − Σ∫pdf − Σp)`; a routine
//! that draws nothing, or outside the grid, where its density says it
//! cannot, or the reverse, fails there).
//!
//! Bins are sorted by expected count; those with `E_i < 5` are pooled into
//! one (with the next bins, while the pool is still below 5), as Pearson's
//! statistic needs expected counts of about 5 or more to follow the χ²
//! distribution. A sample in a bin whose expected count is exactly 0 fails
//! at once. The statistic is `X² = Σ (O_i − E_i)²/E_i` with `k − 1` degrees
//! of freedom for k bins after pooling; its p-value `Q((k − 1)/2, X²/2)` is
//! the regularised upper incomplete gamma function ([`gamma_q`]).
//!
//! # Significance
//!
//! A check fails when `p < α`. The whole crate's χ² checks share a budget
//! of [`SIGNIFICANCE`] = 1 %: with at most [`CHECKS`] of them, each gets
//! the Šidák-corrected `α = 1 − (1 − 0.01)^(1/CHECKS) ≈ 1.0·10⁻⁴` (Mitsuba
//! 3's `test_count` correction), so a correct routine fails some check of
//! the suite with probability below 1 % whatever its seeds, and a single
//! check with probability 10⁻⁴ (≈ a 3.9σ two-sided bound). The seeds are
//! fixed ([`SampleRng`]), so a run is reproducible; the bound does not rely
//! on them. Keep the count of checks in the crate below [`CHECKS`] (76 in
//! use, the `χ² =` lines of `cargo test -p rt-core --lib -- --nocapture`,
//! when this was written). Pearson's statistic with expected counts near
//! 5 has a slightly heavier tail than χ² (its variance is about
//! `2·dof + Σ 1/E_i` rather than `2·dof`), so the true level of a check can
//! be up to about twice α; the unused half of the budget covers that.
//!
//! Every check prints its statistic with `--nocapture`; a failure names the
//! bins that contribute most (bin, observed, expected), the pooled bin as
//! `usize::MAX` and the "nothing" bin as the last index.

use glam::DVec3;

use crate::sampling::sampler::SampleRng;

/// The probability that some correct routine fails a χ² check of the crate.
pub(crate) const SIGNIFICANCE: f64 = 0.01;

/// An upper bound on the number of χ² checks in the crate's tests (each
/// configuration of each test is one check).
pub(crate) const CHECKS: u32 = 100;

/// Expected counts below this are pooled (the usual rule for Pearson's test).
pub(crate) const MIN_EXPECTED: f64 = 5.0;

/// The significance level of one check: Šidák's correction of
/// [`SIGNIFICANCE`] over [`CHECKS`] checks.
pub(crate) fn alpha() -> f64 {
    1.0 - (1.0 - SIGNIFICANCE).powf(1.0 / CHECKS as f64)
}

/// `ln Γ(x)` for x > 0, by Lanczos' approximation (g = 7, nine
/// coefficients, relative error below 10⁻¹⁵; Numerical Recipes 3rd ed. §6.1
/// uses the same form), with the reflection formula below ½.
pub(crate) fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + G + 0.5;
    for (i, c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularised upper incomplete gamma function
/// `Q(a, x) = Γ(a, x)/Γ(a) = 1 − P(a, x)`, for a > 0, x ≥ 0: by its power
/// series for x < a + 1 and by Lentz's continued fraction otherwise
/// (Numerical Recipes 3rd ed. §6.2, `gser` and `gcf`), in f64. Both need
/// O(√a) terms, so dof in the thousands are fine.
pub(crate) fn gamma_q(a: f64, x: f64) -> f64 {
    assert!(a > 0.0 && x >= 0.0, "Q({a}, {x})");
    if x == 0.0 {
        return 1.0;
    }
    let log_prefactor = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        // P(a, x) = e^{−x}·x^a/Γ(a) · Σ_n x^n/(a·(a+1)…(a+n)).
        let (mut ap, mut term) = (a, 1.0 / a);
        let mut sum = term;
        for _ in 0..100_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).max(0.0)
    } else {
        // Q(a, x) = e^{−x}·x^a/Γ(a) · 1/(x + 1 − a − 1·(1 − a)/(x + 3 − a − …)).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..100_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).min(1.0)
    }
}

/// The probability that a χ² variable of `dof` degrees of freedom is at
/// least `statistic`: `Q(dof/2, statistic/2)`.
pub(crate) fn chi_square_p_value(statistic: f64, dof: usize) -> f64 {
    gamma_q(dof as f64 / 2.0, statistic / 2.0)
}

/// The outcome of Pearson's test.
#[derive(Clone, Debug)]
pub(crate) struct Pearson {
    /// `X² = Σ (O − E)²/E` over the bins after pooling.
    pub statistic: f64,
    /// Bins after pooling, minus one.
    pub dof: usize,
    /// `P(χ²_dof ≥ X²)`.
    pub p_value: f64,
    /// The bins with the largest contributions: (bin, observed, expected).
    pub worst: Vec<(usize, f64, f64)>,
}

/// Pearson's χ² test of `observed` against `expected` counts (same
/// length, both summing to N), pooling the bins with expected counts below
/// [`MIN_EXPECTED`] as Mitsuba 3 does. `Err` names a bin where samples fell
/// although nothing was expected there.
pub(crate) fn pearson(observed: &[f64], expected: &[f64]) -> Result<Pearson, String> {
    assert_eq!(observed.len(), expected.len());
    let mut order: Vec<usize> = (0..expected.len()).collect();
    order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
    let (mut statistic, mut bins) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    let mut contributions = Vec::new();
    for &i in &order {
        let (o, e) = (observed[i], expected[i]);
        if e <= 0.0 {
            if o > 0.0 {
                return Err(format!("{o} samples in bin {i}, where the density says none can be"));
            }
        } else if e < MIN_EXPECTED || (pool_e > 0.0 && pool_e < MIN_EXPECTED) {
            pool_o += o;
            pool_e += e;
        } else {
            let c = (o - e) * (o - e) / e;
            statistic += c;
            bins += 1;
            contributions.push((c, i, o, e));
        }
    }
    if pool_e > 0.0 {
        statistic += (pool_o - pool_e) * (pool_o - pool_e) / pool_e;
        bins += 1;
        contributions.push(((pool_o - pool_e).powi(2) / pool_e, usize::MAX, pool_o, pool_e));
    }
    let dof = bins.saturating_sub(1).max(1);
    contributions.sort_by(|a, b| b.0.total_cmp(&a.0));
    let worst = contributions.iter().take(5).map(|&(_, i, o, e)| (i, o, e)).collect();
    Ok(Pearson { statistic, dof, p_value: chi_square_p_value(statistic, dof), worst })
}

/// Panics unless `observed` fits `expected` at the level [`alpha`].
pub(crate) fn assert_fits(name: &str, observed: &[f64], expected: &[f64]) {
    match pearson(observed, expected) {
        Err(e) => panic!("{name}: {e}"),
        Ok(t) => {
            // Shown with `--nocapture`: how far from failing each check is.
            eprintln!(
                "{name}: χ² = {:.1} for {} dof, p = {:.3} {:?}",
                t.statistic, t.dof, t.p_value, t.worst
            );
            assert!(
                t.p_value >= alpha(),
                "{name}: χ² = {:.1} for {} dof, p = {:.3e} < α = {:.3e}; worst bins (bin, observed, expected; \
             {} = pooled): {:?}",
                t.statistic,
                t.dof,
                t.p_value,
                alpha(),
                usize::MAX,
                t.worst
            )
        }
    }
}

/// `∫_a^b f` by adaptive Simpson quadrature with Lyness's stopping rule and
/// Richardson's correction, to an absolute error of about `eps`, halving
/// intervals at most `depth` times (pbrt-v4 `bsdfs_test.cpp`, `AdaptiveSimpson`).
/// The first [`MIN_SPLITS`] halvings are always made (8 Simpson panels, 17
/// points), so that a density that is nonzero on a sliver of the interval
/// only (the corner of a triangle's cone of directions) is not missed by the
/// three points of the first estimate all being zero.
pub(crate) fn adaptive_simpson(f: &mut dyn FnMut(f64) -> f64, a: f64, b: f64, eps: f64, depth: u32) -> f64 {
    #[allow(clippy::too_many_arguments)]
    fn step(
        f: &mut dyn FnMut(f64) -> f64,
        (a, m, b): (f64, f64, f64),
        (fa, fm, fb): (f64, f64, f64),
        whole: f64,
        eps: f64,
        (depth, forced): (u32, u32),
    ) -> f64 {
        let (l, r) = (0.5 * (a + m), 0.5 * (m + b));
        let (fl, fr) = (f(l), f(r));
        let left = (m - a) / 6.0 * (fa + 4.0 * fl + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * fr + fb);
        let both = left + right;
        if depth == 0 || (forced == 0 && (both - whole).abs() <= 15.0 * eps) {
            return both + (both - whole) / 15.0;
        }
        let next = (depth - 1, forced.saturating_sub(1));
        step(f, (a, l, m), (fa, fl, fm), left, 0.5 * eps, next)
            + step(f, (m, r, b), (fm, fr, fb), right, 0.5 * eps, next)
    }
    let m = 0.5 * (a + b);
    let (fa, fm, fb) = (f(a), f(m), f(b));
    let whole = (b - a) / 6.0 * (fa + 4.0 * fm + fb);
    step(f, (a, m, b), (fa, fm, fb), whole, eps, (depth, MIN_SPLITS.min(depth)))
}

/// Halvings [`adaptive_simpson`] always makes.
const MIN_SPLITS: u32 = 2;

/// `∫∫ f(s, t) ds dt` over a rectangle by nested [`adaptive_simpson`].
pub(crate) fn adaptive_simpson_2d(
    f: &dyn Fn(f64, f64) -> f64,
    (s0, s1): (f64, f64),
    (t0, t1): (f64, f64),
    eps: f64,
    depth: u32,
) -> f64 {
    let mut outer = |t: f64| adaptive_simpson(&mut |s| f(s, t), s0, s1, eps / (t1 - t0), depth);
    adaptive_simpson(&mut outer, t0, t1, eps, depth)
}

/// The probability of a bin: [`adaptive_simpson_2d`] to an absolute error
/// of [`EPS`] plus [`RELATIVE_EPS`] of the bin's midpoint-rule estimate on
/// a 4 × 4 grid.
fn bin_probability(f: &dyn Fn(f64, f64) -> f64, (s0, s1): (f64, f64), (t0, t1): (f64, f64)) -> f64 {
    let (ws, wt) = ((s1 - s0) / 4.0, (t1 - t0) / 4.0);
    let mut rough = 0.0;
    for i in 0..4 {
        for j in 0..4 {
            rough += f(s0 + (i as f64 + 0.5) * ws, t0 + (j as f64 + 0.5) * wt) * ws * wt;
        }
    }
    adaptive_simpson_2d(f, (s0, s1), (t0, t1), EPS + RELATIVE_EPS * rough.abs(), DEPTH)
}

/// Quadrature tolerance per bin, in probability, and relative to the bin's
/// probability p: far below the standard error `√(p/N)` of any bin of the
/// tests (N ≤ 10⁷: `√(p/N) ≥ 3·10⁻⁴·√p`, against `10⁻⁹ + 10⁻⁶·p`).
const EPS: f64 = 1e-9;
const RELATIVE_EPS: f64 = 1e-6;
/// Quadrature depth: a jump of the density across a bin is resolved to
/// 2⁻¹⁰ of its width (≈ 0.1 % of the bin's mass).
const DEPTH: u32 = 10;

/// What one call of a sampling routine gave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Draw<P> {
    /// A point from the smooth density.
    At(P),
    /// The discrete outcome `k` (a δ lobe), which the routine says it picks
    /// with probability `p`.
    Delta(usize, f64),
    /// No sample (the routine refused, or drew something that carries nothing).
    Nothing,
}

/// Counts draws in `bins` smooth bins, δ outcomes and the "nothing or
/// outside" bin, then tests them against `bin_probability` of each smooth
/// bin, the δ outcomes' claimed probabilities and what is left.
fn run<P>(
    name: &str,
    samples: usize,
    bins: usize,
    bin_of: impl Fn(P) -> Option<usize>,
    mut draw: impl FnMut(&mut SampleRng) -> Draw<P>,
    bin_probability: Vec<f64>,
    seed: u32,
) {
    let mut counts = vec![0.0; bins];
    let mut deltas: Vec<(f64, f64)> = Vec::new(); // (count, claimed probability) per outcome
    let mut nothing = 0.0;
    let mut rng = SampleRng::new(seed, 0x5c4e, 0x0c41);
    for _ in 0..samples {
        match draw(&mut rng) {
            Draw::At(p) => match bin_of(p) {
                Some(b) => counts[b] += 1.0,
                None => nothing += 1.0,
            },
            Draw::Delta(k, p) => {
                if deltas.len() <= k {
                    deltas.resize(k + 1, (0.0, f64::NAN));
                }
                let (count, claim) = &mut deltas[k];
                assert!(
                    claim.is_nan() || (*claim - p).abs() <= 1e-5 * p,
                    "{name}: δ outcome {k} claims {p} and {claim}"
                );
                *count += 1.0;
                *claim = p;
            }
            Draw::Nothing => nothing += 1.0,
        }
    }
    let n = samples as f64;
    let smooth: f64 = bin_probability.iter().sum();
    let discrete: f64 = deltas.iter().filter(|d| d.0 > 0.0).map(|d| d.1).sum();
    let rest = 1.0 - smooth - discrete;
    assert!(
        rest > -1e-4,
        "{name}: the densities add up to {} > 1 (smooth {smooth}, δ {discrete})",
        1.0 - rest
    );
    let mut observed = counts;
    let mut expected: Vec<f64> = bin_probability.iter().map(|p| p * n).collect();
    for (count, claim) in deltas.into_iter().filter(|d| d.0 > 0.0) {
        observed.push(count);
        expected.push(claim * n);
    }
    observed.push(nothing);
    expected.push(rest.max(0.0) * n);
    assert_fits(name, &observed, &expected);
}

/// An orthonormal frame about a unit axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    axis: DVec3,
    t1: DVec3,
    t2: DVec3,
}

impl Frame {
    /// The frame about `axis` (normalised here).
    pub(crate) fn new(axis: DVec3) -> Self {
        let axis = axis.normalize();
        let (t1, t2) = axis.any_orthonormal_pair();
        Self { axis, t1, t2 }
    }

    /// The coordinates `(1 − cos θ, φ)` of direction `d` (normalised here)
    /// about the axis, `φ` in [0, 2π), `1 − cos θ` computed without
    /// cancellation near the axis.
    pub(crate) fn coordinates(&self, d: DVec3) -> (f64, f64) {
        let d = d.normalize();
        let (x, y, z) = (d.dot(self.t1), d.dot(self.t2), d.dot(self.axis));
        let u = if z > 0.0 { (x * x + y * y) / (1.0 + z) } else { 1.0 - z };
        let phi = y.atan2(x).rem_euclid(std::f64::consts::TAU);
        (u, phi)
    }
}

/// An equal-area grid over the directions within `1 − cos θ ≤ u_max` of an
/// axis: `n_u` bins in `u = 1 − cos θ` times `n_phi` bins in φ (each bin has
/// solid angle `u_max·2π/(n_u·n_phi)`). `u_max = 2` is the whole sphere;
/// with `n_u` even, `u = 1` (the plane normal to the axis) is a bin edge.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SphereGrid {
    frame: Frame,
    u_max: f64,
    n_u: usize,
    n_phi: usize,
}

impl SphereGrid {
    /// The grid of the whole sphere about `axis`.
    pub(crate) fn sphere(axis: DVec3, n_u: usize, n_phi: usize) -> Self {
        Self::cap(axis, 2.0, n_u, n_phi)
    }

    /// The grid of the cap `1 − cos θ ≤ u_max` about `axis`.
    pub(crate) fn cap(axis: DVec3, u_max: f64, n_u: usize, n_phi: usize) -> Self {
        assert!(u_max > 0.0 && u_max <= 2.0);
        Self { frame: Frame::new(axis), u_max, n_u, n_phi }
    }

    /// Grid coordinates `(1 − cos θ, φ)` of a direction ([`Frame::coordinates`]).
    fn coordinates(&self, d: DVec3) -> (f64, f64) {
        self.frame.coordinates(d)
    }

    /// The unit direction at grid coordinates `(u, φ)`.
    fn direction(&self, u: f64, phi: f64) -> DVec3 {
        let r = (u * (2.0 - u)).max(0.0).sqrt();
        let (s, c) = phi.sin_cos();
        r * c * self.frame.t1 + r * s * self.frame.t2 + (1.0 - u) * self.frame.axis
    }

    fn bin(&self, d: DVec3) -> Option<usize> {
        let (u, phi) = self.coordinates(d);
        if !(u.is_finite() && u <= self.u_max) {
            return None;
        }
        let i = ((u / self.u_max * self.n_u as f64) as usize).min(self.n_u - 1);
        let j = ((phi / std::f64::consts::TAU * self.n_phi as f64) as usize).min(self.n_phi - 1);
        Some(i * self.n_phi + j)
    }

    /// `∫ pdf dω` over each bin.
    fn probabilities(&self, pdf: &dyn Fn(DVec3) -> f64) -> Vec<f64> {
        let du = self.u_max / self.n_u as f64;
        let dphi = std::f64::consts::TAU / self.n_phi as f64;
        let f = |u: f64, phi: f64| pdf(self.direction(u, phi));
        let mut out = Vec::with_capacity(self.n_u * self.n_phi);
        for i in 0..self.n_u {
            for j in 0..self.n_phi {
                let (u, phi) = (i as f64 * du, j as f64 * dphi);
                out.push(bin_probability(&f, (u, u + du), (phi, phi + dphi)));
            }
        }
        out
    }
}

/// Tests a routine that draws unit directions (δ outcomes and nothing
/// allowed, see [`Draw`]) against its claimed density over solid angle,
/// with `samples` draws binned on `grid`. Directions outside the grid count
/// as "nothing": the density must integrate over the grid to the fraction
/// of draws that land in it.
pub(crate) fn directions(
    name: &str,
    grid: &SphereGrid,
    samples: usize,
    draw: impl FnMut(&mut SampleRng) -> Draw<DVec3>,
    pdf: &dyn Fn(DVec3) -> f64,
) {
    let probabilities = grid.probabilities(pdf);
    run(name, samples, grid.n_u * grid.n_phi, |d| grid.bin(d), draw, probabilities, 0xd1);
}

/// `n` equal bins over `[lo, hi)`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Interval {
    /// Lower end.
    pub lo: f64,
    /// Upper end.
    pub hi: f64,
    /// Number of bins.
    pub n: usize,
}

impl Interval {
    fn bin(&self, x: f64) -> Option<usize> {
        let k = (x - self.lo) / (self.hi - self.lo) * self.n as f64;
        (k >= 0.0 && k < self.n as f64).then_some(k as usize)
    }

    fn probabilities(&self, pdf: &dyn Fn(f64) -> f64) -> Vec<f64> {
        let w = (self.hi - self.lo) / self.n as f64;
        (0..self.n)
            .map(|k| {
                let a = self.lo + k as f64 * w;
                adaptive_simpson(&mut |x| pdf(x), a, a + w, EPS, 2 * DEPTH)
            })
            .collect()
    }
}

/// Tests a routine that draws reals against its claimed density over the
/// line, binned on `bins`; draws outside it count as "nothing", so the
/// density must integrate over it to the fraction of draws inside.
pub(crate) fn line(
    name: &str,
    bins: Interval,
    samples: usize,
    draw: impl FnMut(&mut SampleRng) -> Draw<f64>,
    pdf: &dyn Fn(f64) -> f64,
) {
    let probabilities = bins.probabilities(pdf);
    run(name, samples, bins.n, |x| bins.bin(x), draw, probabilities, 0x1d);
}

/// A rectangle `[s.lo, s.hi) × [t.lo, t.hi)` cut into `s.n × t.n` cells.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Rectangle {
    /// The first coordinate's bins.
    pub s: Interval,
    /// The second coordinate's bins.
    pub t: Interval,
}

/// Tests a routine that draws points of the plane against its claimed
/// density over area, binned on `grid`; points outside it count as
/// "nothing".
pub(crate) fn plane(
    name: &str,
    grid: Rectangle,
    samples: usize,
    draw: impl FnMut(&mut SampleRng) -> Draw<(f64, f64)>,
    pdf: &dyn Fn(f64, f64) -> f64,
) {
    let (ws, wt) = ((grid.s.hi - grid.s.lo) / grid.s.n as f64, (grid.t.hi - grid.t.lo) / grid.t.n as f64);
    let mut probabilities = Vec::with_capacity(grid.s.n * grid.t.n);
    for j in 0..grid.t.n {
        for i in 0..grid.s.n {
            let (s, t) = (grid.s.lo + i as f64 * ws, grid.t.lo + j as f64 * wt);
            probabilities.push(bin_probability(pdf, (s, s + ws), (t, t + wt)));
        }
    }
    let bin_of = |(s, t): (f64, f64)| Some(grid.t.bin(t)? * grid.s.n + grid.s.bin(s)?);
    run(name, samples, grid.s.n * grid.t.n, bin_of, draw, probabilities, 0x2d);
}

/// Tests the frequencies of `samples` discrete draws (outcome indices
/// below `probabilities.len()`, or `None`) against `probabilities`.
pub(crate) fn discrete(
    name: &str,
    probabilities: &[f64],
    samples: usize,
    mut draw: impl FnMut(&mut SampleRng) -> Option<usize>,
) {
    let to_draw = |k: Option<usize>| match k {
        Some(k) => Draw::At(k),
        None => Draw::Nothing,
    };
    let n = probabilities.len();
    run(name, samples, n, |k| (k < n).then_some(k), |rng| to_draw(draw(rng)), probabilities.to_vec(), 0x3d);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_incomplete_gamma_function_gives_the_chi_square_tables_p_values() {
        // Q(1, x) = e^{−x}; Q(½, x) = erfc(√x).
        for x in [0.01, 0.5, 1.0, 2.0, 10.0, 50.0] {
            assert!((gamma_q(1.0, x) - (-x).exp()).abs() < 1e-14 * (1.0 + (-x).exp().recip()));
        }
        assert!((gamma_q(0.5, 1.0) - 0.157_299_207_050_285_13).abs() < 1e-13);
        // Critical values of χ² at p = 0.01 (NIST/SEMATECH e-Handbook, table 1.3.6.7.4),
        // and for 1000 dof from the Wilson–Hilferty approximation's exact value.
        for (dof, critical) in [(1, 6.635), (2, 9.210), (10, 23.209), (100, 135.807), (1000, 1106.969)] {
            let p = chi_square_p_value(critical, dof);
            assert!((p - 0.01).abs() < 2e-5, "{dof} dof: p({critical}) = {p}");
        }
        // ln Γ at integers and at ½.
        assert!((ln_gamma(10.0) - (362_880.0f64).ln()).abs() < 1e-12);
        assert!((ln_gamma(0.5) - std::f64::consts::PI.sqrt().ln()).abs() < 1e-12);
        assert!((ln_gamma(0.1) - 2.252_712_651_734_206).abs() < 1e-12);
    }

    #[test]
    fn adaptive_simpson_integrates_a_peak_and_a_jump() {
        // ∫₀¹ a/(a² + x²)… : atan(1/a) for a narrow peak at 0.
        let a = 1e-3;
        let got = adaptive_simpson(&mut |x| a / (a * a + x * x), 0.0, 1.0, 1e-10, 30);
        assert!((got - (1.0f64 / a).atan()).abs() < 1e-8, "{got}");
        // A step at 1/3: depth 10 resolves it to 2⁻¹⁰ of the interval.
        let got = adaptive_simpson(&mut |x| if x < 1.0 / 3.0 { 1.0 } else { 0.0 }, 0.0, 1.0, 1e-12, 10);
        assert!((got - 1.0 / 3.0).abs() < 1e-3, "{got}");
        let got = adaptive_simpson_2d(&|x, y| x * y * y, (0.0, 2.0), (0.0, 1.0), 1e-12, 10);
        assert!((got - 2.0 / 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_test_accepts_the_right_density_and_rejects_a_slightly_wrong_one() {
        // x = √u has density 2x on [0, 1); claiming 2x passes, 1.9x + 0.05 fails.
        let draw = |rng: &mut SampleRng| Draw::At(crate::math::real::to_f64(rng.next_pair().0.sqrt()));
        let bins = Interval { lo: 0.0, hi: 1.0, n: 50 };
        line("√u against 2x", bins, 100_000, draw, &|x| 2.0 * x);
        let wrong = std::panic::catch_unwind(|| line("√u", bins, 100_000, draw, &|x| 1.9 * x + 0.05));
        assert!(wrong.is_err());
        // A density that integrates to 0.97 fails through the "nothing" bin.
        let short = std::panic::catch_unwind(|| line("√u", bins, 100_000, draw, &|x| 1.94 * x));
        assert!(short.is_err());
        // A sample where the density is 0.
        assert!(pearson(&[1.0, 9.0], &[0.0, 10.0]).is_err());
    }

    #[test]
    fn the_sphere_grid_has_equal_area_bins_and_finds_each_directions_bin() {
        let grid = SphereGrid::sphere(DVec3::new(1.0, 2.0, -0.5), 8, 16);
        let p = grid.probabilities(&|_| 1.0 / (4.0 * std::f64::consts::PI));
        assert!(p.iter().all(|&q| (q - 1.0 / 128.0).abs() < 1e-12), "{p:?}");
        for (i, j) in [(0, 0), (3, 5), (7, 15), (4, 8)] {
            let du = 2.0 / 8.0;
            let dphi = std::f64::consts::TAU / 16.0;
            let d = grid.direction((i as f64 + 0.5) * du, (j as f64 + 0.5) * dphi);
            assert_eq!(grid.bin(d), Some(i * 16 + j));
        }
    }
}
