//! `rt-view export`: the scene as JSON with every default filled in, and
//! triangle objects as OBJ files that load back to the same triangles.

// `x as rt_core::Real as f64` rounds a value to the geometry's precision;
// with the `f64` feature `Real` is f64 and the second cast does nothing.
#![allow(clippy::unnecessary_cast)]

mod common;

use std::path::Path;

use common::{rt_view, scenes_dir, stderr};
use serde_json::Value;

/// `rt-view export`s `scene` to `dir`/`name`.json and reads the JSON back.
fn export(scene: &Path, dir: &Path, name: &str) -> Value {
    let out = dir.join(format!("{name}.json"));
    let o = rt_view(&["export", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
}

/// A JSON number array as `f64`s.
fn floats(v: &Value) -> Vec<f64> {
    v.as_array().unwrap_or_else(|| panic!("not an array: {v}")).iter().map(|x| x.as_f64().unwrap()).collect()
}

/// A JSON colour (`f32` in rt-view) as `f32`s: exact, as serde_json prints
/// the shortest text that reads back to the same `f32`.
fn colour(v: &Value) -> [f32; 3] {
    let f = floats(v);
    assert_eq!(f.len(), 3, "{v}");
    [f[0] as f32, f[1] as f32, f[2] as f32]
}

/// A vector of rt-view's geometry (`Real`) as the `f64`s the export writes.
fn wide(v: rt_core::Vec3) -> [f64; 3] {
    let d = rt_core::math::real::widen(v);
    [d.x, d.y, d.z]
}

/// The keys of a JSON object, sorted.
fn keys(v: &Value) -> Vec<&str> {
    let mut k: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    k.sort();
    k
}

/// The triangles of an exported OBJ file, read strictly as the export writes
/// them: three `v x y z` lines per triangle, then `f 3i+1 3i+2 3i+3` for
/// triangle i, nothing else.
fn obj_triangles(path: &Path) -> Vec<[[f64; 3]; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for line in text.lines() {
        let mut words = line.split(' ');
        match words.next() {
            Some("v") => {
                let v: Vec<f64> = words.map(|w| w.parse().unwrap()).collect();
                assert_eq!(v.len(), 3, "{line}");
                vertices.push([v[0], v[1], v[2]]);
            }
            Some("f") => faces.push(words.map(|w| w.parse::<usize>().unwrap()).collect::<Vec<_>>()),
            _ => panic!("{}: unexpected line {line:?}", path.display()),
        }
    }
    assert_eq!(vertices.len(), 3 * faces.len(), "{}", path.display());
    for (i, f) in faces.iter().enumerate() {
        assert_eq!(f, &[3 * i + 1, 3 * i + 2, 3 * i + 3], "{}: face {i}", path.display());
    }
    vertices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn length(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// `(b − a) × (c − a)`: the winding normal, twice the area long.
fn winding(t: &[[f64; 3]; 3]) -> [f64; 3] {
    cross(sub(t[1], t[0]), sub(t[2], t[0]))
}

#[test]
fn export_writes_every_object_material_and_light_with_defaults_resolved() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene.json");
    let scene = scenes_dir().join("showcase.ron");
    let o = rt_view(&["export", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let loaded = rt_core::load_scene(&scene).unwrap();
    let objects = json["objects"].as_array().unwrap();
    assert_eq!(objects.len(), loaded.scene.objects().len());
    assert_eq!(json["materials"].as_array().unwrap().len(), loaded.scene.materials().len());
    assert_eq!(json["width"], loaded.settings.image.width());
    assert_eq!(json["camera"]["projection"], "Perspective");
    assert!(json["global_illumination"].is_null());
    // A default filled in: every material has its shininess and roughness.
    for m in json["materials"].as_array().unwrap() {
        assert!(m["shininess"].is_number() && m["roughness"].is_number(), "{m}");
    }
    // Triangle objects are OBJ files beside the JSON, loading back to the
    // same triangles (a mesh's vertex for vertex, in order); spheres and
    // planes stay analytic.
    let kinds: Vec<&str> = objects.iter().map(|o| o["kind"].as_str().unwrap()).collect();
    assert!(
        kinds.contains(&"Sphere") && kinds.contains(&"Plane") && kinds.contains(&"Triangles"),
        "{kinds:?}"
    );
    for (o, object) in objects.iter().zip(loaded.scene.objects()) {
        if o["kind"] != "Triangles" {
            continue;
        }
        let triangles = obj_triangles(&dir.path().join(o["file"].as_str().unwrap()));
        assert_eq!(triangles.len() as u64, o["triangles"].as_u64().unwrap());
        let obj = dir.path().join(o["file"].as_str().unwrap());
        let mesh = rt_core::geometry::mesh::Mesh::load_obj(&obj, 1.0, rt_core::Vec3::ZERO).unwrap();
        assert_eq!(mesh.triangle_count(), triangles.len());
        if let rt_core::Primitive::Mesh(m) = &object.primitive {
            assert_eq!(m.triangle_count(), triangles.len());
            for (i, t) in triangles.iter().enumerate() {
                assert_eq!(t.to_vec(), m.triangle(i).map(wide).to_vec(), "{}: triangle {i}", o["file"]);
            }
        }
    }
}

#[test]
fn exported_triangles_keep_the_normals_rt_view_uses() {
    // The box's faces point out: (b − a) × (c − a) of every exported
    // triangle points away from the box's centre.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("box.ron");
    std::fs::write(
        &scene,
        r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 8, height: 6),
        materials: { "m": (color: (0.5, 0.5, 0.5), emission: (1, 1, 1)) },
        objects: [ Aabb(min: (-1, -2, -3), max: (1, 2, 3), material: "m") ],
        effects: (global_illumination: (max_bounces: 3)),
    )"#,
    )
    .unwrap();
    let out = dir.path().join("box.json");
    let o = rt_view(&["export", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(json["global_illumination"]["max_bounces"], 3);
    let obj = dir.path().join(json["objects"][0]["file"].as_str().unwrap());
    let mesh = rt_core::geometry::mesh::Mesh::load_obj(&obj, 1.0, rt_core::Vec3::ZERO).unwrap();
    assert_eq!(mesh.triangle_count(), 12);
    for i in 0..12 {
        let [a, b, c] = mesh.triangle(i);
        assert!(mesh.normal(i).dot((a + b + c) / 3.0) > 0.0, "triangle {i} faces in");
    }
}

#[test]
fn a_translucent_material_is_exported_with_its_medium() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sss.ron");
    std::fs::write(
        &scene,
        r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 8, height: 6),
        materials: {
            "jade": (color: (0.3, 0.7, 0.4), ior: 1.6, subsurface: (albedo: (0.8, 0.9, 0.85), mean_free_path: (0.2, 0.3, 0.25), anisotropy: 0.3)),
            "grey": (color: (0.5, 0.5, 0.5)),
        },
        objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "jade"), Plane(normal: (0, 1, 0), d: -1, material: "grey") ],
        effects: (global_illumination: (max_walk_steps: 100)),
    )"#,
    )
    .unwrap();
    let out = dir.path().join("sss.json");
    let o = rt_view(&["export", scene.to_str().unwrap(), "-o", out.to_str().unwrap()], "");
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(json["global_illumination"]["max_walk_steps"], 100);
    let materials = json["materials"].as_array().unwrap();
    let jade = materials.iter().find(|m| m["name"] == "jade").unwrap();
    let f = |v: &serde_json::Value| {
        v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect::<Vec<_>>()
    };
    assert_eq!(f(&jade["subsurface"]["albedo"]), [0.8, 0.9, 0.85]);
    assert_eq!(f(&jade["subsurface"]["mean_free_path"]), [0.2, 0.3, 0.25]);
    assert_eq!(jade["subsurface"]["anisotropy"].as_f64().unwrap() as f32, 0.3);
    let grey = materials.iter().find(|m| m["name"] == "grey").unwrap();
    assert!(grey.get("subsurface").is_none());
}

#[test]
fn export_refuses_a_bad_scene_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.json");
    let o = rt_view(&["export", "/no/such/scene.ron", "-o", out.to_str().unwrap()], "");
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("cannot read scene file"), "{}", stderr(&o));
    assert!(!out.exists());
}

#[test]
fn every_light_is_exported_with_its_kind_place_power_and_shadow_flag() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("lights.ron");
    std::fs::write(
        &scene,
        r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 8, height: 6),
        materials: { "m": (color: (0.5, 0.5, 0.5)) },
        objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
        lights: [
            Point(position: (4, 5, -4), color: (0.5, 0.55, 0.7), intensity: 47.12),
            Directional(direction: (0, -2, 0), color: (1, 0.5, 0), intensity: 2, shadows: false),
            Sphere(center: (-3, 6, -2.5), radius: 1.25, color: (1, 0.95, 0.85), intensity: 141.4, samples: 8),
            Point(position: (0.1, -0.2, 0.3)),
        ],
    )"#,
    )
    .unwrap();
    let json = export(&scene, dir.path(), "lights");
    let lights = json["lights"].as_array().unwrap();
    assert_eq!(lights.len(), 4, "{json}");
    // Power: colour × intensity, in f32 as rt-view computes it.
    let power = |c: [f32; 3], i: f32| c.map(|x| x * i);
    let point = &lights[0];
    assert_eq!(keys(point), ["kind", "position", "power", "shadows"]);
    assert_eq!(point["kind"], "Point");
    assert_eq!(floats(&point["position"]), [4.0, 5.0, -4.0]);
    assert_eq!(colour(&point["power"]), power([0.5, 0.55, 0.7], 47.12));
    assert_eq!(point["shadows"], true);
    // The direction normalised; shadows as written.
    let sun = &lights[1];
    assert_eq!(keys(sun), ["direction", "kind", "power", "shadows"]);
    assert_eq!(sun["kind"], "Directional");
    assert_eq!(floats(&sun["direction"]), [0.0, -1.0, 0.0]);
    assert_eq!(colour(&sun["power"]), [2.0, 1.0, 0.0]);
    assert_eq!(sun["shadows"], false);
    let lamp = &lights[2];
    assert_eq!(keys(lamp), ["center", "kind", "power", "radius", "shadows"]);
    assert_eq!(lamp["kind"], "Sphere");
    assert_eq!(floats(&lamp["center"]), [-3.0, 6.0, -2.5]);
    assert_eq!(lamp["radius"].as_f64().unwrap(), 1.25);
    assert_eq!(colour(&lamp["power"]), power([1.0, 0.95, 0.85], 141.4));
    assert_eq!(lamp["shadows"], true);
    // Defaults filled in: white, intensity 1, shadows on. The position is
    // rt-view's (f32 by default), widened exactly.
    let plain = &lights[3];
    assert_eq!(
        floats(&plain["position"]),
        [0.1 as rt_core::Real as f64, -0.2 as rt_core::Real as f64, 0.3 as rt_core::Real as f64]
    );
    assert_eq!(colour(&plain["power"]), [1.0, 1.0, 1.0]);
    assert_eq!(plain["shadows"], true);
}

#[test]
fn the_lights_of_the_every_effect_scene_are_exported_as_rt_view_loads_them() {
    use rt_core::lights::light::LightKind;
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("effects.ron");
    let json = export(&scene, dir.path(), "effects");
    let loaded = rt_core::load_scene(&scene).unwrap();
    let lights = json["lights"].as_array().unwrap();
    assert_eq!(lights.len(), loaded.scene.lights().len());
    assert!(!lights.is_empty());
    for (j, l) in lights.iter().zip(loaded.scene.lights()) {
        assert_eq!(colour(&j["power"]), l.power.to_array(), "{j}");
        assert_eq!(j["shadows"], l.shadows, "{j}");
        match l.kind {
            LightKind::Point { position } => {
                assert_eq!(j["kind"], "Point", "{j}");
                assert_eq!(floats(&j["position"]), wide(position), "{j}");
            }
            LightKind::Spot { position, direction, cos_inner, cos_outer } => {
                assert_eq!(j["kind"], "Spot", "{j}");
                assert_eq!(floats(&j["position"]), wide(position), "{j}");
                assert_eq!(floats(&j["direction"]), wide(direction), "{j}");
                assert_eq!(j["cos_inner"].as_f64().unwrap(), cos_inner as f64, "{j}");
                assert_eq!(j["cos_outer"].as_f64().unwrap(), cos_outer as f64, "{j}");
            }
            LightKind::Directional { direction } => {
                assert_eq!(j["kind"], "Directional", "{j}");
                assert_eq!(floats(&j["direction"]), wide(direction), "{j}");
            }
            LightKind::Sphere { center, radius, .. } => {
                assert_eq!(j["kind"], "Sphere", "{j}");
                assert_eq!(floats(&j["center"]), wide(center), "{j}");
                assert_eq!(j["radius"].as_f64().unwrap(), radius as f64, "{j}");
            }
        }
    }
}

#[test]
fn every_object_is_exported_with_its_geometry_and_triangles_with_their_vertices_and_winding() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(scenes_dir().join("meshes/icosphere.obj"), dir.path().join("ico.obj")).unwrap();
    let scene = dir.path().join("shapes.ron");
    std::fs::write(
        &scene,
        r#"(
        camera: (position: (0, 0, -9), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 8, height: 6),
        materials: { "a": (color: (0.5, 0.5, 0.5)), "b": (color: (0.2, 0.3, 0.4)) },
        objects: [
            Sphere(center: (1, 2, 3), radius: 0.5, material: "a"),
            Plane(normal: (0, 2, 0), d: -1, material: "b"),
            Triangle(a: (0.1, 0.2, 0.3), b: (1.5, 0.25, 0.3), c: (0.2, 1.7, 0.35), material: "a"),
            Polygon(points: [(0, 0, 2), (2, 0, 2), (2, 1, 2), (1, 2, 2), (0, 1, 2)], material: "b"),
            Aabb(min: (-1, -2, -3), max: (1, 2, 3), material: "a"),
            Mesh(file: "ico.obj", scale: 0.9, translate: (-1.1, 0, 0.5), material: "b"),
        ],
    )"#,
    )
    .unwrap();
    let json = export(&scene, dir.path(), "shapes");
    let loaded = rt_core::load_scene(&scene).unwrap();
    let objects = json["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 6);
    let materials: Vec<&str> = objects.iter().map(|o| o["material"].as_str().unwrap()).collect();
    assert_eq!(materials, ["a", "b", "a", "b", "a", "b"]);

    assert_eq!(objects[0]["kind"], "Sphere");
    assert_eq!(floats(&objects[0]["center"]), [1.0, 2.0, 3.0]);
    assert_eq!(objects[0]["radius"].as_f64().unwrap(), 0.5);
    // The plane normalised: (0, 2, 0)·p = −1 is (0, 1, 0)·p = −0.5.
    assert_eq!(objects[1]["kind"], "Plane");
    assert_eq!(floats(&objects[1]["normal"]), [0.0, 1.0, 0.0]);
    assert_eq!(objects[1]["d"].as_f64().unwrap(), -0.5);

    let triangles = |i: usize| {
        let o = &objects[i];
        assert_eq!(o["kind"], "Triangles", "{o}");
        assert_eq!(o["file"], format!("shapes.json.object-{i}.obj"), "{o}");
        let t = obj_triangles(&dir.path().join(o["file"].as_str().unwrap()));
        assert_eq!(o["triangles"].as_u64().unwrap(), t.len() as u64, "{o}");
        t
    };
    let r = |x: f64| x as rt_core::Real as f64;
    // A triangle: its own corners, in order (so its winding).
    let tri = triangles(2);
    assert_eq!(tri, [[[r(0.1), r(0.2), r(0.3)], [r(1.5), r(0.25), r(0.3)], [r(0.2), r(1.7), r(0.35)]]]);

    // A polygon: a fan of n − 2 triangles on its corners, covering its area
    // (shoelace: 3), each wound like the polygon (normal rt-view uses).
    let poly = triangles(3);
    assert_eq!(poly.len(), 3);
    let corners = [[0.0, 0.0, 2.0], [2.0, 0.0, 2.0], [2.0, 1.0, 2.0], [1.0, 2.0, 2.0], [0.0, 1.0, 2.0]];
    let rt_core::Primitive::Polygon(polygon) = &loaded.scene.objects()[3].primitive else {
        panic!("not a polygon")
    };
    let normal = wide(polygon.normal());
    let mut area = 0.0;
    for t in &poly {
        assert!(t.iter().all(|v| corners.contains(v)), "{t:?}");
        let w = winding(t);
        area += length(w) / 2.0;
        for k in 0..3 {
            assert!((w[k] / length(w) - normal[k]).abs() < 1e-6, "{t:?} against {normal:?}");
        }
    }
    assert!((area - 3.0).abs() < 1e-9, "{area}");

    // A box: 12 triangles, two on each face, corners of the box, covering the
    // face's area and wound outward.
    let boxed = triangles(4);
    assert_eq!(boxed.len(), 12);
    let (lo, hi) = ([-1.0, -2.0, -3.0], [1.0, 2.0, 3.0]);
    let mut face_area = std::collections::HashMap::new();
    for t in &boxed {
        for v in t {
            assert!((0..3).all(|k| v[k] == lo[k] || v[k] == hi[k]), "{t:?}");
        }
        // The face: the axis all three corners share, and which end of it.
        let axis = (0..3).find(|&k| t[0][k] == t[1][k] && t[1][k] == t[2][k]).expect("a face triangle");
        let outward = if t[0][axis] == hi[axis] { 1.0 } else { -1.0 };
        let w = winding(t);
        assert!(w[axis] * outward > 0.0 && w[(axis + 1) % 3] == 0.0 && w[(axis + 2) % 3] == 0.0, "{t:?}");
        *face_area.entry((axis, outward as i32)).or_insert(0.0) += length(w) / 2.0;
    }
    assert_eq!(face_area.len(), 6);
    for ((axis, side), area) in face_area {
        let size: f64 = (0..3).filter(|&k| k != axis).map(|k| hi[k] - lo[k]).product();
        assert_eq!(area, size, "face {axis} {side}");
    }

    // A mesh: its triangles in world space (scaled and moved), in order,
    // vertex for vertex as rt-view intersects them.
    let mesh_triangles = triangles(5);
    let rt_core::Primitive::Mesh(mesh) = &loaded.scene.objects()[5].primitive else { panic!("not a mesh") };
    assert_eq!(mesh_triangles.len(), mesh.triangle_count());
    assert_eq!(objects[5]["smooth"], mesh.has_vertex_normals());
    for (i, t) in mesh_triangles.iter().enumerate() {
        assert_eq!(t.to_vec(), mesh.triangle(i).map(wide).to_vec(), "triangle {i}");
    }
    // Independently of the loaded mesh: the icosphere's first vertex of the
    // file, scaled by 0.9 and moved, is a vertex of the export.
    let first = std::fs::read_to_string(dir.path().join("ico.obj")).unwrap();
    let v: Vec<f64> = first
        .lines()
        .find_map(|l| l.strip_prefix("v "))
        .unwrap()
        .split_whitespace()
        .map(|w| w.parse().unwrap())
        .collect();
    let moved =
        [r(r(r(v[0]) * r(0.9)) + r(-1.1)), r(r(r(v[1]) * r(0.9)) + 0.0), r(r(r(v[2]) * r(0.9)) + r(0.5))];
    assert!(
        mesh_triangles.iter().flatten().any(|p| (0..3).all(|k| (p[k] - moved[k]).abs() < 1e-6)),
        "{moved:?} not exported"
    );
}

#[test]
fn an_environment_map_its_sun_and_the_lens_are_exported_for_outside_tools() {
    let dir = tempfile::tempdir().unwrap();
    // The studio map: the .hdr beside the JSON reads back as the scene's map.
    let json = export(&scenes_dir().join("depth_of_field.ron"), dir.path(), "dof");
    let env = &json["environment"];
    assert_eq!((env["width"].as_u64(), env["height"].as_u64()), (Some(256), Some(128)));
    assert_eq!((env["strength"].as_f64(), env["rotation_degrees"].as_f64()), (Some(1.0), Some(0.0)));
    assert!(env.get("sun").is_none());
    let written = rt_core::files::environment_image::read_environment_image(
        &dir.path().join(env["file"].as_str().unwrap()),
    )
    .unwrap();
    let original =
        rt_core::files::environment_image::read_environment_image(&scenes_dir().join("studio.hdr")).unwrap();
    assert_eq!(written.texels, original.texels);
    assert_eq!(colour(&json["background"]), [0.0; 3]);
    let (aperture, focus) =
        (json["camera"]["aperture"].as_f64().unwrap(), json["camera"]["focus_distance"].as_f64().unwrap());
    assert!((aperture - 0.12).abs() < 1e-6 && (focus - 6.22).abs() < 1e-5, "{aperture}, {focus}");
    // The sky: a baked map with its sun.
    let json = export(&scenes_dir().join("outdoor.ron"), dir.path(), "outdoor");
    let sun = &json["environment"]["sun"];
    assert_eq!(colour(&sun["irradiance"]), [10.0, 9.5, 8.5]);
    assert!((sun["angular_radius_degrees"].as_f64().unwrap() - 0.2667).abs() < 1e-3);
    assert_eq!(json["camera"]["aperture"].as_f64(), Some(0.0));
}
