//! How fast each sampler's error falls with samples per pixel, per scene
//! (`bench/sampler_convergence.sh` runs it on every global-illumination
//! scene and writes the table of `docs/sampling.md`):
//!
//! ```text
//! cargo run -p rt-core --example sampler_convergence -- scenes/cornell_box.ron [MORE.ron …]
//!     [--width 64] [--height 48] [--reference-spp 8192] [--max-spp 1024]
//! ```
//!
//! For each scene, at the reduced size: a reference, the mean of two
//! stratified renders of `--reference-spp / 2` samples with seeds of their
//! own (independent of the measured renders); then each sampler at 4, 8, …
//! `--max-spp` samples per pixel (seed 0). The error is the RMSE over all
//! pixels and channels of linear radiance against the reference, less the
//! reference's own noise: its variance per pixel and channel is estimated
//! as mean((a − b)²)/4 from its two halves a and b, and subtracted from the
//! measured mean squared error (an unbiased render's MSE against a noisy
//! reference is its own plus the reference's). The exponent is the slope of
//! the least-squares line through (log spp, log RMSE): −0.5 for independent
//! samples, steeper where stratification pays. Output: one line per
//! render, then a Markdown table row per scene.

use std::path::PathBuf;
use std::time::Instant;

use rt_core::sampling::sampler::SamplerKind;
use rt_core::{Color, Renderer, load_scene};

struct Args {
    scenes: Vec<PathBuf>,
    width: u32,
    height: u32,
    reference_spp: u32,
    max_spp: u32,
}

fn args() -> Result<Args, String> {
    let mut a = Args { scenes: Vec::new(), width: 64, height: 48, reference_spp: 8192, max_spp: 1024 };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut number = |name: &str| -> Result<u32, String> {
            it.next().and_then(|v| v.parse().ok()).ok_or(format!("{name} wants a number"))
        };
        match arg.as_str() {
            "--width" => a.width = number("--width")?,
            "--height" => a.height = number("--height")?,
            "--reference-spp" => a.reference_spp = number("--reference-spp")?.max(2),
            "--max-spp" => a.max_spp = number("--max-spp")?.max(4),
            _ if arg.starts_with("--") => return Err(format!("unknown option {arg}")),
            _ => a.scenes.push(arg.into()),
        }
    }
    if a.scenes.is_empty() {
        return Err("usage: sampler_convergence SCENE.ron … [--width W] [--height H] \
                    [--reference-spp N] [--max-spp N]"
            .into());
    }
    Ok(a)
}

/// The linear pixels of `scene` at the size of `a`, `spp` samples, `seed`, `sampler`.
fn render(
    scene: &rt_core::LoadedScene,
    a: &Args,
    spp: u32,
    seed: u64,
    sampler: SamplerKind,
) -> (Vec<Color>, f64) {
    let settings = scene
        .settings
        .overridden(Some(a.width), Some(a.height), Some(spp))
        .expect("valid size and count")
        .with_seed(seed)
        .with_sampler(sampler);
    let renderer = Renderer::new(&scene.scene, scene.camera, &settings).expect("a usable camera");
    let start = Instant::now();
    let frame = renderer.render(|_| {});
    (frame.pixels, start.elapsed().as_secs_f64())
}

/// Mean over pixels and channels of (a − b)².
fn mean_square(a: &[Color], b: &[Color]) -> f64 {
    let sum: f64 = a.iter().zip(b).map(|(p, q)| (*p - *q).length_squared() as f64).sum();
    sum / (3 * a.len()) as f64
}

/// The slope of the least-squares line through (ln x, ln y).
fn log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|&(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut table = vec![
        "| scene | exponent, stratified | exponent, Sobol | RMSE at 64 spp, stratified / Sobol | RMSE at max spp, stratified / Sobol | time, stratified / Sobol |".to_owned(),
        "|---|---|---|---|---|---|".to_owned(),
    ];
    for path in &a.scenes {
        let scene = match load_scene(path) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        let name = path.file_stem().unwrap_or_default().to_string_lossy().into_owned();
        let half = a.reference_spp / 2;
        let (ra, _) = render(&scene, &a, half, 1_000_001, SamplerKind::Stratified);
        let (rb, _) = render(&scene, &a, half, 1_000_002, SamplerKind::Stratified);
        let reference: Vec<Color> = ra.iter().zip(&rb).map(|(p, q)| (*p + *q) * 0.5).collect();
        let reference_variance = mean_square(&ra, &rb) / 4.0;
        println!("{name}: reference {} spp, its own RMSE {:.3e}", 2 * half, reference_variance.sqrt());
        let mut results = Vec::new();
        for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
            let mut points = Vec::new();
            let mut time = 0.0;
            let mut spp = 4;
            while spp <= a.max_spp {
                let (pixels, t) = render(&scene, &a, spp, 0, kind);
                let mse = mean_square(&pixels, &reference);
                let rmse = (mse - reference_variance).max(mse * 1e-4).sqrt();
                println!(
                    "{name} {} spp {spp}: RMSE {rmse:.4e} (uncorrected {:.4e}), {t:.2} s",
                    kind.name(),
                    mse.sqrt()
                );
                points.push((spp as f64, rmse));
                time += t;
                spp *= 2;
            }
            results.push((log_slope(&points), points, time));
        }
        let at = |points: &[(f64, f64)], spp: f64| {
            points.iter().find(|p| p.0 == spp).map_or("–".into(), |p| format!("{:.2e}", p.1))
        };
        let (s, o) = (&results[0], &results[1]);
        let last = s.1.last().map_or(0.0, |p| p.0);
        table.push(format!(
            "| {name} | {:.2} | {:.2} | {} / {} | {} / {} ({last} spp) | {:.1} / {:.1} s |",
            s.0,
            o.0,
            at(&s.1, 64.0),
            at(&o.1, 64.0),
            at(&s.1, last),
            at(&o.1, last),
            s.2,
            o.2
        ));
    }
    println!();
    for line in table {
        println!("{line}");
    }
}
