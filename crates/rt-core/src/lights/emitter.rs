//! Emissive objects as area lights, for global illumination.
//!
//! An object whose material has an `emission` gives off that radiance from
//! the side its geometric normal points to (a one-sided diffuse emitter, as
//! pbrt-v4's `DiffuseAreaLight` and Mitsuba 3's `area` emitter). Under global
//! illumination each such object is also a light that next-event estimation
//! samples ([`crate::lights::light_sampler`]):
//!
//! - a **sphere** by the cone of directions it subtends from the shaded
//!   point ([`SphereCone`]), density `1/(2π·(1 − cos θ_max))`;
//! - a **triangle, polygon, box or mesh** by area: a triangle chosen in
//!   proportion to its area (a polygon is cut into triangles, a box into
//!   twelve), then a uniform point on it; the density over area is
//!   `1/A` for the whole object, and over solid angle `r²/(A·|cos θ_l|)`
//!   (pbrt-v4 §4.2.3);
//! - a **parallelogram** (a four-cornered polygon with `p₀ + p₂ = p₁ + p₃`
//!   as computed, as a rectangular lamp has) by area too, but as one piece: the
//!   point `p₀ + u·(p₁ − p₀) + v·(p₃ − p₀)` is uniform over it for (u, v)
//!   uniform in [0,1)², a linear map with constant Jacobian `A`, so the
//!   density is the same `1/A`; there is no triangle to choose, no square
//!   root, and the sampler's stratification of (u, v) carries over to the
//!   lamp unwarped;
//! - an emissive **plane** has no finite area to sample: it lights the scene
//!   only through rays that happen to hit it.

use thiserror::Error;

use crate::geometry::primitive::Primitive;
use crate::geometry::triangle::geometric_normal;
use crate::lights::light::SphereCone;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, normalize_robust};

/// Why an emissive object cannot be a light.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum EmitterError {
    /// A polygon whose edges cross: its area cannot be sampled.
    #[error("an emissive polygon must be simple (its edges must not cross)")]
    SelfCrossingPolygon,
}

/// One emissive object, as a light.
#[derive(Clone, Debug, PartialEq)]
pub struct Emitter {
    /// The object's index in the scene's object list.
    pub object: usize,
    /// The radiance it gives off from its front side.
    pub radiance: Color,
    shape: Shape,
}

/// The sampled shape of an emitter.
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    /// A sphere, sampled by solid angle.
    Sphere { center: Vec3, radius: Real },
    /// Triangles, sampled by area: the corners and normals of the
    /// non-degenerate ones, the running sums of their areas from 0 (one
    /// more than the triangles: triangle `i` spans `cumulative[i]` to
    /// `cumulative[i + 1]`, with no branch for the first), and the total.
    Triangles { corners: Vec<[Vec3; 3]>, normals: Vec<Vec3>, cumulative: Vec<Real>, area: Real },
    /// A parallelogram, sampled by area as one piece: the corner `origin`,
    /// the `edges` from it to its two neighbours, its unit `normal` (the
    /// polygon's), its `area` `|e₁ × e₂|`, and its two triangles (for
    /// [`Emitter::triangles`]).
    Parallelogram { origin: Vec3, edges: [Vec3; 2], normal: Vec3, area: Real, corners: [[Vec3; 3]; 2] },
    /// An infinite plane: not sampled.
    Unbounded,
}

/// A point on an emitter chosen for a shaded point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// Unit direction from the shaded point towards the emitter.
    pub wi: Vec3,
    /// Distance to the sampled point along `wi`.
    pub distance: Real,
    /// Radiance arriving along `-wi` (zero from the emitter's back).
    pub radiance: Color,
    /// The density of `wi` over solid angle.
    pub pdf: Real,
}

impl Emitter {
    /// The light of object `object`, shaped `primitive`, giving off `radiance`.
    pub fn new(object: usize, primitive: &Primitive, radiance: Color) -> Result<Self, EmitterError> {
        let corners: Vec<[Vec3; 3]> = match primitive {
            Primitive::Sphere(s) => {
                let shape = Shape::Sphere { center: s.center(), radius: s.radius() };
                return Ok(Self { object, radiance, shape });
            }
            Primitive::Plane(_) => return Ok(Self { object, radiance, shape: Shape::Unbounded }),
            Primitive::Triangle(t) => vec![t.corners()],
            Primitive::Polygon(p) => {
                if let Some(shape) = parallelogram(p) {
                    return Ok(Self { object, radiance, shape });
                }
                p.triangulate().ok_or(EmitterError::SelfCrossingPolygon)?
            }
            Primitive::Aabb(b) => box_triangles(b.min(), b.max()),
            Primitive::Mesh(m) => (0..m.triangle_count()).map(|i| m.triangle(i)).collect(),
        };
        let mut kept = Vec::with_capacity(corners.len());
        let mut normals = Vec::with_capacity(corners.len());
        let mut cumulative = Vec::with_capacity(corners.len() + 1);
        cumulative.push(0.0);
        let mut area: Real = 0.0;
        for [a, b, c] in corners {
            let Some(n) = geometric_normal(a, b, c) else { continue };
            area += 0.5 * (b - a).cross(c - a).length();
            kept.push([a, b, c]);
            normals.push(n);
            cumulative.push(area);
        }
        let shape = Shape::Triangles { corners: kept, normals, cumulative, area };
        Ok(Self { object, radiance, shape })
    }

    /// The triangles it is sampled on (none for a sphere or a plane), each
    /// wound so that `(b − a) × (c − a)` points to the side that glows.
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        match &self.shape {
            Shape::Triangles { corners, .. } => corners,
            Shape::Parallelogram { corners, .. } => corners,
            _ => &[],
        }
    }

    /// The power it gives off, `π·L·A` (the mean of the colour channels), for
    /// choosing among lights; 0 for a plane, which is never sampled.
    pub fn power(&self) -> Real {
        let l = (self.radiance.element_sum() / 3.0) as Real;
        let pi = std::f64::consts::PI as Real;
        match &self.shape {
            Shape::Sphere { radius, .. } => pi * l * 4.0 * pi * radius * radius,
            Shape::Triangles { area, .. } | Shape::Parallelogram { area, .. } => pi * l * area,
            Shape::Unbounded => 0.0,
        }
    }

    /// A direction from `p` towards the emitter for (u, v) ∈ [0,1)².
    /// Inlined into the path tracer's loop, so that the sample stays in
    /// registers (returned through memory, it was read back with loads
    /// wider than the stores that wrote it, a store-to-load forwarding
    /// stall).
    #[inline(always)]
    pub fn sample(&self, p: Vec3, (u, v): (Real, Real)) -> Option<EmitterSample> {
        match &self.shape {
            Shape::Sphere { center, radius } => {
                let axis = *center - p;
                let d = axis.length();
                // From inside, the sphere's emitting (outer) side faces away.
                if !(d > *radius && d.is_finite()) {
                    return None;
                }
                let cone = SphereCone::new(d, *radius);
                let (wi, distance) = cone.sample(axis / d, u, v);
                Some(EmitterSample { wi, distance, radiance: self.radiance, pdf: cone.pdf() })
            }
            Shape::Triangles { corners, normals, cumulative, area } => {
                // Choose a triangle by area, and reuse u within it.
                let target = u * area;
                let i = cumulative[1..].partition_point(|&c| c <= target).min(corners.len() - 1);
                let start = cumulative[i];
                let width = cumulative[i + 1] - start;
                let u = if width > 0.0 { ((target - start) / width).clamp(0.0, 1.0) } else { 0.5 };
                let [a, b, c] = corners[i];
                // A uniform point on the triangle (pbrt-v4 §A.5.4, `SampleUniformTriangle`).
                let su = u.sqrt();
                let (b0, b1) = (1.0 - su, v * su);
                let x = a * b0 + b * b1 + c * (1.0 - b0 - b1);
                self.towards(p, x, normals[i], *area)
            }
            Shape::Parallelogram { origin, edges, normal, area, .. } => {
                self.towards(p, *origin + edges[0] * u + edges[1] * v, *normal, *area)
            }
            Shape::Unbounded => None,
        }
    }

    /// The sample towards the point `x` of an emitter sampled by area
    /// (total `area`) whose unit normal there is `normal`: density
    /// `r²/(A·cos θ_l)` over solid angle; `None` from behind it.
    #[inline(always)]
    fn towards(&self, p: Vec3, x: Vec3, normal: Vec3, area: Real) -> Option<EmitterSample> {
        let to = x - p;
        let distance = to.length();
        let wi = normalize_robust(to)?;
        let cos_light = -wi.dot(normal);
        if cos_light <= 0.0 {
            return None; // The back of the emitter: no light towards p.
        }
        let pdf = distance * distance / (area * cos_light);
        pdf.is_finite().then_some(EmitterSample { wi, distance, radiance: self.radiance, pdf })
    }

    /// The density over solid angle with which [`Emitter::sample`] picks the
    /// direction `wi` from `p`, where a ray along it meets the emitter at
    /// `distance` with unit geometric normal `normal`.
    #[inline]
    pub fn pdf(&self, p: Vec3, wi: Vec3, distance: Real, normal: Vec3) -> Real {
        match &self.shape {
            Shape::Sphere { center, radius } => {
                let d = (*center - p).length();
                if d > *radius { SphereCone::new(d, *radius).pdf() } else { 0.0 }
            }
            Shape::Triangles { area, .. } | Shape::Parallelogram { area, .. } => {
                let cos_light = wi.dot(normal).abs();
                if cos_light > 0.0 { distance * distance / (area * cos_light) } else { 0.0 }
            }
            Shape::Unbounded => 0.0,
        }
    }
}

/// The polygon `p` as a [`Shape::Parallelogram`], if it is one: four
/// corners whose sums `p₀ + p₂` and `p₁ + p₃` come out equal in every
/// coordinate (so the map's far corner `p₀ + e₁ + e₂` is `p₂` to within the
/// rounding of one addition), and a finite, non-zero area. No tolerance
/// beyond that: a quadrilateral that is only nearly a parallelogram would
/// be sampled a little outside itself, so it stays with the triangles.
fn parallelogram(p: &crate::geometry::polygon::Polygon) -> Option<Shape> {
    let &[p0, p1, p2, p3] = p.points() else { return None };
    if p0 + p2 != p1 + p3 {
        return None;
    }
    let edges = [p1 - p0, p3 - p0];
    let area = edges[0].cross(edges[1]).length();
    (area > 0.0 && area.is_finite()).then_some(Shape::Parallelogram {
        origin: p0,
        edges,
        normal: p.normal(),
        area,
        corners: [[p0, p1, p2], [p0, p2, p3]],
    })
}

/// The twelve triangles of a box's faces, each wound so its normal points out.
fn box_triangles(lo: Vec3, hi: Vec3) -> Vec<[Vec3; 3]> {
    let corner = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z })
    };
    let mut out = Vec::with_capacity(12);
    for axis in 0..3 {
        for high in [false, true] {
            // The face's four corners, counter-clockwise seen from outside.
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let at = |a: bool, b: bool| {
                let mut bits = [false; 3];
                bits[axis] = high;
                bits[u] = a;
                bits[v] = b;
                corner(bits[0], bits[1], bits[2])
            };
            let (p00, p10, p11, p01) = (at(false, false), at(true, false), at(true, true), at(false, true));
            // (u × v) is +axis: this order faces +axis; reverse it for the low face.
            if high {
                out.push([p00, p10, p11]);
                out.push([p00, p11, p01]);
            } else {
                out.push([p00, p11, p10]);
                out.push([p00, p01, p11]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::geometry::aabb::Aabb;
    use crate::geometry::mesh::Mesh;
    use crate::geometry::sphere::Sphere;
    use crate::geometry::triangle::Triangle;
    use crate::math::ray::{Interval, Ray};
    use crate::math::real::to_f64;
    use crate::math::real::{narrow, widen};
    use crate::sampling::sampler::SampleRng;
    use crate::testing::chi_square::{self, Draw, SphereGrid};

    #[test]
    fn a_sphere_emitter_is_sampled_off_the_origin_and_never_from_inside_or_on_it() {
        // Radius 1.5 at (2, 3, −1), seen from (−4, 1, 2): every sample ends on
        // the sphere's near side, with the cone's density, which `pdf` gives
        // back. From inside and from its surface (exactly 1.5 from the
        // centre) its glowing side faces away: no sample, density 0.
        let center = Vec3::new(2.0, 3.0, -1.0);
        let e = Emitter::new(0, &Primitive::Sphere(Sphere::new(center, 1.5).unwrap()), Color::ONE).unwrap();
        let p = Vec3::new(-4.0, 1.0, 2.0);
        let cone = crate::lights::light::SphereCone::new((center - p).length(), 1.5);
        for k in 0..64 {
            let s = e.sample(p, SampleRng::new(k, 1, 1).next_pair()).unwrap();
            let on = p + s.wi * s.distance - center;
            assert!((on.length() - 1.5).abs() < 1e-4 && on.dot(p - center) > 0.0, "sample {k} ends at {on}");
            assert_eq!((s.pdf, e.pdf(p, s.wi, s.distance, on / 1.5)), (cone.pdf(), cone.pdf()));
        }
        for q in [center + Vec3::X * 0.5, center + Vec3::Y * 1.5] {
            assert_eq!(e.sample(q, (0.3, 0.6)), None, "from {q}");
            assert_eq!(e.pdf(q, Vec3::X, 1.0, Vec3::X), 0.0, "from {q}");
        }
    }

    #[test]
    fn an_emitters_power_is_pi_times_its_radiance_times_its_area() {
        // Radiance (1, 2, 3): mean L = 2. A right triangle of legs 2 (area 2)
        // gives π·2·2; a sphere of radius 1.5 (area 9π) gives π·2·9π.
        let pi = std::f64::consts::PI as Real;
        let radiance = Color::new(1.0, 2.0, 3.0);
        let triangle = Triangle::new(Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)).unwrap();
        let t = Emitter::new(0, &Primitive::Triangle(triangle), radiance).unwrap();
        assert!((t.power() - 4.0 * pi).abs() < 1e-5, "{}", t.power());
        // Its density where a ray meets it edge-on is 0, not infinite.
        assert_eq!(t.pdf(Vec3::new(-1.0, 0.5, 0.0), Vec3::X, 1.0, Vec3::Z), 0.0);
        let s = Emitter::new(0, &Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.5).unwrap()), radiance).unwrap();
        assert!((s.power() - 18.0 * pi * pi).abs() < 1e-4, "{}", s.power());
    }

    #[test]
    fn a_number_rounded_up_to_one_still_samples_the_last_triangle() {
        // u is drawn from [0, 1); rounded up to 1, u·area equals the last
        // cumulative area and the choice must stay on the last triangle.
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE).unwrap();
        let e = Emitter::new(0, &Primitive::Aabb(b), Color::ONE).unwrap();
        let s = e.sample(Vec3::new(0.5, 0.5, -3.0), (1.0, 0.5));
        assert!(s.is_none_or(|s| s.pdf.is_finite() && s.wi.is_finite()), "{s:?}");
    }

    #[test]
    fn box_faces_point_outward_and_cover_its_surface() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(2.0, 1.0, 4.0)).unwrap();
        let triangles = box_triangles(b.min(), b.max());
        let mut area = 0.0;
        for [p, q, r] in &triangles {
            let n = geometric_normal(*p, *q, *r).unwrap();
            let centre = (*p + *q + *r) / 3.0;
            assert!(n.dot(centre - b.center()) > 0.0, "inward face {n}");
            area += 0.5 * (*q - *p).cross(*r - *p).length();
        }
        assert!((area - b.surface_area()).abs() < 1e-5, "{area} vs {}", b.surface_area());
    }

    /// Estimates ∫ L·cos θ dω over the hemisphere above `p` (normal +y) seen
    /// by sampling `e`, i.e. the irradiance the emitter gives `p`.
    fn irradiance(e: &Emitter, p: Vec3, n: usize) -> f64 {
        let mut rng = SampleRng::new(1, 1, 1);
        let mut sum = 0.0;
        for _ in 0..n {
            if let Some(s) = e.sample(p, rng.next_pair()) {
                let cos = s.wi.y.max(0.0);
                sum += (s.radiance.x as f64) * to_f64(cos) / to_f64(s.pdf);
            }
        }
        sum / n as f64
    }

    /// A regular `n`-gon of radius `r` in the plane y = `h`, centred on the y axis, facing down.
    fn disk(n: usize, r: Real, h: Real) -> crate::geometry::polygon::Polygon {
        let points = (0..n)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI as Real * k as Real / n as Real;
                Vec3::new(r * a.cos(), h, r * a.sin())
            })
            .collect();
        crate::geometry::polygon::Polygon::new(points).unwrap()
    }

    #[test]
    fn a_disk_lights_a_point_below_it_by_its_form_factor() {
        // A disk of radius R and radiance L at height h gives the point below
        // its centre the irradiance π·L·R²/(h² + R²); here R = h = 1: π/2.
        let polygon = disk(256, 1.0, 1.0);
        assert_eq!(polygon.normal(), -Vec3::Y);
        let e = Emitter::new(0, &Primitive::Polygon(polygon.clone()), Color::ONE).unwrap();
        let got = irradiance(&e, Vec3::ZERO, 400_000);
        let expected = std::f64::consts::FRAC_PI_2;
        assert!((got - expected).abs() < 0.01 * expected, "{got} vs {expected}");
        // The same disk wound the other way faces up: no light below it.
        let mut up = polygon.points().to_vec();
        up.reverse();
        let e = Emitter::new(
            0,
            &Primitive::Polygon(crate::geometry::polygon::Polygon::new(up).unwrap()),
            Color::ONE,
        )
        .unwrap();
        assert_eq!(irradiance(&e, Vec3::ZERO, 1000), 0.0);
    }

    #[test]
    fn a_sphere_lights_a_point_like_a_point_light_of_the_same_intensity() {
        // A sphere of radius R and radiance L has intensity π·R²·L: at distance
        // d straight above, the irradiance is π·L·R²/d² (exactly, for a sphere).
        let (r, d) = (0.5 as Real, 4.0 as Real);
        let sphere = Sphere::new(Vec3::new(0.0, d, 0.0), r).unwrap();
        let e = Emitter::new(0, &Primitive::Sphere(sphere), Color::ONE).unwrap();
        let expected = std::f64::consts::PI * to_f64(r * r / (d * d));
        let got = irradiance(&e, Vec3::ZERO, 100_000);
        assert!((got - expected).abs() < 2e-3 * expected + 1e-5, "{got} vs {expected}");
    }

    #[test]
    fn the_density_of_a_sampled_direction_is_what_pdf_says_where_the_ray_meets_the_emitter() {
        let t = Triangle::new(Vec3::new(-1.0, 2.0, 0.0), Vec3::new(1.0, 2.0, 1.0), Vec3::new(0.5, 3.0, -1.0))
            .unwrap();
        let primitive = Primitive::Triangle(t);
        // Wound to face away from the origin: sample from the side it faces.
        let p = 2.0 * t.corners().iter().sum::<Vec3>() / 3.0 + 3.0 * t.normal();
        let e = Emitter::new(0, &primitive, Color::ONE).unwrap();
        let mut rng = SampleRng::new(3, 4, 5);
        for _ in 0..100 {
            let s = e.sample(p, rng.next_pair()).unwrap();
            let hit = primitive.intersect(&Ray::new(p, s.wi), Interval::new(0.0, Real::INFINITY)).unwrap();
            assert!((hit.t - s.distance).abs() < 1e-4 * s.distance);
            let pdf = e.pdf(p, s.wi, hit.t, hit.normal);
            assert!((pdf - s.pdf).abs() < 1e-3 * s.pdf, "{pdf} vs {}", s.pdf);
        }
    }

    #[test]
    fn only_an_exact_parallelogram_is_sampled_as_one_piece_of_the_same_area_and_normal() {
        let polygon = |points: Vec<Vec3>| crate::geometry::polygon::Polygon::new(points).unwrap();
        // The Cornell box's lamp: a rectangle, glowing downwards.
        let lamp = polygon(vec![
            Vec3::new(2.13, 5.48, 2.27),
            Vec3::new(3.43, 5.48, 2.27),
            Vec3::new(3.43, 5.48, 3.32),
            Vec3::new(2.13, 5.48, 3.32),
        ]);
        let e = Emitter::new(0, &Primitive::Polygon(lamp.clone()), Color::ONE).unwrap();
        let Shape::Parallelogram { normal, area, .. } = e.shape else { panic!("{:?}", e.shape) };
        assert_eq!(normal, lamp.normal());
        assert_eq!(normal, -Vec3::Y);
        assert!((area - 1.3 * 1.05).abs() < 1e-5, "{area}");
        let below = Vec3::new(2.5, 0.0, 2.5);
        let s = e.sample(below, (0.25, 0.75)).unwrap();
        let on = below + s.wi * s.distance;
        assert!((on - Vec3::new(2.13 + 0.25 * 1.3, 5.48, 2.27 + 0.75 * 1.05)).length() < 1e-5, "{on}");
        // Its triangles (for exports) cover it with the same winding.
        assert_eq!(e.triangles().len(), 2);
        for [a, b, c] in e.triangles() {
            assert!(geometric_normal(*a, *b, *c).unwrap().dot(normal) > 0.999);
        }
        // A corner moved by a little: two triangles, as any polygon.
        let mut points = lamp.points().to_vec();
        points[3].x += 0.01;
        let e = Emitter::new(0, &Primitive::Polygon(polygon(points)), Color::ONE).unwrap();
        assert!(matches!(e.shape, Shape::Triangles { .. }), "{:?}", e.shape);
        // Five corners: triangles.
        let e = Emitter::new(0, &Primitive::Polygon(disk(5, 1.0, 1.0)), Color::ONE).unwrap();
        assert!(matches!(e.shape, Shape::Triangles { .. }), "{:?}", e.shape);
    }

    #[test]
    fn a_square_lamp_lights_a_point_below_its_centre_by_its_form_factor() {
        // A square of side 2a at height h, radiance L, gives the point below its
        // centre E = 4·L·(a/√(a² + h²))·atan(a/√(a² + h²)) (four right
        // rectangles of sides a, a: the form factor of a rectangle seen from a
        // point below its corner, Howell's catalogue C-11); a = h = 1 here.
        let square = crate::geometry::polygon::Polygon::new(vec![
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ])
        .unwrap();
        assert_eq!(square.normal(), -Vec3::Y);
        let e = Emitter::new(0, &Primitive::Polygon(square), Color::ONE).unwrap();
        assert!(matches!(e.shape, Shape::Parallelogram { .. }));
        let s = 1.0 / 2f64.sqrt();
        let expected = 4.0 * s * s.atan();
        let got = irradiance(&e, Vec3::ZERO, 400_000);
        assert!((got - expected).abs() < 0.01 * expected, "{got} vs {expected}");
    }

    #[test]
    fn a_self_crossing_emissive_polygon_is_refused() {
        assert_eq!(
            Emitter::new(0, &Primitive::Polygon(crate::geometry::polygon::tests::pentagram()), Color::ONE),
            Err(EmitterError::SelfCrossingPolygon)
        );
    }

    /// The χ² test of [`Emitter::sample`]'s directions from `p` against
    /// [`Emitter::pdf`] where a ray along each meets `primitive` (0 where it
    /// misses, and where it meets the emitter's back, which gives no light:
    /// `sample` never draws it and the path tracer never asks `pdf` there).
    /// `samples` draws on a 20 × 40 equal-area grid of the cap about
    /// `axis` that holds the emitter (`u_max` in 1 − cos θ), α ≈ 10⁻⁴.
    fn assert_directions_follow_the_pdf(
        name: &str,
        primitive: &Primitive,
        p: Vec3,
        (axis, u_max): (DVec3, f64),
        samples: usize,
    ) {
        let e = Emitter::new(0, primitive, Color::ONE).unwrap();
        let grid = SphereGrid::cap(axis, u_max.min(2.0), 20, 40);
        let draw = |rng: &mut SampleRng| match e.sample(p, rng.next_pair()) {
            Some(s) => Draw::At(widen(s.wi)),
            None => Draw::Nothing,
        };
        // A mesh's own intersection is slow for a million queries: its
        // triangles one by one instead.
        let surface: Vec<Primitive> = match primitive {
            Primitive::Mesh(m) => (0..m.triangle_count())
                .map(|i| {
                    let [a, b, c] = m.triangle(i);
                    Primitive::Triangle(Triangle::new(a, b, c).unwrap())
                })
                .collect(),
            other => vec![other.clone()],
        };
        let pdf = |wi: DVec3| {
            let wi = narrow(wi);
            let ray = Ray::new(p, wi);
            let hit = surface
                .iter()
                .filter_map(|s| s.intersect(&ray, Interval::new(0.0, Real::INFINITY)))
                .min_by(|a, b| a.t.total_cmp(&b.t));
            match hit {
                Some(hit) if wi.dot(hit.normal) < 0.0 => to_f64(e.pdf(p, wi, hit.t, hit.normal)),
                _ => 0.0,
            }
        };
        chi_square::directions(name, &grid, samples, draw, &pdf);
    }

    /// The axis from `p` to the centroid of the emitter's corners, and the
    /// cap about it that holds them all (so the whole emitter: the cone of
    /// directions within an angle of the axis is convex), widened by 5 %.
    fn cap_of_corners(primitive: &Primitive, p: Vec3) -> (DVec3, f64) {
        let e = Emitter::new(0, primitive, Color::ONE).unwrap();
        let corners: Vec<DVec3> = e.triangles().iter().flatten().map(|&c| widen(c) - widen(p)).collect();
        let axis = corners.iter().map(|c| c.normalize()).sum::<DVec3>().normalize();
        let u_max = corners.iter().map(|c| 1.0 - c.normalize().dot(axis)).fold(0.0, f64::max);
        (axis, 1.05 * u_max)
    }

    #[test]
    fn sampled_directions_follow_the_density_pdf_reports_for_every_emitter_shape() {
        // 2·10⁵ draws per emitter seen from a point outside it: a disk
        // (32-gon), a triangle, a box (three faces visible, three facing
        // away: their draws give nothing), an octahedron mesh, and spheres
        // far and near (the cone's edge by exact f64 geometry).
        let mut shapes: Vec<(&str, Primitive, Vec3)> = vec![
            ("disk", Primitive::Polygon(disk(32, 1.0, 1.0)), Vec3::new(0.3, 0.0, 0.2)),
            (
                "triangle",
                Primitive::Triangle(
                    Triangle::new(
                        Vec3::new(-1.0, 2.0, 0.0),
                        Vec3::new(0.5, 3.0, -1.0),
                        Vec3::new(1.0, 2.0, 1.0),
                    )
                    .unwrap(),
                ),
                Vec3::new(0.2, 0.5, 0.1),
            ),
            (
                "box",
                Primitive::Aabb(Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(2.0, 1.0, 4.0)).unwrap()),
                Vec3::new(-2.0, 3.0, 0.5),
            ),
        ];
        // A slanted parallelogram (sampled as one piece) and a quadrilateral
        // that misses being one by a little (sampled as two triangles).
        let quad = |last: Vec3| {
            Primitive::Polygon(
                crate::geometry::polygon::Polygon::new(vec![
                    Vec3::new(-1.0, 2.0, -1.0),
                    Vec3::new(1.0, 2.0, -0.5),
                    Vec3::new(1.5, 2.0, 1.0),
                    last,
                ])
                .unwrap(),
            )
        };
        shapes.push(("parallelogram", quad(Vec3::new(-0.5, 2.0, 0.5)), Vec3::new(0.1, 0.3, -0.2)));
        shapes.push(("quadrilateral", quad(Vec3::new(-0.5, 2.0, 0.6)), Vec3::new(0.1, 0.3, -0.2)));
        // An octahedron wound outward: face (sx·x, sy·y, sz·z) faces out
        // when sx·sy·sz = +1, else its last two corners swap.
        let positions = vec![Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
        let mut faces = Vec::new();
        for (x, sx) in [(0u32, 1), (1, -1)] {
            for (y, sy) in [(2u32, 1), (3, -1)] {
                for (z, sz) in [(4u32, 1), (5, -1)] {
                    faces.push(if sx * sy * sz > 0 { [x, y, z] } else { [x, z, y] });
                }
            }
        }
        let octahedron = Mesh::new(positions, faces).unwrap();
        shapes.push(("octahedron", Primitive::Mesh(octahedron), Vec3::new(2.0, 1.5, -1.0)));
        for (name, primitive, p) in &shapes {
            assert_directions_follow_the_pdf(name, primitive, *p, cap_of_corners(primitive, *p), 200_000);
        }
        for (d, r) in [(4.0, 0.5), (1.2, 1.0)] {
            let center = Vec3::new(0.3, d, -0.2);
            let primitive = Primitive::Sphere(Sphere::new(center, r).unwrap());
            let u_max = 1.0 - (1.0 - (to_f64(r) / to_f64(d)).powi(2)).sqrt();
            let cap = (widen(center).normalize(), 1.05 * u_max);
            assert_directions_follow_the_pdf(
                &format!("sphere at {d}/{r}"),
                &primitive,
                Vec3::ZERO,
                cap,
                200_000,
            );
        }
    }
}
