//! `rt-view export`: the scene as JSON with every default filled in, and
//! triangle objects as OBJ files that load back to the same triangles.

mod common;

use common::{rt_view, scenes_dir, stderr};

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
    assert_eq!(objects.len(), loaded.objects().len());
    assert_eq!(json["materials"].as_array().unwrap().len(), loaded.materials().len());
    assert_eq!(json["width"], loaded.width);
    assert_eq!(json["camera"]["projection"], "Perspective");
    assert!(json["global_illumination"].is_null());
    // A default filled in: every material has its shininess and roughness.
    for m in json["materials"].as_array().unwrap() {
        assert!(m["shininess"].is_number() && m["roughness"].is_number(), "{m}");
    }
    // Triangle objects are OBJ files beside the JSON, loading back to the
    // same number of triangles; spheres and planes stay analytic.
    let kinds: Vec<&str> = objects.iter().map(|o| o["kind"].as_str().unwrap()).collect();
    assert!(
        kinds.contains(&"Sphere") && kinds.contains(&"Plane") && kinds.contains(&"Triangles"),
        "{kinds:?}"
    );
    for o in objects.iter().filter(|o| o["kind"] == "Triangles") {
        let obj = dir.path().join(o["file"].as_str().unwrap());
        let mesh = rt_core::mesh::Mesh::load_obj(&obj, 1.0, rt_core::Vec3::ZERO).unwrap();
        assert_eq!(mesh.triangle_count() as u64, o["triangles"].as_u64().unwrap());
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
    let mesh = rt_core::mesh::Mesh::load_obj(&obj, 1.0, rt_core::Vec3::ZERO).unwrap();
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
