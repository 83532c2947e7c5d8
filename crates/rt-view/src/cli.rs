//! The command line: `rt-view [SCENE]`, `rt-view render`, `rt-view cast`.

use std::path::PathBuf;

use clap::{Parser, Subcommand};

use crate::commands::explain::ExplainArgs;
use crate::commands::{
    self, accuracy::AccuracyArgs, bench::BenchArgs, cast::CastArgs, export::ExportArgs, merge::MergeArgs,
    prepare::PrepareArgs, render::RenderArgs,
};
use crate::viewer;

/// A CPU ray tracer: view RON scene files live, render them to PNG, or query rays against them.
///
/// With no command, opens the interactive viewer on SCENE (default: the
/// scene shown when the viewer last closed, else a built-in scene): drag to orbit, shift- or right-drag to pan, wheel to zoom, ctrl+wheel
/// to zoom the image, hover to inspect a pixel, F1 for every shortcut; the
/// side panel has the camera, image and effect controls. Saving the scene
/// file or one of its meshes in an editor reloads it.
#[derive(Debug, Parser)]
#[command(
    name = "rt-view",
    version,
    args_conflicts_with_subcommands = true,
    after_help = "Examples:\n  \
        rt-view                      (the viewer, on the last scene or the built-in one)\n  \
        rt-view scenes/showcase.ron  (the viewer, on a scene file)\n  \
        rt-view render scenes/showcase.ron -o showcase.png\n  \
        rt-view render scenes/sphere.ron -o sphere.png --width 1280 --height 960 --spp 16\n  \
        rt-view render scenes/cornell_box.ron --part 0/4 -o part0.rtpart   (one part of four)\n  \
        rt-view merge part*.rtpart -o cornell_box.exr\n  \
        rt-view prepare scenes/cornell_box.ron -o cornell_box.rtc   (load and build once)\n  \
        echo '0,0,-5,0,0,1' | rt-view cast scenes/sphere.ron\n  \
        rt-view cast scenes/sphere.ron --pixels > pixels.csv"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Scene to open in the interactive viewer (default: the scene shown
    /// when the viewer last closed, else a built-in scene).
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
    ///
    /// With --part K/N, renders only part K of N into a part file
    /// (OUT.rtpart) for `rt-view merge`: one task of a render split over a
    /// cluster (docs/cluster.md).
    Render(RenderArgs),
    /// Merge the part files of a split render (`render --part K/N`) into
    /// its image: the very image `render` makes on one machine, bit for bit.
    ///
    /// The parts must be of one scene (its content hash), one set of
    /// settings and one split, each part once; missing parts are named, and
    /// --partial merges those that are there. Damaged or truncated part files
    /// are refused.
    Merge(MergeArgs),
    /// Load and build a scene once and write it as a scene cache (OUT.rtc):
    /// meshes, BVH, decoded textures, materials, camera and settings.
    ///
    /// Every command that takes a SCENE takes the cache instead (told by its
    /// first bytes, not its name) and starts from it in a fraction of the
    /// load time; parts rendered from it carry the scene's content hash and
    /// merge with parts rendered from the scene file. A cache of another
    /// format or rt-view version, a stale one (a source file still there has
    /// changed) and a damaged one are refused (docs/cluster.md).
    Prepare(PrepareArgs),
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
    /// Write the scene as rt-view reads it, every default filled in, as JSON
    /// (with OBJ files for its triangle objects) for outside tools such as
    /// `bench/mitsuba_compare.py`.
    Export(ExportArgs),
    /// Print the light path of one sample of one pixel as JSON, as the
    /// renderer computes it: the camera basis, the view plane, the pixel's
    /// 3D point, every ray with what it hit and the course's tests on the
    /// hit, and every term added towards the sample's value (docs/explain.md).
    Explain(ExplainArgs),
}

/// Runs the parsed command line.
pub fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Some(Command::Render(args)) => commands::render::run(&args),
        Some(Command::Merge(args)) => commands::merge::run(&args),
        Some(Command::Prepare(args)) => commands::prepare::run(&args),
        Some(Command::Cast(args)) => commands::cast::run(&args),
        Some(Command::Bench(args)) => commands::bench::run(&args),
        Some(Command::Accuracy(args)) => commands::accuracy::run(&args),
        Some(Command::Export(args)) => commands::export::run(&args),
        Some(Command::Explain(args)) => commands::explain::run(&args),
        None => viewer::run(viewer::ViewerOptions { scene: cli.scene, screenshot: cli.screenshot }),
    }
}
