//! The viewer's window: start-up errors, a smoke test of the real window
//! under Xvfb that checks the screenshot shows the rendered scene, and the
//! state it remembers between runs.
//!
//! Every run keeps what it remembers in a folder of its test
//! (`RT_VIEW_CONFIG_DIR`), never in the user's.
//!
//! The smoke test needs `xvfb-run` (Debian: xvfb, xauth, and Mesa's GL
//! libraries; `.ci/run` installs them). Without it the test says so and
//! passes, unless `RT_REQUIRE_XVFB` is set, as CI sets it, where it fails.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::{read_png, scenes_dir, stderr};

fn rt_view_bin() -> &'static str {
    env!("CARGO_BIN_EXE_rt-view")
}

/// The viewer, remembering its state in `state` (a folder of the test's).
fn rt_view(state: &Path) -> Command {
    let mut command = Command::new(rt_view_bin());
    command.env("RT_VIEW_CONFIG_DIR", state);
    command
}

#[test]
fn the_viewer_refuses_a_bad_scene_before_opening_a_window() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.ron");
    std::fs::write(&scene, "Scene(camera: (").unwrap();
    let o =
        rt_view(dir.path()).arg(&scene).env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").output().unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).starts_with("error: ") && stderr(&o).contains("bad.ron:1:"), "{}", stderr(&o));
}

#[test]
fn without_a_display_the_viewer_fails_with_a_clear_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let o = rt_view(dir.path())
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.starts_with("error: cannot open the viewer window"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    // The reason, without the windowing library's source location (a path
    // into the build machine's cargo registry means nothing to a user).
    assert!(err.contains("DISPLAY is set"), "{err}");
    assert!(!err.contains(".rs:") && !err.contains("registry"), "{err}");
}

fn have_xvfb() -> bool {
    let found =
        Command::new("sh").args(["-c", "command -v xvfb-run"]).output().is_ok_and(|o| o.status.success());
    if !found {
        assert!(
            std::env::var_os("RT_REQUIRE_XVFB").is_none(),
            "RT_REQUIRE_XVFB is set but xvfb-run is not installed"
        );
        eprintln!("SKIPPED: xvfb-run is not installed (apt-get install xvfb xauth libgl1-mesa-dri ...)");
    }
    found
}

/// Opens the window under Xvfb in `cwd`, on `scene` (with `None`, the one it
/// remembers, or the built-in scene), remembering in `cwd/state`; returns
/// its screenshot and what it printed.
fn screenshot_and_output(scene: Option<&Path>, cwd: &Path) -> (image::RgbImage, Output) {
    let out = cwd.join("shot.png");
    let mut command = Command::new("xvfb-run");
    command.args(["-a", "-s", "-screen 0 1280x800x24"]).arg(rt_view_bin()).arg("--screenshot").arg(&out);
    command.args(scene).current_dir(cwd).env_remove("WAYLAND_DISPLAY");
    command.env("RT_VIEW_CONFIG_DIR", cwd.join("state"));
    let o = command.output().unwrap();
    assert!(o.status.success(), "viewer failed: {}\n{}", stderr(&o), String::from_utf8_lossy(&o.stdout));
    (read_png(&out), o)
}

/// [`screenshot_and_output`]'s screenshot.
fn screenshot(scene: Option<&Path>, cwd: &Path) -> image::RgbImage {
    screenshot_and_output(scene, cwd).0
}

/// Whether `pixel` is within 3 levels per channel of `rgb`.
fn near(pixel: &image::Rgb<u8>, rgb: [u8; 3]) -> bool {
    pixel.0.iter().zip(rgb).all(|(&a, b)| (a as i32 - b as i32).abs() <= 3)
}

/// Pixels within 3 levels per channel of `rgb`.
fn count_colour(img: &image::RgbImage, rgb: [u8; 3]) -> usize {
    img.pixels().filter(|p| near(p, rgb)).count()
}

#[test]
fn the_real_window_shows_the_rendered_scene() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let img = screenshot(Some(&scenes_dir().join("sphere.ron")), dir.path());
    let (w, h) = img.dimensions();
    assert!(w >= 640 && h >= 400, "screenshot {w}x{h}");
    // sphere.ron: the sphere's flat colour (0.9, 0.15, 0.1) → (230, 38, 26), the
    // background (0.05, 0.05, 0.1) → (13, 13, 26). The image fills most of the
    // central panel; the sphere covers about a fifth of the image.
    let sphere = count_colour(&img, [230, 38, 26]);
    let background = count_colour(&img, [13, 13, 26]);
    let total = (w * h) as usize;
    assert!(sphere > total / 40, "only {sphere} sphere pixels of {total}: the scene is not shown");
    assert!(background > total / 5, "only {background} background pixels of {total}");
    // The sphere is round and in the middle of the image: the widest run of
    // sphere pixels is on the row through its centre, well inside the window.
    let row_of_widest =
        (0..h).max_by_key(|&y| (0..w).filter(|&x| near(img.get_pixel(x, y), [230, 38, 26])).count()).unwrap();
    assert!(row_of_widest > h / 4 && row_of_widest < 3 * h / 4, "sphere centre row {row_of_widest} of {h}");
}

#[test]
fn the_built_in_default_scene_opens_without_a_scene_file() {
    if !have_xvfb() {
        return;
    }
    // Run where there is no scenes/ folder: the scene must be built in.
    let dir = tempfile::tempdir().unwrap();
    let img = screenshot(None, dir.path());
    // default.ron's red sphere (0.85, 0.18, 0.15) → (217, 46, 38).
    assert!(count_colour(&img, [217, 46, 38]) > 1000, "the default scene's red sphere is missing");
}

#[test]
fn started_again_without_a_scene_the_window_shows_the_last_one_and_survives_a_broken_state() {
    if !have_xvfb() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let sphere_red = [230, 38, 26]; // sphere.ron's sphere
    let default_red = [217, 46, 38]; // default.ron's sphere
    let first = screenshot(Some(&scenes_dir().join("sphere.ron")), dir.path());
    let state = dir.path().join("state/app.ron");
    let saved = std::fs::read_to_string(&state).expect("the state is saved where RT_VIEW_CONFIG_DIR says");
    assert!(saved.contains("sphere.ron") && saved.contains("window"), "{saved}");

    let (again, o) = screenshot_and_output(None, dir.path());
    assert_eq!(again.dimensions(), first.dimensions());
    let total = (again.width() * again.height()) as usize;
    assert!(count_colour(&again, sphere_red) > total / 40, "the last scene did not come back");
    assert!(count_colour(&again, default_red) < 100, "the built-in scene is shown");
    assert!(!stderr(&o).contains("warning"), "{}", stderr(&o));

    // A state that cannot be read (the viewer's entry, or the whole file):
    // one warning, and the built-in scene.
    for broken in ["{\"app\": \"(show_panel: maybe\"}", "{\"app\": "] {
        std::fs::write(&state, broken).unwrap();
        let (fresh, o) = screenshot_and_output(None, dir.path());
        let err = stderr(&o);
        assert_eq!(err.lines().filter(|l| l.starts_with("warning: ")).count(), 1, "{broken}: {err}");
        assert!(err.contains("app.ron: forgot the viewer's remembered state"), "{err}");
        assert!(count_colour(&fresh, default_red) > 1000, "{broken}: the built-in scene is not shown");
    }
}
