//! Meshes read from model files into the scene: one object per material
//! part with the file's own materials and textures ([`crate::files::model`]), or
//! one object with the material the scene names.
//!
//! A glTF file's `KHR_lights_punctual` lights join the scene's lights when
//! its entry says `lights: true` (placed with the model); without, a file
//! with lights has a warning saying so. An OBJ file has no lights.
//!
//! A part's material is named `FILE:NAME` (the mesh's `file` as written,
//! and the material's name in the file; `FILE:default` for faces without
//! one). The model's warnings go to the scene, prefixed with `FILE`.

use std::path::Path;
use std::sync::Arc;

use crate::files::model::{Model, ModelError, default_material, is_gltf};
use crate::files::{gltf_model, obj_model};
use crate::geometry::mesh::Mesh;
use crate::geometry::primitive::Primitive;
use crate::lights::light::Light;
use crate::math::real::{Real, Vec3};
use crate::scene::SceneBuilder;

/// Reads the OBJ or glTF file at `path` (by its extension), with a glTF
/// file's lights `with_lights`.
fn load(
    path: &Path,
    scale: Real,
    translate: Vec3,
    with_lights: bool,
) -> Result<(Model, Vec<Light>), ModelError> {
    if is_gltf(path) {
        gltf_model::load_with_lights(path, scale, translate, with_lights)
    } else {
        obj_model::load(path, scale, translate).map(|m| (m, Vec::new()))
    }
}

/// Adds the model at `path` (`written` as in the scene file), transformed
/// by `scale` and then `translate`, to `scene`: with `material`, as one
/// object of that material; without, one object per part with the file's
/// own materials; and a glTF file's lights `with_lights`. Returns the scene
/// and how many objects were added.
pub(super) fn add_model(
    scene: SceneBuilder,
    path: &Path,
    written: &str,
    (scale, translate): (Real, Vec3),
    material: Option<String>,
    with_lights: bool,
    camera_named: bool,
) -> Result<(SceneBuilder, usize), ModelError> {
    let mut scene = scene.source_file(path);
    if let Some(material) = material {
        let mesh = if is_gltf(path) {
            let (mesh, files, lights) = gltf_model::load_geometry(path, scale, translate)?;
            for file in &files {
                scene = scene.source_file(file);
            }
            for light in lights.into_iter().filter(|_| with_lights) {
                scene = scene.light(light);
            }
            mesh
        } else {
            Mesh::load_obj(path, scale, translate)?
        };
        return Ok((scene.object(Primitive::Mesh(mesh), material), 1));
    }
    let (model, lights) = load(path, scale, translate, with_lights)?;
    for light in lights {
        scene = scene.light(light);
    }
    for file in &model.files {
        scene = scene.source_file(file);
    }
    for warning in model.warnings {
        scene = scene.warning(format!("{written}: {warning}"));
    }
    if model.cameras > 0 && !camera_named {
        scene = scene.warning(format!(
            "{written}: its {} camera(s) are not used: the scene's camera is its own; \
             camera: (gltf: \"{written}\", index: N) would take one",
            model.cameras
        ));
    }
    let first_texture = scene.texture_count() as u32;
    for texture in model.textures {
        scene = scene.texture(Arc::new(texture));
    }
    let names: Vec<String> = model.materials.iter().map(|(name, _)| format!("{written}:{name}")).collect();
    for ((_, mut m), name) in model.materials.into_iter().zip(&names) {
        m.offset_textures(first_texture);
        scene = scene.material(name.clone(), m);
    }
    let default = format!("{written}:default");
    if model.parts.iter().any(|(_, m)| m.is_none()) {
        scene = scene.material(default.clone(), default_material());
    }
    let count = model.parts.len();
    for (mesh, material) in model.parts {
        let name = material.map_or(&default, |i| &names[i]);
        scene = scene.object(Primitive::Mesh(mesh), name.clone());
    }
    Ok((scene, count))
}

#[cfg(test)]
mod tests {
    use crate::files::scene_file::parse_scene;
    use crate::lights::light::LightKind;

    /// A scene in a folder holding `m.glb`, a textured triangle with a
    /// camera and a spot light (the fuzz corpus's Blender-like file), with
    /// `camera` and `mesh` written in.
    fn scene_with(camera: &str, mesh: &str) -> Result<crate::files::scene_file::LoadedScene, String> {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.glb"),
            include_bytes!("../../../../../fuzz/corpus/gltf/blender-like.glb"),
        )
        .unwrap();
        let text = format!(
            "Scene(camera: {camera}, image: (width: 32, height: 24), materials: {{ \"grey\": (color: (0.5, 0.5, 0.5)) }}, \
             lights: [Point(position: (0, 5, 0))], objects: [{mesh}])"
        );
        parse_scene(&text, "s.ron", dir.path()).map_err(|e| e.to_string())
    }

    const CAMERA: &str =
        "(position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1)";

    #[test]
    fn a_gltf_files_lights_join_the_scenes_only_when_asked_for() {
        let without = scene_with(CAMERA, "Mesh(file: \"m.glb\")").unwrap();
        assert_eq!(without.scene.lights().len(), 1);
        assert!(
            without
                .scene
                .warnings()
                .iter()
                .any(|w| w.starts_with("m.glb: its 1 KHR_lights_punctual light(s) are not used")),
            "{:?}",
            without.scene.warnings()
        );
        for mesh in
            ["Mesh(file: \"m.glb\", lights: true)", "Mesh(file: \"m.glb\", material: \"grey\", lights: true)"]
        {
            let with = scene_with(CAMERA, mesh).unwrap();
            let lights = with.scene.lights();
            assert_eq!(lights.len(), 2, "{mesh}");
            assert!(matches!(lights[1].kind, LightKind::Spot { .. }), "{mesh}: {lights:?}");
        }
    }

    #[test]
    fn a_gltf_files_cameras_are_called_unused_only_when_the_scene_does_not_take_one() {
        let says = |w: &String| w.starts_with("m.glb: its 1 camera(s) are not used");
        let own = scene_with(CAMERA, "Mesh(file: \"m.glb\")").unwrap();
        assert!(own.scene.warnings().iter().any(says), "{:?}", own.scene.warnings());
        let taken = scene_with("(gltf: \"m.glb\", index: 0)", "Mesh(file: \"m.glb\")").unwrap();
        assert!(!taken.scene.warnings().iter().any(|w| w.contains("camera")), "{:?}", taken.scene.warnings());
    }

    #[test]
    fn the_scenes_camera_can_be_a_gltf_files_camera() {
        let loaded =
            scene_with("(gltf: \"m.glb\", index: 0, scale: 2)", "Mesh(file: \"m.glb\", scale: 2)").unwrap();
        let c = loaded.camera;
        assert!((c.position() - crate::Vec3::new(0.0, 0.0, -10.0)).length() < 1e-4, "{}", c.position());
        assert!((c.near() - 0.2).abs() < 1e-6);
        for (camera, says) in [
            ("(gltf: \"m.glb\", index: 3)", "s.ron: camera: glTF file "),
            ("(gltf: \"gone.glb\")", "gone.glb: cannot open it"),
            (
                "(gltf: \"m.glb\", fov_y: 30)",
                "either described (position, center_of_interest, up, fov_y, near, projection, aperture, \
                 focus_distance) or taken from a glTF file",
            ),
            ("(index: 0)", "missing field named `gltf`"),
            ("(gltf: \"m.glb\", scale: 0)", "camera.scale must be positive, got 0"),
        ] {
            let e = scene_with(camera, "Mesh(file: \"m.glb\")").unwrap_err();
            assert!(e.contains(says), "{camera}: {e}");
        }
        let e = scene_with("(gltf: \"m.glb\", index: 3)", "Mesh(file: \"m.glb\")").unwrap_err();
        assert!(e.ends_with("it has no camera 3 (it has 1)"), "{e}");
    }
}
