//! Spheres: centre and radius; inside/on/outside test and ray intersection.

use crate::geometry::aabb::Aabb;
use crate::geometry::geometry_error::GeometryError;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::{Placement, SphereTest};
use crate::geometry::surface::SurfacePoint;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, gamma};

/// Where a point lies relative to a closed surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Containment {
    /// Strictly inside, by more than the tolerance.
    Inside,
    /// Within the tolerance of the surface.
    On,
    /// Strictly outside, by more than the tolerance.
    Outside,
}

/// The sphere `|p − center| = radius`, world units. Normals point outward.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Sphere {
    center: Vec3,
    radius: Real,
}

impl Sphere {
    /// A sphere; the radius must be positive and finite, the centre finite.
    pub fn new(center: Vec3, radius: Real) -> Result<Self, GeometryError> {
        if !center.is_finite() {
            return Err(GeometryError::NotFinite("sphere center"));
        }
        if radius.is_nan() || radius <= 0.0 {
            return Err(GeometryError::SphereRadius(radius));
        }
        // The intersection uses r²: it must be a normal number.
        if !(radius * radius).is_normal() {
            return Err(GeometryError::SphereRadiusRange(radius));
        }
        Ok(Self { center, radius })
    }

    /// Centre, world units.
    pub fn center(&self) -> Vec3 {
        self.center
    }
    /// Radius, world units, > 0.
    pub fn radius(&self) -> Real {
        self.radius
    }

    /// Inside, on (|‖p − c‖ − r| ≤ `tolerance`) or outside the sphere.
    pub fn classify(&self, p: Vec3, tolerance: Real) -> Containment {
        let distance = (p - self.center).length() - self.radius;
        if distance.abs() <= tolerance {
            Containment::On
        } else if distance < 0.0 {
            Containment::Inside
        } else {
            Containment::Outside
        }
    }

    /// The box `center ± radius`.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_corners(self.center - self.radius, self.center + self.radius)
    }

    /// `p` (a computed hit) moved onto the sphere along its radius,
    /// `c + (p − c)·r/|p − c|`, with error `γ₆(|c| + |p − c|)` per component
    /// (the scaling costs ≤ γ₅ relative, the sum one more rounding; pbrt-v4 §6.8.5).
    pub fn surface_point(&self, p: Vec3, normal: Vec3) -> SurfacePoint {
        let offset = match (p - self.center).try_normalize() {
            Some(unit) => unit * self.radius,
            None => normal * self.radius,
        };
        let p = self.center + offset;
        SurfacePoint { p, error: gamma(6) * (self.center.abs() + offset.abs()), normal }
    }

    /// The nearest hit with `t` in `range`, from outside (near root) or from
    /// inside (far root).
    ///
    /// With `f = o − c`, the roots of `a·t² − 2b·t + (f·f − r²) = 0`, where
    /// `a = d·d` and `b = −f·d`, are `t = (b ± √Δ) / a`. Following Haines,
    /// Günther and Akenine-Möller, "Precision Improvements for Ray/Sphere
    /// Intersection" (*Ray Tracing Gems*, ch. 7, 2019):
    /// - `Δ = a·(r² − |l|²)` with `l = f + (b/a)·d`, the vector from the centre
    ///   to the ray's closest approach, instead of the cancelling `b² − a·(f·f − r²)`;
    /// - `q = b + sign(b)·√Δ`, roots `c/q` and `q/a`, so neither root is a
    ///   difference of nearly equal numbers.
    ///
    /// The hit point relative to the centre is `l ∓ (√Δ/a)·d` (near/far root),
    /// which gives the normal without subtracting two large coordinates.
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let f = ray.origin - self.center;
        let d = ray.dir;
        let a = d.dot(d);
        let b = -f.dot(d);
        let l = f + (b / a) * d;
        let r2 = self.radius * self.radius;
        let discriminant = a * (r2 - l.dot(l));
        if discriminant < 0.0 || discriminant.is_nan() {
            return None;
        }
        let root = discriminant.sqrt();
        let q = if b >= 0.0 { b + root } else { b - root };
        if q == 0.0 {
            return None; // b = Δ = 0: tangent at the origin itself, t = 0.
        }
        let c = f.dot(f) - r2;
        let (t0, t1) = (c / q, q / a);
        let (near, far) = if t0 <= t1 { (t0, t1) } else { (t1, t0) };
        let half_chord = (root / a) * d;
        let (t, to_hit) = if range.contains(near) {
            (near, l - half_chord)
        } else if range.contains(far) {
            (far, l + half_chord)
        } else {
            return None;
        };
        let normal =
            to_hit.try_normalize().unwrap_or_else(|| (ray.at(t) - self.center).normalize_or(Vec3::X));
        Some(PrimitiveHit { t, primitive: 0, normal })
    }

    /// The textbook quadratic: with `f = o − c`, `t = (−b ± √(b² − 4ac)) / 2a`
    /// for `a = d·d`, `b = 2 f·d`, `c = f·f − r²`; the nearer root in `range`,
    /// normal `(o + t·d − c) / r`.
    ///
    /// Two cancellations make it fail where [`Sphere::intersect`] does not:
    /// `c = f·f − r²` loses all of `r²` once `|f|² ≫ r²` (a small sphere far
    /// away: in f32 a radius-1 sphere 10⁴ units off is missed or hit with a
    /// wrong `t`), and `−b + √Δ` cancels for the root near the origin.
    pub fn intersect_textbook(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        let f = ray.origin - self.center;
        let d = ray.dir;
        let a = d.dot(d);
        let b = 2.0 * f.dot(d);
        let c = f.dot(f) - self.radius * self.radius;
        let discriminant = b * b - 4.0 * a * c;
        if discriminant.is_nan() || discriminant < 0.0 {
            return None;
        }
        let root = discriminant.sqrt();
        let (near, far) = ((-b - root) / (2.0 * a), (-b + root) / (2.0 * a));
        let t = [near, far].into_iter().find(|&t| range.contains(t))?;
        let normal = ((ray.at(t) - self.center) / self.radius).normalize_or(Vec3::X);
        Some(PrimitiveHit { t, primitive: 0, normal })
    }
}

impl Sphere {
    /// The course's numbers for `ray`, which hit this sphere at `t`
    /// ([`SphereTest`]): whether its origin is inside, on or outside
    /// ([`Sphere::classify`], within the rounding bound `γ₄(|o − c| + r)` of
    /// `|o − c| − r`), the course's quadratic and discriminant, and the two
    /// roots by the stable formulas of [`Sphere::intersect`] (Haines et al.,
    /// *Ray Tracing Gems* ch. 7), of which `t` is the nearer one.
    pub fn explain(&self, ray: &Ray, t: Real) -> SphereTest {
        let f = ray.origin - self.center;
        let d = ray.dir;
        let r2 = self.radius * self.radius;
        let (a, b, c) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - r2);
        let origin_distance = f.length() - self.radius;
        let tolerance = gamma(4) * (f.length() + self.radius);
        // The stable roots, as `intersect` computes them.
        let half_b = -f.dot(d);
        let l = f + (half_b / a) * d;
        let stable = a * (r2 - l.dot(l));
        let roots = (stable >= 0.0).then(|| {
            let root = stable.sqrt();
            let q = if half_b >= 0.0 { half_b + root } else { half_b - root };
            let (t0, t1) = (c / q, q / a);
            if t0 <= t1 { [t0, t1] } else { [t1, t0] }
        });
        SphereTest {
            center: self.center,
            radius: self.radius,
            origin_distance,
            origin: match self.classify(ray.origin, tolerance) {
                Containment::Inside => Placement::Inside,
                Containment::On => Placement::On,
                Containment::Outside => Placement::Outside,
            },
            quadratic: [a, b, c],
            discriminant: b * b - 4.0 * a * c,
            roots,
            far_root: roots.is_some_and(|[near, far]| (t - far).abs() < (t - near).abs()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    fn unit_sphere_at(center: Vec3) -> Sphere {
        Sphere::new(center, 1.0).unwrap()
    }

    #[test]
    fn ray_towards_the_centre_hits_the_near_side_with_an_outward_normal() {
        // Sphere at (0,0,5) r=1, ray from the origin along +z: |t·ẑ − 5ẑ| = 1 → t = 4 or 6.
        let hit =
            unit_sphere_at(Vec3::new(0.0, 0.0, 5.0)).intersect(&Ray::new(Vec3::ZERO, Vec3::Z), ALL).unwrap();
        assert_eq!(hit.t, 4.0);
        assert_eq!(hit.normal, -Vec3::Z);
    }

    #[test]
    fn t_is_for_the_rays_own_unnormalised_direction() {
        // Same ray with dir = (0,0,2): the hit at distance 4 has t = 2.
        let hit = unit_sphere_at(Vec3::new(0.0, 0.0, 5.0))
            .intersect(&Ray::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0)), ALL)
            .unwrap();
        assert_eq!(hit.t, 2.0);
    }

    #[test]
    fn off_centre_ray_hits_where_pythagoras_says() {
        // Ray y = 0.6 along +z: the sphere's surface is at z = 5 − √(1 − 0.36) = 4.2,
        // normal (0, 0.6, −0.8).
        let hit = unit_sphere_at(Vec3::new(0.0, 0.0, 5.0))
            .intersect(&Ray::new(Vec3::new(0.0, 0.6, 0.0), Vec3::Z), ALL)
            .unwrap();
        assert!((hit.t - 4.2).abs() < 1e-6);
        assert!((hit.normal - Vec3::new(0.0, 0.6, -0.8)).length() < 1e-6);
    }

    #[test]
    fn ray_from_inside_hits_the_far_side_with_the_outward_normal() {
        // From the centre of a radius-2 sphere along +x: t = 2, normal +x.
        let s = Sphere::new(Vec3::new(1.0, 1.0, 1.0), 2.0).unwrap();
        let hit = s.intersect(&Ray::new(Vec3::new(1.0, 1.0, 1.0), Vec3::X), ALL).unwrap();
        assert_eq!(hit.t, 2.0);
        assert_eq!(hit.normal, Vec3::X);
    }

    #[test]
    fn ray_pointing_away_misses() {
        let s = unit_sphere_at(Vec3::new(0.0, 0.0, 5.0));
        assert_eq!(s.intersect(&Ray::new(Vec3::ZERO, -Vec3::Z), ALL), None);
    }

    #[test]
    fn ray_passing_beside_misses() {
        // Closest approach 1.5 > r = 1.
        let s = unit_sphere_at(Vec3::new(0.0, 0.0, 5.0));
        assert_eq!(s.intersect(&Ray::new(Vec3::new(1.5, 0.0, 0.0), Vec3::Z), ALL), None);
    }

    #[test]
    fn hits_outside_the_interval_do_not_count() {
        // Roots 4 and 6: with max 3.9 nothing; with min 4.5 the far root.
        let s = unit_sphere_at(Vec3::new(0.0, 0.0, 5.0));
        let ray = Ray::new(Vec3::ZERO, Vec3::Z);
        assert_eq!(s.intersect(&ray, Interval::new(0.0, 3.9)), None);
        let far = s.intersect(&ray, Interval::new(4.5, Real::INFINITY)).unwrap();
        assert_eq!(far.t, 6.0);
        assert_eq!(far.normal, Vec3::Z);
    }

    #[test]
    fn far_tiny_sphere_is_hit_at_the_right_distance() {
        // r = 1 at 1e6 along +z: t = 1e6 − 1 exactly representable in f32.
        let s = unit_sphere_at(Vec3::new(0.0, 0.0, 1e6));
        let hit = s.intersect(&Ray::new(Vec3::ZERO, Vec3::Z), ALL).unwrap();
        assert_eq!(hit.t, 1e6 - 1.0);
        assert!((hit.normal + Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn radius_one_spheres_ten_thousand_to_ten_million_away_are_hit_at_the_exact_distance() {
        // Along the unit direction (0.36, −0.48, 0.8): the near side is at D − 1,
        // exactly representable in f32 for these D.
        let dir = Vec3::new(0.36, -0.48, 0.8);
        for d in [1e4 as Real, 1e5, 1e6, 1e7] {
            let hit = unit_sphere_at(dir * d).intersect(&Ray::new(Vec3::ZERO, dir), ALL).unwrap();
            assert_eq!(hit.t, d - 1.0, "D = {d}");
        }
    }

    #[test]
    fn a_huge_sphere_seen_from_just_above_is_hit_on_the_near_side() {
        // r = 1e5 with the eye 0.5 above the top (64 f32 ulps at 1e5): t ≈ 0.5, not 2e5.
        let r: Real = 1e5;
        let s = Sphere::new(Vec3::new(0.0, -r, 0.0), r).unwrap();
        let hit = s.intersect(&Ray::new(Vec3::new(0.0, 0.5, 0.0), -Vec3::Y), ALL).unwrap();
        assert!((hit.t - 0.5).abs() < 0.01, "t = {}", hit.t);
        assert_eq!(hit.normal, Vec3::Y);
    }

    #[test]
    fn classify_puts_points_inside_on_or_outside() {
        let s = Sphere::new(Vec3::new(1.0, 0.0, 0.0), 2.0).unwrap();
        assert_eq!(s.classify(Vec3::new(1.5, 0.0, 0.0), 1e-6), Containment::Inside);
        assert_eq!(s.classify(Vec3::new(3.0, 0.0, 0.0), 1e-6), Containment::On);
        assert_eq!(s.classify(Vec3::new(1.0, 2.0 + 1e-7, 0.0), 1e-6), Containment::On);
        assert_eq!(s.classify(Vec3::new(4.0, 0.0, 0.0), 1e-6), Containment::Outside);
    }

    #[test]
    fn radius_must_be_positive_and_finite() {
        for r in [0.0, -1.0, Real::NAN] {
            assert!(matches!(Sphere::new(Vec3::ZERO, r), Err(GeometryError::SphereRadius(_))));
        }
        let too_big = Real::MAX.sqrt() * 2.0;
        let too_small = Real::MIN_POSITIVE.sqrt() / 2.0;
        for r in [Real::INFINITY, too_big, too_small] {
            assert!(matches!(Sphere::new(Vec3::ZERO, r), Err(GeometryError::SphereRadiusRange(_))), "{r}");
        }
    }

    #[test]
    fn a_ray_that_touches_the_sphere_at_one_point_hits_it_there() {
        // Tangent: f = (1, 0, −5), d = +z, so b = 5, l = (1, 0, 0) and
        // Δ = a·(r² − |l|²) = 0 exactly; the double root is t = 5, at (1, 0, 0).
        let s = unit_sphere_at(Vec3::ZERO);
        let tangent = Ray::new(Vec3::new(1.0, 0.0, -5.0), Vec3::Z);
        let hit = s.intersect(&tangent, ALL).unwrap();
        assert_eq!((hit.t, hit.normal), (5.0, Vec3::X));
        // The textbook form's b² − 4ac = 100 − 4·1·25 = 0 exactly too.
        let hit = s.intersect_textbook(&tangent, ALL).unwrap();
        assert_eq!((hit.t, hit.normal), (5.0, Vec3::X));
        // Straight down onto the pole: the hit is (0, 1, 0) exactly, and both
        // methods give the pole's normal.
        let down = Ray::new(Vec3::new(0.0, 5.0, 0.0), -Vec3::Y);
        for hit in [s.intersect(&down, ALL), s.intersect_textbook(&down, ALL)] {
            assert_eq!(hit.map(|h| (h.t, h.normal)), Some((4.0, Vec3::Y)));
        }
        // A hair further out it misses.
        let beside = Ray::new(Vec3::new(1.0 + 4.0 * Real::EPSILON, 0.0, -5.0), Vec3::Z);
        assert_eq!(s.intersect(&beside, ALL), None);
    }

    #[test]
    fn surface_points_lie_on_the_sphere_within_their_error_bound() {
        // Points near the surface of spheres of several radii and centres,
        // moved onto it: each coordinate is within the stated bound of the
        // exact projection c + (p − c)·r/|p − c| (computed in f64), and the
        // bound is a few ulps of the coordinates, not more.
        use crate::math::real::{to_f64, widen};
        for (center, radius) in [
            (Vec3::ZERO, 1.0 as Real),
            (Vec3::new(3.0, -2.0, 5.0), 2.5),
            (Vec3::new(-1e3, 40.0, 7e2), 0.01),
            (Vec3::new(1e4, 1e4, -1e4), 300.0),
        ] {
            let s = Sphere::new(center, radius).unwrap();
            for k in 0..500u32 {
                let rng = &mut crate::sampling::sampler::SampleRng::new(k, 7, 3);
                let (u, v) = rng.next_pair();
                let z = 1.0 - 2.0 * u;
                let phi = 2.0 * std::f64::consts::PI as Real * v;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                let p = center + dir * radius * (1.0 + 1e-3 * (rng.next_pair().0 - 0.5));
                let sp = s.surface_point(p, dir);
                let f = widen(p) - widen(center);
                let exact = widen(center) + f * (to_f64(radius) / f.length());
                let off = (widen(sp.p) - exact).abs();
                let bound = widen(sp.error);
                assert!(
                    off.cmple(bound).all(),
                    "{center} r {radius}: {} off the sphere by {off}, bound {bound}",
                    sp.p
                );
                let ulps = widen(center.abs() + Vec3::splat(radius)) * to_f64(Real::EPSILON);
                assert!(bound.cmple(ulps * 8.0).all(), "bound {bound} against ulps {ulps}");
            }
            // The centre itself has no direction: it goes along the normal given.
            assert_eq!(s.surface_point(center, Vec3::Y).p, center + Vec3::Y * radius, "{center} r {radius}");
        }
    }

    #[test]
    fn the_textbook_quadratic_agrees_with_the_careful_test_where_nothing_cancels() {
        // Spheres a few radii from the ray's origin, from outside and from
        // inside: the two methods solve the same quadratic, so they hit and
        // miss alike and agree on t and the normal to rounding (f32: 10⁻⁵).
        for (center, radius) in [(Vec3::new(0.5, -0.3, 4.0), 1.5 as Real), (Vec3::new(0.2, 0.1, 0.3), 2.0)] {
            let s = Sphere::new(center, radius).unwrap();
            for k in 0..400u32 {
                let (u, v) = crate::sampling::sampler::SampleRng::new(k, 11, 5).next_pair();
                let dir = Vec3::new(u - 0.5, v - 0.5, 1.0) * (1.0 + u);
                let ray = Ray::new(Vec3::ZERO, dir);
                let (careful, textbook) = (s.intersect(&ray, ALL), s.intersect_textbook(&ray, ALL));
                assert_eq!(careful.is_some(), textbook.is_some(), "{center}, ray {k}");
                if let (Some(c), Some(t)) = (careful, textbook) {
                    assert!((c.t - t.t).abs() <= 1e-5 * c.t, "{center}, ray {k}: t {} against {}", t.t, c.t);
                    assert!((c.normal - t.normal).length() <= 1e-4, "{center}, ray {k}");
                }
            }
        }
    }

    #[test]
    fn bounds_contain_the_sphere() {
        let b = Sphere::new(Vec3::new(1.0, 2.0, 3.0), 0.5).unwrap().bounds();
        assert_eq!((b.min(), b.max()), (Vec3::new(0.5, 1.5, 2.5), Vec3::new(1.5, 2.5, 3.5)));
    }

    proptest::proptest! {
        /// Rays aimed at a random point of a random sphere hit it from outside
        /// (near root, surface point, outward normal) and, leaving that point
        /// outward under the cast rule, never hit it again.
        #[test]
        fn rays_aimed_at_a_sphere_hit_its_surface_and_leave_it_cleanly(
            center in proptest::array::uniform3(-1e3f32..1e3),
            radius in 0.01f32..100.0,
            theta in 0.0f32..std::f32::consts::PI,
            phi in 0.0f32..std::f32::consts::TAU,
            distance in 1.5f32..50.0,
            spread in proptest::array::uniform3(-0.3f32..0.3),
        ) {
            let c = Vec3::new(center[0] as Real, center[1] as Real, center[2] as Real);
            let r = radius as Real;
            let s = Sphere::new(c, r).unwrap();
            let dir_to_surface = Vec3::new(
                (theta.sin() * phi.cos()) as Real,
                theta.cos() as Real,
                (theta.sin() * phi.sin()) as Real,
            );
            let target = c + r * dir_to_surface;
            let offset = dir_to_surface + Vec3::new(spread[0] as Real, spread[1] as Real, spread[2] as Real);
            let origin = target + (distance as Real) * r * offset.normalize();
            proptest::prop_assume!(s.classify(origin, 1e-3 * r) == Containment::Outside);
            let ray = Ray::new(origin, target - origin);
            let hit = s.intersect(&ray, ALL);
            proptest::prop_assert!(hit.is_some());
            let hit = hit.unwrap();
            let p = ray.at(hit.t);
            let scale = crate::math::real::magnitude_scale(p);
            proptest::prop_assert!(((p - c).length() - r).abs() <= 1e-4 * r + 1e-5 * scale);
            proptest::prop_assert!((hit.normal.length() - 1.0).abs() < 1e-5);
            proptest::prop_assert!(hit.normal.dot(p - c) > 0.0);
            proptest::prop_assert!(hit.t <= 1.0 + 1e-4, "the aimed-at point is at t = 1 or beyond the near side");
            // Leave along the normal: no second hit on this convex surface.
            let out = Ray::new(p, hit.normal);
            let range = Interval::new(crate::math::real::cast_min_t(out.origin, out.dir), Real::INFINITY);
            proptest::prop_assert_eq!(s.intersect(&out, range), None);
        }
    }
}
