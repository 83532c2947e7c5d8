//! A histogram of the linear image's log2 luminance and of each channel's
//! log2, as the panel draws it.
//!
//! The range is the data's: from the smallest to the largest log2 of a
//! positive value (luminance or channel), in [`BINS`] equal bins; values
//! of zero or below (black, or noise below zero) have no logarithm and are
//! counted apart. A histogram is made from the rows rendered so far, at
//! most [`MAX_SAMPLES`] pixels of them (every k-th pixel beyond that): a
//! few milliseconds however large the image, and the viewer makes one at
//! most every [`REFRESH`], only when rows arrived since.

use std::time::Duration;

use super::canvas::Canvas;
use super::display::luminance;

/// Bins of each histogram.
pub const BINS: usize = 64;
/// The most pixels a histogram is made of.
pub const MAX_SAMPLES: usize = 1 << 18;
/// The shortest time between two histograms of a changing image.
pub const REFRESH: Duration = Duration::from_millis(250);

/// Counts of log2 values in [`BINS`] bins over `range`.
#[derive(Clone, Debug, PartialEq)]
pub struct Histogram {
    /// log2 of the lowest and highest positive value (bin 0 starts at the
    /// first, the last bin ends at the second).
    pub range: [f32; 2],
    /// Counts of the luminance, then red, green, blue, per bin.
    pub counts: [[u32; BINS]; 4],
    /// How many values of each (luminance, red, green, blue) were zero or
    /// below (or not a number), so not in a bin.
    pub not_positive: [u32; 4],
    /// Pixels counted.
    pub pixels: u32,
}

impl Histogram {
    /// The histogram of `pixels` (linear colours).
    pub fn of(pixels: &[[f32; 3]]) -> Self {
        let values = |p: &[f32; 3]| [luminance(*p), p[0], p[1], p[2]];
        let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
        for v in pixels.iter().flat_map(values) {
            if v > 0.0 && v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        let range = if lo <= hi { [lo.log2(), hi.log2()] } else { [0.0, 0.0] };
        let mut h = Self { range, counts: [[0; BINS]; 4], not_positive: [0; 4], pixels: pixels.len() as u32 };
        for p in pixels {
            for (i, v) in values(p).into_iter().enumerate() {
                match h.bin(v) {
                    Some(b) => h.counts[i][b] += 1,
                    None => h.not_positive[i] += 1,
                }
            }
        }
        h
    }

    /// The histogram of the rows of `canvas` rendered so far: of every
    /// k-th of their pixels, k the smallest that keeps to [`MAX_SAMPLES`].
    pub fn of_canvas(canvas: &Canvas) -> Self {
        let [w, h] = canvas.size();
        let step = (canvas.rows_done() as usize * w).div_ceil(MAX_SAMPLES).max(1);
        let mut samples = Vec::with_capacity(MAX_SAMPLES.min(canvas.rows_done() as usize * w));
        let mut skip = 0;
        for row in (0..h as u32).filter_map(|y| canvas.linear_row(y)) {
            // Continues the stride across rows, so narrow images sample evenly.
            samples.extend(row.iter().skip(skip).step_by(step));
            skip = (skip + step - w % step) % step;
        }
        Self::of(&samples)
    }

    /// The bin of value `v`: `None` for zero, below, or NaN.
    pub fn bin(&self, v: f32) -> Option<usize> {
        if v.is_nan() || v <= 0.0 || v.is_infinite() {
            return None;
        }
        let [lo, hi] = self.range;
        let t = if hi > lo { (v.log2() - lo) / (hi - lo) } else { 0.0 };
        Some(((t * BINS as f32) as usize).min(BINS - 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_fall_in_equal_log2_bins_over_the_datas_range() {
        // Greys of 1/16 to 16: log2 from −4 to 4, 8 stops in 64 bins of 1/8.
        let pixels = [[1.0 / 16.0; 3], [1.0; 3], [16.0; 3], [0.0; 3], [2.0; 3]];
        let h = Histogram::of(&pixels);
        assert_eq!(h.range, [-4.0, 4.0]);
        assert_eq!(h.pixels, 5);
        for channel in 0..4 {
            let bins: Vec<usize> = (0..BINS).filter(|&b| h.counts[channel][b] > 0).collect();
            assert_eq!(bins, [0, 32, 40, 63], "channel {channel}: {:?}", h.counts[channel]);
            assert_eq!(h.counts[channel].iter().sum::<u32>(), 4);
        }
        assert_eq!(h.not_positive, [1; 4], "black has no logarithm");
        assert_eq!((h.bin(0.0), h.bin(-1.0), h.bin(f32::NAN)), (None, None, None));
    }

    #[test]
    fn channels_are_counted_apart_from_the_luminance() {
        let h = Histogram::of(&[[1.0, 0.0, 0.0], [0.0, 0.0, 4.0]]);
        // Luminance 0.2126 and 0.2888; red 1; blue 4; range log2 0.2126 … 2.
        assert_eq!(h.not_positive, [0, 1, 2, 1]);
        assert_eq!(h.counts[1][h.bin(1.0).unwrap()], 1);
        assert_eq!(h.counts[3][BINS - 1], 1);
        assert_eq!(h.counts[0][0], 1);
    }

    #[test]
    fn a_canvas_histogram_counts_only_rendered_rows_and_at_most_the_sample_limit() {
        use crate::viewer::render_job::Row;
        let mut c = Canvas::new(1, 4, 3, 4096);
        let row = |y, v| Row {
            generation: 1,
            y,
            samples: 1,
            pixels: vec![egui::Color32::BLACK; 4],
            linear: vec![[v; 3]; 4],
        };
        c.apply(&row(0, 1.0));
        c.apply(&row(2, 2.0));
        let h = Histogram::of_canvas(&c);
        assert_eq!((h.pixels, h.range, h.not_positive), (8, [0.0, 1.0], [0; 4]), "row 1 is not rendered");
        // A large image is sampled.
        let mut big = Canvas::new(1, 1000, 1000, 4096);
        for y in 0..1000 {
            big.apply(&Row {
                generation: 1,
                y,
                samples: 1,
                pixels: vec![egui::Color32::BLACK; 1000],
                linear: vec![[1.0; 3]; 1000],
            });
        }
        let h = Histogram::of_canvas(&big);
        assert!(h.pixels as usize <= MAX_SAMPLES && h.pixels as usize > MAX_SAMPLES / 2, "{}", h.pixels);
    }
}
