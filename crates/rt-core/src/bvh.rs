//! A bounding volume hierarchy over every bounded primitive of a scene.
//!
//! Mesh triangles are flattened into it one by one; planes, which have no
//! bounds, are kept aside and tested directly. The tree is built once per
//! scene load with the binned surface-area heuristic (Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies", 2007) and stored
//! as 32-byte nodes (with f32 geometry) whose two children are adjacent.
//! Traversal visits the nearer child first and skips subtrees that start
//! beyond the closest hit so far.
//!
//! Results equal the brute-force loop over all objects bit for bit: the same
//! primitive functions compute each `t`, and exact ties go to the lower
//! (object, primitive) index, as the in-order loop gives them.

use std::time::{Duration, Instant};

use crate::aabb::Aabb;
use crate::hit::{Hit, PrimitiveHit};
use crate::method::Methods;
use crate::primitive::Primitive;
use crate::ray::{Interval, Ray};
use crate::real::{Real, Vec3, gamma};
use crate::scene::Object;

/// Leaves hold at most this many primitives unless their centroids coincide.
const MAX_LEAF: usize = 4;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this depth the SAH chooses splits; from here on, splits are at the
/// median, so the depth stays under [`STACK`].
const SAH_DEPTH: usize = 64;
/// Traversal stack size: SAH_DEPTH plus log₂ of the largest primitive count.
const STACK: usize = 128;
/// Cost of visiting a node relative to testing one primitive.
const TRAVERSAL_COST: Real = 1.0;

/// One bounded piece of a scene: an object, and the triangle inside it for
/// meshes (0 otherwise).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PrimRef {
    object: u32,
    primitive: u32,
}

/// A node: its bounds, and either two adjacent children at `offset` and
/// `offset + 1` (`count == 0`) or `count` primitives at `refs[offset..]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Node {
    min: Vec3,
    offset: u32,
    max: Vec3,
    count: u32,
}

/// What a build produced, for `--stats` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Bounded primitives in the tree (mesh triangles counted one by one,
    /// degenerate ones left out).
    pub primitives: usize,
    /// Nodes in the tree.
    pub nodes: usize,
    /// Bytes of nodes and primitive references.
    pub bytes: usize,
    /// Wall time of the build.
    pub build_time: Duration,
}

/// The hierarchy over a scene's objects (it stores indices, not geometry).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    refs: Vec<PrimRef>,
    /// Objects without bounds (planes), tested on every query.
    unbounded: Vec<u32>,
    stats: BvhStats,
}

/// A primitive during the build.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    centroid: Vec3,
    r: PrimRef,
}

impl Bvh {
    /// Builds the hierarchy over `objects`.
    pub fn build(objects: &[Object]) -> Self {
        let start = Instant::now();
        let mut items = Vec::new();
        let mut unbounded = Vec::new();
        for (o, object) in objects.iter().enumerate() {
            match &object.primitive {
                Primitive::Mesh(mesh) => {
                    for i in 0..mesh.triangle_count() {
                        if mesh.normal(i) != Vec3::ZERO {
                            let bounds = Aabb::from_points(mesh.triangle(i)).expect("three corners");
                            items.push(Item::new(bounds, o, i));
                        }
                    }
                }
                p => match p.bounds() {
                    Some(bounds) => items.push(Item::new(bounds, o, 0)),
                    None => unbounded.push(o as u32),
                },
            }
        }
        let mut bvh = Self { nodes: Vec::new(), refs: Vec::new(), unbounded, stats: BvhStats::default() };
        if !items.is_empty() {
            bvh.nodes.push(Node::PLACEHOLDER);
            bvh.build_node(&mut items, 0, 0, 0);
        }
        bvh.refs = items.iter().map(|i| i.r).collect();
        bvh.stats = BvhStats {
            primitives: items.len(),
            nodes: bvh.nodes.len(),
            bytes: bvh.nodes.len() * size_of::<Node>() + bvh.refs.len() * size_of::<PrimRef>(),
            build_time: start.elapsed(),
        };
        bvh
    }

    /// Statistics of the build.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// Splits node `node`, which holds `items` (starting at `first` in the
    /// final order), by the binned SAH, or leaves it a leaf.
    fn build_node(&mut self, items: &mut [Item], node: usize, first: usize, depth: usize) {
        let n = items.len();
        self.nodes[node] = Node::leaf(items, first);
        if n <= 1 {
            return;
        }
        let centroids = Aabb::from_points(items.iter().map(|i| i.centroid)).expect("non-empty");
        let axis = centroids.size().max_position();
        let (lo, extent) = (centroids.min()[axis], centroids.size()[axis]);
        let mid = if extent <= 0.0 || depth >= SAH_DEPTH {
            // Coincident centroids, or deep enough: a leaf if small, else the median.
            if n <= MAX_LEAF && extent <= 0.0 {
                return;
            }
            items.sort_unstable_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
            n / 2
        } else {
            let bin_of = |c: Vec3| (((c[axis] - lo) / extent * BINS as Real) as usize).min(BINS - 1);
            let mut bins = [(None::<Aabb>, 0usize); BINS];
            for item in items.iter() {
                let b = &mut bins[bin_of(item.centroid)];
                b.0 = Some(b.0.map_or(item.bounds, |x| x.union(item.bounds)));
                b.1 += 1;
            }
            // Sweep from the right for the right-hand areas, then from the left.
            let mut right_area = [0.0 as Real; BINS];
            let (mut acc, mut count) = (None::<Aabb>, 0);
            let mut right_count = [0usize; BINS];
            for k in (1..BINS).rev() {
                acc = union_opt(acc, bins[k].0);
                count += bins[k].1;
                right_area[k] = acc.map_or(0.0, |b| b.surface_area());
                right_count[k] = count;
            }
            let (mut best, mut best_cost) = (0, Real::INFINITY);
            let (mut acc, mut count) = (None::<Aabb>, 0);
            for k in 1..BINS {
                acc = union_opt(acc, bins[k - 1].0);
                count += bins[k - 1].1;
                let cost = count as Real * acc.map_or(0.0, |b| b.surface_area())
                    + right_count[k] as Real * right_area[k];
                if cost < best_cost && count > 0 && right_count[k] > 0 {
                    (best, best_cost) = (k, cost);
                }
            }
            let area = self.nodes[node].bounds().surface_area();
            let split_cost = TRAVERSAL_COST + best_cost / area.max(Real::MIN_POSITIVE);
            if best == 0 || (n <= MAX_LEAF && split_cost >= n as Real) {
                if n <= MAX_LEAF {
                    return;
                }
                items.sort_unstable_by(|a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
                n / 2
            } else {
                partition(items, |i| bin_of(i.centroid) < best)
            }
        };
        let children = self.nodes.len();
        // Filled in by the recursive calls below, which compute their bounds.
        self.nodes.push(Node::PLACEHOLDER);
        self.nodes.push(Node::PLACEHOLDER);
        self.nodes[node] = Node { count: 0, offset: children as u32, ..self.nodes[node] };
        let (left, right) = items.split_at_mut(mid);
        self.build_node(left, children, first, depth + 1);
        self.build_node(right, children + 1, first + mid, depth + 1);
    }

    /// The closest hit with `t` in `range`, exactly as the in-order loop over
    /// all objects finds it.
    pub fn closest_hit(
        &self,
        objects: &[Object],
        ray: &Ray,
        range: Interval,
        methods: Methods,
    ) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        let consider = |r: PrimRef, best: &mut Option<Hit>| {
            // Accept t equal to the best so far, so that ties can go to the lower index.
            let max = best.map_or(range.max, |b| b.t.next_up());
            let hit = intersect_ref(objects, r, ray, Interval::new(range.min, max), methods);
            if let Some(h) = hit {
                let h = Hit::new(r.object as usize, h);
                let better = best.is_none_or(|b| {
                    h.t < b.t || (h.t == b.t && (h.object, h.primitive) < (b.object, b.primitive))
                });
                if better {
                    *best = Some(h);
                }
            }
        };
        for &o in &self.unbounded {
            consider(PrimRef { object: o, primitive: 0 }, &mut best);
        }
        // Boxes entering beyond the best hit so far cannot improve on it (one
        // entering exactly there can still win a tie, and is visited).
        let t_max = best.map_or(range.max, |b| b.t);
        self.traverse(ray, Interval::new(range.min, t_max), |refs| {
            for &r in refs {
                consider(r, &mut best);
            }
            best.map(|b| b.t)
        });
        best
    }

    /// Whether anything is hit with `t` in `range` (shadow rays): stops at
    /// the first hit found.
    pub fn any_hit(&self, objects: &[Object], ray: &Ray, range: Interval, methods: Methods) -> bool {
        let hits = |r: PrimRef| intersect_ref(objects, r, ray, range, methods).is_some();
        if self.unbounded.iter().any(|&o| hits(PrimRef { object: o, primitive: 0 })) {
            return true;
        }
        let mut found = false;
        self.traverse(ray, range, |refs| {
            found = refs.iter().any(|&r| hits(r));
            // −∞ as the new limit: no box can be entered before it, so the traversal ends.
            found.then_some(Real::NEG_INFINITY)
        });
        found
    }

    /// Visits the leaves whose boxes the ray enters within `range`, nearer
    /// child first. `leaf` tests a leaf's primitives and returns the `t` of
    /// the closest hit so far, which prunes boxes that start beyond it.
    fn traverse(&self, ray: &Ray, range: Interval, mut leaf: impl FnMut(&[PrimRef]) -> Option<Real>) {
        if self.nodes.is_empty() {
            return;
        }
        let slabs = Slabs::new(ray);
        let mut t_max = range.max;
        let mut stack = [0u32; STACK];
        let mut sp = 0;
        let mut node = 0usize;
        if slabs.entry(&self.nodes[0], range.min, t_max).is_none() {
            return;
        }
        loop {
            let n = &self.nodes[node];
            if n.count > 0 {
                let refs = &self.refs[n.offset as usize..(n.offset + n.count) as usize];
                if let Some(t) = leaf(refs) {
                    t_max = t_max.min(t);
                }
            } else {
                let (a, b) = (n.offset as usize, n.offset as usize + 1);
                let ta = slabs.entry(&self.nodes[a], range.min, t_max);
                let tb = slabs.entry(&self.nodes[b], range.min, t_max);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far) = if ta <= tb { (a, b) } else { (b, a) };
                        stack[sp] = far as u32;
                        sp += 1;
                        node = near;
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree that can still hold a hit no later than t_max.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                node = stack[sp] as usize;
                if slabs.entry(&self.nodes[node], range.min, t_max).is_some() {
                    break;
                }
            }
        }
    }
}

impl Item {
    fn new(bounds: Aabb, object: usize, primitive: usize) -> Self {
        // Widen by a few ulps, so that rounding in a primitive's own bounds
        // can never cut off a hit its intersection routine finds.
        let pad = Vec3::splat(4.0 * Real::EPSILON) * bounds.min().abs().max(bounds.max().abs());
        let bounds = Aabb::from_corners(bounds.min() - pad, bounds.max() + pad);
        Self {
            bounds,
            centroid: bounds.center(),
            r: PrimRef { object: object as u32, primitive: primitive as u32 },
        }
    }
}

impl Node {
    /// A slot reserved for a node that `build_node` fills in.
    const PLACEHOLDER: Node = Node { min: Vec3::ZERO, offset: 0, max: Vec3::ZERO, count: 0 };

    /// A leaf over `items`, which start at `first` in the final order.
    fn leaf(items: &[Item], first: usize) -> Self {
        let b = items.iter().map(|i| i.bounds).reduce(Aabb::union).expect("non-empty");
        Self { min: b.min(), max: b.max(), offset: first as u32, count: items.len() as u32 }
    }

    fn bounds(&self) -> Aabb {
        Aabb::from_corners(self.min, self.max)
    }
}

/// A ray prepared for many slab tests: its inverse direction per axis.
struct Slabs {
    origin: Vec3,
    inv: Vec3,
}

impl Slabs {
    fn new(ray: &Ray) -> Self {
        Self { origin: ray.origin, inv: Vec3::ONE / ray.dir }
    }

    /// Where the ray enters the node's box, if the box overlaps `[t_min, t_max]`.
    ///
    /// A zero direction component gives an infinite inverse; `(min − o)·∞`
    /// is NaN exactly when the origin lies on that face plane, i.e. the ray
    /// runs inside the closed slab. Bounds are updated with `>`/`<`
    /// comparisons, which are false for NaN, so such a bound is ignored
    /// instead of poisoning the result (pbrt-v4's `Bounds3::IntersectP`), for
    /// +0.0 and −0.0 alike. The far bound is widened by 1 + 2γ₃ so rounding
    /// never rejects a box the ray touches.
    #[inline]
    fn entry(&self, node: &Node, t_min: Real, t_max: Real) -> Option<Real> {
        let (mut near, mut far) = (t_min, t_max);
        for axis in 0..3 {
            let inv = self.inv[axis];
            let mut t0 = (node.min[axis] - self.origin[axis]) * inv;
            let mut t1 = (node.max[axis] - self.origin[axis]) * inv;
            if inv < 0.0 {
                std::mem::swap(&mut t0, &mut t1);
            }
            t1 *= 1.0 + 2.0 * gamma(3);
            if t0 > near {
                near = t0;
            }
            if t1 < far {
                far = t1;
            }
        }
        (near <= far).then_some(near)
    }
}

/// The hit on one referenced primitive: a single triangle of a mesh, or the
/// whole primitive otherwise.
#[inline]
fn intersect_ref(
    objects: &[Object],
    r: PrimRef,
    ray: &Ray,
    range: Interval,
    methods: Methods,
) -> Option<PrimitiveHit> {
    match &objects[r.object as usize].primitive {
        Primitive::Mesh(m) => m.intersect_triangle(r.primitive as usize, ray, range, methods.triangle),
        p => p.intersect_with(ray, range, methods),
    }
}

fn union_opt(a: Option<Aabb>, b: Option<Aabb>) -> Option<Aabb> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.union(b)),
        (a, b) => a.or(b),
    }
}

/// Moves the items for which `left` holds to the front; returns how many.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if left(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Mesh;
    use crate::test_support::{
        primitives_of, random_parts, random_primitive as primitive, scene_of as scene, v,
    };
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn bvh_hits_equal_brute_force_hits(
            parts in random_parts(20.0, 24),
            rays in prop::collection::vec((prop::array::uniform3(-25f32..25.0), prop::array::uniform3(-1f32..1.0), 0u8..8, any::<bool>(), any::<bool>()), 16),
        ) {
            let s = scene(primitives_of(parts));
            for (origin, dir, zero_mask, negative_zero, from_a_box) in rays {
                let mut origin = v(origin);
                // Start some rays inside a box of the scene.
                if from_a_box
                    && let Some(b) = s.objects().iter().find_map(|o| match &o.primitive { Primitive::Aabb(b) => Some(*b), _ => None })
                {
                    origin = b.center();
                }
                let mut d = v(dir);
                for axis in 0..3 {
                    if zero_mask & (1 << axis) != 0 {
                        d[axis] = if negative_zero { -0.0 } else { 0.0 };
                    }
                }
                let ray = Ray::new(origin, d);
                let range = s.cast_range(&ray);
                let bvh = s.closest_hit(&ray, range);
                let brute = s.closest_hit_brute_force(&ray, range);
                prop_assert_eq!(bvh.map(|h| (h.object, h.primitive, h.t.to_bits())), brute.map(|h| (h.object, h.primitive, h.t.to_bits())), "ray {:?}", ray);
                prop_assert_eq!(s.any_hit(&ray, range), brute.is_some());
            }
        }

        #[test]
        fn every_primitive_lies_inside_its_bounds(
            kind in any::<u8>(),
            p in prop::array::uniform3(-20f32..20.0), q in prop::array::uniform3(-20f32..20.0), r in prop::array::uniform3(-20f32..20.0),
            origin in prop::array::uniform3(-30f32..30.0), dir in prop::array::uniform3(-1f32..1.0),
        ) {
            let Some(prim) = primitive(kind, p, q, r) else { return Ok(()) };
            let ray = Ray::new(v(origin), v(dir));
            if let (Some(bounds), Some(hit)) = (prim.bounds(), prim.intersect(&ray, Interval::new(0.0, Real::INFINITY))) {
                let point = ray.at(hit.t);
                let slack = 1e-4 * (1.0 + point.abs().max_element());
                prop_assert!(point.cmpge(bounds.min() - slack).all() && point.cmple(bounds.max() + slack).all(), "{point} outside {bounds:?}");
            }
        }
    }

    #[test]
    fn axis_parallel_rays_along_a_box_face_find_what_brute_force_finds() {
        // Unit boxes in a row along x, touching faces; rays along the shared
        // planes y = 0 and z = 0 with +0.0 and −0.0 components.
        let boxes = (0..8)
            .map(|i| {
                Primitive::Aabb(
                    Aabb::new(Vec3::new(i as Real, 0.0, 0.0), Vec3::new(i as Real + 1.0, 1.0, 1.0)).unwrap(),
                )
            })
            .collect();
        let s = scene(boxes);
        for dir in [Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, -0.0, -0.0), Vec3::new(-1.0, 0.0, -0.0)] {
            for origin in [
                Vec3::new(-5.0, 0.0, 0.5),
                Vec3::new(-5.0, 0.5, 0.0),
                Vec3::new(20.0, 1.0, 1.0),
                Vec3::new(3.5, 0.5, 0.5),
            ] {
                let ray = Ray::new(origin, dir);
                let range = s.cast_range(&ray);
                assert_eq!(
                    s.closest_hit(&ray, range),
                    s.closest_hit_brute_force(&ray, range),
                    "{origin} {dir}"
                );
            }
        }
    }

    #[test]
    fn nodes_are_32_bytes_with_f32_geometry() {
        if size_of::<Real>() == 4 {
            assert_eq!(size_of::<Node>(), 32);
        }
    }

    #[test]
    fn a_large_mesh_builds_a_shallow_tree_and_stats_add_up() {
        // A 100×100 grid: 20 000 triangles.
        let n = 100u32;
        let positions =
            (0..=n).flat_map(|j| (0..=n).map(move |i| Vec3::new(i as Real, j as Real, 0.0))).collect();
        let at = |i: u32, j: u32| j * (n + 1) + i;
        let triangles = (0..n)
            .flat_map(|j| {
                (0..n).flat_map(move |i| {
                    [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]]
                })
            })
            .collect();
        let s = scene(vec![Primitive::Mesh(Mesh::new(positions, triangles).unwrap())]);
        let stats = s.bvh_stats();
        assert_eq!(stats.primitives, 20_000);
        assert!(stats.nodes < 2 * 20_000 && stats.nodes > 20_000 / MAX_LEAF, "{} nodes", stats.nodes);
        assert_eq!(stats.bytes, stats.nodes * size_of::<Node>() + 20_000 * size_of::<PrimRef>());
        let ray = Ray::new(Vec3::new(37.3, 61.2, -10.0), Vec3::Z);
        let hit = s.cast(&ray).unwrap();
        assert_eq!(Some(hit), s.closest_hit_brute_force(&ray, s.cast_range(&ray)));
    }
}
