//! `rt-view cast SCENE [--rays FILE | --pixels]`: ray queries as CSV (`docs/command-line.md`).
//!
//! All input is read and checked before anything is cast, and the whole CSV is
//! built before it is written, so a bad line produces an error and no output.

use std::fmt::Write as _;
use std::io::{Read, Write as _};
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use rayon::prelude::*;
use rt_core::{Ray, Scene};

pub use rt_core::files::ray_text::{LineError, parse_ray_line, parse_rays};

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

/// The CSV header of ray queries.
pub const HEADER: &str = "ox,oy,oz,dx,dy,dz,hit,t,object,primitive,nx,ny,nz";

/// Rows cast and written per batch: bounds memory for `--pixels` of a large
/// image while keeping all cores busy.
const BATCH: usize = 1 << 14;

/// Runs `cast`, writing the CSV to standard output. All input is read and
/// validated first; after that nothing can fail but the write itself.
pub fn run(args: &CastArgs) -> anyhow::Result<()> {
    let loaded = crate::scene_cache::load_scene(&args.scene)?;
    let scene = &loaded.scene;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if args.pixels {
        let cannot = || format!("{}: cannot cast pixels", args.scene.display());
        let image = loaded.settings.overridden(args.width, args.height, None).with_context(cannot)?.image;
        let (width, height) = (image.width(), image.height());
        let view = rt_core::ViewPlane::new(loaded.camera, width, height).with_context(cannot)?;
        writeln!(out, "px,py,{HEADER}")?;
        let pixels = width as usize * height as usize;
        for start in (0..pixels).step_by(BATCH) {
            let chunk: String = (start..(start + BATCH).min(pixels))
                .into_par_iter()
                .map(|i| {
                    let (px, py) = ((i % width as usize) as u32, (i / width as usize) as u32);
                    let ray = view.center_ray(px, py);
                    let mut row = format!("{px},{py},");
                    push_row(&mut row, &ray, scene.cast(&ray).as_ref());
                    row
                })
                .collect();
            out.write_all(chunk.as_bytes())?;
        }
    } else {
        let (name, text) = read_rays_input(args.rays.as_deref())?;
        let rays = parse_rays(&text).map_err(|e| anyhow::anyhow!("{name}:{e}"))?;
        writeln!(out, "{HEADER}")?;
        for chunk in rays.chunks(BATCH) {
            out.write_all(rays_rows(scene, chunk).as_bytes())?;
        }
    }
    out.flush().context("cannot write to standard output")
}

/// Reads the ray file, or standard input for `None` or `-`; returns a name for
/// messages and the text.
fn read_rays_input(path: Option<&Path>) -> anyhow::Result<(String, String)> {
    let mut text = String::new();
    match path {
        Some(p) if p != Path::new("-") => {
            let name = p.display().to_string();
            text = std::fs::read_to_string(p).with_context(|| format!("{name}: cannot read rays"))?;
            Ok((name, text))
        }
        _ => {
            std::io::stdin().read_to_string(&mut text).context("<stdin>: cannot read rays")?;
            Ok(("<stdin>".to_owned(), text))
        }
    }
}

/// CSV rows (no header) for a list of rays, cast in parallel, in input order.
pub fn rays_rows(scene: &Scene, rays: &[Ray]) -> String {
    rays.par_iter()
        .map(|ray| {
            let mut row = String::with_capacity(96);
            push_row(&mut row, ray, scene.cast(ray).as_ref());
            row
        })
        .collect()
}

/// Appends one CSV row (with newline). Rust's `{}` prints the shortest text
/// that parses back to the same float, so every number round-trips.
fn push_row(csv: &mut String, ray: &Ray, hit: Option<&rt_core::Hit>) {
    let (o, d) = (ray.origin, ray.dir);
    let _ = write!(csv, "{},{},{},{},{},{},", o.x, o.y, o.z, d.x, d.y, d.z);
    let _ = match hit {
        Some(h) => writeln!(
            csv,
            "1,{},{},{},{},{},{}",
            h.t, h.object, h.primitive, h.normal.x, h.normal.y, h.normal.z
        ),
        None => writeln!(csv, "0,,,,,,"),
    };
}
