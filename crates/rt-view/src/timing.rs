//! Timing helpers shared by the measuring commands (`bench`, `accuracy`):
//! medians, because the machines these run on are shared and noisy.

use std::time::{Duration, Instant};

/// The median of `values` (times, counts: the upper one of the middle two
/// for an even count); `values` must not be empty.
pub fn median<T: Ord + Copy>(mut values: Vec<T>) -> T {
    values.sort_unstable();
    values[values.len() / 2]
}

/// The median wall time of `runs` calls of `f` (at least one).
pub fn median_time(runs: usize, mut f: impl FnMut()) -> Duration {
    median(
        (0..runs.max(1))
            .map(|_| {
                let start = Instant::now();
                f();
                start.elapsed()
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_median_is_the_middle_value_or_the_upper_middle_one() {
        let ms = |v: &[u64]| v.iter().map(|&m| Duration::from_millis(m)).collect::<Vec<_>>();
        assert_eq!(median(ms(&[5, 1, 3])), Duration::from_millis(3));
        assert_eq!(median(ms(&[4, 1, 3, 2])), Duration::from_millis(3));
    }

    #[test]
    fn median_time_calls_the_function_once_per_run() {
        let mut calls = 0;
        median_time(5, || calls += 1);
        assert_eq!(calls, 5);
        median_time(0, || calls += 1);
        assert_eq!(calls, 6, "at least one run");
    }
}
