//! One ray's closest-hit query while the tree is traversed: what single
//! rays ([`super::Bvh::closest_hit`]) and packets ([`super::packet`]) both
//! do at a leaf.

use super::leaf::{Lanes, Leaf, lanes_of};
use super::{Bvh, object_primitive};
use crate::hit::Hit;
use crate::method::Methods;
use crate::object::Object;
use crate::primitive::Primitive;
use crate::ray::{Interval, Ray};
use crate::real::{Real, Vec3};
use crate::triangle::TriangleRay;

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
    #[inline(always)]
    pub fn new(ray: &Ray, range: Interval) -> Self {
        Self { prepared: TriangleRay::new(ray), range, best: None }
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
    #[inline(always)]
    fn consider(&mut self, h: Hit) {
        if self
            .best
            .is_none_or(|b| h.t < b.t || (h.t == b.t && (h.object, h.primitive) < (b.object, b.primitive)))
        {
            self.best = Some(h);
        }
    }

    /// Tests the objects without bounds (planes).
    pub fn test_unbounded(&mut self, bvh: &Bvh, objects: &[Object], methods: Methods) {
        for &object in &bvh.unbounded {
            self.test_object(objects, object, methods);
        }
    }

    fn test_object(&mut self, objects: &[Object], object: u32, methods: Methods) {
        if let Some(h) =
            object_primitive(objects, object).intersect_with(&self.prepared.ray, self.within(), methods)
        {
            self.consider(Hit::new(object as usize, h));
        }
    }

    /// Tests the primitives of `leaf`.
    #[inline(always)]
    pub fn test_leaf(&mut self, objects: &[Object], leaf: &Leaf, lanes: Lanes, methods: Methods) {
        let within = self.within();
        let (t, hit) = leaf.intersect_triangles(lanes.triangles(), &self.prepared, within, methods.triangle);
        for lane in lanes_of(hit) {
            let (object, primitive) = (leaf.object(lane) as usize, leaf.index(lane) as usize);
            self.consider(Hit { t: t[lane], object, primitive, normal: Vec3::ZERO });
        }
        for lane in lanes_of(lanes.objects()) {
            self.test_object(objects, leaf.object(lane), methods);
        }
    }

    /// The closest hit, with its normal.
    pub fn finish(self, objects: &[Object]) -> Option<Hit> {
        let mut hit = None;
        self.finish_into(objects, &mut hit);
        hit
    }

    /// [`Query::finish`] into `out`, the normal written straight into its
    /// field: a hit put together on the stack first would be read back in
    /// wider pieces than it was written, which stalls the store-to-load
    /// forwarding (packets finish 64 at a time).
    #[inline(always)]
    pub fn finish_into(&self, objects: &[Object], out: &mut Option<Hit>) {
        *out = self.best;
        if let Some(best) = out
            && let Primitive::Mesh(mesh) = object_primitive(objects, best.object as u32)
        {
            best.normal = mesh.normal(best.primitive);
        }
    }
}
