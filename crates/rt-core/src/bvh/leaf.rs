//! A leaf of the hierarchy: one or two blocks of up to four primitives
//! side by side.
//!
//! Mesh triangles have their corners stored lane by lane (a structure of
//! arrays: `corners[corner][axis][lane]`), so that one SIMD watertight test
//! covers a block's four at once, as Embree's `Triangle4` leaves do (Wald et
//! al., "Embree: A Kernel Framework for Efficient CPU Ray Tracing", 2014).
//! The test uses SSE2, which every x86-64 CPU has, so one release binary
//! runs everywhere; where the CPU has AVX2 (asked at run time) the two
//! blocks of a leaf go through one eight-lane test with the same
//! operations. The SAH counts a leaf's cost by the block, as Embree's
//! does, so a two-block leaf is made only where splitting it would cost
//! more: on the 1 M-triangle terrain a third of the leaves have two blocks,
//! and a bounce ray visits 2.24 leaves instead of 2.34 (measured with
//! 4-wide nodes; docs/performance.md has the timings).
//!
//! Both tests perform exactly the scalar test's operations
//! ([`crate::geometry::triangle::intersect_watertight_prepared`]), lane by lane and
//! in the same order, with no fused multiply-adds, so each lane's `t` has
//! the same bits as the scalar test's (tested); a lane whose edge functions
//! need the exact re-evaluation ([`crate::geometry::triangle::edge_functions`]) is
//! handed to the scalar test. Elsewhere (other CPUs, `f64` geometry, the
//! other triangle methods) the scalar test runs lane by lane.
//!
//! Other bounded primitives (spheres, boxes, polygons, single triangles)
//! occupy a lane too, but only their object index is stored: they are
//! looked up in the scene and tested whole.

use super::item::Item;
use crate::geometry::method::TriangleMethod;
use crate::geometry::object::Object;
use crate::geometry::primitive::Primitive;
use crate::geometry::triangle::{TriangleRay, geometric_normal, intersect_by};
use crate::math::ray::Interval;
use crate::math::real::{Real, Vec3};

/// Primitives per block.
pub(crate) const LANES: usize = 4;
/// Blocks per leaf at most (two: one AVX2 test covers both).
pub(crate) const BLOCKS: usize = 2;

/// A block of up to [`LANES`] primitives; a leaf is one to [`BLOCKS`] of
/// them, stored one after the other. Which lanes hold mesh triangles and
/// which whole objects is kept in the parent's child entry ([`Lanes`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub(super) struct Leaf {
    /// `corners[corner][axis][lane]`; NaN in lanes without a triangle.
    corners: [[[Real; LANES]; 3]; 3],
    /// The object of each lane (`u32::MAX` where unused).
    object: [u32; LANES],
    /// The triangle's index in its mesh (0 for whole objects).
    index: [u32; LANES],
}

/// Lane masks of a leaf, a byte per block (block `b` in bits `8b..8b + 8`):
/// bit `lane` of a byte set for a mesh triangle, bit `LANES + lane` for a
/// whole object. Never 0 for a leaf; every block of a leaf has a lane in
/// use, so the highest byte in use tells how many blocks the leaf has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Lanes(pub u32);

impl Lanes {
    /// Bits per block.
    const BITS: u32 = 2 * LANES as u32;

    /// The masks of block `b` alone (in the lowest byte).
    #[inline(always)]
    pub fn block(self, b: usize) -> Lanes {
        Lanes((self.0 >> (Self::BITS * b as u32)) & ((1 << Self::BITS) - 1))
    }
    /// The masks of a leaf whose block `b` has `lanes`, added to these.
    pub fn with_block(self, b: usize, lanes: Lanes) -> Lanes {
        Lanes(self.0 | lanes.0 << (Self::BITS * b as u32))
    }
    /// How many blocks the leaf has.
    #[inline(always)]
    pub fn blocks(self) -> usize {
        (u32::BITS - self.0.leading_zeros()).div_ceil(Self::BITS) as usize
    }
    /// The lanes of a one-block mask holding mesh triangles.
    #[inline(always)]
    pub fn triangles(self) -> u32 {
        self.0 & ((1 << LANES) - 1)
    }
    /// The lanes of a one-block mask holding whole objects.
    #[inline(always)]
    pub fn objects(self) -> u32 {
        self.0 >> LANES
    }
    /// Whether any block of the leaf holds a whole object (most leaves of
    /// a mesh hold only its triangles).
    #[inline(always)]
    pub fn has_objects(self) -> bool {
        // The whole-object bits of every block: the upper half of each byte.
        const OBJECT_BITS: u32 = {
            let mut bits = 0;
            let mut b = 0;
            while b < BLOCKS {
                bits |= ((1 << LANES) - 1) << (LANES as u32 + Lanes::BITS * b as u32);
                b += 1;
            }
            bits
        };
        self.0 & OBJECT_BITS != 0
    }
    /// The tests a ray makes in the leaf: one per block with triangles
    /// (they are tested at once), one per whole object.
    pub fn tests(self) -> u32 {
        (0..self.blocks()).map(|b| u32::from(self.block(b).triangles() != 0)).sum::<u32>()
            + (0..self.blocks()).map(|b| self.block(b).objects().count_ones()).sum::<u32>()
    }
}

impl Leaf {
    /// The leaf of `items` (at most [`LANES`]), in their order, and its lanes.
    pub fn new(items: &[Item], objects: &[Object]) -> (Self, Lanes) {
        debug_assert!(!items.is_empty() && items.len() <= LANES);
        let mut leaf =
            Leaf { corners: [[[Real::NAN; LANES]; 3]; 3], object: [u32::MAX; LANES], index: [0; LANES] };
        let mut lanes = 0;
        for (lane, item) in items.iter().enumerate() {
            leaf.object[lane] = item.object();
            match &objects[item.object() as usize].primitive {
                Primitive::Mesh(mesh) => {
                    leaf.index[lane] = item.index();
                    for (corner, p) in mesh.triangle(item.index() as usize).into_iter().enumerate() {
                        for axis in 0..3 {
                            leaf.corners[corner][axis][lane] = p[axis];
                        }
                    }
                    lanes |= 1 << lane;
                }
                _ => lanes |= 1 << (LANES + lane),
            }
        }
        (leaf, Lanes(lanes))
    }

    /// Reals per leaf in [`Leaf::flatten`]'s layout.
    pub const FLAT_REALS: usize = 9 * LANES;
    /// Indices per leaf in [`Leaf::flatten`]'s layout.
    pub const FLAT_IDS: usize = 2 * LANES;

    /// Appends the leaf as plain numbers: its corners in storage order
    /// (`corners[corner][axis][lane]`), then the lanes' objects and indices.
    pub fn flatten(&self, reals: &mut Vec<Real>, ids: &mut Vec<u32>) {
        reals.extend(self.corners.iter().flatten().flatten());
        ids.extend(self.object.iter().chain(&self.index));
    }

    /// The leaf [`Leaf::flatten`] wrote: [`Leaf::FLAT_REALS`] reals and
    /// [`Leaf::FLAT_IDS`] indices.
    pub fn from_flat(reals: &[Real], ids: &[u32]) -> Self {
        let mut leaf = Leaf { corners: [[[0.0; LANES]; 3]; 3], object: [0; LANES], index: [0; LANES] };
        for (to, from) in leaf.corners.iter_mut().flatten().flatten().zip(reals) {
            *to = *from;
        }
        leaf.object.copy_from_slice(&ids[..LANES]);
        leaf.index.copy_from_slice(&ids[LANES..2 * LANES]);
        leaf
    }

    /// The lanes [`Leaf::new`] gives `items`, without making the leaf.
    pub fn lanes(items: &[Item], objects: &[Object]) -> Lanes {
        Lanes(items.iter().enumerate().fold(0, |lanes, (lane, item)| {
            lanes
                | match objects[item.object() as usize].primitive {
                    Primitive::Mesh(_) => 1 << lane,
                    _ => 1 << (LANES + lane),
                }
        }))
    }

    /// The object in `lane`.
    #[inline(always)]
    pub fn object(&self, lane: usize) -> u32 {
        self.object[lane]
    }

    /// The triangle index in `lane`; for a whole object the number of its
    /// block's [`super::object_block::ObjectBlock`] (`u32::MAX` if none).
    #[inline(always)]
    pub fn index(&self, lane: usize) -> u32 {
        self.index[lane]
    }

    /// The lanes holding whole objects (any primitive of `objects` but a
    /// mesh).
    pub fn whole_object_lanes(&self, objects: &[Object]) -> u32 {
        (0..LANES).fold(0, |mask, lane| match objects.get(self.object[lane] as usize).map(|o| &o.primitive) {
            Some(Primitive::Mesh(_)) | None => mask,
            Some(_) => mask | 1 << lane,
        })
    }

    /// Sets the index of `lane`, a whole object's: the number of its block's
    /// [`super::object_block::ObjectBlock`].
    pub fn set_index(&mut self, lane: usize, index: u32) {
        self.index[lane] = index;
    }

    /// A block of the whole objects `objects` (at most [`LANES`]), in order.
    #[cfg(test)]
    pub fn whole_objects(objects: &[u32]) -> Self {
        let mut leaf =
            Leaf { corners: [[[Real::NAN; LANES]; 3]; 3], object: [u32::MAX; LANES], index: [0; LANES] };
        leaf.object[..objects.len()].copy_from_slice(objects);
        leaf
    }

    /// The corners a, b, c of the triangle in `lane`.
    fn corners(&self, lane: usize) -> [Vec3; 3] {
        self.corners.map(|c| Vec3::new(c[0][lane], c[1][lane], c[2][lane]))
    }

    /// The unit geometric normal of the triangle in `lane`: from the same
    /// corners by the same function, so the same bits as its mesh's
    /// [`crate::geometry::mesh::Mesh::normal`].
    pub fn normal(&self, lane: usize) -> Vec3 {
        let [a, b, c] = self.corners(lane);
        geometric_normal(a, b, c).unwrap_or(Vec3::ZERO)
    }

    /// The triangles of the lanes in `mask` that `ray` hits with `t` in
    /// `range` by `method`: each lane's `t`, and the mask of the lanes hit.
    #[inline(always)]
    pub fn intersect_triangles(
        &self,
        mask: u32,
        ray: &TriangleRay,
        range: Interval,
        method: TriangleMethod,
    ) -> ([Real; LANES], u32) {
        if mask == 0 {
            return ([0.0; LANES], 0);
        }
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        if method == TriangleMethod::Watertight {
            return self.watertight_sse(mask, ray, range);
        }
        self.intersect_scalar(mask, ray, range, method)
    }

    /// The mesh triangles of a leaf (its `blocks`, with `lanes`) that `ray`
    /// hits with `t` in `range` by `method`: each one's `t` at index
    /// `LANES · block + lane`, and the mask of those hit (the same bits).
    /// A leaf of two blocks takes one eight-lane watertight test where the
    /// CPU has AVX2 (detected at run time), else a test per block.
    #[inline(always)]
    pub fn intersect_leaf(
        blocks: &[Leaf],
        lanes: Lanes,
        ray: &TriangleRay,
        range: Interval,
        method: TriangleMethod,
    ) -> ([Real; BLOCKS * LANES], u32) {
        Self::intersect_leaf_with::<false>(blocks, lanes, ray, range, method)
    }

    /// [`Leaf::intersect_leaf`]; with `AVX2` the caller is compiled for
    /// AVX2 (it has checked the CPU), and the two-block test is inlined into
    /// it instead of called.
    #[inline(always)]
    pub fn intersect_leaf_with<const AVX2: bool>(
        blocks: &[Leaf],
        lanes: Lanes,
        ray: &TriangleRay,
        range: Interval,
        method: TriangleMethod,
    ) -> ([Real; BLOCKS * LANES], u32) {
        let mask = (0..blocks.len()).fold(0, |m, b| m | lanes.block(b).triangles() << (b * LANES));
        // A leaf of whole objects only (the Cornell box's walls, spheres)
        // has nothing to test: the block loop below would still write each
        // block's `t` in four-lane pieces that the caller reads back whole,
        // a store-to-load forwarding stall for nothing.
        if mask == 0 {
            return ([0.0; BLOCKS * LANES], 0);
        }
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        if let Ok(pair) = <&[Leaf; 2]>::try_from(blocks)
            && method == TriangleMethod::Watertight
        {
            if AVX2 {
                // SAFETY: `AVX2` is true only in code compiled for AVX2 on a
                // CPU that has it.
                return unsafe { Self::watertight_pair_avx2_body(pair, mask, ray, range) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU has AVX2.
                return unsafe { Self::watertight_pair_avx2(pair, mask, ray, range) };
            }
        }
        if let [leaf] = blocks {
            // Widened in registers: copied into the eight-lane array in
            // memory, its four `t`s would be read back eight at a time by
            // the caller, a store-to-load forwarding stall.
            let (block_t, hit) = leaf.intersect_triangles(mask, ray, range, method);
            return (std::array::from_fn(|i| if i < LANES { block_t[i] } else { 0.0 }), hit);
        }
        let mut t = [0.0; BLOCKS * LANES];
        let mut hit = 0;
        for (b, leaf) in blocks.iter().enumerate() {
            let block_mask = (mask >> (b * LANES)) & ((1 << LANES) - 1);
            let (block_t, block_hit) = leaf.intersect_triangles(block_mask, ray, range, method);
            t[b * LANES..(b + 1) * LANES].copy_from_slice(&block_t);
            hit |= block_hit << (b * LANES);
        }
        (t, hit)
    }

    /// [`Leaf::watertight_sse`] on the eight lanes of two blocks with AVX2:
    /// every operation is the SSE test's on twice the lanes (no fused
    /// multiply-adds), so each lane's `t` has the scalar test's bits.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[target_feature(enable = "avx2")]
    #[inline]
    unsafe fn watertight_pair_avx2(
        pair: &[Leaf; 2],
        mask: u32,
        ray: &TriangleRay,
        range: Interval,
    ) -> ([Real; BLOCKS * LANES], u32) {
        // SAFETY: this function is compiled for AVX2.
        unsafe { Self::watertight_pair_avx2_body(pair, mask, ray, range) }
    }

    /// The body of [`Leaf::watertight_pair_avx2`], to be inlined into a
    /// caller compiled for AVX2 (a function with `#[target_feature]` cannot
    /// be `#[inline(always)]`, and the compiler does not inline it into the
    /// single-ray traversal on its own).
    ///
    /// # Safety
    /// The CPU must have AVX2, and the caller must be compiled for AVX2:
    /// elsewhere every intrinsic below would be a call.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[inline(always)]
    unsafe fn watertight_pair_avx2_body(
        pair: &[Leaf; 2],
        mask: u32,
        ray: &TriangleRay,
        range: Interval,
    ) -> ([Real; BLOCKS * LANES], u32) {
        use std::arch::x86_64::*;
        // SAFETY: the caller has AVX2 (above); the loads and stores are argued below.
        unsafe {
            if mask == 0 {
                return ([0.0; BLOCKS * LANES], 0);
            }
            let [kx, ky, kz] = ray.axes();
            let s = ray.shear();
            let o = ray.ray.origin;
            let (ox, oy, oz) = (_mm256_set1_ps(o[kx]), _mm256_set1_ps(o[ky]), _mm256_set1_ps(o[kz]));
            let (sx, sy, sz) = (_mm256_set1_ps(s.x), _mm256_set1_ps(s.y), _mm256_set1_ps(s.z));
            // Macros, not closures: a closure is a function of its own, not
            // compiled for AVX2, in which every intrinsic would be a call.
            // The row of four lanes of each block side by side. SAFETY: aligned
            // loads of 16-byte-aligned rows of four f32 (`repr(C, align(16))`).
            macro_rules! load {
                ($corner:expr, $axis:expr) => {
                    _mm256_set_m128(
                        _mm_load_ps(pair[1].corners[$corner][$axis].as_ptr()),
                        _mm_load_ps(pair[0].corners[$corner][$axis].as_ptr()),
                    )
                };
            }
            // p = corner − origin, axes permuted, then sheared: (x + sx·z, y + sy·z, z).
            macro_rules! shear {
                ($corner:expr) => {{
                    let (px, py, pz) = (
                        _mm256_sub_ps(load!($corner, kx), ox),
                        _mm256_sub_ps(load!($corner, ky), oy),
                        _mm256_sub_ps(load!($corner, kz), oz),
                    );
                    (_mm256_add_ps(px, _mm256_mul_ps(sx, pz)), _mm256_add_ps(py, _mm256_mul_ps(sy, pz)), pz)
                }};
            }
            let ((x0, y0, z0), (x1, y1, z1), (x2, y2, z2)) = (shear!(0), shear!(1), shear!(2));
            let e0 = _mm256_sub_ps(_mm256_mul_ps(x1, y2), _mm256_mul_ps(y1, x2));
            let e1 = _mm256_sub_ps(_mm256_mul_ps(x2, y0), _mm256_mul_ps(y2, x0));
            let e2 = _mm256_sub_ps(_mm256_mul_ps(x0, y1), _mm256_mul_ps(y0, x1));
            // The SSE test's comparisons: `cmpneq` is unordered (true for NaN),
            // the others ordered (false for NaN).
            let zero = _mm256_setzero_ps();
            let abs = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fff_ffff));
            let inf = _mm256_set1_ps(Real::INFINITY);
            macro_rules! regular {
                ($e:expr) => {{
                    let e = $e;
                    _mm256_and_ps(
                        _mm256_cmp_ps::<_CMP_NEQ_UQ>(e, zero),
                        _mm256_cmp_ps::<_CMP_LT_OS>(_mm256_and_ps(e, abs), inf),
                    )
                }};
            }
            let regular = _mm256_and_ps(_mm256_and_ps(regular!(e0), regular!(e1)), regular!(e2));
            let exact = mask & !(_mm256_movemask_ps(regular) as u32);

            macro_rules! lt {
                ($a:expr, $b:expr) => {
                    _mm256_cmp_ps::<_CMP_LT_OS>($a, $b)
                };
            }
            macro_rules! gt {
                ($a:expr, $b:expr) => {
                    _mm256_cmp_ps::<_CMP_GT_OS>($a, $b)
                };
            }
            let negative = _mm256_or_ps(_mm256_or_ps(lt!(e0, zero), lt!(e1, zero)), lt!(e2, zero));
            let positive = _mm256_or_ps(_mm256_or_ps(gt!(e0, zero), gt!(e1, zero)), gt!(e2, zero));
            let det = _mm256_add_ps(_mm256_add_ps(e0, e1), e2);
            let mut reject =
                _mm256_or_ps(_mm256_and_ps(negative, positive), _mm256_cmp_ps::<_CMP_EQ_OQ>(det, zero));
            let (z0, z1, z2) = (_mm256_mul_ps(z0, sz), _mm256_mul_ps(z1, sz), _mm256_mul_ps(z2, sz));
            let t_scaled = _mm256_add_ps(
                _mm256_add_ps(_mm256_mul_ps(e0, z0), _mm256_mul_ps(e1, z1)),
                _mm256_mul_ps(e2, z2),
            );
            let max_det = _mm256_mul_ps(_mm256_set1_ps(range.max), det);
            let below = _mm256_and_ps(
                lt!(det, zero),
                _mm256_or_ps(_mm256_cmp_ps::<_CMP_GE_OS>(t_scaled, zero), lt!(t_scaled, max_det)),
            );
            let above = _mm256_and_ps(
                gt!(det, zero),
                _mm256_or_ps(_mm256_cmp_ps::<_CMP_LE_OS>(t_scaled, zero), gt!(t_scaled, max_det)),
            );
            reject = _mm256_or_ps(reject, _mm256_or_ps(below, above));
            let t = _mm256_mul_ps(t_scaled, _mm256_div_ps(_mm256_set1_ps(1.0), det));
            let inside = _mm256_and_ps(gt!(t, _mm256_set1_ps(range.min)), lt!(t, _mm256_set1_ps(range.max)));
            let mut hit = _mm256_movemask_ps(_mm256_andnot_ps(reject, inside)) as u32 & mask & !exact;
            let mut out = [0.0; BLOCKS * LANES];
            // SAFETY: `out` holds eight f32.
            _mm256_storeu_ps(out.as_mut_ptr(), t);
            if exact != 0 {
                for (b, leaf) in pair.iter().enumerate() {
                    let lanes = (exact >> (b * LANES)) & ((1 << LANES) - 1);
                    if lanes != 0 {
                        let (t, exact_hit) =
                            leaf.intersect_scalar(lanes, ray, range, TriangleMethod::Watertight);
                        for lane in lanes_of(exact_hit) {
                            out[b * LANES + lane] = t[lane];
                        }
                        hit |= exact_hit << (b * LANES);
                    }
                }
            }
            (out, hit)
        }
    }

    /// [`Leaf::intersect_triangles`] one lane at a time.
    pub fn intersect_scalar(
        &self,
        mask: u32,
        ray: &TriangleRay,
        range: Interval,
        method: TriangleMethod,
    ) -> ([Real; LANES], u32) {
        let mut t = [0.0; LANES];
        let mut hit = 0;
        for lane in lanes_of(mask) {
            let [a, b, c] = self.corners(lane);
            if let Some(h) = intersect_by(method, a, b, c, ray, range) {
                t[lane] = h.t;
                hit |= 1 << lane;
            }
        }
        (t, hit)
    }

    /// The watertight test on four lanes with SSE2. Every line is the
    /// scalar test's line ([`crate::geometry::triangle::intersect_watertight_prepared`])
    /// on four lanes at once.
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[inline(always)]
    fn watertight_sse(&self, mask: u32, ray: &TriangleRay, range: Interval) -> ([Real; LANES], u32) {
        use std::arch::x86_64::*;
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline, and every
        // load reads 16-byte-aligned rows of `self.corners` (the struct is
        // `repr(C, align(16))` with rows of four f32).
        unsafe {
            let [kx, ky, kz] = ray.axes();
            let s = ray.shear();
            let o = ray.ray.origin;
            let (ox, oy, oz) = (_mm_set1_ps(o[kx]), _mm_set1_ps(o[ky]), _mm_set1_ps(o[kz]));
            let (sx, sy, sz) = (_mm_set1_ps(s.x), _mm_set1_ps(s.y), _mm_set1_ps(s.z));
            let load = |corner: usize, axis: usize| _mm_load_ps(self.corners[corner][axis].as_ptr());
            // p = corner − origin, axes permuted, then sheared: (x + sx·z, y + sy·z, z).
            let shear = |corner: usize| {
                let (px, py, pz) = (
                    _mm_sub_ps(load(corner, kx), ox),
                    _mm_sub_ps(load(corner, ky), oy),
                    _mm_sub_ps(load(corner, kz), oz),
                );
                (_mm_add_ps(px, _mm_mul_ps(sx, pz)), _mm_add_ps(py, _mm_mul_ps(sy, pz)), pz)
            };
            let ((x0, y0, z0), (x1, y1, z1), (x2, y2, z2)) = (shear(0), shear(1), shear(2));
            let e0 = _mm_sub_ps(_mm_mul_ps(x1, y2), _mm_mul_ps(y1, x2));
            let e1 = _mm_sub_ps(_mm_mul_ps(x2, y0), _mm_mul_ps(y2, x0));
            let e2 = _mm_sub_ps(_mm_mul_ps(x0, y1), _mm_mul_ps(y0, x1));
            // Lanes with an edge function that is 0 or not finite go to the
            // scalar test, which re-evaluates them exactly.
            let zero = _mm_setzero_ps();
            let abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff));
            let inf = _mm_set1_ps(Real::INFINITY);
            let regular =
                |e: __m128| _mm_and_ps(_mm_cmpneq_ps(e, zero), _mm_cmplt_ps(_mm_and_ps(e, abs), inf));
            let regular = _mm_and_ps(_mm_and_ps(regular(e0), regular(e1)), regular(e2));
            let exact = mask & !(_mm_movemask_ps(regular) as u32);

            let negative =
                _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(e0, zero), _mm_cmplt_ps(e1, zero)), _mm_cmplt_ps(e2, zero));
            let positive =
                _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(e0, zero), _mm_cmpgt_ps(e1, zero)), _mm_cmpgt_ps(e2, zero));
            let det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
            let mut reject = _mm_or_ps(_mm_and_ps(negative, positive), _mm_cmpeq_ps(det, zero));
            let (z0, z1, z2) = (_mm_mul_ps(z0, sz), _mm_mul_ps(z1, sz), _mm_mul_ps(z2, sz));
            let t_scaled = _mm_add_ps(_mm_add_ps(_mm_mul_ps(e0, z0), _mm_mul_ps(e1, z1)), _mm_mul_ps(e2, z2));
            let max_det = _mm_mul_ps(_mm_set1_ps(range.max), det);
            let below = _mm_and_ps(
                _mm_cmplt_ps(det, zero),
                _mm_or_ps(_mm_cmpge_ps(t_scaled, zero), _mm_cmplt_ps(t_scaled, max_det)),
            );
            let above = _mm_and_ps(
                _mm_cmpgt_ps(det, zero),
                _mm_or_ps(_mm_cmple_ps(t_scaled, zero), _mm_cmpgt_ps(t_scaled, max_det)),
            );
            reject = _mm_or_ps(reject, _mm_or_ps(below, above));
            let t = _mm_mul_ps(t_scaled, _mm_div_ps(_mm_set1_ps(1.0), det));
            let inside =
                _mm_and_ps(_mm_cmpgt_ps(t, _mm_set1_ps(range.min)), _mm_cmplt_ps(t, _mm_set1_ps(range.max)));
            let mut hit = _mm_movemask_ps(_mm_andnot_ps(reject, inside)) as u32 & mask & !exact;
            let mut out = [0.0; LANES];
            _mm_storeu_ps(out.as_mut_ptr(), t);
            if exact != 0 {
                let (t, exact_hit) = self.intersect_scalar(exact, ray, range, TriangleMethod::Watertight);
                for lane in lanes_of(exact_hit) {
                    out[lane] = t[lane];
                }
                hit |= exact_hit;
            }
            (out, hit)
        }
    }
}

/// The lanes set in `mask`, lowest first.
#[inline(always)]
pub(super) fn lanes_of(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let lane = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            lane
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::mesh::Mesh;
    use crate::math::ray::Ray;
    use proptest::prelude::*;

    /// A leaf of four triangles with corners `corners`.
    fn leaf_of(corners: &[[[Real; 3]; 3]]) -> (Leaf, Lanes) {
        let positions = corners.iter().flatten().map(|&p| Vec3::from(p)).collect();
        let triangles = (0..corners.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
        let mesh = Mesh::new(positions, triangles).unwrap();
        let objects = vec![Object { primitive: Primitive::Mesh(mesh), material: 0 }];
        let items: Vec<Item> = (0..corners.len() as u32)
            .map(|i| {
                Item::new(
                    crate::geometry::aabb::Aabb::from_points(corners[i as usize].map(Vec3::from)).unwrap(),
                    0,
                    i,
                )
            })
            .collect();
        let (leaf, lanes) = Leaf::new(&items, &objects);
        assert_eq!(Leaf::lanes(&items, &objects), lanes);
        (leaf, lanes)
    }

    fn bits(t: &[Real], hit: u32) -> Vec<(usize, u64)> {
        #[allow(clippy::useless_conversion)] // to_bits gives u32 for f32 geometry
        lanes_of(hit).map(|lane| (lane, u64::from(t[lane].to_bits()))).collect()
    }

    proptest! {
        /// A leaf's normal of a triangle is its mesh's, bit for bit: a
        /// closest-hit query takes it from either (`NORMALS_READ_UP_TO`).
        #[test]
        fn a_leaf_makes_its_triangles_normals_as_the_mesh_does(
            corners in prop::array::uniform4(prop::array::uniform3(prop::array::uniform3(-1.0 as Real..1.0))),
            scale in prop::sample::select(vec![1.0 as Real, 1e-3, 1e4, 1e20, 1e-20]),
        ) {
            let corners: Vec<[[Real; 3]; 3]> = corners.iter().map(|t| t.map(|p| p.map(|x| x * scale))).collect();
            let positions = corners.iter().flatten().map(|&p| Vec3::from(p)).collect();
            let triangles = (0..4u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            let mesh = Mesh::new(positions, triangles).unwrap();
            let (leaf, _) = leaf_of(&corners);
            for lane in 0..LANES {
                prop_assert_eq!(leaf.normal(lane).to_array().map(Real::to_bits), mesh.normal(lane).to_array().map(Real::to_bits));
            }
        }

        /// The SIMD tests and the scalar one agree bit for bit, on random
        /// triangles and on triangles sharing edges and corners with rays
        /// through them (where edge functions are 0 and the exact
        /// re-evaluation runs): four lanes of a block (SSE), and the eight
        /// lanes of a two-block leaf (AVX2 where the CPU has it), some lanes
        /// left out.
        #[test]
        fn the_simd_tests_give_the_scalar_test_bits(
            corners in prop::array::uniform8(prop::array::uniform3(prop::array::uniform3(-4i8..4))),
            used in 1u32..256,
            scale in prop::sample::select(vec![1.0 as Real, 0.1, 1e-3, 1e4, 1e20, 1e-20]),
            origin in prop::array::uniform3(-6i8..6),
            target in prop::array::uniform3(-8i8..8),
            jitter in prop::array::uniform3(-1.0 as Real..1.0),
            snap in any::<bool>(),
            max in prop::sample::select(vec![Real::INFINITY, 0.5, 1.0, 2.0]),
        ) {
            // Small integer grids make shared edges, shared corners and rays
            // exactly through them common.
            let corners: Vec<[[Real; 3]; 3]> = corners.iter().map(|t| t.map(|p| p.map(|x| x as Real * scale))).collect();
            let ((leaf, lanes), (second, second_lanes)) = (leaf_of(&corners[..4]), leaf_of(&corners[4..]));
            let origin = Vec3::from(origin.map(|x| x as Real * scale));
            let mut target = Vec3::from(target.map(|x| x as Real * scale * 0.5));
            if !snap {
                target += Vec3::from(jitter) * scale;
            }
            let dir = target - origin;
            prop_assume!(dir != Vec3::ZERO && dir.is_finite());
            let ray = TriangleRay::new(&Ray::new(origin, dir));
            let range = Interval::new(0.0, max);
            let method = TriangleMethod::Watertight;
            let (t, hit) = leaf.intersect_triangles(lanes.triangles(), &ray, range, method);
            let (ts, hits) = leaf.intersect_scalar(lanes.triangles(), &ray, range, method);
            prop_assert_eq!(bits(&t, hit), bits(&ts, hits));

            let (low, high) = (used & 0xF, used >> 4);
            let pair_lanes = Lanes(lanes.0 & low).with_block(1, Lanes(second_lanes.0 & high));
            let (t, hit) = Leaf::intersect_leaf(&[leaf, second], pair_lanes, &ray, range, method);
            let (t0, hit0) = leaf.intersect_scalar(low, &ray, range, method);
            let (t1, hit1) = second.intersect_scalar(high, &ray, range, method);
            let scalar: Vec<(usize, u64)> =
                bits(&t0, hit0).into_iter().chain(bits(&t1, hit1).into_iter().map(|(l, t)| (l + LANES, t))).collect();
            prop_assert_eq!(bits(&t, hit), scalar);
        }
    }

    #[test]
    fn a_leaf_has_objects_when_any_block_holds_a_whole_object() {
        let triangles = Lanes(0b0111);
        let object = Lanes(1 << LANES);
        assert!(!triangles.has_objects());
        assert!(!triangles.with_block(1, Lanes(0b1111)).has_objects());
        assert!(object.has_objects());
        assert!(triangles.with_block(1, Lanes(0b0001 | 1 << (LANES + 3))).has_objects());
        for lane in 0..LANES {
            assert!(!Lanes(1 << lane).with_block(1, Lanes(1 << lane)).has_objects(), "{lane}");
            assert!(Lanes(1).with_block(1, Lanes(1 << (LANES + lane))).has_objects(), "{lane}");
        }
    }

    #[test]
    fn lanes_outside_the_mask_and_unused_lanes_are_never_hit() {
        let tri = [[-1.0, -1.0, 1.0], [1.0, -1.0, 1.0], [0.0, 1.0, 1.0]];
        let (leaf, lanes) = leaf_of(&[tri, tri, tri]);
        assert_eq!(lanes, Lanes(0b0111));
        let ray = TriangleRay::new(&Ray::new(Vec3::ZERO, Vec3::Z));
        let range = Interval::new(0.0, Real::INFINITY);
        for method in [TriangleMethod::Watertight, TriangleMethod::MollerTrumbore, TriangleMethod::AreaRatio]
        {
            assert_eq!(leaf.intersect_triangles(0b1111, &ray, range, method).1, 0b0111, "{method:?}");
            assert_eq!(leaf.intersect_triangles(0b0101, &ray, range, method).1, 0b0101, "{method:?}");
        }
    }
}
