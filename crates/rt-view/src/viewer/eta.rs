//! How long a render still needs, from what its bands of rows cost so far.
//!
//! Rows differ in cost many times over (background against glass and
//! global illumination), and a render's rows finish top to bottom, so the
//! rate of the rows done so far says little about the rows to come: on
//! `scenes/effects.ron` at 16 spp the first pass (1 spp, cheap sky rows
//! first) said its pass ends in 0.3 s, and the last pass, three quarters of
//! the work, started with 7 s to go for 8.5 s. The estimate here keeps each
//! band's own cost per sample, measured the last time the band was
//! rendered, so every band's remaining samples are priced at that band's
//! cost; until every band has been rendered once (the first pass) there is
//! no estimate rather than a guess from the cheapest rows. On that render
//! (5.95 s that time) the first estimate, 0.5 s in, put the end at 6.2 s.

use std::time::Duration;

/// What the estimate knows of one band of rows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BandCost {
    /// Samples per pixel the band has so far.
    pub samples: u32,
    /// Thread time one sample per pixel of the band took in the last pass
    /// that rendered it, in seconds (`None` before its first pass).
    pub seconds_per_sample: Option<f64>,
}

/// The wall time until every band has `target` samples per pixel: each
/// band's missing samples at its own cost per sample, all over the
/// parallelism so far (`busy` thread-seconds spent in `elapsed` seconds of
/// wall time). `None` until every band has a cost, before any work, and
/// once no band misses a sample.
pub fn time_to(target: u32, bands: &[BandCost], busy: f64, elapsed: f64) -> Option<Duration> {
    if busy <= 0.0 || elapsed <= 0.0 {
        return None;
    }
    let mut thread_seconds = 0.0;
    let mut missing = false;
    for band in bands {
        let todo = target.saturating_sub(band.samples);
        if todo > 0 {
            thread_seconds += band.seconds_per_sample? * todo as f64;
            missing = true;
        }
    }
    let parallelism = busy / elapsed;
    missing.then(|| Duration::from_secs_f64(thread_seconds / parallelism))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn band(samples: u32, cost: f64) -> BandCost {
        BandCost { samples, seconds_per_sample: Some(cost) }
    }

    #[test]
    fn each_band_is_priced_at_its_own_cost_over_the_parallelism_so_far() {
        // Cheap rows on top (0.1 s per sample), costly below (0.9 s): after
        // a 1-spp pass on 2 threads, 4 bands took 2 thread-seconds in 1 s.
        let bands = [band(1, 0.1), band(1, 0.1), band(1, 0.9), band(1, 0.9)];
        let eta = time_to(4, &bands, 2.0, 1.0).unwrap();
        // 3 more samples of each: 3 × 2.0 thread-seconds, 2 at a time.
        assert!((eta.as_secs_f64() - 3.0).abs() < 1e-9, "{eta:?}");
        // Halfway into the next pass (3 samples): the cheap top bands are
        // done, the costly rest remains, priced at the costly rows' cost.
        let bands = [band(4, 0.1), band(4, 0.1), band(1, 0.9), band(1, 0.9)];
        let eta = time_to(4, &bands, 2.6, 1.3).unwrap();
        assert!((eta.as_secs_f64() - 2.7).abs() < 1e-9, "{eta:?}");
        // A rate-so-far model prices those rows at the mean rate: 10
        // band-samples done in 1.3 s, 6 to go: 0.78 s, under a third of it.
        let rate_so_far = 1.3 / (4.0 + 2.0 * 3.0) * 6.0;
        assert!(rate_so_far < eta.as_secs_f64() / 3.0);
    }

    #[test]
    fn there_is_no_estimate_before_every_band_is_measured_nor_after_the_target() {
        let unmeasured = BandCost { samples: 0, seconds_per_sample: None };
        assert_eq!(time_to(4, &[band(1, 0.1), unmeasured], 0.1, 0.1), None);
        assert_eq!(time_to(4, &[band(4, 0.1), band(5, 0.1)], 0.1, 0.1), None);
        assert_eq!(time_to(4, &[band(1, 0.1)], 0.0, 0.0), None);
        // A band already past the target needs no cost of its own.
        assert!(
            time_to(4, &[band(1, 0.1), BandCost { samples: 4, seconds_per_sample: None }], 0.1, 0.1)
                .is_some()
        );
    }
}
