//! A scene's parts: everything a built scene holds but what is made from
//! the others (its BVH, emitters and light sampler). A build puts them
//! together ([`super::SceneBuilder::build`]); a scene cache stores them, the
//! meshes with their tangents already made, and puts them back together
//! with the BVH it stored ([`super::Scene::from_parts`], in
//! `reassemble.rs`).

use std::path::PathBuf;
use std::sync::Arc;

use thiserror::Error;

use crate::bvh::parts::BvhArraysError;
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::lights::emitter::EmitterError;
use crate::lights::environment::Environment;
use crate::lights::light::Light;
use crate::materials::material::Material;
use crate::materials::texture::Texture;
use crate::math::color::Color;

/// Everything of a built scene but its BVH, emitters and light sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneParts {
    /// See [`super::Scene::environment`].
    pub environment: Environment,
    /// See [`super::Scene::lights`].
    pub lights: Vec<Light>,
    /// See [`super::Scene::ambient`].
    pub ambient: Color,
    /// See [`super::Scene::methods`].
    pub methods: Methods,
    /// See [`super::Scene::materials`].
    pub materials: Vec<Material>,
    /// See [`super::Scene::material_names`]: one per material.
    pub material_names: Vec<String>,
    /// The decoded textures with their mip-maps.
    pub textures: Vec<Arc<Texture>>,
    /// See [`super::Scene::objects`]: meshes with their tangents made.
    pub objects: Vec<Object>,
    /// See [`super::Scene::source_files`].
    pub source_files: Vec<PathBuf>,
    /// See [`super::Scene::warnings`].
    pub warnings: Vec<String>,
}

/// Why parts do not make a scene.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ScenePartsError {
    /// Material names and materials differ in number.
    #[error("{materials} materials but {names} material names")]
    Names {
        /// Materials.
        materials: usize,
        /// Names.
        names: usize,
    },
    /// An object's material index is not a material.
    #[error("objects[{object}]: material {material}, but there are {count}")]
    Material {
        /// The object.
        object: usize,
        /// Its material index.
        material: usize,
        /// Materials in the scene.
        count: usize,
    },
    /// A material's texture slot names a texture that is not there.
    #[error("material {material}: texture {texture}, but there are {count}")]
    Texture {
        /// The material's index.
        material: usize,
        /// The texture index.
        texture: u32,
        /// Textures in the scene.
        count: usize,
    },
    /// An emissive object cannot be a light.
    #[error("objects[{index}]: {reason}")]
    Emitter {
        /// The object.
        index: usize,
        /// Why.
        reason: EmitterError,
    },
    /// The BVH's arrays do not make a tree over the objects.
    #[error(transparent)]
    Bvh(#[from] BvhArraysError),
}
