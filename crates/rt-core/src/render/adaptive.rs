//! Adaptive sampling: pixels stop taking samples once their noise estimate
//! falls below a threshold ([`AdaptiveSampling`]), without biasing the
//! image ([`StoppingRule::LastPass`]).
//!
//! **Schedule.** Every pixel takes its first samples up to the first
//! checkpoint, `min_samples` rounded up to a block end of the open-ended
//! film layout (1, 4, 16, 64, 256, 1024, then multiples of 1024:
//! [`crate::sampling::sampler::open_ended_block`]); then the pixels still
//! sampling take passes that each end at four times the count before (16,
//! 64, 256, …), the last cut at the settings' samples per pixel N
//! ([`passes`]). Film positions are those of the open-ended layout
//! ([`Renderer::open_ended`]), so each pass is a whole stratification of
//! the pixel (or, for Sobol points, a run of a (0,2)-sequence): a pixel
//! that stops at a checkpoint has no part of its area left out.
//!
//! **Noise estimate.** Each pixel keeps two half sums, of its even- and of
//! its odd-numbered samples: two estimates of the pixel whose difference
//! shows the noise of their mean without storing the samples' squares. The
//! error is the L1 distance of the half means over the square root of the
//! intensity (the sum of the channels), so a bright pixel may be as noisy
//! in absolute terms as √ its brightness — the perceptual scaling of
//! Dammertz et al., "A Hierarchical Automatic Stopping Condition for Monte
//! Carlo Global Illumination" (WSCG 2010), §2.1, as Cycles computes it
//! (`intern/cycles/kernel/film/adaptive_sampling.h`,
//! `film_adaptive_sampling_convergence_check`). Both the distance and the
//! intensity are averaged over the pixel's 3 × 3 window ([`window_error`];
//! Cycles too filters convergence over neighbours): with D and I the means
//! over the window of each pixel's Σ_c |E_c − O_c| / n and Σ_c (E_c + O_c) / n,
//!
//! error = D / (10⁻⁴ + √I).
//!
//! A single pixel's estimate from 16 samples is itself very noisy (a pixel
//! whose samples all missed a rare bright path reads 0); the window's,
//! from nine pixels, is not, and a pixel whose neighbours are noisy goes on.
//!
//! **Stopping rules** ([`StoppingRule`]):
//!
//! - [`StoppingRule::LastPass`] (the default) decides on the samples taken
//!   so far and outputs samples it has not looked at: at a checkpoint of n
//!   samples, a pixel whose error predicted for the next pass's L samples,
//!   error · √(n/L), is below the threshold takes that pass and stops, and
//!   its value is the mean of that last pass alone (a pixel that reaches N
//!   likewise outputs its last pass). Whether a pass is the last depends
//!   only on samples taken before it, and a pass's samples are independent
//!   of those (stratified sampler) and each a whole stratification of the
//!   pixel, so the pixel's expected value is its true value whenever it
//!   stops: **no bias**. The cost is noise: the last pass is ¾ of a pixel's
//!   samples (the schedule grows ×4), so the output has 4/3 the variance of
//!   all the samples' mean. With Sobol points a pass is not independent of
//!   the earlier ones (they share the sequence's strata); each point is
//!   still uniform, and `docs/sampling.md` measures what is left.
//! - [`StoppingRule::AllSamples`] stops a pixel as soon as its error is
//!   below the threshold and outputs the mean of all its samples, the
//!   common rule (Cycles'). It decides on the samples it averages, so it is
//!   biased: a pixel whose samples by chance look smooth (or brighter, as
//!   the error is divided by √ the intensity) stops with that value, while
//!   one that looks noisy goes on and is corrected. The window dilutes the
//!   pixel's own part in the decision but does not remove it.
//!   `docs/sampling.md` measures both rules.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::math::color::Color;
use crate::math::real::ADAPTIVE_DARK;
use crate::render::settings::AdaptiveSampling;
use crate::render::{Frame, NoFeatures, Renderer, band_rows};
use crate::scene::effects::RayCounts;

/// How a pixel's samples become its value once adaptive sampling stops it
/// (the module's "Stopping rules").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StoppingRule {
    /// Decide on the samples taken so far, output the last pass's samples
    /// alone: unbiased, 4/3 the variance of all the samples' mean.
    #[default]
    LastPass,
    /// Stop when the error is below the threshold and output all samples:
    /// less noise, biased.
    AllSamples,
}

/// Adaptively sampled image: the frame, and how many samples each
/// pixel took.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveFrame {
    /// The image: each pixel's value under the stopping rule.
    pub frame: Frame,
    /// Samples taken by each pixel, row-major as the frame's pixels.
    pub samples: Vec<u32>,
    /// The totals.
    pub stats: AdaptiveStats,
}

/// What adaptive sampling did: the samples taken against the full count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdaptiveStats {
    /// Samples taken, over all pixels.
    pub taken: u64,
    /// Samples the full count would have taken (pixels × samples per pixel).
    pub full: u64,
    /// Pixels that converged before the full count.
    pub converged: u64,
    /// Passes run (the first, to the first checkpoint, included).
    pub passes: u32,
}

impl AdaptiveStats {
    /// The share of the full count's samples not taken, in [0, 1].
    pub fn saved(&self) -> f64 {
        if self.full == 0 { 0.0 } else { 1.0 - self.taken as f64 / self.full as f64 }
    }
}

/// The first checkpoint for a minimum of `min_samples`: the smallest block
/// end of the open-ended film layout at or above it (1, 4, 16, 64, 256,
/// 1024, then multiples of 1024).
fn first_checkpoint(min_samples: u32) -> u32 {
    if min_samples > 1024 {
        return min_samples.div_ceil(1024).saturating_mul(1024);
    }
    let mut end = 1;
    while end < min_samples {
        end *= 4;
    }
    end
}

/// The sample ranges of adaptive sampling's passes up to `samples` per
/// pixel: `0..c` for c the first checkpoint at or above `min_samples`
/// (a block end of the open-ended film layout, at most `samples`), then
/// ranges that each end at four times the count before, the last cut at
/// `samples`.
pub fn passes(min_samples: u32, samples: u32) -> Vec<Range<u32>> {
    let samples = samples.max(1);
    let first = first_checkpoint(min_samples.max(1)).min(samples);
    let mut out = Vec::new();
    out.push(0..first);
    let mut end = first;
    while end < samples {
        let next = end.saturating_mul(4).min(samples);
        out.push(end..next);
        end = next;
    }
    out
}

/// The relative error of a noise distance `difference` (Σ_c |E_c − O_c| / n)
/// at `intensity` (Σ_c (E_c + O_c) / n): difference / (10⁻⁴ + √intensity)
/// (the module's formula).
fn error_of(difference: f32, intensity: f32) -> f32 {
    difference / (ADAPTIVE_DARK + intensity.max(0.0).sqrt())
}

/// The relative error estimate of a single pixel from the sums of its
/// even- and odd-numbered samples, `n` in all (the module's formula
/// without the window).
pub fn relative_error(even: Color, odd: Color, n: u32) -> f32 {
    let n = n.max(1) as f32;
    error_of((even - odd).abs().element_sum() / n, (even + odd).element_sum() / n)
}

/// The error of pixel (`x`, `y`) over its 3 × 3 window (clipped at the
/// image's edges): the window's mean noise distance over the root of its
/// mean intensity, from each pixel's `(distance, intensity)` in `noise`
/// (row-major, `width` wide).
pub fn window_error(noise: &[(f32, f32)], width: usize, x: usize, y: usize) -> f32 {
    let height = noise.len() / width.max(1);
    let (mut difference, mut intensity, mut count) = (0.0, 0.0, 0.0);
    for wy in y.saturating_sub(1)..(y + 2).min(height) {
        for wx in x.saturating_sub(1)..(x + 2).min(width) {
            let (d, i) = noise[wy * width + wx];
            difference += d;
            intensity += i;
            count += 1.0;
        }
    }
    error_of(difference / count, intensity / count)
}

/// Where a pixel stands in the schedule.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum State {
    /// Takes the next pass and is checked after it.
    #[default]
    Sampling,
    /// Takes the next pass, its last (under [`StoppingRule::LastPass`]).
    Last,
    /// Takes no more samples.
    Done,
}

/// One pixel's state under adaptive sampling.
#[derive(Clone, Copy, Debug, Default)]
struct Pixel {
    /// Sums of the even- and odd-numbered samples.
    halves: [Color; 2],
    /// Samples taken.
    taken: u32,
    /// Sum and count of the samples of the latest pass the pixel took.
    pass: Color,
    pass_taken: u32,
    state: State,
}

impl Pixel {
    /// Adds sample `k`'s colour `c`.
    fn add(&mut self, k: u32, c: Color) {
        self.halves[(k & 1) as usize] += c;
        self.taken += 1;
        self.pass += c;
        self.pass_taken += 1;
    }

    /// The noise distance and intensity of [`error_of`].
    fn noise(&self) -> (f32, f32) {
        let n = self.taken.max(1) as f32;
        let [even, odd] = self.halves;
        ((even - odd).abs().element_sum() / n, (even + odd).element_sum() / n)
    }

    /// The pixel's value under `rule`.
    fn value(&self, rule: StoppingRule) -> Color {
        match rule {
            StoppingRule::LastPass => self.pass / self.pass_taken.max(1) as f32,
            StoppingRule::AllSamples => (self.halves[0] + self.halves[1]) / self.taken.max(1) as f32,
        }
    }
}

/// Runs the schedule of passes up to `spp` over a `width`×`height` image:
/// `sample(rows, samples, band)` adds samples `samples` of every pixel of
/// `band` (rows `rows`, row-major) that is not [`State::Done`]; bands run
/// in parallel. Decisions are made on the whole image between passes, so
/// the outcome does not depend on the thread count. `None` if `stop` was set.
fn run_schedule(
    (width, height, spp): (u32, u32, u32),
    adaptive: AdaptiveSampling,
    rule: StoppingRule,
    stop: &AtomicBool,
    sample: impl Fn(Range<u32>, Range<u32>, &mut [Pixel]) -> RayCounts + Sync,
) -> Option<(Vec<Pixel>, RayCounts, u32)> {
    let mut pixels = vec![Pixel::default(); width as usize * height as usize];
    let schedule = passes(adaptive.min_samples(), spp);
    let mut rays = RayCounts::default();
    for (i, samples) in schedule.iter().enumerate() {
        for p in pixels.iter_mut().filter(|p| p.state != State::Done) {
            (p.pass, p.pass_taken) = (Color::ZERO, 0);
        }
        let band_rows = band_rows(samples.len() as u32);
        rays += pixels
            .par_chunks_mut(width as usize * band_rows as usize)
            .enumerate()
            .map(|(band, band_pixels)| {
                if stop.load(Ordering::Relaxed) {
                    return RayCounts::default();
                }
                let first = band as u32 * band_rows;
                sample(first..(first + band_rows).min(height), samples.clone(), band_pixels)
            })
            .sum::<RayCounts>();
        if stop.load(Ordering::Relaxed) {
            return None;
        }
        let Some(next) = schedule.get(i + 1) else { break };
        let noise: Vec<(f32, f32)> = pixels.iter().map(Pixel::noise).collect();
        for (at, p) in pixels.iter_mut().enumerate() {
            match p.state {
                State::Done => {}
                State::Last => p.state = State::Done,
                State::Sampling => {
                    let error =
                        window_error(&noise, width as usize, at % width as usize, at / width as usize);
                    match rule {
                        StoppingRule::LastPass => {
                            // The next pass's mean has √(n / L) the error of these n samples'.
                            if error * (p.taken as f32 / next.len() as f32).sqrt() < adaptive.threshold() {
                                p.state = State::Last;
                            }
                        }
                        StoppingRule::AllSamples => {
                            if error < adaptive.threshold() {
                                p.state = State::Done;
                            }
                        }
                    }
                }
            }
        }
    }
    Some((pixels, rays, schedule.len() as u32))
}

impl Renderer<'_> {
    /// Renders every pixel adaptively ([`crate::render::adaptive`]) with
    /// the default, unbiased [`StoppingRule::LastPass`]: at most the
    /// settings' samples per pixel, fewer for pixels whose noise estimate
    /// falls below `adaptive`'s threshold. Film positions are the
    /// open-ended layout's ([`Renderer::open_ended`]). Each pass's rows go
    /// in parallel bands as in [`Renderer::render`], and `row_done` is
    /// called once per row per pass (`passes(…).len()` times the height in
    /// all). A sample's colour depends on its pixel and index alone, and
    /// the decisions on the sums after each whole pass, so the image is the
    /// same whatever the thread count. `None` if `stop` was set.
    pub fn render_adaptive(
        &self,
        adaptive: AdaptiveSampling,
        row_done: impl Fn(u32) + Sync,
        stop: &AtomicBool,
    ) -> Option<AdaptiveFrame> {
        self.render_adaptive_with(adaptive, StoppingRule::default(), row_done, stop)
    }

    /// [`Renderer::render_adaptive`] with the stopping rule `rule`.
    pub fn render_adaptive_with(
        &self,
        adaptive: AdaptiveSampling,
        rule: StoppingRule,
        row_done: impl Fn(u32) + Sync,
        stop: &AtomicBool,
    ) -> Option<AdaptiveFrame> {
        let renderer = self.open_ended();
        let (width, height) = (self.view.width(), self.view.height());
        let (pixels, rays, passes) =
            run_schedule((width, height, self.spp), adaptive, rule, stop, |rows, samples, band| {
                let wanted: Vec<bool> = band.iter().map(|p| p.state != State::Done).collect();
                let counts = renderer.sample_region(
                    rows.clone(),
                    0..width,
                    samples,
                    |at| wanted[at],
                    |at, k, c| band[at].add(k, c),
                    &mut NoFeatures,
                );
                rows.for_each(&row_done);
                counts
            })?;
        let stats = AdaptiveStats {
            taken: pixels.iter().map(|p| p.taken as u64).sum(),
            full: pixels.len() as u64 * self.spp as u64,
            converged: pixels.iter().filter(|p| p.taken < self.spp).count() as u64,
            passes,
        };
        let samples = pixels.iter().map(|p| p.taken).collect();
        let pixels = pixels.iter().map(|p| p.value(rule)).collect();
        let frame = Frame { width, height, pixels, color_space: self.color_space, rays };
        Some(AdaptiveFrame { frame, samples, stats })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test_support::renderer;
    use std::path::Path;

    #[test]
    fn passes_start_at_a_block_end_at_or_above_the_minimum_and_grow_fourfold() {
        assert_eq!(passes(16, 256), vec![0..16, 16..64, 64..256]);
        assert_eq!(passes(10, 256), vec![0..16, 16..64, 64..256]);
        assert_eq!(passes(16, 100), vec![0..16, 16..64, 64..100]);
        assert_eq!(passes(16, 8), vec![0..8]);
        assert_eq!(passes(1, 4), vec![0..1, 1..4]);
        assert_eq!(passes(2000, 8192), vec![0..2048, 2048..8192]);
        assert_eq!(passes(1024, 1 << 16), vec![0..1024, 1024..4096, 4096..16384, 16384..65536]);
    }

    #[test]
    fn the_error_is_the_half_means_l1_distance_over_the_root_of_the_intensity() {
        // Halves equal: no error, however dark. Even 2, odd 1 per channel
        // over 4 samples: |E − O| sums to 3, /4; intensity 9/4, root 1.5.
        assert_eq!(relative_error(Color::ZERO, Color::ZERO, 8), 0.0);
        assert_eq!(relative_error(Color::splat(0.3), Color::splat(0.3), 8), 0.0);
        let e = relative_error(Color::splat(2.0), Color::ONE, 4);
        assert!((e - 0.75 / (1.5 + ADAPTIVE_DARK)).abs() < 1e-6, "{e}");
        // Four times the light with the same relative spread: twice the
        // error (a bright pixel's noise is allowed to grow as its root only).
        let bright = relative_error(Color::splat(8.0), Color::splat(4.0), 4);
        assert!((bright - 3.0 / (3.0 + ADAPTIVE_DARK)).abs() < 1e-6, "{bright}");
    }

    #[test]
    fn the_window_error_averages_distance_and_intensity_over_the_neighbours_clipped_at_the_edges() {
        // 3 × 2 pixels; only the middle top one is noisy.
        let noise = [(0.0, 1.0), (0.9, 1.0), (0.0, 1.0), (0.0, 1.0), (0.0, 1.0), (0.0, 1.0)];
        // Every window holds the noisy pixel: 0.9 over 4 or 6 pixels.
        assert!((window_error(&noise, 3, 0, 0) - 0.9 / 4.0 / (1.0 + ADAPTIVE_DARK)).abs() < 1e-6);
        assert!((window_error(&noise, 3, 1, 1) - 0.9 / 6.0 / (1.0 + ADAPTIVE_DARK)).abs() < 1e-6);
        // Intensity is averaged before its root: a black pixel beside
        // bright ones is judged on the window's light.
        let dark = [(0.1, 0.0), (0.0, 4.0)];
        assert!((window_error(&dark, 2, 0, 0) - 0.05 / (2f32.sqrt() + ADAPTIVE_DARK)).abs() < 1e-6);
    }

    /// A uniform number in [0, 1) from (x, y, k) (SplitMix64's finaliser).
    fn uniform(x: u32, y: u32, k: u32) -> f32 {
        let mut z = ((x as u64) << 40 ^ (y as u64) << 20 ^ k as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    /// What pixel (x, y) of the test image of [`kind_means`] is: 0 black,
    /// 1 a rare bright path, 2 smooth grey.
    fn kind(x: u32, y: u32) -> usize {
        match x / 16 {
            1 if x % 2 == 1 && y % 2 == 1 => 1,
            0 | 1 => 0,
            _ => 2,
        }
    }

    /// A test image 48 pixels wide: 16 black columns; 16 black columns with
    /// every other pixel of every other row (so black all around) on a rare
    /// bright path (16 with probability 1/32, else 0: mean 0.5, variance
    /// 7.75 a sample); and 16 columns of smooth grey (0.5 ± 0.25 uniform:
    /// variance 1/48); each pixel's samples drawn independently. The mean
    /// of each kind of pixel over `height` rows after the schedule under
    /// `rule`, and its standard error given each pixel's output count.
    fn kind_means(rule: StoppingRule, threshold: f32, height: u32) -> ([f64; 3], [f64; 3], AdaptiveStats) {
        let value = |x: u32, y: u32, k: u32| match kind(x, y) {
            0 => 0.0,
            1 => 16.0 * (uniform(x, y, k) < 1.0 / 32.0) as u32 as f32,
            _ => 0.25 + 0.5 * uniform(x, y, k),
        };
        let adaptive = AdaptiveSampling::new(threshold, 16).unwrap();
        let (pixels, _, passes) = run_schedule(
            (48, height, 1024),
            adaptive,
            rule,
            &AtomicBool::new(false),
            |rows, samples, band| {
                for (at, p) in band.iter_mut().enumerate().filter(|(_, p)| p.state != State::Done) {
                    let (x, y) = (at as u32 % 48, rows.start + at as u32 / 48);
                    samples.clone().for_each(|k| p.add(k, Color::splat(value(x, y, k))));
                }
                RayCounts::default()
            },
        )
        .unwrap();
        let (mut sum, mut variance, mut n) = ([0.0f64; 3], [0.0f64; 3], [0.0f64; 3]);
        let per_sample = [0.0, 7.75, 1.0 / 48.0];
        for (at, p) in pixels.iter().enumerate() {
            let k = kind(at as u32 % 48, at as u32 / 48);
            let count = match rule {
                StoppingRule::LastPass => p.pass_taken,
                StoppingRule::AllSamples => p.taken,
            };
            sum[k] += p.value(rule).x as f64;
            variance[k] += per_sample[k] / count as f64;
            n[k] += 1.0;
        }
        let taken = pixels.iter().map(|p| p.taken as u64).sum();
        let stats = AdaptiveStats { taken, full: 48 * height as u64 * 1024, converged: 0, passes };
        let mean = [0, 1, 2].map(|k| sum[k] / n[k]);
        (mean, [0, 1, 2].map(|k| variance[k].sqrt() / n[k]), stats)
    }

    #[test]
    fn the_last_pass_rule_is_unbiased_where_the_all_samples_rule_is_not() {
        // Rare bright paths among black pixels: a pixel whose first samples
        // all missed looks black and smooth. The last-pass rule still
        // outputs samples it never looked at, so every kind of pixel's mean
        // is its true value within noise; the all-samples rule keeps such
        // pixels' black.
        let (mean, error, stats) = kind_means(StoppingRule::LastPass, 0.02, 1024);
        assert!(stats.saved() > 0.35, "{stats:?}");
        assert_eq!(mean[0], 0.0);
        for k in [1, 2] {
            let z = (mean[k] - 0.5) / error[k];
            assert!(z.abs() < 4.0, "kind {k}: mean {} (z = {z:.1}), {stats:?}", mean[k]);
        }
        let (mean, error, stats) = kind_means(StoppingRule::AllSamples, 0.02, 1024);
        assert!(stats.saved() > 0.35, "{stats:?}");
        let z = (mean[1] - 0.5) / error[1];
        assert!(z < -8.0, "the all-samples rule: mean {} (z = {z:.1})", mean[1]);
    }

    fn cornell(spp: u32) -> crate::LoadedScene {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut s = crate::load_scene(&scenes.join("cornell_box.ron")).unwrap();
        s.settings.samples = crate::SamplesPerPixel::new(spp).unwrap();
        s
    }

    #[test]
    fn converged_pixels_stop_and_the_rest_take_every_sample_the_same_on_any_thread_count() {
        // The walls converge at a loose threshold; the count of samples
        // taken is what the pixels say; an unreachable threshold takes
        // every sample and, averaging them all, gives the open-ended
        // fixed-count image.
        let s = cornell(64);
        let r = renderer(&s, 24, 18, 64);
        let stop = AtomicBool::new(false);
        let loose = AdaptiveSampling::new(0.5, 4).unwrap();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| r.render_adaptive(loose, |_| {}, &stop).unwrap())
        };
        let AdaptiveFrame { frame, samples, stats } = run(1);
        assert_eq!(AdaptiveFrame { frame: frame.clone(), samples: samples.clone(), stats }, run(2));
        assert_eq!(stats.full, 24 * 18 * 64);
        assert_eq!(stats.taken, samples.iter().map(|&n| n as u64).sum::<u64>());
        assert!(samples.iter().all(|n| [16, 64].contains(n)), "{samples:?}");
        assert_eq!(stats.converged, samples.iter().filter(|&&n| n < 64).count() as u64);
        assert!(stats.converged > 0 && stats.saved() > 0.2, "{stats:?}");
        assert_eq!(stats.passes, 3);
        assert_eq!(frame.rays.primary, stats.taken);
        let never = AdaptiveSampling::new(1e-30, 4).unwrap();
        let all = r.render_adaptive_with(never, StoppingRule::AllSamples, |_| {}, &stop).unwrap();
        let fixed = r.open_ended().render(|_| {});
        for ((a, b), n) in all.frame.pixels.iter().zip(&fixed.pixels).zip(&all.samples) {
            if *n == 64 {
                // The same samples, summed in two halves: equal to rounding.
                assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "{a} vs {b}");
            }
        }
        assert!(all.stats.converged < all.stats.full / 64 / 2, "{:?}", all.stats);
        // A stopped render returns nothing.
        assert!(r.render_adaptive(loose, |_| {}, &AtomicBool::new(true)).is_none());
    }
}
