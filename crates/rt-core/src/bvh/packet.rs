//! Packets of coherent rays traced through the tree together: a pixel's
//! samples, or a run of neighbouring pixels of a row.
//!
//! The packet descends the tree once, with one box test per node for all
//! its rays: interval arithmetic over the rays' origins and inverse
//! directions gives, for each of the node's eight children, a lower bound
//! on where any of the rays enters it and an upper bound on where any
//! leaves it (the frustum test of Reshetov, Soupikov and Hurley, "Multi-Level
//! Ray Tracing Algorithm", 2005, in the interval form of Boulos et al.,
//! "Geometric and Arithmetic Culling Methods for Entire Ray Packets",
//! 2006). At a leaf, each ray first tests the leaf's box on its own, with
//! the single-ray test's arithmetic, and only the rays that enter it test
//! the leaf's triangles.
//!
//! Every bound is taken over the rays' *rounded* values (their computed
//! origins and inverse directions), and rounding is monotone, so the
//! packet's bounds hold for each ray's own rounded slab test: any box a ray
//! enters by the single-ray test, the packet enters too. A ray therefore
//! visits every leaf that can hold its closest hit, and its result is the
//! single-ray result bit for bit (tested). Rays whose direction signs differ
//! within a packet, or with a zero direction component (an infinite
//! inverse), are traced one by one.

use std::mem::MaybeUninit;

use super::leaf::lanes_of;
use super::node::{Child, Node, WIDTH};
use super::query::Query;
use super::{Bvh, INLINE_STACK, PACKET_RAYS, push_sorted};
use crate::geometry::hit::Hit;
use crate::geometry::method::Methods;
use crate::geometry::object::Object;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{CONE_PAD, CONE_SLOPE_MARGIN, Real, Vec3, divide, gamma};

/// Bounds on a packet's rays, per axis: origins in `[origin_lo, origin_hi]`,
/// inverse directions in `[inv_lo, inv_hi]` (all of one sign, finite), and
/// the side each ray enters a box by (as [`Slabs`](super::Slabs): 0 for min, 1 for max).
struct Frustum {
    origin_lo: [Real; 3],
    origin_hi: [Real; 3],
    inv_lo: [Real; 3],
    inv_hi: [Real; 3],
    enter: [usize; 3],
}

impl Frustum {
    /// The bounds of the rays in `blocks`, or `None` if their direction
    /// signs differ or an inverse direction is not finite. Lane-wise minima
    /// and maxima over the blocks first (SIMD), then across the lanes.
    #[inline(always)]
    fn new(blocks: &[RayBlock]) -> Option<Self> {
        let first = blocks.first()?;
        let (mut o_lo, mut o_hi, mut i_lo, mut i_hi) = (first.origin, first.origin, first.inv, first.inv);
        for b in &blocks[1..] {
            for axis in 0..3 {
                o_lo[axis] = lane_min(o_lo[axis], b.origin[axis]);
                o_hi[axis] = lane_max(o_hi[axis], b.origin[axis]);
                i_lo[axis] = lane_min(i_lo[axis], b.inv[axis]);
                i_hi[axis] = lane_max(i_hi[axis], b.inv[axis]);
            }
        }
        let inv_hi = i_hi.map(greatest);
        let f = Frustum {
            origin_lo: o_lo.map(least),
            origin_hi: o_hi.map(greatest),
            inv_lo: i_lo.map(least),
            inv_hi,
            enter: inv_hi.map(|i| usize::from(i < 0.0)),
        };
        // An inverse is never ±0 (directions are finite), so a sign change
        // shows as a negative minimum with a positive maximum.
        (0..3)
            .all(|a| {
                f.inv_lo[a].is_finite() && f.inv_hi[a].is_finite() && (f.inv_lo[a] > 0.0 || f.inv_hi[a] < 0.0)
            })
            .then_some(f)
    }

    /// For each of the node's boxes, a lower bound on where any ray enters
    /// it, and the mask of boxes some ray may overlap within `[t_min,
    /// t_max]`.
    ///
    /// With `d ∈ [d_lo, d_hi]` (a plane minus the origins) and `i ∈ [i_lo,
    /// i_hi]`, the lower bound of `d·i` for positive `i` is `d_lo·i_lo` if
    /// `d_lo ≥ 0`, else `d_lo·i_hi`; for negative `i` it is `d_hi·i_lo` if
    /// `d_hi ≥ 0`, else `d_hi·i_hi`; the upper bounds mirror these. Each
    /// ray's rounded `(plane − o)·i` lies within the rounded bounds, and the
    /// far bound gets the same `1 + 2γ₃` as the single-ray test.
    #[inline(always)]
    fn entries(&self, node: &Node, t_min: Real, t_max: Real) -> ([Real; WIDTH], u32) {
        let mut near = [t_min; WIDTH];
        let mut far = [t_max; WIDTH];
        for axis in 0..3 {
            let side = self.enter[axis] & 1;
            let (enter, leave) = (&node.bounds[side][axis], &node.bounds[side ^ 1][axis]);
            let (o_lo, o_hi, i_lo, i_hi) =
                (self.origin_lo[axis], self.origin_hi[axis], self.inv_lo[axis], self.inv_hi[axis]);
            for slot in 0..WIDTH {
                let (t0, t1) = if side == 0 {
                    // Positive direction: enters at the min plane, leaves at the max.
                    let d = enter[slot] - o_hi;
                    let e = leave[slot] - o_lo;
                    (if d >= 0.0 { d * i_lo } else { d * i_hi }, if e >= 0.0 { e * i_hi } else { e * i_lo })
                } else {
                    // Negative direction: enters at the max plane, leaves at the min.
                    let d = enter[slot] - o_lo;
                    let e = leave[slot] - o_hi;
                    (if d >= 0.0 { d * i_lo } else { d * i_hi }, if e <= 0.0 { e * i_lo } else { e * i_hi })
                };
                let t1 = t1 * (1.0 + 2.0 * gamma(3));
                near[slot] = if t0 > near[slot] { t0 } else { near[slot] };
                far[slot] = if t1 < far[slot] { t1 } else { far[slot] };
            }
        }
        let entered = (0..WIDTH).fold(0, |mask, slot| mask | (u32::from(near[slot] <= far[slot]) << slot));
        (near, entered)
    }
}

/// For a packet whose rays share one origin (a pinhole camera's): the
/// range of their slopes `u = d_i/d_k`, `v = d_j/d_k` against the axis `k`
/// along which the first ray goes fastest. A ray's points `p` (relative to
/// the origin) all have `p_i/p_k = u`, so a box whose points' slopes all
/// lie outside the packet's range holds no point of any of its rays.
///
/// The per-axis intervals of [`Frustum`] bound each axis separately, which
/// at grazing angles lets through many boxes that no ray comes near (on a
/// terrain seen at 34°, nine times as many leaves as the rays enter); this
/// test couples the axes. It must never cull a box that a ray enters by its
/// own rounded slab test, which can accept a box the exact ray misses by a
/// relative `≈ 5γ₃ ≈ 10⁻⁶` of the distance `S` to the box. So each box is
/// first widened by `10⁻⁴·S` on every side, slopes are compared with a
/// margin of `10⁻⁶·(1 + max|u|)`, and boxes reaching to or behind the
/// plane `p_k = 0` through the origin are never culled. Both margins are a
/// hundred times the rounding they cover, and still far below a pixel's
/// footprint (`10⁻³` of the distance at 640×480).
struct Cone {
    origin: [Real; 3],
    /// Axes `i, j, k`.
    axes: [usize; 3],
    /// The sign of the rays' `d_k`.
    sign: Real,
    u: (Real, Real),
    v: (Real, Real),
    margin: Real,
}

impl Cone {
    /// The cone of the rays in `blocks` (bounded by `frustum`), whose first
    /// ray is `first`, or `None` if their origins differ. All `d_k` have
    /// one sign (the frustum's), none is 0. The slopes are computed from the
    /// inverse directions, `u = (1/d_k)/(1/d_i)`: three roundings, a relative
    /// error under `2·10⁻⁷`, far inside the margin.
    #[inline(always)]
    fn new(blocks: &[RayBlock], frustum: &Frustum, first: &Ray) -> Option<Self> {
        if frustum.origin_lo != frustum.origin_hi {
            return None;
        }
        let k = first.dir.abs().max_position();
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        let sign = if frustum.enter[k] == 0 { 1.0 } else { -1.0 };
        let (mut u_lo, mut u_hi) = ([Real::INFINITY; BLOCK], [Real::NEG_INFINITY; BLOCK]);
        let (mut v_lo, mut v_hi) = (u_lo, u_hi);
        for b in blocks {
            let u = std::array::from_fn(|l| b.inv[k][l] / b.inv[i][l]);
            let v = std::array::from_fn(|l| b.inv[k][l] / b.inv[j][l]);
            (u_lo, u_hi) = (lane_min(u_lo, u), lane_max(u_hi, u));
            (v_lo, v_hi) = (lane_min(v_lo, v), lane_max(v_hi, v));
        }
        let (u, v) = ((least(u_lo), greatest(u_hi)), (least(v_lo), greatest(v_hi)));
        let reach = u.0.abs().max(u.1.abs()).max(v.0.abs()).max(v.1.abs());
        (u.0.is_finite() && u.1.is_finite() && v.0.is_finite() && v.1.is_finite()).then_some(Cone {
            origin: frustum.origin_lo,
            axes: [i, j, k],
            sign,
            u,
            v,
            margin: CONE_SLOPE_MARGIN * (1.0 + reach),
        })
    }

    /// The mask of the node's boxes that no ray of the packet comes near.
    #[inline(always)]
    fn culled(&self, node: &Node) -> u32 {
        let [i, j, k] = self.axes;
        // Corners relative to the origin, turned (exactly, by −1) so that
        // the rays go towards +k: u and v do not change.
        let (lo, hi) = if self.sign > 0.0 { (0, 1) } else { (1, 0) };
        let rel = |side: usize, axis: usize, slot: usize| {
            (node.bounds[side][axis][slot] - self.origin[axis]) * self.sign
        };
        let mut mask = 0;
        for slot in 0..WIDTH {
            let (mut pi, mut pj, mut pk) = (
                (rel(lo, i, slot), rel(hi, i, slot)),
                (rel(lo, j, slot), rel(hi, j, slot)),
                (rel(lo, k, slot), rel(hi, k, slot)),
            );
            let reach =
                pi.0.abs().max(pi.1.abs()).max(pj.0.abs()).max(pj.1.abs()).max(pk.0.abs()).max(pk.1.abs());
            let pad = CONE_PAD * reach;
            for p in [&mut pi, &mut pj, &mut pk] {
                *p = (p.0 - pad, p.1 + pad);
            }
            // The least slope over the (widened) box is p_lo / (pk.1 if
            // p_lo ≥ 0, else pk.0), the greatest p_hi / (pk.0 if p_hi ≥ 0,
            // else pk.1); when the box lies wholly in front (pk.0 > 0) these
            // denominators are positive, so the slopes are compared with the
            // packet's by multiplying instead of dividing (the rounding of the
            // product is far inside the margin).
            let below =
                |p_hi: Real, lo: Real| p_hi < (lo - self.margin) * if p_hi >= 0.0 { pk.0 } else { pk.1 };
            let above =
                |p_lo: Real, hi: Real| p_lo > (hi + self.margin) * if p_lo >= 0.0 { pk.1 } else { pk.0 };
            let outside = below(pi.1, self.u.0)
                || above(pi.0, self.u.1)
                || below(pj.1, self.v.0)
                || above(pj.0, self.v.1);
            mask |= u32::from(pk.0 > 0.0 && outside) << slot;
        }
        mask
    }
}

/// Rays per [`RayBlock`].
const BLOCK: usize = 4;

/// Lane by lane, `y` where it is below `x`, else `x` (one SIMD minimum).
#[inline(always)]
fn lane_min(x: [Real; BLOCK], y: [Real; BLOCK]) -> [Real; BLOCK] {
    std::array::from_fn(|l| if y[l] < x[l] { y[l] } else { x[l] })
}

/// Lane by lane, `y` where it is above `x`, else `x` (one SIMD maximum).
#[inline(always)]
fn lane_max(x: [Real; BLOCK], y: [Real; BLOCK]) -> [Real; BLOCK] {
    std::array::from_fn(|l| if y[l] > x[l] { y[l] } else { x[l] })
}

/// The least of the lanes.
#[inline(always)]
fn least(x: [Real; BLOCK]) -> Real {
    x.into_iter().fold(Real::INFINITY, Real::min)
}

/// The greatest of the lanes.
#[inline(always)]
fn greatest(x: [Real; BLOCK]) -> Real {
    x.into_iter().fold(Real::NEG_INFINITY, Real::max)
}

/// Four of the packet's rays for the box test of a leaf, stored lane by
/// lane so that one SIMD slab test covers all four: the same arithmetic as
/// [`Slabs::entries`](super::Slabs::entries), so each lane's answer is its ray's own. Unused lanes
/// have an empty range and never enter.
#[derive(Clone, Copy)]
struct RayBlock {
    origin: [[Real; BLOCK]; 3],
    inv: [[Real; BLOCK]; 3],
    t_min: [Real; BLOCK],
    /// Where each ray's closest hit so far is ([`Query::t_max`]).
    t_max: [Real; BLOCK],
}

impl RayBlock {
    const EMPTY: RayBlock = RayBlock {
        origin: [[0.0; BLOCK]; 3],
        inv: [[0.0; BLOCK]; 3],
        t_min: [Real::INFINITY; BLOCK],
        t_max: [Real::NEG_INFINITY; BLOCK],
    };

    /// Puts the ray with `origin`, inverse direction `inv` and range
    /// `[t_min, t_max]` into `lane`.
    #[inline(always)]
    fn set(&mut self, lane: usize, origin: Vec3, inv: Vec3, t_min: Real, t_max: Real) {
        for axis in 0..3 {
            self.origin[axis][lane] = origin[axis];
            self.inv[axis][lane] = inv[axis];
        }
        self.t_min[lane] = t_min;
        self.t_max[lane] = t_max;
    }

    /// Fills the lanes from `used` on with lane 0's ray and an empty range:
    /// they never enter a box, and bounds over all four lanes are the used
    /// lanes' bounds.
    #[inline(always)]
    fn pad(&mut self, used: usize) {
        for lane in used..BLOCK {
            for axis in 0..3 {
                self.origin[axis][lane] = self.origin[axis][0];
                self.inv[axis][lane] = self.inv[axis][0];
            }
            self.t_min[lane] = Real::INFINITY;
            self.t_max[lane] = Real::NEG_INFINITY;
        }
    }

    /// The lanes whose rays enter the box with planes `enter` and `leave`
    /// (per axis, in the order the rays cross them) within their range.
    #[inline(always)]
    fn entering(&self, enter: [Real; 3], leave: [Real; 3]) -> u32 {
        let mut near = self.t_min;
        let mut far = self.t_max;
        for axis in 0..3 {
            let (o, inv) = (&self.origin[axis], &self.inv[axis]);
            for lane in 0..BLOCK {
                let t0 = (enter[axis] - o[lane]) * inv[lane];
                let t1 = (leave[axis] - o[lane]) * inv[lane] * (1.0 + 2.0 * gamma(3));
                near[lane] = if t0 > near[lane] { t0 } else { near[lane] };
                far[lane] = if t1 < far[lane] { t1 } else { far[lane] };
            }
        }
        (0..BLOCK).fold(0, |mask, lane| mask | (u32::from(near[lane] <= far[lane]) << lane))
    }
}

/// A subtree waiting on the packet's stack: the child, the packet's lower
/// bound on where it is entered, and its parent node and slot (whose box a
/// leaf's rays test on their own).
#[derive(Clone, Copy)]
struct Pending {
    child: Child,
    near: Real,
    parent: u32,
    slot: u32,
}

impl Bvh {
    /// The closest hit of each of `rays` with `t` in its `ranges` entry,
    /// into `hits`: exactly what [`Bvh::closest_hit`] gives for each, found
    /// by tracing them as packets of up to [`PACKET_RAYS`]. Rays next to
    /// each other in the slice should be close in space and direction.
    pub fn closest_hits(
        &self,
        objects: &[Object],
        rays: &[Ray],
        ranges: &[Interval],
        methods: Methods,
        hits: &mut [Option<Hit>],
    ) {
        assert!(rays.len() == ranges.len() && rays.len() == hits.len(), "one range and one hit per ray");
        for ((rays, ranges), hits) in
            rays.chunks(PACKET_RAYS).zip(ranges.chunks(PACKET_RAYS)).zip(hits.chunks_mut(PACKET_RAYS))
        {
            self.closest_hits_packet(objects, rays, ranges, methods, hits);
        }
    }

    /// [`Bvh::closest_hits`] for at most [`PACKET_RAYS`] rays.
    ///
    /// The packet code is compiled twice: for baseline x86-64 (SSE2), and
    /// with AVX2 enabled, which the CPU is asked for at run time (one
    /// release binary for every x86-64). AVX2 brings three-operand
    /// instructions and 8-lane loops where the compiler finds them; no fused
    /// multiply-add (Rust never contracts `a·b + c`), so both give the same
    /// bits (tested).
    fn closest_hits_packet(
        &self,
        objects: &[Object],
        rays: &[Ray],
        ranges: &[Interval],
        methods: Methods,
        hits: &mut [Option<Hit>],
    ) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { self.closest_hits_packet_avx2(objects, rays, ranges, methods, hits) };
        }
        self.closest_hits_packet_baseline(objects, rays, ranges, methods, hits)
    }

    /// [`Bvh::closest_hits_packet`] compiled for AVX2.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn closest_hits_packet_avx2(
        &self,
        objects: &[Object],
        rays: &[Ray],
        ranges: &[Interval],
        methods: Methods,
        hits: &mut [Option<Hit>],
    ) {
        self.closest_hits_packet_with::<true>(objects, rays, ranges, methods, hits)
    }

    /// [`Bvh::closest_hits_packet`] for any CPU of the target.
    fn closest_hits_packet_baseline(
        &self,
        objects: &[Object],
        rays: &[Ray],
        ranges: &[Interval],
        methods: Methods,
        hits: &mut [Option<Hit>],
    ) {
        self.closest_hits_packet_with::<false>(objects, rays, ranges, methods, hits)
    }

    /// [`Bvh::closest_hits_packet`]; with `AVX2` the caller is compiled for
    /// AVX2 (it has checked the CPU), and a two-block leaf's eight-lane
    /// test is inlined into the leaf loop ([`Query::test_leaf_with`])
    /// instead of called: as a call, its eight `t`s came back through
    /// memory written four lanes at a time and were read back eight at a
    /// time, which stalls the store-to-load forwarding.
    #[inline(always)]
    fn closest_hits_packet_with<const AVX2: bool>(
        &self,
        objects: &[Object],
        rays: &[Ray],
        ranges: &[Interval],
        methods: Methods,
        hits: &mut [Option<Hit>],
    ) {
        let n = rays.len();
        let mut queries: [MaybeUninit<Query>; PACKET_RAYS] = [const { MaybeUninit::uninit() }; PACKET_RAYS];
        let mut blocks = [const { MaybeUninit::<RayBlock>::uninit() }; PACKET_RAYS / BLOCK];
        let count = n.div_ceil(BLOCK);
        for block in &mut blocks[..count] {
            block.write(RayBlock::EMPTY);
        }
        // SAFETY: the first `count` blocks were written just above.
        let blocks =
            unsafe { &mut *(&mut blocks[..count] as *mut [MaybeUninit<RayBlock>] as *mut [RayBlock]) };
        for i in 0..n {
            // Made in place: a query copied in after a call had written it
            // would be read back in wider pieces than it was written, which
            // stalls the store-to-load forwarding.
            let query = queries[i].write(Query::new(self.prepared::<true>(&rays[i]), ranges[i]));
            if !self.unbounded.is_empty() {
                query.test_unbounded(&self.unbounded, objects, methods);
            }
            // The single-ray test's inverse direction (`Slabs::new` divides
            // lane by lane; a correctly rounded quotient either way).
            let inv = divide(Vec3::ONE, rays[i].dir);
            blocks[i / BLOCK].set(i % BLOCK, rays[i].origin, inv, query.range.min, query.t_max());
        }
        if !n.is_multiple_of(BLOCK) {
            blocks[count - 1].pad(n % BLOCK);
        }
        // SAFETY: the first n entries were written just above.
        let queries = unsafe { &mut *(&mut queries[..n] as *mut [MaybeUninit<Query>] as *mut [Query]) };
        match Frustum::new(blocks) {
            Some(frustum) if !self.nodes.is_empty() && self.stack_bound <= INLINE_STACK => {
                // One ray's frustum test is its own slab test already.
                let cone = if n > 1 { Cone::new(blocks, &frustum, &rays[0]) } else { None };
                self.traverse_packet::<AVX2>(objects, &frustum, cone.as_ref(), blocks, queries, methods)
            }
            _ => {
                for query in queries.iter_mut() {
                    let range = Interval::new(query.range.min, query.t_max());
                    let ray = query.prepared.ray;
                    self.traverse(&ray, range, |leaf, lanes| {
                        query.test_leaf_with::<AVX2>(objects, &self.object_blocks, leaf, lanes, methods);
                        query.best_t()
                    });
                }
            }
        }
        for (hit, query) in hits.iter_mut().zip(queries.iter()) {
            query.finish_into(objects, hit);
        }
    }

    /// Descends the tree with the packet, nearest child first by the
    /// packet's entry bound; at each leaf the rays that enter its box test
    /// its primitives.
    #[inline(always)]
    fn traverse_packet<const AVX2: bool>(
        &self,
        objects: &[Object],
        frustum: &Frustum,
        cone: Option<&Cone>,
        blocks: &mut [RayBlock],
        queries: &mut [Query],
        methods: Methods,
    ) {
        let t_min = least(blocks.iter().fold([Real::INFINITY; BLOCK], |m, b| lane_min(m, b.t_min)));
        // The packet goes on while any ray could still find a closer hit.
        let farthest = |blocks: &[RayBlock]| {
            greatest(blocks.iter().fold([Real::NEG_INFINITY; BLOCK], |m, b| lane_max(m, b.t_max)))
        };
        let mut t_max = farthest(blocks);
        let mut stack = [const { MaybeUninit::<Pending>::uninit() }; INLINE_STACK];
        let mut sp = 0;
        let mut current = Pending { child: Child::node(0), near: t_min, parent: 0, slot: 0 };
        loop {
            if !current.child.is_leaf() {
                let index = current.child.index;
                let node = &self.nodes[index as usize];
                let (near, mut entered) = frustum.entries(node, t_min, t_max);
                if let Some(cone) = cone
                    && entered != 0
                {
                    entered &= !cone.culled(node);
                }
                if entered != 0 {
                    let pending = |slot: usize| Pending {
                        child: node.children[slot],
                        near: near[slot],
                        parent: index,
                        slot: slot as u32,
                    };
                    let slot = entered.trailing_zeros() as usize;
                    let mut rest = entered & (entered - 1);
                    let mut nearest = pending(slot);
                    let base = sp;
                    while rest != 0 {
                        let slot = rest.trailing_zeros() as usize;
                        rest &= rest - 1;
                        let mut entry = pending(slot);
                        if entry.near < nearest.near {
                            std::mem::swap(&mut entry, &mut nearest);
                        }
                        // Sorted, the nearest on top, as a single ray's.
                        push_sorted(&mut stack, base, &mut sp, entry, |e| e.near);
                    }
                    current = nearest;
                    continue;
                }
            } else {
                let parent = &self.nodes[current.parent as usize];
                let leaf = self.blocks(current.child);
                let slot = current.slot as usize;
                // The leaf's box, planes in the order the rays cross them.
                let planes = |side: usize| {
                    [0, 1, 2].map(|axis| parent.bounds[(frustum.enter[axis] & 1) ^ side][axis][slot])
                };
                let (enter, leave) = (planes(0), planes(1));
                for (b, block) in blocks.iter_mut().enumerate() {
                    for lane in lanes_of(block.entering(enter, leave)) {
                        let query = &mut queries[b * BLOCK + lane];
                        query.test_leaf_with::<AVX2>(
                            objects,
                            &self.object_blocks,
                            leaf,
                            current.child.lanes,
                            methods,
                        );
                        block.t_max[lane] = query.t_max();
                    }
                }
                t_max = farthest(blocks);
            }
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                // SAFETY: entries below `sp` were all written above.
                let pending = unsafe { stack[sp].assume_init() };
                if pending.near <= t_max {
                    current = pending;
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::primitive::Primitive;
    use crate::math::real::Vec3;
    use crate::testing::test_support::{grid_mesh, primitives_of, random_parts, scene_of as scene, v};
    use proptest::prelude::*;

    /// A hit as comparable bits: object, primitive, `t`.
    type Key = Option<(usize, usize, u64)>;

    /// The packet results and the single-ray results. The packet code
    /// compiled for the baseline CPU must agree with the one the CPU runs
    /// (AVX2 where it has it) bit for bit.
    fn both(s: &crate::scene::Scene, rays: &[Ray]) -> (Vec<Key>, Vec<Key>) {
        let ranges: Vec<Interval> = rays.iter().map(|r| s.cast_range(r)).collect();
        let mut hits = vec![None; rays.len()];
        s.bvh().closest_hits(s.objects(), rays, &ranges, s.methods(), &mut hits);
        #[allow(clippy::useless_conversion)] // to_bits gives u32 for f32 geometry
        let key = |h: Option<Hit>| h.map(|h| (h.object, h.primitive, u64::from(h.t.to_bits())));
        let mut baseline = vec![None; rays.len()];
        for ((rays, ranges), hits) in
            rays.chunks(PACKET_RAYS).zip(ranges.chunks(PACKET_RAYS)).zip(baseline.chunks_mut(PACKET_RAYS))
        {
            s.bvh().closest_hits_packet_baseline(s.objects(), rays, ranges, s.methods(), hits);
        }
        assert_eq!(
            baseline.iter().map(|&h| key(h)).collect::<Vec<_>>(),
            hits.iter().map(|&h| key(h)).collect::<Vec<_>>(),
            "baseline and dispatched packet code differ"
        );
        let single = rays
            .iter()
            .zip(&ranges)
            .map(|(r, &range)| key(s.bvh().closest_hit(s.objects(), r, range, s.methods())));
        (hits.into_iter().map(key).collect(), single.collect())
    }

    proptest! {
        #[test]
        fn packets_find_the_single_ray_hits(
            parts in random_parts(20.0, 24),
            origin in prop::array::uniform3(-25f32..25.0),
            dir in prop::array::uniform3(-1f32..1.0),
            spread in prop::sample::select(vec![0.0 as Real, 1e-4, 1e-2, 0.3, 2.0]),
            offsets in prop::collection::vec((prop::array::uniform3(-1f32..1.0), prop::array::uniform3(-1f32..1.0)), 1..80),
            common_origin in any::<bool>(),
        ) {
            let s = scene(primitives_of(parts));
            let rays: Vec<Ray> = offsets.iter().map(|(o, d)| {
                let origin = if common_origin { v(origin) } else { v(origin) + v(*o) * spread };
                Ray::new(origin, v(dir) + v(*d) * spread)
            }).collect();
            let (packet, single) = both(&s, &rays);
            prop_assert_eq!(packet, single);
        }
    }

    #[test]
    fn a_pixel_of_rays_over_a_fine_grid_finds_the_single_ray_hits() {
        // Rays of one pixel's footprint and of a row of pixels over a grid of
        // 20 000 triangles, from above at an angle: shared edges everywhere.
        let grid = grid_mesh(100, |i, j| {
            Vec3::new(i as Real * 0.1, ((i * 7 + j * 3) % 5) as Real * 0.01, j as Real * 0.1)
        });
        let s = scene(vec![Primitive::Mesh(grid)]);
        let origin = Vec3::new(5.0, 4.0, -3.0);
        for (step, count) in [(1e-4, 8), (1e-2, 64), (0.3, 64)] {
            let rays: Vec<Ray> = (0..count)
                .map(|k| {
                    let (x, y) = ((k % 8) as Real * step, (k / 8) as Real * step);
                    Ray::new(origin, Vec3::new(x - 0.1, -0.8 + y, 1.0))
                })
                .collect();
            let (packet, single) = both(&s, &rays);
            assert_eq!(packet, single, "step {step}");
            assert!(packet.iter().any(Option::is_some));
        }
    }

    #[test]
    fn mixed_direction_signs_and_zero_components_fall_back_to_single_rays() {
        let s = scene(vec![
            Primitive::Sphere(crate::geometry::sphere::Sphere::new(Vec3::new(0.0, 0.0, 5.0), 1.0).unwrap()),
            Primitive::Sphere(crate::geometry::sphere::Sphere::new(Vec3::new(0.0, 0.0, -5.0), 1.0).unwrap()),
        ]);
        let rays = [
            Ray::new(Vec3::ZERO, Vec3::Z),
            Ray::new(Vec3::ZERO, -Vec3::Z),
            Ray::new(Vec3::ZERO, Vec3::new(0.1, -0.0, 1.0)),
            Ray::new(Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0)),
        ];
        let (packet, single) = both(&s, &rays);
        assert_eq!(packet, single);
        assert_eq!(packet.iter().filter(|h| h.is_some()).count(), 3);
    }
}
