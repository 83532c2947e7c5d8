//! The course's tests on a hit, as numbers: what each primitive's
//! `explain` method returns for a ray and the point it hit, so a student can
//! check their own code against them number by number (`rt-view explain`,
//! `docs/explain.md`).
//!
//! - plane `p·n = d`: n, d, `n·dir`, and the side of the plane the ray's
//!   origin (the eye, for a camera ray) is on;
//! - sphere: whether the ray's origin is inside, on or outside it, and the
//!   quadratic's roots;
//! - box: the three slabs' entry and exit parameters (Kay and Kajiya), the
//!   face the ray entered or left by;
//! - triangle: the barycentric coordinates of the hit point and the
//!   course's area-ratio test `w_a + w_b + w_c ≤ 1 + ε`
//!   ([`crate::math::real::AREA_RATIO_EPSILON`]);
//! - polygon: its plane, the two axes it is projected on, the crossing-number
//!   test on them, and the triangle of its fan that holds the point.
//!
//! Each is computed by the functions the intersection itself uses
//! ([`crate::geometry::plane::Plane::side`],
//! [`crate::geometry::sphere::Sphere::classify`],
//! [`crate::geometry::triangle::Triangle::barycentric`], …), not copies.

use serde::Serialize;

use crate::math::real::{Real, Vec3};

/// The course's tests on one hit, by the kind of primitive hit (a mesh's
/// triangle is a `Triangle`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "shape", rename_all = "snake_case")]
pub enum HitTest {
    /// An infinite plane.
    Plane(PlaneTest),
    /// A sphere.
    Sphere(SphereTest),
    /// An axis-aligned box.
    Box(BoxTest),
    /// A triangle (alone, or one of a mesh).
    Triangle(TriangleTest),
    /// A planar polygon.
    Polygon(PolygonTest),
}

/// Where a point is relative to a plane or a closed surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Placement {
    /// On the side the normal points to (plane), or inside (sphere, box).
    Above,
    /// Within the tolerance of the surface.
    On,
    /// On the side opposite the normal (plane).
    Below,
    /// Inside a closed surface.
    Inside,
    /// Outside a closed surface.
    Outside,
}

/// A plane `p·n = d` and a ray `o + t·dir` (course: "ray–plane").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlaneTest {
    /// The unit normal n.
    pub normal: Vec3,
    /// d, the plane's signed distance from the world origin along n.
    pub d: Real,
    /// `n·dir`: 0 for a ray parallel to the plane (no hit).
    pub n_dot_dir: Real,
    /// `o·n − d`: the origin's signed distance from the plane (for a unit n).
    pub origin_distance: Real,
    /// The side of the plane the ray's origin is on (the eye's side, for a
    /// camera ray): above (where n points), on, below.
    pub origin_side: Placement,
    /// `t = (d − o·n) / (n·dir)`, the course's formula.
    pub t: Real,
}

/// A sphere `|p − c| = r` and a ray `o + t·dir` (course: "ray–sphere").
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SphereTest {
    /// Centre c.
    pub center: Vec3,
    /// Radius r.
    pub radius: Real,
    /// `|o − c| − r`: negative inside, positive outside.
    pub origin_distance: Real,
    /// Whether the ray's origin is inside, on or outside the sphere (within
    /// the tolerance the scene uses to classify points).
    pub origin: Placement,
    /// The quadratic `a·t² + b·t + c = 0`: `[a, b, c]` with `a = dir·dir`,
    /// `b = 2(o − c)·dir`, `c = |o − c|² − r²` (the course's form).
    pub quadratic: [Real; 3],
    /// Its discriminant `b² − 4ac` (as the course computes it; the renderer
    /// computes it without cancellation, see `Sphere::intersect`).
    pub discriminant: Real,
    /// The two roots, nearer first, from the renderer's stable formula; `None`
    /// when the ray misses.
    pub roots: Option<[Real; 2]>,
    /// Which root the hit is: `false` the near one (entering from outside),
    /// `true` the far one (leaving from inside).
    pub far_root: bool,
}

/// One slab of a box: the two planes `x_axis = min` and `x_axis = max`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SlabTest {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// `(min − o)/dir` on this axis.
    pub t_min_plane: Real,
    /// `(max − o)/dir` on this axis.
    pub t_max_plane: Real,
    /// The ray enters the slab at this parameter (the smaller of the two).
    pub t_enter: Real,
    /// The ray leaves the slab at this parameter (the larger of the two).
    pub t_exit: Real,
}

/// An axis-aligned box and a ray (course: the slab test, Kay and Kajiya 1986).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BoxTest {
    /// The lower corner.
    pub min: Vec3,
    /// The upper corner.
    pub max: Vec3,
    /// The three slabs.
    pub slabs: [SlabTest; 3],
    /// The largest entry parameter of the three slabs: where the ray enters
    /// the box.
    pub t_enter: Real,
    /// The smallest exit parameter: where it leaves (a miss if `< t_enter`).
    pub t_exit: Real,
    /// Whether the ray's origin is inside or outside the box.
    pub origin: Placement,
    /// The axis of the face hit.
    pub face_axis: usize,
    /// Whether it is the face at `max` (true) or `min` (false) on that axis.
    pub face_max: bool,
    /// Whether the ray entered the box there (from outside) rather than left it.
    pub entered: bool,
}

/// A triangle a, b, c and the point p a ray hit (course: barycentric
/// coordinates by area ratios).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TriangleTest {
    /// Corners a, b, c.
    pub corners: [Vec3; 3],
    /// `normalize((b−a)×(c−a))`.
    pub normal: Vec3,
    /// The signed barycentric weights `(w_a, w_b, w_c)` of p
    /// ([`crate::geometry::triangle::Triangle::barycentric`]): p is inside
    /// when all are ≥ 0.
    pub barycentric: [Real; 3],
    /// The course's unsigned area ratios `|(b−p)×(c−p)|/|n|`, cyclically.
    pub area_ratios: [Real; 3],
    /// Their sum: 1 inside the triangle, more outside.
    pub area_ratio_sum: Real,
    /// The ε of the course's test `sum ≤ 1 + ε`.
    pub epsilon: Real,
    /// Whether the course's test accepts p (`1 − ε ≤ sum ≤ 1 + ε`).
    pub inside: bool,
}

/// A planar polygon and the point p a ray hit (course: ray–plane, then
/// point in polygon in 2D).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PolygonTest {
    /// The unit normal of the winding (Newell).
    pub normal: Vec3,
    /// d of the polygon's plane `p·n = d`.
    pub d: Real,
    /// The two axes kept when projecting onto a coordinate plane (the normal's
    /// largest axis dropped).
    pub axes: [usize; 2],
    /// Whether the crossing-number test (even–odd rule) puts p inside.
    pub inside: bool,
    /// The triangle of the polygon's triangulation that holds p, with its
    /// barycentric test; `None` for a self-intersecting polygon or a point
    /// outside every triangle.
    pub triangle: Option<TriangleTest>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::aabb::Aabb;
    use crate::geometry::plane::Plane;
    use crate::geometry::polygon::Polygon;
    use crate::geometry::primitive::Primitive;
    use crate::geometry::sphere::Sphere;
    use crate::geometry::triangle::Triangle;
    use crate::math::ray::{Interval, Ray};

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    #[test]
    fn a_plane_says_which_side_the_eye_is_on_and_gives_the_intersections_t() {
        let floor = Plane::new(Vec3::Y, -1.0).unwrap();
        let down = Ray::new(Vec3::new(0.0, 1.0, -6.0), Vec3::new(0.0, -1.0, 1.0));
        let test = floor.explain(&down);
        assert_eq!((test.origin_side, test.origin_distance, test.n_dot_dir), (Placement::Above, 2.0, -1.0));
        assert_eq!(test.t, floor.intersect(&down, ALL).unwrap().t);
        let up = Ray::new(Vec3::new(0.0, -3.0, 0.0), Vec3::Y);
        assert_eq!((floor.explain(&up).origin_side, floor.explain(&up).t), (Placement::Below, 2.0));
        let on = Ray::new(Vec3::new(5.0, -1.0, 0.0), Vec3::X);
        assert_eq!((floor.explain(&on).origin_side, floor.explain(&on).n_dot_dir), (Placement::On, 0.0));
    }

    #[test]
    fn a_sphere_says_whether_the_origin_is_inside_on_or_outside_and_which_root_was_hit() {
        let s = Sphere::new(Vec3::ZERO, 1.0).unwrap();
        let from = |z: Real| Ray::new(Vec3::new(0.0, 0.0, z), Vec3::Z);
        let outside = s.explain(&from(-5.0), 4.0);
        assert_eq!(
            (outside.origin, outside.roots, outside.far_root),
            (Placement::Outside, Some([4.0, 6.0]), false)
        );
        // a = 1, b = 2·(−5) = −10, c = 25 − 1 = 24: b² − 4ac = 4.
        assert_eq!((outside.quadratic, outside.discriminant), ([1.0, -10.0, 24.0], 4.0));
        let t = s.intersect(&from(0.0), ALL).unwrap().t;
        let inside = s.explain(&from(0.0), t);
        assert_eq!((inside.origin, inside.far_root, inside.origin_distance), (Placement::Inside, true, -1.0));
        assert_eq!(s.explain(&from(-1.0), 0.0).origin, Placement::On);
        let miss = s.explain(&Ray::new(Vec3::new(0.0, 2.0, -5.0), Vec3::Z), 0.0);
        assert!(miss.roots.is_none() && miss.discriminant < 0.0);
    }

    #[test]
    fn a_box_gives_its_slabs_and_the_face_entered_or_left() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::new(1.0, 2.0, 1.0)).unwrap();
        let ray = Ray::new(Vec3::new(0.0, 0.5, -5.0), Vec3::Z);
        let test = b.explain(&ray, b.intersect(&ray, ALL).unwrap().t);
        assert_eq!((test.t_enter, test.t_exit, test.origin), (4.0, 6.0, Placement::Outside));
        assert_eq!((test.face_axis, test.face_max, test.entered), (2, false, true));
        assert_eq!((test.slabs[2].t_min_plane, test.slabs[2].t_max_plane), (4.0, 6.0));
        assert_eq!((test.slabs[1].t_enter, test.slabs[1].t_exit), (Real::NEG_INFINITY, Real::INFINITY));
        // From inside, along −y: it leaves by the face y = min.
        let ray = Ray::new(Vec3::new(0.0, 0.5, 0.0), -Vec3::Y);
        let test = b.explain(&ray, b.intersect(&ray, ALL).unwrap().t);
        assert_eq!(
            (test.origin, test.face_axis, test.face_max, test.entered),
            (Placement::Inside, 1, false, false)
        );
        assert_eq!(test.t_exit, 1.5);
    }

    #[test]
    fn a_triangle_gives_the_barycentric_coordinates_and_the_one_plus_epsilon_test() {
        let t = Triangle::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 0.0, 2.0))
            .unwrap();
        let inside = t.explain(Vec3::new(0.25, 0.5, 2.0));
        assert_eq!(inside.barycentric, [0.25, 0.5, 0.25]);
        assert_eq!((inside.area_ratio_sum, inside.inside), (1.0, true));
        let outside = t.explain(Vec3::new(1.0, 1.0, 2.0));
        assert!(!outside.inside && outside.area_ratio_sum > 1.0 + outside.epsilon);
        assert!(outside.barycentric.iter().any(|&w| w < 0.0));
        // A mesh's triangle is explained as that triangle.
        let mesh = crate::geometry::mesh::Mesh::new(t.corners().to_vec(), vec![[0, 1, 2]]).unwrap();
        let ray = Ray::new(Vec3::new(0.25, 0.5, 0.0), Vec3::Z);
        assert_eq!(Primitive::Mesh(mesh).explain(0, &ray, 2.0), Some(HitTest::Triangle(inside)));
    }

    #[test]
    fn a_polygon_gives_the_crossing_test_and_the_triangle_holding_the_point() {
        let square = Polygon::new(vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
        ])
        .unwrap();
        let inside = square.explain(Vec3::new(0.5, 0.2, 0.0));
        assert!(inside.inside && inside.triangle.as_ref().is_some_and(|t| t.inside));
        assert_eq!(inside.axes, [0, 1]);
        let outside = square.explain(Vec3::new(2.0, 0.0, 0.0));
        assert!(!outside.inside && outside.triangle.is_some_and(|t| !t.inside));
    }
}
