//! A loaded, validated scene: camera, image size, background, materials and
//! objects, and the closest-hit query over all of them.

use crate::camera::Camera;
use crate::hit::Hit;
use crate::material::{Color, Material};
use crate::primitive::Primitive;
use crate::ray::{Interval, Ray};
use crate::real::{Real, cast_min_t};
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
/// every field is already validated.
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
    /// Objects in file order: a hit's `object` indexes this list.
    pub objects: Vec<Object>,
}

impl Scene {
    /// The nearest hit over all objects with `t` in `range`; ties keep the
    /// object listed first. A ray with a zero or non-finite direction, or a
    /// non-finite origin, hits nothing.
    pub fn closest_hit(&self, ray: &Ray, range: Interval) -> Option<Hit> {
        if !(ray.origin.is_finite() && ray.dir.is_finite()) || ray.dir == crate::real::Vec3::ZERO {
            return None;
        }
        let mut range = range;
        let mut closest = None;
        for (index, object) in self.objects.iter().enumerate() {
            if let Some(hit) = object.primitive.intersect(ray, range) {
                range.max = hit.t;
                closest = Some(Hit::new(index, hit));
            }
        }
        closest
    }

    /// The nearest hit of a ray whose history is unknown (a `cast` query or a
    /// primary ray): hits within `2⁻¹⁶·max(1, |origin|∞)` of the origin do not
    /// count ([`crate::real::CAST_MIN_DISTANCE_FACTOR`]).
    pub fn cast(&self, ray: &Ray) -> Option<Hit> {
        let min_t = cast_min_t(ray.origin, ray.dir);
        self.closest_hit(ray, Interval::new(min_t, Real::INFINITY))
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
