//! What a ray hit: parameter, object, primitive and normal.

use crate::math::real::{Real, Vec3};

/// A hit on one primitive, before the scene knows which object it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimitiveHit {
    /// Ray parameter of the hit, for the ray's own (not necessarily unit) direction.
    pub t: Real,
    /// Index of the triangle inside a mesh (0-based, file order, faces fanned);
    /// 0 for every other primitive.
    pub primitive: usize,
    /// Unit geometric normal: outward for spheres and boxes, the given `n`
    /// for planes, `normalize((b−a)×(c−a))` for triangles, the winding normal
    /// for polygons. It does not depend on the side the ray came from.
    pub normal: Vec3,
}

/// The closest hit of a ray in a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit, for the ray's own direction.
    pub t: Real,
    /// Index of the object in the scene file's object list (0-based).
    pub object: usize,
    /// See [`PrimitiveHit::primitive`].
    pub primitive: usize,
    /// See [`PrimitiveHit::normal`].
    pub normal: Vec3,
}

impl Hit {
    /// Attach the object index to a primitive-level hit.
    pub fn new(object: usize, hit: PrimitiveHit) -> Self {
        Self { t: hit.t, object, primitive: hit.primitive, normal: hit.normal }
    }
}
