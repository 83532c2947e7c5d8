//! A render split into parts (`render --part K/N`) and merged (`merge`):
//! the merged image is `render`'s, bit for bit, for sample ranges and for
//! tiles; missing, doubled, foreign, killed, truncated and damaged parts
//! are refused with a message that names them, never a panic.

mod common;

use std::path::Path;
use std::process::Output;

use common::{rt_view, scenes_dir, stderr};

/// A small global-illumination scene (the Cornell box: every pixel lit by
/// paths), at a size and sample count that render in a moment.
const SIZE: [&str; 6] = ["--width", "16", "--height", "12", "--spp", "14"];

fn cornell() -> String {
    scenes_dir().join("cornell_box.ron").display().to_string()
}

fn run(args: &[&str]) -> Output {
    rt_view(args, "")
}

fn ok(args: &[&str]) -> Output {
    let o = run(args);
    assert!(o.status.success(), "rt-view {}: {}", args.join(" "), stderr(&o));
    o
}

/// Fails with exit status 1 (an error, not a panic's 101) and says `message`.
fn fails(args: &[&str], message: &str) -> String {
    let o = run(args);
    assert_eq!(o.status.code(), Some(1), "rt-view {}: {}", args.join(" "), stderr(&o));
    let e = stderr(&o);
    assert!(e.contains(message), "rt-view {}: wanted {message:?} in: {e}", args.join(" "));
    e
}

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

/// Renders parts `indices` of `count` of `scene` into `dir` (`extra`
/// arguments besides the size), returning their paths.
fn parts(dir: &Path, scene: &str, count: u32, indices: &[u32], extra: &[&str]) -> Vec<String> {
    indices
        .iter()
        .map(|k| {
            let out = path(dir, &format!("part{k}of{count}.rtpart"));
            let part = format!("{k}/{count}");
            let mut args = vec!["render", scene, "--part", &part, "-o", &out];
            args.extend_from_slice(&SIZE);
            args.extend_from_slice(extra);
            ok(&args);
            out
        })
        .collect()
}

fn merge(parts: &[String], out: &str, extra: &[&str]) -> Output {
    let mut args = vec!["merge"];
    args.extend(parts.iter().map(String::as_str));
    args.extend_from_slice(&["-o", out]);
    args.extend_from_slice(extra);
    run(&args)
}

/// The linear pixels of an EXR, as bits.
fn exr_bits(path: &str) -> Vec<u32> {
    let image = image::open(path).unwrap_or_else(|e| panic!("{path}: {e}")).to_rgb32f();
    image.into_raw().iter().map(|v| v.to_bits()).collect()
}

fn one_machine_render(dir: &Path, extra: &[&str]) -> String {
    let out = path(dir, "whole.exr");
    let mut args = vec!["render".to_owned(), cornell(), "-o".into(), out.clone()];
    args.extend(SIZE.iter().chain(extra).map(|s| s.to_string()));
    ok(&args.iter().map(String::as_str).collect::<Vec<_>>());
    out
}

#[test]
fn sample_range_parts_merge_into_the_one_machine_render_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let whole = exr_bits(&one_machine_render(dir.path(), &[]));
    for count in [1, 2, 4, 7] {
        let indices: Vec<u32> = (0..count).rev().collect();
        let files = parts(dir.path(), &cornell(), count, &indices, &[]);
        let out = path(dir.path(), &format!("merged{count}.exr"));
        let o = merge(&files, &out, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains(&format!("merged {count} of {count} parts (sample ranges)")),
            "{}",
            stderr(&o)
        );
        assert_eq!(exr_bits(&out), whole, "{count} parts");
    }
}

#[test]
fn tile_parts_merge_into_the_one_machine_render_bit_for_bit_and_as_png_too() {
    let dir = tempfile::tempdir().unwrap();
    let whole = one_machine_render(dir.path(), &["--seed", "3"]);
    for count in [1, 3, 12] {
        let indices: Vec<u32> = (0..count).collect();
        let files = parts(dir.path(), &cornell(), count, &indices, &["--tiles", "--seed", "3"]);
        let out = path(dir.path(), &format!("tiles{count}.exr"));
        assert!(merge(&files, &out, &[]).status.success());
        assert_eq!(exr_bits(&out), exr_bits(&whole), "{count} tiles");
    }
    // The PNG: exposed and encoded as `render` writes it.
    let (c, png) = (cornell(), path(dir.path(), "whole.png"));
    let mut args = vec!["render", &c, "-o", &png, "--seed", "3", "--exposure", "1"];
    args.extend_from_slice(&SIZE);
    ok(&args);
    let files = parts(dir.path(), &cornell(), 3, &[0, 1, 2], &["--tiles", "--seed", "3", "--exposure", "1"]);
    let merged = path(dir.path(), "merged.png");
    assert!(merge(&files, &merged, &[]).status.success());
    assert_eq!(std::fs::read(&merged).unwrap(), std::fs::read(&png).unwrap());
}

#[test]
fn missing_parts_are_named_and_partial_merges_what_is_there() {
    let dir = tempfile::tempdir().unwrap();
    let files = parts(dir.path(), &cornell(), 4, &[0, 3], &[]);
    let out = path(dir.path(), "out.exr");
    let o = merge(&files, &out, &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing parts 1,2 of 4 (sample ranges)"), "{}", stderr(&o));
    assert!(stderr(&o).contains("--array=1,2"), "{}", stderr(&o));
    assert!(!Path::new(&out).exists(), "nothing is written");
    let o = merge(&files, &out, &["--partial"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("PARTIAL: 7 of 14 spp (missing parts 1,2)"), "{}", stderr(&o));
    // The partial image is the mean of the 7 samples it has (0..3 and
    // 10..14): finite, and lit where the whole render is.
    let bits = exr_bits(&out);
    assert!(bits.iter().all(|&b| f32::from_bits(b).is_finite()));
    assert!(bits.iter().filter(|&&b| f32::from_bits(b) > 0.0).count() > bits.len() / 2);
    // Tiles: the missing rows are black.
    let tiles = parts(dir.path(), &cornell(), 3, &[1], &["--tiles"]);
    let o = merge(&tiles, &out, &["--partial"]);
    assert!(
        stderr(&o).contains("PARTIAL: rows of missing parts 0,2 black (4 of 12 rows rendered)"),
        "{}",
        stderr(&o)
    );
    let image = image::open(&out).unwrap().to_rgb32f();
    assert!(image.rows().take(4).flatten().all(|p| p.0 == [0.0; 3]));
    assert!(image.rows().skip(4).take(4).flatten().any(|p| p.0 != [0.0; 3]));
}

#[test]
fn parts_of_another_scene_other_settings_or_another_split_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let base = parts(dir.path(), &cornell(), 2, &[0], &[]);
    // The same scene file with one byte more: another scene.
    let edited = dir.path().join("cornell_box.ron");
    let mut text = std::fs::read_to_string(cornell()).unwrap();
    text.push(' ');
    std::fs::write(&edited, text).unwrap();
    let other_dir = dir.path().join("other");
    std::fs::create_dir(&other_dir).unwrap();
    let other = parts(&other_dir, &edited.display().to_string(), 2, &[1], &[]);
    let out = path(dir.path(), "out.exr");
    let e = stderr(&merge(&[base[0].clone(), other[0].clone()], &out, &[]));
    assert!(e.contains("a part of another scene than"), "{e}");
    assert!(e.contains("the scene file or a file it loads differs"), "{e}");
    // Another seed.
    let seeded = parts(&other_dir, &cornell(), 2, &[1], &["--seed", "5"]);
    let e = stderr(&merge(&[base[0].clone(), seeded[0].clone()], &out, &[]));
    assert!(e.contains("rendered with other settings than") && e.contains("seed 5 against 0"), "{e}");
    // Another split.
    let tiles = parts(&other_dir, &cornell(), 2, &[1], &["--tiles"]);
    let e = stderr(&merge(&[base[0].clone(), tiles[0].clone()], &out, &[]));
    assert!(e.contains("split into 2 tiles, but"), "{e}");
    // The same part twice.
    let e = stderr(&merge(&[base[0].clone(), base[0].clone()], &out, &[]));
    assert!(e.contains("part 0/2 given twice"), "{e}");
    assert!(!Path::new(&out).exists());
}

#[test]
fn truncated_and_damaged_part_files_are_errors_never_panics() {
    let dir = tempfile::tempdir().unwrap();
    let files = parts(dir.path(), &cornell(), 2, &[0, 1], &[]);
    let good = std::fs::read(&files[1]).unwrap();
    let out = path(dir.path(), "out.exr");
    let len = good.len();
    for cut in [0, 1, 11, 12, 20, 24, 40, len / 3, len / 2, len - 17, len - 16, len - 1] {
        std::fs::write(&files[1], &good[..cut]).unwrap();
        let e = fails(&["merge", &files[0], &files[1], "-o", &out], &files[1]);
        assert!(e.contains("truncated") || e.contains("not an rt-view part file"), "cut at {cut}: {e}");
    }
    for at in [0, 13, 30, len / 2, len - 1] {
        let mut damaged = good.clone();
        damaged[at] ^= 0x10;
        std::fs::write(&files[1], &damaged).unwrap();
        fails(&["merge", &files[0], &files[1], "-o", &out], &files[1]);
    }
    let mut damaged = good.clone();
    damaged[len / 2] ^= 1;
    std::fs::write(&files[1], &damaged).unwrap();
    fails(&["merge", &files[0], &files[1], "-o", &out], "damaged: the checksum does not match its contents");
    std::fs::write(&files[1], b"").unwrap();
    fails(
        &["merge", &files[0], &path(dir.path(), "nowhere.rtpart"), "-o", &out],
        "nowhere.rtpart: cannot read",
    );
    assert!(!Path::new(&out).exists());
}

#[test]
fn part_arguments_are_checked_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let c = cornell();
    let part = path(dir.path(), "p.rtpart");
    let o = run(&["render", &c, "--part", "4/4", "-o", &part]);
    assert_eq!(o.status.code(), Some(2), "a usage error: {}", stderr(&o));
    assert!(stderr(&o).contains("\"4/4\" is not K/N with 0 <= K < N"), "{}", stderr(&o));
    fails(
        &["render", &c, "--part", "0/4", "-o", &path(dir.path(), "p.exr")],
        "a part (--part) is written to a .rtpart file",
    );
    fails(&["render", &c, "--part", "0/20", "--spp", "14", "-o", &part], "use at most 14 parts (or --tiles)");
    let o = run(&["render", &c, "--tiles", "-o", &path(dir.path(), "x.png")]);
    assert_eq!(o.status.code(), Some(2), "--tiles without --part: {}", stderr(&o));
    fails(&["merge", &part, "-o", &path(dir.path(), "x.txt")], "output must be a .png or .exr file");
}

#[test]
fn a_task_killed_mid_render_leaves_no_part_and_rendering_it_again_completes_the_image() {
    // Large enough that the killed part is still rendering when killed.
    let size = ["--width", "200", "--height", "150", "--spp", "64"];
    let dir = tempfile::tempdir().unwrap();
    let c = cornell();
    let part = |k: u32| path(dir.path(), &format!("p{k}.rtpart"));
    let render_part = |k: u32| {
        let (p, out) = (format!("{k}/4"), part(k));
        let mut args = vec!["render", &c, "--part", &p, "-o", &out];
        args.extend_from_slice(&size);
        ok(&args);
    };
    for k in [0, 1, 3] {
        render_part(k);
    }
    let (p2, out2) = ("2/4".to_owned(), part(2));
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_rt-view"))
        .args(["render", &c, "--part", &p2, "-o", &out2])
        .args(size)
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(150));
    assert!(child.try_wait().unwrap().is_none(), "the part finished before it was killed: make it larger");
    child.kill().unwrap(); // SIGKILL: no handler runs.
    child.wait().unwrap();
    assert!(!Path::new(&out2).exists(), "a killed task leaves no part file");
    let all: Vec<String> = (0..4).map(part).collect();
    let present: Vec<String> = [0, 1, 3].map(part).to_vec();
    let out = path(dir.path(), "out.exr");
    let e = stderr(&merge(&present, &out, &[]));
    assert!(e.contains("missing part 2 of 4") && e.contains("--array=2"), "{e}");
    render_part(2);
    let o = merge(&all, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let whole = path(dir.path(), "whole.exr");
    let mut args = vec!["render", &c, "-o", &whole];
    args.extend_from_slice(&size);
    ok(&args);
    assert_eq!(exr_bits(&out), exr_bits(&whole));
}
