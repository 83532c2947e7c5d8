//! Piecewise-constant densities over [0,1) and [0,1)², sampled by
//! inverting their cumulative distribution (pbrt-v4 §A.1
//! `PiecewiseConstant1D`, `PiecewiseConstant2D`): what an environment map
//! is importance-sampled with ([`crate::lights::environment_map`]).
//!
//! A 1D function of `n` non-negative values f₀ … f₍ₙ₋₁₎ on equal cells of
//! [0,1) has the density `p(x) = f_i / ∫f` on cell i, `∫f = Σ f_i / n`.
//! The 2D one over `nu × nv` cells (row v, column u) is a marginal density
//! over rows times each row's conditional density over its cells:
//! `p(u, v) = p(v) · p(u | v) = f(u, v) / ∫∫f`.

use crate::math::real::{Real, to_f64};

/// A piecewise-constant density over [0,1) in equal cells.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Distribution1D {
    /// The function's values, one per cell (≥ 0).
    func: Vec<f64>,
    /// `cdf[i]` = ∫₀^{i/n} p; `cdf[0] = 0`, `cdf[n] = 1`.
    cdf: Vec<f64>,
    /// `∫f` over [0,1): the mean of the values.
    integral: f64,
}

impl Distribution1D {
    /// The density proportional to `values` (at least one; negative or NaN
    /// values count as 0). All zero: uniform, and [`Distribution1D::integral`] 0.
    pub fn new(values: &[f64]) -> Self {
        let n = values.len().max(1);
        let func: Vec<f64> = (0..n)
            .map(|i| values.get(i).copied().filter(|v| *v > 0.0 && v.is_finite()).unwrap_or(0.0))
            .collect();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        let mut sum = 0.0;
        for f in &func {
            sum += f / n as f64;
            cdf.push(sum);
        }
        let integral = sum;
        if integral > 0.0 {
            cdf.iter_mut().for_each(|c| *c /= integral);
        } else {
            cdf.iter_mut().enumerate().for_each(|(i, c)| *c = i as f64 / n as f64);
        }
        cdf[n] = 1.0;
        Self { func, cdf, integral }
    }

    /// The number of cells.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no cells (never: a distribution has at least one).
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// `∫f` over [0,1), the mean of the values (0: the density is uniform).
    pub fn integral(&self) -> f64 {
        self.integral
    }

    /// The density at a point of cell `i`: `f_i / ∫f` (1 where all are 0).
    pub fn density(&self, i: usize) -> f64 {
        if self.integral > 0.0 { self.func[i] / self.integral } else { 1.0 }
    }

    /// A point x ∈ [0,1) for `u` ∈ [0,1), its cell and its density: the
    /// cell i with `cdf[i] ≤ u < cdf[i+1]` (binary search), and x where the
    /// cdf's linear piece in it reaches u. Cells of density 0 are never picked.
    pub fn sample(&self, u: f64) -> (f64, usize, f64) {
        let n = self.func.len();
        // The last i with cdf[i] ≤ u, among 0..n (cdf[n] = 1 > u).
        let i = self.cdf[1..n].partition_point(|&c| c <= u);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let within = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        // (i + within)/n < 1 for within < 1; `min` keeps it so after rounding.
        let x = ((i as f64 + within) / n as f64).min(1.0 - f64::EPSILON / 2.0);
        (x, i, self.density(i))
    }

    /// The cell that x ∈ [0, 1] falls in (1 in the last).
    pub fn cell(&self, x: f64) -> usize {
        ((x * self.func.len() as f64) as usize).min(self.func.len() - 1)
    }
}

/// A piecewise-constant density over [0,1)² on a grid of `nu × nv` cells:
/// the marginal over rows v, then the row's conditional over columns u.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Distribution2D {
    rows: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    /// The density proportional to `values`, row after row (`nv` rows of
    /// `nu` values; `nu, nv ≥ 1` and `values.len() = nu·nv`).
    pub fn new(values: &[f64], nu: usize, nv: usize) -> Self {
        assert!(nu >= 1 && nv >= 1 && values.len() == nu * nv, "{nu} x {nv} cells, {} values", values.len());
        let rows: Vec<Distribution1D> = values.chunks(nu).map(Distribution1D::new).collect();
        let marginal = Distribution1D::new(&rows.iter().map(Distribution1D::integral).collect::<Vec<_>>());
        Self { rows, marginal }
    }

    /// `∫∫f` over [0,1)² (0: the density is uniform).
    pub fn integral(&self) -> f64 {
        self.marginal.integral()
    }

    /// A point (u, v) ∈ [0,1)² for `sample` ∈ [0,1)² and its density:
    /// v from the marginal, then u from row v's conditional.
    pub fn sample(&self, sample: (Real, Real)) -> ((f64, f64), f64) {
        let (v, row, pv) = self.marginal.sample(to_f64(sample.1));
        let (u, _, pu) = self.rows[row].sample(to_f64(sample.0));
        ((u, v), pv * pu)
    }

    /// The density at (u, v) ∈ [0, 1]²: `f(u, v) / ∫∫f`.
    pub fn pdf(&self, (u, v): (f64, f64)) -> f64 {
        let row = self.marginal.cell(v);
        self.marginal.density(row) * self.rows[row].density(self.rows[row].cell(u))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, Interval, Rectangle};

    #[test]
    fn a_one_dimensional_density_is_its_values_over_their_mean() {
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0]);
        assert_eq!(d.integral(), 2.0);
        assert_eq!((0..4).map(|i| d.density(i)).collect::<Vec<_>>(), [0.5, 1.5, 0.0, 2.0]);
        // u = 0.5 is half way: cdf = 0, 0.125, 0.5, 0.5, 1 → the start of cell 3.
        let (x, i, p) = d.sample(0.5);
        assert_eq!((x, i, p), (0.75, 3, 2.0));
        let (x, i, _) = d.sample(0.0625);
        assert_eq!((x, i), (0.125, 0));
    }

    #[test]
    fn cells_of_zero_density_are_never_sampled() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 0.0, 1.0, f64::NAN, -3.0]);
        for k in 0..1000 {
            let (x, i, p) = d.sample(k as f64 / 1000.0);
            assert!(i == 1 || i == 4, "u {k}: cell {i}");
            assert!(p > 0.0 && d.cell(x) == i && x < 1.0);
        }
    }

    #[test]
    fn an_all_zero_function_is_sampled_uniformly() {
        let d = Distribution1D::new(&[0.0; 5]);
        assert_eq!(d.integral(), 0.0);
        let (x, i, p) = d.sample(0.5);
        assert!((x - 0.5).abs() < 1e-12 && i == 2 && p == 1.0);
    }

    #[test]
    fn a_two_dimensional_density_integrates_to_one_and_matches_its_samples() {
        let values: Vec<f64> = (0..12).map(|k| ((k * 7) % 5) as f64).collect();
        let d = Distribution2D::new(&values, 4, 3);
        // ∫∫ p = Σ p(cell)/12 = 1.
        let sum: f64 = (0..12).map(|k| d.pdf(((k % 4) as f64 / 4.0 + 0.1, (k / 4) as f64 / 3.0 + 0.1))).sum();
        assert!((sum / 12.0 - 1.0).abs() < 1e-12, "{sum}");
        for k in 0..400 {
            let s = ((k % 20) as Real / 20.0 + 0.01, (k / 20) as Real / 20.0 + 0.02);
            let (uv, p) = d.sample(s);
            assert!((p - d.pdf(uv)).abs() < 1e-12 && p > 0.0, "{uv:?}");
        }
    }

    #[test]
    fn one_dimensional_samples_follow_the_density() {
        // χ² on two bins per cell (the density is constant in each, so the
        // bins' probabilities are exact); a cell of value 0 must get nothing.
        let d = Distribution1D::new(&[1.0, 3.0, 0.0, 4.0, 0.5, 2.0, 6.0, 1.5]);
        let draw = |rng: &mut SampleRng| Draw::At(d.sample(to_f64(rng.next_pair().0)).0);
        let pdf = |x: f64| d.density(d.cell(x));
        chi_square::line("piecewise-constant 1D", Interval { lo: 0.0, hi: 1.0, n: 16 }, 200_000, draw, &pdf);
    }

    #[test]
    fn two_dimensional_samples_follow_the_density() {
        // The same on two bins per cell each way, rows of different totals,
        // a row of zeros and single cells of zero.
        let (nu, nv) = (6, 4);
        let values: Vec<f64> = (0..nu * nv)
            .map(|k| if k / nu == 2 { 0.0 } else { ((k * 7) % 5) as f64 + (k / nu) as f64 })
            .collect();
        let d = Distribution2D::new(&values, nu, nv);
        let grid = Rectangle {
            s: Interval { lo: 0.0, hi: 1.0, n: 2 * nu },
            t: Interval { lo: 0.0, hi: 1.0, n: 2 * nv },
        };
        let draw = |rng: &mut SampleRng| Draw::At(d.sample(rng.next_pair()).0);
        let pdf = |u: f64, v: f64| d.pdf((u, v));
        chi_square::plane("piecewise-constant 2D", grid, 200_000, draw, &pdf);
    }
}
