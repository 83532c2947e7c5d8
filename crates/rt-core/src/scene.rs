//! A loaded, validated scene: camera, image size, background, materials and
//! objects, and the closest-hit query over all of them.

use crate::bvh::{Bvh, BvhStats};
use crate::camera::Camera;
use crate::effects::Lighting;
use crate::hit::Hit;
use crate::material::{Color, ColorSpace, Material};
use crate::method::Methods;
use crate::primitive::Primitive;
use crate::ray::{Interval, Ray, rescale_t};
use crate::real::{Real, cast_min_t, scale_pow2};
use crate::view_plane::{ViewPlane, ViewPlaneError};

/// One entry of the scene file's object list.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Its geometry.
    pub primitive: Primitive,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

/// A scene ready to render. Built by [`crate::scene_file`] from a RON file;
/// every field is already validated. The objects sit behind a BVH built once
/// here, so they can be read ([`Scene::objects`]) but not changed.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The camera.
    pub camera: Camera,
    /// Image width in pixels (from the file; renderers may override it).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Colour of rays that hit nothing.
    pub background: Color,
    /// Samples per pixel; 1 means one ray through each pixel centre.
    pub samples_per_pixel: u32,
    /// Materials, in the file's (sorted by name) order.
    pub materials: Vec<Material>,
    /// Material names, parallel to `materials`.
    pub material_names: Vec<String>,
    /// Lights and effect settings; none by default (pure ray casting).
    pub lighting: Lighting,
    /// How rendered colours are encoded into 8-bit pixels.
    pub color_space: ColorSpace,
    /// The intersection routines (the careful ones by default).
    pub methods: Methods,
    objects: Vec<Object>,
    bvh: Bvh,
}

impl Scene {
    /// A scene from validated parts; builds the BVH over `objects`.
    pub fn new(
        camera: Camera,
        (width, height): (u32, u32),
        background: Color,
        samples_per_pixel: u32,
        materials: Vec<Material>,
        material_names: Vec<String>,
        objects: Vec<Object>,
    ) -> Self {
        let bvh = Bvh::build(&objects);
        Self {
            camera,
            width,
            height,
            background,
            samples_per_pixel,
            materials,
            material_names,
            lighting: Lighting::default(),
            color_space: ColorSpace::default(),
            methods: Methods::default(),
            objects,
            bvh,
        }
    }

    /// The same scene lit by `lighting`.
    pub fn with_lighting(self, lighting: Lighting) -> Self {
        Self { lighting, ..self }
    }

    /// The same scene traced with the intersection routines `methods`.
    pub fn with_methods(self, methods: Methods) -> Self {
        Self { methods, ..self }
    }

    /// Objects in file order: a hit's `object` indexes this list.
    pub fn objects(&self) -> &[Object] {
        &self.objects
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
    pub fn closest_hit_brute_force(&self, ray: &Ray, range: Interval) -> Option<Hit> {
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
    /// count ([`crate::real::CAST_MIN_DISTANCE_FACTOR`]).
    pub fn cast(&self, ray: &Ray) -> Option<Hit> {
        // Rescale once: the rule's minimum t is computed on the rescaled ray.
        let (unit, k) = ray.rescaled()?;
        self.closest_hit_rescaled(&unit, Interval::new(cast_min_t(unit.origin, unit.dir), Real::INFINITY), k)
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

    /// The colour a hit shows: its object's material colour.
    pub fn hit_color(&self, hit: &Hit) -> Color {
        self.materials[self.objects[hit.object].material].color
    }

    /// The view plane of the scene's camera for a `width`×`height` image.
    pub fn view_plane(&self, width: u32, height: u32) -> Result<ViewPlane, ViewPlaneError> {
        ViewPlane::new(self.camera, width, height)
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
    use crate::real::Vec3;
    use crate::sphere::Sphere;
    use crate::test_support::{primitives_of, random_parts, scene_of, v};
    use proptest::prelude::*;

    fn scene(objects: Vec<Object>) -> Scene {
        scene_of(objects.into_iter().map(|o| o.primitive).collect())
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
        let s = scene(vec![
            Object { primitive: sphere.clone(), material: 0 },
            Object { primitive: sphere, material: 0 },
        ]);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::Z)).unwrap().object, 0);
    }

    #[test]
    fn direction_magnitude_changes_t_but_not_the_hit() {
        // Unit sphere at z = 5: from the origin along +z the hit is at distance 4.
        let sphere = Primitive::Sphere(Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap());
        let s = scene(vec![Object { primitive: sphere, material: 0 }]);
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
        let s = scene(vec![Object { primitive: sphere, material: 0 }]);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::ZERO)), None);
        assert_eq!(s.cast(&Ray::new(Vec3::ZERO, Vec3::new(Real::NAN, 0.0, 1.0))), None);
        assert_eq!(s.cast(&Ray::new(Vec3::splat(Real::INFINITY), Vec3::Z)), None);
    }
}
