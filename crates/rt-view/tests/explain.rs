//! `rt-view explain`: the JSON record of a pixel sample against `cast
//! --pixels` (the same primary ray and hit, number for number), the
//! course's tests on the hit of each kind of primitive, and clear errors.

mod common;

use common::{rt_view, scenes_dir, stderr, stdout};
use serde_json::Value;

fn scene(name: &str) -> String {
    scenes_dir().join(name).to_str().unwrap().to_owned()
}

/// `rt-view explain` on a 32×24 image of `name` at pixel (x, y), parsed.
fn explain(name: &str, x: u32, y: u32, extra: &[&str]) -> Value {
    let pixel = format!("{x},{y}");
    let path = scene(name);
    let mut args = vec!["explain", &path, "--pixel", &pixel, "--width", "32", "--height", "24"];
    args.extend_from_slice(extra);
    let o = rt_view(&args, "");
    assert!(o.status.success(), "{name}: {}", stderr(&o));
    serde_json::from_str(&stdout(&o)).unwrap()
}

fn f32_of(v: &Value) -> f32 {
    v.as_f64().unwrap_or_else(|| panic!("{v} is not a number")) as f32
}

fn vec3(v: &Value) -> [f32; 3] {
    [f32_of(&v[0]), f32_of(&v[1]), f32_of(&v[2])]
}

#[test]
fn the_primary_ray_and_its_hit_are_those_of_cast_pixels_number_for_number() {
    for name in ["effects.ron", "orthographic.ron", "box.ron", "triangle.ron", "polygon.ron", "plane.ron"] {
        let o = rt_view(&["cast", &scene(name), "--pixels", "--width", "32", "--height", "24"], "");
        assert!(o.status.success(), "{}", stderr(&o));
        let csv = stdout(&o);
        for (x, y) in [(0u32, 0u32), (16, 12), (31, 23), (9, 17)] {
            let row: Vec<&str> = csv.lines().nth(1 + (y * 32 + x) as usize).unwrap().split(',').collect();
            let num = |i: usize| row[i].parse::<f32>().unwrap();
            let json = explain(name, x, y, &["--spp", "1"]);
            let primary = &json["segments"][0];
            assert_eq!(primary["kind"]["type"], "primary");
            assert_eq!(vec3(&primary["origin"]), [num(2), num(3), num(4)], "{name} ({x}, {y})");
            assert_eq!(vec3(&primary["direction"]), [num(5), num(6), num(7)], "{name} ({x}, {y})");
            if row[8] == "1" {
                let hit = &primary["hit"];
                assert_eq!(f32_of(&hit["t"]), num(9), "{name} ({x}, {y})");
                assert_eq!(hit["object"].as_u64().unwrap().to_string(), row[10]);
                assert_eq!(hit["primitive"].as_u64().unwrap().to_string(), row[11]);
                assert_eq!(vec3(&hit["normal"]), [num(12), num(13), num(14)]);
            } else {
                assert!(primary["hit"].is_null(), "{name} ({x}, {y})");
            }
            // 1 spp: the sample is the pixel centre.
            assert_eq!(json["film"], serde_json::json!([0.5, 0.5]));
        }
    }
}

#[test]
fn the_record_holds_the_camera_basis_the_view_plane_and_the_pixel_point() {
    // triangle.ron: C = (0, 0, −4) looking at the origin, up y, fov 50°, near 1.
    let json = explain("triangle.ron", 0, 0, &[]);
    let camera = &json["camera"];
    assert_eq!(vec3(&camera["position"]), [0.0, 0.0, -4.0]);
    assert_eq!(vec3(&camera["x"]), [1.0, 0.0, 0.0]);
    assert_eq!(vec3(&camera["y"]), [0.0, 1.0, 0.0]);
    assert_eq!(vec3(&camera["z"]), [0.0, 0.0, 1.0]);
    let plane_h = 2.0 * (25f32).to_radians().tan();
    let plane_w = plane_h * 32.0 / 24.0;
    let size = &json["view_plane"]["size"];
    assert!((f32_of(&size[0]) - plane_w).abs() < 1e-6 && (f32_of(&size[1]) - plane_h).abs() < 1e-6);
    let ul = vec3(&json["view_plane"]["upper_left"]);
    let expected = [-plane_w / 2.0, plane_h / 2.0, -3.0];
    assert!(ul.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6), "{ul:?}");
    // Pixel (0, 0)'s centre is half a pixel right of and below the corner.
    let p = vec3(&json["pixel_point"]);
    let expected = [-plane_w / 2.0 + plane_w / 64.0, plane_h / 2.0 - plane_h / 48.0, -3.0];
    assert!(p.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-6), "{p:?}");
    assert_eq!(json["pixel"], serde_json::json!([0, 0]));
}

#[test]
fn each_kind_of_primitive_hit_carries_the_course_test() {
    // The centre pixel of each scene sees its first object head-on.
    let centre = |name: &str| explain(name, 16, 12, &[])["segments"][0]["hit"]["test"].clone();
    let plane = explain("plane.ron", 16, 20, &[])["segments"][0]["hit"]["test"].clone();
    assert_eq!(plane["shape"], "plane");
    // The eye at y = 1 is above the floor y = −1 (n = +y).
    assert_eq!(plane["origin_side"], "above");
    assert_eq!(f32_of(&plane["origin_distance"]), 2.0);
    let sphere = centre("sphere.ron");
    assert_eq!((sphere["shape"].as_str(), sphere["origin"].as_str()), (Some("sphere"), Some("outside")));
    assert_eq!(sphere["far_root"], false);
    let triangle = centre("triangle.ron");
    assert_eq!((triangle["shape"].as_str(), triangle["inside"].as_bool()), (Some("triangle"), Some(true)));
    let sum: f32 = triangle["barycentric"].as_array().unwrap().iter().map(f32_of).sum();
    assert!(
        (sum - 1.0).abs() < 1e-5
            && triangle["barycentric"].as_array().unwrap().iter().all(|w| f32_of(w) >= 0.0)
    );
    let polygon = centre("polygon.ron");
    assert_eq!((polygon["shape"].as_str(), polygon["inside"].as_bool()), (Some("polygon"), Some(true)));
    assert_eq!(polygon["triangle"]["inside"], true);
    let aabb = explain("box.ron", 16, 12, &[])["segments"][0]["hit"]["test"].clone();
    assert_eq!((aabb["shape"].as_str(), aabb["entered"].as_bool()), (Some("box"), Some(true)));
    assert_eq!(f32_of(&aabb["t_enter"]), f32_of(&explain("box.ron", 16, 12, &[])["segments"][0]["hit"]["t"]));
}

#[test]
fn a_whitted_record_has_shadow_rays_and_contributions_adding_up_to_its_value() {
    let json = explain("effects.ron", 16, 16, &[]);
    assert_eq!(json["integrator"], "direct");
    let segments = json["segments"].as_array().unwrap();
    assert!(segments.iter().any(|s| s["kind"]["type"] == "shadow"), "{json}");
    let value = vec3(&json["value"]);
    assert_eq!(vec3(&segments[0]["radiance"]), value);
}

#[test]
fn a_bad_pixel_or_sample_is_an_error_that_says_what_and_prints_nothing() {
    for (args, says) in [
        (vec!["--pixel", "32,0"], "pixel 32,0 is outside the 32x24 image"),
        (vec!["--pixel", "3;4"], "is not a pixel"),
        (vec!["--pixel", "0,0", "--sample", "1"], "sample 1 does not exist"),
    ] {
        let s = scene("sphere.ron");
        let mut all = vec!["explain", s.as_str(), "--width", "32", "--height", "24"];
        all.extend(args);
        let o = rt_view(&all, "");
        assert_eq!(o.status.code(), Some(if says == "is not a pixel" { 2 } else { 1 }), "{}", stderr(&o));
        assert!(stderr(&o).contains(says), "{}", stderr(&o));
        assert!(stdout(&o).is_empty());
    }
    let o = rt_view(&["explain", "no-such.ron", "--pixel", "0,0"], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("no-such.ron") && stdout(&o).is_empty());
}

#[test]
fn the_value_is_the_pixel_of_a_one_sample_render_bit_for_bit() {
    // A linear EXR holds the render's f32 colours exactly.
    let dir = tempfile::tempdir().unwrap();
    for name in ["cornell_box.ron", "effects.ron", "subsurface.ron"] {
        let exr = dir.path().join(format!("{name}.exr"));
        let o = rt_view(
            &[
                "render",
                &scene(name),
                "-o",
                exr.to_str().unwrap(),
                "--width",
                "32",
                "--height",
                "24",
                "--spp",
                "1",
                "--seed",
                "3",
            ],
            "",
        );
        assert!(o.status.success(), "{}", stderr(&o));
        let image = image::open(&exr).unwrap().to_rgb32f();
        for (x, y) in [(16, 12), (5, 20), (30, 2)] {
            let json = explain(name, x, y, &["--spp", "1", "--seed", "3"]);
            assert_eq!(vec3(&json["value"]), image.get_pixel(x, y).0, "{name} ({x}, {y})");
        }
    }
}

#[test]
fn scene_view_writes_the_picture_of_the_path_beside_the_json_and_refuses_a_bad_path_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("view.png");
    let out_arg = out.to_str().unwrap().to_owned();
    let record = explain("shadows.ron", 16, 12, &["--scene-view", &out_arg, "--scene-view-size", "240,160"]);
    assert!(record["segments"].as_array().is_some_and(|s| !s.is_empty()), "the JSON is still printed");
    let image = common::read_png(&out);
    assert_eq!(image.dimensions(), (240, 160));
    // The primary ray is drawn white over the flat render.
    assert!(
        image.pixels().any(|p| p.0 == [255, 255, 255]),
        "nothing drawn in white (the eye, the primary ray)"
    );
    // A path that is no PNG is refused before any work, with nothing printed.
    let bad = dir.path().join("view.jpg");
    let o = rt_view(
        &["explain", &scene("shadows.ron"), "--pixel", "1,1", "--scene-view", bad.to_str().unwrap()],
        "",
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("must be a .png file"), "{}", stderr(&o));
    assert!(stdout(&o).is_empty());
    assert!(!bad.exists());
}
