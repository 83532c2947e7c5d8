//! What adaptive sampling's stopping rule does to the estimate
//! (`docs/sampling.md`, "Adaptive sampling"):
//!
//! ```text
//! cargo run -p rt-core --example adaptive_bias -- scenes/cornell_box.ron \
//!     [--width 128] [--height 128] [--spp 256] [--threshold 0.02] [--min-samples 16] \
//!     [--reference-spp 8192] [--sampler stratified|sobol]
//! ```
//!
//! Renders the scene three ways at the same size: the full count (`--spp`,
//! seed 0), adaptively to `--threshold` with the same seed (so its samples
//! are a subset of the full render's: every difference is the stopping
//! rule's), and a reference of `--reference-spp` with another seed. Prints
//! the samples saved, the mean of every pixel and channel of each image and
//! its relative difference from the reference, the same over the middle of
//! the image's top third (the back wall of the Cornell box: a flat region),
//! and the block-mean test: the image cut into 16 × 16-pixel blocks, each
//! block's mean compared with the reference's, in units of the full
//! render's standard error for that block (estimated from a second full
//! render with seed 1: the spread of the two blocks' means); the share of
//! blocks beyond 3 such units and the mean signed difference over blocks,
//! for the full and the adaptive render.

use std::sync::atomic::AtomicBool;

use rt_core::render::adaptive::AdaptiveFrame;
use rt_core::render::settings::AdaptiveSampling;
use rt_core::sampling::sampler::SamplerKind;
use rt_core::{Color, Renderer, load_scene};

fn main() {
    let mut a = std::env::args().skip(1);
    let (mut scene, mut width, mut height, mut spp, mut threshold, mut min, mut reference_spp, mut sampler) =
        (None, 128u32, 128u32, 256u32, 0.02f32, 16u32, 8192u32, SamplerKind::Stratified);
    while let Some(arg) = a.next() {
        let mut value = || a.next().unwrap_or_else(|| panic!("{arg} wants a value"));
        match arg.as_str() {
            "--width" => width = value().parse().expect("a number"),
            "--height" => height = value().parse().expect("a number"),
            "--spp" => spp = value().parse().expect("a number"),
            "--threshold" => threshold = value().parse().expect("a number"),
            "--min-samples" => min = value().parse().expect("a number"),
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
    let full = renderer(spp, 0).render(|_| {}).pixels;
    let other = renderer(spp, 1).render(|_| {}).pixels;
    let adaptive = AdaptiveSampling::new(threshold, min).unwrap();
    let AdaptiveFrame { frame, stats, .. } =
        renderer(spp, 0).render_adaptive(adaptive, |_| {}, &AtomicBool::new(false)).unwrap();
    let reference = renderer(reference_spp, 2).render(|_| {}).pixels;
    println!(
        "{width}x{height}, {spp} spp, threshold {threshold}, at least {min}, {}: {:.1} % of the samples saved",
        sampler.name(),
        100.0 * stats.saved()
    );
    let (w, h) = (width as usize, height as usize);
    let mean = |p: &[Color], x0: usize, x1: usize, y0: usize, y1: usize| {
        let mut sum = 0.0f64;
        for y in y0..y1 {
            for x in x0..x1 {
                sum += p[y * w + x].element_sum() as f64;
            }
        }
        sum / (3 * (x1 - x0) * (y1 - y0)) as f64
    };
    for (what, (x0, x1, y0, y1)) in
        [("whole image", (0, w, 0, h)), ("flat region", (w * 3 / 8, w * 5 / 8, h / 8, h / 3))]
    {
        let r = mean(&reference, x0, x1, y0, y1);
        let f = mean(&full, x0, x1, y0, y1);
        let ad = mean(&frame.pixels, x0, x1, y0, y1);
        println!(
            "{what}: reference {r:.5}, full {f:.5} ({:+.2} %), adaptive {ad:.5} ({:+.2} %)",
            100.0 * (f / r - 1.0),
            100.0 * (ad / r - 1.0)
        );
    }
    let mut outliers = [0usize; 2];
    let mut signed = [0.0f64; 2];
    let mut blocks = 0usize;
    for by in (0..h).step_by(16) {
        for bx in (0..w).step_by(16) {
            let (x1, y1) = ((bx + 16).min(w), (by + 16).min(h));
            let r = mean(&reference, bx, x1, by, y1);
            let (f, o) = (mean(&full, bx, x1, by, y1), mean(&other, bx, x1, by, y1));
            // E[(f − o)²] = 2σ² for two independent renders.
            let sigma = ((f - o).abs() / 2f64.sqrt()).max(1e-6 * r.abs().max(1e-3));
            for (i, v) in [f, mean(&frame.pixels, bx, x1, by, y1)].into_iter().enumerate() {
                if ((v - r) / sigma).abs() > 3.0 {
                    outliers[i] += 1;
                }
                signed[i] += (v - r) / r.abs().max(1e-6);
            }
            blocks += 1;
        }
    }
    println!(
        "blocks beyond 3σ: full {} of {blocks}, adaptive {} of {blocks}; mean relative block difference: full {:+.2} %, adaptive {:+.2} %",
        outliers[0],
        outliers[1],
        100.0 * signed[0] / blocks as f64,
        100.0 * signed[1] / blocks as f64
    );
}
