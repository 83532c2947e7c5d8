//! A built scene taken apart and put back together without building it
//! again: what a scene cache stores is its [`SceneParts`] and its BVH's
//! arrays.
//!
//! [`Scene::from_parts`] checks what [`super::SceneBuilder::build`] checks of
//! indices (each object's material, each texture slot's texture) and
//! takes the BVH through [`Bvh::from_arrays`], which checks every index of
//! the tree; the emitters and the light sampler, which are cheap, are made
//! again, and the scene put together by the same function as a build's
//! (`Scene::assemble`).

use super::Scene;
use super::parts::{SceneParts, ScenePartsError};
use crate::bvh::Bvh;
use crate::bvh::parts::{BvhArrays, BvhArraysRef};

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
        let (materials, textures, objects) = (&parts.materials, &parts.textures, &parts.objects);
        if materials.len() != parts.material_names.len() {
            return Err(ScenePartsError::Names {
                materials: materials.len(),
                names: parts.material_names.len(),
            });
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
        let emitters = super::emitters_of(objects, materials)
            .map_err(|(index, reason)| ScenePartsError::Emitter { index, reason })?;
        let bvh = Bvh::from_arrays(bvh, objects)?;
        Ok(Scene::assemble(parts, bvh, emitters))
    }
}
