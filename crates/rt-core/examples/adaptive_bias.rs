//! What adaptive sampling's stopping rules do to the estimate
//! (`docs/sampling.md`, "Adaptive sampling"):
//!
//! ```text
//! cargo run -p rt-core --example adaptive_bias -- scenes/cornell_box.ron \
//!     [--width 64] [--height 64] [--spp 256] [--threshold 0.02] [--min-samples 16] \
//!     [--seeds 8] [--reference-spp 4096] [--sampler stratified|sobol]
//! ```
//!
//! Renders a reference of `--reference-spp` (seed 1000), then for each of
//! `--seeds` seeds the full count (`--spp`) and an adaptive render under
//! each stopping rule ([`StoppingRule`]), and a full-count render of as
//! many samples per pixel as the last-pass rule took on average (equal
//! samples, about equal time). Prints, for each kind of render: samples
//! saved, seconds per render, RMSE against the reference (its own noise
//! not subtracted), the whole image's mean against the reference's (with
//! the standard error of the seeds' mean), and the 16 × 16-pixel block
//! test: each block's mean over the seeds against the reference's, in
//! units of the reference block's standard error σ_ref (from the
//! full-count renders' spread, scaled by spp / reference spp): the mean of
//! those differences over the blocks (the bias in units of the reference's
//! noise) and the share of blocks whose difference, over the combined
//! error of the seeds' mean and the reference, lies beyond 3.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use rt_core::render::adaptive::StoppingRule;
use rt_core::render::settings::AdaptiveSampling;
use rt_core::sampling::sampler::SamplerKind;
use rt_core::{Color, Renderer, load_scene};

/// One kind of render over the seeds: each seed's block means and image
/// mean, the RMSE against the reference, seconds, samples taken.
#[derive(Default)]
struct Runs {
    blocks: Vec<Vec<f64>>,
    means: Vec<f64>,
    rmse: Vec<f64>,
    seconds: f64,
    taken: u64,
}

fn main() {
    let mut a = std::env::args().skip(1);
    let (mut scene, mut width, mut height, mut spp, mut threshold, mut min) =
        (None, 64u32, 64u32, 256u32, 0.02f32, 16u32);
    let (mut seeds, mut reference_spp, mut sampler) = (8u64, 4096u32, SamplerKind::Stratified);
    while let Some(arg) = a.next() {
        let mut value = || a.next().unwrap_or_else(|| panic!("{arg} wants a value"));
        match arg.as_str() {
            "--width" => width = value().parse().expect("a number"),
            "--height" => height = value().parse().expect("a number"),
            "--spp" => spp = value().parse().expect("a number"),
            "--threshold" => threshold = value().parse().expect("a number"),
            "--min-samples" => min = value().parse().expect("a number"),
            "--seeds" => seeds = value().parse().expect("a number"),
            "--reference-spp" => reference_spp = value().parse().expect("a number"),
            "--sampler" => sampler = value().parse().expect("stratified or sobol"),
            _ => scene = Some(arg),
        }
    }
    let scene = load_scene(scene.expect("a scene file").as_ref()).unwrap_or_else(|e| panic!("{e}"));
    let settings = |n, seed| {
        scene
            .settings
            .overridden(Some(width), Some(height), Some(n))
            .unwrap()
            .with_seed(seed)
            .with_sampler(sampler)
    };
    let renderer = |n, seed| Renderer::new(&scene.scene, scene.camera, &settings(n, seed)).unwrap();
    let (w, h) = (width as usize, height as usize);
    let pixels = (w * h) as f64;
    let mean = |p: &[Color], x0: usize, x1: usize, y0: usize, y1: usize| {
        let mut sum = 0.0f64;
        for y in y0..y1 {
            for x in x0..x1 {
                sum += p[y * w + x].element_sum() as f64;
            }
        }
        sum / (3 * (x1 - x0) * (y1 - y0)) as f64
    };
    let blocks = |p: &[Color]| {
        let mut out = Vec::new();
        for by in (0..h).step_by(16) {
            for bx in (0..w).step_by(16) {
                out.push(mean(p, bx, (bx + 16).min(w), by, (by + 16).min(h)));
            }
        }
        out
    };
    let reference = renderer(reference_spp, 1000).render(|_| {}).pixels;
    let rmse = |p: &[Color]| {
        let sum: f64 = p.iter().zip(&reference).map(|(a, b)| ((*a - *b).length_squared() / 3.0) as f64).sum();
        (sum / pixels).sqrt()
    };
    let record = |runs: &mut Runs, p: &[Color], seconds: f64, taken: u64| {
        runs.blocks.push(blocks(p));
        runs.means.push(mean(p, 0, w, 0, h));
        runs.rmse.push(rmse(p));
        runs.seconds += seconds;
        runs.taken += taken;
    };
    let adaptive = AdaptiveSampling::new(threshold, min).unwrap();
    let rules = [
        ("adaptive, last pass", StoppingRule::LastPass),
        ("adaptive, all samples", StoppingRule::AllSamples),
    ];
    let (mut full, mut equal) = (Runs::default(), Runs::default());
    let mut adaptive_runs: Vec<Runs> = rules.iter().map(|_| Runs::default()).collect();
    for seed in 0..seeds {
        let t = Instant::now();
        let p = renderer(spp, seed).render(|_| {}).pixels;
        record(&mut full, &p, t.elapsed().as_secs_f64(), (w * h) as u64 * spp as u64);
        for ((_, rule), runs) in rules.iter().zip(&mut adaptive_runs) {
            let t = Instant::now();
            let f = renderer(spp, seed)
                .render_adaptive_with(adaptive, *rule, |_| {}, &AtomicBool::new(false))
                .unwrap();
            record(runs, &f.frame.pixels, t.elapsed().as_secs_f64(), f.stats.taken);
        }
        let equal_spp =
            (adaptive_runs[0].taken as f64 / ((seed + 1) as f64 * pixels)).round().max(1.0) as u32;
        let t = Instant::now();
        let p = renderer(equal_spp, seed).render(|_| {}).pixels;
        record(&mut equal, &p, t.elapsed().as_secs_f64(), (w * h) as u64 * equal_spp as u64);
    }
    let n = seeds as f64;
    let reference_blocks = blocks(&reference);
    let reference_mean = mean(&reference, 0, w, 0, h);
    // Per block: the variance of one full-count render's block mean, from the seeds' spread.
    let spread = |runs: &Runs, b: usize| {
        let m = runs.blocks.iter().map(|v| v[b]).sum::<f64>() / n;
        (m, runs.blocks.iter().map(|v| (v[b] - m).powi(2)).sum::<f64>() / (n - 1.0))
    };
    let reference_variance: Vec<f64> =
        (0..reference_blocks.len()).map(|b| spread(&full, b).1 * spp as f64 / reference_spp as f64).collect();
    println!(
        "{width}x{height}, {spp} spp, threshold {threshold}, at least {min}, {}, {seeds} seeds, reference {reference_spp} spp",
        sampler.name()
    );
    println!(
        "| render | samples saved | s per render | RMSE | image mean vs reference | block bias / σ_ref (mean over blocks) | blocks beyond 3σ |"
    );
    let equal_label =
        format!("full count at equal samples ({} spp)", (equal.taken as f64 / (n * pixels)).round());
    let mut all: Vec<(&str, &Runs)> = vec![("full count", &full)];
    all.extend(rules.iter().map(|(label, _)| *label).zip(adaptive_runs.iter()));
    all.push((equal_label.as_str(), &equal));
    for (label, runs) in all {
        let saved = 1.0 - runs.taken as f64 / (n * pixels * spp as f64);
        let m = runs.means.iter().sum::<f64>() / n;
        let se = (runs.means.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let (mut bias, mut beyond) = (0.0, 0);
        for (b, r) in reference_blocks.iter().enumerate() {
            let (bm, var) = spread(runs, b);
            bias += (bm - r) / reference_variance[b].sqrt().max(1e-12);
            if ((bm - r) / (var / n + reference_variance[b]).sqrt().max(1e-12)).abs() > 3.0 {
                beyond += 1;
            }
        }
        println!(
            "| {label} | {:.1} % | {:.2} | {:.2e} | {:+.2} % ± {:.2} % | {:+.2} | {beyond} of {} |",
            100.0 * saved,
            runs.seconds / n,
            runs.rmse.iter().sum::<f64>() / n,
            100.0 * (m / reference_mean - 1.0),
            100.0 * se / reference_mean,
            bias / reference_blocks.len() as f64,
            reference_blocks.len()
        );
    }
}
