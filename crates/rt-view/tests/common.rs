//! Helpers shared by the CLI integration tests.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The repository's `scenes/` folder.
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// Runs `rt-view` with `args`, feeding `stdin`.
pub fn rt_view(args: &[&str], stdin: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_rt-view"))
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("rt-view starts");
    child.stdin.take().unwrap().write_all(stdin.as_bytes()).unwrap();
    child.wait_with_output().unwrap()
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Standard output as text.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// Reads an 8-bit RGB PNG.
pub fn read_png(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8()
}

/// Whether every program in `names` is installed (the window tests need
/// an X server and more). When one is missing the test says so and skips,
/// unless `RT_REQUIRE_XVFB` is set, as CI sets it: then it fails.
pub fn have_programs(names: &[&str]) -> bool {
    let missing: Vec<&str> = names
        .iter()
        .copied()
        .filter(|name| {
            let found = Command::new("sh").args(["-c", &format!("command -v {name}")]).output();
            !found.is_ok_and(|o| o.status.success())
        })
        .collect();
    if missing.is_empty() {
        return true;
    }
    assert!(
        std::env::var_os("RT_REQUIRE_XVFB").is_none(),
        "RT_REQUIRE_XVFB is set but {} not installed",
        missing.join(", ")
    );
    eprintln!(
        "SKIPPED: {} not installed (apt-get install xvfb xdotool libgl1-mesa-dri ...)",
        missing.join(", ")
    );
    false
}
