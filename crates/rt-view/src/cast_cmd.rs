//! `rt-view cast SCENE [--rays FILE | --pixels]`: ray queries as CSV (SPEC.md).
//!
//! All input is read and checked before anything is cast, and the whole CSV is
//! built before it is written, so a bad line produces an error and no output.

use std::fmt::Write as _;
use std::io::{Read, Write as _};
use std::path::Path;

use anyhow::Context;
use rayon::prelude::*;
use rt_core::{Ray, Real, Scene, Vec3};

use crate::cli::CastArgs;

/// The CSV header of ray queries.
pub const HEADER: &str = "ox,oy,oz,dx,dy,dz,hit,t,object,primitive,nx,ny,nz";

/// Rows cast and written per batch: bounds memory for `--pixels` of a large
/// image while keeping all cores busy.
const BATCH: usize = 1 << 14;

/// Runs `cast`, writing the CSV to standard output. All input is read and
/// validated first; after that nothing can fail but the write itself.
pub fn run(args: &CastArgs) -> anyhow::Result<()> {
    let scene = rt_core::load_scene(&args.scene)?;
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    if args.pixels {
        let width = args.width.unwrap_or(scene.width);
        let height = args.height.unwrap_or(scene.height);
        let view = scene
            .view_plane(width, height)
            .with_context(|| format!("{}: cannot cast pixels", args.scene.display()))?;
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
            out.write_all(rays_rows(&scene, chunk).as_bytes())?;
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

/// A ray-line error: the 1-based line number and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.line, self.message)
    }
}

/// Parses every line of `text`: blank lines and `#` comments are skipped; any
/// other line must be a ray. Stops at the first bad line.
pub fn parse_rays(text: &str) -> Result<Vec<Ray>, LineError> {
    let mut rays = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let error = |message| LineError { line: i + 1, message };
        if let Some(ray) = parse_ray_line(line).map_err(error)? {
            rays.push(ray);
        }
    }
    Ok(rays)
}

/// One line: `Ok(None)` for a blank or `#` line, the ray for
/// `ox,oy,oz,dx,dy,dz` (finite numbers, spaces around them allowed, a
/// non-zero direction), or what is wrong.
pub fn parse_ray_line(line: &str) -> Result<Option<Ray>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != 6 {
        return Err(format!(
            "expected 6 comma-separated numbers ox,oy,oz,dx,dy,dz, found {} fields",
            fields.len()
        ));
    }
    let mut v = [0.0 as Real; 6];
    for (k, (slot, field)) in v.iter_mut().zip(&fields).enumerate() {
        let name = ["ox", "oy", "oz", "dx", "dy", "dz"][k];
        *slot = field.parse().map_err(|_| format!("{name} = \"{field}\" is not a number"))?;
        if !slot.is_finite() {
            return Err(format!("{name} = \"{field}\" is not finite"));
        }
    }
    let dir = Vec3::new(v[3], v[4], v[5]);
    if dir == Vec3::ZERO {
        let precision = std::any::type_name::<Real>();
        return Err(format!("the direction (dx,dy,dz) is zero (in {precision}, the geometry's precision)"));
    }
    Ok(Some(Ray::new(Vec3::new(v[0], v[1], v[2]), dir)))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blank_and_comment_lines_are_skipped() {
        assert_eq!(parse_ray_line("   "), Ok(None));
        assert_eq!(parse_ray_line("# a comment"), Ok(None));
        assert_eq!(parse_ray_line("  # indented comment"), Ok(None));
    }

    #[test]
    fn a_ray_line_allows_spaces_exponents_and_signs() {
        let r = parse_ray_line(" 1, -2.5 ,3e2, 0,0 , -1e-3\r").unwrap().unwrap();
        assert_eq!(r, Ray::new(Vec3::new(1.0, -2.5, 300.0), Vec3::new(0.0, 0.0, -1e-3)));
    }

    #[test]
    fn malformed_lines_say_what_is_wrong() {
        let cases = [
            ("1,2,3,4,5", "found 5 fields"),
            ("1,2,3,4,5,6,7", "found 7 fields"),
            ("1,2,x,4,5,6", "oz = \"x\" is not a number"),
            ("1,2,3,,5,6", "dx = \"\" is not a number"),
            ("1,2,3,NaN,5,6", "dx = \"NaN\" is not finite"),
            ("1,2,inf,4,5,6", "oz = \"inf\" is not finite"),
            ("1,2,3,0,-0,0", "the direction (dx,dy,dz) is zero"),
            ("1e40,0,0,1,0,0", "ox = \"1e40\" is not finite"),
        ];
        for (line, expected) in cases {
            let e = parse_ray_line(line).unwrap_err();
            assert!(e.contains(expected), "{line}: {e}");
        }
    }

    #[test]
    fn errors_carry_the_line_number_counting_skipped_lines() {
        let e = parse_rays("# header\n0,0,0,0,0,1\n\n0,0,0,0,0\n").unwrap_err();
        assert_eq!(e.line, 4);
        assert_eq!(e.to_string(), "4: expected 6 comma-separated numbers ox,oy,oz,dx,dy,dz, found 5 fields");
    }
}
