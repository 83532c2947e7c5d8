//! A scene object: one primitive and the material it is drawn with.

use crate::geometry::primitive::Primitive;

/// One entry of a scene's object list: a hit's `object` index points here.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Its geometry.
    pub primitive: Primitive,
    /// Index into the scene's materials ([`crate::scene::Scene::material`]).
    pub material: usize,
}
