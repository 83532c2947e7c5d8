//! Rays against shapes: one `enum` of primitives ([`primitive`]) over the
//! sphere, plane, box, triangle, polygon and mesh, each with its
//! intersection routines (the careful ones and the course's, chosen by
//! [`method`]), its [`hit`]s, and the point on its surface with an error
//! bound that secondary rays leave from ([`surface`]); an [`object`] is a
//! primitive with its material. Bad parameters are
//! [`geometry_error::GeometryError`]s.

pub mod aabb;
pub mod geometry_error;
pub mod hit;
pub mod hit_test;
pub mod mesh;
pub mod method;
pub mod object;
pub mod plane;
pub mod polygon;
pub mod primitive;
pub mod sphere;
pub mod surface;
pub mod triangle;
