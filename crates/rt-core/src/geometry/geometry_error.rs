//! Why a primitive cannot be built: the one error type every shape's
//! constructor returns, kept apart from the shapes and from the
//! [`crate::geometry::primitive::Primitive`] enum that dispatches to them.

use thiserror::Error;

use crate::math::real::Real;

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
