//! `rt-view render SCENE -o OUT.png`: a headless render with a progress bar.

use std::time::Instant;

use anyhow::Context;
use indicatif::{ProgressBar, ProgressStyle};
use rt_core::Renderer;

use crate::cli::RenderArgs;
use crate::png_out::PendingPng;

/// Loads the scene, renders it in parallel (one progress tick per finished
/// row) and writes the PNG atomically. Nothing is written on any error.
pub fn run(args: &RenderArgs) -> anyhow::Result<()> {
    let output = PendingPng::create(&args.output)?;
    let scene = rt_core::load_scene(&args.scene)?;
    let width = args.width.unwrap_or(scene.width);
    let height = args.height.unwrap_or(scene.height);
    let spp = args.spp.unwrap_or(scene.samples_per_pixel);
    let renderer = Renderer::new(&scene, width, height, spp)
        .with_context(|| format!("{}: cannot render", args.scene.display()))?;

    let bar = ProgressBar::new(height as u64).with_style(
        ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, {elapsed} (ETA {eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(format!("rendering {width}x{height}, {spp} spp"));
    let start = Instant::now();
    let frame = renderer.render(|_| bar.inc(1));
    let elapsed = start.elapsed();
    bar.finish_and_clear();

    output.write(&frame)?;
    eprintln!(
        "wrote {} ({width}x{height}, {spp} spp) in {:.3} s",
        args.output.display(),
        elapsed.as_secs_f64()
    );
    Ok(())
}
