//! The showcase scene rendered by the CLI, compared with committed references:
//! a small golden image, and the README's picture at the scene's own size.
//!
//! Tolerance: a pixel "differs" when any channel is off by more than 2/255; at
//! most 0.5% of the pixels may differ. Flat colours make every difference an
//! edge pixel that changed object, which is what a change in floating-point
//! rounding (another compiler, CPU or the f64 build) can do, and nothing more.
//!
//! Regenerate both references after an intended change in the picture:
//!
//! ```text
//! RT_BLESS=1 cargo test -p rt-view --test golden
//! ```

mod common;

use std::path::Path;

use common::{read_png, rt_view, scenes_dir, stderr};

const CHANNEL_TOLERANCE: i32 = 2;
const MAX_DIFFERING_FRACTION: f64 = 0.005;

#[test]
fn showcase_matches_the_reference_image() {
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/showcase_240x135.png");
    compare_showcase_render(&reference, &["--width", "240", "--height", "135"]);
}

/// The README's picture is what the README's command renders (the scene's own
/// size, 800×450), so the README stays true when the scene or renderer changes.
#[test]
fn readme_picture_is_the_current_showcase_render() {
    let picture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/showcase.png");
    compare_showcase_render(&picture, &[]);
}

/// Renders showcase.ron with `extra` arguments and compares the result with
/// `reference`, or overwrites `reference` when `RT_BLESS` is set.
fn compare_showcase_render(reference: &Path, extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("showcase.png");
    let scene = scenes_dir().join("showcase.ron");
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = rt_view(&args, "");
    assert!(o.status.success(), "{}", stderr(&o));
    if std::env::var_os("RT_BLESS").is_some() {
        std::fs::copy(&out, reference).unwrap();
        eprintln!("wrote {}", reference.display());
        return;
    }
    let (got, want) = (read_png(&out), read_png(reference));
    assert_eq!(got.dimensions(), want.dimensions());
    let differing = got
        .pixels()
        .zip(want.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(&x, y)| (x as i32 - y as i32).abs() > CHANNEL_TOLERANCE))
        .count();
    let fraction = differing as f64 / got.pixels().len() as f64;
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{differing} pixels ({:.2}%) differ from {}; if the change is intended, \
         regenerate with RT_BLESS=1 cargo test -p rt-view --test golden",
        100.0 * fraction,
        reference.display()
    );
}
