//! How far the render is from the reference: the error metrics over the
//! image.
//!
//! With `a` the render and `b` the reference, over the `N` pixels of the
//! rows rendered so far and their three channels:
//!
//! - RMSE = √( Σ (a − b)² / 3N )
//! - relative MSE = Σ (a − b)² / (b² + ε) / 3N, ε = 0.01 (tev's "relative
//!   squared error"; ε keeps black pixels of the reference finite).
//!
//! They are kept per row ([`Metrics`]): when rows arrive, only those rows
//! are summed again, so the numbers follow the render as it refines at the
//! cost of the rows that changed, never of the whole image each frame.

use std::sync::Arc;

use super::canvas::Canvas;
use super::reference::Reference;

/// The ε of the relative MSE, `(a − b)² / (b² + ε)`.
pub const RELATIVE_MSE_EPSILON: f64 = 0.01;

/// The error metrics of the render against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorMetrics {
    /// Root of the mean squared error over pixels and channels.
    pub rmse: f64,
    /// Mean of `(a − b)² / (b² + ε)` over pixels and channels.
    pub relative_mse: f64,
    /// Pixels compared (those of the rows rendered so far).
    pub pixels: u64,
}

/// The metrics kept per row, for one canvas and one reference: rows are
/// summed again only when they arrived again.
#[derive(Default)]
pub struct Metrics {
    /// What the sums are of: the canvas generation and the reference.
    of: Option<(u64, Arc<Reference>)>,
    /// Per row: the samples it had when summed (0: not summed), its sum of
    /// squared errors and of relative squared errors.
    rows: Vec<(u32, f64, f64)>,
}

impl Metrics {
    /// Brings the sums up to date with `canvas` (rows whose samples changed
    /// since) and returns the metrics; `None` without rows, or if the
    /// reference has another size than the canvas.
    pub fn update(&mut self, canvas: &Canvas, reference: &Arc<Reference>) -> Option<ErrorMetrics> {
        let [w, h] = canvas.size();
        if reference.size() != [w, h] {
            return None;
        }
        let same = matches!(&self.of, Some((g, r)) if *g == canvas.generation() && Arc::ptr_eq(r, reference));
        if !same {
            self.of = Some((canvas.generation(), reference.clone()));
            self.rows = vec![(0, 0.0, 0.0); h];
        }
        for (y, row) in self.rows.iter_mut().enumerate() {
            let samples = canvas.row_samples(y as u32);
            if samples != row.0 {
                let (squared, relative) =
                    canvas.linear_row(y as u32).map_or((0.0, 0.0), |a| row_errors(a, reference.row(y)));
                *row = (samples, squared, relative);
            }
        }
        let done: Vec<_> = self.rows.iter().filter(|r| r.0 > 0).collect();
        if done.is_empty() {
            return None;
        }
        let values = (done.len() * w * 3) as f64;
        let squared: f64 = done.iter().map(|r| r.1).sum();
        let relative: f64 = done.iter().map(|r| r.2).sum();
        Some(ErrorMetrics {
            rmse: (squared / values).sqrt(),
            relative_mse: relative / values,
            pixels: (done.len() * w) as u64,
        })
    }
}

/// The sums of `(a − b)²` and of `(a − b)² / (b² + ε)` over a row's pixels
/// and channels, `a` the render, `b` the reference.
fn row_errors(a: &[[f32; 3]], b: &[[f32; 3]]) -> (f64, f64) {
    let (mut squared, mut relative) = (0.0, 0.0);
    for (a, b) in a.iter().zip(b) {
        for i in 0..3 {
            let (a, b) = (a[i] as f64, b[i] as f64);
            let d2 = (a - b) * (a - b);
            squared += d2;
            relative += d2 / (b * b + RELATIVE_MSE_EPSILON);
        }
    }
    (squared, relative)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::viewer::render_job::Row;
    use egui::Color32;

    fn row(generation: u64, y: u32, samples: u32, linear: Vec<[f32; 3]>) -> Row {
        Row { generation, y, samples, pixels: vec![Color32::BLACK; linear.len()], linear }
    }

    #[test]
    fn rmse_and_relative_mse_match_a_hand_computation() {
        let reference = Arc::new(
            Reference::new(2, 2, vec![[0.0; 3], [1.0; 3], [0.5, 0.0, 0.0], [0.0; 3]], "r".into()).unwrap(),
        );
        let mut canvas = Canvas::new(1, 2, 2, 4096);
        let mut metrics = Metrics::default();
        assert_eq!(metrics.update(&canvas, &reference), None, "no rows yet");
        // Row 0: errors (0.1, 0, 0) and (0, 0, −0.5).
        canvas.apply(&row(1, 0, 1, vec![[0.1, 0.0, 0.0], [1.0, 1.0, 0.5]]));
        let m = metrics.update(&canvas, &reference).unwrap();
        // Σ(a−b)² = 0.01 + 0.25 over 6 values; relative: 0.01/0.01 + 0.25/1.01.
        assert!((m.rmse - (0.26f64 / 6.0).sqrt()).abs() < 1e-7, "{m:?}");
        assert!((m.relative_mse - (0.01 / 0.01 + 0.25 / 1.01) / 6.0).abs() < 1e-7, "{m:?}");
        assert_eq!(m.pixels, 2);
        // Row 1 arrives equal to the reference, row 0 again with more samples and no error.
        canvas.apply(&row(1, 1, 1, vec![[0.5, 0.0, 0.0], [0.0; 3]]));
        canvas.apply(&row(1, 0, 4, vec![[0.0; 3], [1.0; 3]]));
        let m = metrics.update(&canvas, &reference).unwrap();
        assert_eq!((m.rmse, m.relative_mse, m.pixels), (0.0, 0.0, 4));
    }

    #[test]
    fn a_reference_of_another_size_is_a_message_and_no_metrics() {
        let reference = Arc::new(Reference::new(3, 2, vec![[0.0; 3]; 6], "r".into()).unwrap());
        assert_eq!(
            reference.mismatch([4, 2]).unwrap(),
            "the reference is 3 × 2 pixels, the render 4 × 2: no comparison"
        );
        assert_eq!(reference.mismatch([3, 2]), None);
        let mut canvas = Canvas::new(1, 4, 2, 4096);
        canvas.apply(&row(1, 0, 1, vec![[0.0; 3]; 4]));
        assert_eq!(Metrics::default().update(&canvas, &reference), None);
    }
}
