//! Writing a cache: the scene loaded and built as usual, then its parts
//! and arrays stored (see [`super::format`] for the container).

use std::path::{Path, PathBuf};

use anyhow::Context;
use rt_core::camera::Camera;
use rt_core::geometry::aabb::Aabb;
use rt_core::geometry::method::Methods;
use rt_core::lights::environment::Environment;
use rt_core::materials::texture_slot::Wrap;
use rt_core::{Color, Light, LoadedScene, Material, Primitive, Real, RenderSettings};
use serde::{Deserialize, Serialize};

use super::format::{Kind, Writer};
use super::meta::{Meta, Source, modified_ns, this_version};
use crate::content_hash::{Fnv1a128, content_hash, scene_files};

/// The scene's small and irregular parts, stored as CBOR (floats in the
/// smallest width that holds them exactly).
#[derive(Serialize, Deserialize)]
pub(super) struct Small {
    pub environment: Environment,
    pub lights: Vec<Light>,
    pub ambient: Color,
    pub methods: Methods,
    pub materials: Vec<Material>,
    pub material_names: Vec<String>,
    pub source_files: Vec<PathBuf>,
    pub warnings: Vec<String>,
    /// Each object's shape and material index.
    pub objects: Vec<(Shape, usize)>,
    /// What the array sections of each mesh hold.
    pub meshes: Vec<MeshInfo>,
    /// What the array sections of each texture hold.
    pub textures: Vec<TextureInfo>,
    pub bvh_bounds: Option<Aabb>,
    pub sah_cost: f64,
    pub camera: Camera,
    pub settings: RenderSettings,
}

/// An object's shape: a mesh (stored as arrays: its index among the
/// meshes) or any other primitive (in the CBOR).
#[derive(Serialize, Deserialize)]
pub(super) enum Shape {
    Mesh(usize),
    Primitive(Primitive),
}

/// A mesh's sizes; its arrays follow in the file.
#[derive(Serialize, Deserialize)]
pub(super) struct MeshInfo {
    pub bounds: Aabb,
    pub positions: usize,
    pub triangles: usize,
    pub vertex_normals: bool,
    pub uvs: bool,
    pub uvs1: bool,
    pub tangents: bool,
}

/// A texture's wrap and levels (width, height, whether it has alpha).
#[derive(Serialize, Deserialize)]
pub(super) struct TextureInfo {
    pub wrap: [Wrap; 2],
    pub levels: Vec<(u32, u32, bool)>,
}

/// Flattens `values` of `N` numbers each.
fn flat<const N: usize, T: Copy>(values: impl Iterator<Item = [T; N]>) -> Vec<T> {
    values.flatten().collect()
}

/// The cache of `loaded`, read from `scene_file`, as bytes.
pub fn cache_bytes(scene_file: &Path, loaded: &LoadedScene) -> anyhow::Result<Vec<u8>> {
    cache_bytes_as(scene_file, loaded, &this_version())
}

/// [`cache_bytes`] as rt-view `version` would write them.
pub(super) fn cache_bytes_as(
    scene_file: &Path,
    loaded: &LoadedScene,
    version: &str,
) -> anyhow::Result<Vec<u8>> {
    let scene = &loaded.scene;
    let files = scene_files(scene_file, scene);
    let mut sources = Vec::new();
    for file in &files {
        let bytes =
            std::fs::read(file).with_context(|| format!("{}: cannot read to hash it", file.display()))?;
        let mut hash = Fnv1a128::default();
        hash.write(&bytes);
        let path = std::path::absolute(file).unwrap_or_else(|_| file.clone());
        let modified = std::fs::metadata(file).ok().as_ref().and_then(modified_ns);
        sources.push(Source { path, len: bytes.len() as u64, hash: hash.hex(), modified });
    }
    let meta = Meta {
        rt_view_version: version.to_owned(),
        content_hash: content_hash(&files)?,
        scene_file: scene_file.to_owned(),
        sources,
    };
    let parts = scene.parts();
    let bvh = scene.bvh_arrays();
    let mut writer = Writer::default();
    let mut arrays = Writer::default();
    let mut meshes = Vec::new();
    let objects = parts
        .objects
        .iter()
        .map(|o| {
            let shape = match &o.primitive {
                Primitive::Mesh(mesh) => {
                    let a = mesh.arrays();
                    arrays.array::<Real>(&flat(a.positions.iter().map(|p| p.to_array())));
                    arrays.array::<u32>(&flat(a.triangles.iter().copied()));
                    arrays.array::<Real>(&flat(a.normals.iter().map(|p| p.to_array())));
                    arrays.array::<Real>(&flat(a.vertex_normals.iter().map(|p| p.to_array())));
                    arrays.array::<f32>(&flat(a.uvs.iter().copied()));
                    arrays.array::<f32>(&flat(a.uvs1.iter().copied()));
                    arrays.array::<f32>(&flat(a.tangents.iter().copied()));
                    meshes.push(MeshInfo {
                        bounds: a.bounds,
                        positions: a.positions.len(),
                        triangles: a.triangles.len(),
                        vertex_normals: !a.vertex_normals.is_empty(),
                        uvs: !a.uvs.is_empty(),
                        uvs1: !a.uvs1.is_empty(),
                        tangents: !a.tangents.is_empty(),
                    });
                    Shape::Mesh(meshes.len() - 1)
                }
                other => Shape::Primitive(other.clone()),
            };
            (shape, o.material)
        })
        .collect();
    let mut textures = Vec::new();
    for texture in &parts.textures {
        let mut levels = Vec::new();
        for level in texture.levels() {
            arrays.array::<f32>(&flat(level.texels.iter().map(|c| c.to_array())));
            arrays.array::<f32>(level.alpha);
            levels.push((level.width, level.height, !level.alpha.is_empty()));
        }
        textures.push(TextureInfo { wrap: texture.wrap(), levels });
    }
    arrays.array::<Real>(&bvh.node_bounds);
    arrays.array::<u32>(&bvh.node_children);
    arrays.array::<Real>(&bvh.leaf_corners);
    arrays.array::<u32>(&bvh.leaf_ids);
    arrays.array::<u32>(&bvh.unbounded);
    let small = Small {
        environment: parts.environment,
        lights: parts.lights,
        ambient: parts.ambient,
        methods: parts.methods,
        materials: parts.materials,
        material_names: parts.material_names,
        source_files: parts.source_files,
        warnings: parts.warnings,
        objects,
        meshes,
        textures,
        bvh_bounds: bvh.bounds,
        sah_cost: bvh.sah_cost,
        camera: loaded.camera,
        settings: loaded.settings,
    };
    writer.bytes(Kind::Meta, to_ron(&meta)?.into_bytes());
    writer.bytes(Kind::Small, to_cbor(&small)?);
    writer.append(arrays);
    Ok(writer.finish())
}

/// RON text of `value`.
fn to_ron<T: Serialize>(value: &T) -> anyhow::Result<String> {
    ron::to_string(value).map_err(|e| anyhow::anyhow!("cannot write the scene's parts: {e}"))
}

/// CBOR of `value`.
fn to_cbor<T: Serialize>(value: &T) -> anyhow::Result<Vec<u8>> {
    let mut out = Vec::new();
    ciborium::into_writer(value, &mut out)
        .map_err(|e| anyhow::anyhow!("cannot write the scene's parts: {e}"))?;
    Ok(out)
}
