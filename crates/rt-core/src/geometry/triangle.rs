//! Triangles: barycentric coordinates and three ray/triangle tests: the
//! watertight one (the default), Möller–Trumbore, and the course's area ratios.

use crate::geometry::aabb::Aabb;
use crate::geometry::geometry_error::GeometryError;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::TriangleTest;
use crate::geometry::method::TriangleMethod;
use crate::geometry::surface::{SurfacePoint, project_onto_plane};
use crate::math::ray::{Interval, Ray};
use crate::math::real::{
    AREA_RATIO_EPSILON, Real, Vec3, difference_of_products, divide, gamma, normalize_robust,
};

/// A hit on a triangle: the ray parameter and the barycentric weights of its
/// corners `(a, b, c)`, which sum to 1; the hit point is `w_a·a + w_b·b + w_c·c`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter, for the ray's own direction.
    pub t: Real,
    /// Weights of corners a, b, c.
    pub barycentric: [Real; 3],
}

/// A triangle with corners a, b, c. Its normal is `normalize((b−a)×(c−a))`:
/// with the usual cross product in a left-handed world, corners that appear
/// clockwise to a viewer have the normal pointing towards the viewer.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Triangle {
    corners: [Vec3; 3],
    normal: Vec3,
}

impl Triangle {
    /// A triangle; refused if a corner is not finite or its area is zero (or
    /// too small for its normal to be computed).
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Result<Self, GeometryError> {
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            return Err(GeometryError::NotFinite("triangle corner"));
        }
        let normal = geometric_normal(a, b, c).ok_or(GeometryError::TriangleDegenerate)?;
        Ok(Self { corners: [a, b, c], normal })
    }

    /// The corners a, b, c.
    pub fn corners(&self) -> [Vec3; 3] {
        self.corners
    }
    /// `normalize((b−a)×(c−a))`.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }
    /// The box around the corners.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.corners).expect("three corners")
    }

    /// Barycentric weights `(w_a, w_b, w_c)` of `p` by area ratios (the course's
    /// test): with `n = (b−a)×(c−a)`,
    /// `w_a = ((c−b)×(p−b))·n / n·n`, `w_b = ((a−c)×(p−c))·n / n·n`, `w_c = 1 − w_a − w_b`.
    /// `p` is projected onto the triangle's plane along the normal; it lies
    /// inside exactly when all three weights are ≥ 0.
    pub fn barycentric(&self, p: Vec3) -> [Real; 3] {
        let [a, b, c] = self.corners;
        let n = (b - a).cross(c - a);
        let nn = n.dot(n);
        let wa = (c - b).cross(p - b).dot(n) / nn;
        let wb = (a - c).cross(p - c).dot(n) / nn;
        [wa, wb, 1.0 - wa - wb]
    }

    /// `p` (a computed hit) projected onto the triangle's plane, with its
    /// error bound: see [`triangle_surface_point`].
    pub fn surface_point(&self, p: Vec3) -> SurfacePoint {
        triangle_surface_point(self.corners, self.normal, p)
    }

    /// The hit with `t` in `range`, from either side (watertight test).
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        self.intersect_with(ray, range, TriangleMethod::Watertight)
    }

    /// The hit with `t` in `range` by the chosen `method`.
    pub fn intersect_with(&self, ray: &Ray, range: Interval, method: TriangleMethod) -> Option<PrimitiveHit> {
        let [a, b, c] = self.corners;
        let hit = intersect_by(method, a, b, c, &TriangleRay::new(ray), range)?;
        Some(PrimitiveHit { t: hit.t, primitive: 0, normal: self.normal })
    }

    /// The hit with its barycentric weights.
    pub fn intersect_barycentric(&self, ray: &Ray, range: Interval) -> Option<TriangleHit> {
        let [a, b, c] = self.corners;
        intersect_watertight(a, b, c, ray, range)
    }
}

/// `p` projected onto the plane of the triangle `corners` with unit normal
/// `normal` ([`project_onto_plane`]). The plane itself is uncertain: the
/// computed normal is off the exact one by an angle of about
/// `γ₈·|e₁|·|e₂|/|e₁ × e₂|` (e₁ = b − a, e₂ = c − a: the cross product's
/// rounding, relative to |e₁|·|e₂|, over its length, which is
/// `|e₁|·|e₂|·sin α` for the corner angle α; γ₈ for a well-shaped
/// triangle, far more for a sliver), which at `p` is that angle times
/// `|p − a|`, and `d = n·a` by `γ₃(|a|·|n|)`; both are added to the bound
/// along the normal.
pub fn triangle_surface_point(corners: [Vec3; 3], normal: Vec3, p: Vec3) -> SurfacePoint {
    let [a, b, c] = corners;
    let (e1, e2) = (b - a, c - a);
    let reach = (p - a).abs().max_element().max(e1.abs().max_element()).max(e2.abs().max_element());
    // The angle: 1/sin α from the edges scaled to their largest component
    // (as `geometric_normal` does, so nothing overflows or underflows), at
    // most 1 radian (a triangle degenerate but for rounding has no
    // direction to speak of; `min` also takes 1 for a NaN or an infinity).
    let m = e1.abs().max_element().max(e2.abs().max_element());
    let (f1, f2) = (e1 / m, e2 / m);
    let angle = (gamma(8) * f1.length() * f2.length() / f1.cross(f2).length()).min(1.0);
    let plane_error = angle * 3.0 * reach + gamma(3) * a.abs().dot(normal.abs());
    let (p, error) = project_onto_plane(p, normal, normal.dot(a), plane_error);
    SurfacePoint { p, error, normal }
}

/// `normalize((b−a)×(c−a))`, or `None` for a zero-area triangle. The edges
/// are divided by their largest component first, so the cross product neither
/// overflows for huge triangles nor underflows for tiny ones.
pub fn geometric_normal(a: Vec3, b: Vec3, c: Vec3) -> Option<Vec3> {
    let (e1, e2) = (b - a, c - a);
    let m = e1.abs().max_element().max(e2.abs().max_element());
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    normalize_robust((e1 / m).cross(e2 / m))
}

/// Watertight ray/triangle intersection: Woop, Benthin and Wald, "Watertight
/// Ray/Triangle Intersection", *JCGT* 2(1), 2013, as in pbrt-v4
/// (`IntersectTriangle`, *PBR* 4th ed. §6.5.3).
///
/// The corners are moved to the ray's frame (origin at the ray origin, the
/// direction's largest axis as z, sheared so the ray is the +z axis); the
/// ray hits where the three 2D edge functions have one sign. Each edge
/// function depends only on its edge's two corners, with a sign-exact product
/// difference ([`difference_of_products`]), so a ray through an edge shared by
/// two triangles hits at least one of them: no leaks through meshes.
/// A zero-area triangle gives `det = 0` and is never hit. A ray with a zero
/// direction must not be passed (the scene filters those).
///
/// The sign tests give `t > 0`; callers keep hits near the origin out with
/// `range.min > 0`. pbrt's extra test `t > δt`, with its conservative bound
/// δt on the rounding error of t, is deliberately left out: δt grows like
/// distance² / triangle size, so it rejected every hit on triangles more than
/// about 10⁵ of their own sizes away (1 mm at 300 m), which made holes in
/// distant meshes.
pub fn intersect_watertight(a: Vec3, b: Vec3, c: Vec3, ray: &Ray, range: Interval) -> Option<TriangleHit> {
    intersect_watertight_prepared(a, b, c, &TriangleRay::new(ray), range)
}

/// A ray prepared for many triangle tests: the ray, and what the watertight
/// test derives from the ray alone: the axis order `(kx, ky, kz)` that makes
/// the direction's largest component z, and the shear `(sx, sy, sz) =
/// (−d_kx/d_kz, −d_ky/d_kz, 1/d_kz)` that maps the direction onto +z.
/// Preparing these once per ray rather than once per triangle saves three
/// divisions a test and changes no result.
#[derive(Clone, Copy, Debug)]
pub struct TriangleRay {
    /// The ray itself.
    pub ray: Ray,
    axes: [usize; 3],
    shear: Vec3,
}

impl TriangleRay {
    /// Prepares `ray`, choosing its axis order without branches: for
    /// incoherent rays the major axis changes from ray to ray, and a branch
    /// on it would often be mispredicted. The first largest `|d|` is `kz`
    /// (`Vec3::max_position`'s choice), and the components are read in the
    /// order `(kx, ky, kz)` from the direction written out twice.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let m = ray.dir.abs();
        let largest = if m.y > m.x { m.y } else { m.x };
        let kz = if m.z > largest { 2 } else { usize::from(m.y > m.x) };
        let kx = (kz + 1) % 3;
        let twice = [ray.dir.x, ray.dir.y, ray.dir.z, ray.dir.x, ray.dir.y];
        Self::with_axes(ray, kz, Vec3::new(twice[kx], twice[kx + 1], twice[kx + 2]))
    }

    /// [`TriangleRay::new`] choosing the axis order by branches, the same
    /// preparation bit for bit: for a packet of coherent rays, which share
    /// their major axis, the branches are predicted and cost less than the
    /// round trip through memory.
    #[inline(always)]
    pub(crate) fn new_coherent(ray: &Ray) -> Self {
        let kz = ray.dir.abs().max_position();
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        Self::with_axes(ray, kz, Vec3::new(ray.dir[kx], ray.dir[ky], ray.dir[kz]))
    }

    /// The preparation of `ray` whose major axis is `kz`, its direction's
    /// components `d` in the order `(kx, ky, kz)`.
    #[inline(always)]
    fn with_axes(ray: &Ray, kz: usize, d: Vec3) -> Self {
        let kx = (kz + 1) % 3;
        let ky = (kx + 1) % 3;
        // The three quotients in one (SIMD) division: each lane is the
        // correctly rounded quotient, as three scalar divisions give.
        let shear = divide(Vec3::new(-d.x, -d.y, 1.0), Vec3::splat(d.z));
        Self { ray: *ray, axes: [kx, ky, kz], shear }
    }

    /// `ray` carried without the preparation, for a query that tests no
    /// triangle (a tree without mesh triangles): the axis order and the
    /// shear, which only a triangle test reads, are left as placeholders
    /// (NaN shear), so that the query does not pay for the major axis and
    /// its division.
    #[inline(always)]
    pub(crate) fn unprepared(ray: &Ray) -> Self {
        Self { ray: *ray, axes: [0, 1, 2], shear: Vec3::NAN }
    }

    /// The axis order `(kx, ky, kz)`.
    #[cfg_attr(any(feature = "f64", not(target_arch = "x86_64")), allow(dead_code))]
    pub(crate) fn axes(&self) -> [usize; 3] {
        self.axes
    }

    /// The shear `(sx, sy, sz)`.
    #[cfg_attr(any(feature = "f64", not(target_arch = "x86_64")), allow(dead_code))]
    pub(crate) fn shear(&self) -> Vec3 {
        self.shear
    }
}

/// [`intersect_watertight`] on a prepared ray.
#[inline]
pub fn intersect_watertight_prepared(
    a: Vec3,
    b: Vec3,
    c: Vec3,
    ray: &TriangleRay,
    range: Interval,
) -> Option<TriangleHit> {
    let [kx, ky, kz] = ray.axes;
    let (sx, sy, sz) = ray.shear.into();
    let shear = |p: Vec3| {
        let p = p - ray.ray.origin;
        let p = Vec3::new(p[kx], p[ky], p[kz]);
        Vec3::new(p.x + sx * p.z, p.y + sy * p.z, p.z)
    };
    let (p0, p1, p2) = (shear(a), shear(b), shear(c));

    let [e0, e1, e2] = edge_functions(p0, p1, p2);
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }

    let (z0, z1, z2) = (p0.z * sz, p1.z * sz, p2.z * sz);
    let t_scaled = e0 * z0 + e1 * z1 + e2 * z2;
    // Compare t = t_scaled/det with the range without dividing.
    if det < 0.0 && (t_scaled >= 0.0 || t_scaled < range.max * det) {
        return None;
    }
    if det > 0.0 && (t_scaled <= 0.0 || t_scaled > range.max * det) {
        return None;
    }
    let inv_det = 1.0 / det;
    let t = t_scaled * inv_det;
    if !range.contains(t) {
        return None;
    }
    Some(TriangleHit { t, barycentric: [e0 * inv_det, e1 * inv_det, e2 * inv_det] })
}

/// The three edge functions of the watertight test for the sheared corners
/// `p0, p1, p2`: `e₀ = x₁y₂ − y₁x₂`, `e₁ = x₂y₀ − y₂x₀`, `e₂ = x₀y₁ − y₀x₁`,
/// each with its exact sign (pbrt-v4's `IntersectTriangle`).
///
/// With `f32` geometry they are first computed as plain `f32` products and a
/// difference. Rounding is monotone, so when `x₁y₂ > y₁x₂` exactly, the
/// rounded products keep that order and their rounded difference is ≥ 0:
/// the sign is right or the result is 0 (a difference of two distinct floats
/// is never rounded to 0 under gradual underflow). Only when an edge
/// function is 0, or not finite (products past `f32::MAX`), are all three
/// recomputed with [`difference_of_products`], whose sign is exact. Edge
/// functions of a shared edge, computed from its two corners in either
/// order, are exact negatives of each other either way, so the test stays
/// watertight. The SIMD tests of four and eight triangles (`bvh::leaf`)
/// do the same operations lane by lane, so all give the same bits. With
/// `f64` geometry every edge function is a [`difference_of_products`].
#[inline(always)]
pub fn edge_functions(p0: Vec3, p1: Vec3, p2: Vec3) -> [Real; 3] {
    #[cfg(not(feature = "f64"))]
    {
        let e = [p1.x * p2.y - p1.y * p2.x, p2.x * p0.y - p2.y * p0.x, p0.x * p1.y - p0.y * p1.x];
        if e.iter().all(|e| *e != 0.0 && e.is_finite()) {
            return e;
        }
    }
    [
        difference_of_products(p1.x, p2.y, p1.y, p2.x),
        difference_of_products(p2.x, p0.y, p2.y, p0.x),
        difference_of_products(p0.x, p1.y, p0.y, p1.x),
    ]
}

/// The ray/triangle test `method` on corners `a, b, c`.
#[inline]
pub fn intersect_by(
    method: TriangleMethod,
    a: Vec3,
    b: Vec3,
    c: Vec3,
    ray: &TriangleRay,
    range: Interval,
) -> Option<TriangleHit> {
    match method {
        TriangleMethod::Watertight => intersect_watertight_prepared(a, b, c, ray, range),
        TriangleMethod::MollerTrumbore => intersect_moller_trumbore(a, b, c, &ray.ray, range),
        TriangleMethod::AreaRatio => intersect_area_ratio(a, b, c, &ray.ray, range),
    }
}

/// Möller and Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection",
/// *JGT* 2(1), 1997. With `e₁ = b − a`, `e₂ = c − a`, `s = o − a`,
/// `p = d × e₂`, `q = s × e₁` and `det = e₁·p`: `u = s·p/det`,
/// `v = d·q/det`, `t = e₂·q/det`; a hit when `u ≥ 0`, `v ≥ 0`, `u + v ≤ 1`.
///
/// Only `det = 0` is rejected (the paper's `|det| < 10⁻⁶` would also reject
/// small or distant triangles). Each triangle computes its own `u` and `v`
/// from its own edge vectors, so the two triangles sharing an edge round
/// differently there: a ray through the edge can miss both (a leak).
pub fn intersect_moller_trumbore(
    a: Vec3,
    b: Vec3,
    c: Vec3,
    ray: &Ray,
    range: Interval,
) -> Option<TriangleHit> {
    let (e1, e2) = (b - a, c - a);
    let p = ray.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = ray.origin - a;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = ray.dir.dot(q) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    range.contains(t).then_some(TriangleHit { t, barycentric: [1.0 - u - v, u, v] })
}

/// The course's test: intersect the triangle's plane `n·p = n·a` (with
/// `n = (b−a)×(c−a)`) at `t = n·(a − o) / n·d`, form `p = o + t·d`, and take
/// the unsigned area ratios `w_a = |(b−p)×(c−p)| / |n|` (and cyclically); `p`
/// is inside when `w_a + w_b + w_c ≤ 1 + ε` ([`AREA_RATIO_EPSILON`]).
///
/// Its accuracy is that of `p`, whose rounding error grows with the distance
/// travelled and the coordinates' magnitude, and of the cross products of
/// vectors from `p`, which cancel when `p` lies near a corner.
pub fn intersect_area_ratio(a: Vec3, b: Vec3, c: Vec3, ray: &Ray, range: Interval) -> Option<TriangleHit> {
    let n = (b - a).cross(c - a);
    let denom = n.dot(ray.dir);
    if denom == 0.0 {
        return None;
    }
    let t = n.dot(a - ray.origin) / denom;
    if !range.contains(t) {
        return None;
    }
    let p = ray.at(t);
    let area = n.length();
    let wa = (b - p).cross(c - p).length() / area;
    let wb = (c - p).cross(a - p).length() / area;
    let wc = (a - p).cross(b - p).length() / area;
    (wa + wb + wc <= 1.0 + AREA_RATIO_EPSILON).then_some(TriangleHit { t, barycentric: [wa, wb, wc] })
}

impl Triangle {
    /// The course's numbers for the point `p` a ray hit ([`TriangleTest`]):
    /// the signed barycentric weights of [`Triangle::barycentric`], and the
    /// unsigned area ratios `|(b−p)×(c−p)|/|n|`, `|(c−p)×(a−p)|/|n|`,
    /// `|(a−p)×(b−p)|/|n|` of [`intersect_area_ratio`] with its test: the
    /// sum is 1 inside, so `1 − ε ≤ sum ≤ 1 + ε` ([`AREA_RATIO_EPSILON`]).
    pub fn explain(&self, p: Vec3) -> TriangleTest {
        let [a, b, c] = self.corners;
        let area = (b - a).cross(c - a).length();
        let area_ratios = [
            (b - p).cross(c - p).length() / area,
            (c - p).cross(a - p).length() / area,
            (a - p).cross(b - p).length() / area,
        ];
        let area_ratio_sum = area_ratios[0] + area_ratios[1] + area_ratios[2];
        TriangleTest {
            corners: self.corners,
            normal: self.normal,
            barycentric: self.barycentric(p),
            area_ratios,
            area_ratio_sum,
            epsilon: AREA_RATIO_EPSILON,
            inside: (1.0 - AREA_RATIO_EPSILON..=1.0 + AREA_RATIO_EPSILON).contains(&area_ratio_sum),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    /// The triangle (0,0,2), (0,1,2), (1,0,2) in the plane z = 2.
    /// n = (b−a)×(c−a) = (0,1,0)×(1,0,0) = (1·0 − 0·0, 0·1 − 0·0, 0·0 − 1·1) = (0,0,−1).
    fn tri() -> Triangle {
        Triangle::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 0.0, 2.0)).unwrap()
    }

    /// Both preparations of `dir`'s ray as comparable bits.
    fn preparations(dir: Vec3) -> [([usize; 3], [u64; 3]); 2] {
        let ray = Ray::new(Vec3::ZERO, dir);
        #[allow(clippy::useless_conversion)] // to_bits gives u32 for f32 geometry
        let bits = |p: TriangleRay| (p.axes, p.shear.to_array().map(|v| u64::from(v.to_bits())));
        [bits(TriangleRay::new(&ray)), bits(TriangleRay::new_coherent(&ray))]
    }

    #[test]
    fn both_preparations_pick_the_first_largest_axis_on_ties() {
        for (dir, kz) in [
            (Vec3::new(1.0, 1.0, 1.0), 0),
            (Vec3::new(-1.0, 1.0, 0.5), 0),
            (Vec3::new(0.5, -1.0, 1.0), 1),
            (Vec3::new(0.0, 0.0, -2.0), 2),
            (Vec3::new(-0.0, 3.0, 0.0), 1),
        ] {
            let [branch_free, branching] = preparations(dir);
            assert_eq!(branch_free, branching, "{dir}");
            assert_eq!(branch_free.0[2], kz, "{dir}");
            assert_eq!(branch_free.0[2], dir.abs().max_position(), "{dir}");
        }
    }

    proptest::proptest! {
        #[test]
        fn both_preparations_give_the_same_bits(
            d in proptest::array::uniform3(proptest::sample::select(vec![-2.0 as Real, -1.0, -0.0, 0.0, 0.25, 1.0, 3.0])),
            jitter in proptest::array::uniform3(-1.0 as Real..1.0),
            exact in proptest::bool::ANY,
        ) {
            // Exact values make ties between |components|; jittered ones the rest.
            let dir = if exact { Vec3::from(d) } else { Vec3::from(d) + Vec3::from(jitter) };
            let [branch_free, branching] = preparations(dir);
            proptest::prop_assert_eq!(branch_free, branching);
        }
    }

    #[test]
    fn normal_follows_the_winding_by_the_cross_product() {
        assert_eq!(tri().normal(), -Vec3::Z);
    }

    #[test]
    fn ray_through_the_inside_hits_with_barycentric_weights() {
        // Through (0.25, 0.5, 2): t = 2; weights w_b = y = 0.5, w_c = x = 0.25, w_a = 0.25.
        let h = tri().intersect_barycentric(&Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z), ALL).unwrap();
        assert_eq!(h.t, 2.0);
        let [wa, wb, wc] = h.barycentric;
        assert!((wa - 0.25).abs() < 1e-6 && (wb - 0.5).abs() < 1e-6 && (wc - 0.25).abs() < 1e-6);
    }

    #[test]
    fn the_course_barycentric_test_agrees_with_the_hit_weights() {
        let w = tri().barycentric(Vec3::new(0.25, 0.5, 2.0));
        assert!((w[0] - 0.25).abs() < 1e-6 && (w[1] - 0.5).abs() < 1e-6 && (w[2] - 0.25).abs() < 1e-6);
        // Outside: (1,1,2) has w_a = 1 − 1 − 1 = −1.
        let w = tri().barycentric(Vec3::new(1.0, 1.0, 2.0));
        assert!((w[0] + 1.0).abs() < 1e-6);
    }

    #[test]
    fn the_back_side_is_hit_too_and_reports_the_same_normal() {
        let h = tri().intersect(&Ray::new(Vec3::new(0.2, 0.2, 5.0), -Vec3::Z), ALL).unwrap();
        assert!((h.t - 3.0).abs() <= 4.0 * Real::EPSILON * 3.0, "t = {}", h.t);
        assert_eq!(h.normal, -Vec3::Z);
    }

    #[test]
    fn rays_beside_behind_or_parallel_miss() {
        let t = tri();
        assert_eq!(t.intersect(&Ray::new(Vec3::new(0.8, 0.8, 0.0), Vec3::Z), ALL), None);
        assert_eq!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), -Vec3::Z), ALL), None);
        assert_eq!(t.intersect(&Ray::new(Vec3::new(-1.0, 0.2, 2.0), Vec3::X), ALL), None);
        assert_eq!(t.intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::Z), Interval::new(0.0, 1.5)), None);
    }

    #[test]
    fn small_triangles_far_away_are_hit_straight_on_and_obliquely() {
        // A 1 mm right triangle at z = 0; rays through the point (0.75, 0.25) mm
        // from up to 10⁴ units away, along the axis and at an angle.
        let t = Triangle::new(Vec3::ZERO, Vec3::new(0.001, 0.0, 0.0), Vec3::new(0.001, 0.001, 0.0)).unwrap();
        let target = Vec3::new(0.00075, 0.00025, 0.0);
        for distance in [1.0 as Real, 300.0, 1000.0, 1e4] {
            for dir in [Vec3::Z, Vec3::new(0.3, -0.2, 1.0), Vec3::new(-1.0, 0.5, 0.8)] {
                let origin = target - distance * dir.normalize();
                let hit = t.intersect(&Ray::new(origin, target - origin), ALL);
                let hit = hit.unwrap_or_else(|| panic!("missed from {distance} along {dir}"));
                // The plane is z = 0 exactly, so on the rounded ray the exact
                // t is −o_z/d_z (in f64, good to 2⁻⁵³). The hit's distance
                // along the ray may be off by a few ulps of the coordinates
                // it is computed from (the origin's, about `distance`), no
                // more: 4ε·|o|∞, 1 mm at 10⁴ in f32 (8 ulps of 10⁴ is 8 mm).
                let (o, d) = (crate::math::real::widen(origin), crate::math::real::widen(target - origin));
                let exact = -o.z / d.z;
                let error = (crate::math::real::to_f64(hit.t) - exact).abs() * d.length();
                let bound = 4.0 * crate::math::real::to_f64(Real::EPSILON) * o.abs().max_element();
                assert!(
                    error <= bound,
                    "from {distance} along {dir}: t = {}, exact {exact}, error {error:e}",
                    hit.t
                );
            }
        }
    }

    #[test]
    fn huge_and_tiny_triangles_have_normals() {
        for s in [1e-15 as Real, 1e10, 1e30] {
            let t = Triangle::new(Vec3::ZERO, Vec3::new(0.0, s, 0.0), Vec3::new(s, 0.0, 0.0));
            assert_eq!(t.map(|t| t.normal()), Ok(-Vec3::Z), "scale {s}");
        }
    }

    #[test]
    fn zero_area_triangles_are_refused_and_never_hit() {
        let (a, b, c) = (Vec3::ZERO, Vec3::new(1.0, 1.0, 1.0), Vec3::new(2.0, 2.0, 2.0));
        assert_eq!(Triangle::new(a, b, c), Err(GeometryError::TriangleDegenerate));
        let ray = Ray::new(Vec3::new(1.0, 1.0, -1.0), Vec3::Z);
        assert_eq!(intersect_watertight(a, b, c, &ray, ALL), None);
        assert_eq!(intersect_watertight(a, a, a, &ray, ALL), None);
    }

    /// Triangles to test the methods and bounds on: well shaped at the
    /// origin, 1 cm at 10³ units, a sliver (corner angle 2·10⁻³ rad) at 50,
    /// and one 10³ units across.
    fn test_triangles() -> [[Vec3; 3]; 4] {
        [
            [Vec3::new(0.1, -0.2, 0.3), Vec3::new(1.0, 0.2, -0.1), Vec3::new(-0.3, 0.9, 0.4)],
            [
                Vec3::new(1e3, -700.0, 400.0),
                Vec3::new(1e3 + 0.01, -700.0, 400.005),
                Vec3::new(1e3, -699.99, 400.002),
            ],
            [Vec3::new(50.0, 0.0, 3.0), Vec3::new(51.0, 0.3, 3.5), Vec3::new(50.5, 0.151, 3.25)],
            [Vec3::new(-400.0, 20.0, 0.0), Vec3::new(600.0, -10.0, 30.0), Vec3::new(100.0, 900.0, -60.0)],
        ]
    }

    #[test]
    fn every_method_hits_inside_misses_outside_and_its_weights_rebuild_the_point() {
        // Rays from random directions through the point with barycentric
        // weights w (random, some negative: beyond each edge and corner),
        // skipping points near an edge. Every method hits exactly when all
        // weights are positive, at the point's t, with weights that agree
        // with w (the area-ratio test's are unsigned, and equal to w inside)
        // to 10⁻³ plus what rounding the point and the ray's origin to
        // `Real` moves them: 8 ulps of the coordinates over the triangle's
        // least height (5 % for the 1 cm triangle at 10³ and the sliver in
        // f32, below 10⁻¹⁰ in f64).
        // Points closer to an edge than 2 % plus that are skipped.
        for (i, [a, b, c]) in test_triangles().into_iter().enumerate() {
            let n = geometric_normal(a, b, c).unwrap();
            let size = (b - a).length().max((c - a).length());
            let scale = a.abs().max_element().max(1.0);
            let rounding = 8.0 * Real::EPSILON * scale;
            let longest = [b - a, c - b, a - c].map(|e| e.length()).into_iter().fold(0.0, Real::max);
            let height = (b - a).cross(c - a).length() / longest;
            let tolerance = 1e-3 + rounding / height;
            for k in 0..400u32 {
                let rng = &mut crate::sampling::sampler::SampleRng::new(k, 13, i as u32);
                let (u, v) = rng.next_pair();
                let w = [1.0 - 2.0 * u + v * 0.5, 2.0 * u - 0.5 - 0.2 * v, 0.0];
                let w = [w[0], w[1], 1.0 - w[0] - w[1]];
                let nearest_edge = w.iter().map(|w| w.abs()).fold(Real::INFINITY, Real::min);
                if nearest_edge < 0.02 + tolerance {
                    continue;
                }
                let inside = w.iter().all(|w| *w > 0.0);
                let target = a * w[0] + b * w[1] + c * w[2];
                let (s, t) = rng.next_pair();
                let dir = (n * (0.3 + s) + (b - a).normalize() * (t - 0.5) + (c - a).normalize() * (s - 0.5))
                    * if k % 2 == 0 { 1.0 } else { -1.0 };
                let distance = 2.0 * size;
                let ray = Ray::new(target - dir * (distance / dir.length()), dir);
                let expected_t = distance / dir.length();
                // The course's barycentric test gives the weights of the point itself.
                let course = Triangle::new(a, b, c).unwrap().barycentric(target);
                for (got, want) in course.into_iter().zip(w) {
                    assert!((got - want).abs() <= tolerance, "triangle {i}, point {k}: {course:?} for {w:?}");
                }
                for method in
                    [TriangleMethod::Watertight, TriangleMethod::MollerTrumbore, TriangleMethod::AreaRatio]
                {
                    let hit = intersect_by(method, a, b, c, &TriangleRay::new(&ray), ALL);
                    let at = format!("triangle {i}, ray {k}, {method:?}, weights {w:?}");
                    assert_eq!(hit.is_some(), inside, "{at}");
                    let Some(hit) = hit else { continue };
                    let t_tolerance = 1e-3 * expected_t + rounding / dir.length();
                    assert!((hit.t - expected_t).abs() <= t_tolerance, "{at}: t {} for {expected_t}", hit.t);
                    for (got, want) in hit.barycentric.into_iter().zip(w) {
                        assert!((got - want).abs() <= tolerance, "{at}: weights {:?}", hit.barycentric);
                    }
                }
            }
        }
    }

    #[test]
    fn a_triangle_behind_the_ray_is_missed_even_when_the_range_allows_negative_t() {
        // The watertight test's sign checks give t > 0 whatever the range,
        // for both windings (det < 0 and det > 0).
        let everywhere = Interval::new(Real::NEG_INFINITY, Real::INFINITY);
        for (origin, dir) in [(Vec3::new(0.2, 0.2, 5.0), Vec3::Z), (Vec3::new(0.2, 0.2, -1.0), -Vec3::Z)] {
            let ray = Ray::new(origin, dir);
            let [a, b, c] = tri().corners();
            for [a, b, c] in [[a, b, c], [a, c, b]] {
                assert_eq!(
                    intersect_watertight(a, b, c, &ray, everywhere),
                    None,
                    "from {origin} along {dir}"
                );
                assert!(intersect_watertight(a, b, c, &Ray::new(origin, -dir), everywhere).is_some());
            }
        }
    }

    #[test]
    fn edge_functions_keep_their_exact_sign_where_the_products_round_equal() {
        // x₁y₂ = (1 + ε)² = 1 + 2ε + ε² and y₁x₂ = 1 + 2ε: the rounded
        // products are equal, the exact edge function is ε² > 0.
        let eps = Real::EPSILON;
        let (p0, p1, p2) = (
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0 + eps, 1.0 + 2.0 * eps, 1.0),
            Vec3::new(1.0, 1.0 + eps, 1.0),
        );
        let [e0, ..] = edge_functions(p0, p1, p2);
        assert!(e0 > 0.0, "e₀ = {e0}");
        let [e0, ..] = edge_functions(p0, p2, p1);
        assert!(e0 < 0.0, "e₀ = {e0} with the corners swapped");
    }

    #[test]
    fn surface_points_lie_on_the_exact_plane_within_a_tight_bound() {
        // Points a little off each test triangle's plane (as a rounded o + t·d
        // would be), moved onto it: the exact distance of the result from the
        // exact plane through the corners (double-double) is within the bound
        // along the normal; and that bound is a few ulps of the coordinates
        // involved — the point's and, through the normal's angle error, the
        // triangle's size over the sine of its corner angle (the sliver's
        // 2·10⁻³ rad makes that term 500 times the size), no more. The first
        // triangle also comes shrunk to √(smallest normal)/4, where products
        // of its edges underflow unless they are scaled first; the exact
        // distance is computed on coordinates scaled by a power of two (exact)
        // to about 1, away from double-double's own underflow.
        use crate::accuracy::double_double::{DdVec3, DoubleDouble};
        use crate::math::real::{UNIT_ROUNDOFF, to_f64, widen};
        let tiny = test_triangles()[0].map(|p| p * (Real::MIN_POSITIVE.sqrt() / 4.0));
        for (i, [a, b, c]) in test_triangles().into_iter().chain([tiny]).enumerate() {
            let n = geometric_normal(a, b, c).unwrap();
            let (e1, e2) = (b - a, c - a);
            let size = e1.length().max(e2.length());
            let unit = 2f64.powi(-to_f64(size).log2().floor() as i32);
            let wide = |p: Vec3| widen(p) * unit;
            let exact_n = DdVec3::difference(wide(b), wide(a)).cross(DdVec3::difference(wide(c), wide(a)));
            let n_length = exact_n.dot(exact_n).sqrt();
            let (f1, f2) = (e1 / size, e2 / size);
            let sine = f1.cross(f2).length() / (f1.length() * f2.length());
            for k in 0..300u32 {
                let rng = &mut crate::sampling::sampler::SampleRng::new(k, 17, i as u32);
                let (u, v) = rng.next_pair();
                let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
                let (h, _) = rng.next_pair();
                let p = a + e1 * u + e2 * v + n * ((h - 0.5) * 1e-4 * size);
                let sp = triangle_surface_point([a, b, c], n, p);
                let distance = (DdVec3::difference(wide(sp.p), wide(a)).dot(exact_n) / n_length).abs()
                    / DoubleDouble::new(unit);
                let bound = widen(sp.error).dot(widen(n).abs());
                let at = format!("triangle {i}, point {k}: {}", sp.p);
                assert!(
                    distance <= DoubleDouble::new(bound),
                    "{at}: {} off the plane, bound {bound:e}",
                    distance.to_f64()
                );
                let ulps = to_f64(UNIT_ROUNDOFF)
                    * (widen(p).abs().max_element() * 16.0 + to_f64(size / sine) * 32.0);
                assert!(bound <= ulps, "{at}: bound {bound:e} against {ulps:e}");
            }
        }
    }

    #[test]
    fn a_ray_through_a_shared_edge_hits_one_of_the_two_triangles() {
        // Square split along its diagonal from (0,0) to (1,1); rays along that diagonal.
        let (p00, p10, p01, p11) = (
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.0, 1.0, 1.0),
            Vec3::new(1.0, 1.0, 1.0),
        );
        let eye = Vec3::new(0.3, -0.2, -2.0);
        for i in 1..1000 {
            let s = i as Real / 1000.0;
            let ray = Ray::new(eye, Vec3::new(s, s, 1.0) - eye);
            let first = intersect_watertight(p00, p10, p11, &ray, ALL);
            let second = intersect_watertight(p00, p11, p01, &ray, ALL);
            assert!(first.is_some() || second.is_some(), "leak at s = {s}");
        }
        // Rays straight along z through points of the diagonal: the shared
        // edge's function is exactly 0 for both triangles, and both count
        // it, whichever of the three edge functions it is (the corners
        // taken from each starting corner).
        for i in 1..16 {
            let s = i as Real / 16.0;
            let ray = Ray::new(Vec3::new(s, s, -1.0), Vec3::Z);
            for start in 0..3 {
                let rotated = |t: [Vec3; 3]| [t[start], t[(start + 1) % 3], t[(start + 2) % 3]];
                let ([a, b, c], [d, e, f]) = (rotated([p00, p10, p11]), rotated([p00, p11, p01]));
                let (first, second) =
                    (intersect_watertight(a, b, c, &ray, ALL), intersect_watertight(d, e, f, &ray, ALL));
                assert!(first.is_some() && second.is_some(), "on the edge at s = {s}: {first:?}, {second:?}");
            }
        }
    }
}
