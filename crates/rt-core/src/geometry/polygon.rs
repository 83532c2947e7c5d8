//! Planar polygons: a plane hit, then a point-in-polygon test in 2D.

use crate::geometry::aabb::Aabb;
use crate::geometry::geometry_error::GeometryError;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::PolygonTest;
use crate::geometry::surface::{SurfacePoint, project_onto_plane};
use crate::geometry::triangle::Triangle;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{PLANARITY_TOLERANCE, Real, Vec3, magnitude_scale, normalize_robust};

/// A simple or self-intersecting planar polygon with ≥ 3 corners (even–odd
/// rule for what is inside). Its normal comes from the winding of the corners
/// by Newell's method, which for a triangle equals `normalize((b−a)×(c−a))`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Polygon {
    points: Vec<Vec3>,
    normal: Vec3,
    d: Real,
    /// The two axes the polygon is projected on (the normal's largest axis dropped).
    axes: [usize; 2],
    bounds: Aabb,
}

impl Polygon {
    /// A polygon from its corners in order; refused if fewer than 3, not
    /// finite, of zero area, or not planar within [`PLANARITY_TOLERANCE`].
    pub fn new(points: Vec<Vec3>) -> Result<Self, GeometryError> {
        if points.len() < 3 {
            return Err(GeometryError::PolygonTooFewPoints(points.len()));
        }
        if !points.iter().all(|p| p.is_finite()) {
            return Err(GeometryError::NotFinite("polygon point"));
        }
        let centroid = points.iter().copied().sum::<Vec3>() / points.len() as Real;
        let normal = newell_normal(&points, centroid).ok_or(GeometryError::PolygonDegenerate)?;
        let d = normal.dot(centroid);
        let bounds = Aabb::from_points(points.iter().copied()).expect("at least three points");
        let scale = points.iter().map(|&p| magnitude_scale(p)).fold(1.0, Real::max);
        let tolerance = PLANARITY_TOLERANCE * bounds.size().length() + 16.0 * Real::EPSILON * scale;
        let (worst, distance) = points
            .iter()
            .map(|p| (normal.dot(*p) - d).abs())
            .enumerate()
            .fold((0, 0.0), |best, (i, e)| if e > best.1 { (i, e) } else { best });
        if distance > tolerance {
            return Err(GeometryError::PolygonNotPlanar { point: worst, distance, tolerance });
        }
        let drop = normal.abs().max_position();
        let axes = [(drop + 1) % 3, (drop + 2) % 3];
        Ok(Self { points, normal, d, axes, bounds })
    }

    /// The corners, in order.
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }
    /// Unit normal given by the winding.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }
    /// `d` of the polygon's plane `p·n = d` ([`Polygon::normal`] `n`).
    pub fn plane_d(&self) -> Real {
        self.d
    }
    /// The two axes the polygon is projected on for the crossing-number
    /// test ([`Polygon::contains_projected`]): the normal's largest axis
    /// dropped, the other two in cyclic order.
    pub fn axes(&self) -> [usize; 2] {
        self.axes
    }
    /// The box around the corners.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Whether `p`, projected onto the polygon's plane, is inside it: the
    /// crossing-number test (even–odd rule) on the two axes kept by the
    /// projection (W. R. Franklin's PNPOLY).
    pub fn contains_projected(&self, p: Vec3) -> bool {
        let [u, v] = self.axes;
        let (px, py) = (p[u], p[v]);
        let mut inside = false;
        let mut j = self.points.len() - 1;
        for (i, pi) in self.points.iter().enumerate() {
            let pj = self.points[j];
            let (xi, yi, xj, yj) = (pi[u], pi[v], pj[u], pj[v]);
            if (yi > py) != (yj > py) && px < (xj - xi) * (py - yi) / (yj - yi) + xi {
                inside = !inside;
            }
            j = i;
        }
        inside
    }

    /// The polygon cut into triangles with its own corners (ear clipping
    /// in the plane of projection; Eberly, "Triangulation by Ear Clipping",
    /// 2002), each wound like the polygon. `None` if the polygon is not
    /// simple (its edges cross), where the even–odd rule's region is not the
    /// union of such triangles. Used to sample points on an emissive polygon
    /// by area.
    ///
    /// The projected corners are computed in f64 and scaled by the power of
    /// two that brings the largest coordinate near 1: exact, so no sign the
    /// tests see changes, and the products of the tests can neither underflow
    /// (corners near 10⁻¹⁵⁰ with f64 geometry) nor overflow.
    pub fn triangulate(&self) -> Option<Vec<[Vec3; 3]>> {
        let [u, v] = self.axes;
        let to_f64 = crate::math::real::to_f64;
        let largest =
            self.points.iter().map(|p| to_f64(p[u]).abs().max(to_f64(p[v]).abs())).fold(0.0, f64::max);
        let unit = if largest > 0.0 && largest.is_finite() {
            2f64.powi(-(largest.log2().floor() as i32))
        } else {
            1.0
        };
        let flat: Vec<(f64, f64)> =
            self.points.iter().map(|p| (to_f64(p[u]) * unit, to_f64(p[v]) * unit)).collect();
        // Orientation of the projected winding: counter-clockwise (> 0) or not.
        let n = flat.len();
        let signed: f64 = (0..n).map(|i| cross2(flat[i], flat[(i + 1) % n], (0.0, 0.0))).sum();
        if signed == 0.0 || edges_cross(&flat) {
            return None;
        }
        let orientation = signed.signum();
        let mut remaining: Vec<usize> = (0..n).collect();
        let mut triangles = Vec::with_capacity(n - 2);
        while remaining.len() > 3 {
            let m = remaining.len();
            let ear = (0..m).find(|&i| {
                let (a, b, c) = (remaining[(i + m - 1) % m], remaining[i], remaining[(i + 1) % m]);
                let convex = cross2(flat[a], flat[b], flat[c]) * orientation > 0.0;
                convex
                    && remaining
                        .iter()
                        .filter(|&&k| k != a && k != b && k != c)
                        .all(|&k| !inside_triangle(flat[k], flat[a], flat[b], flat[c]))
            })?;
            let (a, b, c) = (remaining[(ear + m - 1) % m], remaining[ear], remaining[(ear + 1) % m]);
            triangles.push([self.points[a], self.points[b], self.points[c]]);
            remaining.remove(ear);
        }
        triangles.push(remaining.iter().map(|&k| self.points[k]).collect::<Vec<_>>().try_into().ok()?);
        Some(triangles)
    }

    /// `p` (a computed hit) projected onto the polygon's plane `x·n = d`,
    /// which is exactly the plane [`Polygon::intersect`] tests against.
    pub fn surface_point(&self, p: Vec3) -> SurfacePoint {
        let (p, error) = project_onto_plane(p, self.normal, self.d, 0.0);
        SurfacePoint { p, error, normal: self.normal }
    }

    /// The hit with `t` in `range` from either side: the plane `p·n = d`,
    /// then [`Polygon::contains_projected`].
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let denom = ray.dir.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.d - ray.origin.dot(self.normal)) / denom;
        if !range.contains(t) || !self.contains_projected(ray.at(t)) {
            return None;
        }
        Some(PrimitiveHit { t, primitive: 0, normal: self.normal })
    }
}

/// Twice the signed area of the 2D triangle (a, b, c): > 0 counter-clockwise.
fn cross2(a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> f64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// Whether `p` lies inside or on the 2D triangle (a, b, c) of either orientation.
fn inside_triangle(p: (f64, f64), a: (f64, f64), b: (f64, f64), c: (f64, f64)) -> bool {
    let (d1, d2, d3) = (cross2(a, b, p), cross2(b, c, p), cross2(c, a, p));
    let negative = d1 < 0.0 || d2 < 0.0 || d3 < 0.0;
    let positive = d1 > 0.0 || d2 > 0.0 || d3 > 0.0;
    !(negative && positive)
}

/// Whether two non-adjacent edges of the closed 2D polygon cross or touch.
fn edges_cross(points: &[(f64, f64)]) -> bool {
    let n = points.len();
    let edge = |i: usize| (points[i], points[(i + 1) % n]);
    (0..n).any(|i| {
        (i + 2..n).any(|j| {
            if i == 0 && j == n - 1 {
                return false; // Adjacent through the closing edge.
            }
            let ((a, b), (c, d)) = (edge(i), edge(j));
            let (d1, d2) = (cross2(a, b, c), cross2(a, b, d));
            let (d3, d4) = (cross2(c, d, a), cross2(c, d, b));
            (d1 * d2 <= 0.0) && (d3 * d4 <= 0.0) && !(d1 == 0.0 && d2 == 0.0 && d3 == 0.0 && d4 == 0.0)
        })
    })
}

/// The unit normal from Newell's area vector Σ (pᵢ − c) × (pᵢ₊₁ − c), which is
/// twice the area times the normal, oriented by the winding. The offsets are
/// divided by their largest component first so the products neither overflow
/// nor underflow. `None` for zero area.
fn newell_normal(points: &[Vec3], center: Vec3) -> Option<Vec3> {
    let m = points.iter().map(|&p| (p - center).abs().max_element()).fold(0.0, Real::max);
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    let n = points.len();
    let area: Vec3 =
        (0..n).map(|i| ((points[i] - center) / m).cross((points[(i + 1) % n] - center) / m)).sum();
    normalize_robust(area)
}

impl Polygon {
    /// The course's numbers for the point `p` a ray hit ([`PolygonTest`]):
    /// the plane, the two axes kept by the projection, the crossing-number
    /// test of [`Polygon::contains_projected`], and, of the triangles of
    /// [`Polygon::triangulate`], the one holding `p` (the largest smallest
    /// barycentric weight) with its own test ([`Triangle::explain`]).
    pub fn explain(&self, p: Vec3) -> PolygonTest {
        let triangle = self
            .triangulate()
            .into_iter()
            .flatten()
            .filter_map(|[a, b, c]| Triangle::new(a, b, c).ok())
            .map(|t| {
                let w = t.barycentric(p);
                (w[0].min(w[1]).min(w[2]), t)
            })
            .max_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, t)| t.explain(p));
        PolygonTest {
            normal: self.normal,
            d: self.d,
            axes: self.axes,
            inside: self.contains_projected(p),
            triangle,
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    /// An L-shaped (concave) hexagon in the plane z = 3, wound so that
    /// (b−a)×(c−a) = (2,0,0)×(2,1,0) = (0,0,2): normal +z.
    fn l_shape() -> Polygon {
        Polygon::new(vec![
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(2.0, 0.0, 3.0),
            Vec3::new(2.0, 1.0, 3.0),
            Vec3::new(1.0, 1.0, 3.0),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(0.0, 2.0, 3.0),
        ])
        .unwrap()
    }

    #[test]
    fn normal_follows_the_winding() {
        assert_eq!(l_shape().normal(), Vec3::Z);
        let mut reversed = l_shape().points().to_vec();
        reversed.reverse();
        assert_eq!(Polygon::new(reversed).unwrap().normal(), -Vec3::Z);
    }

    #[test]
    fn ray_through_the_filled_part_hits_and_through_the_notch_misses() {
        let p = l_shape();
        let hit = p.intersect(&Ray::new(Vec3::new(0.5, 1.5, 0.0), Vec3::Z), ALL).unwrap();
        assert_eq!((hit.t, hit.normal), (3.0, Vec3::Z));
        assert!(p.intersect(&Ray::new(Vec3::new(1.5, 0.5, 0.0), Vec3::Z), ALL).is_some());
        // (1.5, 1.5) is in the notch of the L.
        assert_eq!(p.intersect(&Ray::new(Vec3::new(1.5, 1.5, 0.0), Vec3::Z), ALL), None);
    }

    #[test]
    fn rays_parallel_behind_or_outside_miss() {
        let p = l_shape();
        assert_eq!(p.intersect(&Ray::new(Vec3::new(0.5, 0.5, 3.0), Vec3::X), ALL), None);
        assert_eq!(p.intersect(&Ray::new(Vec3::new(0.5, 0.5, 4.0), Vec3::Z), ALL), None);
        assert_eq!(p.intersect(&Ray::new(Vec3::new(3.0, 0.5, 0.0), Vec3::Z), ALL), None);
    }

    #[test]
    fn a_tilted_polygon_is_hit_from_behind() {
        // Square in the plane x + z = 4.
        let sq = Polygon::new(vec![
            Vec3::new(2.0, -1.0, 2.0),
            Vec3::new(2.0, 1.0, 2.0),
            Vec3::new(3.0, 1.0, 1.0),
            Vec3::new(3.0, -1.0, 1.0),
        ])
        .unwrap();
        let h = sq.intersect(&Ray::new(Vec3::new(5.0, 0.0, 1.5), -Vec3::X), ALL).unwrap();
        // x + 1.5 = 4 → x = 2.5, t = 2.5. Winding: (b−a)×(c−a) = (0,2,0)×(1,2,−1)
        // = (2·(−1) − 0·2, 0·1 − 0·(−1), 0·2 − 2·1) = (−2,0,−2).
        assert!((h.t - 2.5).abs() < 1e-6);
        assert!((h.normal + Vec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-6);
    }

    /// The area of triangles by the cross product.
    fn area(triangles: &[[Vec3; 3]]) -> Real {
        triangles.iter().map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length()).sum()
    }

    #[test]
    fn a_concave_polygon_is_cut_into_triangles_covering_exactly_its_area() {
        let p = l_shape();
        let triangles = p.triangulate().unwrap();
        assert_eq!(triangles.len(), 4);
        assert!((area(&triangles) - 3.0).abs() < 1e-6, "the L covers 3 unit squares");
        for t in &triangles {
            // Wound like the polygon, and inside it.
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(n.dot(p.normal()) > 0.0);
            assert!(p.contains_projected((t[0] + t[1] + t[2]) / 3.0));
        }
        let mut reversed = p.points().to_vec();
        reversed.reverse();
        let r = Polygon::new(reversed).unwrap().triangulate().unwrap();
        assert!((area(&r) - 3.0).abs() < 1e-6);
    }

    /// A five-pointed star drawn in one stroke: its edges cross.
    pub(crate) fn pentagram() -> Polygon {
        let points = (0..5)
            .map(|k| {
                let a = (90.0 + 144.0 * k as Real).to_radians();
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        Polygon::new(points).unwrap()
    }

    #[test]
    fn a_self_crossing_polygon_cannot_be_triangulated() {
        assert_eq!(pentagram().triangulate(), None);
        // Its centre is outside by the even–odd rule.
        assert!(!pentagram().contains_projected(Vec3::ZERO));
    }

    #[test]
    fn tiny_and_huge_polygons_have_normals_and_are_cut() {
        // Corners whose offsets' products would underflow or overflow
        // unless scaled first (Newell's sums divide by the largest offset).
        let tiny = Real::MIN_POSITIVE.sqrt() / 8.0;
        let huge = Real::MAX.sqrt() * 8.0;
        for s in [tiny, huge] {
            let corners = vec![
                Vec3::ZERO,
                Vec3::new(2.0 * s, 0.0, 0.0),
                Vec3::new(2.0 * s, s, 0.0),
                Vec3::new(0.0, 2.0 * s, 0.0),
            ];
            let polygon = Polygon::new(corners).unwrap_or_else(|e| panic!("scale {s}: {e}"));
            assert_eq!(polygon.normal(), Vec3::Z, "scale {s}");
            assert_eq!(polygon.triangulate().map(|t| t.len()), Some(2), "scale {s}");
        }
    }

    #[test]
    fn bad_polygons_are_refused_with_the_reason() {
        assert_eq!(Polygon::new(vec![Vec3::ZERO, Vec3::X]), Err(GeometryError::PolygonTooFewPoints(2)));
        let collinear = vec![Vec3::ZERO, Vec3::X, 2.0 * Vec3::X, 3.0 * Vec3::X];
        assert_eq!(Polygon::new(collinear), Err(GeometryError::PolygonDegenerate));
        let bent = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.1), Vec3::Y];
        assert!(matches!(Polygon::new(bent), Err(GeometryError::PolygonNotPlanar { .. })));
    }

    /// A random star-shaped polygon (simple: corners at increasing angles
    /// around a centre, at random radii 0.3–1.3), of 3 to 9 corners, in a
    /// random plane through `origin`; its corners in the plane's own 2D
    /// frame (f64) and the frame `(x, y, normal)`. Wound counter-clockwise
    /// in that frame when `ccw`, so its normal is `normal`, else `−normal`.
    fn star(seed: u32, origin: Vec3, ccw: bool) -> (Polygon, Vec<(f64, f64)>, [Vec3; 3]) {
        let rng = &mut crate::sampling::sampler::SampleRng::new(seed, 23, 0);
        let (u, v) = rng.next_pair();
        let z = 1.0 - 2.0 * u;
        let phi = 2.0 * std::f64::consts::PI as Real * v;
        let normal = Vec3::new(
            (1.0 - z * z).max(0.0).sqrt() * phi.cos(),
            (1.0 - z * z).max(0.0).sqrt() * phi.sin(),
            z,
        );
        let (x, y) = normal.any_orthonormal_pair();
        let n = 3 + (seed % 7) as usize;
        let mut flat: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let (r, jitter) = rng.next_pair();
                let angle =
                    (k as f64 + 0.8 * crate::math::real::to_f64(jitter)) / n as f64 * std::f64::consts::TAU;
                let r = 0.3 + crate::math::real::to_f64(r);
                (r * angle.cos(), r * angle.sin())
            })
            .collect();
        if !ccw {
            flat.reverse();
        }
        let points = flat.iter().map(|&(a, b)| origin + x * a as Real + y * b as Real).collect();
        (Polygon::new(points).unwrap(), flat, [x, y, normal])
    }

    /// The winding number of the closed 2D polygon `flat` around `p`, by
    /// summing the signed angles its edges subtend (f64): a different
    /// algorithm from the crossing count under test.
    fn winding_number(flat: &[(f64, f64)], p: (f64, f64)) -> i32 {
        let n = flat.len();
        let total: f64 = (0..n)
            .map(|i| {
                let (a, b) = (flat[i], flat[(i + 1) % n]);
                let (ax, ay, bx, by) = (a.0 - p.0, a.1 - p.1, b.0 - p.0, b.1 - p.1);
                (ax * by - ay * bx).atan2(ax * bx + ay * by)
            })
            .sum();
        (total / std::f64::consts::TAU).round() as i32
    }

    /// The distance from `p` to the closest edge of `flat`.
    fn edge_distance(flat: &[(f64, f64)], p: (f64, f64)) -> f64 {
        let n = flat.len();
        (0..n)
            .map(|i| {
                let (a, b) = (flat[i], flat[(i + 1) % n]);
                let (dx, dy) = (b.0 - a.0, b.1 - a.1);
                let s = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
                ((a.0 + s * dx - p.0).powi(2) + (a.1 + s * dy - p.1).powi(2)).sqrt()
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn random_star_polygons_are_hit_exactly_where_their_winding_number_is_nonzero() {
        // 200 polygons of 3–9 corners in random planes, at the origin and
        // 10³ from it, wound either way; 60 rays each, from either side,
        // through points of the plane within the polygon's reach. Points
        // within 10⁻³ of an edge are skipped (rounding of the point at 10³
        // in f32 is 6·10⁻⁵). The normal follows the winding, and t is the
        // distance to the point.
        for seed in 0..200u32 {
            let origin = if seed % 2 == 0 { Vec3::ZERO } else { Vec3::new(1e3, -600.0, 300.0) };
            let ccw = seed % 3 != 0;
            let (polygon, flat, [x, y, normal]) = star(seed, origin, ccw);
            let expected_normal = if ccw { normal } else { -normal };
            // The corners are rounded at 10³ (6·10⁻⁵ in f32), which tilts the plane.
            let tilt = 1e-5 + 8.0 * Real::EPSILON * origin.abs().max_element() / 0.3;
            assert!(
                (polygon.normal() - expected_normal).length() < tilt,
                "polygon {seed}: normal {}",
                polygon.normal()
            );
            for k in 0..60u32 {
                let rng = &mut crate::sampling::sampler::SampleRng::new(k, 29, seed);
                let (a, b) = rng.next_pair();
                let p2 = (crate::math::real::to_f64(a) * 2.8 - 1.4, crate::math::real::to_f64(b) * 2.8 - 1.4);
                if edge_distance(&flat, p2) < 1e-3 {
                    continue;
                }
                let inside = winding_number(&flat, p2) != 0;
                let target = origin + x * p2.0 as Real + y * p2.1 as Real;
                let (s, t) = rng.next_pair();
                let dir = (normal + x * (s - 0.5) + y * (t - 0.5)) * if k % 2 == 0 { 1.0 } else { -1.0 };
                let ray = Ray::new(target - dir * 3.0, dir);
                let at = format!("polygon {seed}, point {p2:?}");
                assert_eq!(polygon.contains_projected(target), inside, "{at}");
                let hit = polygon.intersect(&ray, ALL);
                assert_eq!(hit.is_some(), inside, "{at}: hit {hit:?}");
                if let Some(hit) = hit {
                    assert!((hit.t - 3.0).abs() < 1e-3, "{at}: t = {}", hit.t);
                    assert_eq!(hit.normal, polygon.normal());
                }
            }
        }
    }

    /// Checks that `polygon`, whose corners are `flat` in the 2D frame
    /// (`origin`, `x`, `y`) of its plane, is cut into n − 2 triangles, each
    /// wound like the polygon, whose areas sum to the shoelace area, and
    /// that 100 random points of the polygon's box lie in exactly one
    /// triangle when inside the polygon and in none outside (so no two
    /// triangles overlap and none pokes out).
    fn assert_cut_into_tiles(polygon: &Polygon, flat: &[(f64, f64)], [origin, x, y]: [Vec3; 3], what: &str) {
        use crate::math::real::to_f64;
        let triangles = polygon.triangulate().unwrap_or_else(|| panic!("{what}: not cut"));
        assert_eq!(triangles.len(), flat.len() - 2, "{what}");
        let n = flat.len();
        let shoelace =
            (0..n).map(|i| flat[i].0 * flat[(i + 1) % n].1 - flat[(i + 1) % n].0 * flat[i].1).sum::<f64>();
        let areas: Real = triangles.iter().map(|[a, b, c]| 0.5 * (*b - *a).cross(*c - *a).length()).sum();
        assert!((to_f64(areas) - shoelace.abs() / 2.0).abs() < 1e-4, "{what}: {areas} against {shoelace}");
        let local = |p: Vec3| {
            let q = p - origin;
            (to_f64(q.dot(x)), to_f64(q.dot(y)))
        };
        for t in &triangles {
            let normal = (t[1] - t[0]).cross(t[2] - t[0]);
            assert!(normal.dot(polygon.normal()) > 0.0, "{what}: a triangle wound the other way");
        }
        let (lo, hi) = flat.iter().fold(((f64::MAX, f64::MAX), (f64::MIN, f64::MIN)), |(lo, hi), &(a, b)| {
            ((lo.0.min(a), lo.1.min(b)), (hi.0.max(a), hi.1.max(b)))
        });
        for k in 0..100u32 {
            let (a, b) = crate::sampling::sampler::SampleRng::new(k, 31, n as u32).next_pair();
            let p = (
                lo.0 + (hi.0 - lo.0) * (1.2 * to_f64(a) - 0.1),
                lo.1 + (hi.1 - lo.1) * (1.2 * to_f64(b) - 0.1),
            );
            if edge_distance(flat, p) < 1e-3 {
                continue;
            }
            let covering = triangles
                .iter()
                .filter(|t| {
                    let [a, b, c] = t.map(local);
                    let on_edge =
                        [(a, b), (b, c), (c, a)].iter().any(|&(e, f)| edge_distance(&[e, f], p) < 1e-6);
                    !on_edge && winding_number(&[a, b, c], p) != 0
                })
                .count();
            let inside = winding_number(flat, p) != 0;
            assert_eq!(covering, usize::from(inside), "{what}, point {p:?}");
        }
    }

    #[test]
    fn random_star_polygons_are_cut_into_n_minus_2_triangles_that_tile_them() {
        for seed in 0..200u32 {
            let origin = Vec3::new(3.0, -2.0, 1.0);
            let (polygon, flat, [x, y, _]) = star(seed, origin, seed % 2 == 0);
            assert_cut_into_tiles(&polygon, &flat, [origin, x, y], &format!("polygon {seed}"));
        }
    }

    #[test]
    fn a_corner_on_the_diagonal_of_an_ear_still_gives_a_tiling() {
        // (2, 0) lies exactly on the diagonal from (0, 0) to (4, 0) that
        // would cut off the corner (2, −1): the ear counts a corner on its
        // edge as inside and waits. From every starting corner, both windings.
        let corners = [(0.0, 0.0), (2.0, -1.0), (4.0, 0.0), (4.0, 2.0), (2.0, 0.0), (0.0, 2.0)];
        for start in 0..6 {
            for reverse in [false, true] {
                let mut flat: Vec<(f64, f64)> = (0..6).map(|i| corners[(start + i) % 6]).collect();
                if reverse {
                    flat.reverse();
                }
                let polygon =
                    Polygon::new(flat.iter().map(|&(a, b)| Vec3::new(a as Real, b as Real, 0.0)).collect())
                        .unwrap();
                let frame = [Vec3::ZERO, Vec3::X, Vec3::Y];
                assert_cut_into_tiles(
                    &polygon,
                    &flat,
                    frame,
                    &format!("from corner {start}, reversed {reverse}"),
                );
            }
        }
    }

    #[test]
    fn crossing_or_touching_edges_make_a_polygon_that_cannot_be_cut() {
        let z = |x: Real, y: Real| Vec3::new(x, y, 0.0);
        // A lopsided bow tie (so its net area is not 0): edges 0 and 2 cross.
        let bow_tie = Polygon::new(vec![z(0.0, 0.0), z(2.0, 1.0), z(2.0, 0.0), z(0.0, 2.0)]).unwrap();
        assert_eq!(bow_tie.triangulate(), None);
        // The fifth corner, (1, 0), touches edge 0 (from (0, 0) to (2, 0)) without crossing it.
        let touching = Polygon::new(vec![
            z(0.0, 0.0),
            z(2.0, 0.0),
            z(2.0, 2.0),
            z(1.5, 2.0),
            z(1.0, 0.0),
            z(0.5, 2.0),
            z(0.0, 2.0),
        ])
        .unwrap();
        assert_eq!(touching.triangulate(), None);
        // The same from every starting corner and wound both ways: the zero
        // falls on each side of the edge test in turn.
        for start in 0..7 {
            for reverse in [false, true] {
                let mut corners: Vec<Vec3> = (0..7).map(|i| touching.points()[(start + i) % 7]).collect();
                if reverse {
                    corners.reverse();
                }
                assert_eq!(
                    Polygon::new(corners).unwrap().triangulate(),
                    None,
                    "from {start}, reversed {reverse}"
                );
            }
        }
        // Moved off the edge by 10⁻³ it is simple, and cut into 5 triangles.
        let apart = Polygon::new(vec![
            z(0.0, 0.0),
            z(2.0, 0.0),
            z(2.0, 2.0),
            z(1.5, 2.0),
            z(1.0, 1e-3),
            z(0.5, 2.0),
            z(0.0, 2.0),
        ])
        .unwrap();
        assert_eq!(apart.triangulate().map(|t| t.len()), Some(5));
    }

    #[test]
    fn a_corner_off_the_plane_is_refused_by_the_tolerance_and_named() {
        // A unit square's third corner lifted by h: refused, naming corner 2
        // or its neighbours (the best-fit plane tilts towards it), exactly
        // when h is a few times the tolerance 10⁻⁴ × diagonal; accepted at
        // a tenth of it.
        let square = |h: Real| Polygon::new(vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, h), Vec3::Y]);
        let tolerance = PLANARITY_TOLERANCE * (2.0 as Real).sqrt();
        assert!(square(0.1 * tolerance).is_ok());
        match square(10.0 * tolerance) {
            Err(GeometryError::PolygonNotPlanar { point, distance, tolerance: t }) => {
                assert!((t - tolerance).abs() < 1e-6 * tolerance + 16.0 * Real::EPSILON, "tolerance {t}");
                // Newell's plane through the centroid leaves every corner h/4 off it.
                assert!((distance - 2.5 * tolerance).abs() < 0.1 * tolerance, "distance {distance}");
                assert!(point < 4);
            }
            other => panic!("{other:?}"),
        }
        // A pentagon with one corner lifted: that corner is the furthest.
        let mut pentagon: Vec<Vec3> = (0..5)
            .map(|k| {
                let a = (72.0 * k as Real).to_radians();
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        pentagon[3].z = 0.05;
        assert!(matches!(Polygon::new(pentagon), Err(GeometryError::PolygonNotPlanar { point: 3, .. })));
    }

    #[test]
    fn the_box_holds_every_corner_and_no_more_and_surface_points_lie_on_the_plane() {
        let (polygon, _, _) = star(5, Vec3::new(-4.0, 7.0, 2.0), true);
        let b = polygon.bounds();
        for axis in 0..3 {
            let values = polygon.points().iter().map(|p| p[axis]);
            assert_eq!(b.min()[axis], values.clone().fold(Real::INFINITY, Real::min));
            assert_eq!(b.max()[axis], values.fold(Real::NEG_INFINITY, Real::max));
        }
        let n = polygon.normal();
        let p = polygon.points()[0] + n * 0.25 + (polygon.points()[1] - polygon.points()[0]) * 0.3;
        let sp = polygon.surface_point(p);
        let d = polygon.points().iter().map(|q| q.dot(n)).sum::<Real>() / polygon.points().len() as Real;
        assert!((sp.p.dot(n) - d).abs() <= sp.error.dot(n.abs()) + 1e-6, "{} off the plane", sp.p.dot(n) - d);
        assert!((sp.p - (p - n * 0.25)).length() < 1e-5);
        assert_eq!(sp.normal, n);
    }

    #[test]
    fn a_slightly_rounded_polygon_far_from_the_origin_is_still_planar() {
        let o = Vec3::new(12345.678, -9876.5, 4321.0);
        let pts =
            vec![o, o + Vec3::new(1.0, 0.0, 0.3), o + Vec3::new(1.0, 1.0, 0.3), o + Vec3::new(0.0, 1.0, 0.0)];
        assert!(Polygon::new(pts).is_ok());
    }
}
