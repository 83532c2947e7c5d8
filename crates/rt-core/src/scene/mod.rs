//! The world: objects and their materials and textures, lights, the
//! environment, the BVH over the objects, and the ray queries over all of
//! them. How it is seen (the camera) and rendered ([`crate::render::settings`]) are
//! values of their own.
//!
//! A scene is made once, by [`crate::files::scene_file`] from a RON file or by a
//! [`SceneBuilder`] in code, and is read-only afterwards: its BVH and the
//! light sampler are built when it is made, from parts that cannot change.
//! A live edit makes a new scene instead ([`Scene::with_material`]), sharing
//! the geometry with the old one.

pub mod effects;

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;

use thiserror::Error;

use crate::bvh::{Bvh, BvhStats, PACKET_RAYS};
use crate::geometry::hit::Hit;
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::lights::emitter::{Emitter, EmitterError};
use crate::lights::environment::Environment;
use crate::lights::light::Light;
use crate::lights::light_sampler::{LightSampler, Source};
use crate::lights::light_source::LightSource;
use crate::materials::material::Material;
use crate::materials::texture::Texture;
use crate::materials::texture_lod::Footprint;
use crate::materials::texture_slot::TextureSlot;
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray, rescale_t};
use crate::math::real::{Real, Vec3, cast_min_t, normalize_robust, scale_pow2};
use crate::scene::effects::{EffectPlan, Effects};

/// A world ready to render, validated and read-only: every part is read
/// through a method.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    environment: Environment,
    lights: Vec<Light>,
    ambient: Color,
    methods: Methods,
    materials: Vec<Material>,
    material_names: Vec<String>,
    textures: Vec<Arc<Texture>>,
    /// Behind `Arc`s, with the BVH and the emitters, so that a copy with
    /// one material replaced ([`Scene::with_material`]) shares the geometry.
    objects: Arc<Vec<Object>>,
    bvh: Arc<Bvh>,
    /// The emissive objects, as lights for global illumination.
    emitters: Arc<Vec<Emitter>>,
    /// Index into `emitters` of each object's emitter.
    emitter_of: Vec<Option<u32>>,
    light_sampler: LightSampler,
    source_files: Vec<PathBuf>,
    warnings: Vec<String>,
}

/// Why a [`SceneBuilder`] cannot make a scene.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SceneBuildError {
    /// Two materials share a name.
    #[error("material \"{0}\" is defined twice")]
    DuplicateMaterial(String),
    /// A material names a texture that was not added.
    #[error("material \"{material}\": texture {texture} does not exist ({count} added)")]
    UnknownTexture {
        /// The material's name.
        material: String,
        /// The texture index it names.
        texture: u32,
        /// How many textures were added.
        count: usize,
    },
    /// An object names a material that was not added.
    #[error("objects[{index}] ({kind}): unknown material \"{name}\" (defined: {defined})")]
    UnknownMaterial {
        /// 0-based object index.
        index: usize,
        /// The object's variant ([`Primitive::kind`]).
        kind: &'static str,
        /// The missing name.
        name: String,
        /// The names that exist, comma-separated.
        defined: String,
    },
    /// An object with a subsurface material has no inside.
    #[error("objects[{index}] ({kind}): material \"{material}\" has a subsurface medium, {reason}")]
    Subsurface {
        /// 0-based object index.
        index: usize,
        /// The object's variant ([`Primitive::kind`]).
        kind: &'static str,
        /// The material's name.
        material: String,
        /// Why it cannot have one.
        reason: String,
    },
    /// An emissive object cannot be a light.
    #[error("objects[{index}] ({kind}): {reason}")]
    Emitter {
        /// 0-based object index.
        index: usize,
        /// The object's variant ([`Primitive::kind`]).
        kind: &'static str,
        /// Why.
        reason: EmitterError,
    },
}

/// Why [`Scene::with_material`] cannot replace a material.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum MaterialEditError {
    /// There is no material of that index.
    #[error("material {index} does not exist ({count} defined)")]
    NoSuchMaterial {
        /// The index asked for.
        index: usize,
        /// How many materials the scene has.
        count: usize,
    },
    /// The new material names a texture the scene does not hold.
    #[error("material {index}: texture {texture} does not exist ({count} in the scene)")]
    UnknownTexture {
        /// The material's index.
        index: usize,
        /// The texture index it names.
        texture: u32,
        /// How many textures the scene holds.
        count: usize,
    },
    /// The emission or the subsurface medium differs: the emitters, the
    /// light sampler and the check that a medium has an inside were built
    /// from them, so the scene must be built again ([`SceneBuilder`]).
    #[error("material {index}: {what} cannot change without building the scene again")]
    NeedsRebuild {
        /// The material's index.
        index: usize,
        /// `"emission"` or `"subsurface"`.
        what: &'static str,
    },
}

impl SceneBuildError {
    /// The error with its object index mapped by `map` (from the built
    /// scene's objects to, say, the entries of the file they came from).
    pub fn with_object_index(self, map: impl Fn(usize) -> usize) -> Self {
        match self {
            Self::UnknownMaterial { index, kind, name, defined } => {
                Self::UnknownMaterial { index: map(index), kind, name, defined }
            }
            Self::Subsurface { index, kind, material, reason } => {
                Self::Subsurface { index: map(index), kind, material, reason }
            }
            Self::Emitter { index, kind, reason } => Self::Emitter { index: map(index), kind, reason },
            other => other,
        }
    }
}

/// Builds a [`Scene`] step by step: any of the background, lights and
/// intersection methods, materials by name and objects that name them, then
/// [`SceneBuilder::build`].
///
/// ```
/// use rt_core::{Material, Primitive, SceneBuilder, Vec3};
/// use rt_core::geometry::sphere::Sphere;
///
/// let scene = SceneBuilder::new()
///     .material("red", Material::flat(glam::Vec3::new(1.0, 0.0, 0.0)))
///     .object(Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap()), "red")
///     .build()
///     .unwrap();
/// assert_eq!(scene.objects().len(), 1);
/// ```
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    environment: Environment,
    lights: Vec<Light>,
    ambient: Color,
    methods: Methods,
    materials: Vec<(String, Material)>,
    textures: Vec<Arc<Texture>>,
    objects: Vec<(Primitive, String)>,
    source_files: Vec<PathBuf>,
    warnings: Vec<String>,
}

impl SceneBuilder {
    /// An empty world: a black environment, no materials, objects or lights,
    /// and the default intersection methods until set otherwise.
    pub fn new() -> Self {
        Self::default()
    }

    /// The colour of rays that hit nothing: a constant environment
    /// ([`Environment::Constant`]).
    pub fn background(self, background: Color) -> Self {
        self.environment(Environment::Constant(background))
    }

    /// The light arriving along rays that leave the scene.
    pub fn environment(self, environment: Environment) -> Self {
        Self { environment, ..self }
    }

    /// Adds a light (point, directional or sphere).
    pub fn light(mut self, light: Light) -> Self {
        self.lights.push(light);
        self
    }

    /// Light reaching every point from everywhere, times the diffuse albedo
    /// (the direct-lighting tracer's ambient term).
    pub fn ambient(self, ambient: Color) -> Self {
        Self { ambient, ..self }
    }

    /// The intersection routines.
    pub fn methods(self, methods: Methods) -> Self {
        Self { methods, ..self }
    }

    /// Adds a material called `name`; materials keep the order they are added in.
    pub fn material(mut self, name: impl Into<String>, material: Material) -> Self {
        self.materials.push((name.into(), material));
        self
    }

    /// Adds an object drawn with the material called `material`; objects
    /// keep the order they are added in (a hit's `object` index).
    pub fn object(mut self, primitive: Primitive, material: impl Into<String>) -> Self {
        self.objects.push((primitive, material.into()));
        self
    }

    /// Records a file the scene was read from besides the scene file (an
    /// OBJ mesh), for whoever watches the scene for changes.
    pub fn source_file(mut self, path: impl Into<PathBuf>) -> Self {
        self.source_files.push(path.into());
        self
    }

    /// Adds a texture; the first is texture 0 ([`TextureSlot::texture`]).
    pub fn texture(mut self, texture: Arc<Texture>) -> Self {
        self.textures.push(texture);
        self
    }

    /// How many textures have been added: the index the next one gets.
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }

    /// Records something the scene's sources hold that the scene does not
    /// use, to be shown to whoever loads it ([`Scene::warnings`]).
    pub fn warning(mut self, warning: impl Into<String>) -> Self {
        self.warnings.push(warning.into());
        self
    }

    /// Checks the parts and builds the scene's BVH.
    pub fn build(self) -> Result<Scene, SceneBuildError> {
        let (material_names, materials): (Vec<String>, Vec<Material>) = self.materials.into_iter().unzip();
        for (i, name) in material_names.iter().enumerate() {
            if material_names[..i].contains(name) {
                return Err(SceneBuildError::DuplicateMaterial(name.clone()));
            }
            if let Some(slot) =
                materials[i].texture_slots().find(|s| s.texture as usize >= self.textures.len())
            {
                let count = self.textures.len();
                return Err(SceneBuildError::UnknownTexture {
                    material: name.clone(),
                    texture: slot.texture,
                    count,
                });
            }
        }
        let objects = self
            .objects
            .into_iter()
            .enumerate()
            .map(|(index, (primitive, name))| match material_names.iter().position(|n| *n == name) {
                Some(material) => Ok(Object { primitive, material }),
                None => Err(SceneBuildError::UnknownMaterial {
                    index,
                    kind: primitive.kind(),
                    name,
                    defined: material_names.join(", "),
                }),
            })
            .collect::<Result<Vec<_>, _>>()?;
        for (index, o) in objects.iter().enumerate() {
            if materials[o.material].subsurface.is_none() {
                continue;
            }
            let reason = match &o.primitive {
                Primitive::Sphere(_) | Primitive::Aabb(_) => None,
                Primitive::Mesh(mesh) => {
                    mesh.closed().err().map(|why| format!("but the mesh is not closed: {why}"))
                }
                other => Some(format!(
                    "but a {} has no inside (only spheres, boxes and closed meshes do)",
                    other.kind()
                )),
            };
            if let Some(reason) = reason {
                let material = material_names[o.material].clone();
                return Err(SceneBuildError::Subsurface {
                    index,
                    kind: o.primitive.kind(),
                    material,
                    reason,
                });
            }
        }
        let mut emitters = Vec::new();
        let mut emitter_of = vec![None; objects.len()];
        for (index, o) in objects.iter().enumerate() {
            let m = &materials[o.material];
            if m.is_emissive() {
                let e = Emitter::new(index, &o.primitive, m.emission)
                    .map_err(|reason| SceneBuildError::Emitter { index, kind: o.primitive.kind(), reason })?;
                emitter_of[index] = Some(emitters.len() as u32);
                emitters.push(e);
            }
        }
        let bvh = Bvh::build(&objects);
        let radius = bvh.bounds().map_or(1.0, |b| (0.5 * b.size().length()).max(1.0));
        let light_sampler = LightSampler::new(&self.lights, &emitters, &self.environment, radius);
        Ok(Scene {
            environment: self.environment,
            lights: self.lights,
            ambient: self.ambient,
            methods: self.methods,
            materials,
            material_names,
            textures: self.textures,
            objects: Arc::new(objects),
            bvh: Arc::new(bvh),
            emitters: Arc::new(emitters),
            emitter_of,
            light_sampler,
            source_files: self.source_files,
            warnings: self.warnings,
        })
    }
}

impl Scene {
    /// Objects in file order: a hit's `object` indexes this list.
    pub fn objects(&self) -> &[Object] {
        &self.objects
    }

    /// The hierarchy over the objects.
    #[cfg(test)]
    pub(crate) fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// The intersection routines the scene is traced with.
    pub fn methods(&self) -> Methods {
        self.methods
    }

    /// The same world traced with other intersection routines (nothing is
    /// rebuilt: the BVH does not depend on them).
    pub fn with_methods(self, methods: Methods) -> Self {
        Self { methods, ..self }
    }

    /// The light arriving along rays that leave the scene.
    #[inline]
    pub fn environment(&self) -> &Environment {
        &self.environment
    }

    /// The point, directional and sphere lights.
    #[inline]
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Light reaching every point from everywhere, times the diffuse albedo.
    #[inline]
    pub fn ambient(&self) -> Color {
        self.ambient
    }

    /// What building the BVH took and produced.
    pub fn bvh_stats(&self) -> BvhStats {
        self.bvh.stats()
    }

    /// The nearest hit over all objects with `t` in `range`; ties keep the
    /// object listed first (and the lower triangle within a mesh). A ray with
    /// a zero or non-finite direction, or a non-finite origin, hits nothing.
    /// The direction may have any magnitude: it is rescaled by a power of two
    /// first ([`Ray::rescaled`]).
    pub fn closest_hit(&self, ray: &Ray, range: Interval) -> Option<Hit> {
        let (unit, range, k) = rescaled_query(ray, range)?;
        self.closest_hit_rescaled(&unit, range, k)
    }

    /// The BVH query on a ray already rescaled by `2ᵏ`, with `t` mapped back.
    fn closest_hit_rescaled(&self, unit: &Ray, range: Interval, k: i32) -> Option<Hit> {
        let mut hit = self.bvh.closest_hit(&self.objects, unit, range, self.methods)?;
        hit.t = rescale_t(hit.t, k)?;
        Some(hit)
    }

    /// The same query by testing every object in order: the reference the
    /// BVH is tested against.
    #[cfg(test)]
    pub(crate) fn closest_hit_brute_force(&self, ray: &Ray, range: Interval) -> Option<Hit> {
        let (unit, mut range, k) = rescaled_query(ray, range)?;
        let mut closest = None;
        for (index, object) in self.objects.iter().enumerate() {
            if let Some(hit) = object.primitive.intersect_with(&unit, range, self.methods) {
                range.max = hit.t;
                closest = Some(Hit::new(index, hit));
            }
        }
        let mut hit: Hit = closest?;
        hit.t = rescale_t(hit.t, k)?;
        Some(hit)
    }

    /// Whether anything is hit with `t` in `range` (for shadow rays).
    pub fn any_hit(&self, ray: &Ray, range: Interval) -> bool {
        rescaled_query(ray, range)
            .is_some_and(|(unit, range, _)| self.bvh.any_hit(&self.objects, &unit, range, self.methods))
    }

    /// The nearest hit of a ray whose history is unknown (a `cast` query or a
    /// primary ray): hits within `2⁻¹⁶·max(1, |origin|∞)` of the origin do not
    /// count ([`crate::math::real::CAST_MIN_DISTANCE_FACTOR`]).
    pub fn cast(&self, ray: &Ray) -> Option<Hit> {
        // Rescale once: the rule's minimum t is computed on the rescaled ray.
        let (unit, k) = ray.rescaled()?;
        self.closest_hit_rescaled(&unit, Interval::new(cast_min_t(unit.origin, unit.dir), Real::INFINITY), k)
    }

    /// [`Scene::cast`] for each of `rays`, into `hits`, with the same
    /// results bit for bit, traced as packets ([`Bvh::closest_hits`]): rays
    /// next to each other in the slice should be close in space and direction,
    /// as a pixel's samples or a run of a row's pixels are.
    pub fn cast_all(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit per ray");
        let mut units = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET_RAYS];
        let mut ranges = [Interval::new(0.0, 0.0); PACKET_RAYS];
        let mut scales = [None; PACKET_RAYS];
        let mut found = [None; PACKET_RAYS];
        for (rays, hits) in rays.chunks(PACKET_RAYS).zip(hits.chunks_mut(PACKET_RAYS)) {
            // Rays that can hit nothing stay out of the packet.
            let mut n = 0;
            for (ray, scale) in rays.iter().zip(&mut scales) {
                *scale = ray.rescaled().map(|(unit, k)| {
                    units[n] = unit;
                    ranges[n] = Interval::new(cast_min_t(unit.origin, unit.dir), Real::INFINITY);
                    n += 1;
                    k
                });
            }
            self.bvh.closest_hits(&self.objects, &units[..n], &ranges[..n], self.methods, &mut found[..n]);
            let mut next = 0;
            for (hit, scale) in hits.iter_mut().zip(&scales) {
                *hit = scale.and_then(|k| {
                    next += 1;
                    let mut h = found[next - 1]?;
                    h.t = rescale_t(h.t, k)?;
                    Some(h)
                });
            }
        }
    }

    /// The range of `t` the cast rule accepts for `ray`: `(min_t, ∞)`.
    pub fn cast_range(&self, ray: &Ray) -> Interval {
        match ray.rescaled() {
            Some((unit, k)) => {
                Interval::new(scale_pow2(cast_min_t(unit.origin, unit.dir), k), Real::INFINITY)
            }
            None => Interval::new(Real::INFINITY, Real::INFINITY),
        }
    }

    /// The colour `hit` (found along `ray`, whose cone is `cone_width` wide
    /// there: [`crate::materials::texture_lod`]) shows without lights: its
    /// material's colour, textured where the surface has texture coordinates.
    pub fn hit_color(&self, hit: &Hit, ray: &Ray, cone_width: f32) -> Color {
        let m = self.object_material(hit.object);
        if m.base_color_texture.is_none() {
            m.color
        } else {
            let cos = normalize_robust(ray.dir).map_or(1.0, |d| d.dot(hit.normal));
            let footprint = Footprint::new(cone_width, cos);
            self.material_at_footprint(hit.object, hit.primitive, ray.at(hit.t), footprint).color
        }
    }

    /// The material of `object` at the point `p` of its `primitive`, its
    /// textures read at their full size ([`Scene::material_at_footprint`]
    /// with a point footprint).
    pub fn material_at(&self, object: usize, primitive: usize, p: Vec3) -> Cow<'_, Material> {
        self.material_at_footprint(object, primitive, p, Footprint::POINT)
    }

    /// The material of `object` at the point `p` of its `primitive`, seen
    /// by a ray whose footprint there is `footprint`: the object's material
    /// with each texture slot read where the surface has the slot's
    /// texture coordinates ([`crate::materials::texture_slot`]), at the
    /// mip-map level the footprint asks for ([`crate::materials::texture_lod`]):
    /// the base colour multiplies `color`, the metallic-roughness texture's
    /// blue and green channels the physically based `metallic` and
    /// `roughness`, the emissive texture `emission`. Borrowed when there is
    /// nothing to change, so an untextured scene pays nothing for textures.
    pub fn material_at_footprint(
        &self,
        object: usize,
        primitive: usize,
        p: Vec3,
        footprint: Footprint,
    ) -> Cow<'_, Material> {
        let o = &self.objects[object];
        let m = &self.materials[o.material];
        if !m.is_textured() {
            return Cow::Borrowed(m);
        }
        let Primitive::Mesh(mesh) = &o.primitive else { return Cow::Borrowed(m) };
        let read = |slot: &Option<TextureSlot>| {
            let slot = slot.as_ref()?;
            let uv = mesh.uv_of_set(primitive, slot.tex_coord, p)?;
            let texture = &self.textures[slot.texture as usize];
            let (w, h) = texture.size();
            let area = mesh.uv_per_world_area(primitive, slot.tex_coord) * slot.transform.area_scale();
            let lod = footprint.level_of_detail(w as f32 * h as f32, area);
            let (u, v) = slot.transformed(uv);
            Some(texture.lookup(u, v, lod, &slot.sampler))
        };
        let (base, metal_rough, emissive) =
            (read(&m.base_color_texture), read(&m.metallic_roughness_texture), read(&m.emissive_texture));
        if base.is_none() && metal_rough.is_none() && emissive.is_none() {
            return Cow::Borrowed(m);
        }
        let mut out = *m;
        if let Some(c) = base {
            out.color *= c;
        }
        if let (Some(c), Some(physical)) = (metal_rough, &mut out.physical) {
            physical.metallic *= c.z;
            physical.roughness *= c.y;
        }
        if let Some(c) = emissive {
            out.emission *= c;
        }
        Cow::Owned(out)
    }

    /// How many textures the scene holds, and their bytes.
    pub fn texture_stats(&self) -> (usize, usize) {
        (self.textures.len(), self.textures.iter().map(|t| t.memory_bytes()).sum())
    }

    /// Texture `index` ([`TextureSlot::texture`]).
    pub fn texture(&self, index: usize) -> &Texture {
        &self.textures[index]
    }

    /// What the scene's sources hold that it does not use (MTL statements
    /// it ignores, missing textures), in a sentence each.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Material `index` ([`Object::material`]).
    pub fn material(&self, index: usize) -> &Material {
        &self.materials[index]
    }

    /// The material of object `object`.
    pub fn object_material(&self, object: usize) -> &Material {
        &self.materials[self.objects[object].material]
    }

    /// All materials, in the order they were defined (a scene file's: sorted by name).
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The materials' names, parallel to [`Scene::materials`].
    pub fn material_names(&self) -> &[String] {
        &self.material_names
    }

    /// The same scene with material `index` replaced by `material`, for a
    /// live edit (the viewer's material panel): the objects, the BVH and
    /// the emitters are shared with `self` (`Arc`s, nothing rebuilt), so
    /// the copy costs the material, light and texture lists. `self` is
    /// left as it was. Refused where what was built from the material
    /// would change: its emission (the emitters and the light sampler)
    /// and its subsurface medium (the check that its objects are closed);
    /// its texture slots must name textures the scene holds.
    pub fn with_material(&self, index: usize, material: Material) -> Result<Scene, MaterialEditError> {
        let count = self.materials.len();
        let old = self.materials.get(index).ok_or(MaterialEditError::NoSuchMaterial { index, count })?;
        if let Some(slot) = material.texture_slots().find(|s| s.texture as usize >= self.textures.len()) {
            let (texture, count) = (slot.texture, self.textures.len());
            return Err(MaterialEditError::UnknownTexture { index, texture, count });
        }
        if material.emission != old.emission {
            return Err(MaterialEditError::NeedsRebuild { index, what: "emission" });
        }
        if material.subsurface != old.subsurface {
            return Err(MaterialEditError::NeedsRebuild { index, what: "subsurface" });
        }
        let mut edited = self.clone();
        edited.materials[index] = material;
        Ok(edited)
    }

    /// The files besides the scene file that the scene was read from (OBJ
    /// meshes), as given to [`SceneBuilder::source_file`].
    pub fn source_files(&self) -> &[PathBuf] {
        &self.source_files
    }

    /// The emissive objects, as lights for global illumination.
    pub fn emitters(&self) -> &[Emitter] {
        &self.emitters
    }

    /// The index in [`Scene::emitters`] of object `object`'s emitter, if it is emissive.
    #[inline]
    pub fn emitter_index(&self, object: usize) -> Option<usize> {
        self.emitter_of.get(object).copied().flatten().map(|i| i as usize)
    }

    /// The light `source` names, through the interface every light shares.
    #[inline]
    pub fn light_source(&self, source: Source) -> LightSource<'_> {
        match source {
            Source::Light(i) => LightSource::Light(&self.lights[i]),
            Source::Emitter(i) => LightSource::Emitter(&self.emitters[i]),
            Source::Environment => LightSource::Environment(&self.environment),
        }
    }

    /// How global illumination chooses among the scene's lights.
    #[inline]
    pub fn light_sampler(&self) -> &LightSampler {
        &self.light_sampler
    }

    /// The rays a render with `effects` casts in this scene: what
    /// `effects` asks for that its lights and the materials its objects use
    /// give something to find ([`EffectPlan::new`]).
    pub fn effect_plan(&self, effects: &Effects) -> EffectPlan {
        EffectPlan::new(
            &self.lights,
            self.ambient,
            effects,
            self.objects.iter().map(|o| &self.materials[o.material]),
        )
    }
}

/// The ray rescaled by `2ᵏ` ([`Ray::rescaled`]), the range of `t` mapped to
/// it, and `k`; `None` for a ray that can hit nothing.
fn rescaled_query(ray: &Ray, range: Interval) -> Option<(Ray, Interval, i32)> {
    let (unit, k) = ray.rescaled()?;
    Some((unit, Interval::new(scale_pow2(range.min, -k), scale_pow2(range.max, -k)), k))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::Sphere;
    use crate::math::real::Vec3;
    use crate::testing::test_support::{primitives_of, random_parts, scene_of, v};
    use proptest::prelude::*;

    #[test]
    fn with_material_renders_the_edit_shares_the_geometry_and_leaves_the_original_untouched() {
        use crate::testing::test_support::{camera_at, renderer_of};
        let sphere = Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap());
        let scene = SceneBuilder::new()
            .material("lamp", Material { emission: Color::ONE, ..Material::flat(Color::ZERO) })
            .material("red", Material::flat(Color::new(0.9, 0.1, 0.1)))
            .object(sphere, "red")
            .build()
            .unwrap();
        let green = Material::flat(Color::new(0.1, 0.9, 0.1));
        let edited = scene.with_material(1, green).unwrap();
        assert_eq!(edited.material(1), &green);
        assert_eq!(scene.material(1).color, Color::new(0.9, 0.1, 0.1), "the original changed");
        assert!(Arc::ptr_eq(&scene.objects, &edited.objects) && Arc::ptr_eq(&scene.bvh, &edited.bvh));
        // Flat colours (no lights): the centre pixel is the material's colour.
        let camera = camera_at(v([0.0, 0.0, -5.0]), Vec3::ZERO, 30.0);
        let centre = |s: &Scene| {
            let frame = renderer_of(s, camera, Effects::default(), (9, 9, 1)).render(|_| {});
            frame.pixels[4 * 9 + 4]
        };
        assert_eq!(centre(&scene), Color::new(0.9, 0.1, 0.1));
        assert_eq!(centre(&edited), Color::new(0.1, 0.9, 0.1));
        // What was built from a material cannot change this way.
        let glowing = Material { emission: Color::ONE, ..green };
        assert_eq!(
            scene.with_material(1, glowing),
            Err(MaterialEditError::NeedsRebuild { index: 1, what: "emission" })
        );
        assert_eq!(
            scene.with_material(2, green),
            Err(MaterialEditError::NoSuchMaterial { index: 2, count: 2 })
        );
        let textured = Material { base_color_texture: Some(TextureSlot::new(0)), ..green };
        assert!(matches!(scene.with_material(1, textured), Err(MaterialEditError::UnknownTexture { .. })));
    }

    #[test]
    fn each_texture_slot_multiplies_its_own_parameter_and_an_untextured_material_is_borrowed() {
        use crate::geometry::mesh::Mesh;
        use crate::materials::principled::Principled;
        use crate::materials::texture_slot::TextureSlot;
        let quad = Mesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
            .unwrap()
            .with_vertex_attributes(vec![], vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
            .unwrap();
        let flat = |c: Color| Arc::new(Texture::new(1, 1, vec![c]).unwrap());
        let p = Principled { metallic: 0.8, roughness: 0.6, ..Principled::DIELECTRIC };
        let textured = Material {
            emission: Color::splat(2.0),
            base_color_texture: Some(TextureSlot::new(0)),
            metallic_roughness_texture: Some(TextureSlot::new(1)),
            emissive_texture: Some(TextureSlot::new(2)),
            occlusion_texture: Some(TextureSlot::new(3)),
            ..Material::principled(Color::splat(0.5), p)
        };
        let scene = SceneBuilder::new()
            .texture(flat(Color::new(1.0, 0.5, 0.25)))
            .texture(flat(Color::new(0.1, 0.5, 0.25)))
            .texture(flat(Color::new(0.5, 1.0, 0.0)))
            .texture(flat(Color::ZERO))
            .material("t", textured)
            .material("plain", Material::principled(Color::splat(0.5), p))
            .object(Primitive::Mesh(quad.clone()), "t")
            .object(Primitive::Mesh(quad), "plain")
            .build()
            .unwrap();
        let at = Vec3::new(0.25, 0.25, 0.0);
        let m = scene.material_at_footprint(0, 0, at, Footprint::new(0.01, 1.0));
        assert_eq!(m.color, Color::new(0.5, 0.25, 0.125));
        let q = m.physical.unwrap();
        // Blue → metallic, green → roughness; red (occlusion's channel) unused.
        assert!((q.metallic - 0.2).abs() < 1e-6 && (q.roughness - 0.3).abs() < 1e-6, "{q:?}");
        assert_eq!(m.emission, Color::new(1.0, 2.0, 0.0));
        // The occlusion texture (all black) changes nothing.
        assert!(matches!(scene.material_at(1, 0, at), Cow::Borrowed(_)));
    }

    proptest! {
        /// Random scenes and rays (including axis-parallel ones with ±0
        /// components): a hit always has a finite t beyond the origin rule, a
        /// unit normal, and a valid object index. No NaN reaches a `cast` row.
        #[test]
        fn random_scenes_never_give_nan_or_broken_hits(
            parts in random_parts(50.0, 8),
            origin in prop::array::uniform3(-60f32..60.0),
            dir in prop::array::uniform3(-1f32..1.0),
            zero_mask in 0u8..8,
            negative_zero in any::<bool>(),
        ) {
            let s = scene_of(primitives_of(parts));
            let mut d = v(dir);
            for axis in 0..3 {
                if zero_mask & (1 << axis) != 0 {
                    d[axis] = if negative_zero { -0.0 } else { 0.0 };
                }
            }
            let ray = Ray::new(v(origin), d);
            if let Some(hit) = s.cast(&ray) {
                prop_assert!(hit.t.is_finite() && hit.t > cast_min_t(ray.origin, ray.dir));
                prop_assert!((hit.normal.length() - 1.0).abs() < 1e-5, "normal {}", hit.normal);
                prop_assert!(hit.object < s.objects().len());
                prop_assert!(ray.at(hit.t).is_finite());
            }
        }
    }

    #[test]
    fn the_first_listed_object_wins_an_exact_tie() {
        let sphere = Primitive::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap());
        let s = scene_of(vec![sphere.clone(), sphere]);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap().object, 0);
    }

    #[test]
    fn direction_magnitude_changes_t_but_not_the_hit() {
        // Unit sphere at z = 5: from the origin along +z the hit is at distance 4.
        let sphere = Primitive::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap());
        let s = scene_of(vec![sphere]);
        for scale in [1e-30 as Real, 1e-20, 1e-3, 1.0, 7.0, 1e15, 1e20, 1e30] {
            let hit = s.cast(&Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, scale)));
            let hit = hit.unwrap_or_else(|| panic!("direction {scale}: miss"));
            assert!((hit.t * scale - 4.0).abs() <= 4.0 * 4.0 * Real::EPSILON, "{scale}: t = {}", hit.t);
            assert_eq!(hit.normal, -Vec3::Z);
        }
    }

    #[test]
    fn zero_and_non_finite_rays_hit_nothing() {
        let sphere = Primitive::Sphere(Sphere::new(Vec3::ZERO, 100.0).unwrap());
        let s = scene_of(vec![sphere]);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::ZERO)), None);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::new(Real::NAN, 0.0, 1.0))), None);
        assert_eq!(s.cast(&Ray::new(Vec3::splat(Real::INFINITY), Vec3::Z)), None);
    }
}
