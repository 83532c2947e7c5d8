//! The showcase scene rendered by the CLI, compared with a committed reference.
//!
//! Tolerance: a pixel "differs" when any channel is off by more than 2/255; at
//! most 0.5% of the pixels may differ. Flat colours make every difference an
//! edge pixel that changed object, which is what a change in floating-point
//! rounding (another compiler, CPU or the f64 build) can do, and nothing more.
//!
//! Regenerate the reference after an intended change in the picture:
//!
//! ```text
//! RT_BLESS=1 cargo test -p rt-view --test golden
//! ```

mod common;

use std::path::Path;

use common::{read_png, rt_view, scenes_dir, stderr};

const WIDTH: u32 = 240;
const HEIGHT: u32 = 135;
const CHANNEL_TOLERANCE: i32 = 2;
const MAX_DIFFERING_FRACTION: f64 = 0.005;

#[test]
fn showcase_matches_the_reference_image() {
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/showcase_240x135.png");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("showcase.png");
    let scene = scenes_dir().join("showcase.ron");
    let o = rt_view(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            &WIDTH.to_string(),
            "--height",
            &HEIGHT.to_string(),
        ],
        "",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    if std::env::var_os("RT_BLESS").is_some() {
        std::fs::copy(&out, &reference).unwrap();
        eprintln!("wrote {}", reference.display());
        return;
    }
    let (got, want) = (read_png(&out), read_png(&reference));
    assert_eq!(got.dimensions(), want.dimensions());
    let differing = got
        .pixels()
        .zip(want.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(&x, y)| (x as i32 - y as i32).abs() > CHANNEL_TOLERANCE))
        .count();
    let fraction = differing as f64 / (WIDTH * HEIGHT) as f64;
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{differing} pixels ({:.2}%) differ from {}; if the change is intended, \
         regenerate with RT_BLESS=1 cargo test -p rt-view --test golden",
        100.0 * fraction,
        reference.display()
    );
}
