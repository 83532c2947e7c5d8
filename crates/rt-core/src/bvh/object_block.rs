//! A leaf block's whole boxes and polygons laid out lane by lane, so that
//! one pass of four-lane arithmetic tests them all.
//!
//! Scenes built from the course's primitives put several objects into one
//! leaf where splitting them does not pay (the build's SAH). Looked up in
//! the scene and tested one by one, each such test is a chain of dependent
//! divisions and branches (the slab test's six quotients, the polygon's
//! plane hit and crossing-number test) waiting on the last; here each step
//! is done for a block's four lanes at once, the way the triangle lanes of
//! [`super::leaf`] are.
//!
//! Each lane performs exactly the operations of [`Aabb::intersect`] (the
//! slab test) or [`Polygon::intersect`] (plane, then crossing-number test),
//! in the same order, so its `t` and normal have the same bits (tested
//! against the primitives' own functions). A polygon of up to
//! [`POLYGON_CORNERS`] corners is padded by repeating its last corner: an
//! edge from a corner to itself crosses no line, so the crossing count is
//! unchanged. Other objects (spheres, single triangles, larger polygons)
//! and boxes under the six-plane method stay with the scalar test.

use super::leaf::{LANES, Leaf, lanes_of};
use crate::geometry::aabb::Aabb;
use crate::geometry::method::{BoxMethod, Methods};
use crate::geometry::object::Object;
use crate::geometry::polygon::Polygon;
use crate::geometry::primitive::Primitive;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3};

/// The most corners a polygon may have to be tested in a block.
pub(super) const POLYGON_CORNERS: usize = 4;

/// The boxes and polygons of one leaf block (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
#[repr(C, align(32))]
pub(super) struct ObjectBlock {
    /// Boxes: `min[axis][lane]` and `max[axis][lane]`; NaN elsewhere.
    min: [[Real; LANES]; 3],
    max: [[Real; LANES]; 3],
    /// Polygons: the unit normal `normal[axis][lane]` and the plane's `d`
    /// (`p·n = d`); NaN elsewhere.
    normal: [[Real; LANES]; 3],
    d: [Real; LANES],
    /// Polygons: the corners projected on the two axes the polygon keeps,
    /// `u[corner][lane]`, `v[corner][lane]`, the last one repeated up to
    /// [`POLYGON_CORNERS`].
    u: [[Real; LANES]; POLYGON_CORNERS],
    v: [[Real; LANES]; POLYGON_CORNERS],
    /// Polygons: `pick_u[axis][lane]` all ones where `axis` is the lane's
    /// first kept axis, else 0 (a bitwise select of the hit point's
    /// coordinate); `pick_v` for the second.
    pick_u: [[u32; LANES]; 3],
    pick_v: [[u32; LANES]; 3],
    /// All ones in the lanes holding polygons, else 0.
    polygon_lanes: [u32; LANES],
    /// Polygons: the axes projected on, per lane.
    axes: [[u8; 2]; LANES],
    /// The lanes holding boxes.
    boxes: u32,
    /// The lanes holding polygons.
    polygons: u32,
}

/// The hits of an [`ObjectBlock`] test.
#[derive(Clone, Copy, Debug)]
pub(super) struct ObjectHits {
    /// Each lane's `t`, valid where `hit` has its bit.
    pub t: [Real; LANES],
    /// The lanes hit within the range.
    pub hit: u32,
    /// Boxes: the axis of the face hit.
    axis: [u8; LANES],
    /// Boxes: the lanes entered (the hit is the entry face, whose outward
    /// normal faces the ray) rather than left.
    entered: u32,
}

impl ObjectBlock {
    /// The block of `leaf`'s whole objects, or `None` if none of them can
    /// be tested here.
    fn new(leaf: &Leaf, objects: &[Object]) -> Option<Self> {
        let mut block = ObjectBlock {
            min: [[Real::NAN; LANES]; 3],
            max: [[Real::NAN; LANES]; 3],
            normal: [[Real::NAN; LANES]; 3],
            d: [Real::NAN; LANES],
            u: [[Real::NAN; LANES]; POLYGON_CORNERS],
            v: [[Real::NAN; LANES]; POLYGON_CORNERS],
            axes: [[0; 2]; LANES],
            pick_u: [[0; LANES]; 3],
            pick_v: [[0; LANES]; 3],
            polygon_lanes: [0; LANES],
            boxes: 0,
            polygons: 0,
        };
        for lane in 0..LANES {
            match objects.get(leaf.object(lane) as usize).map(|o| &o.primitive) {
                Some(Primitive::Aabb(b)) => block.set_box(lane, b),
                // At least three corners, as `Polygon::new` makes them (a
                // polygon read back from a scene cache is not made again).
                Some(Primitive::Polygon(p)) if (3..=POLYGON_CORNERS).contains(&p.points().len()) => {
                    block.set_polygon(lane, p)
                }
                _ => {}
            }
        }
        (block.boxes | block.polygons != 0).then_some(block)
    }

    fn set_box(&mut self, lane: usize, b: &Aabb) {
        for axis in 0..3 {
            self.min[axis][lane] = b.min()[axis];
            self.max[axis][lane] = b.max()[axis];
        }
        self.boxes |= 1 << lane;
    }

    fn set_polygon(&mut self, lane: usize, p: &Polygon) {
        let n = p.normal();
        for axis in 0..3 {
            self.normal[axis][lane] = n[axis];
        }
        self.d[lane] = p.plane_d();
        let [u, v] = p.axes();
        let points = p.points();
        for corner in 0..POLYGON_CORNERS {
            let q = points[corner.min(points.len() - 1)];
            self.u[corner][lane] = q[u];
            self.v[corner][lane] = q[v];
        }
        self.axes[lane] = [u as u8, v as u8];
        self.pick_u[u][lane] = u32::MAX;
        self.pick_v[v][lane] = u32::MAX;
        self.polygon_lanes[lane] = u32::MAX;
        self.polygons |= 1 << lane;
    }

    /// The lanes this block tests under `methods` (boxes only by the slab
    /// test).
    #[inline(always)]
    pub fn lanes(&self, methods: Methods) -> u32 {
        self.polygons | if methods.aabb == BoxMethod::Slab { self.boxes } else { 0 }
    }

    /// The objects of the lanes in `mask` (a subset of [`ObjectBlock::lanes`])
    /// that `ray` hits with `t` in `range`: four-lane SSE arithmetic with
    /// `f32` geometry on x86-64, else lane by lane; the same bits either way.
    #[inline(always)]
    pub fn intersect(&self, mask: u32, ray: &Ray, range: Interval) -> ObjectHits {
        #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
        return self.intersect_sse(mask, ray, range);
        #[cfg(not(all(target_arch = "x86_64", not(feature = "f64"))))]
        self.intersect_lanes(mask, ray, range)
    }

    /// [`ObjectBlock::intersect`] one lane after the other: each lane's
    /// steps written out as [`Aabb::intersect`] and [`Polygon::intersect`]
    /// take them.
    #[cfg_attr(all(target_arch = "x86_64", not(feature = "f64")), allow(dead_code))]
    fn intersect_lanes(&self, mask: u32, ray: &Ray, range: Interval) -> ObjectHits {
        let mut hits = ObjectHits { t: [0.0; LANES], hit: 0, axis: [0; LANES], entered: 0 };
        for lane in lanes_of(mask & self.boxes) {
            self.intersect_box(lane, ray, range, &mut hits);
        }
        for lane in lanes_of(mask & self.polygons) {
            self.intersect_polygon(lane, ray, range, &mut hits);
        }
        hits
    }

    /// [`Aabb::intersect`] in `lane`: the slab span (`Aabb::slab_span`,
    /// Kay & Kajiya 1986), then the entry if in range, else the exit.
    fn intersect_box(&self, lane: usize, ray: &Ray, range: Interval, hits: &mut ObjectHits) {
        let (mut enter, mut enter_axis) = (Real::NEG_INFINITY, 0);
        let (mut exit, mut exit_axis) = (Real::INFINITY, 0);
        for axis in 0..3 {
            let (o, d) = (ray.origin[axis], ray.dir[axis]);
            let (lo, hi) = (self.min[axis][lane], self.max[axis][lane]);
            if d == 0.0 {
                // Inside this slab for every t, or never.
                if o < lo || o > hi {
                    return;
                }
                continue;
            }
            let (t_lo, t_hi) = ((lo - o) / d, (hi - o) / d);
            let (near, far) = if t_lo <= t_hi { (t_lo, t_hi) } else { (t_hi, t_lo) };
            if near > enter {
                (enter, enter_axis) = (near, axis as u8);
            }
            if far < exit {
                (exit, exit_axis) = (far, axis as u8);
            }
        }
        if !(enter <= exit && exit.is_finite()) {
            return;
        }
        if range.contains(enter) {
            (hits.t[lane], hits.axis[lane]) = (enter, enter_axis);
            hits.entered |= 1 << lane;
        } else if range.contains(exit) {
            (hits.t[lane], hits.axis[lane]) = (exit, exit_axis);
        } else {
            return;
        }
        hits.hit |= 1 << lane;
    }

    /// [`Polygon::intersect`] in `lane`: the plane `p·n = d` from either
    /// side, then the crossing-number test (W. R. Franklin's PNPOLY) on the
    /// two axes the polygon keeps.
    fn intersect_polygon(&self, lane: usize, ray: &Ray, range: Interval, hits: &mut ObjectHits) {
        let n = Vec3::new(self.normal[0][lane], self.normal[1][lane], self.normal[2][lane]);
        let denom = ray.dir.dot(n);
        if denom == 0.0 {
            return;
        }
        let t = (self.d[lane] - ray.origin.dot(n)) / denom;
        if !range.contains(t) {
            return;
        }
        let p = ray.at(t);
        let [a, b] = self.axes[lane];
        let (px, py) = (p[a as usize], p[b as usize]);
        let mut inside = false;
        let mut j = POLYGON_CORNERS - 1;
        for i in 0..POLYGON_CORNERS {
            let (xi, yi, xj, yj) = (self.u[i][lane], self.v[i][lane], self.u[j][lane], self.v[j][lane]);
            if (yi > py) != (yj > py) && px < (xj - xi) * (py - yi) / (yj - yi) + xi {
                inside = !inside;
            }
            j = i;
        }
        if inside {
            hits.t[lane] = t;
            hits.hit |= 1 << lane;
        }
    }

    /// [`ObjectBlock::intersect_lanes`] with SSE: each step of the scalar
    /// tests done for the four lanes by one instruction (SSE2 only, the
    /// x86-64 baseline), branches replaced by lane masks, the same IEEE
    /// operations in the same order (no fused multiply-adds).
    #[cfg(all(target_arch = "x86_64", not(feature = "f64")))]
    #[inline(always)]
    fn intersect_sse(&self, mask: u32, ray: &Ray, range: Interval) -> ObjectHits {
        use std::arch::x86_64::*;
        let mut hits = ObjectHits { t: [0.0; LANES], hit: 0, axis: [0; LANES], entered: 0 };
        // SAFETY: SSE and SSE2 are part of the x86-64 baseline; every load
        // reads a whole row of four f32 or u32 of `self` (unaligned loads).
        unsafe {
            let load = |row: &[Real; LANES]| _mm_loadu_ps(row.as_ptr());
            // a where m, else b.
            let select = |m: __m128, a: __m128, b: __m128| _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b));
            let (min, max) = (_mm_set1_ps(range.min), _mm_set1_ps(range.max));
            let in_range = |t: __m128| _mm_and_ps(_mm_cmpgt_ps(t, min), _mm_cmplt_ps(t, max));
            let mut t_out = _mm_setzero_ps();
            if mask & self.boxes != 0 {
                let mut enter = _mm_set1_ps(Real::NEG_INFINITY);
                let mut exit = _mm_set1_ps(Real::INFINITY);
                let (mut enter_axis, mut exit_axis) = (_mm_setzero_ps(), _mm_setzero_ps());
                let mut missed = _mm_setzero_ps();
                for axis in 0..3 {
                    let (o, d) = (ray.origin[axis], ray.dir[axis]);
                    let (lo, hi) = (load(&self.min[axis]), load(&self.max[axis]));
                    let o4 = _mm_set1_ps(o);
                    if d == 0.0 {
                        missed = _mm_or_ps(missed, _mm_or_ps(_mm_cmplt_ps(o4, lo), _mm_cmpgt_ps(o4, hi)));
                        continue;
                    }
                    let d4 = _mm_set1_ps(d);
                    let (t_lo, t_hi) =
                        (_mm_div_ps(_mm_sub_ps(lo, o4), d4), _mm_div_ps(_mm_sub_ps(hi, o4), d4));
                    let ordered = _mm_cmple_ps(t_lo, t_hi);
                    let (near, far) = (select(ordered, t_lo, t_hi), select(ordered, t_hi, t_lo));
                    let axis4 = _mm_castsi128_ps(_mm_set1_epi32(axis as i32));
                    let closer = _mm_cmpgt_ps(near, enter);
                    enter = select(closer, near, enter);
                    enter_axis = select(closer, axis4, enter_axis);
                    let sooner = _mm_cmplt_ps(far, exit);
                    exit = select(sooner, far, exit);
                    exit_axis = select(sooner, axis4, exit_axis);
                }
                let abs = _mm_castsi128_ps(_mm_set1_epi32(0x7fff_ffff));
                let finite = _mm_cmplt_ps(_mm_and_ps(exit, abs), _mm_set1_ps(Real::INFINITY));
                let spans = _mm_andnot_ps(missed, _mm_and_ps(_mm_cmple_ps(enter, exit), finite));
                let enters = _mm_and_ps(spans, in_range(enter));
                let leaves = _mm_andnot_ps(enters, _mm_and_ps(spans, in_range(exit)));
                t_out = select(enters, enter, exit);
                let mut axes = [0u32; LANES];
                _mm_storeu_si128(
                    axes.as_mut_ptr().cast(),
                    _mm_castps_si128(select(enters, enter_axis, exit_axis)),
                );
                hits.axis = axes.map(|a| a as u8);
                let boxes = mask & self.boxes;
                let entered = _mm_movemask_ps(enters) as u32;
                hits.entered = entered & boxes;
                hits.hit = (entered | _mm_movemask_ps(leaves) as u32) & boxes;
            }
            let polygons = mask & self.polygons;
            if polygons != 0 {
                let (o, dir) = (ray.origin, ray.dir);
                let (nx, ny, nz) = (load(&self.normal[0]), load(&self.normal[1]), load(&self.normal[2]));
                // Vec3::dot's order: (x·x + y·y) + z·z.
                let dot = |v: Vec3| {
                    _mm_add_ps(
                        _mm_add_ps(_mm_mul_ps(_mm_set1_ps(v.x), nx), _mm_mul_ps(_mm_set1_ps(v.y), ny)),
                        _mm_mul_ps(_mm_set1_ps(v.z), nz),
                    )
                };
                let denom = dot(dir);
                let t = _mm_div_ps(_mm_sub_ps(load(&self.d), dot(o)), denom);
                let ok = _mm_and_ps(_mm_cmpneq_ps(denom, _mm_setzero_ps()), in_range(t));
                // Ray::at: o + t·d, then the two kept axes of each lane.
                let at = |o: Real, d: Real| _mm_add_ps(_mm_set1_ps(o), _mm_mul_ps(t, _mm_set1_ps(d)));
                let point = [at(o.x, dir.x), at(o.y, dir.y), at(o.z, dir.z)];
                let pick = |which: &[[u32; LANES]; 3]| {
                    let lanes =
                        |axis: usize| _mm_and_ps(point[axis], _mm_loadu_ps(which[axis].as_ptr().cast()));
                    _mm_or_ps(_mm_or_ps(lanes(0), lanes(1)), lanes(2))
                };
                let (px, py) = (pick(&self.pick_u), pick(&self.pick_v));
                let mut inside = _mm_setzero_ps();
                let mut j = POLYGON_CORNERS - 1;
                for i in 0..POLYGON_CORNERS {
                    let (xi, yi, xj, yj) =
                        (load(&self.u[i]), load(&self.v[i]), load(&self.u[j]), load(&self.v[j]));
                    let crosses = _mm_xor_ps(_mm_cmpgt_ps(yi, py), _mm_cmpgt_ps(yj, py));
                    let x = _mm_add_ps(
                        _mm_div_ps(_mm_mul_ps(_mm_sub_ps(xj, xi), _mm_sub_ps(py, yi)), _mm_sub_ps(yj, yi)),
                        xi,
                    );
                    inside = _mm_xor_ps(inside, _mm_and_ps(crosses, _mm_cmplt_ps(px, x)));
                    j = i;
                }
                let hit = _mm_movemask_ps(_mm_and_ps(ok, inside)) as u32 & polygons;
                let is_polygon = _mm_loadu_ps(self.polygon_lanes.as_ptr().cast());
                t_out = select(is_polygon, t, t_out);
                hits.hit |= hit;
            }
            _mm_storeu_ps(hits.t.as_mut_ptr(), t_out);
        }
        hits
    }

    /// The outward normal of the hit in `lane` (one of `hits.hit`), as the
    /// object's own test gives it.
    #[inline(always)]
    pub fn normal(&self, lane: usize, hits: &ObjectHits, ray: &Ray) -> Vec3 {
        if self.polygons & (1 << lane) != 0 {
            return Vec3::new(self.normal[0][lane], self.normal[1][lane], self.normal[2][lane]);
        }
        let axis = hits.axis[lane] as usize;
        let sign = ray.dir[axis].signum();
        let mut normal = Vec3::ZERO;
        normal[axis] = if hits.entered & (1 << lane) != 0 { -sign } else { sign };
        normal
    }
}

/// The object block of `leaf`'s whole objects (its lanes `whole`, not 0),
/// found by the number [`attach`] put in their index, and the lanes of
/// `whole` it tests under `methods` ([`ObjectBlock::lanes`]); `None` where
/// the leaf has none (its whole objects are all tested one by one).
#[inline(always)]
pub(super) fn block_of<'a>(
    blocks: &'a [ObjectBlock],
    leaf: &Leaf,
    whole: u32,
    methods: Methods,
) -> Option<(&'a ObjectBlock, u32)> {
    let block = blocks.get(leaf.index(whole.trailing_zeros() as usize) as usize)?;
    Some((block, block.lanes(methods) & whole))
}

/// The object blocks of `leaves` (whose whole objects are among
/// `objects`), numbered in leaf order: each block with lanes a block can
/// test gets one, and its whole-object lanes' index (unused by whole
/// objects otherwise) is set to that number; other whole-object lanes get
/// `u32::MAX`. Computed again whenever leaves are made or read back, never
/// stored.
pub(super) fn attach(leaves: &mut [Leaf], objects: &[Object]) -> Vec<ObjectBlock> {
    let mut blocks = Vec::new();
    if objects.iter().all(|o| matches!(o.primitive, Primitive::Mesh(_) | Primitive::Plane(_))) {
        return blocks; // Meshes and planes only: no leaf has a whole object.
    }
    for leaf in leaves.iter_mut() {
        let whole = leaf.whole_object_lanes(objects);
        if whole == 0 {
            continue;
        }
        let number = match ObjectBlock::new(leaf, objects) {
            Some(block) => {
                blocks.push(block);
                (blocks.len() - 1) as u32
            }
            None => u32::MAX,
        };
        for lane in lanes_of(whole) {
            leaf.set_index(lane, number);
        }
    }
    blocks
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::hit::PrimitiveHit;
    use proptest::prelude::*;

    fn object(primitive: Primitive) -> Object {
        Object { primitive, material: 0 }
    }

    /// A block of `objects`, as a leaf holding them would get it.
    fn block_of(objects: &[Object]) -> ObjectBlock {
        let mut leaf = Leaf::whole_objects((0..objects.len() as u32).collect::<Vec<_>>().as_slice());
        let mut blocks = attach(std::slice::from_mut(&mut leaf), objects);
        assert_eq!(blocks.len(), 1);
        blocks.remove(0)
    }

    /// What the primitives' own tests give, lane by lane.
    fn scalar(objects: &[Object], ray: &Ray, range: Interval) -> Vec<Option<PrimitiveHit>> {
        objects.iter().map(|o| o.primitive.intersect(ray, range)).collect()
    }

    /// What the block gives, lane by lane, in the same form: by the test
    /// the build uses, which must agree with the lane-by-lane form.
    fn lanes(objects: &[Object], ray: &Ray, range: Interval) -> Vec<Option<PrimitiveHit>> {
        let block = block_of(objects);
        let mask = block.lanes(Methods::default());
        let hits = block.intersect(mask, ray, range);
        let one_by_one = block.intersect_lanes(mask, ray, range);
        assert_eq!(hits.hit, one_by_one.hit, "{ray:?}");
        for lane in lanes_of(hits.hit) {
            assert_eq!(hits.t[lane].to_bits(), one_by_one.t[lane].to_bits(), "{ray:?}");
            assert_eq!(block.normal(lane, &hits, ray), block.normal(lane, &one_by_one, ray), "{ray:?}");
        }
        (0..objects.len())
            .map(|lane| {
                (hits.hit & (1 << lane) != 0).then(|| PrimitiveHit {
                    t: hits.t[lane],
                    primitive: 0,
                    normal: block.normal(lane, &hits, ray),
                })
            })
            .collect()
    }

    fn quad(corners: [[Real; 3]; 4]) -> Object {
        object(Primitive::Polygon(Polygon::new(corners.map(Vec3::from).to_vec()).unwrap()))
    }

    /// Two boxes, a quad and a triangle-shaped polygon, one per lane.
    fn four_objects() -> Vec<Object> {
        vec![
            object(Primitive::Aabb(
                Aabb::new(Vec3::new(1.3, 0.0, 0.65), Vec3::new(2.95, 1.65, 2.3)).unwrap(),
            )),
            quad([[0.0, 0.0, 5.59], [0.0, 5.49, 5.59], [5.56, 5.49, 5.59], [5.56, 0.0, 5.59]]),
            object(Primitive::Aabb(Aabb::new(Vec3::new(2.65, 0.0, 2.95), Vec3::new(4.3, 3.3, 4.6)).unwrap())),
            object(Primitive::Polygon(
                Polygon::new(vec![
                    Vec3::new(0.0, 0.0, 0.0),
                    Vec3::new(0.0, 5.49, 0.0),
                    Vec3::new(0.0, 5.49, 5.59),
                ])
                .unwrap(),
            )),
        ]
    }

    #[test]
    fn blocks_are_made_for_boxes_and_small_polygons_only() {
        let objects = four_objects();
        let block = block_of(&objects);
        assert_eq!((block.boxes, block.polygons), (0b0101, 0b1010));
        assert_eq!(block.lanes(Methods { aabb: BoxMethod::SixPlane, ..Methods::default() }), 0b1010);
        let sphere =
            object(Primitive::Sphere(crate::geometry::sphere::Sphere::new(Vec3::ZERO, 1.0).unwrap()));
        let mut leaf = Leaf::whole_objects(&[0]);
        assert!(attach(std::slice::from_mut(&mut leaf), &[sphere]).is_empty());
        assert_eq!(leaf.index(0), u32::MAX);
    }

    #[test]
    fn rays_through_the_corners_and_edges_give_the_scalar_tests_bits() {
        // Rays from inside the box and from outside aimed exactly at
        // corners, edges and faces: where rounding decides in or out, the
        // lanes must decide as the scalar tests do.
        let objects = four_objects();
        let mut targets = Vec::new();
        for o in &objects {
            let b = o.primitive.bounds().unwrap();
            for corner in 0..8 {
                let pick = |axis: usize| if corner >> axis & 1 == 0 { b.min()[axis] } else { b.max()[axis] };
                targets.push(Vec3::new(pick(0), pick(1), pick(2)));
            }
            targets.push(b.center());
            targets.push(0.5 * (b.min() + Vec3::new(b.max().x, b.min().y, b.max().z)));
        }
        // From outside everything, from inside the room, on a wall, and
        // from inside the first box.
        let origins = [
            Vec3::new(2.78, 2.73, -8.0),
            Vec3::new(2.78, 2.73, 2.0),
            Vec3::new(0.0, 2.0, 1.0),
            Vec3::new(2.0, 1.0, 1.5),
        ];
        let ranges = [Interval::new(0.0, Real::INFINITY), Interval::new(1e-4, 3.0)];
        for origin in origins {
            for &target in &targets {
                for range in ranges {
                    let ray = Ray::new(origin, target - origin);
                    assert_eq!(lanes(&objects, &ray, range), scalar(&objects, &ray, range), "{ray:?}");
                }
            }
        }
    }

    #[test]
    fn axis_parallel_rays_take_the_scalar_tests_zero_direction_branch() {
        let objects = four_objects();
        for origin in [Vec3::new(1.3, 0.5, -1.0), Vec3::new(2.0, 1.65, -1.0), Vec3::new(0.0, 0.0, -1.0)] {
            for dir in [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::Y, -Vec3::Y] {
                let ray = Ray::new(origin, dir);
                let range = Interval::new(0.0, Real::INFINITY);
                assert_eq!(lanes(&objects, &ray, range), scalar(&objects, &ray, range), "{ray:?}");
            }
        }
    }

    proptest! {
        #[test]
        fn any_ray_gets_the_scalar_tests_bits(
            o in prop::array::uniform3(-2.0 as Real..8.0),
            d in prop::array::uniform3(-1.0 as Real..1.0),
            min in 0.0 as Real..1.0,
            len in 0.5 as Real..20.0,
        ) {
            let ray = Ray::new(Vec3::from(o), Vec3::from(d));
            prop_assume!(ray.dir != Vec3::ZERO);
            let objects = four_objects();
            let range = Interval::new(min, min + len);
            prop_assert_eq!(lanes(&objects, &ray, range), scalar(&objects, &ray, range));
        }
    }
}
