//! A built scene taken apart and put back together without building it
//! again: what a scene cache stores is these parts, the meshes with their
//! tangents already made and the BVH already built.
//!
//! [`Scene::from_parts`] checks what [`super::SceneBuilder::build`] checks of
//! indices (each object's material, each texture slot's texture) and
//! takes the BVH through [`Bvh::from_arrays`], which checks every index of
//! the tree; the emitters and the light sampler, which are cheap, are made
//! again exactly as a build makes them.

use std::path::PathBuf;
use std::sync::Arc;

use thiserror::Error;

use super::Scene;
use crate::bvh::Bvh;
use crate::bvh::parts::{BvhArrays, BvhArraysError, BvhArraysRef};
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::lights::emitter::EmitterError;
use crate::lights::environment::Environment;
use crate::lights::light::Light;
use crate::lights::light_sampler::LightSampler;
use crate::materials::material::Material;
use crate::materials::texture::Texture;
use crate::math::color::Color;

/// Everything of a built scene but its BVH, emitters and light sampler.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneParts {
    /// See [`Scene::environment`].
    pub environment: Environment,
    /// See [`Scene::lights`].
    pub lights: Vec<Light>,
    /// See [`Scene::ambient`].
    pub ambient: Color,
    /// See [`Scene::methods`].
    pub methods: Methods,
    /// See [`Scene::materials`].
    pub materials: Vec<Material>,
    /// See [`Scene::material_names`]: one per material.
    pub material_names: Vec<String>,
    /// The decoded textures with their mip-maps.
    pub textures: Vec<Arc<Texture>>,
    /// See [`Scene::objects`]: meshes with their tangents made.
    pub objects: Vec<Object>,
    /// See [`Scene::source_files`].
    pub source_files: Vec<PathBuf>,
    /// See [`Scene::warnings`].
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

impl Scene {
    /// The scene's parts (copies), for a scene cache; with
    /// [`Scene::bvh_arrays`] they are all [`Scene::from_parts`] needs.
    pub fn parts(&self) -> SceneParts {
        SceneParts {
            environment: self.environment.clone(),
            lights: self.lights.clone(),
            ambient: self.ambient,
            methods: self.methods,
            materials: self.materials.clone(),
            material_names: self.material_names.clone(),
            textures: self.textures.clone(),
            objects: self.objects.as_ref().clone(),
            source_files: self.source_files.clone(),
            warnings: self.warnings.clone(),
        }
    }

    /// The scene's hierarchy as plain arrays ([`Bvh::arrays`]).
    pub fn bvh_arrays(&self) -> BvhArrays {
        self.bvh.arrays()
    }

    /// The scene of `parts` with the hierarchy `bvh` (as [`Bvh::arrays`]
    /// gave it), every index checked; equal to the scene the parts came
    /// from but for the BVH's build time.
    pub fn from_parts(parts: SceneParts, bvh: BvhArraysRef<'_>) -> Result<Scene, ScenePartsError> {
        let SceneParts {
            environment,
            lights,
            ambient,
            methods,
            materials,
            material_names,
            textures,
            objects,
            source_files,
            warnings,
        } = parts;
        if materials.len() != material_names.len() {
            return Err(ScenePartsError::Names { materials: materials.len(), names: material_names.len() });
        }
        for (material, m) in materials.iter().enumerate() {
            if let Some(slot) = m.texture_slots().find(|s| s.texture as usize >= textures.len()) {
                let (texture, count) = (slot.texture, textures.len());
                return Err(ScenePartsError::Texture { material, texture, count });
            }
        }
        if let Some((object, o)) = objects.iter().enumerate().find(|(_, o)| o.material >= materials.len()) {
            let (material, count) = (o.material, materials.len());
            return Err(ScenePartsError::Material { object, material, count });
        }
        // As `super::SceneBuilder::build` makes them.
        let (emitters, emitter_of) = super::emitters_of(&objects, &materials)
            .map_err(|(index, reason)| ScenePartsError::Emitter { index, reason })?;
        let bvh = Bvh::from_arrays(bvh, &objects)?;
        let cuts = objects.iter().any(|o| materials[o.material].alpha_mode.cuts());
        let radius = bvh.bounds().map_or(1.0, |b| (0.5 * b.size().length()).max(1.0));
        let light_sampler = LightSampler::new(&lights, &emitters, &environment, radius);
        Ok(Scene {
            environment,
            lights,
            ambient,
            methods,
            materials,
            material_names,
            textures,
            objects: Arc::new(objects),
            bvh: Arc::new(bvh),
            emitters: Arc::new(emitters),
            emitter_of,
            light_sampler,
            source_files,
            warnings,
            cuts,
        })
    }
}
