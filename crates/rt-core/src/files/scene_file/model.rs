//! Meshes read from model files into the scene: one object per material
//! part with the file's own materials and textures ([`crate::files::model`]), or
//! one object with the material the scene names.
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
use crate::math::real::{Real, Vec3};
use crate::scene::SceneBuilder;

/// Reads the OBJ or glTF file at `path` (by its extension).
fn load(path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    if is_gltf(path) {
        gltf_model::load(path, scale, translate)
    } else {
        obj_model::load(path, scale, translate)
    }
}

/// Adds the model at `path` (`written` as in the scene file), transformed
/// by `scale` and `translate`, to `scene`: with `material`, as one object
/// of that material; without, one object per part with the file's own
/// materials. Returns the scene and how many objects were added.
pub(super) fn add_model(
    scene: SceneBuilder,
    path: &Path,
    written: &str,
    scale: Real,
    translate: Vec3,
    material: Option<String>,
) -> Result<(SceneBuilder, usize), ModelError> {
    let mut scene = scene.source_file(path);
    if let Some(material) = material {
        let mesh = if is_gltf(path) {
            let (mesh, files) = gltf_model::load_geometry(path, scale, translate)?;
            for file in &files {
                scene = scene.source_file(file);
            }
            mesh
        } else {
            Mesh::load_obj(path, scale, translate)?
        };
        return Ok((scene.object(Primitive::Mesh(mesh), material), 1));
    }
    let model = load(path, scale, translate)?;
    for file in &model.files {
        scene = scene.source_file(file);
    }
    for warning in model.warnings {
        scene = scene.warning(format!("{written}: {warning}"));
    }
    let first_texture = scene.texture_count() as u32;
    for texture in model.textures {
        scene = scene.texture(Arc::new(texture));
    }
    let names: Vec<String> = model.materials.iter().map(|(name, _)| format!("{written}:{name}")).collect();
    for ((_, mut m), name) in model.materials.into_iter().zip(&names) {
        m.texture = m.texture.map(|t| t + first_texture);
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
