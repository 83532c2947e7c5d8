//! Where a hit lies, how sure we are of it, and where secondary rays start.
//!
//! A hit point computed as `o + t·d` carries the rounding error of `t` (which
//! can be large for grazing rays and far surfaces) and of the sum. Each
//! primitive first *reprojects* it onto its own surface (the sphere along its
//! radius, a plane or triangle along its normal, a box face by snapping one
//! coordinate), which leaves a small error that can be bounded per component
//! with pbrt's γₙ ([`crate::math::real::gamma`]).
//!
//! A secondary ray (shadow, reflection, refraction, ambient occlusion) then
//! starts from that point pushed along the geometric normal, towards the side
//! the ray leaves on, by the error bound projected on the normal, and one
//! more float outward per component ([`offset_ray_origin`]). The origin is
//! then provably on the right side of the surface, so the ray cannot hit it
//! again at `t ≈ 0`, at any distance from the world origin, with no
//! hand-tuned epsilon. This is pbrt-v4's method (Pharr, Jakob, Humphreys,
//! *Physically Based Rendering*, 4th ed., §6.8.4–6.8.6, `OffsetRayOrigin`).

use crate::math::real::{Real, Vec3, gamma};

/// A point on a surface with a per-component bound on its distance from the
/// exact surface, and the surface's unit geometric normal there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The point, world units.
    pub p: Vec3,
    /// `|p_exact − p| ≤ error` componentwise, world units.
    pub error: Vec3,
    /// Unit geometric normal (the primitive's own orientation, see [`crate::geometry::hit::Hit`]).
    pub normal: Vec3,
}

impl SurfacePoint {
    /// Where a ray leaving along `dir` starts: see [`offset_ray_origin`].
    #[inline(always)]
    pub fn spawn_origin(&self, dir: Vec3) -> Vec3 {
        offset_ray_origin(self.p, self.error, self.normal, dir)
    }
}

/// `p` pushed off its surface towards the side `dir` points to.
///
/// The push is `(|n|·error)·n` (the error bound measured along the normal),
/// negated if `dir·n < 0`, and each component touched by the normal is then
/// moved one more float away from the surface, so the rounding of the sum
/// cannot bring it back (pbrt-v4 `OffsetRayOrigin`, with the extra float also
/// applied when the bound is exactly zero, as on a box face).
///
/// Inlined: called out of line, its vectors went through memory and the
/// reload of `n` and `error` stalled on the stores that had just written them.
#[inline(always)]
pub fn offset_ray_origin(p: Vec3, error: Vec3, n: Vec3, dir: Vec3) -> Vec3 {
    let side: Real = if dir.dot(n) < 0.0 { -1.0 } else { 1.0 };
    let push = n * (n.abs().dot(error) * side);
    let mut origin = p + push;
    for axis in 0..3 {
        let outward = n[axis] * side;
        if outward > 0.0 {
            origin[axis] = origin[axis].next_up();
        } else if outward < 0.0 {
            origin[axis] = origin[axis].next_down();
        }
    }
    origin
}

/// `p` projected onto the plane `x·n = d` (n unit), with its error bound.
///
/// `q = p − (p·n − d)·n`. The signed distance `s = p·n − d` is off by at most
/// `γ₄(|p|·|n| + |d|)`, each component of `q` by `γ₂(|pᵢ| + |s·nᵢ|)` more, and
/// `plane_error` (the plane's own uncertainty, e.g. a triangle's normal
/// computed from its corners, as a distance) adds along the normal.
pub fn project_onto_plane(p: Vec3, n: Vec3, d: Real, plane_error: Real) -> (Vec3, Vec3) {
    let s = p.dot(n) - d;
    let q = p - s * n;
    let s_error = gamma(4) * (p.abs().dot(n.abs()) + d.abs());
    let error = gamma(2) * (p.abs() + (s * n).abs()) + (s_error + plane_error) * n.abs();
    (q, error)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::aabb::Aabb;
    use crate::geometry::plane::Plane;
    use crate::geometry::primitive::Primitive;
    use crate::geometry::sphere::Sphere;
    use crate::math::ray::{Interval, Ray};
    use crate::testing::test_support::{random_primitive, v};
    use proptest::prelude::*;

    /// Whether the triangle is no sliver: its least height is at least a
    /// tenth of its longest side, which is at least 0.3.
    fn well_shaped([a, b, c]: [Vec3; 3]) -> bool {
        let longest = [b - a, c - b, a - c].map(|e| e.length()).into_iter().fold(0.0, Real::max);
        (b - a).cross(c - a).length() >= 0.1 * longest * longest && longest >= 0.3
    }

    /// The f32 point `a` moved by `centre` (rounded to f32, as a scene file's would be).
    fn moved(a: [f32; 3], centre: Vec3) -> [f32; 3] {
        [0, 1, 2].map(|i| crate::math::real::to_f32(a[i] as Real + centre[i]))
    }

    const ALL: Interval = Interval::new(0.0, Real::INFINITY);

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]

        /// Secondary rays leave a surface for good: from a hit on a sphere,
        /// box, plane, triangle or polygon (all convex), a ray spawned on the
        /// outside, or on either side of a flat one, never hits that primitive
        /// again; from a mesh triangle, never that triangle. The primitives are
        /// well shaped (no slivers: every triangle's least height is at least
        /// a tenth of its longest side, box sides at least 0.3, sizes 0.3 to
        /// 8) and centred at the origin or 10³ to 10⁵ units from it in any
        /// direction; the ray leaves at any slope down to |d·n| = 10⁻⁷ and
        /// exactly along the surface (d·n = 0 as computed; for a solid, the
        /// side the offset rule then picks is the outside), towards any
        /// point of the primitive. The random mesh's triangles include
        /// slivers, some of them degenerate but for rounding (three of its
        /// vertices may lie on a line).
        #[test]
        fn spawned_rays_never_hit_their_own_surface_again(
            kind in 0u8..6,
            p in prop::array::uniform3(-4.0f32..4.0),
            q in prop::array::uniform3(-4.0f32..4.0),
            r in prop::array::uniform3(-4.0f32..4.0),
            aim in prop::array::uniform3(0.0f32..1.0),
            from in prop::array::uniform3(-20.0f32..20.0),
            leave in prop::array::uniform3(-1.0f32..1.0),
            slope in prop_oneof![Just(None), (-2.0f32..7.0, any::<bool>()).prop_map(Some)],
            place in prop::array::uniform3(-1.0f32..1.0),
            distance in prop_oneof![Just(0.0f32), (3.0f32..5.0).prop_map(|e| 10f32.powf(e))],
        ) {
            let centre = v(place).normalize_or(Vec3::X) * distance as Real;
            let at = |a: [f32; 3]| centre + v(a);
            let (a, b, c) = (v(p), v(q), v(r));
            let (s, t) = if aim[0] + aim[1] > 1.0 { (1.0 - aim[0], 1.0 - aim[1]) } else { (aim[0], aim[1]) };
            let (s, t) = (s as Real, t as Real);
            // The primitive, and a point of it (or near it) to aim at.
            let (primitive, target) = match kind % 6 {
                0 => {
                    let radius = 0.3 + q[0].abs() as Real;
                    let offset = (v(aim) * 2.0 - Vec3::ONE) * (0.5 * radius);
                    (Primitive::Sphere(Sphere::new(at(p), radius).unwrap()), at(p) + offset)
                }
                1 => {
                    let Ok(plane) = Plane::new(b, 0.0) else { return Ok(()) };
                    let plane = Plane::new(b, plane.normal().dot(at(p))).unwrap();
                    (Primitive::Plane(plane), plane.closest_point(at(r)))
                }
                2 => {
                    if (a - b).abs().min_element() < 0.3 {
                        return Ok(());
                    }
                    let bx = Aabb::from_corners(at(p), at(q));
                    (Primitive::Aabb(bx), bx.center() + (v(aim) - Vec3::splat(0.5)) * (b - a).abs() * 0.98)
                }
                k => {
                    if !well_shaped([a, b, c]) {
                        return Ok(());
                    }
                    let Some(primitive) = random_primitive(k, moved(p, centre), moved(q, centre), moved(r, centre))
                    else { return Ok(()) };
                    // A point of the triangle, of the parallelogram, or of one mesh triangle.
                    let [a, b, c] = match &primitive {
                        Primitive::Mesh(m) => m.triangle((aim[2] * m.triangle_count() as f32) as usize % m.triangle_count()),
                        _ => [at(p), at(q), at(r)],
                    };
                    let (s, t) = if k == 4 { (aim[0] as Real, aim[1] as Real) } else { (s, t) };
                    (primitive, a + (b - a) * s + (c - a) * t)
                }
            };
            let origin = at(from);
            let ray = Ray::new(origin, target - origin);
            let Some(hit) = primitive.intersect(&ray, ALL) else { return Ok(()) };
            let sp = primitive.surface_point(hit.primitive, hit.normal, ray.at(hit.t));
            // Leave along the surface, tilted off it by `slope` (or not at all).
            let n = hit.normal;
            let Some(along) = (v(leave) - n * v(leave).dot(n)).try_normalize() else { return Ok(()) };
            let dir = match slope {
                None => along,
                Some((e, up)) => (along + n * ((10.0 as Real).powf(-e as Real) * if up { 1.0 } else { -1.0 })).normalize(),
            };
            let flat = matches!(primitive, Primitive::Plane(_) | Primitive::Triangle(_) | Primitive::Polygon(_) | Primitive::Mesh(_));
            if !flat && dir.dot(n) < 0.0 {
                return Ok(()); // Into a solid: it may rightly hit the far side.
            }
            let spawned = Ray::new(sp.spawn_origin(dir), dir);
            match primitive.intersect(&spawned, ALL) {
                None => {}
                Some(again) => prop_assert!(
                    matches!(primitive, Primitive::Mesh(_)) && again.primitive != hit.primitive,
                    "{} hit again at t = {} (triangle {} after {}) from {} (error {}), leaving along {dir} (d·n = {:e})",
                    primitive.kind(), again.t, again.primitive, hit.primitive, sp.p, sp.error, dir.dot(n)
                ),
            }
        }
    }

    #[test]
    fn spawned_rays_leave_sliver_triangles_for_good() {
        // Thin triangles (4 long, 10⁻¹ to 10⁻⁸ high: their corner angles down
        // to 10⁻⁸), at the origin and 10³ and 5·10⁴ from it: from 2000 hits
        // on each, a ray spawned at any slope to either side never hits the
        // triangle again. The computed normal of a sliver is off by up to
        // γ·|e₁|·|e₂|/|e₁ × e₂|, not γ: with the latter, half of these rays
        // came back near the origin in f64 (up to a fifth in f32).
        use crate::geometry::triangle::Triangle;
        for far in [0.0 as Real, 1e3, 5e4] {
            for height in [1e-1 as Real, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8] {
                let centre = Vec3::new(-0.8, -0.53, -0.47).normalize() * far;
                let e = Vec3::new(0.3, -0.8, 2.2).normalize() * 4.0;
                let up = e.cross(Vec3::new(0.2, 0.9, 0.1)).normalize();
                let (a, b, c) = (centre, centre + e, centre + e * 0.37 + up * height);
                let Ok(t) = Triangle::new(a, b, c) else { continue };
                let triangle = Primitive::Triangle(t);
                let mut hits = 0;
                for k in 0..2000u32 {
                    let rng = &mut crate::sampling::sampler::SampleRng::new(k, 3, 9);
                    let (s, w) = rng.next_pair();
                    let (s, w) = if s + w > 1.0 { (1.0 - s, 1.0 - w) } else { (s, w) };
                    let target = a + (b - a) * s + (c - a) * w;
                    let (x, y) = rng.next_pair();
                    let origin = centre + Vec3::new(x * 20.0 - 10.0, y * 20.0 - 10.0, 7.0);
                    let ray = Ray::new(origin, target - origin);
                    let Some(hit) = triangle.intersect(&ray, ALL) else { continue };
                    hits += 1;
                    let sp = triangle.surface_point(0, hit.normal, ray.at(hit.t));
                    let (u, v) = rng.next_pair();
                    let dir = (hit.normal * (u - 0.5) * 2.0 + up.cross(hit.normal) * (v - 0.5)).normalize();
                    let spawned = Ray::new(sp.spawn_origin(dir), dir);
                    let again = triangle.intersect(&spawned, ALL);
                    assert!(
                        again.is_none(),
                        "{far} away, {height} high: hit again at t = {:e} from {} (error {}) along {dir}",
                        again.unwrap().t,
                        sp.p,
                        sp.error
                    );
                }
                assert!(hits > 0, "{far} away, {height} high");
            }
        }
    }

    #[test]
    fn the_origin_moves_to_the_side_the_ray_leaves_on() {
        let n = Vec3::Y;
        let up = offset_ray_origin(Vec3::ZERO, Vec3::splat(1e-3), n, Vec3::new(1.0, 1.0, 0.0));
        let down = offset_ray_origin(Vec3::ZERO, Vec3::splat(1e-3), n, Vec3::new(1.0, -1.0, 0.0));
        assert!(up.y > 1e-3 && down.y < -1e-3);
        assert_eq!((up.x, up.z, down.x, down.z), (0.0, 0.0, 0.0, 0.0));
    }

    #[test]
    fn a_zero_error_bound_still_moves_one_float_along_the_normal() {
        let p = Vec3::new(3.0, 1e5, -2.0);
        let o = offset_ray_origin(p, Vec3::ZERO, Vec3::Y, Vec3::Y);
        assert_eq!(o, Vec3::new(3.0, (1e5 as Real).next_up(), -2.0));
    }

    #[test]
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    fn projection_lands_on_the_plane_within_its_bound() {
        let n = Vec3::new(1.0, 2.0, 2.0) / 3.0;
        let d: Real = 1234.5;
        for p in [Vec3::new(1e4, -3.0, 7.0), Vec3::new(-2.0, 640.0, 5e3), Vec3::splat(0.1)] {
            let (q, error) = project_onto_plane(p, n, d, 0.0);
            // In f64 the distance of q from the plane is measured almost exactly.
            let wide = |v: Vec3| v.to_array().map(|x| x as f64);
            let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
            let (qd, nd) = (wide(q), wide(n));
            let distance = (dot(qd, nd) - d as f64).abs();
            let bound = dot(wide(error), nd.map(f64::abs));
            assert!(distance <= bound + 1e-12, "{p}: {distance} vs {error}");
        }
    }
}
