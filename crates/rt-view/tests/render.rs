//! `rt-view render`: output, options, and refusal of bad input without writing anything.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use common::{read_png, rt_view, scenes_dir, stderr};

#[test]
fn render_writes_a_png_of_the_requested_size_showing_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("sphere.png");
    let scene = scenes_dir().join("sphere.ron");
    let o = rt_view(
        &["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "64", "--height", "48"],
        "",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let img = read_png(&out);
    assert_eq!(img.dimensions(), (64, 48));
    // Centre: the sphere's colour (0.9, 0.15, 0.1); corner: the background (0.05, 0.05, 0.1).
    assert_eq!(img.get_pixel(32, 24).0, [230, 38, 26]);
    assert_eq!(img.get_pixel(0, 0).0, [13, 13, 26]);
    // Nothing else is left in the directory (no temporary file).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    // The image is readable by others like any new file, not private like a temporary one.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let mode = std::fs::metadata(&out).unwrap().permissions().mode();
        assert_ne!(mode & 0o077, 0, "mode {mode:o}: private temporary-file permissions leaked");
    }
}

#[test]
fn render_takes_the_size_from_the_scene_by_default_and_spp_from_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("aa.png");
    let scene = scenes_dir().join("sphere.ron");
    let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--spp", "4"], "");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("320x240, 4 spp"), "{}", stderr(&o));
    let img = read_png(&out);
    assert_eq!(img.dimensions(), (320, 240));
    // Anti-aliased edge pixels mix sphere red and background.
    assert!(img.pixels().any(|p| p.0[0] > 13 && p.0[0] < 230), "no blended edge pixels");
}

/// A valid scene with one line replaced.
fn broken_scene(from: &str, to: &str) -> String {
    let good = std::fs::read_to_string(scenes_dir().join("sphere.ron")).unwrap();
    assert!(good.contains(from), "{from}");
    good.replacen(from, to, 1)
}

#[test]
fn every_bad_scene_is_refused_with_file_line_and_reason_and_writes_nothing() {
    let cases: &[(&str, String, &str)] = &[
        ("syntax", broken_scene("radius: 1.2,", "radius: 1.2,,"), "bad.ron:17:47: Expected identifier"),
        (
            "unknown field",
            broken_scene("radius: 1.2,", "radius: 1.2, colour: 1,"),
            "Unexpected field named `colour`",
        ),
        (
            "missing material",
            broken_scene("material: \"red\"", "material: \"blue\""),
            "objects[0] (Sphere): unknown material \"blue\"",
        ),
        ("NaN", broken_scene("fov_y: 40", "fov_y: NaN"), "expected a finite number, found NaN"),
        ("infinity", broken_scene("radius: 1.2", "radius: inf"), "expected a finite number, found inf"),
        ("negative radius", broken_scene("radius: 1.2", "radius: -1.2"), "sphere radius must be positive"),
        ("up parallel", broken_scene("up: (0, 1, 0)", "up: (0, 0, 1)"), "camera.up is zero or parallel"),
        (
            "C == COI",
            broken_scene("position: (0, 0, -5)", "position: (0, 0, 0)"),
            "coincides with camera.position",
        ),
        (
            "fov 180",
            broken_scene("fov_y: 40", "fov_y: 180"),
            "camera.fov_y must be strictly between 0 and 180",
        ),
        ("near 0", broken_scene("near: 1", "near: 0"), "camera.near must be a positive finite number"),
        (
            "bent polygon",
            broken_scene(
                "Sphere(center: (0, 0, 0), radius: 1.2, material: \"red\")",
                "Polygon(points: [(0,0,0), (1,0,0), (1,1,1), (0,1,0)], material: \"red\")",
            ),
            "polygon is not planar",
        ),
        (
            "degenerate polygon",
            broken_scene(
                "Sphere(center: (0, 0, 0), radius: 1.2, material: \"red\")",
                "Polygon(points: [(0,0,0), (1,1,1), (2,2,2)], material: \"red\")",
            ),
            "polygon has zero area",
        ),
        (
            "missing OBJ",
            broken_scene(
                "Sphere(center: (0, 0, 0), radius: 1.2, material: \"red\")",
                "Mesh(file: \"no/such.obj\", material: \"red\")",
            ),
            "objects[0] (Mesh): cannot open OBJ file",
        ),
    ];
    for (name, text, expected) in cases {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("bad.ron");
        std::fs::write(&scene, text).unwrap();
        let out = dir.path().join("out.png");
        let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.starts_with("error: ") && err.contains("bad.ron") && err.contains(expected),
            "{name}: {err}"
        );
        assert!(!err.contains("panicked"), "{name}: {err}");
        // Nothing written: only the scene file is in the directory.
        assert!(!out.exists(), "{name}: output written");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "{name}: stray files");
    }
}

#[test]
fn a_failed_render_leaves_an_existing_output_untouched() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("bad.ron");
    std::fs::write(&scene, broken_scene("radius: 1.2", "radius: -1")).unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"precious").unwrap();
    let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(!o.status.success());
    assert_eq!(std::fs::read(&out).unwrap(), b"precious");
}

#[test]
fn missing_scene_files_and_bad_outputs_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let o = rt_view(&["render", "/no/such/scene.ron", "-o", out.to_str().unwrap()], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("/no/such/scene.ron: cannot read scene file"), "{}", stderr(&o));

    let scene = scenes_dir().join("sphere.ron");
    let o = rt_view(&["render", scene.to_str().unwrap(), "-o", "/no/such/dir/x.png"], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot write to directory /no/such/dir"), "{}", stderr(&o));

    let o =
        rt_view(&["render", scene.to_str().unwrap(), "-o", dir.path().join("x.jpg").to_str().unwrap()], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("output must be a .png or .exr file"), "{}", stderr(&o));
}

#[test]
fn out_of_range_sizes_and_sample_counts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let scene = scenes_dir().join("sphere.ron");
    for (flag, value, expected) in [
        ("--width", "0", "image size 0x240 is out of range"),
        ("--height", "100000", "image size 320x100000 is out of range"),
        ("--spp", "0", "samples per pixel must be 1 to"),
    ] {
        let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), flag, value], "");
        assert_eq!(o.status.code(), Some(1), "{flag} {value}");
        assert!(stderr(&o).contains(expected), "{flag} {value}: {}", stderr(&o));
        assert!(!out.exists());
    }
}

/// Starts a render of showcase.ron at 4000×3000, 16 spp (many seconds) to `out`.
fn spawn_long_render(out: &std::path::Path) -> std::process::Child {
    let scene = scenes_dir().join("showcase.ron");
    std::process::Command::new(env!("CARGO_BIN_EXE_rt-view"))
        .args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .args(["--width", "4000", "--height", "3000", "--spp", "16"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap()
}

/// Starts `rt-view render` of sphere.ron (flat colours: quick to trace) at
/// `width`×`height` to `out`; a large EXR takes measurable time to encode and
/// write.
fn spawn_render(out: &Path, width: u32, height: u32) -> std::process::Child {
    let scene = scenes_dir().join("sphere.ron");
    std::process::Command::new(env!("CARGO_BIN_EXE_rt-view"))
        .args(["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .args(["--width", &width.to_string(), "--height", &height.to_string(), "--spp", "1"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// The names in `dir` of temporary files (`.NAME.rt-view-PID-XXXXXX.tmp`)
/// with their writers' pids and sizes.
fn temp_files(dir: &Path) -> Vec<(String, u32, u64)> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let e = e.ok()?;
            let name = e.file_name().into_string().ok()?;
            let pid = rt_view::image_out::temp_file_writer(&name)?;
            Some((name, pid, e.metadata().ok()?.len()))
        })
        .collect()
}

/// The names of the files in `dir`, sorted.
fn names(dir: &Path) -> Vec<String> {
    let mut n: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    n.sort();
    n
}

/// Polls `dir` every millisecond until `child` has written bytes into its
/// temporary file (its write phase began: `true`) or has exited (`false`).
fn wait_for_write_phase(child: &mut std::process::Child, dir: &Path) -> bool {
    loop {
        if temp_files(dir).iter().any(|(_, pid, size)| *pid == child.id() && *size > 0) {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// SIGKILL cannot be caught: a render killed while it writes leaves its
/// temporary file. What must hold whenever it is killed: the old output is
/// untouched (or, killed after the rename, the complete new one is there),
/// nothing but temporary files of killed writers is left, and the next write
/// to the directory removes them. Ten kills: six at delays spread over a
/// whole run (tracing about 60 %, writing 40 % of it, measured first), four
/// at delays spread over the write phase once the temporary file is seen to
/// grow (polled every millisecond), so that some land mid-write whatever the
/// machine's speed. About 3 s.
#[test]
fn a_render_killed_at_any_moment_keeps_the_old_output_and_the_next_write_removes_its_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    let (width, height) = (1600, 1200);
    // A whole run, timed: tracing, then the write phase (the temporary file
    // growing, synced, renamed).
    let reference = dir.path().join("reference.exr");
    let start = Instant::now();
    let mut child = spawn_render(&reference, width, height);
    assert!(wait_for_write_phase(&mut child, dir.path()), "no temporary file seen");
    let trace = start.elapsed();
    assert!(child.wait().unwrap().success());
    let write = start.elapsed() - trace;
    let full = std::fs::read(&reference).unwrap();
    eprintln!("tracing {trace:?}, writing {write:?} ({} bytes)", full.len());

    let out = dir.path().join("out.exr");
    std::fs::write(&out, b"previous image").unwrap();
    // The EXR encoder compresses blocks in parallel and writes them in the
    // order they finish (line order "random"), so a complete image is told
    // by its pixels, not its bytes.
    let pixels = |bytes: &[u8]| image::load_from_memory(bytes).ok().map(|i| i.to_rgb32f().into_raw());
    let full_pixels = pixels(&full).expect("the reference decodes");
    let old_output = |what: &str| {
        // The old output, or (killed after the rename) the complete new one.
        let now = std::fs::read(&out).unwrap_or_else(|e| panic!("{what}: the output is gone: {e}"));
        let complete = now == full || pixels(&now).is_some_and(|p| p == full_pixels);
        assert!(now == b"previous image" || complete, "{what}: the output is neither old nor complete");
        std::fs::write(&out, b"previous image").unwrap();
    };
    let mut killed = Vec::new();
    let mut left_mid_write = 0;
    // Kills at delays spread over the whole run, then at delays spread over
    // the write phase once it is seen to have begun.
    let run = trace + write;
    let at_times = (0..6).map(|i| (false, run * (2 * i + 1) / 12));
    let in_write = (0..4).map(|j| (true, write * j / 4));
    for (after_write_began, delay) in at_times.chain(in_write) {
        let mut child = spawn_render(&out, width, height);
        let writing = after_write_began && wait_for_write_phase(&mut child, dir.path());
        std::thread::sleep(delay);
        child.kill().unwrap(); // SIGKILL: nothing can clean up.
        child.wait().unwrap();
        killed.push(child.id());
        let what =
            format!("killed {delay:?} after {}", if writing { "the write began" } else { "the start" });
        old_output(&what);
        let temps = temp_files(dir.path());
        // Only temporary files of killed writers are left, named for the output.
        for (name, pid, _) in &temps {
            assert!(killed.contains(pid) && name.starts_with(".out.exr.rt-view-"), "{what}: {name}");
        }
        assert_eq!(names(dir.path()).len(), 2 + temps.len(), "{what}: {:?}", names(dir.path()));
        if writing {
            // Its own write removed the temporary files of those killed before.
            assert!(temps.iter().all(|(_, pid, _)| *pid == child.id()), "{what}: {temps:?}");
            left_mid_write += temps.len();
        }
    }
    assert!(left_mid_write > 0, "no kill landed in the write phase (write {write:?})");
    eprintln!(
        "{} kills, {left_mid_write} of those after the write began left a temporary file",
        killed.len()
    );
    // The next render to the same output replaces it and removes what the
    // killed ones left.
    let mut child = spawn_render(&out, 64, 48);
    assert!(child.wait().unwrap().success());
    assert_eq!(names(dir.path()), ["out.exr", "reference.exr"]);
    assert_eq!(image::open(&out).unwrap().to_rgb32f().dimensions(), (64, 48));
}

#[test]
fn a_write_never_removes_a_live_writers_temporary_file() {
    let dir = tempfile::tempdir().unwrap();
    // This test's process is alive; a process that has been waited for is not.
    let live = format!(".out.png.rt-view-{}-abc123.tmp", std::process::id());
    let mut gone = std::process::Command::new(env!("CARGO_BIN_EXE_rt-view"))
        .args(["cast", "/no/such/scene.ron"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    gone.wait().unwrap();
    let stale = format!(".out.png.rt-view-{}-abc123.tmp", gone.id());
    let unrelated = ".out.png.tmp";
    for name in [&live, &stale, unrelated] {
        std::fs::write(dir.path().join(name), b"half an image").unwrap();
    }
    let out = dir.path().join("out.png");
    let scene = scenes_dir().join("sphere.ron");
    let args =
        ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "8", "--height", "6"];
    let o = rt_view(&args, "");
    assert!(o.status.success(), "{}", stderr(&o));
    let mut want = vec![live, unrelated.to_owned(), "out.png".to_owned()];
    if !cfg!(target_os = "linux") {
        want.push(stale); // Elsewhere only an age limit tells a stale file.
    }
    want.sort();
    assert_eq!(names(dir.path()), want);
}

#[test]
fn ctrl_c_stops_a_render_cleanly_and_keeps_the_old_output() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"previous image").unwrap();
    let child = spawn_long_render(&out);
    std::thread::sleep(std::time::Duration::from_millis(500));
    // SAFETY: `kill` only sends a signal; the child is ours and still running
    // (it is waited for below, so its pid cannot have been reused).
    let sent = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    assert_eq!(sent, 0, "kill: {}", std::io::Error::last_os_error());
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(130), "{}", stderr(&o));
    assert!(stderr(&o).contains("error: interrupted: nothing was written"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap(), b"previous image");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1, "stray files");
}

#[test]
fn stats_report_load_bvh_and_tracing_separately() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.png");
    let scene = scenes_dir().join("mesh.ron");
    let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--stats"], "");
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    // mesh.ron: the icosphere (320 triangles) and the torus (288 quads → 576 triangles).
    assert!(err.contains("BVH: 896 primitives,"), "{err}");
    assert!(err.contains("scene load: ") && err.contains("(of which BVH build "), "{err}");
    let steps = err.lines().find_map(|l| l.strip_prefix("BVH build steps: ")).expect("build steps line");
    assert!(steps.starts_with("items ") && steps.contains(", collapse with the leaves "), "{steps}");
    // No lights: pure ray casting, one primary ray per pixel (320×240) and nothing else.
    assert!(err.contains("effects: none (no lights"), "{err}");
    assert!(
        err.contains("rays: primary 76800, shadow 0, reflection 0, refraction 0, ambient occlusion 0"),
        "{err}"
    );
    let mrays = err.lines().find_map(|l| l.strip_prefix("tracing: ")).expect("tracing line");
    let value: f64 = mrays.split(" Mrays/s").next().unwrap().rsplit(' ').next().unwrap().parse().unwrap();
    assert!(value > 0.0 && value.is_finite(), "{mrays}");
}

#[test]
fn stats_count_every_kind_of_ray_a_lit_scene_asks_for() {
    let err = stats_of("effects", 64, 36, 2);
    assert!(
        err.contains("effects: shading, shadows, reflection, refraction, max depth 5, ambient occlusion (4 samples, radius 1)"),
        "{err}"
    );
    let count = |kind: &str| ray_count(&err, kind);
    assert_eq!(count("primary "), 64 * 36 * 2);
    for kind in ["shadow ", "reflection ", "refraction ", "ambient occlusion "] {
        assert!(count(kind) > 0, "{kind}: {err}");
    }
}

#[test]
fn an_exr_output_holds_the_linear_colours_unclamped() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("shadows.ron");
    let (png, exr) = (dir.path().join("s.png"), dir.path().join("s.exr"));
    for out in [&png, &exr] {
        let o = rt_view(
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--width",
                "80",
                "--height",
                "45",
            ],
            "",
        );
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let linear = image::open(&exr).unwrap().to_rgb32f();
    let encoded = read_png(&png);
    assert_eq!(linear.dimensions(), (80, 45));
    // The PNG is the EXR's linear values clamped and sRGB-encoded.
    let srgb = |v: f32| {
        let v = v.clamp(0.0, 1.0);
        let e = if v <= 0.0031308 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
        (e * 255.0 + 0.5) as u8
    };
    for (l, e) in linear.pixels().zip(encoded.pixels()) {
        assert_eq!(l.0.map(srgb), e.0);
    }
    // The lit floor near the point light is brighter than 1: HDR survives.
    assert!(linear.pixels().any(|p| p.0[0] > 1.0), "no value above 1");
}

#[test]
fn bench_runs_and_writes_meshes_cameras_and_csv() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench-out");
    let showcase = scenes_dir().join("showcase.ron");
    let args = ["bench", "--quick", "--runs", "1", "--threads", "1", "--out", out.to_str().unwrap()];
    let o = rt_view(&[&args[..], &["--showcase", showcase.to_str().unwrap()]].concat(), "");
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("Mrays/s") && table.contains("full render"), "{table}");
    for file in ["terrain_10k.obj", "terrain_10k.json", "terrain_10k.bounce", "terrain_100k.obj", "bench.csv"]
    {
        assert!(out.join(file).exists(), "{file} missing");
    }
    let csv = std::fs::read_to_string(out.join("bench.csv")).unwrap();
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(
        rows[0],
        "mesh,triangles,threads,bvh_build_s,sah_cost,bytes_per_triangle,primary_packets_mrays_per_s,\
         primary_single_mrays_per_s,bounce_mrays_per_s,hits,bounce_hits,peak_rss_mib"
    );
    assert_eq!(rows.len(), 3, "{csv}");
    assert!(rows[1].starts_with("10k,10082,1,") && rows[2].starts_with("100k,100352,1,"), "{csv}");
    // One bounce ray (28 bytes) from every primary hit, and some of them hit.
    let fields: Vec<&str> = rows[1].split(',').collect();
    let (hits, bounce_hits): (u64, u64) = (fields[9].parse().unwrap(), fields[10].parse().unwrap());
    assert_eq!(std::fs::metadata(out.join("terrain_10k.bounce")).unwrap().len(), 28 * hits);
    assert!(bounce_hits > 0 && bounce_hits < hits, "{csv}");
}

#[test]
fn stats_count_bounce_and_next_event_rays_under_global_illumination_and_nothing_else() {
    let err = stats_of("cornell_box", 32, 32, 4);
    assert!(
        err.contains("effects: global illumination (path tracing, at most 8 bounces, Russian roulette)"),
        "{err}"
    );
    let count = |kind: &str| ray_count(&err, kind);
    assert_eq!(count("primary "), 32 * 32 * 4);
    for kind in ["shadow ", "reflection ", "refraction ", "ambient occlusion "] {
        assert_eq!(count(kind), 0, "{kind}: {err}");
    }
    assert!(count("bounce ") > 0 && count("next event ") > 0, "{err}");
    assert_eq!((count("subsurface "), walk_steps(&err)), (0, 0), "{err}");
}

#[test]
fn stats_count_subsurface_rays_and_walk_steps_where_a_material_is_translucent() {
    let err = stats_of("subsurface", 32, 24, 2);
    assert!(err.contains("subsurface random walks of at most 4096 steps"), "{err}");
    assert_eq!(ray_count(&err, "primary "), 32 * 24 * 2);
    assert!(ray_count(&err, "subsurface ") > 0 && walk_steps(&err) > 0, "{err}");
}

#[test]
fn models_with_their_own_materials_render_say_what_they_leave_out_and_count_their_size() {
    let err = stats_of("models", 40, 24, 1);
    // The vase's MTL file has an ambient colour, which the model does not use.
    assert!(
        err.contains("warning: ") && err.contains("models/vase.obj: material \"glaze\": not used: Ka"),
        "{err}"
    );
    let meshes = err.lines().find(|l| l.starts_with("meshes: ")).expect("a meshes line");
    // Two vase parts and three still-life parts; all but the gem smooth.
    assert!(meshes.starts_with("meshes: 5 (4 with vertex normals, 3 with texture coordinates)"), "{meshes}");
    assert!(meshes.contains("bytes per triangle") && meshes.contains("textures: 2"), "{meshes}");
}

/// The walk steps in `--stats` output.
fn walk_steps(stats: &str) -> u64 {
    let counts = stats.lines().find_map(|l| l.strip_prefix("rays: ")).expect("rays line");
    let steps = counts.split("(walk steps ").nth(1).expect("walk steps");
    steps.trim_end_matches(')').parse().unwrap()
}

/// `render --stats` of scenes/`name`.ron at `width`×`height` and `spp`: its stderr.
fn stats_of(name: &str, width: u32, height: u32, spp: u32) -> String {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.png");
    let scene = scenes_dir().join(format!("{name}.ron"));
    let (w, h, n) = (width.to_string(), height.to_string(), spp.to_string());
    let args =
        ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", &w, "--height", &h];
    let o = rt_view(&[&args[..], &["--spp", &n, "--stats"]].concat(), "");
    assert!(o.status.success(), "{}", stderr(&o));
    stderr(&o)
}

/// The count of rays of `kind` ("primary ", "bounce ", …) in `--stats` output.
fn ray_count(stats: &str, kind: &str) -> u64 {
    let counts = stats.lines().find_map(|l| l.strip_prefix("rays: ")).expect("rays line");
    let count = counts.split(", ").find_map(|c| c.strip_prefix(kind)).unwrap();
    count.split_whitespace().next().unwrap().parse().unwrap()
}

#[test]
fn a_global_illumination_scene_with_nothing_that_glows_says_why_it_is_black() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("dark.ron");
    std::fs::write(
        &scene,
        r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 8, height: 6),
        materials: { "m": (color: (0.5, 0.5, 0.5)) },
        objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
        effects: (global_illumination: ()),
    )"#,
    )
    .unwrap();
    let out = dir.path().join("dark.png");
    let o = rt_view(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--stats"], "");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("note: nothing gives off light"), "{}", stderr(&o));
    assert!(read_png(&out).pixels().all(|p| p.0 == [0, 0, 0]));
}

#[test]
fn seeds_give_independent_images_and_seed_zero_is_the_default() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("cornell_box.ron");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let args = [
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            "24",
            "--height",
            "24",
            "--spp",
            "2",
        ];
        let o = rt_view(&[&args[..], extra].concat(), "");
        assert!(o.status.success(), "{}", stderr(&o));
        read_png(&out)
    };
    let default = render("a.png", &[]);
    assert_eq!(default, render("b.png", &["--seed", "0"]));
    assert_ne!(default, render("c.png", &["--seed", "1"]));
}

#[test]
fn exposure_and_view_transform_change_the_png_and_leave_the_exr_linear() {
    // sphere.ron's centre pixel is (0.9, 0.15, 0.1), encoded linearly as
    // (230, 38, 26). One stop down halves it; AgX maps it through its curve
    // (sRGB-encoded); the EXR holds the linear colour whatever the flags.
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("sphere.ron");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--width",
            "64",
            "--height",
            "48",
        ];
        args.extend_from_slice(extra);
        let o = rt_view(&args, "");
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let plain = read_png(&render("plain.png", &[]));
    let same = read_png(&render("same.png", &["--exposure", "0", "--view-transform", "standard"]));
    assert_eq!(plain, same, "exposure 0 with the standard transform is the plain encoding");
    let darker = read_png(&render("darker.png", &["--exposure", "-1"]));
    assert_eq!(darker.get_pixel(32, 24).0, [115, 19, 13]);
    let agx = read_png(&render("agx.png", &["--view-transform", "agx"]));
    let expected = rt_core::render::view_transform::Display {
        exposure: 0.0,
        view_transform: rt_core::render::view_transform::ViewTransform::AgX,
    }
    .encode(rt_core::Color::new(0.9, 0.15, 0.1), rt_core::math::color::ColorSpace::Linear);
    assert_eq!(agx.get_pixel(32, 24).0, expected);
    assert_ne!(expected, [230, 38, 26]);
    let exr_plain = std::fs::read(render("plain.exr", &[])).unwrap();
    let exr_flags =
        std::fs::read(render("flags.exr", &["--exposure", "3", "--view-transform", "agx"])).unwrap();
    assert_eq!(exr_plain, exr_flags, "EXR is scene-referred");
}

#[test]
fn a_bad_exposure_or_view_transform_is_refused_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let scene = scenes_dir().join("sphere.ron");
    for (flags, says) in
        [(["--exposure", "100"], "--exposure must be"), (["--view-transform", "filmic"], "standard or agx")]
    {
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend_from_slice(&flags);
        let o = rt_view(&args, "");
        assert!(!o.status.success() && stderr(&o).contains(says), "{flags:?}: {}", stderr(&o));
        assert!(!out.exists());
    }
}

#[test]
fn the_environment_scenes_render_and_a_missing_map_is_an_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["studio", "outdoor", "depth_of_field"] {
        let out = dir.path().join(format!("{name}.png"));
        let scene = scenes_dir().join(format!("{name}.ron"));
        let o = rt_view(
            &[
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--width",
                "32",
                "--height",
                "20",
                "--spp",
                "2",
            ],
            "",
        );
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        // Lit: not a black image.
        assert!(read_png(&out).pixels().any(|p| p.0.iter().any(|&c| c > 40)), "{name} is dark");
    }
    let text = std::fs::read_to_string(scenes_dir().join("depth_of_field.ron")).unwrap();
    let bad = dir.path().join("bad.ron");
    std::fs::write(&bad, text.replace("studio.hdr", "gone.hdr")).unwrap();
    let out = dir.path().join("bad.png");
    let o = rt_view(&["render", bad.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(
        !o.status.success() && stderr(&o).contains("gone.hdr") && stderr(&o).contains("cannot read"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

#[test]
fn the_sobol_sampler_and_adaptive_sampling_are_chosen_on_the_command_line_and_reported_by_stats() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("cornell_box.ron");
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
        args.extend(["--width", "32", "--height", "32", "--spp", "32", "--stats"]);
        args.extend(extra);
        let o = rt_view(&args, "");
        (o.status.success(), stderr(&o), out)
    };
    let (ok, _, stratified) = render("stratified.png", &[]);
    assert!(ok);
    let (ok, err, sobol) = render("sobol.png", &["--sampler", "sobol"]);
    assert!(ok, "{err}");
    assert_ne!(read_png(&stratified), read_png(&sobol));
    let (ok, err, _) = render("adaptive.png", &["--noise-threshold", "0.1", "--min-samples", "8"]);
    assert!(ok, "{err}");
    assert!(
        err.contains("adaptive sampling (noise threshold 0.1, at least 8 samples, 2 passes):")
            && err.contains("of 32768 samples taken")
            && err.contains("% saved"),
        "{err}"
    );
    let (ok, err, out) = render("refused.png", &["--min-samples", "8"]);
    assert!(!ok && err.contains("a minimum sample count needs a noise threshold"), "{err}");
    assert!(!out.exists());
    let (ok, err, _) = render("refused.png", &["--sampler", "halton"]);
    assert!(!ok && err.contains("unknown sampler \"halton\": stratified or sobol"), "{err}");
}
