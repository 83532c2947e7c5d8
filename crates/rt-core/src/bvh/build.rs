//! The first step of the build: a binary tree by the binned surface-area
//! heuristic (Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", 2007), in parallel.
//!
//! Each node's items are binned into [`BINS`] bins along the axis where
//! their centroids spread most; the split between bins that minimises
//! `n_left·A_left + n_right·A_right` wins, unless making a leaf costs less.
//! Large nodes bin their items on every thread (each thread bins a share,
//! then the bins are merged), and the two halves of a split are built at
//! the same time (`rayon::join`). A child built on one thread is binned by
//! its parent's partition, as the items move to their sides, so each level
//! of the tree reads its items once. Every decision depends only on the
//! node's items, and merging bins (box unions, counts) is exact whatever
//! the order, so the tree is the same, node for node, on any number of
//! threads (tested).
//!
//! The binary tree lives only until the collapse (`bvh/collapse.rs`) has
//! read it, so its nodes are not allocated one by one: each task that
//! builds a subtree appends its nodes' pairs of children to a list of its
//! own ([`Arena`]), and a subtree built by another task (the second half of
//! a parallel split) comes back as a [`BuildNode::Subtree`] with its list.
//! On the 1 M-triangle terrain that replaced about 200 000 allocations and
//! frees of a pair by a few hundred growing lists (3 % fewer instructions;
//! the 2-thread build 3 % faster, the 1-thread one level: docs/performance.md).

use rayon::prelude::*;

use super::item::{Item, Wide};
use crate::geometry::aabb::Aabb;
use crate::math::real::Real;

/// Leaves hold at most this many primitives.
pub(super) const MAX_LEAF: usize = super::leaf::LANES * super::leaf::BLOCKS;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this depth the SAH chooses splits; from here on, splits are at the
/// median, so the depth stays under SAH_DEPTH plus log₂ of the primitive count.
const SAH_DEPTH: usize = 64;
/// Cost of visiting a node relative to testing one primitive.
pub(super) const TRAVERSAL_COST: Real = 1.0;
/// Nodes with more items than this bin them on all threads and build their
/// halves in parallel; smaller ones are built by one thread.
const PARALLEL_ITEMS: usize = 8 * 1024;

/// The pairs of children of a task's inner nodes, in the order they were
/// made (an inner node's pair after its subtrees' pairs).
pub(super) type Arena = Vec<[BuildNode; 2]>;

/// A node of the binary tree; an inner node's children are a pair in the
/// [`Arena`] of the task that built it.
#[derive(Debug, PartialEq)]
pub(super) enum BuildNode {
    /// `count` items at `first` in the final item order.
    Leaf { bounds: Aabb, first: u32, count: u32 },
    /// Two subtrees over the `count` items at `first`: the pair at
    /// `children` in the arena.
    Inner { bounds: Aabb, children: u32, first: u32, count: u32 },
    /// A subtree built by another task: its root, and the arena its root's
    /// descendants are in.
    Subtree(Box<(BuildNode, Arena)>),
}

impl BuildNode {
    /// The box around everything below.
    pub fn bounds(&self) -> Aabb {
        match self {
            Self::Leaf { bounds, .. } | Self::Inner { bounds, .. } => *bounds,
            Self::Subtree(tree) => tree.0.bounds(),
        }
    }

    /// The items below: the first one's position and how many.
    pub fn items(&self) -> (u32, u32) {
        match self {
            Self::Leaf { first, count, .. } | Self::Inner { first, count, .. } => (*first, *count),
            Self::Subtree(tree) => tree.0.items(),
        }
    }

    /// This node as a leaf or an inner node, with the arena its children
    /// are in: `arena` itself, or a subtree's own.
    pub fn resolve<'a>(&'a self, arena: &'a [[BuildNode; 2]]) -> (&'a BuildNode, &'a [[BuildNode; 2]]) {
        match self {
            Self::Subtree(tree) => (&tree.0, &tree.1),
            _ => (self, arena),
        }
    }
}

/// A binary tree: its root and the root task's [`Arena`].
#[derive(Debug, PartialEq)]
pub(super) struct BinaryTree {
    pub root: BuildNode,
    pub arena: Arena,
}

/// Builds the binary tree over `items` (non-empty), reordering them so that
/// every leaf's items are contiguous; also returns how many leaves it has.
/// `sizes` (as long as `items`, all 0) gets each leaf's item count at its
/// first item's position, so the leaves can be listed in tree order (their
/// items' order) without walking the tree.
pub(super) fn build(items: &mut [Item], sizes: &mut [u8]) -> (BinaryTree, usize) {
    debug_assert_eq!(items.len(), sizes.len());
    let all = Bin::of(items, items.len() > PARALLEL_ITEMS);
    let mut arena = Arena::new();
    let (root, leaves) = build_node(items, sizes, all, None, 0, 0, &mut arena);
    (BinaryTree { root, arena }, leaves)
}

/// How a node's items are binned: along `axis`, item `i` into bin
/// `⌊(cᵢ − lo)·scale⌋` (clamped to the bins) of its centroid `cᵢ`.
#[derive(Clone, Copy)]
struct Binning {
    axis: usize,
    lo: Real,
    scale: Real,
}

impl Binning {
    /// How the node of `n` items at `depth` whose [`Bin`] is `all` bins
    /// them, or `None` where it does not (a leaf of one item, coincident
    /// centroids, or deeper than [`SAH_DEPTH`]: the median split).
    fn of(all: &Bin, n: usize, depth: usize) -> Option<Binning> {
        let centroids = all.centroids();
        let axis = centroids.size().max_position();
        let (lo, extent) = (centroids.min()[axis], centroids.size()[axis]);
        (n > 1 && extent > 0.0 && depth < SAH_DEPTH).then(|| Binning {
            axis,
            lo,
            scale: BINS as Real / extent,
        })
    }

    /// The bin of the centroid `c` (through `i32`, whose conversion takes
    /// fewer instructions than `usize`'s; a NaN gives 0 either way).
    #[inline(always)]
    fn bin(&self, c: Wide) -> usize {
        (((c[self.axis] - self.lo) * self.scale) as i32).clamp(0, BINS as i32 - 1) as usize
    }

    /// Whether the centroid `c` falls into a bin below `k` (`1 ≤ k < BINS`):
    /// [`Binning::bin`]`(c) < k` without the conversion to an integer (for
    /// `x ≥ 0`, `⌊x⌋ < k` exactly when `x < k`; a NaN, bin 0, and a
    /// negative `x` go below too).
    #[inline(always)]
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // a NaN goes below, as bin 0 does
    fn below(&self, c: Wide, k: usize) -> bool {
        !((c[self.axis] - self.lo) * self.scale >= k as Real)
    }
}

/// The boxes of a set of items: around the items, and around their
/// centroids.
#[derive(Clone, Copy)]
struct Bin {
    /// Box around the items (empty: min = +∞, max = −∞).
    min: Wide,
    max: Wide,
    /// Box around their centroids.
    centroid_min: Wide,
    centroid_max: Wide,
    count: usize,
    /// How many of them are whole objects (the rest are mesh triangles).
    whole: usize,
}

impl Bin {
    const EMPTY: Bin = Bin {
        min: Wide::INFINITY,
        max: Wide::NEG_INFINITY,
        centroid_min: Wide::INFINITY,
        centroid_max: Wide::NEG_INFINITY,
        count: 0,
        whole: 0,
    };

    /// Adds `item`, whose centroid is `centroid`; `WHOLE` false where the
    /// caller knows that no item is a whole object (the count stays 0).
    #[inline(always)]
    fn add<const WHOLE: bool>(&mut self, item: &Item, centroid: Wide) {
        self.min = self.min.min(item.min());
        self.max = self.max.max(item.max());
        self.centroid_min = self.centroid_min.min(centroid);
        self.centroid_max = self.centroid_max.max(centroid);
        self.count += 1;
        if WHOLE {
            self.whole += usize::from(item.is_whole());
        }
    }

    fn merge(&mut self, other: &Bin) {
        self.min = self.min.min(other.min);
        self.max = self.max.max(other.max);
        self.centroid_min = self.centroid_min.min(other.centroid_min);
        self.centroid_max = self.centroid_max.max(other.centroid_max);
        self.count += other.count;
        self.whole += other.whole;
    }

    /// What testing these items in leaves costs, relative to one node
    /// visit: leaves test a block of up to [`LANES`](super::leaf::LANES)
    /// mesh triangles at once with SIMD, so triangles cost by the block
    /// (Embree's SAH counts blocks the same way); every other primitive is
    /// tested on its own.
    fn leaf_cost(&self) -> Real {
        (self.count - self.whole).div_ceil(super::leaf::LANES) as Real + self.whole as Real
    }

    /// The items of `items`, on all threads if `parallel` (min and max are
    /// exact in any order, so the result is the same).
    fn of(items: &[Item], parallel: bool) -> Bin {
        let all = |chunk: &[Item]| {
            let mut bin = Bin::EMPTY;
            chunk.iter().for_each(|item| bin.add::<true>(item, item.centroid()));
            bin
        };
        if parallel {
            items.par_chunks(PARALLEL_ITEMS / 2).map(all).reduce(|| Bin::EMPTY, |a, b| a.merged(&b))
        } else {
            all(items)
        }
    }

    fn merged(mut self, other: &Bin) -> Bin {
        self.merge(other);
        self
    }

    // `Wide` is `Real`'s vector in the f64 build: the conversions are the
    // identity there.
    #[allow(clippy::useless_conversion)]
    fn bounds(&self) -> Aabb {
        Aabb::from_corners(self.min.into(), self.max.into())
    }

    #[allow(clippy::useless_conversion)]
    fn centroids(&self) -> Aabb {
        Aabb::from_corners(self.centroid_min.into(), self.centroid_max.into())
    }

    /// The surface area of the box, 0 when empty: [`Aabb::surface_area`]'s
    /// operations in its order (so the same bits), on the corners as they
    /// are (a bin's minimum is never above its maximum).
    fn area(&self) -> Real {
        if self.count == 0 {
            return 0.0;
        }
        let s = self.max - self.min;
        2.0 * (s.x * s.y + s.y * s.z + s.z * s.x)
    }
}

fn merge_bins(mut a: [Bin; BINS], b: [Bin; BINS]) -> [Bin; BINS] {
    for (x, y) in a.iter_mut().zip(&b) {
        x.merge(y);
    }
    a
}

/// The items of `items` in [`BINS`] bins along `axis`: item `i` goes to
/// bin `⌊(cᵢ − lo)·scale⌋` (clamped) of its centroid `cᵢ`. `WHOLE` as in
/// [`Bin::add`].
///
/// Consecutive items tend to fall into the same bin (a mesh's triangles
/// come in spatial order), and each update of a bin waits for the one
/// before it to be written; so even and odd items go to two sets of bins,
/// merged at the end (exact in any order), which halves that chain.
fn bin_items<const WHOLE: bool>(items: &[Item], binning: Binning) -> [Bin; BINS] {
    let (mut even, mut odd) = ([Bin::EMPTY; BINS], [Bin::EMPTY; BINS]);
    let mut pairs = items.chunks_exact(2);
    for pair in &mut pairs {
        let (a, b) = (pair[0].centroid(), pair[1].centroid());
        even[binning.bin(a)].add::<WHOLE>(&pair[0], a);
        odd[binning.bin(b)].add::<WHOLE>(&pair[1], b);
    }
    for item in pairs.remainder() {
        let c = item.centroid();
        even[binning.bin(c)].add::<WHOLE>(item, c);
    }
    merge_bins(even, odd)
}

/// The node over `items` (`all` is their [`Bin`]; `binned`, if given,
/// their bins by [`Binning::of`]), which start at `first` in the final
/// order, and how many leaves it has; each leaf's size goes into `sizes`
/// (the items' slice of [`build`]'s) at its first item, and the pairs of
/// children of its inner nodes into `arena` (those of a half built by
/// another task into that task's, returned in a [`BuildNode::Subtree`]).
fn build_node(
    items: &mut [Item],
    sizes: &mut [u8],
    all: Bin,
    binned: Option<&[Bin; BINS]>,
    first: usize,
    depth: usize,
    arena: &mut Arena,
) -> (BuildNode, usize) {
    let n = items.len();
    let parallel = n > PARALLEL_ITEMS;
    let bounds = all.bounds();
    let leaf = |sizes: &mut [u8]| {
        // MAX_LEAF items at most: a size fits a byte.
        sizes[0] = n as u8;
        (BuildNode::Leaf { bounds, first: first as u32, count: n as u32 }, 1)
    };
    if n <= 1 {
        return leaf(sizes);
    }
    // The node's own bins where it bins its items, and its children's
    // where they are binned here; referred to, not copied (1.3 kB each).
    let own;
    let mut children_bins;
    let median = |items: &mut [Item]| {
        let centroids = all.centroids();
        sort_by_centroid(items, centroids.size().max_position(), parallel);
        let (left, right) = items.split_at(n / 2);
        (n / 2, Bin::of(left, parallel), Bin::of(right, parallel), None, None)
    };
    let (mid, left_bin, right_bin, left_bins, right_bins) = match Binning::of(&all, n, depth) {
        None => {
            // Coincident centroids, or deep enough: a leaf if small, else the median.
            if n <= MAX_LEAF && all.centroids().size().max_element() <= 0.0 {
                return leaf(sizes);
            }
            median(items)
        }
        Some(binning) => {
            // Each thread bins a chunk in place; merging bins is exact in any order.
            let bin_all = |chunk: &[Item]| {
                if all.whole == 0 {
                    bin_items::<false>(chunk, binning)
                } else {
                    bin_items::<true>(chunk, binning)
                }
            };
            let bins = match binned {
                Some(bins) => bins,
                None => {
                    own = if parallel {
                        items
                            .par_chunks(PARALLEL_ITEMS / 2)
                            .map(bin_all)
                            .reduce(|| [Bin::EMPTY; BINS], merge_bins)
                    } else {
                        bin_all(items)
                    };
                    &own
                }
            };
            match best_split(bins, bounds) {
                Some(best) if !(n <= MAX_LEAF && best.1 >= all.leaf_cost() && !apart_pays(items, &all)) => {
                    let side =
                        |range: std::ops::Range<usize>| bins[range].iter().fold(Bin::EMPTY, Bin::merged);
                    let (left, right) = (side(0..best.0), side(best.0..BINS));
                    // A child that will bin its items on one thread gets
                    // them binned here, as the partition moves them: one
                    // pass over the items per level instead of two.
                    let plan = |side: &Bin| {
                        (side.count <= PARALLEL_ITEMS || rayon::current_num_threads() == 1)
                            .then(|| Binning::of(side, side.count, depth + 1))
                            .flatten()
                    };
                    let plans = [plan(&left), plan(&right)];
                    children_bins = [[Bin::EMPTY; BINS]; 2];
                    let mid = if all.whole == 0 {
                        partition_and_bin::<false>(
                            items,
                            |c| binning.below(c, best.0),
                            plans,
                            &mut children_bins,
                        )
                    } else {
                        partition_and_bin::<true>(
                            items,
                            |c| binning.below(c, best.0),
                            plans,
                            &mut children_bins,
                        )
                    };
                    debug_assert_eq!(mid, left.count);
                    let [l, r] = &children_bins;
                    (mid, left, right, plans[0].map(|_| l), plans[1].map(|_| r))
                }
                _ if n <= MAX_LEAF => return leaf(sizes),
                _ => median(items),
            }
        }
    };
    let (left, right) = items.split_at_mut(mid);
    let (left_sizes, right_sizes) = sizes.split_at_mut(mid);
    let ((l, l_leaves), (r, r_leaves)) = if parallel {
        rayon::join(
            || build_node(left, left_sizes, left_bin, left_bins, first, depth + 1, arena),
            || {
                // Another task may take this half: it keeps its own list.
                let mut own = Arena::new();
                let (r, leaves) =
                    build_node(right, right_sizes, right_bin, right_bins, first + mid, depth + 1, &mut own);
                (BuildNode::Subtree(Box::new((r, own))), leaves)
            },
        )
    } else {
        (
            build_node(left, left_sizes, left_bin, left_bins, first, depth + 1, arena),
            build_node(right, right_sizes, right_bin, right_bins, first + mid, depth + 1, arena),
        )
    };
    arena.push([l, r]);
    let inner =
        BuildNode::Inner { bounds, children: (arena.len() - 1) as u32, first: first as u32, count: n as u32 };
    (inner, l_leaves + r_leaves)
}

/// Moves the items whose centroid `left` holds for to the front, as
/// [`partition`] does, and bins each side by its [`Binning`] (where given)
/// on the way into `bins` (left, right; empty to begin with); returns how
/// many went left.
///
/// As in [`bin_items`], neighbouring items tend to fall into the same bin,
/// and each update of a bin waits for the one before it; so in a node over
/// [`PARALLEL_ITEMS`] (on one thread, its children are binned here) each
/// side's items go to two sets of bins by the parity of their position,
/// merged at the end (exact in any order: the same bins). That took 4 %
/// off the one-thread binary tree of the 1 M-triangle terrain; used on
/// every node, the second sets (cleared and merged each time) made it 30 %
/// slower instead, so only large nodes use them (docs/performance.md).
fn partition_and_bin<const WHOLE: bool>(
    items: &mut [Item],
    left: impl Fn(Wide) -> bool,
    binnings: [Option<Binning>; 2],
    bins: &mut [[Bin; BINS]; 2],
) -> usize {
    if binnings.iter().all(Option::is_none) {
        return partition(items, |i| left(i.centroid()));
    }
    if items.len() > PARALLEL_ITEMS {
        partition_and_bin_in::<WHOLE, true>(items, left, binnings, bins)
    } else {
        partition_and_bin_in::<WHOLE, false>(items, left, binnings, bins)
    }
}

/// [`partition_and_bin`] with a second set of bins for each side where
/// `TWO_SETS`.
fn partition_and_bin_in<const WHOLE: bool, const TWO_SETS: bool>(
    items: &mut [Item],
    left: impl Fn(Wide) -> bool,
    [left_binning, right_binning]: [Option<Binning>; 2],
    bins: &mut [[Bin; BINS]; 2],
) -> usize {
    // The second set of each side, for the items at odd positions.
    let mut odd = [[Bin::EMPTY; BINS]; 2];
    let add = |bins: &mut [[Bin; BINS]; 2],
               odd: &mut [[Bin; BINS]; 2],
               side: usize,
               at: usize,
               item: &Item,
               c: Wide| {
        if let Some(b) = [left_binning, right_binning][side] {
            let set = if TWO_SETS && at & 1 == 1 { &mut odd[side] } else { &mut bins[side] };
            set[b.bin(c)].add::<WHOLE>(item, c);
        }
    };
    // Hoare's scheme as in `partition`; each item is binned once, when its
    // side is settled.
    let (mut i, mut j) = (0, items.len());
    loop {
        while i < j {
            let c = items[i].centroid();
            if !left(c) {
                break;
            }
            add(bins, &mut odd, 0, i, &items[i], c);
            i += 1;
        }
        while i < j {
            let c = items[j - 1].centroid();
            if left(c) {
                break;
            }
            add(bins, &mut odd, 1, j - 1, &items[j - 1], c);
            j -= 1;
        }
        if i + 1 >= j {
            break;
        }
        items.swap(i, j - 1);
        add(bins, &mut odd, 0, i, &items[i], items[i].centroid());
        add(bins, &mut odd, 1, j - 1, &items[j - 1], items[j - 1].centroid());
        i += 1;
        j -= 1;
    }
    if TWO_SETS {
        for (set, other) in bins.iter_mut().zip(odd) {
            *set = merge_bins(*set, other);
        }
    }
    i
}

/// Whether the whole objects among `items` (at most [`MAX_LEAF`], with
/// their bin `all`) are cheaper in leaves of their own than in one leaf:
/// split down to single items, they end up as children of one 8-wide node
/// (the collapse fills a node's eight slots), so a ray pays one node visit
/// and then tests only the items whose boxes it enters: `c_node + Σ
/// A(itemᵢ)/A(all)·c_leaf(itemᵢ)` against the leaf's `Σ c_leaf`. The
/// greedy binned SAH never sees this for a few large objects that overlap
/// (the walls of a room): every split into two groups has children as
/// large as the room, so each split alone costs more than the leaf. Mesh
/// triangles are left to the SAH (a block of four costs one test).
fn apart_pays(items: &[Item], all: &Bin) -> bool {
    if all.whole == 0 {
        return false;
    }
    let area = all.bounds().surface_area().max(Real::MIN_POSITIVE);
    let apart: Real = items.iter().map(|item| item.bounds().surface_area() / area).sum();
    TRAVERSAL_COST + apart < all.leaf_cost()
}

/// The best split between bins `k − 1` and `k`, and its cost relative to
/// testing one primitive (`TRAVERSAL_COST + Σ nᵢ·Aᵢ / A`); `None` if every
/// item is in one bin.
///
/// Only the bins with items are swept: an empty bin leaves both sides'
/// boxes and counts as they are (min with +∞, max with −∞, +0 are exact),
/// so a split next to it costs what the split before it costs, and of equal
/// costs the first wins. Among the splits that leave the same items on each
/// side that is the one just past the last non-empty bin on the left, which
/// is the one returned (the same as a sweep over all bins, tested). Most
/// nodes are small (a few dozen items or fewer in 16 bins), and this halves
/// their sweeps.
fn best_split(bins: &[Bin; BINS], bounds: Aabb) -> Option<(usize, Real)> {
    // The non-empty bins' indices, in order (written unconditionally, kept
    // by advancing the count: no branch on the bin's count).
    let mut full = [0u8; BINS];
    let mut m = 0;
    for (k, bin) in bins.iter().enumerate() {
        full[m] = k as u8;
        m += usize::from(bin.count > 0);
    }
    if m < 2 {
        return None;
    }
    // Sweep from the right for the right-hand areas, then from the left;
    // `t` is the first non-empty bin on the right.
    let mut right_area = [0.0 as Real; BINS];
    let mut right_cost = [0.0 as Real; BINS];
    let mut acc = Bin::EMPTY;
    for t in (1..m).rev() {
        acc.merge(&bins[usize::from(full[t])]);
        right_area[t] = acc.area();
        right_cost[t] = acc.leaf_cost();
    }
    let (mut best, mut best_cost) = (0, Real::INFINITY);
    let mut acc = Bin::EMPTY;
    for t in 1..m {
        acc.merge(&bins[usize::from(full[t - 1])]);
        let cost = acc.leaf_cost() * acc.area() + right_cost[t] * right_area[t];
        if cost < best_cost {
            (best, best_cost) = (t, cost);
        }
    }
    (best > 0).then(|| {
        (
            usize::from(full[best - 1]) + 1,
            TRAVERSAL_COST + best_cost / bounds.surface_area().max(Real::MIN_POSITIVE),
        )
    })
}

/// Sorts `items` by their centroids' coordinate on `axis`.
fn sort_by_centroid(items: &mut [Item], axis: usize, parallel: bool) {
    // Ties go by (object, index), so the order is the same whichever sort runs.
    let key = |a: &Item, b: &Item| {
        a.centroid()[axis]
            .total_cmp(&b.centroid()[axis])
            .then((a.object(), a.index()).cmp(&(b.object(), b.index())))
    };
    if parallel { items.par_sort_unstable_by(key) } else { items.sort_unstable_by(key) }
}

/// Moves the items for which `left` holds to the front; returns how many.
/// Hoare's scheme: items already on their side stay put, and each swap
/// puts two misplaced ones right (the order within each side is not kept;
/// the build does not depend on it).
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let (mut i, mut j) = (0, items.len());
    loop {
        while i < j && left(&items[i]) {
            i += 1;
        }
        while i < j && !left(&items[j - 1]) {
            j -= 1;
        }
        if i + 1 >= j {
            return i;
        }
        items.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::Vec3;

    /// Items of a noisy grid of `n`×`n` small boxes.
    fn items(n: u32) -> Vec<Item> {
        let mut out = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let h = ((i * 7919 + j * 104_729) % 1000) as Real / 1000.0;
                let p = Vec3::new(i as Real, h, j as Real);
                out.push(Item::new(Aabb::from_corners(p, p + Vec3::splat(0.9)), 0, i * n + j));
            }
        }
        out
    }

    #[test]
    fn the_tree_is_the_same_on_one_thread_and_on_many() {
        let mut a = items(150); // 22 500 items: the top levels go parallel.
        let mut b = a.clone();
        let (mut sa, mut sb) = (vec![0; a.len()], vec![0; b.len()]);
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| build(&mut a, &mut sa));
        let four = rayon::ThreadPoolBuilder::new()
            .num_threads(4)
            .build()
            .unwrap()
            .install(|| build(&mut b, &mut sb));
        assert!(matches!(one.0.root, BuildNode::Inner { .. }));
        // The root's split is parallel: its second half is a subtree with
        // its own arena (the same on one thread as on four).
        assert!(one.0.arena.iter().flatten().any(|n| matches!(n, BuildNode::Subtree(_))));
        assert_eq!(one, four);
        let order = |v: &[Item]| v.iter().map(|i| i.index()).collect::<Vec<_>>();
        assert_eq!(order(&a), order(&b));
        assert_eq!(sa, sb);
    }

    #[test]
    fn two_sets_of_bins_by_parity_give_the_bins_of_one() {
        // 10 000 items, over PARALLEL_ITEMS: mesh triangles only, then every
        // third one a whole object (the count of whole objects binned too).
        let triangles = items(100);
        assert!(triangles.len() > PARALLEL_ITEMS);
        let mixed: Vec<Item> = (triangles.iter().enumerate())
            .map(|(k, item)| if k % 3 == 0 { Item::whole(item.bounds(), 1) } else { *item })
            .collect();
        check_two_sets::<false>(&triangles);
        check_two_sets::<true>(&mixed);
    }

    fn check_two_sets<const WHOLE: bool>(items: &[Item]) {
        let all = Bin::of(items, false);
        assert_eq!(all.whole > 0, WHOLE);
        let binning = Binning::of(&all, items.len(), 0).unwrap();
        // The children's binnings, as `build_node` plans them, split near the middle.
        let left = |c: Wide| binning.below(c, BINS / 2);
        let plan = |side: Bin| Binning::of(&side, side.count, 1);
        let (l, r) = items.iter().fold((Bin::EMPTY, Bin::EMPTY), |(mut l, mut r), item| {
            let c = item.centroid();
            if left(c) {
                l.add::<true>(item, c)
            } else {
                r.add::<true>(item, c)
            }
            (l, r)
        });
        let binnings = [plan(l), plan(r)];
        let (mut a, mut b) = (items.to_vec(), items.to_vec());
        let (mut bins_a, mut bins_b) = ([[Bin::EMPTY; BINS]; 2], [[Bin::EMPTY; BINS]; 2]);
        let mid_a = partition_and_bin_in::<WHOLE, true>(&mut a, left, binnings, &mut bins_a);
        let mid_b = partition_and_bin_in::<WHOLE, false>(&mut b, left, binnings, &mut bins_b);
        assert_eq!(mid_a, mid_b);
        assert_eq!(mid_a, l.count);
        let order = |v: &[Item]| v.iter().map(|i| (i.object(), i.index())).collect::<Vec<_>>();
        assert_eq!(order(&a), order(&b));
        let fields = |bins: &[[Bin; BINS]; 2]| {
            bins.iter()
                .flatten()
                .map(|b| (b.min, b.max, b.centroid_min, b.centroid_max, b.count, b.whole))
                .collect::<Vec<_>>()
        };
        assert_eq!(fields(&bins_a), fields(&bins_b));
        // Every item was binned on its side, whole objects counted as such.
        let sum = |bins: &[Bin; BINS], f: fn(&Bin) -> usize| bins.iter().map(f).sum::<usize>();
        assert_eq!((sum(&bins_a[0], |b| b.count), sum(&bins_a[1], |b| b.count)), (l.count, r.count));
        assert_eq!((sum(&bins_a[0], |b| b.whole), sum(&bins_a[1], |b| b.whole)), (l.whole, r.whole));
    }

    /// Checks that `tree` over `items` (as `build` left them) is a valid
    /// tree of `leaves` leaves: every item in exactly one leaf of at most
    /// [`MAX_LEAF`] items, each leaf's size at its first item in `sizes`,
    /// every leaf's box around its items' boxes, every inner node's box
    /// around its children's. Returns how many leaves it saw.
    fn check(
        node: &BuildNode,
        arena: &[[BuildNode; 2]],
        items: &[Item],
        sizes: &[u8],
        seen: &mut [u32],
    ) -> usize {
        let contains = |outer: Aabb, inner: Aabb| {
            outer.min().cmple(inner.min()).all() && outer.max().cmpge(inner.max()).all()
        };
        match node {
            BuildNode::Leaf { bounds, first, count } => {
                assert!(*count >= 1 && *count as usize <= MAX_LEAF, "leaf of {count} items");
                assert_eq!(u32::from(sizes[*first as usize]), *count, "a leaf's size not at its first item");
                for i in *first..first + count {
                    assert!(i == *first || sizes[i as usize] == 0, "a leaf's size inside another leaf");
                    seen[i as usize] += 1;
                    assert!(contains(*bounds, items[i as usize].bounds()), "a leaf's box misses an item");
                }
                1
            }
            BuildNode::Inner { bounds, children, first, count } => {
                let pair = &arena[*children as usize];
                pair.iter().for_each(|c| assert!(contains(*bounds, c.bounds()), "a box misses a child"));
                let ((l_first, l_count), (r_first, r_count)) = (pair[0].items(), pair[1].items());
                assert_eq!(
                    (l_first, r_first, l_count + r_count),
                    (*first, first + l_count, *count),
                    "items below"
                );
                pair.iter().map(|c| check(c, arena, items, sizes, seen)).sum()
            }
            BuildNode::Subtree(tree) => {
                assert!(!matches!(tree.0, BuildNode::Subtree(_)), "a subtree of a subtree alone");
                check(&tree.0, &tree.1, items, sizes, seen)
            }
        }
    }

    /// Builds over `items` and checks the tree (see [`check`]), and that
    /// the items are the same ones, reordered.
    fn build_and_check(mut items: Vec<Item>) {
        let key = |i: &Item| (i.object(), i.index(), i.is_whole());
        let mut before: Vec<_> = items.iter().map(key).collect();
        let mut sizes = vec![0; items.len()];
        let (tree, leaves) = build(&mut items, &mut sizes);
        let mut seen = vec![0; items.len()];
        assert_eq!(check(&tree.root, &tree.arena, &items, &sizes, &mut seen), leaves);
        assert!(seen.iter().all(|&s| s == 1), "an item in no leaf or in two");
        let mut after: Vec<_> = items.iter().map(key).collect();
        before.sort_unstable();
        after.sort_unstable();
        assert_eq!(before, after);
    }

    /// A small pseudo-random generator (SplitMix64), in [0, 1).
    fn random(state: &mut u64) -> Real {
        *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 40) as Real / (1u64 << 24) as Real
    }

    /// The sweep over all bins, empty ones too, as [`best_split`] was
    /// written before it skipped them.
    fn best_split_over_all_bins(bins: &[Bin; BINS], bounds: Aabb) -> Option<(usize, Real)> {
        let mut right_area = [0.0 as Real; BINS];
        let mut right_cost = [0.0 as Real; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Bin::EMPTY;
        for k in (1..BINS).rev() {
            acc.merge(&bins[k]);
            right_area[k] = acc.area();
            right_cost[k] = acc.leaf_cost();
            right_count[k] = acc.count;
        }
        let (mut best, mut best_cost) = (0, Real::INFINITY);
        let mut acc = Bin::EMPTY;
        for k in 1..BINS {
            acc.merge(&bins[k - 1]);
            let cost = acc.leaf_cost() * acc.area() + right_cost[k] * right_area[k];
            if cost < best_cost && acc.count > 0 && right_count[k] > 0 {
                (best, best_cost) = (k, cost);
            }
        }
        (best > 0).then(|| (best, TRAVERSAL_COST + best_cost / bounds.surface_area().max(Real::MIN_POSITIVE)))
    }

    #[test]
    fn skipping_empty_bins_finds_the_split_and_cost_of_the_sweep_over_all_bins() {
        let mut state = 7u64;
        let mut checked = 0;
        for round in 0..4000 {
            // 1 to 40 random small boxes, some coincident, binned as a node would.
            let n = 1 + round % 40;
            let its: Vec<Item> = (0..n)
                .map(|i| {
                    let p = Vec3::new(random(&mut state), random(&mut state), random(&mut state))
                        * if round % 3 == 0 { 4.0 } else { 100.0 };
                    let p = if round % 5 == 0 { p.round() } else { p };
                    Item::new(Aabb::from_corners(p, p + Vec3::splat(random(&mut state))), 0, i as u32)
                })
                .collect();
            let all = Bin::of(&its, false);
            let Some(binning) = Binning::of(&all, its.len(), 0) else { continue };
            let bins = bin_items::<false>(&its, binning);
            let (fast, slow) =
                (best_split(&bins, all.bounds()), best_split_over_all_bins(&bins, all.bounds()));
            assert_eq!(fast.map(|(k, c)| (k, c.to_bits())), slow.map(|(k, c)| (k, c.to_bits())));
            checked += 1;
        }
        assert!(checked > 3000, "{checked}");
    }

    #[test]
    fn trees_are_valid_on_random_and_degenerate_inputs() {
        let mut state = 7;
        let mut r = || random(&mut state);
        let cube = |p: Vec3, s: Real| Aabb::from_corners(p, p + Vec3::splat(s));
        // Random boxes of all sizes, a few of them whole objects, enough
        // to go parallel at the top.
        let random_boxes: Vec<Item> = (0..20_000)
            .map(|i| {
                let b = cube(Vec3::new(r(), r(), r()) * 100.0, r() * r() * 20.0);
                if i % 97 == 0 { Item::whole(b, 1 + i) } else { Item::new(b, 0, i) }
            })
            .collect();
        build_and_check(random_boxes);
        // Every centroid the same (the median fallback; equal boxes).
        build_and_check((0..10_000).map(|i| Item::new(cube(Vec3::ONE, 1.0), 0, i)).collect());
        // Same centroid, different sizes.
        build_and_check(
            (0..500).map(|i| Item::new(cube(Vec3::splat(-(i as Real)), 2.0 * i as Real), 0, i)).collect(),
        );
        // A flat mesh: all boxes of zero height.
        build_and_check(
            (0..30_000)
                .map(|i| {
                    let p = Vec3::new(r() * 10.0, 0.0, r() * 10.0);
                    Item::new(Aabb::from_corners(p, p + Vec3::new(0.1, 0.0, 0.1)), 0, i)
                })
                .collect(),
        );
        // Huge coordinates, near the largest finite ones.
        let huge = Real::MAX / 8.0;
        build_and_check(
            (0..5_000)
                .map(|i| {
                    let p = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * huge;
                    Item::new(cube(p, huge / 1e3), 0, i)
                })
                .collect(),
        );
        // A single item, and two.
        build_and_check(vec![Item::new(cube(Vec3::ZERO, 1.0), 0, 0)]);
        build_and_check(vec![Item::new(cube(Vec3::ZERO, 1.0), 0, 0), Item::whole(cube(Vec3::ONE, 1.0), 1)]);
    }

    #[test]
    fn partition_puts_the_chosen_items_first() {
        let mut state = 3;
        for n in [0, 1, 2, 3, 10, 101] {
            let mut v: Vec<Item> =
                (0..n).map(|i| Item::new(Aabb::from_corners(Vec3::ZERO, Vec3::ONE), 0, i)).collect();
            let left: Vec<bool> = (0..n).map(|_| random(&mut state) < 0.5).collect();
            let mid = partition(&mut v, |i| left[i.index() as usize]);
            assert_eq!(mid, left.iter().filter(|&&l| l).count());
            assert!(v[..mid].iter().all(|i| left[i.index() as usize]));
            assert!(v[mid..].iter().all(|i| !left[i.index() as usize]));
        }
    }

    #[test]
    fn binning_during_the_partition_gives_the_bins_of_each_side_binned_afterwards() {
        let key = |b: &Bin| {
            let v = |w: Wide| [w[0], w[1], w[2]].map(Real::to_bits);
            (v(b.min), v(b.max), v(b.centroid_min), v(b.centroid_max), b.count, b.whole)
        };
        let mut state = 11;
        for n in [2, 3, 9, 100, 1001] {
            let mut v: Vec<Item> = (0..n)
                .map(|i| {
                    let p = Vec3::new(random(&mut state), random(&mut state), random(&mut state)) * 10.0;
                    let b = Aabb::from_corners(p, p + Vec3::splat(random(&mut state)));
                    if i % 7 == 0 { Item::whole(b, i) } else { Item::new(b, 0, i) }
                })
                .collect();
            let all = Bin::of(&v, false);
            let split = Binning::of(&all, v.len(), 0).unwrap();
            let sides = {
                let mut w = v.clone();
                let mid = partition(&mut w, |i| split.below(i.centroid(), 7));
                [Bin::of(&w[..mid], false), Bin::of(&w[mid..], false)]
            };
            let plans = sides.map(|s| Binning::of(&s, s.count, 1));
            let mut bins = [[Bin::EMPTY; BINS]; 2];
            let mid = partition_and_bin::<true>(&mut v, |c| split.below(c, 7), plans, &mut bins);
            assert_eq!(mid, sides[0].count);
            for (side, range) in [(0, 0..mid), (1, mid..v.len())] {
                let Some(plan) = plans[side] else { continue };
                let expected = bin_items::<true>(&v[range], plan);
                assert_eq!(bins[side].map(|b| key(&b)), expected.map(|b| key(&b)), "n = {n}, side {side}");
            }
        }
    }

    #[test]
    fn every_item_lands_in_exactly_one_leaf_of_at_most_the_leaf_size() {
        let mut v = items(40);
        let (tree, _) = build(&mut v, &mut vec![0; 1600]);
        let mut seen = vec![0; v.len()];
        fn walk(n: &BuildNode, arena: &[[BuildNode; 2]], seen: &mut [u32]) {
            let (n, arena) = n.resolve(arena);
            match n {
                BuildNode::Leaf { first, count, .. } => {
                    assert!(*count as usize <= MAX_LEAF);
                    for i in *first..first + count {
                        seen[i as usize] += 1;
                    }
                }
                BuildNode::Inner { children, .. } => {
                    arena[*children as usize].iter().for_each(|c| walk(c, arena, seen))
                }
                BuildNode::Subtree(_) => unreachable!("resolved"),
            }
        }
        walk(&tree.root, &tree.arena, &mut seen);
        assert!(seen.iter().all(|&s| s == 1));
    }

    #[test]
    fn a_room_of_large_whole_objects_is_split_into_leaves_of_their_own() {
        // The Cornell box's five walls, light and two blocks: any split into
        // two groups has a child as large as the room, so the greedy SAH
        // alone keeps all eight in one leaf, and every ray tests them all.
        let b = |min: [Real; 3], max: [Real; 3]| Aabb::from_corners(Vec3::from(min), Vec3::from(max));
        let boxes = [
            b([0.0, 0.0, 0.0], [5.56, 0.0, 5.59]),
            b([0.0, 5.49, 0.0], [5.56, 5.49, 5.59]),
            b([0.0, 0.0, 5.59], [5.56, 5.49, 5.59]),
            b([0.0, 0.0, 0.0], [0.0, 5.49, 5.59]),
            b([5.56, 0.0, 0.0], [5.56, 5.49, 5.59]),
            b([2.13, 5.48, 2.27], [3.43, 5.48, 3.32]),
            b([1.3, 0.0, 0.65], [2.95, 1.65, 2.3]),
            b([2.65, 0.0, 2.95], [4.3, 3.3, 4.6]),
        ];
        let mut v: Vec<Item> = boxes.iter().enumerate().map(|(o, &b)| Item::whole(b, o as u32)).collect();
        let (tree, leaves) = build(&mut v, &mut [0; 8]);
        // Seven: the light shares a leaf with the ceiling, whose slab its
        // box lies in (apart, a ray entering one box would enter both).
        assert_eq!(leaves, 7);
        // Two mesh triangles' worth of items stay together: a block of four
        // costs one test.
        let mut triangles: Vec<Item> = boxes.iter().take(4).map(|&b| Item::new(b, 0, 0)).collect();
        assert_eq!(build(&mut triangles, &mut [0; 4]).1, 1);
        assert!(matches!(tree.root, BuildNode::Inner { .. }));
    }
}
