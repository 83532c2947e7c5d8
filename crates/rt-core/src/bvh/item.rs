//! An item of the build: one bounded primitive (a mesh triangle or a whole
//! object) with its box. The build (`bvh/build.rs`) sorts items into
//! leaves, and each leaf (`bvh/leaf.rs`) is filled from its items.

use crate::geometry::aabb::Aabb;
use crate::math::real::{Real, Vec3};

/// A primitive during the build: triangle `index` of the mesh `object`, or
/// the whole object `object` (`whole`, with `index` 0).
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    pub bounds: Aabb,
    pub object: u32,
    pub index: u32,
    pub whole: bool,
}

impl Item {
    /// Triangle `index` of the mesh `object`, with `bounds`.
    pub fn new(bounds: Aabb, object: u32, index: u32) -> Self {
        Self::padded(bounds, object, index, false)
    }

    /// The whole object `object` (any bounded primitive but a mesh), with `bounds`.
    pub fn whole(bounds: Aabb, object: u32) -> Self {
        Self::padded(bounds, object, 0, true)
    }

    fn padded(bounds: Aabb, object: u32, index: u32, whole: bool) -> Self {
        // Widen by a few ulps, so that rounding in a primitive's own bounds
        // can never cut off a hit its intersection routine finds.
        let pad = Vec3::splat(4.0 * Real::EPSILON) * bounds.min().abs().max(bounds.max().abs());
        let bounds = Aabb::from_corners(bounds.min() - pad, bounds.max() + pad);
        Self { bounds, object, index, whole }
    }

    /// The centre of its box (computed when needed: the build moves items
    /// around a lot, and smaller ones move faster).
    #[inline(always)]
    pub fn centroid(&self) -> Vec3 {
        self.bounds.center()
    }
}
