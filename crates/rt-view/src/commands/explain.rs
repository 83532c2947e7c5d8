//! `rt-view explain SCENE --pixel X,Y [--sample N] [--seed S]`: the record
//! of one pixel sample's light path as JSON (`docs/explain.md`), computed by
//! the renderer itself ([`rt_core::Renderer::record_sample`]).

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use rt_core::Renderer;

/// `rt-view explain`.
#[derive(Debug, Args)]
pub struct ExplainArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// The pixel, `X,Y`: column from the left and row from the top, 0-based.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    pub pixel: (u32, u32),
    /// Which of the pixel's samples (0-based, below the samples per pixel).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub sample: u32,
    /// Seed of the random numbers, as for `render --seed`.
    #[arg(long, value_name = "S", default_value_t = 0)]
    pub seed: u64,
    /// Samples per pixel of the render the sample belongs to (default: the
    /// scene's): film positions are stratified over them.
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Image width in pixels (default: the scene's).
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Image height in pixels (default: the scene's).
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    /// Also write the scene view of the sample's path to this PNG: the
    /// scene seen from beside the camera, the camera, its view plane and
    /// frustum, the lights and every ray of the path (the viewer's scene
    /// view, drawn without a window).
    #[arg(long, value_name = "OUT.png")]
    pub scene_view: Option<PathBuf>,
    /// The scene view's size, `W,H` pixels.
    #[arg(long, value_name = "W,H", value_parser = parse_pixel, default_value = "960,640")]
    pub scene_view_size: (u32, u32),
}

/// `X,Y` as two pixel indices.
fn parse_pixel(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("{text:?} is not a pixel: expected X,Y, two whole numbers ≥ 0 such as 12,34");
    let (x, y) = text.split_once(',').ok_or_else(bad)?;
    Ok((x.trim().parse().map_err(|_| bad())?, y.trim().parse().map_err(|_| bad())?))
}

/// Runs `explain`, writing the JSON to standard output; nothing is written
/// if the scene, the pixel or the sample is not valid.
pub fn run(args: &ExplainArgs) -> anyhow::Result<()> {
    let name = args.scene.display();
    let loaded = crate::scene_cache::load_scene(&args.scene)?;
    let settings = loaded
        .settings
        .overridden(args.width, args.height, args.spp)
        .with_context(|| format!("{name}: cannot explain"))?
        .with_seed(args.seed);
    let renderer = Renderer::new(&loaded.scene, loaded.camera, &settings)
        .with_context(|| format!("{name}: cannot explain"))?;
    let (x, y) = args.pixel;
    let (width, height, spp) = (settings.image.width(), settings.image.height(), settings.samples.get());
    if x >= width || y >= height {
        anyhow::bail!(
            "{name}: pixel {x},{y} is outside the {width}x{height} image (X 0 to {}, Y 0 to {})",
            width - 1,
            height - 1
        );
    }
    if args.sample >= spp {
        anyhow::bail!(
            "{name}: sample {} does not exist: the render takes {spp} samples per pixel (0 to {}; --spp sets more)",
            args.sample,
            spp - 1
        );
    }
    // Check the picture's path before any work.
    let picture = args.scene_view.as_deref().map(crate::image_out::PendingImage::png).transpose()?;
    let record = renderer.record_sample(x, y, args.sample).context("the pixel sample was refused")?;
    if let Some(out) = picture {
        use crate::viewer::scene_view_image::{SceneViewShot, scene_view_image};
        let (w, h) = args.scene_view_size;
        if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
            anyhow::bail!("--scene-view-size {w},{h}: each side must be 1 to 8192 pixels");
        }
        let scene = std::sync::Arc::new(loaded.clone());
        let shot = SceneViewShot {
            scene: &scene,
            camera: loaded.camera,
            image_size: (width, height),
            pixel: Some([x, y]),
            observer: None,
            record: Some(&record),
        };
        out.write_rgb8(w, h, &scene_view_image(&shot, [w, h]))?;
    }
    let json = serde_json::to_string_pretty(&record).context("cannot write the record as JSON")?;
    let mut out = std::io::stdout().lock();
    writeln!(out, "{json}").and_then(|()| out.flush()).context("cannot write to standard output")
}
