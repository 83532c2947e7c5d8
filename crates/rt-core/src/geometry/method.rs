//! Which intersection routine each primitive uses: the accuracy knobs.
//!
//! The defaults are the numerically careful routines that every hard-case
//! test pins down. The others are the textbook and course versions, kept so
//! that `rt-view accuracy` can measure what the careful ones buy and cost;
//! each is documented next to its primitive ([`crate::geometry::triangle`],
//! [`crate::geometry::sphere`], [`crate::geometry::aabb`]).

use serde::{Deserialize, Serialize};

/// Ray/triangle test (also used for every triangle of a mesh).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TriangleMethod {
    /// The course's test: hit the plane, then compare the three sub-triangle
    /// areas with the whole ([`crate::geometry::triangle::intersect_area_ratio`]).
    AreaRatio,
    /// Möller & Trumbore 1997 ([`crate::geometry::triangle::intersect_moller_trumbore`]).
    MollerTrumbore,
    /// Woop, Benthin & Wald 2013 ([`crate::geometry::triangle::intersect_watertight`]): never
    /// leaks through shared edges.
    #[default]
    Watertight,
}

/// Ray/sphere test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SphereMethod {
    /// The quadratic formula as printed in textbooks
    /// ([`crate::geometry::sphere::Sphere::intersect_textbook`]).
    Textbook,
    /// Haines et al., *Ray Tracing Gems* ch. 7 ([`crate::geometry::sphere::Sphere::intersect`]).
    #[default]
    Careful,
}

/// Ray/axis-aligned-box test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum BoxMethod {
    /// The course's test: each face's plane, then the hit point against the
    /// other two axes' bounds ([`crate::geometry::aabb::Aabb::intersect_six_plane`]).
    SixPlane,
    /// Kay & Kajiya's slab test ([`crate::geometry::aabb::Aabb::intersect`]).
    #[default]
    Slab,
}

/// The intersection routines a scene is traced with. Planes and polygons
/// have one routine each and no knob.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Methods {
    /// For triangles and mesh triangles.
    pub triangle: TriangleMethod,
    /// For spheres.
    pub sphere: SphereMethod,
    /// For axis-aligned boxes (not the BVH's own node boxes, which always
    /// use the slab test).
    #[serde(rename = "box")]
    pub aabb: BoxMethod,
}

impl Methods {
    /// Whether these are the default (careful) routines.
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }
}
