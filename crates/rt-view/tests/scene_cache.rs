//! `rt-view prepare` and the commands reading its cache: the same images
//! and ray queries as from the scene file, parts that merge with the scene
//! file's, a cache told by its bytes not its name, and damaged caches
//! refused with a message (exit status 1, never a panic).

mod common;

use std::process::Output;

use common::{read_png, rt_view, scenes_dir, stderr, stdout};

const SIZE: [&str; 6] = ["--width", "16", "--height", "12", "--spp", "6"];

fn ok(args: &[&str]) -> Output {
    let o = rt_view(args, "");
    assert!(o.status.success(), "rt-view {}: {}", args.join(" "), stderr(&o));
    o
}

fn scene(name: &str) -> String {
    scenes_dir().join(name).display().to_string()
}

#[test]
fn parts_from_a_cache_and_from_the_scene_file_merge_into_the_one_machine_image() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    let ron = scene("cornell_box.ron");
    ok(&["prepare", &ron, "-o", &p("cornell.rtc")]);
    let render = |scene: &str, extra: &[&str]| {
        let mut args = vec!["render", scene];
        args.extend_from_slice(extra);
        args.extend_from_slice(&SIZE);
        ok(&args);
    };
    render(&ron, &["-o", &p("whole.png")]);
    render(&p("cornell.rtc"), &["-o", &p("cached.png")]);
    render(&ron, &["--part", "0/2", "-o", &p("a.rtpart")]);
    render(&p("cornell.rtc"), &["--part", "1/2", "-o", &p("b.rtpart")]);
    ok(&["merge", &p("a.rtpart"), &p("b.rtpart"), "-o", &p("merged.png")]);
    assert_eq!(read_png(&dir.path().join("cached.png")), read_png(&dir.path().join("whole.png")));
    assert_eq!(read_png(&dir.path().join("merged.png")), read_png(&dir.path().join("whole.png")));
}

#[test]
fn a_cache_is_told_by_its_bytes_and_casts_the_scene_files_rays() {
    let dir = tempfile::tempdir().unwrap();
    // Named .ron, yet a cache.
    let cache = dir.path().join("mesh-cache.ron").display().to_string();
    ok(&["prepare", &scene("mesh.ron"), "-o", &cache]);
    let cast = |s: &str| stdout(&ok(&["cast", s, "--pixels", "--width", "8", "--height", "6"]));
    assert_eq!(cast(&cache), cast(&scene("mesh.ron")));
}

#[test]
fn a_damaged_or_truncated_cache_is_refused_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("models.rtc");
    ok(&["prepare", &scene("models.ron"), "-o", &path.display().to_string()]);
    let bytes = std::fs::read(&path).unwrap();
    let out = dir.path().join("x.png").display().to_string();
    for (name, damaged) in [
        ("cut.rtc", bytes[..bytes.len() / 2].to_vec()),
        ("flipped.rtc", {
            let mut b = bytes.clone();
            let at = b.len() * 2 / 3;
            b[at] ^= 0xff;
            b
        }),
    ] {
        let file = dir.path().join(name);
        std::fs::write(&file, damaged).unwrap();
        let o = rt_view(&["render", &file.display().to_string(), "-o", &out], "");
        assert_eq!(o.status.code(), Some(1), "{name}: {}", stderr(&o));
        assert!(
            stderr(&o).contains(name) && stderr(&o).contains("damaged or truncated"),
            "{name}: {}",
            stderr(&o)
        );
    }
    let o = rt_view(&["prepare", &scene("no_such.ron"), "-o", &path.display().to_string()], "");
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // The cache that was there is left as it was.
    assert_eq!(std::fs::read(&path).unwrap(), bytes);
}

#[test]
fn stats_name_the_build_steps_of_a_tree_built_and_not_of_one_read_from_a_cache() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    ok(&["prepare", &scene("mesh.ron"), "-o", &p("mesh.rtc")]);
    let out = p("m.png");
    let stats = |s: &str| {
        let mut args = vec!["render", s, "-o", &out, "--stats"];
        args.extend(SIZE);
        stderr(&ok(&args))
    };
    let (built, read) = (stats(&scene("mesh.ron")), stats(&p("mesh.rtc")));
    assert!(built.contains("BVH build steps: items "), "{built}");
    assert!(read.contains("BVH: 896 primitives,") && !read.contains("BVH build steps"), "{read}");
}
