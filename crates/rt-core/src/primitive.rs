//! The primitive enum: one variant per kind of geometry, one `match` per operation.

use thiserror::Error;

use crate::aabb::Aabb;
use crate::hit::PrimitiveHit;
use crate::mesh::Mesh;
use crate::method::{BoxMethod, Methods, SphereMethod};
use crate::plane::Plane;
use crate::polygon::Polygon;
use crate::ray::{Interval, Ray};
use crate::real::{Real, Vec3};
use crate::sphere::Sphere;
use crate::surface::SurfacePoint;
use crate::triangle::Triangle;

/// Why a primitive cannot be built from its parameters.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum GeometryError {
    /// A coordinate is NaN or infinite.
    #[error("{0} must be finite")]
    NotFinite(&'static str),
    /// Radius ≤ 0 or NaN.
    #[error("sphere radius must be positive, got {0}")]
    SphereRadius(Real),
    /// Radius whose square overflows or is subnormal.
    #[error("sphere radius {0} is out of range: its square must be a normal, finite number")]
    SphereRadiusRange(Real),
    /// A zero plane normal.
    #[error("plane normal must not be zero")]
    PlaneNormalZero,
    /// Some `min` coordinate exceeds its `max`.
    #[error("box min must not exceed max on any axis")]
    BoxInverted,
    /// Three corners on a line (or too close to have a normal).
    #[error("triangle has zero area (its corners are collinear or coincide)")]
    TriangleDegenerate,
    /// Fewer than three corners.
    #[error("polygon needs at least 3 points, got {0}")]
    PolygonTooFewPoints(usize),
    /// All corners on a line.
    #[error("polygon has zero area (its points are collinear or coincide)")]
    PolygonDegenerate,
    /// A corner off the polygon's plane.
    #[error(
        "polygon is not planar: point {point} is {distance} from the best-fit plane \
         (tolerance {tolerance})"
    )]
    PolygonNotPlanar {
        /// 0-based index of the corner furthest from the plane.
        point: usize,
        /// Its distance from the plane, world units.
        distance: Real,
        /// The allowed distance, world units.
        tolerance: Real,
    },
}

/// Every kind of geometry a scene object can be.
#[derive(Clone, Debug, PartialEq)]
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
    /// See [`Mesh`].
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

    /// The hit point `p = o + t·d` of a hit on `primitive` (the triangle
    /// index in a mesh) with geometric `normal`, moved onto the surface and
    /// given an error bound, so secondary rays can leave it safely.
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
