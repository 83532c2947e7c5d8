//! Infinite planes `p·n = d`: above/on/below test, closest point, ray intersection.

use crate::geometry::geometry_error::GeometryError;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::{Placement, PlaneTest};
use crate::geometry::surface::{SurfacePoint, project_onto_plane};
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3};

/// Which side of a plane a point is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// `p·n − d > tolerance`: the side the normal points to.
    Above,
    /// `|p·n − d| ≤ tolerance`.
    On,
    /// `p·n − d < −tolerance`.
    Below,
}

/// The plane of points `p` with `p·n = d`, `n` unit length. Its normal is `n`
/// whichever side a ray comes from.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plane {
    normal: Vec3,
    d: Real,
}

impl Plane {
    /// The plane `p·n = d`. A non-unit `n` is normalised and `d` scaled with
    /// it (`p·n = d` ⇔ `p·n/|n| = d/|n|`), so the set of points is unchanged.
    pub fn new(normal: Vec3, d: Real) -> Result<Self, GeometryError> {
        if !normal.is_finite() || !d.is_finite() {
            return Err(GeometryError::NotFinite("plane normal or d"));
        }
        // Divide by the largest component first, so |n| cannot overflow or underflow.
        let m = normal.abs().max_element();
        if m == 0.0 {
            return Err(GeometryError::PlaneNormalZero);
        }
        let n = normal / m;
        let len = n.length();
        let (normal, d) = (n / len, d / m / len);
        if !d.is_finite() {
            return Err(GeometryError::NotFinite("plane d / |normal|"));
        }
        Ok(Self { normal, d })
    }

    /// Unit normal n.
    pub fn normal(&self) -> Vec3 {
        self.normal
    }
    /// Signed distance of the plane from the origin along n.
    pub fn d(&self) -> Real {
        self.d
    }

    /// `p·n − d`: the signed distance of `p` from the plane, positive above.
    pub fn signed_distance(&self, p: Vec3) -> Real {
        p.dot(self.normal) - self.d
    }

    /// Above, on (|p·n − d| ≤ `tolerance`) or below the plane.
    pub fn side(&self, p: Vec3, tolerance: Real) -> Side {
        let s = self.signed_distance(p);
        if s.abs() <= tolerance {
            Side::On
        } else if s > 0.0 {
            Side::Above
        } else {
            Side::Below
        }
    }

    /// The point of the plane closest to `p`: `p − (p·n − d)·n`.
    pub fn closest_point(&self, p: Vec3) -> Vec3 {
        p - self.signed_distance(p) * self.normal
    }

    /// `p` (a computed hit) projected onto the plane, with its error bound
    /// ([`project_onto_plane`]; `n` and `d` define the plane exactly).
    pub fn surface_point(&self, p: Vec3) -> SurfacePoint {
        let (p, error) = project_onto_plane(p, self.normal, self.d, 0.0);
        SurfacePoint { p, error, normal: self.normal }
    }

    /// `t = (d − o·n) / (dir·n)` if the ray is not parallel to the plane and
    /// `t` is in `range`. A ray lying in the plane is parallel: no hit.
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let denom = ray.dir.dot(self.normal);
        if denom == 0.0 {
            return None;
        }
        let t = (self.d - ray.origin.dot(self.normal)) / denom;
        range.contains(t).then_some(PrimitiveHit { t, primitive: 0, normal: self.normal })
    }
}

impl Plane {
    /// The course's numbers for `ray` against this plane ([`PlaneTest`]):
    /// `n·dir`, the origin's signed distance `o·n − d` and its side by
    /// [`Plane::side`] (exact sign: tolerance 0), and
    /// `t = (d − o·n)/(n·dir)`, the formula [`Plane::intersect`] evaluates.
    pub fn explain(&self, ray: &Ray) -> PlaneTest {
        let n_dot_dir = ray.dir.dot(self.normal);
        PlaneTest {
            normal: self.normal,
            d: self.d,
            n_dot_dir,
            origin_distance: self.signed_distance(ray.origin),
            origin_side: match self.side(ray.origin, 0.0) {
                Side::Above => Placement::Above,
                Side::On => Placement::On,
                Side::Below => Placement::Below,
            },
            t: (self.d - ray.origin.dot(self.normal)) / n_dot_dir,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    fn floor() -> Plane {
        Plane::new(Vec3::Y, -1.0).unwrap() // y = −1
    }

    #[test]
    fn ray_down_onto_the_floor_hits_with_the_given_normal() {
        // From (0,2,0) along (0,−1,1): y = 2 − t = −1 → t = 3, at (0,−1,3).
        let hit = floor().intersect(&Ray::new(Vec3::new(0.0, 2.0, 0.0), Vec3::new(0.0, -1.0, 1.0)), ALL);
        assert_eq!(hit, Some(PrimitiveHit { t: 3.0, primitive: 0, normal: Vec3::Y }));
    }

    #[test]
    fn ray_from_below_still_reports_the_given_normal() {
        let hit = floor().intersect(&Ray::new(Vec3::new(0.0, -3.0, 0.0), Vec3::Y), ALL).unwrap();
        assert_eq!((hit.t, hit.normal), (2.0, Vec3::Y));
    }

    #[test]
    fn rays_parallel_to_the_plane_miss_including_those_lying_in_it() {
        for (o, d) in [
            (Vec3::new(0.0, 2.0, 0.0), Vec3::X),
            (Vec3::new(0.0, -1.0, 0.0), Vec3::Z),
            (Vec3::new(0.0, -1.0, 0.0), Vec3::new(-0.0, 0.0, 1.0)),
            (Vec3::new(0.0, 2.0, 0.0), Vec3::new(1.0, -0.0, 0.0)),
        ] {
            assert_eq!(floor().intersect(&Ray::new(o, d), ALL), None);
        }
    }

    #[test]
    fn ray_pointing_away_misses() {
        assert_eq!(floor().intersect(&Ray::new(Vec3::ZERO, Vec3::Y), ALL), None);
    }

    #[test]
    fn non_unit_normals_are_normalised_with_d_scaled() {
        // 2y = −2 is y = −1.
        let p = Plane::new(Vec3::new(0.0, 2.0, 0.0), -2.0).unwrap();
        assert_eq!((p.normal(), p.d()), (Vec3::Y, -1.0));
        assert_eq!(Plane::new(Vec3::ZERO, 1.0), Err(GeometryError::PlaneNormalZero));
        // Huge and tiny normals are fine: only their direction matters.
        assert_eq!(
            Plane::new(Vec3::new(0.0, 1e20, 0.0), 1e20).map(|p| (p.normal(), p.d())),
            Ok((Vec3::Y, 1.0))
        );
        assert_eq!(Plane::new(Vec3::new(0.0, 1e-30, 0.0), 0.0).map(|p| p.normal()), Ok(Vec3::Y));
    }

    #[test]
    fn side_reports_above_on_and_below() {
        let p = floor();
        assert_eq!(p.side(Vec3::new(5.0, 0.0, 3.0), 1e-6), Side::Above);
        assert_eq!(p.side(Vec3::new(5.0, -1.0, 3.0), 1e-6), Side::On);
        assert_eq!(p.side(Vec3::new(5.0, -2.0, 3.0), 1e-6), Side::Below);
    }

    #[test]
    fn closest_point_is_the_foot_of_the_perpendicular() {
        // Plane x + y = 0 (n = (1,1,0)/√2, d = 0); from (2,0,5) the foot is (1,−1,5).
        let p = Plane::new(Vec3::new(1.0, 1.0, 0.0), 0.0).unwrap();
        let q = p.closest_point(Vec3::new(2.0, 0.0, 5.0));
        assert!((q - Vec3::new(1.0, -1.0, 5.0)).length() < 1e-6);
        assert_eq!(p.side(q, 1e-6), Side::On);
    }
}
