//! `rt-view render SCENE -o OUT.png`: a headless render with a progress bar.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use rt_core::Renderer;

use crate::cli::RenderArgs;
use crate::png_out::PendingPng;

/// The render was stopped by Ctrl-C (SIGINT); nothing was written. `main`
/// exits with status 130, as shells expect after SIGINT.
#[derive(Debug, thiserror::Error)]
#[error("interrupted: nothing was written")]
pub struct Interrupted;

/// Loads the scene, renders it in parallel (one progress tick per finished
/// row) and writes the PNG atomically. Nothing is written on any error or on
/// Ctrl-C, which stops the workers after their current row.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let output = PendingPng::create(&args.output)?;
    let load_start = Instant::now();
    let scene = rt_core::load_scene(&args.scene)?;
    let load_time = load_start.elapsed();
    let width = args.width.unwrap_or(scene.width);
    let height = args.height.unwrap_or(scene.height);
    let spp = args.spp.unwrap_or(scene.samples_per_pixel);
    let renderer = Renderer::new(&scene, width, height, spp)
        .with_context(|| format!("{}: cannot render", args.scene.display()))?;

    let stop = Arc::new(AtomicBool::new(false));
    let handler_stop = stop.clone();
    // Only fails if a handler is already set (not in this program) or the OS refuses.
    let _ = ctrlc::set_handler(move || handler_stop.store(true, Ordering::Relaxed));

    let bar = ProgressBar::new(height as u64).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, {elapsed} (ETA {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(format!("rendering {width}x{height}, {spp} spp"));
    let start = Instant::now();
    let frame = renderer.render_until(|_| bar.inc(1), &stop);
    let elapsed = start.elapsed();
    bar.finish_and_clear();
    let frame = frame.ok_or(Interrupted)?;

    output.write(&frame)?;
    eprintln!(
        "wrote {} ({width}x{height}, {spp} spp) in {:.3} s",
        args.output.display(),
        elapsed.as_secs_f64()
    );
    if args.stats {
        let bvh = scene.bvh_stats();
        let rays = width as f64 * height as f64 * spp as f64;
        let build = bvh.build_time.as_secs_f64();
        eprintln!("scene load: {:.3} s (of which BVH build {build:.3} s)", load_time.as_secs_f64());
        eprintln!(
            "BVH: {} primitives, {} nodes, {:.1} KiB ({:.1} bytes per primitive)",
            bvh.primitives,
            bvh.nodes,
            bvh.bytes as f64 / 1024.0,
            bvh.bytes as f64 / bvh.primitives.max(1) as f64
        );
        eprintln!(
            "tracing: {:.3} s, {rays} primary rays, {:.3} Mrays/s on {} threads",
            elapsed.as_secs_f64(),
            rays / elapsed.as_secs_f64() / 1e6,
            rayon::current_num_threads()
        );
    }
    Ok(())
}
