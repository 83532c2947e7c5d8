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
pub mod parts;
mod reassemble;

use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;

use thiserror::Error;

use crate::bvh::{Bvh, BvhStats, PACKET_RAYS, Rays};
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
use crate::scene::parts::SceneParts;

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
    /// Whether an object's material cuts holes by alpha
    /// ([`crate::materials::alpha`]): only then do ray queries look at
    /// alpha, so opaque scenes pay one flag test per query.
    cuts: bool,
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
                Some(material) => {
                    Ok(Object { primitive: with_tangents(primitive, &materials[material]), material })
                }
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
        let mut warnings = self.warnings;
        for (index, o) in objects.iter().enumerate() {
            let Some(slot) = materials[o.material].normal_texture else { continue };
            let uvs = matches!(&o.primitive, Primitive::Mesh(mesh) if mesh.has_uv_set(slot.tex_coord));
            if !uvs {
                warnings.push(format!(
                    "material \"{}\": normal_texture is not used on objects[{index}] ({}): it has no texture \
                     coordinates",
                    material_names[o.material],
                    o.primitive.kind()
                ));
            }
        }
        let emitters = emitters_of(&objects, &materials).map_err(|(index, reason)| {
            SceneBuildError::Emitter { index, kind: objects[index].primitive.kind(), reason }
        })?;
        let bvh = Bvh::build(&objects);
        let parts = SceneParts {
            environment: self.environment,
            lights: self.lights,
            ambient: self.ambient,
            methods: self.methods,
            materials,
            material_names,
            textures: self.textures,
            objects,
            source_files: self.source_files,
            warnings,
        };
        Ok(Scene::assemble(parts, bvh, emitters))
    }
}

impl Scene {
    /// The scene of checked `parts`, the hierarchy over their objects and
    /// their emitters ([`emitters_of`]): what is derived from the parts
    /// (whether any material cuts holes, the light sampler, sized by the
    /// radius of the scene's bounds, at least 1) is made here, for a build
    /// and a scene cache alike.
    fn assemble(parts: SceneParts, bvh: Bvh, (emitters, emitter_of): Emitters) -> Scene {
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
        let cuts = objects.iter().any(|o| materials[o.material].alpha_mode.cuts());
        let radius = bvh.bounds().map_or(1.0, |b| (0.5 * b.size().length()).max(1.0));
        let light_sampler = LightSampler::new(&lights, &emitters, &environment, radius);
        Scene {
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
        }
    }
}

/// `primitive` with MikkTSpace tangents where it is a mesh lacking them
/// and `material` has a normal map, from the map's texture-coordinate set
/// ([`crate::geometry::mesh::Mesh::with_generated_tangents_of_set`]).
fn with_tangents(primitive: Primitive, material: &Material) -> Primitive {
    match primitive {
        Primitive::Mesh(mesh) => match &material.normal_texture {
            Some(slot) => Primitive::Mesh(mesh.with_generated_tangents_of_set(slot.tex_coord)),
            None => Primitive::Mesh(mesh),
        },
        other => other,
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
    /// object listed first (and the lower triangle within a mesh). Points
    /// that alpha cuts out ([`crate::materials::alpha`]) are not hit: the
    /// ray goes on through them, for every query alike. A ray with
    /// a zero or non-finite direction, or a non-finite origin, hits nothing.
    /// The direction may have any magnitude: it is rescaled by a power of two
    /// first ([`Ray::rescaled`]).
    pub fn closest_hit(&self, ray: &Ray, range: Interval) -> Option<Hit> {
        let (unit, range, k) = rescaled_query(ray, range)?;
        self.closest_hit_rescaled(&unit, range, k, Rays::Alone)
    }

    /// The BVH query on a ray already rescaled by `2ᵏ` that comes as `rays`
    /// say, with `t` mapped back. Inlined into its callers, so that a single
    /// ray's set-up (rescaling, the range) runs in one function up to the
    /// BVH's.
    #[inline(always)]
    fn closest_hit_rescaled(&self, unit: &Ray, range: Interval, k: i32, rays: Rays) -> Option<Hit> {
        let found = self.bvh.closest_hit_among(&self.objects, unit, range, self.methods, rays)?;
        if self.cuts && self.cut_out(unit, &found) {
            let hit = self.closest_past_cut_outs(unit, Interval::new(found.t, range.max))?;
            return rescaled_hit(&hit, k);
        }
        rescaled_hit(&found, k)
    }

    /// The nearest hit on `unit` (rescaled) in `range` that alpha does not
    /// cut out: the same query again past each cut-out point, on the exact
    /// same ray, from the `t` of the point (the range is open, so that
    /// triangle is not found again, and every surface behind it is). A
    /// surface at exactly the same `t` as a cut-out point that loses the
    /// tie to it (coincident geometry) is skipped with it.
    fn closest_past_cut_outs(&self, unit: &Ray, mut range: Interval) -> Option<Hit> {
        loop {
            let hit = self.bvh.closest_hit(&self.objects, unit, range, self.methods)?;
            if !self.cut_out(unit, &hit) {
                return Some(hit);
            }
            range.min = hit.t;
        }
    }

    /// Whether alpha removes the point `hit` of the ray `ray` (the rescaled
    /// ray of the query, so a packet and a single ray decide alike): its
    /// material's [`crate::materials::alpha::AlphaMode`] applied to the alpha there.
    fn cut_out(&self, ray: &Ray, hit: &Hit) -> bool {
        let m = self.object_material(hit.object);
        if !m.alpha_mode.cuts() {
            return false;
        }
        let alpha = self.alpha_at(hit.object, hit.primitive, ray.at(hit.t));
        !m.alpha_mode.is_there(alpha, || {
            crate::materials::alpha::blend_coin(ray.origin, ray.dir, hit.t, hit.object, hit.primitive)
        })
    }

    /// The alpha of `object` at the point `p` of its `primitive`, read at
    /// the full-size image (a ray query carries no cone): its material's
    /// factor times its base colour slot's alpha where the surface has the
    /// slot's texture coordinates ([`Scene::alpha_at_footprint`]).
    pub fn alpha_at(&self, object: usize, primitive: usize, p: Vec3) -> f32 {
        self.alpha_at_footprint(object, primitive, p, Footprint::POINT)
    }

    /// The alpha of `object` at `p` for a ray of footprint `footprint`: the
    /// material's `alpha` (glTF's `baseColorFactor[3]`) times the base
    /// colour texture's alpha, read through the base colour slot (its
    /// coordinate set, transform and sampler) at the level of detail the
    /// base colour is read at; the factor alone without a base colour
    /// texture or texture coordinates.
    pub fn alpha_at_footprint(&self, object: usize, primitive: usize, p: Vec3, footprint: Footprint) -> f32 {
        let o = &self.objects[object];
        let m = &self.materials[o.material];
        let texture_alpha = m.base_color_texture.as_ref().and_then(|slot| {
            let Primitive::Mesh(mesh) = &o.primitive else { return None };
            self.slot_read(mesh, primitive, slot, p, footprint, |t, u, v, lod, s| {
                t.lookup_alpha(u, v, lod, s)
            })
        });
        m.alpha * texture_alpha.unwrap_or(1.0)
    }

    /// The texel of `object`'s normal map at `p` for a ray of footprint
    /// `footprint` (linear, not yet a normal: [`crate::materials::normal_map`]),
    /// with the slot's scale; `None` without a normal map or texture
    /// coordinates in the slot's set.
    #[inline]
    pub fn normal_texel_at(
        &self,
        object: usize,
        primitive: usize,
        p: Vec3,
        footprint: Footprint,
    ) -> Option<(Color, f32)> {
        // The test inline at every hit, the read out of line.
        let o = &self.objects[object];
        let slot = self.materials[o.material].normal_texture.as_ref()?;
        self.read_normal_texel(o, slot, primitive, p, footprint)
    }

    /// [`Scene::normal_texel_at`] for a material with a normal map.
    #[inline(never)]
    fn read_normal_texel(
        &self,
        o: &Object,
        slot: &TextureSlot,
        primitive: usize,
        p: Vec3,
        footprint: Footprint,
    ) -> Option<(Color, f32)> {
        let Primitive::Mesh(mesh) = &o.primitive else { return None };
        let texel =
            self.slot_read(mesh, primitive, slot, p, footprint, |t, u, v, lod, s| t.lookup(u, v, lod, s))?;
        Some((texel, slot.scale))
    }

    /// `read` applied to `slot`'s texture at the point `p` of `mesh`'s
    /// triangle `primitive`: at the slot's transformed coordinates, with its
    /// sampler, at the level of detail `footprint` asks for
    /// ([`crate::materials::texture_lod`]); `None` where the mesh lacks the
    /// slot's coordinate set.
    #[inline]
    fn slot_read<T>(
        &self,
        mesh: &crate::geometry::mesh::Mesh,
        primitive: usize,
        slot: &TextureSlot,
        p: Vec3,
        footprint: Footprint,
        read: impl Fn(&Texture, Real, Real, f32, &crate::materials::texture_slot::Sampler) -> T,
    ) -> Option<T> {
        let uv = mesh.uv_of_set(primitive, slot.tex_coord, p)?;
        let texture = &self.textures[slot.texture as usize];
        let (w, h) = texture.size();
        let area = mesh.uv_per_world_area(primitive, slot.tex_coord) * slot.transform.area_scale();
        let lod = footprint.level_of_detail(w as f32 * h as f32, area);
        let (u, v) = slot.transformed(uv);
        Some(read(texture, u, v, lod, &slot.sampler))
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

    /// Whether anything is hit with `t` in `range` (for shadow rays); a
    /// point alpha cuts out is not ([`Scene::closest_hit`]).
    pub fn any_hit(&self, ray: &Ray, range: Interval) -> bool {
        // The rescaled ray made where the query reads it: handed on through
        // `rescaled_query`'s tuple, it was copied with 16-byte loads across
        // the narrower stores that had just written it (a store-to-load
        // forwarding stall, a third of this function's samples).
        let Some((unit, k)) = ray.rescaled() else { return false };
        let range = rescaled_range(range, k);
        self.bvh.any_hit(&self.objects, &unit, range, self.methods)
            && (!self.cuts || self.closest_past_cut_outs(&unit, range).is_some())
    }

    /// The nearest hit of a ray whose history is unknown (a `cast` query or a
    /// primary ray): hits within `2⁻¹⁶·max(1, |origin|∞)` of the origin do not
    /// count ([`crate::math::real::CAST_MIN_DISTANCE_FACTOR`]). Such rays come
    /// in runs of neighbours (a row's pixels), so a mesh triangle's normal is
    /// read from the mesh's list ([`Rays::InARun`]), as a packet's are
    /// ([`Scene::cast_all`]); the hit is the same either way.
    pub fn cast(&self, ray: &Ray) -> Option<Hit> {
        // Rescale once: the rule's minimum t is computed on the rescaled ray.
        let (unit, k) = ray.rescaled()?;
        self.closest_hit_rescaled(
            &unit,
            Interval::new(cast_min_t(unit.origin, unit.dir), Real::INFINITY),
            k,
            Rays::InARun,
        )
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
                    if self.cuts && self.cut_out(&units[next - 1], &h) {
                        let range = Interval::new(h.t, ranges[next - 1].max);
                        h = self.closest_past_cut_outs(&units[next - 1], range)?;
                    }
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
        match self.textured_material(object, primitive, p, footprint) {
            Some(textured) => Cow::Owned(textured),
            None => Cow::Borrowed(self.object_material(object)),
        }
    }

    /// [`Scene::material_at_footprint`] where a texture changes the
    /// material; `None` where the object's own material is the answer (no
    /// texture, or none read here).
    #[inline]
    pub fn textured_material(
        &self,
        object: usize,
        primitive: usize,
        p: Vec3,
        footprint: Footprint,
    ) -> Option<Material> {
        // The test inline at every hit, the reads out of line: most
        // materials have no texture.
        let o = &self.objects[object];
        let m = &self.materials[o.material];
        if !m.is_textured() {
            return None;
        }
        self.read_material_textures(o, m, primitive, p, footprint)
    }

    /// [`Scene::textured_material`] for a material with a texture.
    #[inline(never)]
    fn read_material_textures(
        &self,
        o: &Object,
        m: &Material,
        primitive: usize,
        p: Vec3,
        footprint: Footprint,
    ) -> Option<Material> {
        let Primitive::Mesh(mesh) = &o.primitive else { return None };
        let read = |slot: &Option<TextureSlot>| {
            self.slot_read(mesh, primitive, slot.as_ref()?, p, footprint, |t, u, v, lod, s| {
                t.lookup(u, v, lod, s)
            })
        };
        let (base, metal_rough, emissive) =
            (read(&m.base_color_texture), read(&m.metallic_roughness_texture), read(&m.emissive_texture));
        if base.is_none() && metal_rough.is_none() && emissive.is_none() {
            return None;
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
        Some(out)
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

/// `hit` of a ray rescaled by `2⁻ᵏ`, its `t` mapped back to the ray's
/// own scale; `None` where that `t` is not finite. Written field by field
/// from the hit the tree wrote: copied whole, or with `t` set in place,
/// the hit was read back with 16-byte loads across the narrower stores
/// that had just written it, a stall the store-to-load forwarding cannot
/// serve (`docs/performance.md`).
#[inline(always)]
fn rescaled_hit(hit: &Hit, k: i32) -> Option<Hit> {
    let t = rescale_t(hit.t, k)?;
    Some(Hit { t, object: hit.object, primitive: hit.primitive, normal: hit.normal })
}

/// The ray rescaled by `2ᵏ` ([`Ray::rescaled`]), the range of `t` mapped to
/// it, and `k`; `None` for a ray that can hit nothing.
#[inline(always)]
fn rescaled_query(ray: &Ray, range: Interval) -> Option<(Ray, Interval, i32)> {
    let (unit, k) = ray.rescaled()?;
    Some((unit, rescaled_range(range, k), k))
}

/// The range of `t` of a ray mapped to the ray rescaled by `2ᵏ` (exact:
/// both ends scaled by `2⁻ᵏ`).
#[inline(always)]
fn rescaled_range(range: Interval, k: i32) -> Interval {
    Interval::new(scale_pow2(range.min, -k), scale_pow2(range.max, -k))
}

/// A scene's emitters and, for each object, the index of its emitter.
pub(crate) type Emitters = (Vec<Emitter>, Vec<Option<u32>>);

/// The emitters of the objects whose material emits, in object order, and
/// for each object the index of its emitter (`None` where it emits
/// nothing); on an object that cannot emit, its index and why.
pub(crate) fn emitters_of(
    objects: &[Object],
    materials: &[Material],
) -> Result<Emitters, (usize, EmitterError)> {
    let mut emitters = Vec::new();
    let mut emitter_of = vec![None; objects.len()];
    for (index, o) in objects.iter().enumerate() {
        let m = &materials[o.material];
        if m.is_emissive() {
            let e = Emitter::new(index, &o.primitive, m.emission).map_err(|reason| (index, reason))?;
            emitter_of[index] = Some(emitters.len() as u32);
            emitters.push(e);
        }
    }
    Ok((emitters, emitter_of))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sphere::Sphere;
    use crate::materials::texture::Texture;
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
        assert_eq!(scene.textured_material(0, 0, at, Footprint::new(0.01, 1.0)), Some(*m));
        // The occlusion texture (all black) changes nothing.
        assert!(matches!(scene.material_at(1, 0, at), Cow::Borrowed(_)));
        assert_eq!(scene.textured_material(1, 0, at, Footprint::POINT), None);
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

    /// A square of side 2 in the plane z = `z`, centred on the z axis,
    /// facing −z, with texture coordinates spanning [0, 1]² (u along +x).
    fn square(z: Real) -> Primitive {
        Primitive::Mesh(crate::testing::test_support::textured_square(z))
    }

    /// A square at z = 0 cut by `mode` with alpha from an n×n checkerboard
    /// of alpha 0 and `alpha` (top-left texel 0), times the factor 1, and
    /// an opaque square just behind it at z = 10⁻³.
    fn cut_square(mode: AlphaMode, n: u32, alpha: f32) -> Scene {
        let texels = vec![Color::ONE; (n * n) as usize];
        let checker =
            (0..n * n).map(|k| if (k % n + k / n).is_multiple_of(2) { 0.0 } else { alpha }).collect();
        let texture = Texture::new(n, n, texels).unwrap().with_alpha(checker).unwrap();
        let cut = Material {
            base_color_texture: Some(TextureSlot::new(0)),
            alpha_mode: mode,
            ..Material::flat(Color::ONE)
        };
        SceneBuilder::new()
            .texture(Arc::new(texture))
            .material("cut", cut)
            .material("wall", Material::flat(Color::splat(0.5)))
            .object(square(0.0), "cut")
            .object(square(1e-3), "wall")
            .build()
            .unwrap()
    }

    use crate::materials::alpha::AlphaMode;

    #[test]
    fn rays_go_through_what_a_mask_cuts_out_and_stop_where_it_does_not() {
        // 2×2 checker: the texel centres at (±0.5, ±0.5) have alpha 0
        // top-left and bottom-right, 1 in the other two.
        let s = cut_square(AlphaMode::Mask { cutoff: 0.5 }, 2, 1.0);
        let ray = |x: Real, y: Real| Ray::new(Vec3::new(x, y, -2.0), Vec3::Z);
        let all = Interval::new(0.0, Real::INFINITY);
        let cases = [(-0.5, 0.5, 1), (0.5, -0.5, 1), (0.5, 0.5, 0), (-0.5, -0.5, 0)];
        let rays: Vec<Ray> = cases.iter().map(|&(x, y, _)| ray(x, y)).collect();
        let mut packet = vec![None; rays.len()];
        s.cast_all(&rays, &mut packet);
        for (&(x, y, object), from_packet) in cases.iter().zip(packet) {
            let hit = s.cast(&ray(x, y)).unwrap();
            assert_eq!(hit.object, object, "({x}, {y})");
            assert_eq!(Some(hit), from_packet, "a packet finds what a single ray finds");
            assert_eq!(s.closest_hit(&ray(x, y), all).unwrap().object, object);
            // A shadow ray that ends before the wall is blocked only by the
            // part that is there.
            assert_eq!(s.any_hit(&ray(x, y), Interval::new(0.0, 2.0005)), object == 0, "({x}, {y})");
            assert!(s.any_hit(&ray(x, y), all));
        }
        // Opaque, the same square stops every ray.
        let opaque = cut_square(AlphaMode::Opaque, 2, 1.0);
        assert!(cases.iter().all(|&(x, y, _)| opaque.cast(&ray(x, y)).unwrap().object == 0));
    }

    #[test]
    fn alpha_is_read_through_the_base_colour_slot_its_transform_and_its_factor() {
        // 2×2 checker: alpha 0 at the top-left texel centre (u, v) = (¼, ¼),
        // 1 at (¾, ¼). The point (−0.5, 0.5) is (u, v) = (¼, ¼).
        let s = cut_square(AlphaMode::Mask { cutoff: 0.5 }, 2, 1.0);
        let p = Vec3::new(-0.5, 0.5, 0.0);
        assert_eq!(s.alpha_at(0, 0, p) + s.alpha_at(0, 1, p), 0.0);
        // Offset by half the image in u: the same point reads the opaque texel.
        let mut m = s.materials[0];
        let slot = m.base_color_texture.unwrap();
        let transform =
            crate::materials::texture_slot::UvTransform::new([0.5, 0.0], 0.0, [1.0, 1.0]).unwrap();
        m.base_color_texture = Some(TextureSlot { transform, ..slot });
        m.alpha = 0.5;
        let shifted = SceneBuilder::new()
            .texture(Arc::new(s.textures[0].as_ref().clone()))
            .material("cut", m)
            .object(square(0.0), "cut")
            .build()
            .unwrap();
        let (a, b) = (shifted.alpha_at(0, 0, p), shifted.alpha_at(0, 1, p));
        assert_eq!(a.max(b), 0.5, "texel alpha 1 times the factor 0.5");
        // Seen from afar (a wide footprint), alpha is the mip-mapped mean, as
        // the base colour is.
        let far = crate::materials::texture_lod::Footprint::new(1e3, 1.0);
        assert!((s.alpha_at_footprint(0, 0, p, far) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn the_normal_map_is_read_through_its_slot_at_the_footprints_level_of_detail() {
        // 2×2 normal map: left column tilted to +x, right column to −x.
        let (a, b) = (Color::new(0.9, 0.5, 0.6), Color::new(0.1, 0.5, 0.6));
        let map = Texture::new(2, 2, vec![a, b, a, b]).unwrap();
        let slot = TextureSlot { scale: 0.5, ..TextureSlot::new(0) };
        let s = SceneBuilder::new()
            .texture(Arc::new(map))
            .material("n", Material { normal_texture: Some(slot), ..Material::flat(Color::ONE) })
            .object(square(0.0), "n")
            .build()
            .unwrap();
        let p = Vec3::new(-0.5, 0.5, 0.0);
        let at = |footprint| (0..2).find_map(|t| s.normal_texel_at(0, t, p, footprint)).unwrap();
        assert_eq!(at(Footprint::POINT), (a, 0.5));
        // From afar, the mip-mapped mean: the tilts cancel.
        let (far, scale) = at(Footprint::new(1e3, 1.0));
        assert!((far - (a + b) * 0.5).abs().max_element() < 1e-6 && scale == 0.5, "{far}");
    }

    /// The share of `n`×`n` rays along +z, spread over the square, that
    /// pass the cut square and stop at z = 5·10⁻⁴ (shadow rays).
    fn share_through(s: &Scene, n: u32) -> f64 {
        let mut through = 0;
        for i in 0..n {
            for j in 0..n {
                let (x, y) =
                    ((i as Real + 0.5) / n as Real * 2.0 - 1.0, (j as Real + 0.5) / n as Real * 2.0 - 1.0);
                let ray = Ray::new(Vec3::new(x, y, -1.0), Vec3::Z);
                through += usize::from(!s.any_hit(&ray, Interval::new(0.0, 1.0005)));
            }
        }
        through as f64 / f64::from(n * n)
    }

    #[test]
    fn a_checkerboard_mask_lets_half_the_light_through_and_blend_lets_one_minus_alpha() {
        // 8×8 texels filtered bilinearly: alpha ≥ 0.5 on exactly half the
        // area by symmetry; 400×400 shadow rays measure it.
        let mask = cut_square(AlphaMode::Mask { cutoff: 0.5 }, 8, 1.0);
        let share = share_through(&mask, 400);
        assert!((share - 0.5).abs() < 0.01, "{share}");
        // BLEND with alpha ¼ on a 1×1 texture: three rays in four pass.
        let blend = cut_square(AlphaMode::Blend, 1, 0.25);
        let blend = Scene {
            materials: vec![
                Material { alpha: 0.25, base_color_texture: None, ..blend.materials[0] },
                blend.materials[1],
            ],
            ..blend
        };
        let share = share_through(&blend, 200);
        assert!((share - 0.75).abs() < 0.015, "{share}");
        assert_eq!(share_through(&cut_square(AlphaMode::Opaque, 8, 1.0), 50), 0.0);
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
