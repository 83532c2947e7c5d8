//! A bounding volume hierarchy over every bounded primitive of a scene.
//!
//! Mesh triangles are flattened into it one by one; planes, which have no
//! bounds, are kept aside and tested directly. The tree is built once per
//! scene load with the binned surface-area heuristic (Wald, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies", 2007) as a binary
//! tree, then collapsed into an 8-wide one (each node holds the boxes of up
//! to eight children, as Embree's BVH8 does; Wald, Benthin and Boulos,
//! "Getting Rid of Packets", 2008): one node visit tests eight boxes with the
//! same instructions, one 8-lane AVX2 test where the CPU has AVX2 (asked at
//! run time), two 4-lane SSE ones elsewhere, and a ray's path from the root
//! to a leaf is a third shorter than in a 4-wide tree (on the 1 M-triangle
//! terrain a bounce ray visits 10.1 nodes instead of 15.0; each visit is a
//! load the next one waits for). A leaf is one
//! or two blocks of up to four triangles with their corners stored lane by
//! lane, tested at once with SIMD (`bvh/leaf.rs`; both blocks in one
//! eight-lane test where the CPU has AVX2, as Embree's leaves may hold
//! several `Triangle4` blocks); leaves are stored in tree order. Coherent rays
//! (a pixel's samples, a run of a row's pixels) go down the tree together
//! as packets ([`Bvh::closest_hits`], `bvh/packet.rs`).
//!
//! Traversal goes on with the nearest child a ray enters (the others wait on
//! a stack) and skips subtrees that start beyond the closest hit so far.
//! Results equal the brute-force loop over all objects bit for bit: the same
//! primitive functions compute each `t` from the same corners, and exact ties
//! go to the lower (object, primitive) index, as the in-order loop gives them.

mod build;
mod collapse;
mod huge_pages;
mod item;
mod leaf;
mod node;
mod object_block;
mod packet;
pub mod parts;
mod query;

use std::mem::MaybeUninit;
use std::ops::Range;
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::geometry::aabb::Aabb;
use crate::geometry::hit::Hit;
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::geometry::triangle::TriangleRay;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, gamma, to_f64};
use item::Item;
use leaf::{Lanes, Leaf, lanes_of};
use node::{Child, Node, WIDTH};
use object_block::ObjectBlock;
use query::{Best, Query, object_primitive};

/// Traversal stack entries kept on the machine stack at most: a node visit
/// leaves at most seven children waiting, so enough for any tree up to 13
/// levels deep (8¹³ leaves); the 1 M-triangle terrain's tree needs 46.
const INLINE_STACK: usize = 96;

/// The most rays a packet holds ([`Bvh::closest_hits`] traces its rays in
/// packets of this many, `bvh/packet.rs`): a pixel's 64 samples, or a run
/// of 64 pixels of a row at one sample each.
pub const PACKET_RAYS: usize = 64;

/// How a single ray's query comes, which decides where its hit's normal
/// comes from ([`Bvh::closest_hit_among`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rays {
    /// A ray on its own (a bounce): a mesh triangle's normal is read from
    /// the mesh's list where the list stays in the cache (up to 4 MiB) and
    /// made again from the leaf's corners where it does not, since the
    /// normals of scattered hits are scattered over the list.
    Alone,
    /// One of a run of neighbouring rays (a row's primary rays, one after
    /// the other): the normal is always read from the list, as a packet's
    /// are, since the neighbour's hit has brought that part of the list
    /// into the cache.
    InARun,
}

/// What a build produced, for `--stats` and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BvhStats {
    /// Bounded primitives in the tree (mesh triangles counted one by one,
    /// degenerate ones left out).
    pub primitives: usize,
    /// Nodes in the tree.
    pub nodes: usize,
    /// Children per node at most.
    pub width: usize,
    /// Nodes on the longest path from the root to a leaf.
    pub depth: usize,
    /// Leaves in the tree.
    pub leaves: usize,
    /// Blocks of up to four primitives in the leaves (a leaf has one or
    /// two).
    pub leaf_blocks: usize,
    /// Bytes of nodes and leaves.
    pub bytes: usize,
    /// The tree's surface-area-heuristic cost: the expected cost of a ray
    /// that crosses the scene's box, `Σ A(node)/A(root)·c_node + Σ
    /// A(leaf)/A(root)·c_leaf` with `c_node` = 1 per 8-wide node visit and
    /// `c_leaf` = 1 per leaf (its up to four primitives are tested at once).
    /// Lower is a better tree.
    pub sah_cost: f64,
    /// Wall time of the build.
    pub build_time: Duration,
    /// How [`BvhStats::build_time`] splits into the build's steps.
    pub build_steps: BuildSteps,
}

/// Wall time of each step of [`Bvh::build`], in order: laps of one clock,
/// which together make up its `build_time` but for the few nanoseconds
/// between the clock's reads. Zero for a tree read back from its arrays
/// (a scene cache).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildSteps {
    /// Listing the items (one per mesh triangle or other bounded object,
    /// with its box and centroid), on all threads.
    pub items: Duration,
    /// The binary tree by the binned SAH (`bvh/build.rs`): nodes over a
    /// few thousand items are binned on all threads and their halves built
    /// at the same time, smaller ones on one thread each.
    pub binary_tree: Duration,
    /// Listing the leaves' blocks and taking the memory for the nodes and
    /// leaves.
    pub leaf_list: Duration,
    /// Collapsing the binary tree into 8-wide nodes (`bvh/collapse.rs`)
    /// while the other threads fill the leaves' blocks.
    pub collapse: Duration,
    /// The rest: the whole objects' blocks and moving a small tree's nodes
    /// onto huge pages.
    pub finish: Duration,
}

impl BuildSteps {
    /// The steps in order, each with the name [`BuildSteps`]' `Display`
    /// gives it.
    pub fn named(&self) -> [(&'static str, Duration); 5] {
        [
            ("items", self.items),
            ("binary tree", self.binary_tree),
            ("leaf list", self.leaf_list),
            ("collapse with the leaves", self.collapse),
            ("finish", self.finish),
        ]
    }
}

impl std::fmt::Display for BuildSteps {
    /// The steps' times in seconds, in order: `items 0.0167 s, binary tree
    /// 0.1124 s, …`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        for (i, (name, time)) in self.named().into_iter().enumerate() {
            let comma = if i == 0 { "" } else { ", " };
            write!(f, "{comma}{name} {:.4} s", time.as_secs_f64())?;
        }
        Ok(())
    }
}

/// The hierarchy over a scene's objects (it stores triangle corners and
/// indices; every other primitive is looked up in the scene).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// The leaves' blocks, each leaf's one after the other.
    leaves: Vec<Leaf>,
    /// The most entries the traversal stack can hold: over all paths from
    /// the root, the largest sum of (children − 1) of the nodes on it.
    stack_bound: usize,
    /// The leaves' boxes and polygons laid out for four-lane tests, one per
    /// block that has any ([`object_block::attach`]).
    object_blocks: Vec<ObjectBlock>,
    /// Objects without bounds (planes), tested on every query.
    unbounded: Vec<u32>,
    /// Whether any leaf can hold mesh triangles (the scene has a mesh): a
    /// query prepares its ray for the triangle test only then.
    triangles: bool,
    /// The box around every bounded object; `None` if there is none.
    bounds: Option<Aabb>,
    stats: BvhStats,
}

/// Room for nodes (bytes) from which the build writes them on huge pages
/// from the start instead of copying them there once built. The room is a
/// bound (a tree fills about a quarter of it) and only the huge pages
/// touched are taken, so a large tree saves the copy and the small pages
/// it was first written to; a tree near one huge page of nodes (the
/// 100 000-triangle terrain's: 1.4 MB in 5.4 MB of room) would pay for
/// clearing a whole huge page it does not fill (docs/performance.md).
const LARGE_NODES: usize = 16 << 20;

/// Whether any of `objects` is a mesh, whose triangles the leaves test with
/// the watertight test ([`Leaf::new`] puts every other primitive in a
/// whole-object lane).
fn has_meshes(objects: &[Object]) -> bool {
    objects.iter().any(|o| matches!(o.primitive, Primitive::Mesh(_)))
}

/// One build item per bounded primitive of `objects`, in object order, a
/// mesh's triangles one by one in index order, degenerate ones (zero normal)
/// left out. A large mesh's triangle boxes are computed on all threads,
/// straight into the list (no per-thread lists joined afterwards), which is
/// marked for huge pages before it is written: the build reads it once per
/// level of the tree, and a 1 M-triangle mesh's 32 MB of items fault in as
/// 16 huge pages instead of 8 000 small ones (docs/performance.md).
fn items_of(objects: &[Object]) -> Vec<Item> {
    use std::sync::atomic::{AtomicBool, Ordering::Relaxed};
    /// Meshes with fewer triangles than this are done on the calling thread.
    const PARALLEL_TRIANGLES: usize = 4096;
    let total = objects
        .iter()
        .map(|o| match &o.primitive {
            Primitive::Mesh(mesh) => mesh.triangle_count(),
            _ => 1,
        })
        .sum();
    let mut items: Vec<Item> = huge_pages::with_capacity(total);
    let degenerate = AtomicBool::new(false);
    for (o, object) in objects.iter().enumerate() {
        let o = o as u32;
        match &object.primitive {
            Primitive::Mesh(mesh) => {
                let item = |i: u32| {
                    if mesh.normal(i as usize) == Vec3::ZERO {
                        degenerate.store(true, Relaxed);
                    }
                    Item::new(Aabb::from_points(mesh.triangle(i as usize)).expect("three corners"), o, i)
                };
                let count = mesh.triangle_count() as u32;
                if count as usize >= PARALLEL_TRIANGLES {
                    items.par_extend((0..count).into_par_iter().map(item));
                } else {
                    items.extend((0..count).map(item));
                }
            }
            p => items.extend(p.bounds().map(|b| Item::whole(b, o))),
        }
    }
    if degenerate.into_inner() {
        items.retain(|item| match &objects[item.object() as usize].primitive {
            Primitive::Mesh(mesh) => mesh.normal(item.index() as usize) != Vec3::ZERO,
            _ => true,
        });
    }
    items
}

/// The item ranges of the leaves' blocks, in item order, from the leaf sizes
/// [`build::build`] wrote (a leaf of `c` items at `i` is blocks of up to
/// [`leaf::LANES`] items from `i` on).
fn leaf_blocks(sizes: &[u8]) -> Vec<Range<usize>> {
    let mut blocks = Vec::with_capacity(sizes.len() / leaf::LANES + sizes.len() / 8);
    let mut i = 0;
    while i < sizes.len() {
        let count = usize::from(sizes[i]);
        debug_assert!(count > 0, "items outside every leaf");
        let end = i + count.max(1);
        for start in (i..end).step_by(leaf::LANES) {
            blocks.push(start..(start + leaf::LANES).min(end));
        }
        i = end;
    }
    blocks
}

impl Bvh {
    /// Builds the hierarchy over `objects`, on rayon's current pool.
    pub fn build(objects: &[Object]) -> Self {
        let start = Instant::now();
        let unbounded: Vec<u32> =
            (0..objects.len() as u32).filter(|&o| objects[o as usize].primitive.bounds().is_none()).collect();
        let mut items = items_of(objects);
        let mut lap = Instant::now();
        let mut steps = BuildSteps { items: lap - start, ..BuildSteps::default() };
        let mut next_step = |step: &mut Duration| {
            let now = Instant::now();
            *step = now - lap;
            lap = now;
        };
        let mut nodes = Vec::new();
        let mut leaves: Vec<Leaf> = Vec::new();
        let mut leaf_count = 0;
        let (mut depth, mut stack_bound, mut sah_cost) = (0, 0, 0.0);
        let mut bounds = None;
        if !items.is_empty() {
            let mut sizes = vec![0; items.len()];
            let (tree, binary_leaves) = build::build(&mut items, &mut sizes);
            next_step(&mut steps.binary_tree);
            // Each leaf's blocks, in tree order (the leaves' items come in
            // tree order): the leaves' slots are known before the collapse,
            // so the blocks are filled while it runs.
            let blocks = leaf_blocks(&sizes);
            drop(sizes);
            // A tree of L leaves has at most L − 1 inner nodes (each has two
            // children or more): room for them from the start, so the list
            // is not copied as it grows. A large tree's nodes go on huge
            // pages at once ([`LARGE_NODES`]); a smaller tree's are moved
            // there once built, below, if they fill one.
            let node_bound = binary_leaves.max(2) - 1;
            nodes = if node_bound * size_of::<Node>() >= LARGE_NODES {
                huge_pages::with_capacity(node_bound)
            } else {
                Vec::with_capacity(node_bound)
            };
            leaves = huge_pages::with_capacity(blocks.len());
            let root_box = tree.root.bounds();
            bounds = Some(root_box);
            let items = &items;
            // A leaf's child entry: its first block's slot and its blocks' lanes.
            let blocks = &blocks;
            next_step(&mut steps.leaf_list);
            let leaf = |block: u32, first: u32, count: u32| {
                let mut lanes = Lanes(0);
                for (b, start) in (first..first + count).step_by(leaf::LANES).enumerate() {
                    let range = start as usize..(start as usize + leaf::LANES).min((first + count) as usize);
                    debug_assert_eq!(blocks[block as usize + b], range);
                    lanes = lanes.with_block(b, Leaf::lanes(&items[range], objects));
                }
                Child { index: block, lanes }
            };
            // The collapse and the blocks filled at the same time (the
            // blocks in place, in memory marked for huge pages); the binary
            // tree is freed on the collapse's side.
            let (root, ()) = rayon::join(
                || {
                    let leaves = collapse::Leaves { blocks, leaf };
                    let root = collapse::collapse(&tree.root, &tree.arena, &mut nodes, &leaves);
                    drop(tree);
                    root
                },
                || {
                    leaves.par_extend(
                        blocks.par_iter().map(|range| Leaf::new(&items[range.clone()], objects).0),
                    )
                },
            );
            next_step(&mut steps.collapse);
            leaf_count = root.leaves;
            (depth, stack_bound) = (root.depth, root.stack);
            if root.child.is_leaf() {
                // The whole tree is one leaf: a root node with it as its only child.
                let mut node = Node::EMPTY;
                node.set(0, root_box, root.child);
                nodes.push(node);
                depth = 1;
            }
            sah_cost = root.cost / to_f64(root_box.surface_area()).max(f64::MIN_POSITIVE);
        }
        let object_blocks = object_block::attach(&mut leaves, objects);
        let mut nodes = if nodes.capacity() * size_of::<Node>() >= LARGE_NODES {
            nodes
        } else {
            huge_pages::moved(nodes)
        };
        nodes.shrink_to_fit(); // no spare room kept
        next_step(&mut steps.finish);
        let stats = BvhStats {
            primitives: items.len(),
            nodes: nodes.len(),
            width: WIDTH,
            leaves: leaf_count,
            leaf_blocks: leaves.len(),
            depth,
            bytes: nodes.len() * size_of::<Node>()
                + leaves.len() * size_of::<Leaf>()
                + object_blocks.len() * size_of::<ObjectBlock>(),
            sah_cost,
            build_time: start.elapsed(),
            build_steps: steps,
        };
        let triangles = has_meshes(objects);
        Self { nodes, leaves, object_blocks, stack_bound, unbounded, triangles, bounds, stats }
    }

    /// The box around every bounded object; `None` if there is none.
    pub fn bounds(&self) -> Option<Aabb> {
        self.bounds
    }

    /// Statistics of the build.
    pub fn stats(&self) -> BvhStats {
        self.stats
    }

    /// `ray` prepared for the leaves' triangle tests, where the tree holds
    /// triangles ([`Bvh::triangles`]): by branches for one of a packet's
    /// `COHERENT` rays ([`TriangleRay::new_coherent`]), else without
    /// ([`TriangleRay::new`]); the same bits either way. Without triangles the
    /// preparation is never read ([`TriangleRay::unprepared`]).
    #[inline(always)]
    fn prepared<const COHERENT: bool>(&self, ray: &Ray) -> TriangleRay {
        match (self.triangles, COHERENT) {
            (false, _) => TriangleRay::unprepared(ray),
            (true, true) => TriangleRay::new_coherent(ray),
            (true, false) => TriangleRay::new(ray),
        }
    }

    /// The closest hit with `t` in `range`, exactly as the in-order loop over
    /// all objects finds it, for a ray on its own ([`Rays::Alone`]).
    pub fn closest_hit(
        &self,
        objects: &[Object],
        ray: &Ray,
        range: Interval,
        methods: Methods,
    ) -> Option<Hit> {
        self.closest_hit_among(objects, ray, range, methods, Rays::Alone)
    }

    /// [`Bvh::closest_hit`] for a ray that comes as `rays` say: the same
    /// hit either way; where the hit's normal comes from differs.
    pub fn closest_hit_among(
        &self,
        objects: &[Object],
        ray: &Ray,
        range: Interval,
        methods: Methods,
        rays: Rays,
    ) -> Option<Hit> {
        let read_up_to = match rays {
            Rays::Alone => NORMALS_READ_UP_TO,
            Rays::InARun => usize::MAX,
        };
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { self.closest_hit_avx2(objects, ray, range, methods, read_up_to) };
        }
        self.closest_hit_with::<false>(objects, ray, range, methods, read_up_to)
    }

    /// [`Bvh::closest_hit`] compiled for AVX2 as a whole: the set-up, the
    /// traversal, the leaf tests and the finish in one function, so that the
    /// query stays in registers.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    unsafe fn closest_hit_avx2(
        &self,
        objects: &[Object],
        ray: &Ray,
        range: Interval,
        methods: Methods,
        read_up_to: usize,
    ) -> Option<Hit> {
        self.closest_hit_with::<true>(objects, ray, range, methods, read_up_to)
    }

    /// [`Bvh::closest_hit_among`], reading normal lists up to `read_up_to`
    /// bytes long, with the AVX2 traversal if `AVX2` (which the caller has
    /// checked the CPU for).
    #[inline(always)]
    fn closest_hit_with<const AVX2: bool>(
        &self,
        objects: &[Object],
        ray: &Ray,
        range: Interval,
        methods: Methods,
        read_up_to: usize,
    ) -> Option<Hit> {
        let mut query = Query::new(self.prepared::<false>(ray), range);
        query.test_unbounded(&self.unbounded, objects, methods);
        // Boxes entering beyond the best hit so far cannot improve on it (one
        // entering exactly there can still win a tie, and is visited).
        let range = Interval::new(range.min, query.t_max());
        // The query is borrowed, not moved in: a move copies it with wide
        // loads from the narrower stores that just wrote it, which stalls
        // on the store-to-load forwarding.
        let mut closest = Closest::<AVX2> {
            query: &mut query,
            objects,
            object_blocks: &self.object_blocks,
            methods,
            read_up_to,
            best_lane: None,
        };
        self.traverse_by::<AVX2, _>(ray, range, &mut closest);
        match closest.best_lane {
            // The normal from the corners in the leaf, which is still in the
            // cache, where the mesh's normal list is too long to stay in it
            // (a cache miss for incoherent rays). Same corners, same
            // function, so the same bits as `Mesh::normal` (a proptest in
            // `leaf.rs` pins it; the brute-force comparisons' meshes are
            // small enough to be read).
            Some((leaf, lane)) => query.finish_with_normal(leaf.normal(lane)),
            None => query.finish(objects),
        }
    }

    /// Whether anything is hit with `t` in `range` (shadow rays): stops at
    /// the first hit found.
    pub fn any_hit(&self, objects: &[Object], ray: &Ray, range: Interval, methods: Methods) -> bool {
        let prepared = self.prepared::<false>(ray);
        let hits =
            |object: u32| object_primitive(objects, object).intersect_with(ray, range, methods).is_some();
        if self.unbounded.iter().any(|&object| hits(object)) {
            return true;
        }
        let mut found = false;
        self.traverse(ray, range, |blocks, lanes| {
            found = Leaf::intersect_leaf(blocks, lanes, &prepared, range, methods.triangle).1 != 0
                || (blocks.iter().enumerate()).any(|(b, leaf)| {
                    let whole = lanes.block(b).objects();
                    if whole == 0 {
                        return false;
                    }
                    // The block's boxes and polygons four at a time, the
                    // rest one by one; a block that blocks the ray ends the
                    // test before the next is looked at.
                    let mut scalar = whole;
                    if let Some((block, mask)) =
                        object_block::block_of(&self.object_blocks, leaf, whole, methods)
                    {
                        if block.intersect(mask, ray, range).hit != 0 {
                            return true;
                        }
                        scalar &= !mask;
                    }
                    lanes_of(scalar).any(|lane| hits(leaf.object(lane)))
                });
            // −∞ as the new limit: no box can be entered before it, so the traversal ends.
            found.then_some(Real::NEG_INFINITY)
        });
        found
    }

    /// Visits the leaves whose boxes the ray enters within `range`, always
    /// going on with the nearest child entered at each node. `leaf` tests a
    /// leaf's primitives (its blocks and lanes) and returns the `t` of the
    /// closest hit so far, which prunes boxes that start beyond it.
    fn traverse<'a>(
        &'a self,
        ray: &Ray,
        range: Interval,
        mut leaf: impl FnMut(&'a [Leaf], Lanes) -> Option<Real>,
    ) {
        self.traverse_by_any(ray, range, &mut leaf)
    }

    /// [`Bvh::traverse`] with any [`LeafTest`].
    #[inline(always)]
    fn traverse_by_any<'a, L: LeafTest<'a>>(&'a self, ray: &Ray, range: Interval, leaf: &mut L) {
        if self.nodes.is_empty() {
            return;
        }
        // The stack is an uninitialised array on the machine stack (setting
        // it up costs nothing), unless the tree is unusually deep.
        let uninit = const { MaybeUninit::uninit() };
        if self.stack_bound <= INLINE_STACK {
            self.traverse_on(&mut [uninit; INLINE_STACK], ray, range, leaf)
        } else {
            self.traverse_on(&mut vec![uninit; self.stack_bound], ray, range, leaf)
        }
    }

    /// [`Bvh::traverse_by_any`] with the AVX2 node test if `AVX2` (which the
    /// caller has checked the CPU for), inlined into the caller.
    #[inline(always)]
    fn traverse_by<'a, const AVX2: bool, L: LeafTest<'a>>(
        &'a self,
        ray: &Ray,
        range: Interval,
        leaf: &mut L,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let uninit = const { MaybeUninit::uninit() };
        if self.stack_bound <= INLINE_STACK {
            self.traverse_with::<AVX2, L>(&mut [uninit; INLINE_STACK], ray, range, leaf)
        } else {
            self.traverse_with::<AVX2, L>(&mut vec![uninit; self.stack_bound], ray, range, leaf)
        }
    }

    /// [`Bvh::traverse`] with `stack` for the children still to visit, with
    /// the t where the ray enters them: with the AVX2 node test where the CPU
    /// has AVX2 (f32 geometry), else with the SSE one on x86-64 or the
    /// portable one (all three give the same bits, tested).
    #[inline(always)]
    fn traverse_on<'a, L: LeafTest<'a>>(
        &'a self,
        stack: &mut [MaybeUninit<(Child, Real)>],
        ray: &Ray,
        range: Interval,
        leaf: &mut L,
    ) {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { self.traverse_avx2(stack, ray, range, leaf) };
        }
        self.traverse_with::<false, L>(stack, ray, range, leaf)
    }

    /// [`Bvh::traverse_with`] compiled for AVX2, with its node test.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    unsafe fn traverse_avx2<'a, L: LeafTest<'a>>(
        &'a self,
        stack: &mut [MaybeUninit<(Child, Real)>],
        ray: &Ray,
        range: Interval,
        leaf: &mut L,
    ) {
        self.traverse_with::<true, L>(stack, ray, range, leaf)
    }

    /// The traversal itself, with [`Slabs::entries_avx2`] as its node test
    /// if `AVX2` (which the caller has checked the CPU for), else
    /// [`Slabs::entries_sse`] on x86-64 with f32 geometry and
    /// [`Slabs::entries`] elsewhere.
    #[inline(always)]
    fn traverse_with<'a, const AVX2: bool, L: LeafTest<'a>>(
        &'a self,
        stack: &mut [MaybeUninit<(Child, Real)>],
        ray: &Ray,
        range: Interval,
        leaf: &mut L,
    ) {
        let slabs = Slabs::new(ray);
        let mut t_max = range.max;
        let mut sp = 0;
        let mut current = Child::node(0);
        loop {
            if !current.is_leaf() {
                let node = &self.nodes[current.index as usize];
                #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
                // SAFETY: `AVX2` is true only where the CPU has AVX2.
                let (near, entered) = if AVX2 {
                    unsafe { slabs.entries_avx2(node, range.min, t_max) }
                } else {
                    slabs.entries_sse(node, range.min, t_max)
                };
                #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
                let (near, entered) = slabs.entries(node, range.min, t_max);
                // Go on with the nearest entered child; the others wait on the
                // stack, sorted so that the nearer pops first (Embree's
                // closest-hit order). A visit enters 1.2–1.3 children on
                // average, so the insertion sort rarely moves anything;
                // where it does, a hit found in the nearer subtree prunes
                // the farther ones (in slot order, a single ray on the 1 M
                // terrain tested 9 % more leaves; docs/performance.md).
                if entered != 0 {
                    let slot = entered.trailing_zeros() as usize;
                    let mut rest = entered & (entered - 1);
                    let mut nearest = (node.children[slot], near[slot]);
                    self.prefetch(nearest.0);
                    let base = sp;
                    while rest != 0 {
                        let slot = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let mut entry = (node.children[slot], near[slot]);
                        self.prefetch(entry.0);
                        if entry.1 < nearest.1 {
                            std::mem::swap(&mut entry, &mut nearest);
                        }
                        push_sorted(stack, base, &mut sp, entry, |e| e.1);
                    }
                    current = nearest.0;
                    continue;
                }
            } else {
                if let Some(t) = leaf.test(self.blocks(current), current.lanes) {
                    t_max = t_max.min(t);
                }
            }
            // Pop the next subtree that can still hold a hit no later than t_max.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were all written above.
                let (child, near) = unsafe { stack[sp].assume_init() };
                if near <= t_max {
                    current = child;
                    break;
                }
            }
        }
    }
}

/// Pushes `entry` onto the stack `stack[..sp]` (raising `sp` by one) so
/// that the entries from `base` up, a node's waiting children, stay sorted
/// by `near`: the nearest on top, popped first. An insertion sort: a visit
/// leaves 0–1 children waiting as a rule, rarely more.
#[inline(always)]
fn push_sorted<T: Copy>(
    stack: &mut [MaybeUninit<T>],
    base: usize,
    sp: &mut usize,
    entry: T,
    near: impl Fn(&T) -> Real,
) {
    let mut at = *sp;
    while at > base {
        // SAFETY: the caller wrote every entry below `sp`.
        let below = unsafe { stack[at - 1].assume_init() };
        if near(&below) >= near(&entry) {
            break;
        }
        stack[at].write(below);
        at -= 1;
    }
    stack[at].write(entry);
    *sp += 1;
}

impl Bvh {
    /// The blocks of the leaf `child`.
    #[inline(always)]
    fn blocks(&self, child: Child) -> &[Leaf] {
        let first = child.index as usize;
        &self.leaves[first..first + child.lanes.blocks()]
    }

    /// Asks the CPU to start loading `child`'s node or leaf into the cache.
    #[inline(always)]
    fn prefetch(&self, child: Child) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            // A line every 64 bytes of `bytes` from `ptr` (loops of constant
            // length, unrolled). SAFETY: prefetching never faults, whatever the address.
            let lines = |ptr: *const i8, bytes: std::ops::Range<usize>| {
                bytes.step_by(64).for_each(|at| unsafe { _mm_prefetch::<_MM_HINT_T0>(ptr.wrapping_add(at)) })
            };
            if child.is_leaf() {
                let first = self.leaves.as_ptr().wrapping_add(child.index as usize) as *const i8;
                lines(first, 0..size_of::<Leaf>());
                if child.lanes.blocks() > 1 {
                    lines(first, size_of::<Leaf>()..2 * size_of::<Leaf>());
                }
            } else {
                lines(
                    self.nodes.as_ptr().wrapping_add(child.index as usize) as *const i8,
                    0..size_of::<Node>(),
                );
            }
        }
    }
}

/// What the traversal does at a leaf: tests its primitives (its blocks,
/// with their lanes) and returns the `t` of the closest hit so far, which
/// prunes boxes that start beyond it.
///
/// A closure is one; [`Bvh::closest_hit`]'s test is a struct whose method is
/// `#[inline(always)]`, so that it is compiled into the AVX2 traversal
/// (where the two-block triangle test can be inlined too) instead of being
/// called at every leaf, with its results passed through memory.
trait LeafTest<'a> {
    fn test(&mut self, blocks: &'a [Leaf], lanes: Lanes) -> Option<Real>;
}

impl<'a, F: FnMut(&'a [Leaf], Lanes) -> Option<Real>> LeafTest<'a> for F {
    #[inline(always)]
    fn test(&mut self, blocks: &'a [Leaf], lanes: Lanes) -> Option<Real> {
        self(blocks, lanes)
    }
}

/// [`Bvh::closest_hit`]'s leaf test: the query, and the leaf and lane of
/// its best hit while that is a mesh triangle.
struct Closest<'a, 'q, const AVX2: bool> {
    query: &'q mut Query,
    objects: &'a [Object],
    object_blocks: &'a [ObjectBlock],
    methods: Methods,
    /// The longest normal list (bytes) the hit's normal is read from.
    read_up_to: usize,
    /// The leaf and lane of the best hit so far if it is a triangle of a
    /// mesh whose normals are made again from the leaf's corners (its list
    /// is longer than `read_up_to`).
    best_lane: Option<(&'a Leaf, usize)>,
}

/// The longest normal list (bytes) a closest-hit query of a ray on its own
/// ([`Rays::Alone`]) reads its hit's normal from; for a longer one it
/// makes the normal again from the leaf's corners. Reading is the cheaper
/// of the two while the list stays in the cache: making it is a chain of
/// two divisions, a square root and a third division. `rt-view bench
/// --threads 1` on the 2-core development machine (docs/performance.md):
/// reading made single rays 23–29 % faster on the 10 k and 100 k meshes
/// (120 KB and 1.2 MB of normals) and bounce rays 0–4 %; on the 1 M mesh
/// (12 MB) single primary rays 8–12 % faster (a neighbour's hit has loaded
/// the part of the list read: [`Rays::InARun`] always reads) but bounce
/// rays, whose normals are scattered over the list, 4–8 % slower.
const NORMALS_READ_UP_TO: usize = 4 << 20;

impl<'a, const AVX2: bool> LeafTest<'a> for Closest<'a, '_, AVX2> {
    #[inline(always)]
    fn test(&mut self, blocks: &'a [Leaf], lanes: Lanes) -> Option<Real> {
        match self.query.test_leaf_with::<AVX2>(self.objects, self.object_blocks, blocks, lanes, self.methods)
        {
            Best::Kept => {}
            Best::Triangle(block, lane) => {
                self.best_lane = None;
                if let Primitive::Mesh(mesh) = &self.objects[blocks[block].object(lane) as usize].primitive {
                    if mesh.normal_list_bytes() <= self.read_up_to {
                        // Read when the traversal ends ([`Query::finish`]):
                        // started now, the load overlaps the rest of it.
                        mesh.prefetch_normal(blocks[block].index(lane) as usize);
                    } else {
                        self.best_lane = Some((&blocks[block], lane));
                    }
                }
            }
            Best::Object => self.best_lane = None,
        }
        self.query.best_t()
    }
}

/// A ray prepared for many slab tests: its origin and inverse direction,
/// and per axis which of a box's planes it enters by: 0 (min) for a
/// positive direction, 1 (max) for a negative one.
struct Slabs {
    origin: [Real; 3],
    inv: [Real; 3],
    /// `inv · (1 + 2γ₃)`, for the far planes (see [`Slabs::entries`]).
    inv_far: [Real; 3],
    /// Per axis, the rows of a node's bounds the ray enters and leaves by,
    /// counted in the bounds flattened to six rows of four
    /// (`bounds[side][axis]` is row `side · 3 + axis`): all below 6.
    rows: [(usize, usize); 3],
}

impl Slabs {
    fn new(ray: &Ray) -> Self {
        let inv = Vec3::ONE / ray.dir;
        let mut rows = [(0, 0); 3];
        for (axis, row) in rows.iter_mut().enumerate() {
            let side = usize::from(inv[axis] < 0.0);
            *row = (side * 3 + axis, (side ^ 1) * 3 + axis);
        }
        let inv_far = inv * (1.0 + 2.0 * gamma(3));
        Self { origin: ray.origin.into(), inv: inv.into(), inv_far: inv_far.into(), rows }
    }

    /// Where the ray enters each of the node's eight boxes, and a mask with
    /// bit `slot` set where it overlaps `[t_min, t_max]` there.
    ///
    /// A zero direction component gives an infinite inverse; `(min − o)·∞`
    /// is NaN exactly when the origin lies on that face plane, i.e. the ray
    /// runs inside the closed slab. Bounds are updated with `>`/`<`
    /// comparisons, which are false for NaN, so such a bound is ignored
    /// instead of poisoning the result (pbrt-v4's `Bounds3::IntersectP`), for
    /// +0.0 and −0.0 alike; the same comparisons are SIMD max/min.
    ///
    /// The far bound is widened so rounding never rejects a box the ray
    /// touches: it is `(leave − o) · fl(fl(1/d) · (1 + 2γ₃))`, four
    /// roundings (the subtraction, the inverse, the widening, the product),
    /// so at least `t·(1 + 2γ₃)(1 − ε)⁴ ≥ t` in magnitude, where `ε` is the
    /// unit roundoff and `fl(1 + 2γ₃) = 1 + 6ε` in f32 and f64 (pbrt-v4's
    /// `Bounds3::IntersectP` rounds the same four times, widening the
    /// product instead; folding the factor into the inverse saves a
    /// multiplication per box). An inverse that the factor carries past
    /// the largest float becomes ∞: `t₁` is then ±∞, or NaN where the
    /// origin is on the plane, both of which only widen the interval for
    /// rays that start in front of the box.
    ///
    /// This is the reference the SIMD forms are tested against, and the
    /// test f64 geometry and other targets than x86-64 run.
    #[cfg_attr(all(target_arch = "x86_64", not(feature = "f64"), not(test)), allow(dead_code))]
    #[inline(always)]
    fn entries(&self, node: &Node, t_min: Real, t_max: Real) -> ([Real; WIDTH], u32) {
        let mut near = [t_min; WIDTH];
        let mut far = [t_max; WIDTH];
        let rows = node.bounds.as_flattened();
        for axis in 0..3 {
            let (enter, leave) = self.rows[axis];
            debug_assert!(enter < 6 && leave < 6);
            // SAFETY: `rows` has 6 entries, and `Slabs::new` makes every row
            // index below 6 (the offsets come from the ray, not the node, so
            // this saves recomputing them at every node).
            let (enter, leave) = unsafe { (rows.get_unchecked(enter), rows.get_unchecked(leave)) };
            let (o, inv, inv_far) = (self.origin[axis], self.inv[axis], self.inv_far[axis]);
            for slot in 0..WIDTH {
                let t0 = (enter[slot] - o) * inv;
                let t1 = (leave[slot] - o) * inv_far;
                near[slot] = if t0 > near[slot] { t0 } else { near[slot] };
                far[slot] = if t1 < far[slot] { t1 } else { far[slot] };
            }
        }
        let entered = (0..WIDTH).fold(0, |mask, slot| mask | (u32::from(near[slot] <= far[slot]) << slot));
        (near, entered)
    }

    /// [`Slabs::entries`] as two 4-lane SSE tests (SSE2 is part of
    /// x86-64), with the same operations as [`Slabs::entries_avx2`]; the
    /// compiler does not find this form in the loops of `entries` at eight
    /// lanes.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[inline(always)]
    fn entries_sse(&self, node: &Node, t_min: Real, t_max: Real) -> ([Real; WIDTH], u32) {
        use std::arch::x86_64::*;
        let rows = node.bounds.as_flattened();
        let mut out = [0.0; WIDTH];
        let mut entered = 0;
        // SAFETY: SSE and SSE2 are part of every x86-64 CPU; the loads and
        // stores are argued below.
        for half in 0..2 {
            unsafe {
                let mut near = _mm_set1_ps(t_min);
                let mut far = _mm_set1_ps(t_max);
                for axis in 0..3 {
                    let (enter, leave) = self.rows[axis];
                    debug_assert!(enter < 6 && leave < 6);
                    // SAFETY: as in `entries`; each half row is four f32 at a
                    // multiple of 16 bytes from the node's 64-byte-aligned start.
                    let (enter, leave) = (
                        _mm_load_ps(rows.get_unchecked(enter).as_ptr().add(4 * half)),
                        _mm_load_ps(rows.get_unchecked(leave).as_ptr().add(4 * half)),
                    );
                    let o = _mm_set1_ps(self.origin[axis]);
                    let t0 = _mm_mul_ps(_mm_sub_ps(enter, o), _mm_set1_ps(self.inv[axis]));
                    let t1 = _mm_mul_ps(_mm_sub_ps(leave, o), _mm_set1_ps(self.inv_far[axis]));
                    near = _mm_max_ps(t0, near);
                    far = _mm_min_ps(t1, far);
                }
                entered |= (_mm_movemask_ps(_mm_cmple_ps(near, far)) as u32) << (4 * half);
                // `out` has room for four f32 from `4 · half`.
                _mm_storeu_ps(out.as_mut_ptr().add(4 * half), near);
            }
        }
        (out, entered)
    }

    /// [`Slabs::entries`] as one 8-lane AVX2 test: the same operations in
    /// the same order, lane by lane (`maxps`/`minps` return their second
    /// operand where a comparison is false, as the `if`s above do, NaN
    /// included; `cmpps` with `_CMP_LE_OQ` is false for NaN as `<=` is), so
    /// the same bits (tested).
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn entries_avx2(&self, node: &Node, t_min: Real, t_max: Real) -> ([Real; WIDTH], u32) {
        use std::arch::x86_64::*;
        let rows = node.bounds.as_flattened();
        let mut near = _mm256_set1_ps(t_min);
        let mut far = _mm256_set1_ps(t_max);
        for axis in 0..3 {
            let (enter, leave) = self.rows[axis];
            debug_assert!(enter < 6 && leave < 6);
            // SAFETY: as in `entries`; each row is eight f32 at a multiple of
            // 32 bytes from the node's 64-byte-aligned start.
            let (enter, leave) = unsafe {
                (
                    _mm256_load_ps(rows.get_unchecked(enter).as_ptr()),
                    _mm256_load_ps(rows.get_unchecked(leave).as_ptr()),
                )
            };
            let o = _mm256_set1_ps(self.origin[axis]);
            let t0 = _mm256_mul_ps(_mm256_sub_ps(enter, o), _mm256_set1_ps(self.inv[axis]));
            let t1 = _mm256_mul_ps(_mm256_sub_ps(leave, o), _mm256_set1_ps(self.inv_far[axis]));
            near = _mm256_max_ps(t0, near);
            far = _mm256_min_ps(t1, far);
        }
        let entered = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
        let mut out = [0.0; WIDTH];
        // SAFETY: `out` has room for eight f32.
        unsafe { _mm256_storeu_ps(out.as_mut_ptr(), near) };
        (out, entered)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::test_support::{
        grid_mesh, primitives_of, random_parts, random_primitive as primitive, scene_of as scene, v,
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
                // The normal too: single rays take a triangle's from its leaf's corners.
                let key = |h: Hit| (h.object, h.primitive, h.t.to_bits(), h.normal.to_array().map(Real::to_bits));
                prop_assert_eq!(bvh.map(key), brute.map(key), "ray {:?}", ray);
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

    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    proptest! {
        #[test]
        fn the_sse_and_avx2_node_tests_give_the_portable_test_bits(
            boxes in prop::collection::vec((prop::array::uniform3(-10f32..10.0), prop::array::uniform3(0f32..5.0), any::<bool>()), WIDTH),
            origin in prop::array::uniform3(-15f32..15.0),
            dir in prop::array::uniform3(-1f32..1.0),
            zero_mask in 0u8..8, negative_zero in any::<bool>(), on_a_face in any::<bool>(),
            t_min in 0f32..1.0, t_max in prop::sample::select(vec![0.5, 5.0, 50.0, Real::INFINITY]),
        ) {
            let mut node = Node::EMPTY;
            for (slot, &(lo, extent, used)) in boxes.iter().enumerate() {
                if used {
                    node.set(slot, Aabb::new(v(lo), v(lo) + v(extent)).unwrap(), Child::node(0));
                }
            }
            let (mut origin, mut d) = (v(origin), v(dir));
            for axis in 0..3 {
                if zero_mask & (1 << axis) != 0 {
                    d[axis] = if negative_zero { -0.0 } else { 0.0 };
                    // On a face plane of the first box: (min − o)·∞ is NaN.
                    if on_a_face {
                        origin[axis] = boxes[0].0[axis];
                    }
                }
            }
            let slabs = Slabs::new(&Ray::new(origin, d));
            let (near, entered) = slabs.entries(&node, t_min, t_max);
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked just above).
                let (near_avx2, entered_avx2) = unsafe { slabs.entries_avx2(&node, t_min, t_max) };
                prop_assert_eq!(entered, entered_avx2);
                prop_assert_eq!(near.map(Real::to_bits), near_avx2.map(Real::to_bits));
            }
            let (near_sse, entered_sse) = slabs.entries_sse(&node, t_min, t_max);
            prop_assert_eq!(entered, entered_sse);
            prop_assert_eq!(near.map(Real::to_bits), near_sse.map(Real::to_bits));
        }
    }

    #[test]
    fn the_leaves_a_ray_enters_are_visited_nearest_first_whichever_way_it_goes() {
        // Eight balls in a row along x, in leaves under the one root node.
        // A leaf test that finds nothing lets the traversal go on to every
        // leaf on the ray's line; they must come nearest first, so that a
        // hit found early prunes the rest, for either direction along the
        // row (the node's slots are in one order, the ray may go the other).
        let balls: Vec<Primitive> = (0..8)
            .map(|k| {
                Primitive::Sphere(
                    crate::geometry::sphere::Sphere::new(v([3.0 * k as f32, 0.0, 0.0]), 1.0).unwrap(),
                )
            })
            .collect();
        let s = scene(balls);
        let bvh = Bvh::build(s.objects());
        assert_eq!(bvh.stats().nodes, 1, "one root node over the leaves");
        for (origin, dir) in [(-5.0, 1.0), (26.0, -1.0)] {
            let ray = Ray::new(Vec3::new(origin, 0.0, 0.0), Vec3::new(dir, 0.0, 0.0));
            // Each leaf visited, by the balls it holds (numbered along +x).
            let mut visited = Vec::new();
            bvh.traverse(&ray, Interval::new(0.0, Real::INFINITY), |blocks, lanes| {
                let balls = (blocks.iter().enumerate())
                    .flat_map(|(b, leaf)| lanes_of(lanes.block(b).objects()).map(|lane| leaf.object(lane)));
                visited.push(balls.collect::<Vec<_>>());
                None
            });
            assert!(visited.len() > 2, "{visited:?}");
            assert_eq!(visited.iter().map(Vec::len).sum::<usize>(), 8, "{visited:?}");
            let mut nearest_first = visited.clone();
            nearest_first.sort_by_key(|balls| if dir > 0.0 { balls[0] as i64 } else { -(balls[0] as i64) });
            assert_eq!(visited, nearest_first, "ray from x = {origin}");
        }
    }

    #[test]
    fn a_coherent_query_reads_the_normal_an_incoherent_one_makes_again_and_they_agree() {
        // A mesh whose normal list is past NORMALS_READ_UP_TO: a ray on its
        // own makes its hit's normal from the leaf's corners, one of a run of
        // neighbours reads it from the list. Same hit, same bits.
        let n = 430;
        let grid = grid_mesh(n, |i, j| {
            Vec3::new(i as Real * 0.1, ((i * 7 + j * 13) % 11) as Real * 0.013, j as Real * 0.1)
        });
        let s = scene(vec![Primitive::Mesh(grid)]);
        let Primitive::Mesh(mesh) = &s.objects()[0].primitive else { unreachable!() };
        assert!(mesh.normal_list_bytes() > NORMALS_READ_UP_TO, "{} bytes", mesh.normal_list_bytes());
        let bvh = Bvh::build(s.objects());
        let (mut hits, mut normals_differ) = (0, 0);
        for k in 0..400 {
            let target = Vec3::new((k % 20) as Real * 2.1 + 0.37, 0.0, (k / 20) as Real * 2.1 + 0.61);
            let ray = Ray::new(Vec3::new(21.0, 9.0, -4.0), target - Vec3::new(21.0, 9.0, -4.0));
            let range = Interval::new(0.0, Real::INFINITY);
            let alone = bvh.closest_hit(s.objects(), &ray, range, Methods::default());
            let in_a_run = bvh.closest_hit_among(s.objects(), &ray, range, Methods::default(), Rays::InARun);
            assert_eq!(alone, in_a_run, "ray {k}");
            if let Some(hit) = alone {
                hits += 1;
                assert_eq!(hit.normal, mesh.normal(hit.primitive), "ray {k}");
                normals_differ += usize::from(hit.normal != mesh.normal(0));
            }
        }
        assert!(hits == 400 && normals_differ > 100, "{hits} hits, {normals_differ} tilted");
    }

    #[test]
    fn a_box_entered_exactly_at_the_closest_hit_so_far_is_still_visited() {
        // It can hold a hit at that same t with a lower index, which wins the tie.
        let mut node = Node::EMPTY;
        node.set(3, Aabb::new(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)).unwrap(), Child::node(0));
        let slabs = Slabs::new(&Ray::new(Vec3::new(0.0, 0.5, 0.5), Vec3::X));
        let (near, entered) = slabs.entries(&node, 0.0, 2.0);
        assert_eq!((near[3], entered), (2.0, 1 << 3));
        assert_eq!(slabs.entries(&node, 0.0, 1.9).1, 0);
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        {
            assert_eq!(slabs.entries_sse(&node, 0.0, 2.0), slabs.entries(&node, 0.0, 2.0));
            assert_eq!(slabs.entries_sse(&node, 0.0, 1.9).1, 0);
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2 (checked just above).
                unsafe {
                    assert_eq!(slabs.entries_avx2(&node, 0.0, 2.0), slabs.entries(&node, 0.0, 2.0));
                    assert_eq!(slabs.entries_avx2(&node, 0.0, 1.9).1, 0);
                }
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
        // only the farthest few, so the tree is a long chain whose stack
        // bound is past the inline stack: every query takes the
        // heap-allocated stack (and packets fall back to single rays).
        let boxes: Vec<Primitive> = (0..300)
            .map(|k| {
                let s = (1.3 as Real).powi(k);
                Primitive::Aabb(Aabb::new(Vec3::splat(s), Vec3::splat(1.2 * s)).unwrap())
            })
            .collect();
        let s = scene(boxes);
        let bvh = Bvh::build(s.objects());
        assert!(bvh.stack_bound > INLINE_STACK, "stack bound {}", bvh.stack_bound);
        for k in 0..300 {
            let target = Vec3::splat(1.1 * (1.3 as Real).powi(k));
            let mut rays = Vec::new();
            for origin in [Vec3::new(-1.0, 0.0, 0.5), Vec3::splat(1e30)] {
                let ray = Ray::new(origin, target - origin);
                let range = s.cast_range(&ray);
                let expected = s.closest_hit_brute_force(&ray, range);
                assert!(expected.is_some());
                assert_eq!(
                    bvh.closest_hit(s.objects(), &ray, range, Methods::default()),
                    expected,
                    "box {k}"
                );
                assert!(bvh.any_hit(s.objects(), &ray, range, Methods::default()));
                rays.push((ray, range, expected));
            }
            let mut hits = [None; 2];
            let (only, ranges): (Vec<Ray>, Vec<Interval>) = rays.iter().map(|r| (r.0, r.1)).unzip();
            bvh.closest_hits(s.objects(), &only, &ranges, Methods::default(), &mut hits);
            assert_eq!(hits.to_vec(), rays.iter().map(|r| r.2).collect::<Vec<_>>());
        }
    }

    #[test]
    fn nodes_fill_four_cache_lines_with_f32_geometry() {
        if size_of::<Real>() == 4 {
            assert_eq!(size_of::<Node>(), 256);
            assert_eq!(align_of::<Node>(), 64);
        }
    }

    #[test]
    fn the_tree_is_the_same_node_for_node_on_one_thread_and_on_many() {
        // 2·130² = 33 800 triangles on a bumpy grid: over the collapse's
        // threshold, so the root's children are collapsed on several threads.
        let height = |i: u32, j: u32| ((i * 7919 + j * 104_729) % 1000) as Real / 400.0;
        let s = scene(vec![Primitive::Mesh(grid_mesh(130, |i, j| {
            Vec3::new(i as Real, height(i, j), j as Real)
        }))]);
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut bvh = pool.install(|| Bvh::build(s.objects()));
            (bvh.stats.build_time, bvh.stats.build_steps) = (Duration::ZERO, BuildSteps::default());
            bvh
        };
        let one = on(1);
        assert!(one.stats.nodes > 500, "{} nodes", one.stats.nodes);
        // Compared as printed: unused leaf lanes hold NaN, which is not equal to itself.
        let printed = |bvh: &Bvh| format!("{bvh:?}");
        assert_eq!(printed(&one), printed(&on(4)));
        assert_eq!(printed(&one), printed(&on(3)));
    }

    #[test]
    fn a_large_mesh_builds_a_shallow_tree_and_stats_add_up() {
        // A 100×100 grid: 20 000 triangles.
        let grid = grid_mesh(100, |i, j| Vec3::new(i as Real, j as Real, 0.0));
        let s = scene(vec![Primitive::Mesh(grid)]);
        let stats = s.bvh_stats();
        assert_eq!(stats.primitives, 20_000);
        assert!(stats.leaves >= 20_000 / build::MAX_LEAF && stats.leaves < 20_000);
        // Each node adds at most WIDTH − 1 slots to the tree's one, so L
        // leaves need at least (L − 1)/(WIDTH − 1) nodes; the collapse fills
        // nodes, so there are not many more (a binary tree would have L − 1).
        let fewest = (stats.leaves - 1).div_ceil(WIDTH - 1);
        assert!(
            stats.nodes >= fewest && stats.nodes < 2 * fewest,
            "{} nodes, {} leaves",
            stats.nodes,
            stats.leaves
        );
        assert!(stats.depth <= 5, "depth {}", stats.depth);
        assert!(stats.leaf_blocks >= stats.leaves && stats.leaf_blocks <= leaf::BLOCKS * stats.leaves);
        assert_eq!(stats.bytes, stats.nodes * size_of::<Node>() + stats.leaf_blocks * size_of::<Leaf>());
        let ray = Ray::new(Vec3::new(37.3, 61.2, -10.0), Vec3::Z);
        let hit = s.cast(&ray).unwrap();
        assert_eq!(Some(hit), s.closest_hit_brute_force(&ray, s.cast_range(&ray)));
    }

    #[test]
    fn the_build_steps_are_timed_one_after_another_within_the_build_time() {
        let grid = grid_mesh(100, |i, j| Vec3::new(i as Real, j as Real, 0.0));
        let stats = scene(vec![Primitive::Mesh(grid)]).bvh_stats();
        let s = stats.build_steps;
        // Consecutive laps of one monotonic clock: together no longer than
        // the whole, and the binary tree over 20 000 items takes some time.
        let total: Duration = s.named().iter().map(|&(_, d)| d).sum();
        assert!(total <= stats.build_time, "{s:?} against {:?}", stats.build_time);
        assert!(s.binary_tree > Duration::ZERO && s.collapse > Duration::ZERO, "{s:?}");
        let line = s.to_string();
        assert!(
            line.starts_with("items ") && line.contains(", binary tree ") && line.ends_with(" s"),
            "{line}"
        );
    }
}
