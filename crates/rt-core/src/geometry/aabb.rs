//! Axis-aligned boxes: `min ≤ p ≤ max` componentwise; slab-test intersection.

use crate::geometry::geometry_error::GeometryError;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::{BoxTest, Placement, SlabTest};
use crate::geometry::surface::SurfacePoint;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, gamma};

/// A closed axis-aligned box. A side may have zero length (a flat box).
/// Normals point outward, along the axis of the face that was hit.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    min: Vec3,
    max: Vec3,
}

/// Where a ray line enters and leaves a box: parameters and the axis of each face.
#[derive(Clone, Copy, Debug, PartialEq)]
struct SlabSpan {
    enter: Real,
    enter_axis: usize,
    exit: Real,
    exit_axis: usize,
}

impl Aabb {
    /// The box from `min` to `max`; refused if any coordinate is not finite or
    /// any `min` exceeds its `max`.
    pub fn new(min: Vec3, max: Vec3) -> Result<Self, GeometryError> {
        if !min.is_finite() || !max.is_finite() {
            return Err(GeometryError::NotFinite("box min or max"));
        }
        if min.cmpgt(max).any() {
            return Err(GeometryError::BoxInverted);
        }
        Ok(Self { min, max })
    }

    /// The smallest box holding both points, whatever their order.
    pub fn from_corners(a: Vec3, b: Vec3) -> Self {
        Self { min: a.min(b), max: a.max(b) }
    }

    /// The smallest box holding all `points`; `None` if there are none.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Option<Self> {
        points.into_iter().fold(None, |acc: Option<Self>, p| {
            Some(acc.map_or(Self { min: p, max: p }, |b| b.union_point(p)))
        })
    }

    /// The smallest box holding both boxes.
    pub fn union(self, other: Self) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    /// `2·(xy + yz + zx)` of the side lengths: the box's surface area.
    pub fn surface_area(&self) -> Real {
        let s = self.size();
        2.0 * (s.x * s.y + s.y * s.z + s.z * s.x)
    }

    /// This box grown to hold `p`.
    pub fn union_point(self, p: Vec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Lower corner.
    pub fn min(&self) -> Vec3 {
        self.min
    }
    /// Upper corner.
    pub fn max(&self) -> Vec3 {
        self.max
    }
    /// `(min + max) / 2`.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }
    /// `(max − min) / 2`: half the side lengths.
    pub fn half_extents(&self) -> Vec3 {
        0.5 * (self.max - self.min)
    }
    /// `max − min`: the side lengths.
    pub fn size(&self) -> Vec3 {
        self.max - self.min
    }
    /// Whether `min ≤ p ≤ max` componentwise (the boundary is inside).
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// `p` (a hit on the face whose outward normal is `normal`) with its
    /// coordinate across that face set to the face's exactly: the error
    /// across the face is then zero, and along it `γ₂|p|` (from `o + t·d`).
    pub fn surface_point(&self, p: Vec3, normal: Vec3) -> SurfacePoint {
        let axis = normal.abs().max_position();
        let mut snapped = p;
        snapped[axis] = if normal[axis] > 0.0 { self.max[axis] } else { self.min[axis] };
        let mut error = gamma(2) * p.abs();
        error[axis] = 0.0;
        SurfacePoint { p: snapped, error, normal }
    }

    /// The nearest face hit with `t` in `range`: the entry face from outside,
    /// the exit face from inside.
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let span = self.slab_span(ray)?;
        let (t, axis, outward_sign) = if range.contains(span.enter) {
            // Entering through the face the ray meets head-on: normal against the ray.
            (span.enter, span.enter_axis, -ray.dir[span.enter_axis].signum())
        } else if range.contains(span.exit) {
            (span.exit, span.exit_axis, ray.dir[span.exit_axis].signum())
        } else {
            return None;
        };
        let mut normal = Vec3::ZERO;
        normal[axis] = outward_sign;
        Some(PrimitiveHit { t, primitive: 0, normal })
    }

    /// The course's six-plane test: for each face, `t = (face − oᵢ) / dᵢ`
    /// on its axis `i`, then the point `o + t·d` counts if its other two
    /// coordinates lie within the box's bounds; the nearest such `t` in
    /// `range` wins, with the face's outward normal.
    ///
    /// It breaks where the slab test ([`Aabb::intersect`]) does not: a ray
    /// aimed at an edge or corner computes a point that rounding may put just
    /// outside both faces' bounds (a leak), and for `dᵢ = ±0` with the origin
    /// on that face `0/0` gives NaN, which it must (and does) skip.
    pub fn intersect_six_plane(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let mut best: Option<PrimitiveHit> = None;
        for axis in 0..3 {
            for (face, outward) in [(self.min[axis], -1.0), (self.max[axis], 1.0)] {
                let t = (face - ray.origin[axis]) / ray.dir[axis];
                if !range.contains(t) || best.is_some_and(|b| b.t <= t) {
                    continue;
                }
                let p = ray.at(t);
                let inside = (1..3).all(|k| {
                    let other = (axis + k) % 3;
                    self.min[other] <= p[other] && p[other] <= self.max[other]
                });
                if inside {
                    let mut normal = Vec3::ZERO;
                    normal[axis] = outward;
                    best = Some(PrimitiveHit { t, primitive: 0, normal });
                }
            }
        }
        best
    }

    /// Whether the ray's segment `range` overlaps the box at all (used to skip
    /// whole meshes).
    pub fn overlaps(&self, ray: &Ray, range: Interval) -> bool {
        self.slab_span(ray).is_some_and(|s| s.enter <= range.max && s.exit >= range.min)
    }

    /// The slab test (Kay & Kajiya 1986): on each axis the ray line is between
    /// the two face planes for `t` in `[(min−o)/d, (max−o)/d]` (ordered); the
    /// box is the intersection of the three intervals.
    ///
    /// An axis with `d = ±0` is handled on its own: the ray is inside that slab
    /// for all `t` when `min ≤ o ≤ max` and never otherwise, so no `0·∞` NaN
    /// can arise. A ray running along a face is inside (the box is closed).
    fn slab_span(&self, ray: &Ray) -> Option<SlabSpan> {
        let mut span =
            SlabSpan { enter: Real::NEG_INFINITY, enter_axis: 0, exit: Real::INFINITY, exit_axis: 0 };
        for axis in 0..3 {
            let (o, d) = (ray.origin[axis], ray.dir[axis]);
            let (lo, hi) = (self.min[axis], self.max[axis]);
            if d == 0.0 {
                if o < lo || o > hi {
                    return None;
                }
                continue;
            }
            let (t_lo, t_hi) = ((lo - o) / d, (hi - o) / d);
            let (near, far) = if t_lo <= t_hi { (t_lo, t_hi) } else { (t_hi, t_lo) };
            if near > span.enter {
                span.enter = near;
                span.enter_axis = axis;
            }
            if far < span.exit {
                span.exit = far;
                span.exit_axis = axis;
            }
        }
        (span.enter <= span.exit && span.exit.is_finite()).then_some(span)
    }
}

impl Aabb {
    /// The course's slab test for `ray`, which hit this box at `t`
    /// ([`BoxTest`]): each axis's parameters `(min − o)/d` and `(max − o)/d`,
    /// the entry and exit of the box from [`Aabb::intersect`]'s own slab span
    /// (the largest entry, the smallest exit, Kay and Kajiya 1986), and the
    /// face hit: the entry face when `t` is the entry (from outside), else
    /// the exit face (from inside).
    pub fn explain(&self, ray: &Ray, t: Real) -> BoxTest {
        let slabs = [0, 1, 2].map(|axis| {
            let (o, d) = (ray.origin[axis], ray.dir[axis]);
            let (t_min_plane, t_max_plane) = ((self.min[axis] - o) / d, (self.max[axis] - o) / d);
            SlabTest {
                axis,
                t_min_plane,
                t_max_plane,
                t_enter: t_min_plane.min(t_max_plane),
                t_exit: t_min_plane.max(t_max_plane),
            }
        });
        let span = self.slab_span(ray);
        let (t_enter, t_exit) = span.as_ref().map_or((Real::NAN, Real::NAN), |s| (s.enter, s.exit));
        let entered = span.as_ref().is_some_and(|s| s.enter == t);
        let face_axis = span.as_ref().map_or(0, |s| if entered { s.enter_axis } else { s.exit_axis });
        let along = ray.dir[face_axis];
        BoxTest {
            min: self.min,
            max: self.max,
            slabs,
            t_enter,
            t_exit,
            origin: if self.contains(ray.origin) { Placement::Inside } else { Placement::Outside },
            face_axis,
            // Entering, the face is the one the ray meets head-on: at max
            // when it travels towards −axis; leaving, the one it runs into.
            face_max: if entered { along < 0.0 } else { along > 0.0 },
            entered,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    fn unit_box() -> Aabb {
        Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0)).unwrap()
    }

    fn hit(o: Vec3, d: Vec3) -> Option<(Real, Vec3)> {
        unit_box().intersect(&Ray::new(o, d), ALL).map(|h| (h.t, h.normal))
    }

    #[test]
    fn ray_from_the_front_enters_through_the_front_face() {
        // From z = −5 along +z: enters at z = −1 (t = 4), normal −z.
        assert_eq!(hit(Vec3::new(0.2, 0.3, -5.0), Vec3::Z), Some((4.0, -Vec3::Z)));
    }

    #[test]
    fn oblique_ray_enters_through_the_face_it_meets_last() {
        // From (−3,0.5,−2) along (1,0,0.5): x-slab t ∈ [2,4], z-slab t ∈ [2,6]; y always in.
        // Enter at t = 2 on the x face (ties keep the first axis), normal −x.
        assert_eq!(hit(Vec3::new(-3.0, 0.5, -2.0), Vec3::new(1.0, 0.0, 0.5)), Some((2.0, -Vec3::X)));
        // From (−3,0.5,−4) along (1,0,1): x ∈ [2,4], z ∈ [3,5]: enters at t = 3 through −z.
        assert_eq!(hit(Vec3::new(-3.0, 0.5, -4.0), Vec3::new(1.0, 0.0, 1.0)), Some((3.0, -Vec3::Z)));
    }

    #[test]
    fn ray_from_inside_leaves_through_a_face_with_the_outward_normal() {
        assert_eq!(hit(Vec3::ZERO, -Vec3::Y), Some((1.0, -Vec3::Y)));
        assert_eq!(hit(Vec3::new(0.5, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0)), Some((0.25, Vec3::X)));
    }

    #[test]
    fn rays_missing_or_pointing_away_miss() {
        assert_eq!(hit(Vec3::new(0.0, 0.0, -5.0), -Vec3::Z), None);
        assert_eq!(hit(Vec3::new(2.0, 0.0, -5.0), Vec3::Z), None);
        // Passes the corner region: x-slab t ∈ [1,3], y-slab t ∈ [3.5,5.5] don't overlap.
        assert_eq!(hit(Vec3::new(-2.0, -4.5, 0.0), Vec3::new(1.0, 1.0, 0.0)), None);
    }

    #[test]
    fn zero_direction_components_of_either_sign_never_make_nan() {
        for d in [Vec3::new(0.0, 0.0, 1.0), Vec3::new(-0.0, -0.0, 1.0)] {
            // Inside the x and y slabs: hit; outside the x slab: miss; on the x face plane: hit.
            assert_eq!(hit(Vec3::new(0.0, 0.0, -3.0), d), Some((2.0, -Vec3::Z)));
            assert_eq!(hit(Vec3::new(1.5, 0.0, -3.0), d), None);
            assert_eq!(hit(Vec3::new(1.0, 0.0, -3.0), d), Some((2.0, -Vec3::Z)));
            assert_eq!(hit(Vec3::new(-1.0, 1.0, -3.0), d), Some((2.0, -Vec3::Z)));
        }
    }

    #[test]
    fn center_and_extents_follow_from_min_and_max() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 2.0)).unwrap();
        assert_eq!(b.center(), Vec3::new(1.0, 0.5, 2.0));
        assert_eq!(b.half_extents(), Vec3::new(2.0, 0.5, 0.0));
        assert_eq!(b.size(), Vec3::new(4.0, 1.0, 0.0));
        assert!(b.contains(Vec3::new(3.0, 1.0, 2.0)) && !b.contains(Vec3::new(3.1, 1.0, 2.0)));
    }

    #[test]
    fn inverted_boxes_are_refused() {
        assert_eq!(Aabb::new(Vec3::ONE, Vec3::ZERO), Err(GeometryError::BoxInverted));
    }

    #[test]
    fn flat_box_is_hit_on_its_face() {
        let b = Aabb::new(Vec3::new(-1.0, -1.0, 2.0), Vec3::new(1.0, 1.0, 2.0)).unwrap();
        let h = b.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), ALL).unwrap();
        assert_eq!((h.t, h.normal), (2.0, -Vec3::Z));
    }

    #[test]
    fn a_segment_overlaps_the_box_only_where_it_passes_through_it() {
        // The unit box from (0, 0, −5) along +z: inside for t in [4, 6].
        let b = unit_box();
        let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!(b.overlaps(&ray, ALL));
        assert!(b.overlaps(&ray, Interval::new(0.0, 4.0)) && b.overlaps(&ray, Interval::new(6.0, 9.0)));
        assert!(!b.overlaps(&ray, Interval::new(0.0, 3.9)), "segment ends before the box");
        assert!(!b.overlaps(&ray, Interval::new(6.1, 9.0)), "segment starts past the box");
        assert!(!b.overlaps(&Ray::new(Vec3::new(1.5, 0.0, -5.0), Vec3::Z), ALL), "passes beside");
        assert!(!b.overlaps(&Ray::new(Vec3::new(0.0, 0.0, -5.0), -Vec3::Z), ALL), "points away");
    }

    #[test]
    fn the_six_plane_test_finds_the_slab_tests_face_t_and_normal() {
        // Rays from outside aimed at random points of a box's faces (well
        // inside them, so rounding cannot decide), and from inside: both
        // methods hit the same face at the same t with the same normal.
        let b = Aabb::new(Vec3::new(-1.0, 0.5, 2.0), Vec3::new(2.0, 1.5, 4.0)).unwrap();
        for k in 0..600u32 {
            let rng = &mut crate::sampling::sampler::SampleRng::new(k, 3, 9);
            let (u, v) = rng.next_pair();
            let (w, side) = rng.next_pair();
            let target = b.min() + b.size() * Vec3::new(0.1 + 0.8 * u, 0.1 + 0.8 * v, 0.1 + 0.8 * w);
            let origin = if k % 3 == 0 {
                b.center() + Vec3::new(u - 0.5, v - 0.5, w - 0.5) * 0.5
            } else {
                b.center() + Vec3::new(u - 0.5, side - 0.5, v - 0.5).normalize() * 10.0
            };
            let ray = Ray::new(origin, target - origin);
            let (slab, six) = (b.intersect(&ray, ALL).unwrap(), b.intersect_six_plane(&ray, ALL).unwrap());
            assert_eq!(slab.normal, six.normal, "ray {k}");
            assert!(
                (slab.t - six.t).abs() <= 4.0 * Real::EPSILON * slab.t,
                "ray {k}: {} vs {}",
                slab.t,
                six.t
            );
        }
    }

    #[test]
    fn surface_points_are_on_their_face_exactly_and_offsets_leave_it() {
        // Hits far from the origin: the coordinate across the hit face is the
        // face's own, with zero error, so a ray spawned to either side starts
        // strictly on that side (one float off the face).
        let b = Aabb::new(Vec3::new(95.0, -60.0, 20.0), Vec3::new(130.0, -40.0, 33.0)).unwrap();
        for k in 0..600u32 {
            let rng = &mut crate::sampling::sampler::SampleRng::new(k, 4, 1);
            let (u, v) = rng.next_pair();
            let (w, s) = rng.next_pair();
            let origin = b.center() + Vec3::new(u - 0.5, v - 0.5, w - 0.5).normalize() * (50.0 + 100.0 * s);
            let ray = Ray::new(origin, b.center() + (Vec3::new(v, w, u) - 0.5) * 10.0 - origin);
            let Some(hit) = b.intersect(&ray, ALL) else { continue };
            let sp = b.surface_point(ray.at(hit.t), hit.normal);
            let axis = hit.normal.abs().max_position();
            let face = if hit.normal[axis] > 0.0 { b.max()[axis] } else { b.min()[axis] };
            assert_eq!((sp.p[axis], sp.error[axis]), (face, 0.0), "ray {k}");
            let (out, back) = (sp.spawn_origin(hit.normal), sp.spawn_origin(-hit.normal));
            assert!(
                (out[axis] - face) * hit.normal[axis] > 0.0 && (back[axis] - face) * hit.normal[axis] < 0.0,
                "ray {k}"
            );
        }
    }

    proptest::proptest! {
        /// Random rays against a random box: every hit lies on the box's
        /// surface with a unit axis normal pointing out of the face it is on,
        /// and agrees with a brute-force check of the six face rectangles.
        #[test]
        fn box_hits_lie_on_a_face_and_match_the_six_face_planes(
            lo in proptest::array::uniform3(-10f32..10.0),
            size in proptest::array::uniform3(0.0f32..5.0),
            o in proptest::array::uniform3(-20f32..20.0),
            d in proptest::array::uniform3(-1f32..1.0),
            zero_axis in 0usize..4,
        ) {
            let min = Vec3::new(lo[0] as Real, lo[1] as Real, lo[2] as Real);
            let max = min + Vec3::new(size[0] as Real, size[1] as Real, size[2] as Real);
            let b = Aabb::new(min, max).unwrap();
            let mut dir = Vec3::new(d[0] as Real, d[1] as Real, d[2] as Real);
            if zero_axis < 3 {
                dir[zero_axis] = 0.0;
            }
            proptest::prop_assume!(dir.length() > 1e-3);
            let ray = Ray::new(Vec3::new(o[0] as Real, o[1] as Real, o[2] as Real), dir);
            let hit = b.intersect(&ray, ALL);
            // Brute force: each face is a plane hit clipped to the other two axes' bounds.
            let mut nearest: Option<Real> = None;
            for axis in 0..3 {
                if dir[axis] == 0.0 { continue; }
                for face in [min[axis], max[axis]] {
                    let t = (face - ray.origin[axis]) / dir[axis];
                    let p = ray.at(t);
                    let inside = (0..3).filter(|&a| a != axis).all(|a| p[a] >= min[a] - 1e-4 && p[a] <= max[a] + 1e-4);
                    if t > 0.0 && inside && nearest.is_none_or(|n| t < n) {
                        nearest = Some(t);
                    }
                }
            }
            match (hit, nearest) {
                (Some(h), Some(t)) => {
                    proptest::prop_assert!((h.t - t).abs() <= 1e-3 * (1.0 + t.abs()), "{} vs {}", h.t, t);
                    let axis = h.normal.abs().max_position();
                    proptest::prop_assert_eq!(h.normal.abs().element_sum(), 1.0);
                    let p = ray.at(h.t);
                    let face = if h.normal[axis] > 0.0 { max[axis] } else { min[axis] };
                    proptest::prop_assert!((p[axis] - face).abs() <= 1e-3 * (1.0 + face.abs()));
                }
                (None, None) => {}
                // Grazing an edge within the brute force's 1e-4 slack may disagree.
                (h, n) => {
                    let t = h.map(|h| h.t).or(n).unwrap();
                    let p = ray.at(t);
                    let slack = (0..3).filter(|&a| (p[a] - min[a]).abs() < 1e-3 || (p[a] - max[a]).abs() < 1e-3).count();
                    proptest::prop_assert!(slack >= 2, "disagreement away from an edge: {:?} vs {:?}", h, n);
                }
            }
        }
    }
}
