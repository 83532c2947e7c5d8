//! Fixed ray sets with known answers for the numerically hard cases: what
//! `rt-view accuracy` scores each intersection method on, and what the tests
//! require of the default methods, in f32 and in f64.
//!
//! A case is a list of queries (primitive, ray, expected outcome), all with
//! `t` in (0, ∞). The outcome is fixed by construction where it can be (a ray
//! from inside a closed surface must hit it; a ray aimed 10⁻⁵ heights outside
//! a triangle's edge must miss), and otherwise computed from the same rounded
//! inputs the method sees (whether a ray aimed at a box's edge passes just
//! inside or just outside; the exact `t`).
//!
//! The reference is independent of the methods it scores, in algorithm and
//! in precision: it is computed in [`DoubleDouble`] arithmetic (about 106
//! bits), by the plain formulas — the textbook quadratic for spheres, the
//! slab test for boxes, the plane equation for triangles — whose cancellations
//! cost at most about 40 of those bits on these cases (the worst, a radius-1
//! sphere 10⁶ away, cancels `b²` against `a·c` at about 10¹² times the
//! discriminant). Its `t` is thus good to about 2⁻⁶⁰ relative, below an f64
//! rounding error (2⁻⁵³), so the f64 build's errors are measured too, not
//! compared with themselves.

use std::f64::consts::PI;

use glam::DVec3;

use crate::accuracy::double_double::{DdVec3, DoubleDouble};

use crate::geometry::aabb::Aabb;
use crate::geometry::mesh::{Mesh, icosahedron};
use crate::geometry::method::Methods;
use crate::geometry::primitive::Primitive;
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, narrow, to_f64, widen};
use crate::sampling::sampler::SampleRng;

/// Rays per case.
pub const RAYS_PER_CASE: u32 = 20_000;

/// Which primitive a case exercises, and so which method knob matters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaseKind {
    /// Spheres: [`Methods::sphere`].
    Sphere,
    /// Triangles and meshes: [`Methods::triangle`].
    Triangle,
    /// Axis-aligned boxes: [`Methods::aabb`].
    Box,
}

/// What a query must give.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Expect {
    /// A hit at this `t` (the double-double reference).
    Hit(DoubleDouble),
    /// No hit.
    Miss,
    /// The line passes within [`GRAZING`] of the surface's edge: rounding
    /// may decide either way, and either answer is right.
    Either,
}

/// How near (world units) a line may pass to a box's edge, inside or outside,
/// for hit and miss both to count as right: 1/20 000 of the box's side, about
/// 13 f32 ulps at the box's distance from the origin.
const GRAZING: f64 = 1e-4;

#[derive(Clone, Debug)]
struct Query {
    primitive: usize,
    ray: Ray,
    expect: Expect,
}

/// One named ray set.
#[derive(Clone, Debug)]
pub struct HardCase {
    /// What the rays do, in a few words (no commas: it is a CSV field).
    pub name: &'static str,
    /// The primitive kind it exercises.
    pub kind: CaseKind,
    primitives: Vec<Primitive>,
    queries: Vec<Query>,
}

/// How a method did on a case.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Score {
    /// Rays cast.
    pub rays: usize,
    /// Rays that missed but must hit, hit but must miss, or gave a non-finite `t`.
    pub wrong: usize,
    /// The largest error of the hit's distance, `|t − t_ref|·|d|`, relative to
    /// `max(1, |o|∞, t_ref·|d|)` (the ray's length or the origin's magnitude),
    /// over the rays that hit as they must: in f32 a few times 2⁻²⁴ is
    /// as good as the coordinates allow.
    pub max_t_error: f64,
}

/// The `t` range of every query: anything in front of the origin.
const IN_FRONT: Interval = Interval::new(0.0, Real::INFINITY);

impl HardCase {
    /// Number of rays.
    pub fn rays(&self) -> usize {
        self.queries.len()
    }

    /// Casts every ray with `methods` and compares with the expected outcomes.
    pub fn score(&self, methods: Methods) -> Score {
        let mut score = Score { rays: self.queries.len(), ..Score::default() };
        for q in &self.queries {
            let hit = self.primitives[q.primitive].intersect_with(&q.ray, IN_FRONT, methods);
            match (q.expect, hit) {
                (Expect::Hit(t_ref), Some(h)) if h.t.is_finite() => {
                    let (o, d) = (widen(q.ray.origin), widen(q.ray.dir).length());
                    let scale = o.abs().max_element().max(1.0).max(t_ref.to_f64() * d);
                    let error = (DoubleDouble::new(to_f64(h.t)) - t_ref).abs().to_f64() * d / scale;
                    score.max_t_error = score.max_t_error.max(error);
                }
                (Expect::Miss, None) | (Expect::Either, _) => {}
                _ => score.wrong += 1,
            }
        }
        score
    }

    /// Casts every ray with `methods` and counts the hits: the loop that
    /// `rt-view accuracy` times.
    pub fn count_hits(&self, methods: Methods) -> usize {
        self.queries
            .iter()
            .filter(|q| self.primitives[q.primitive].intersect_with(&q.ray, IN_FRONT, methods).is_some())
            .count()
    }
}

/// Every case, in a fixed order, each with [`RAYS_PER_CASE`] rays.
pub fn all_cases() -> Vec<HardCase> {
    vec![
        far_sphere("radius-1 sphere 10^3 away", 1e3, 1),
        far_sphere("radius-1 sphere 10^5 away", 1e5, 2),
        far_sphere("radius-1 sphere 10^6 away", 1e6, 3),
        huge_sphere_from_just_above(4),
        sphere_from_inside(5),
        closed_mesh_from_inside("closed mesh from inside at the origin", DVec3::ZERO, 6),
        closed_mesh_from_inside(
            "closed mesh from inside at (148376 1234 -223423)",
            DVec3::new(148376.0, 1234.0, -223423.0),
            7,
        ),
        triangle_near_edges(8),
        box_edges_and_corners(9),
        box_along_faces(10),
    ]
}

/// Two uniform numbers in [0, 1) for ray `i` of case `case`.
fn uniform(case: u32, i: u32, draw: u32) -> (f64, f64) {
    let (u, v) = SampleRng::new(case, i, draw).next_pair();
    (to_f64(u), to_f64(v))
}

/// A uniformly distributed unit vector.
fn unit_vector((u, v): (f64, f64)) -> DVec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The ray from `origin` towards `target` (both f64), rounded to [`Real`];
/// the origin is rounded first and the direction taken from the rounded origin.
fn ray_towards(origin: DVec3, target: DVec3) -> Ray {
    let o = narrow(origin);
    Ray::new(o, narrow(target - widen(o)))
}

/// The ray/sphere reference in double-double arithmetic on the (already
/// rounded) inputs: the textbook quadratic `a·t² − 2b·t + c = 0` with
/// `f = o − c` (exact), `a = d·d`, `b = −f·d`, `c = f·f − r²`, roots
/// `(b ± √(b² − a·c))/a` — not the cancellation-free form of
/// [`Sphere::intersect`] it checks; the nearest root with `t > 0`.
fn reference_sphere(ray: &Ray, sphere: &Sphere) -> Expect {
    let f = DdVec3::difference(widen(ray.origin), widen(sphere.center()));
    let d = DdVec3::new(widen(ray.dir));
    let r = DoubleDouble::new(to_f64(sphere.radius()));
    let (a, b) = (d.dot(d), -f.dot(d));
    let c = f.dot(f) - r * r;
    let discriminant = b * b - a * c;
    if discriminant < DoubleDouble::ZERO {
        return Expect::Miss;
    }
    let root = discriminant.sqrt();
    let (near, far) = ((b - root) / a, (b + root) / a);
    [near, far].into_iter().find(|&t| t > DoubleDouble::ZERO).map_or(Expect::Miss, Expect::Hit)
}

/// Spheres of radius 1 at `distance` from the origin in random directions,
/// each hit by one ray from the origin aimed within 0.9 radii of its centre.
fn far_sphere(name: &'static str, distance: f64, case: u32) -> HardCase {
    let mut primitives = Vec::new();
    let mut queries = Vec::new();
    for i in 0..RAYS_PER_CASE {
        let axis = unit_vector(uniform(case, i, 0));
        let sphere = Sphere::new(narrow(axis * distance), 1.0).expect("valid sphere");
        let side =
            unit_vector(uniform(case, i, 1)).reject_from(axis).normalize_or(axis.any_orthonormal_vector());
        let (s, _) = uniform(case, i, 2);
        let ray = ray_towards(DVec3::ZERO, widen(sphere.center()) + side * 0.9 * s.sqrt());
        queries.push(Query { primitive: primitives.len(), ray, expect: reference_sphere(&ray, &sphere) });
        primitives.push(Primitive::Sphere(sphere));
    }
    HardCase { name, kind: CaseKind::Sphere, primitives, queries }
}

/// A sphere of radius 10⁵ (the ground) seen from 0.5 to 10 units above its
/// top (64 to 1280 f32 ulps of 10⁵), looking down at 45° to 90°: the near
/// root must be found.
fn huge_sphere_from_just_above(case: u32) -> HardCase {
    let ground = Sphere::new(narrow(DVec3::new(0.0, -1e5, 0.0)), 1e5 as Real).expect("valid sphere");
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let (u, v) = uniform(case, i, 0);
            let (w, h) = uniform(case, i, 1);
            let origin = DVec3::new(40.0 * u - 20.0, 0.5 * 20f64.powf(h), 40.0 * v - 20.0);
            let (a, b) = uniform(case, i, 2);
            let dir = DVec3::new(a - 0.5, -0.5 - w, b - 0.5);
            let ray = Ray::new(narrow(origin), narrow(dir));
            Query { primitive: 0, ray, expect: reference_sphere(&ray, &ground) }
        })
        .collect();
    HardCase {
        name: "radius-10^5 sphere from 0.5-10 above",
        kind: CaseKind::Sphere,
        primitives: vec![Primitive::Sphere(ground)],
        queries,
    }
}

/// Rays from random points inside a sphere, in random directions: the far root.
fn sphere_from_inside(case: u32) -> HardCase {
    let centre = DVec3::new(3.0, -2.0, 5.0);
    let sphere = Sphere::new(narrow(centre), 2.0).expect("valid sphere");
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let (s, _) = uniform(case, i, 0);
            let origin = centre + unit_vector(uniform(case, i, 1)) * 1.99 * s.cbrt();
            let ray = Ray::new(narrow(origin), narrow(unit_vector(uniform(case, i, 2))));
            Query { primitive: 0, ray, expect: reference_sphere(&ray, &sphere) }
        })
        .collect();
    HardCase {
        name: "sphere from inside",
        kind: CaseKind::Sphere,
        primitives: vec![Primitive::Sphere(sphere)],
        queries,
    }
}

/// An icosahedron of circumradius 2 around `centre`, hit from its centre:
/// a third of the rays aimed at its corners, a third at random points of its
/// edges, a third in random directions. Every ray must hit (a miss is a
/// leak); `t` is checked against the exit distance from the convex solid,
/// `min (n·(a − o)) / (n·d)` over the faces with `n·d > 0`, in f64.
fn closed_mesh_from_inside(name: &'static str, centre: DVec3, case: u32) -> HardCase {
    let (corners, faces) = icosahedron();
    let corners = corners.map(DVec3::from_array);
    let scale = 2.0 / corners[0].length();
    let positions: Vec<_> = corners.iter().map(|&c| narrow(centre + c * scale)).collect();
    let mesh = Mesh::new(positions.clone(), faces.to_vec()).expect("valid mesh");
    let corner = |k: u32| widen(positions[k as usize]);
    let origin = widen(narrow(centre));
    let exit = |ray: &Ray| {
        faces
            .iter()
            .filter_map(|&[a, b, c]| {
                let (t, facing) = reference_plane_t(ray, [a, b, c].map(corner));
                (facing > DoubleDouble::ZERO).then_some(t)
            })
            .fold(DoubleDouble::new(f64::INFINITY), DoubleDouble::min)
    };
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let (u, v) = uniform(case, i, 0);
            let target = match i % 3 {
                0 => corner((u * 12.0) as u32 % 12),
                1 => {
                    let [a, b, _] = faces[(u * 20.0) as usize % 20].map(corner);
                    a + (b - a) * v
                }
                _ => origin + unit_vector((u, v)),
            };
            let ray = ray_towards(origin, target);
            Query { primitive: 0, ray, expect: Expect::Hit(exit(&ray)) }
        })
        .collect();
    HardCase { name, kind: CaseKind::Triangle, primitives: vec![Primitive::Mesh(mesh)], queries }
}

/// Rays from around (0, 0, −3) at a tilted triangle of size ~1.5, aimed at
/// points 10⁻⁵ of the triangle's height beyond one of its edges (must miss)
/// or as far inside it (must hit).
fn triangle_near_edges(case: u32) -> HardCase {
    let corners = [DVec3::new(0.3, -0.2, 1.1), DVec3::new(1.4, 0.5, 0.7), DVec3::new(-0.4, 1.2, 0.9)];
    let [a, b, c] = corners.map(narrow);
    let triangle = Triangle::new(a, b, c).expect("valid triangle");
    let [a, b, c] = [a, b, c].map(widen);
    let normal = (b - a).cross(c - a);
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let (u, v) = uniform(case, i, 0);
            let edge = (u * 3.0) as usize % 3;
            let (p, q, opposite) = [(a, b, c), (b, c, a), (c, a, b)][edge];
            let on_edge = p + (q - p) * (0.05 + 0.9 * v);
            // Unit vector in the plane, across the edge, away from the opposite corner.
            let across = (q - p).cross(normal).normalize();
            let across = if across.dot(opposite - p) > 0.0 { -across } else { across };
            let height = (opposite - p).reject_from(q - p).length();
            let outside = i % 2 == 0;
            let target = on_edge + across * (if outside { 1e-5 } else { -1e-5 }) * height;
            let (s, w) = uniform(case, i, 1);
            let origin = DVec3::new(s - 0.5, w - 0.5, -3.0);
            let ray = ray_towards(origin, target);
            let expect =
                if outside { Expect::Miss } else { Expect::Hit(reference_plane_t(&ray, [a, b, c]).0) };
            Query { primitive: 0, ray, expect }
        })
        .collect();
    HardCase {
        name: "triangle: 10^-5 heights either side of an edge",
        kind: CaseKind::Triangle,
        primitives: vec![Primitive::Triangle(triangle)],
        queries,
    }
}

/// The box `[min, max]` of both reference cases: sides 2, centred at (100, −50, 30).
fn reference_box() -> (DVec3, DVec3) {
    let centre = DVec3::new(100.0, -50.0, 30.0);
    (centre - 1.0, centre + 1.0)
}

/// Where the ray meets the plane of the triangle `[a, b, c]`, in
/// double-double: `t = n·(a − o)/(n·d)` with `n = (b − a)×(c − a)`, and
/// `n·d` (positive when the ray leaves through the side `n` points to).
fn reference_plane_t(ray: &Ray, [a, b, c]: [DVec3; 3]) -> (DoubleDouble, DoubleDouble) {
    let n = DdVec3::difference(b, a).cross(DdVec3::difference(c, a));
    let d = DdVec3::new(widen(ray.dir));
    let facing = n.dot(d);
    (n.dot(DdVec3::difference(a, widen(ray.origin))) / facing, facing)
}

/// The slab test in double-double: the first of the entry and exit `t`
/// that is > 0, or [`Expect::Either`] for a line that grazes an edge. An
/// axis with `d = ±0` keeps the ray in its slab exactly when `min ≤ o ≤ max`.
fn reference_box_hit(ray: &Ray, (min, max): (DVec3, DVec3)) -> Expect {
    let (o, d) = (widen(ray.origin), widen(ray.dir));
    let (mut enter, mut exit) = (DoubleDouble::new(f64::NEG_INFINITY), DoubleDouble::new(f64::INFINITY));
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < min[k] || o[k] > max[k] {
                return Expect::Miss;
            }
            continue;
        }
        let dk = DoubleDouble::new(d[k]);
        let (t0, t1) = (DoubleDouble::sum(min[k], -o[k]) / dk, DoubleDouble::sum(max[k], -o[k]) / dk);
        enter = enter.max(t0.min(t1));
        exit = exit.min(t0.max(t1));
    }
    if ((enter - exit).to_f64() * d.length()).abs() < GRAZING && enter.max(exit) > DoubleDouble::ZERO {
        return Expect::Either;
    }
    if enter > exit {
        return Expect::Miss;
    }
    [enter, exit]
        .into_iter()
        .find(|&t| t > DoubleDouble::ZERO && t.is_finite())
        .map_or(Expect::Miss, Expect::Hit)
}

/// Rays from 6 units around the box, aimed at random points of its 12 edges
/// (and, one in eight, at its corners): rounding decides whether each passes
/// just inside or just outside, and the f64 slab test says which.
fn box_edges_and_corners(case: u32) -> HardCase {
    let (min, max) = reference_box();
    let aabb = Aabb::new(narrow(min), narrow(max)).expect("valid box");
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let (u, v) = uniform(case, i, 0);
            let pick = |bit: u32| ((u * 256.0) as u32 >> bit) & 1 == 1;
            let mut target = DVec3::new(
                if pick(0) { max.x } else { min.x },
                if pick(1) { max.y } else { min.y },
                if pick(2) { max.z } else { min.z },
            );
            if i % 8 != 0 {
                // Free one axis: a point on an edge.
                let axis = i as usize % 3;
                target[axis] = min[axis] + (max[axis] - min[axis]) * v;
            }
            let origin = narrow((min + max) / 2.0 + unit_vector(uniform(case, i, 1)) * 6.0);
            // A direction of random length, so that it is rounded (one exactly
            // from the origin to the target would be exact in f32 here).
            let (length, _) = uniform(case, i, 2);
            let ray = Ray::new(origin, narrow((target - widen(origin)) * (0.5 + length)));
            Query { primitive: 0, ray, expect: reference_box_hit(&ray, (min, max)) }
        })
        .collect();
    HardCase {
        name: "box edges and corners",
        kind: CaseKind::Box,
        primitives: vec![Primitive::Aabb(aabb)],
        queries,
    }
}

/// Rays starting on a face plane of the box (inside the face, on its edges or
/// corners, or beyond them) and running along it: the direction's component
/// across the face is exactly +0.0 or −0.0.
fn box_along_faces(case: u32) -> HardCase {
    let (min, max) = reference_box();
    let aabb = Aabb::new(narrow(min), narrow(max)).expect("valid box");
    let queries = (0..RAYS_PER_CASE)
        .map(|i| {
            let axis = i as usize % 3;
            let (u, v) = uniform(case, i, 0);
            let (s, w) = uniform(case, i, 1);
            // Coordinates on a coarse grid from 2 below to 2 above the box, so
            // origins land exactly on edges and corners too.
            let snap = |x: f64, k: usize| min[k] - 2.0 + ((x * 12.0).floor() / 2.0);
            let mut origin = DVec3::new(snap(u, 0), snap(v, 1), snap(s, 2));
            origin[axis] = if w < 0.5 { min[axis] } else { max[axis] };
            let mut dir = unit_vector(uniform(case, i, 2));
            dir[axis] = if i % 2 == 0 { 0.0 } else { -0.0 };
            let ray = Ray::new(narrow(origin), narrow(dir));
            Query { primitive: 0, ray, expect: reference_box_hit(&ray, (min, max)) }
        })
        .collect();
    HardCase {
        name: "box: rays along its faces (+0/-0)",
        kind: CaseKind::Box,
        primitives: vec![Primitive::Aabb(aabb)],
        queries,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_methods_get_every_hard_case_right() {
        for case in all_cases() {
            let score = case.score(Methods::default());
            assert_eq!(score.wrong, 0, "{}: {score:?}", case.name);
            // Measured against the double-double reference, in f32 and in f64
            // alike: a few ulps of the working precision ε (2⁻²³ or 2⁻⁵²) of t,
            // whatever the distance (2.5ε at most on these cases). From just
            // above the huge sphere, `f·f − r²` cancels from |f|² ≈ 10¹⁰ down
            // to 2·r·h ≈ 10⁵, so the near root keeps its value only to about
            // 10⁵ε (4·10⁴ε measured in f32, 9·10⁴ε in f64): bound 2·10⁵ε,
            // 2.4 % in f32.
            let epsilon = to_f64(Real::EPSILON);
            let bound = if case.name.starts_with("radius-10^5") { 2e5 * epsilon } else { 8.0 * epsilon };
            assert!(score.max_t_error < bound, "{}: {score:?}", case.name);
        }
    }

    #[test]
    fn the_reference_is_finer_than_the_working_precision_and_tells_methods_apart() {
        // A reference computed like the method it scores, at the same
        // precision, would give the careful sphere test no error at all (the
        // f64 build once did). The double-double reference sees its rounding
        // errors, a fraction of an ulp to a few, and the textbook quadratic's
        // cancellation far above them, in f32 and in f64.
        use crate::geometry::method::SphereMethod;
        let epsilon = to_f64(Real::EPSILON);
        let far = far_sphere("far", 1e6, 3);
        let careful = far.score(Methods::default()).max_t_error;
        let textbook =
            far.score(Methods { sphere: SphereMethod::Textbook, ..Methods::default() }).max_t_error;
        assert!(careful > 0.1 * epsilon && careful < 8.0 * epsilon, "careful: {careful:e}");
        assert!(textbook > 100.0 * careful, "textbook {textbook:e}, careful {careful:e}");
    }

    #[test]
    fn every_case_is_mostly_decidable_and_expects_hits() {
        for case in all_cases() {
            let hits = case.queries.iter().filter(|q| matches!(q.expect, Expect::Hit(_))).count();
            assert_eq!(case.rays(), RAYS_PER_CASE as usize);
            assert!(hits > case.rays() / 4, "{}: only {hits} rays expect a hit", case.name);
            let either = case.queries.iter().filter(|q| q.expect == Expect::Either).count();
            assert!(either < case.rays() * 3 / 5, "{}: {either} grazing rays", case.name);
            if case.name.contains("either side") {
                assert_eq!(hits, case.rays() / 2);
            }
        }
    }

    /// The documented failures of the textbook and course methods (README,
    /// "Accuracy"), pinned so that the table cannot silently go stale.
    #[cfg(not(feature = "f64"))]
    #[test]
    fn the_simpler_methods_fail_where_the_readme_says_in_f32() {
        use crate::geometry::method::{BoxMethod, SphereMethod, TriangleMethod};
        let cases = all_cases();
        let wrong = |name: &str, methods: Methods| {
            cases.iter().find(|c| c.name.starts_with(name)).unwrap().score(methods).wrong
        };
        let textbook = Methods { sphere: SphereMethod::Textbook, ..Methods::default() };
        assert!(wrong("radius-1 sphere 10^5", textbook) > 0);
        let area = Methods { triangle: TriangleMethod::AreaRatio, ..Methods::default() };
        assert!(wrong("triangle: 10^-5", area) > 0);
        let mt = Methods { triangle: TriangleMethod::MollerTrumbore, ..Methods::default() };
        assert!(wrong("closed mesh from inside at (148376", mt) > 0);
        // The six-plane box test gets every box case right: it costs only time.
        let six = Methods { aabb: BoxMethod::SixPlane, ..Methods::default() };
        assert!(cases.iter().filter(|c| c.kind == CaseKind::Box).all(|c| c.score(six).wrong == 0));
    }
}
