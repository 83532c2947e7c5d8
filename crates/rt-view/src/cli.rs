//! The command line: `rt-view [SCENE]`, `rt-view render`, `rt-view cast`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// A CPU ray tracer: view RON scene files live, render them to PNG, or query rays against them.
///
/// With no command, opens the interactive viewer on SCENE (or a built-in
/// scene): drag to orbit, shift- or right-drag to pan, wheel to zoom; the side
/// panel has FOV, near, position and look-at controls. Saving the scene file
/// in an editor reloads it.
#[derive(Debug, Parser)]
#[command(
    name = "rt-view",
    version,
    args_conflicts_with_subcommands = true,
    after_help = "Examples:\n  \
        rt-view                      (the viewer, on the built-in scene)\n  \
        rt-view scenes/showcase.ron  (the viewer, on a scene file)\n  \
        rt-view render scenes/showcase.ron -o showcase.png\n  \
        rt-view render scenes/sphere.ron -o sphere.png --width 1280 --height 960 --spp 16\n  \
        echo '0,0,-5,0,0,1' | rt-view cast scenes/sphere.ron\n  \
        rt-view cast scenes/sphere.ron --pixels > pixels.csv"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scene to open in the interactive viewer (default: a built-in scene).
    pub scene: Option<PathBuf>,
    /// Viewer: once the first full-resolution frame is on screen, save a
    /// screenshot of the window to this PNG and exit.
    #[arg(long, value_name = "OUT.png")]
    pub screenshot: Option<PathBuf>,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Render a scene to a PNG (or linear OpenEXR) file, with a progress bar on stderr.
    ///
    /// The image is written to a temporary file next to OUT and renamed over
    /// OUT only when complete, so OUT is never left half-written. A .png gets
    /// 8-bit pixels in the scene's colour space (`color_space`: Linear or
    /// Srgb); a .exr gets the linear colours as 32-bit floats, unclamped.
    Render(RenderArgs),
    /// Cast rays into a scene and print what each hits, as CSV on stdout.
    ///
    /// Input: one ray a line, `ox,oy,oz,dx,dy,dz` (blank lines and lines
    /// starting with `#` are skipped). Output header:
    /// `ox,oy,oz,dx,dy,dz,hit,t,object,primitive,nx,ny,nz`; on a miss `hit` is 0
    /// and the later columns are empty. `t` is for the ray's own direction;
    /// `object` is the 0-based index in the scene's object list, `primitive`
    /// the triangle index inside a mesh (else 0); the normal is the unit
    /// geometric normal. Hits closer to the origin than 2^-16 * max(1, largest
    /// |origin coordinate|) are ignored (the ray is taken to leave that surface).
    Cast(CastArgs),
    /// Benchmark the BVH on generated meshes of about 10k, 100k and 1M
    /// triangles: build time, primary-ray throughput per thread count,
    /// memory; and the full render time of the showcase scene.
    ///
    /// Writes each mesh as OBJ (with its camera as JSON) and the results as
    /// bench.csv to --out, so `bench/embree_primary.py` can cast the same
    /// rays with Embree.
    Bench(BenchArgs),
    /// Measure what each step of accuracy costs in time: samples per pixel,
    /// recursion depth and intersection methods on rendered scenes (error
    /// against a converged reference), and every intersection method on fixed
    /// ray sets of hard cases (wrong hits or misses, error of t, ns per ray).
    ///
    /// Writes accuracy.csv, accuracy.md (tables) and accuracy.png (error
    /// against time) to --out. With --with-f64, an f64 build's geometry rows
    /// are measured in the same run.
    Accuracy(AccuracyArgs),
}

/// `rt-view accuracy`.
#[derive(Debug, Args)]
pub struct AccuracyArgs {
    /// Folder for accuracy.csv, accuracy.md and accuracy.png.
    #[arg(long, default_value = "accuracy-out")]
    pub out: PathBuf,
    /// Timed runs per measurement; the median is reported.
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Smaller images and fewer samples (a quick run).
    #[arg(long)]
    pub quick: bool,
    /// An rt-view built with `--features f64`, whose geometry rows are added.
    #[arg(long, value_name = "RT_VIEW_F64")]
    pub with_f64: Option<PathBuf>,
    /// Only the geometry part, written as accuracy-f32.csv or accuracy-f64.csv
    /// (what --with-f64 runs in the other build).
    #[arg(long)]
    pub geometry_only: bool,
    /// Folder of the measured scene files.
    #[arg(long, default_value = "scenes")]
    pub scenes: PathBuf,
}

/// `rt-view bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Folder for the generated OBJ files, cameras and bench.csv.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Timed runs per measurement; the median is reported.
    #[arg(long, default_value_t = 5)]
    pub runs: usize,
    /// Thread counts to measure throughput with, comma-separated.
    #[arg(long, value_delimiter = ',', default_values_t = [1, 2])]
    pub threads: Vec<usize>,
    /// Only the 10k and 100k meshes (a quick run).
    #[arg(long)]
    pub quick: bool,
    /// Scene whose full render is timed too.
    #[arg(long, default_value = "scenes/showcase.ron")]
    pub showcase: PathBuf,
}

/// `rt-view render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Output file: .png, or .exr for linear HDR.
    #[arg(short, long, value_name = "OUT.png")]
    pub output: PathBuf,
    /// Image width in pixels (default: the scene's).
    #[arg(long, value_name = "W")]
    pub width: Option<u32>,
    /// Image height in pixels (default: the scene's).
    #[arg(long, value_name = "H")]
    pub height: Option<u32>,
    /// Samples per pixel, for anti-aliasing (default: the scene's, else 1).
    #[arg(long, value_name = "N")]
    pub spp: Option<u32>,
    /// Print to stderr: scene load and BVH build times, the effects
    /// simulated, the rays cast by kind (primary, shadow, reflection,
    /// refraction, ambient occlusion), tracing time and Mrays/s (all rays).
    #[arg(long)]
    pub stats: bool,
}

/// `rt-view cast`.
#[derive(Debug, Args)]
pub struct CastArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// File of rays, one `ox,oy,oz,dx,dy,dz` a line; `-` or absent: standard input.
    #[arg(long, value_name = "FILE", conflicts_with = "pixels")]
    pub rays: Option<PathBuf>,
    /// Instead of reading rays, cast the camera's primary ray through every
    /// pixel centre (row-major, top row first); rows start with `px,py`.
    #[arg(long)]
    pub pixels: bool,
    /// With --pixels: image width (default: the scene's).
    #[arg(long, value_name = "W", requires = "pixels")]
    pub width: Option<u32>,
    /// With --pixels: image height (default: the scene's).
    #[arg(long, value_name = "H", requires = "pixels")]
    pub height: Option<u32>,
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Render(args)) => crate::render_cmd::run(&args),
        Some(Command::Cast(args)) => crate::cast_cmd::run(&args),
        Some(Command::Bench(args)) => crate::bench_cmd::run(&args),
        Some(Command::Accuracy(args)) => crate::accuracy_cmd::run(&args),
        None => {
            crate::viewer::run(crate::viewer::ViewerOptions { scene: cli.scene, screenshot: cli.screenshot })
        }
    }
}
