//! An item of the build: one bounded primitive (a mesh triangle or a whole
//! object) with its box. The build (`bvh/build.rs`) sorts items into
//! leaves, and each leaf (`bvh/leaf.rs`) is filled from its items.
//!
//! The build reads every item once per level of the tree to bin it and
//! once more to partition it, so items are small and aligned: with f32
//! geometry an item is two 16-byte vectors, the box's minimum with the
//! object index in its fourth lane and the maximum with the triangle index
//! (as Embree's `PrimRef` is), each read with one aligned load straight
//! into the vector type the bins use ([`Wide`]).

use crate::geometry::aabb::Aabb;
use crate::math::real::{Real, Vec3};

/// The vector type the build keeps boxes in: with f32 geometry glam's
/// 16-byte `Vec3A`, whose min and max are one SSE instruction each.
#[cfg(not(feature = "f64"))]
pub(super) type Wide = glam::Vec3A;
#[cfg(feature = "f64")]
pub(super) type Wide = Vec3;

/// The `index` that marks a whole object (no mesh has 2³² − 1 triangles).
const WHOLE: u32 = u32::MAX;

/// A primitive during the build: triangle `index` of the mesh `object`, or
/// the whole object `object`.
#[cfg(not(feature = "f64"))]
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    /// The box's minimum; lane w holds the bits of the object index.
    lo: glam::Vec4,
    /// The box's maximum; lane w holds the bits of the triangle index
    /// ([`WHOLE`] for a whole object).
    hi: glam::Vec4,
}

/// A primitive during the build: triangle `index` of the mesh `object`, or
/// the whole object `object`.
#[cfg(feature = "f64")]
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    min: Vec3,
    max: Vec3,
    object: u32,
    /// The triangle index ([`WHOLE`] for a whole object).
    index: u32,
}

impl Item {
    /// Triangle `index` of the mesh `object`, with `bounds`.
    pub fn new(bounds: Aabb, object: u32, index: u32) -> Self {
        debug_assert!(index != WHOLE);
        Self::padded(bounds, object, index)
    }

    /// The whole object `object` (any bounded primitive but a mesh), with `bounds`.
    pub fn whole(bounds: Aabb, object: u32) -> Self {
        Self::padded(bounds, object, WHOLE)
    }

    fn padded(bounds: Aabb, object: u32, index: u32) -> Self {
        // Widen by a few ulps, so that rounding in a primitive's own bounds
        // can never cut off a hit its intersection routine finds.
        let pad = Vec3::splat(4.0 * Real::EPSILON) * bounds.min().abs().max(bounds.max().abs());
        let (min, max) = (bounds.min() - pad, bounds.max() + pad);
        #[cfg(not(feature = "f64"))]
        return Self { lo: min.extend(f32::from_bits(object)), hi: max.extend(f32::from_bits(index)) };
        #[cfg(feature = "f64")]
        return Self { min, max, object, index };
    }

    /// The object: a mesh, or a whole bounded primitive.
    #[inline(always)]
    pub fn object(&self) -> u32 {
        #[cfg(not(feature = "f64"))]
        return self.lo.w.to_bits();
        #[cfg(feature = "f64")]
        return self.object;
    }

    /// The triangle's index in its mesh (0 for a whole object).
    #[inline(always)]
    pub fn index(&self) -> u32 {
        let index = self.raw_index();
        if index == WHOLE { 0 } else { index }
    }

    #[inline(always)]
    fn raw_index(&self) -> u32 {
        #[cfg(not(feature = "f64"))]
        return self.hi.w.to_bits();
        #[cfg(feature = "f64")]
        return self.index;
    }

    /// Whether the item is a whole object rather than a mesh triangle.
    #[inline(always)]
    pub fn is_whole(&self) -> bool {
        self.raw_index() == WHOLE
    }

    /// The box's minimum, as a [`Wide`] vector.
    #[inline(always)]
    pub fn min(&self) -> Wide {
        #[cfg(not(feature = "f64"))]
        return xyz(self.lo);
        #[cfg(feature = "f64")]
        return self.min;
    }

    /// The box's maximum, as a [`Wide`] vector.
    #[inline(always)]
    pub fn max(&self) -> Wide {
        #[cfg(not(feature = "f64"))]
        return xyz(self.hi);
        #[cfg(feature = "f64")]
        return self.max;
    }

    /// The box.
    #[allow(clippy::useless_conversion)] // `Wide` is `Vec3` in the f64 build
    pub fn bounds(&self) -> Aabb {
        Aabb::from_corners(self.min().into(), self.max().into())
    }

    /// The centre of its box, `(min + max) / 2` (the same sum and product as
    /// [`Aabb::center`], so the same bits), computed when needed: the build
    /// moves items around a lot, and smaller ones move faster.
    #[inline(always)]
    pub fn centroid(&self) -> Wide {
        #[cfg(not(feature = "f64"))]
        return 0.5 * (xyz(self.lo) + xyz(self.hi));
        #[cfg(feature = "f64")]
        return 0.5 * (self.min + self.max);
    }
}

/// The first three lanes of `v`, the fourth zeroed (one AND). The indices'
/// bits there read as subnormal floats, and the compiler does arithmetic on
/// all four lanes where it pays (a box's area, say): with subnormals CPUs
/// take a slow path for it, which cost the build a third of its time.
#[cfg(not(feature = "f64"))]
#[inline(always)]
fn xyz(v: glam::Vec4) -> Wide {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{__m128, _mm_and_ps, _mm_castsi128_ps, _mm_set_epi32};
        // SAFETY: SSE and SSE2 are part of every x86-64 CPU.
        Wide::from(unsafe { _mm_and_ps(__m128::from(v), _mm_castsi128_ps(_mm_set_epi32(0, -1, -1, -1))) })
    }
    #[cfg(not(target_arch = "x86_64"))]
    Wide::from(v.truncate())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_item_gives_back_its_object_index_and_padded_box() {
        let b = Aabb::from_corners(Vec3::new(-1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0));
        let t = Item::new(b, 7, 1234);
        assert_eq!((t.object(), t.index(), t.is_whole()), (7, 1234, false));
        let w = Item::whole(b, u32::MAX - 1);
        assert_eq!((w.object(), w.index(), w.is_whole()), (u32::MAX - 1, 0, true));
        for item in [t, w] {
            let got = item.bounds();
            assert!(got.min().cmple(b.min()).all() && got.max().cmpge(b.max()).all());
            assert!((got.min() - b.min()).abs().max_element() < 1e-5);
        }
    }

    #[test]
    fn items_are_two_aligned_vectors() {
        #[cfg(not(feature = "f64"))]
        assert_eq!((size_of::<Item>(), align_of::<Item>()), (32, 16));
    }
}
