//! One ray's closest-hit query while the tree is traversed: what single
//! rays ([`super::Bvh::closest_hit`]) and packets ([`super::packet`]) both
//! do at a leaf.

use super::leaf::{LANES, Lanes, Leaf, lanes_of};
use super::object_block::{self, ObjectBlock};
use crate::geometry::hit::Hit;
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::geometry::triangle::TriangleRay;
use crate::math::ray::Interval;
use crate::math::real::{Real, Vec3};

/// What a leaf test did to the best hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Best {
    /// It stayed what it was.
    Kept,
    /// It is the mesh triangle in this block and lane now.
    Triangle(usize, usize),
    /// It is one of the leaf's whole objects now.
    Object,
}

/// A ray prepared for triangle tests, the range of `t` it accepts, and the
/// closest hit found so far. Triangle hits carry a zero normal until
/// [`Query::finish`]: only the closest one's is looked up.
#[derive(Clone, Copy, Debug)]
pub(super) struct Query {
    pub prepared: TriangleRay,
    pub range: Interval,
    best: Option<Hit>,
}

impl Query {
    /// The query of the ray `prepared` ([`super::Bvh::prepared`]) over `range`.
    #[inline(always)]
    pub fn new(prepared: TriangleRay, range: Interval) -> Self {
        Self { prepared, range, best: None }
    }

    /// The `t` of the best hit so far.
    #[inline(always)]
    pub fn best_t(&self) -> Option<Real> {
        self.best.map(|b| b.t)
    }

    /// The farthest `t` a box may be entered at and still hold a hit that
    /// wins (an entry exactly at the best hit can still win a tie).
    #[inline(always)]
    pub fn t_max(&self) -> Real {
        self.best_t().unwrap_or(self.range.max)
    }

    /// The range a primitive's hit must lie in to be considered: up to and
    /// including the best hit's `t`, so that ties can go to the lower index.
    #[inline(always)]
    fn within(&self) -> Interval {
        Interval::new(self.range.min, self.best.map_or(self.range.max, |b| b.t.next_up()))
    }

    /// Keeps `h` if it is closer than the best so far, or as close with a
    /// lower (object, primitive): the order the in-order loop over all
    /// objects gives, whatever order leaves are visited in.
    /// Whether it was kept.
    #[inline(always)]
    fn consider(&mut self, h: Hit) -> bool {
        let better = self
            .best
            .is_none_or(|b| h.t < b.t || (h.t == b.t && (h.object, h.primitive) < (b.object, b.primitive)));
        if better {
            self.best = Some(h);
        }
        better
    }

    /// Tests the objects without bounds (planes), `unbounded`.
    pub fn test_unbounded(&mut self, unbounded: &[u32], objects: &[Object], methods: Methods) {
        for &object in unbounded {
            self.test_object(objects, object, methods);
        }
    }

    /// Whether it hit and was kept.
    fn test_object(&mut self, objects: &[Object], object: u32, methods: Methods) -> bool {
        object_primitive(objects, object)
            .intersect_with(&self.prepared.ray, self.within(), methods)
            .is_some_and(|h| self.consider(Hit::new(object as usize, h)))
    }

    /// Tests the primitives of a leaf (its `blocks`, with `lanes`); says
    /// which of them, if any, is the best hit now. `AVX2` as in
    /// [`Leaf::intersect_leaf_with`].
    #[inline(always)]
    pub fn test_leaf_with<const AVX2: bool>(
        &mut self,
        objects: &[Object],
        object_blocks: &[ObjectBlock],
        blocks: &[Leaf],
        lanes: Lanes,
        methods: Methods,
    ) -> Best {
        let mut best = Best::Kept;
        // All the triangles at once, then the whole objects: the best hit is
        // the least (t, object, primitive) whatever the order.
        let (t, hit) =
            Leaf::intersect_leaf_with::<AVX2>(blocks, lanes, &self.prepared, self.within(), methods.triangle);
        for i in lanes_of(hit) {
            let (leaf, lane) = (&blocks[i / LANES], i % LANES);
            let (object, primitive) = (leaf.object(lane) as usize, leaf.index(lane) as usize);
            if self.consider(Hit { t: t[i], object, primitive, normal: Vec3::ZERO }) {
                best = Best::Triangle(i / LANES, lane);
            }
        }
        if !lanes.has_objects() {
            return best;
        }
        // The blocks' boxes and polygons four at a time (the same bits as
        // their own tests), all blocks against the same range before any
        // hit is taken, so that their tests do not wait on each other (a
        // wider range than the best so far gives the same best: a farther
        // hit loses anyway); then the other objects one by one.
        let ray = self.prepared.ray;
        let within = self.within();
        let mut found = [None; super::leaf::BLOCKS];
        for (b, leaf) in blocks.iter().enumerate() {
            let whole = lanes.block(b).objects();
            if whole != 0
                && let Some((block, mask)) = object_block::block_of(object_blocks, leaf, whole, methods)
            {
                found[b] = Some((block, mask, block.intersect(mask, &ray, within)));
            }
        }
        for (b, leaf) in blocks.iter().enumerate() {
            let mut scalar = lanes.block(b).objects();
            // Borrowed, not copied out: the copy read the block's result in
            // 16-byte pieces across the narrower stores that had just
            // written it, which the store-to-load forwarding cannot serve.
            if let Some((block, mask, hits)) = &found[b] {
                for lane in lanes_of(hits.hit) {
                    let normal = block.normal(lane, hits, &ray);
                    let object = leaf.object(lane) as usize;
                    if self.consider(Hit { t: hits.t[lane], object, primitive: 0, normal }) {
                        best = Best::Object;
                    }
                }
                scalar &= !*mask;
            }
            for lane in lanes_of(scalar) {
                if self.test_object(objects, leaf.object(lane), methods) {
                    best = Best::Object;
                }
            }
        }
        best
    }

    /// The closest hit, a mesh triangle, with its `normal` (which the
    /// caller computed from the triangle's corners in its leaf).
    pub fn finish_with_normal(self, normal: Vec3) -> Option<Hit> {
        self.best.map(|best| Hit { normal, ..best })
    }

    /// The closest hit, with its normal. A mesh triangle's is written field
    /// by field, each read once from the best hit (copied whole and its
    /// normal set in place, it was read with 16-byte loads across the
    /// narrower stores the last leaf test had just made, a store-to-load
    /// forwarding stall); a whole object's, whose test made its normal, is
    /// the best hit as it is.
    pub fn finish(self, objects: &[Object]) -> Option<Hit> {
        let best = self.best?;
        let Some(normal) = mesh_normal(objects, &best) else { return Some(best) };
        Some(Hit { t: best.t, object: best.object, primitive: best.primitive, normal })
    }

    /// [`Query::finish`] into `out`, the normal written straight into its
    /// field: a hit put together on the stack first would be read back in
    /// wider pieces than it was written, which stalls the store-to-load
    /// forwarding (packets finish 64 at a time).
    #[inline(always)]
    pub fn finish_into(&self, objects: &[Object], out: &mut Option<Hit>) {
        *out = self.best;
        if let Some(best) = out
            && let Some(normal) = mesh_normal(objects, best)
        {
            best.normal = normal;
        }
    }
}

/// The normal of `hit` where it is a mesh triangle: the mesh's own for the
/// triangle (a leaf test leaves it unset); `None` for a whole object, whose
/// test made it.
#[inline(always)]
fn mesh_normal(objects: &[Object], hit: &Hit) -> Option<Vec3> {
    match object_primitive(objects, hit.object as u32) {
        Primitive::Mesh(mesh) => Some(mesh.normal(hit.primitive)),
        _ => None,
    }
}

/// The primitive of object `o`.
pub(super) fn object_primitive(objects: &[Object], o: u32) -> &Primitive {
    &objects[o as usize].primitive
}
