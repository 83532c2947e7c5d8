//! Adaptive sampling: pixels stop taking samples once their noise estimate
//! falls below a threshold ([`AdaptiveSampling`]).
//!
//! **Schedule.** Every pixel takes its first `min_samples` (m); then the
//! pixels not yet converged take samples in passes that double the count,
//! `m..2m`, `2m..4m`, … up to the settings' samples per pixel N
//! ([`passes`]). After each pass every pixel still sampling is checked.
//!
//! **Noise estimate.** Each pixel keeps two half sums, of its even- and of
//! its odd-numbered samples: two independent estimates of the pixel (for
//! independent samples), whose difference shows the noise of their mean
//! without storing the samples' squares. The error is the L1 distance of
//! the half means over the square root of the pixel's intensity (the sum of
//! its channels), so a bright pixel may be as noisy in absolute terms as √
//! its brightness — the perceptual scaling of Dammertz et al., "A
//! Hierarchical Automatic Stopping Condition for Monte Carlo Global
//! Illumination" (WSCG 2010), §2.1, as Cycles computes it
//! (`intern/cycles/kernel/film/adaptive_sampling.h`,
//! `film_adaptive_sampling_convergence_check`): with E and O the even and
//! odd sums of n samples,
//!
//! error = Σ_c |E_c − O_c| / n  /  (10⁻⁴ + √(Σ_c (E_c + O_c) / n)),
//!
//! and the pixel has converged when error < threshold. (Cycles' `I − A`,
//! the whole sum less twice the odd one, is E − O.)
//!
//! **Bias.** Stopping on the very samples that are averaged biases the
//! estimate: a pixel whose samples have, by chance, missed a rare bright
//! path looks both darker and less noisy than it is, converges, and keeps
//! its low value; one that found it keeps sampling, and its excess is
//! diluted. So adaptive images are darker where rare paths carry the
//! light (caustics, small lights seen through bounces). `docs/sampling.md`
//! measures it.
//!
//! With Sobol samples ([`crate::sampling::sampler::SamplerKind::Sobol`])
//! the even and odd samples of a pixel each fill half of every dimension's
//! range (the shuffle keeps the index's parity, and the first Sobol
//! dimension splits on it), so E − O also holds the pixel's variation
//! across those halves: the estimate is larger than the mean's error (the
//! pixel samples longer, as in Cycles, which pairs the same way).

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use crate::math::color::Color;
use crate::render::settings::AdaptiveSampling;
use crate::render::{BAND_ROWS, Frame, NoFeatures, Renderer};
use crate::scene::effects::RayCounts;

/// Added to the square root of the intensity in [`relative_error`]
/// (Cycles' value), so a black pixel's error is finite: 0 if its halves
/// agree.
const DARK: f32 = 1e-4;

/// An adaptively sampled image: the frame, and how many samples each
/// pixel took.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveFrame {
    /// The image: each pixel the mean of the samples it took.
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
    /// Passes run (the first, of `min_samples`, included).
    pub passes: u32,
}

impl AdaptiveStats {
    /// The share of the full count's samples not taken, in [0, 1].
    pub fn saved(&self) -> f64 {
        if self.full == 0 { 0.0 } else { 1.0 - self.taken as f64 / self.full as f64 }
    }
}

/// The sample ranges of adaptive sampling's passes up to `samples` per
/// pixel: `0..m` for m = `min_samples` (at most `samples`), then ranges
/// doubling the count, the last cut at `samples`.
pub fn passes(min_samples: u32, samples: u32) -> Vec<Range<u32>> {
    let m = min_samples.clamp(1, samples.max(1));
    let mut out = Vec::new();
    out.push(0..m);
    let mut end = m;
    while end < samples {
        let next = end.saturating_mul(2).min(samples);
        out.push(end..next);
        end = next;
    }
    out
}

/// The relative error estimate of a pixel from the sums of its even- and
/// odd-numbered samples, `n` in all (the module's formula).
pub fn relative_error(even: Color, odd: Color, n: u32) -> f32 {
    let n = n.max(1) as f32;
    let difference = (even - odd).abs().element_sum() / n;
    let intensity = (even + odd).element_sum().max(0.0) / n;
    difference / (DARK + intensity.sqrt())
}

/// One pixel's state under adaptive sampling.
#[derive(Clone, Copy, Debug, Default)]
struct Pixel {
    /// Sums of the even- and odd-numbered samples.
    halves: [Color; 2],
    /// Samples taken.
    taken: u32,
    /// Whether it still takes samples.
    sampling: bool,
}

impl Renderer<'_> {
    /// Renders every pixel adaptively ([`crate::render::adaptive`]): at
    /// most the settings' samples per pixel, fewer for pixels whose noise
    /// estimate falls below `adaptive`'s threshold. Each pass's rows go in
    /// parallel bands as in [`Renderer::render`], and `row_done` is called
    /// once per row per pass (`passes(…).len()` times the height in all).
    /// A sample's colour depends on its pixel and index alone, and the
    /// decisions on the sums after each whole pass, so the image is the
    /// same whatever the thread count. `None` if `stop` was set.
    pub fn render_adaptive(
        &self,
        adaptive: AdaptiveSampling,
        row_done: impl Fn(u32) + Sync,
        stop: &AtomicBool,
    ) -> Option<AdaptiveFrame> {
        let (width, height) = (self.view.width(), self.view.height());
        let mut pixels = vec![Pixel { sampling: true, ..Pixel::default() }; width as usize * height as usize];
        let schedule = passes(adaptive.min_samples(), self.spp);
        let mut rays = RayCounts::default();
        for samples in &schedule {
            let band_rows = (crate::bvh::PACKET_RAYS as u32 / samples.len() as u32).clamp(1, BAND_ROWS);
            rays += pixels
                .par_chunks_mut(width as usize * band_rows as usize)
                .enumerate()
                .map(|(band, band_pixels)| {
                    if stop.load(Ordering::Relaxed) {
                        return RayCounts::default();
                    }
                    let first = band as u32 * band_rows;
                    let rows = first..(first + band_rows).min(height);
                    let wanted: Vec<bool> = band_pixels.iter().map(|p| p.sampling).collect();
                    let counts = self.sample_region(
                        rows.clone(),
                        0..width,
                        samples.clone(),
                        |at| wanted[at],
                        |at, k, c| {
                            let p = &mut band_pixels[at];
                            p.halves[(k & 1) as usize] += c;
                            p.taken += 1;
                        },
                        &mut NoFeatures,
                    );
                    rows.for_each(&row_done);
                    counts
                })
                .sum::<RayCounts>();
            if stop.load(Ordering::Relaxed) {
                return None;
            }
            for p in pixels.iter_mut().filter(|p| p.sampling) {
                if relative_error(p.halves[0], p.halves[1], p.taken) < adaptive.threshold() {
                    p.sampling = false;
                }
            }
        }
        let stats = AdaptiveStats {
            taken: pixels.iter().map(|p| p.taken as u64).sum(),
            full: pixels.len() as u64 * self.spp as u64,
            converged: pixels.iter().filter(|p| p.taken < self.spp).count() as u64,
            passes: schedule.len() as u32,
        };
        let samples = pixels.iter().map(|p| p.taken).collect();
        let pixels = pixels.iter().map(|p| (p.halves[0] + p.halves[1]) / p.taken.max(1) as f32).collect();
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
    fn passes_start_at_the_minimum_and_double_up_to_the_sample_count() {
        assert_eq!(passes(16, 256), vec![0..16, 16..32, 32..64, 64..128, 128..256]);
        assert_eq!(passes(16, 100), vec![0..16, 16..32, 32..64, 64..100]);
        assert_eq!((passes(16, 8).len(), passes(16, 8)[0].clone()), (1, 0..8));
        assert_eq!(passes(1, 4), vec![0..1, 1..2, 2..4]);
        assert_eq!((passes(3, 3).len(), passes(3, 3)[0].clone()), (1, 0..3));
    }

    #[test]
    fn the_error_is_the_half_means_l1_distance_over_the_root_of_the_intensity() {
        // Halves equal: no error, however dark. Even 2, odd 1 per channel
        // over 4 samples: |E − O| sums to 3, /4; intensity 9/4, root 1.5.
        assert_eq!(relative_error(Color::ZERO, Color::ZERO, 8), 0.0);
        assert_eq!(relative_error(Color::splat(0.3), Color::splat(0.3), 8), 0.0);
        let e = relative_error(Color::splat(2.0), Color::ONE, 4);
        assert!((e - 0.75 / (1.5 + DARK)).abs() < 1e-6, "{e}");
        // Four times the light with the same relative spread: twice the
        // error (a bright pixel's noise is allowed to grow as its root only).
        let bright = relative_error(Color::splat(8.0), Color::splat(4.0), 4);
        assert!((bright - 3.0 / (3.0 + DARK)).abs() < 1e-6, "{bright}");
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
        // every sample and gives the fixed-count image bit for bit.
        let s = cornell(64);
        let r = renderer(&s, 24, 18, 64);
        let stop = AtomicBool::new(false);
        let loose = AdaptiveSampling::new(0.5, 8).unwrap();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| r.render_adaptive(loose, |_| {}, &stop).unwrap())
        };
        let AdaptiveFrame { frame, samples, stats } = run(1);
        assert_eq!(AdaptiveFrame { frame: frame.clone(), samples: samples.clone(), stats }, run(2));
        assert_eq!(stats.full, 24 * 18 * 64);
        assert_eq!(stats.taken, samples.iter().map(|&n| n as u64).sum::<u64>());
        assert!(samples.iter().all(|n| [8, 16, 32, 64].contains(n)), "{samples:?}");
        assert_eq!(stats.converged, samples.iter().filter(|&&n| n < 64).count() as u64);
        assert!(stats.converged > 0 && stats.saved() > 0.2, "{stats:?}");
        assert_eq!(stats.passes, 4);
        assert_eq!(frame.rays.primary, stats.taken);
        // A threshold no noise meets: only pixels whose halves agree
        // exactly stop (eight black samples, or eight of the light itself),
        // and the pixels that took every sample are the fixed count's.
        let never = AdaptiveSampling::new(1e-30, 8).unwrap();
        let all = r.render_adaptive(never, |_| {}, &stop).unwrap();
        let fixed = r.render(|_| {});
        assert!(all.stats.converged < all.stats.full / 64 / 2, "{:?}", all.stats);
        for ((a, b), n) in all.frame.pixels.iter().zip(&fixed.pixels).zip(&all.samples) {
            assert!([8, 64].contains(n));
            if *n == 64 {
                // The same samples, summed in two halves: equal to rounding.
                assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "{a} vs {b}");
            }
        }
        // A stopped render returns nothing.
        assert!(r.render_adaptive(loose, |_| {}, &AtomicBool::new(true)).is_none());
    }
}
