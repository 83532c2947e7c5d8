//! `rt-view accuracy`: the CSV, table and plot it writes, and its refusals.

mod common;

use common::{read_png, rt_view, scenes_dir, stderr};

#[test]
fn a_quick_run_measures_every_knob_and_writes_csv_table_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let scenes = scenes_dir();
    let o = rt_view(
        &["accuracy", "--quick", "--runs", "1", "--out", out, "--scenes", scenes.to_str().unwrap()],
        "",
    );
    assert!(o.status.success(), "{}", stderr(&o));

    let csv = std::fs::read_to_string(dir.path().join("accuracy.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("precision,part,experiment,setting,time_s,ns_per_ray,rmse,max_error,wrong,rays")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let find = |experiment: &str, setting: &str| {
        rows.iter()
            .find(|r| r[2] == experiment && r[3] == setting)
            .unwrap_or_else(|| panic!("no row {experiment} / {setting}"))
    };
    let rmse = |experiment: &str, setting: &str| find(experiment, setting)[6].parse::<f64>().unwrap();
    // Every spp, depth and method setting is there; references have no error.
    for spp in ["spp=1", "spp=4", "spp=16"] {
        for experiment in ["edges (spp)", "soft shadows (spp)", "ambient occlusion (spp)"] {
            assert!(rmse(experiment, spp) > 0.0, "{experiment} {spp}");
        }
    }
    assert_eq!(rmse("soft shadows (spp)", "spp=64"), 0.0);
    assert!(rmse("soft shadows (spp)", "spp=1") > rmse("soft shadows (spp)", "spp=16"));
    assert!(rmse("mirrors (depth)", "max_depth=0") > rmse("mirrors (depth)", "max_depth=4"));
    assert_eq!(rmse("glass (depth)", "max_depth=64"), 0.0);
    for setting in ["triangle=MollerTrumbore", "triangle=AreaRatio", "sphere=Textbook", "box=SixPlane"] {
        find("methods (showcase)", setting);
    }
    // Subsurface: noise against samples, and a walk capped at one step
    // loses light that the reference's walks carry.
    assert!(rmse("subsurface (spp)", "spp=1") > rmse("subsurface (spp)", "spp=16"));
    assert_eq!(rmse("subsurface (walk cap)", "max_walk_steps=1000000"), 0.0);
    assert!(
        rmse("subsurface (walk cap)", "max_walk_steps=1")
            > rmse("subsurface (walk cap)", "max_walk_steps=4096")
    );
    // Geometry: the default methods are never wrong; the course's triangle test is.
    let wrong = |experiment: &str, setting: &str| find(experiment, setting)[8].parse::<usize>().unwrap();
    for r in rows.iter().filter(|r| r[1] == "geometry") {
        if ["triangle=Watertight", "sphere=Careful", "box=Slab"].contains(&r[3]) {
            assert_eq!(r[8], "0", "{r:?}");
        }
        assert!(r[5].parse::<f64>().unwrap() > 0.0, "ns per ray in {r:?}");
    }
    assert!(wrong("triangle: 10^-5 heights either side of an edge", "triangle=AreaRatio") > 0);

    let table = std::fs::read_to_string(dir.path().join("accuracy.md")).unwrap();
    assert!(table.contains("| ray set | method | precision | ns/ray |"));
    assert_eq!(read_png(&dir.path().join("accuracy.png")).dimensions(), (1600, 560));
}

#[test]
fn geometry_only_writes_this_builds_rows_alone() {
    let dir = tempfile::tempdir().unwrap();
    let o =
        rt_view(&["accuracy", "--geometry-only", "--runs", "1", "--out", dir.path().to_str().unwrap()], "");
    assert!(o.status.success(), "{}", stderr(&o));
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    let expected = if cfg!(feature = "f64") { "accuracy-f64.csv" } else { "accuracy-f32.csv" };
    assert_eq!(names, [expected]);
}

#[test]
fn a_missing_or_wrong_f64_build_is_refused_with_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().to_str().unwrap();
    let o = rt_view(&["accuracy", "--with-f64", "/no/such/rt-view", "--out", out], "");
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--with-f64 /no/such/rt-view: no such file"), "{}", stderr(&o));
    // Nothing was measured or written.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}
