//! Arbitrary bytes as `cast` input: parsing must never panic, and every ray
//! it accepts, cast into a scene of every analytic primitive, must give a
//! finite `t` beyond the origin and a unit normal.
#![no_main]

use std::path::Path;
use std::sync::OnceLock;

use libfuzzer_sys::fuzz_target;
use rt_core::Scene;

const SCENE: &str = r#"(
    camera: (position: (0, 2, -8), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 45, near: 1),
    image: (width: 8, height: 6),
    materials: { "m": (color: (1, 1, 1)) },
    objects: [
        Plane(normal: (0, 1, 0), d: -1, material: "m"),
        Sphere(center: (0, 0, 0), radius: 1, material: "m"),
        Sphere(center: (1e5, 3, -2e4), radius: 1e-3, material: "m"),
        Aabb(min: (2, -1, -1), max: (3, 1, 1), material: "m"),
        Triangle(a: (-3, -1, 0), b: (-2, 1, 0), c: (-1, -1, 0), material: "m"),
        Polygon(points: [(0, 0, 3), (2, 0, 3), (2, 1, 3), (1, 1, 3), (1, 2, 3), (0, 2, 3)], material: "m"),
    ],
)"#;

fn scene() -> &'static Scene {
    static SCENE_CELL: OnceLock<Scene> = OnceLock::new();
    SCENE_CELL.get_or_init(|| rt_core::parse_scene(SCENE, "fuzz.ron", Path::new(".")).unwrap().scene)
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(rays) = rt_core::files::ray_text::parse_rays(text) else { return };
    for ray in rays.iter().take(256) {
        assert!(ray.origin.is_finite() && ray.dir.is_finite() && ray.dir.length_squared() >= 0.0);
        if let Some(hit) = scene().cast(ray) {
            assert!(hit.t.is_finite() && hit.t > 0.0, "t = {} for {ray:?}", hit.t);
            assert!((hit.normal.length() - 1.0).abs() < 1e-4, "normal {} for {ray:?}", hit.normal);
        }
    }
});
