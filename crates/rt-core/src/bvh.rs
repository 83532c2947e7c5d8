//! A bounding volume hierarchy over every bounded primitive of a scene.
//!
//! Mesh triangles are flattened into it one by one; planes, which have no
//! bounds, are kept aside and tested directly. The tree is built once per
//! scene load with the binned surface-area heuristic (Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies", 2007) as a binary
//! tree, then collapsed into a 4-wide one (each node holds the boxes of up to
//! four children, as Embree's BVH4 does; Wald, Benthin and Boulos, "Getting
//! Rid of Packets", 2008): one node visit tests four boxes with the same
//! instructions, which the compiler turns into 4-lane SIMD. Leaves store
//! their triangles' corners inline, in tree order, so a leaf's triangles sit
//! together in memory.
//!
//! Traversal goes on with the nearest child a ray enters (the others wait on
//! a stack) and skips subtrees that start beyond the closest hit so far.
//! Results equal the brute-force loop over all objects bit for bit: the same
//! primitive functions compute each `t` from the same corners, and exact ties
//! go to the lower (object, primitive) index, as the in-order loop gives them.

use std::time::{Duration, Instant};

use crate::aabb::Aabb;
use crate::hit::{Hit, PrimitiveHit};
use crate::method::Methods;
use crate::object::Object;
use crate::primitive::Primitive;
use crate::ray::{Interval, Ray};
use crate::real::{Real, Vec3, gamma};
use crate::triangle::{TriangleRay, intersect_by};

/// Leaves hold at most this many primitives.
const MAX_LEAF: usize = 4;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this depth the SAH chooses splits; from here on, splits are at the
/// median, so the depth stays under SAH_DEPTH plus log₂ of the primitive count.
const SAH_DEPTH: usize = 64;
/// Traversal stack entries kept on the machine stack at most: enough for
/// any tree up to 21 levels deep (4²¹ leaves).
const INLINE_STACK: usize = 64;
/// Children per node.
const WIDTH: usize = 4;
/// Cost of visiting a node relative to testing one primitive.
const TRAVERSAL_COST: Real = 1.0;

/// One bounded primitive in a leaf: a mesh triangle with its corners copied
/// in (so testing it reads nothing else), or a whole object.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Leaf {
    /// Triangle `index` of the mesh `object`, corners a, b, c.
    Triangle { corners: [Vec3; 3], object: u32, index: u32 },
    /// Any other bounded primitive.
    Object { object: u32 },
}

/// A child slot of a [`Node`]: an inner node (`count == 0`), or a leaf of
/// `count` primitives at `leaves[index..]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Child {
    index: u32,
    count: u32,
}

/// A 4-wide node: the boxes of its children, stored axis by axis
/// (`bounds[min or max][axis][slot]`) so that one slab test covers all
/// four. Unused slots have the empty box (min = +∞, max = −∞), which no ray
/// enters.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
struct Node {
    /// `bounds[0]` are the minima, `bounds[1]` the maxima.
    bounds: [[[Real; WIDTH]; 3]; 2],
    children: [Child; WIDTH],
}

/// What a build produced, for `--stats` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Bounded primitives in the tree (mesh triangles counted one by one,
    /// degenerate ones left out).
    pub primitives: usize,
    /// Nodes in the tree.
    pub nodes: usize,
    /// Nodes on the longest path from the root to a leaf.
    pub depth: usize,
    /// Bytes of nodes and leaf primitives.
    pub bytes: usize,
    /// Wall time of the build.
    pub build_time: Duration,
}

/// The hierarchy over a scene's objects (it stores triangle corners and
/// indices; every other primitive is looked up in the scene).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    leaves: Vec<Leaf>,
    /// The most entries the traversal stack can hold: over all paths from
    /// the root, the largest sum of (children − 1) of the nodes on it.
    stack_bound: usize,
    /// Objects without bounds (planes), tested on every query.
    unbounded: Vec<u32>,
    /// The box around every bounded object; `None` if there is none.
    bounds: Option<Aabb>,
    stats: BvhStats,
}

/// A primitive during the build: object `object`, and the triangle `index`
/// inside it for meshes.
#[derive(Clone, Copy)]
struct Item {
    bounds: Aabb,
    centroid: Vec3,
    object: u32,
    index: u32,
}

/// A node of the binary tree the build makes first: two adjacent children at
/// `offset` and `offset + 1` (`count == 0`), or `count` items at `offset`.
#[derive(Clone, Copy)]
struct BinaryNode {
    bounds: Aabb,
    offset: u32,
    count: u32,
}

impl Bvh {
    /// Builds the hierarchy over `objects`.
    pub fn build(objects: &[Object]) -> Self {
        let start = Instant::now();
        let mut items = Vec::new();
        let mut unbounded = Vec::new();
        for (o, object) in objects.iter().enumerate() {
            let (primitive, object) = (&object.primitive, o as u32);
            match primitive {
                Primitive::Mesh(mesh) => {
                    for i in 0..mesh.triangle_count() {
                        if mesh.normal(i) != Vec3::ZERO {
                            let bounds = Aabb::from_points(mesh.triangle(i)).expect("three corners");
                            items.push(Item::new(bounds, object, i as u32));
                        }
                    }
                }
                p => match p.bounds() {
                    Some(bounds) => items.push(Item::new(bounds, object, 0)),
                    None => unbounded.push(object),
                },
            }
        }
        let mut nodes = Vec::new();
        let (mut depth, mut stack_bound) = (0, 0);
        let mut bounds = None;
        if !items.is_empty() {
            let mut binary = vec![BinaryNode::placeholder()];
            build_binary(&mut binary, &mut items, 0, 0, 0);
            bounds = Some(binary[0].bounds);
            let root;
            (root, depth, stack_bound) = child_of(&binary, 0, &mut nodes);
            if root.count > 0 {
                // The whole tree is one leaf: a root node with it as its only child.
                let mut node = Node::EMPTY;
                node.set(0, binary[0].bounds, root);
                nodes.push(node);
                depth = 1;
            }
        }
        let leaves: Vec<Leaf> = items
            .iter()
            .map(|&Item { object, index, .. }| match object_primitive(objects, object) {
                Primitive::Mesh(mesh) => {
                    Leaf::Triangle { corners: mesh.triangle(index as usize), object, index }
                }
                _ => Leaf::Object { object },
            })
            .collect();
        let stats = BvhStats {
            primitives: leaves.len(),
            nodes: nodes.len(),
            depth,
            bytes: nodes.len() * size_of::<Node>() + leaves.len() * size_of::<Leaf>(),
            build_time: start.elapsed(),
        };
        Self { nodes, leaves, stack_bound, unbounded, bounds, stats }
    }

    /// The box around every bounded object; `None` if there is none.
    pub fn bounds(&self) -> Option<Aabb> {
        self.bounds
    }

    /// Statistics of the build.
    pub fn stats(&self) -> BvhStats {
        self.stats
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
        let prepared = TriangleRay::new(ray);
        let consider = |leaf: &Leaf, best: &mut Option<Hit>| {
            // Accept t equal to the best so far, so that ties can go to the lower index.
            let max = best.map_or(range.max, |b| b.t.next_up());
            if let Some(h) = intersect_leaf(objects, leaf, &prepared, Interval::new(range.min, max), methods)
            {
                let better = best.is_none_or(|b| {
                    h.t < b.t || (h.t == b.t && (h.object, h.primitive) < (b.object, b.primitive))
                });
                if better {
                    *best = Some(h);
                }
            }
        };
        for &object in &self.unbounded {
            consider(&Leaf::Object { object }, &mut best);
        }
        // Boxes entering beyond the best hit so far cannot improve on it (one
        // entering exactly there can still win a tie, and is visited).
        let t_max = best.map_or(range.max, |b| b.t);
        self.traverse(ray, Interval::new(range.min, t_max), |leaves| {
            for leaf in leaves {
                consider(leaf, &mut best);
            }
            best.map(|b| b.t)
        });
        best
    }

    /// Whether anything is hit with `t` in `range` (shadow rays): stops at
    /// the first hit found.
    pub fn any_hit(&self, objects: &[Object], ray: &Ray, range: Interval, methods: Methods) -> bool {
        let prepared = TriangleRay::new(ray);
        let hits = |leaf: &Leaf| intersect_leaf(objects, leaf, &prepared, range, methods).is_some();
        if self.unbounded.iter().any(|&object| hits(&Leaf::Object { object })) {
            return true;
        }
        let mut found = false;
        self.traverse(ray, range, |leaves| {
            found = leaves.iter().any(hits);
            // −∞ as the new limit: no box can be entered before it, so the traversal ends.
            found.then_some(Real::NEG_INFINITY)
        });
        found
    }

    /// Visits the leaves whose boxes the ray enters within `range`, always
    /// going on with the nearest child entered at each node. `leaf` tests a leaf's primitives and returns the `t` of the
    /// closest hit so far, which prunes boxes that start beyond it.
    fn traverse(&self, ray: &Ray, range: Interval, leaf: impl FnMut(&[Leaf]) -> Option<Real>) {
        if self.nodes.is_empty() {
            return;
        }
        // The stack is an array on the machine stack, no bigger than the
        // tree needs (clearing it is part of every ray's cost), unless the
        // tree is unusually deep.
        const EMPTY: (Child, Real) = (Child { index: 0, count: 0 }, 0.0);
        match self.stack_bound {
            0..=16 => self.traverse_with(&mut [EMPTY; 16], ray, range, leaf),
            17..=32 => self.traverse_with(&mut [EMPTY; 32], ray, range, leaf),
            33..=INLINE_STACK => self.traverse_with(&mut [EMPTY; INLINE_STACK], ray, range, leaf),
            needed => self.traverse_with(&mut vec![EMPTY; needed], ray, range, leaf),
        }
    }

    /// [`Bvh::traverse`] with `stack` for the children still to visit, with
    /// the t where the ray enters them.
    fn traverse_with(
        &self,
        stack: &mut [(Child, Real)],
        ray: &Ray,
        range: Interval,
        mut leaf: impl FnMut(&[Leaf]) -> Option<Real>,
    ) {
        let slabs = Slabs::new(ray);
        let mut t_max = range.max;
        let mut sp = 0;
        let mut current = Child { index: 0, count: 0 };
        loop {
            if current.count == 0 {
                let node = &self.nodes[current.index as usize];
                let (near, entered) = slabs.entries(node, range.min, t_max);
                // Go on with the nearest entered child; the others wait on the
                // stack (pushed in slot order: with at most three of them, a
                // full sort buys little).
                if entered != 0 {
                    let slot = entered.trailing_zeros() as usize;
                    let mut rest = entered & (entered - 1);
                    let mut nearest = (node.children[slot], near[slot]);
                    while rest != 0 {
                        let slot = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let mut entry = (node.children[slot], near[slot]);
                        if entry.1 < nearest.1 {
                            std::mem::swap(&mut entry, &mut nearest);
                        }
                        stack[sp] = entry;
                        sp += 1;
                    }
                    current = nearest.0;
                    continue;
                }
            } else {
                let first = current.index as usize;
                if let Some(t) = leaf(&self.leaves[first..first + current.count as usize]) {
                    t_max = t_max.min(t);
                }
            }
            // Pop the next subtree that can still hold a hit no later than t_max.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                if stack[sp].1 <= t_max {
                    current = stack[sp].0;
                    break;
                }
            }
        }
    }
}

/// The primitive of object `o`.
fn object_primitive(objects: &[Object], o: u32) -> &Primitive {
    &objects[o as usize].primitive
}

/// Splits binary node `node`, which holds `items` (starting at `first` in
/// the final order), by the binned SAH, or leaves it a leaf.
fn build_binary(nodes: &mut Vec<BinaryNode>, items: &mut [Item], node: usize, first: usize, depth: usize) {
    let n = items.len();
    let bounds = items.iter().map(|i| i.bounds).reduce(Aabb::union).expect("non-empty");
    nodes[node] = BinaryNode { bounds, offset: first as u32, count: n as u32 };
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
        let split_cost = TRAVERSAL_COST + best_cost / bounds.surface_area().max(Real::MIN_POSITIVE);
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
    let children = nodes.len();
    // Filled in by the recursive calls below, which compute their bounds.
    nodes.push(BinaryNode::placeholder());
    nodes.push(BinaryNode::placeholder());
    nodes[node].count = 0;
    nodes[node].offset = children as u32;
    let (left, right) = items.split_at_mut(mid);
    build_binary(nodes, left, children, first, depth + 1);
    build_binary(nodes, right, children + 1, first + mid, depth + 1);
}

/// The 4-wide child for binary node `b`: a leaf as it is, or a new node
/// (appended to `nodes`) whose children are the up to four binary subtrees
/// found by repeatedly opening the inner child with the largest surface
/// area (the usual collapse; it keeps the SAH tree's splits).
///
/// Also returns the number of 4-wide nodes on the longest path down, and the
/// stack bound of the subtree (see [`Bvh::stack_bound`]).
fn child_of(binary: &[BinaryNode], b: usize, nodes: &mut Vec<Node>) -> (Child, usize, usize) {
    let node = binary[b];
    if node.count > 0 {
        return (Child { index: node.offset, count: node.count }, 0, 0);
    }
    let mut open = vec![node.offset as usize, node.offset as usize + 1];
    while open.len() < WIDTH {
        let widest =
            open.iter().enumerate().filter(|&(_, &c)| binary[c].count == 0).max_by(|a, b| {
                binary[*a.1].bounds.surface_area().total_cmp(&binary[*b.1].bounds.surface_area())
            });
        let Some((slot, &c)) = widest else { break };
        let first = binary[c].offset as usize;
        open[slot] = first;
        open.insert(slot + 1, first + 1);
    }
    let index = nodes.len();
    nodes.push(Node::EMPTY);
    let (mut depth, mut stack) = (0, 0);
    for (slot, &c) in open.iter().enumerate() {
        let (child, below, child_stack) = child_of(binary, c, nodes);
        nodes[index].set(slot, binary[c].bounds, child);
        depth = depth.max(below);
        stack = stack.max(child_stack);
    }
    (Child { index: index as u32, count: 0 }, depth + 1, stack + open.len() - 1)
}

impl Item {
    fn new(bounds: Aabb, object: u32, index: u32) -> Self {
        // Widen by a few ulps, so that rounding in a primitive's own bounds
        // can never cut off a hit its intersection routine finds.
        let pad = Vec3::splat(4.0 * Real::EPSILON) * bounds.min().abs().max(bounds.max().abs());
        let bounds = Aabb::from_corners(bounds.min() - pad, bounds.max() + pad);
        Self { bounds, centroid: bounds.center(), object, index }
    }
}

impl BinaryNode {
    /// A slot reserved for a node that `build_binary` fills in.
    fn placeholder() -> Self {
        Self { bounds: Aabb::from_corners(Vec3::ZERO, Vec3::ZERO), offset: 0, count: 0 }
    }
}

impl Node {
    /// A node with four empty slots.
    const EMPTY: Node = Node {
        bounds: [[[Real::INFINITY; WIDTH]; 3], [[Real::NEG_INFINITY; WIDTH]; 3]],
        children: [Child { index: 0, count: 0 }; WIDTH],
    };

    /// Puts `child` with `bounds` into `slot`.
    fn set(&mut self, slot: usize, bounds: Aabb, child: Child) {
        for axis in 0..3 {
            self.bounds[0][axis][slot] = bounds.min()[axis];
            self.bounds[1][axis][slot] = bounds.max()[axis];
        }
        self.children[slot] = child;
    }
}

/// A ray prepared for many slab tests: its origin and inverse direction,
/// and per axis which of a box's planes it enters by: 0 (min) for a
/// positive direction, 1 (max) for a negative one.
struct Slabs {
    origin: [Real; 3],
    inv: [Real; 3],
    enter: [usize; 3],
}

impl Slabs {
    fn new(ray: &Ray) -> Self {
        let inv = Vec3::ONE / ray.dir;
        let enter = [inv.x, inv.y, inv.z].map(|i| usize::from(i < 0.0));
        Self { origin: ray.origin.into(), inv: inv.into(), enter }
    }

    /// Where the ray enters each of the node's four boxes, and a mask with
    /// bit `slot` set where it overlaps `[t_min, t_max]` there.
    ///
    /// A zero direction component gives an infinite inverse; `(min − o)·∞`
    /// is NaN exactly when the origin lies on that face plane, i.e. the ray
    /// runs inside the closed slab. Bounds are updated with `>`/`<`
    /// comparisons, which are false for NaN, so such a bound is ignored
    /// instead of poisoning the result (pbrt-v4's `Bounds3::IntersectP`), for
    /// +0.0 and −0.0 alike; the same comparisons are SIMD max/min. The far
    /// bound is widened by 1 + 2γ₃ so rounding never rejects a box the ray
    /// touches.
    #[inline(always)]
    fn entries(&self, node: &Node, t_min: Real, t_max: Real) -> ([Real; WIDTH], u32) {
        let mut near = [t_min; WIDTH];
        let mut far = [t_max; WIDTH];
        for axis in 0..3 {
            // `& 1` shows the optimiser both indices are in bounds.
            let side = self.enter[axis] & 1;
            let (enter, leave) = (&node.bounds[side][axis], &node.bounds[side ^ 1][axis]);
            let (o, inv) = (self.origin[axis], self.inv[axis]);
            for slot in 0..WIDTH {
                let t0 = (enter[slot] - o) * inv;
                let t1 = (leave[slot] - o) * inv * (1.0 + 2.0 * gamma(3));
                near[slot] = if t0 > near[slot] { t0 } else { near[slot] };
                far[slot] = if t1 < far[slot] { t1 } else { far[slot] };
            }
        }
        let entered = (0..WIDTH).fold(0, |mask, slot| mask | (u32::from(near[slot] <= far[slot]) << slot));
        (near, entered)
    }
}

/// The hit on one leaf primitive: a single triangle of a mesh, or the whole
/// primitive otherwise.
#[inline]
fn intersect_leaf(
    objects: &[Object],
    leaf: &Leaf,
    ray: &TriangleRay,
    range: Interval,
    methods: Methods,
) -> Option<Hit> {
    match *leaf {
        Leaf::Triangle { corners: [a, b, c], object, index } => {
            let hit = intersect_by(methods.triangle, a, b, c, ray, range)?;
            let Primitive::Mesh(mesh) = object_primitive(objects, object) else {
                unreachable!("triangle leaves come from meshes")
            };
            let index = index as usize;
            Some(Hit::new(
                object as usize,
                PrimitiveHit { t: hit.t, primitive: index, normal: mesh.normal(index) },
            ))
        }
        Leaf::Object { object } => object_primitive(objects, object)
            .intersect_with(&ray.ray, range, methods)
            .map(|h| Hit::new(object as usize, h)),
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
    fn a_tree_too_deep_for_the_inline_stack_still_finds_every_hit() {
        // Boxes at exponentially growing distances: each SAH split peels off
        // only the farthest few, so the tree is a long chain.
        let boxes: Vec<Primitive> = (0..100)
            .map(|k| {
                let s = (1.5 as Real).powi(k);
                Primitive::Aabb(Aabb::new(Vec3::splat(s), Vec3::splat(1.2 * s)).unwrap())
            })
            .collect();
        let s = scene(boxes);
        let depth = s.bvh_stats().depth;
        let bound = Bvh::build(s.objects()).stack_bound;
        assert!(bound > INLINE_STACK, "depth {depth}, stack bound {bound}");
        for k in 0..100 {
            let target = Vec3::splat(1.1 * (1.5 as Real).powi(k));
            for origin in [Vec3::new(-1.0, 0.0, 0.5), Vec3::splat(1e30)] {
                let ray = Ray::new(origin, target - origin);
                let range = s.cast_range(&ray);
                assert_eq!(s.closest_hit(&ray, range), s.closest_hit_brute_force(&ray, range), "box {k}");
                assert!(s.any_hit(&ray, range));
            }
        }
    }

    #[test]
    fn nodes_fill_two_cache_lines_with_f32_geometry() {
        if size_of::<Real>() == 4 {
            assert_eq!(size_of::<Node>(), 128);
            assert_eq!(align_of::<Node>(), 64);
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
        // A 4-wide tree over leaves of up to MAX_LEAF triangles: about a
        // third as many nodes as leaves.
        let leaves_min = 20_000 / MAX_LEAF;
        assert!(stats.nodes > leaves_min / 4 && stats.nodes < 20_000 / 2, "{} nodes", stats.nodes);
        assert_eq!(stats.bytes, stats.nodes * size_of::<Node>() + 20_000 * size_of::<Leaf>());
        let ray = Ray::new(Vec3::new(37.3, 61.2, -10.0), Vec3::Z);
        let hit = s.cast(&ray).unwrap();
        assert_eq!(Some(hit), s.closest_hit_brute_force(&ray, s.cast_range(&ray)));
    }
}
