//! Models that bring their own materials: an OBJ file with its MTL files
//! ([`crate::files::obj_model`]) or a glTF 2.0 file ([`crate::files::gltf_model`]), read
//! into meshes, materials and textures that a scene can take over.
//!
//! A model is split into **parts**, one [`Mesh`] per material (an OBJ
//! file's in the order it first uses them, a glTF file's in the order of its
//! material list, faces without a material last): a scene makes each part
//! an object of its own. Faces without a material get [`default_material`].
//! What the file holds that rt-view does not use (an MTL statement, a glTF
//! texture other than the base colour, a texture that cannot be read) is
//! named in [`Model::warnings`], never dropped silently.

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::geometry::mesh::{Mesh, MeshError};
use crate::materials::material::Material;
use crate::materials::texture::Texture;
use crate::math::color::Color;

/// A model file's meshes, materials and textures.
#[derive(Debug)]
pub struct Model {
    /// Each part's mesh and the index of its material in `materials`
    /// (`None`: [`default_material`]).
    pub parts: Vec<(Mesh, Option<usize>)>,
    /// The materials, named as in the file; a material's `texture` indexes
    /// `textures`.
    pub materials: Vec<(String, Material)>,
    /// The textures the materials use.
    pub textures: Vec<Texture>,
    /// What the file holds that is not used, a sentence each.
    pub warnings: Vec<String>,
    /// The other files it was read from (MTL files, textures), to watch.
    pub files: Vec<PathBuf>,
    /// How many cameras the file defines (glTF): a scene uses one only where
    /// its camera names the file, so the scene says when they go unused.
    pub cameras: usize,
}

/// Why a model file cannot be used.
#[derive(Debug, Error)]
pub enum ModelError {
    /// The OBJ file cannot be used.
    #[error(transparent)]
    Obj(#[from] MeshError),
    /// An MTL material has a bad value.
    #[error("OBJ file {path}: material \"{material}\": {reason}")]
    Material {
        /// The OBJ file.
        path: PathBuf,
        /// The MTL material's name.
        material: String,
        /// What is wrong, naming the field.
        reason: String,
    },
    /// The glTF file cannot be used.
    #[error("glTF file {path}: {reason}")]
    Gltf {
        /// The glTF file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

/// The material of faces that have none: diffuse grey 0.8 (Blender's default).
pub fn default_material() -> Material {
    Material::flat(Color::splat(0.8))
}

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case) rather
/// than an OBJ file.
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}
