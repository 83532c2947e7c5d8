//! The primitive enum: one variant per kind of geometry, one `match` per operation.

use crate::geometry::aabb::Aabb;
use crate::geometry::hit::PrimitiveHit;
use crate::geometry::hit_test::HitTest;
use crate::geometry::mesh::Mesh;
use crate::geometry::method::{BoxMethod, Methods, SphereMethod};
use crate::geometry::plane::Plane;
use crate::geometry::polygon::Polygon;
use crate::geometry::sphere::Sphere;
use crate::geometry::surface::SurfacePoint;
use crate::geometry::triangle::Triangle;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3};

/// Every kind of geometry a scene object can be.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Primitive {
    /// See [`Sphere`].
    Sphere(Sphere),
    /// See [`Plane`]; the only unbounded primitive.
    Plane(Plane),
    /// See [`Aabb`].
    Aabb(Aabb),
    /// See [`Triangle`].
    Triangle(Triangle),
    /// See [`Polygon`].
    Polygon(Polygon),
    /// See [`Mesh`]. Not in serde's form: a scene cache stores meshes as
    /// arrays ([`Mesh::arrays`]).
    #[serde(skip)]
    Mesh(Mesh),
}

impl Primitive {
    /// The nearest hit with `t` in `range`, by the default (careful) routines.
    #[inline]
    pub fn intersect(&self, ray: &Ray, range: Interval) -> Option<PrimitiveHit> {
        self.intersect_with(ray, range, Methods::default())
    }

    /// The nearest hit with `t` in `range`, by the routines `methods` chooses.
    #[inline]
    pub fn intersect_with(&self, ray: &Ray, range: Interval, methods: Methods) -> Option<PrimitiveHit> {
        match self {
            Self::Sphere(s) => match methods.sphere {
                SphereMethod::Careful => s.intersect(ray, range),
                SphereMethod::Textbook => s.intersect_textbook(ray, range),
            },
            Self::Plane(p) => p.intersect(ray, range),
            Self::Aabb(b) => match methods.aabb {
                BoxMethod::Slab => b.intersect(ray, range),
                BoxMethod::SixPlane => b.intersect_six_plane(ray, range),
            },
            Self::Triangle(t) => t.intersect_with(ray, range, methods.triangle),
            Self::Polygon(p) => p.intersect(ray, range),
            Self::Mesh(m) => m.intersect_with(ray, range, methods.triangle),
        }
    }

    /// The shading normal at `p` on `primitive` (a mesh's interpolated
    /// vertex normals, [`Mesh::shading_normal`]), or `None` where it is the
    /// geometric normal.
    pub fn shading_normal(&self, primitive: usize, p: Vec3) -> Option<Vec3> {
        match self {
            Self::Mesh(m) => m.shading_normal(primitive, p),
            _ => None,
        }
    }

    /// The texture coordinates at `p` on `primitive` ([`Mesh::uv`]); `None`
    /// for primitives without them.
    pub fn uv(&self, primitive: usize, p: Vec3) -> Option<(Real, Real)> {
        match self {
            Self::Mesh(m) => m.uv(primitive, p),
            _ => None,
        }
    }

    /// The tangent frame `(∂p/∂u, ∂p/∂v)` at a hit on `primitive` with unit
    /// geometric `normal`: a mesh's along its texture coordinates
    /// ([`Mesh::tangents`]); elsewhere, and where those do not span the
    /// triangle, two unit vectors completing `normal` to an orthonormal frame.
    pub fn tangents(&self, primitive: usize, normal: Vec3) -> (Vec3, Vec3) {
        let along_uv = match self {
            Self::Mesh(m) => m.tangents(primitive),
            _ => None,
        };
        along_uv.unwrap_or_else(|| normal.any_orthonormal_pair())
    }

    /// The hit point `p = o + t·d` of a hit on `primitive` (the triangle
    /// index in a mesh) with geometric `normal`, moved onto the surface and
    /// given an error bound, so secondary rays can leave it safely.
    /// Inlined into its callers, so that the point comes back in registers
    /// (returned through memory, it was read back with loads wider than the
    /// stores that wrote it, a store-to-load forwarding stall).
    #[inline(always)]
    pub fn surface_point(&self, primitive: usize, normal: Vec3, p: Vec3) -> SurfacePoint {
        match self {
            Self::Sphere(s) => s.surface_point(p, normal),
            Self::Plane(pl) => pl.surface_point(p),
            Self::Aabb(b) => b.surface_point(p, normal),
            Self::Triangle(t) => t.surface_point(p),
            Self::Polygon(pg) => pg.surface_point(p),
            Self::Mesh(m) => m.surface_point(primitive, p),
        }
    }

    /// A box containing the primitive; `None` for an unbounded plane.
    pub fn bounds(&self) -> Option<Aabb> {
        match self {
            Self::Sphere(s) => Some(s.bounds()),
            Self::Plane(_) => None,
            Self::Aabb(b) => Some(*b),
            Self::Triangle(t) => Some(t.bounds()),
            Self::Polygon(p) => Some(p.bounds()),
            Self::Mesh(m) => Some(m.bounds()),
        }
    }

    /// The course's tests on a hit of `ray` at `t` on `primitive` (a mesh's
    /// triangle index) ([`HitTest`]): each primitive's own `explain`
    /// ([`Plane::explain`], [`Sphere::explain`], [`Aabb::explain`],
    /// [`Triangle::explain`], [`Polygon::explain`]; a mesh's triangle as a
    /// [`Triangle`]). `None` for a mesh triangle too thin to have a normal.
    pub fn explain(&self, primitive: usize, ray: &Ray, t: Real) -> Option<HitTest> {
        let p = ray.at(t);
        Some(match self {
            Self::Sphere(s) => HitTest::Sphere(s.explain(ray, t)),
            Self::Plane(pl) => HitTest::Plane(pl.explain(ray)),
            Self::Aabb(b) => HitTest::Box(b.explain(ray, t)),
            Self::Triangle(tri) => HitTest::Triangle(tri.explain(p)),
            Self::Polygon(pg) => HitTest::Polygon(pg.explain(p)),
            Self::Mesh(m) => {
                let [a, b, c] = m.triangle(primitive);
                HitTest::Triangle(Triangle::new(a, b, c).ok()?.explain(p))
            }
        })
    }

    /// The variant's name as written in scene files.
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Sphere(_) => "Sphere",
            Self::Plane(_) => "Plane",
            Self::Aabb(_) => "Aabb",
            Self::Triangle(_) => "Triangle",
            Self::Polygon(_) => "Polygon",
            Self::Mesh(_) => "Mesh",
        }
    }
}
