//! rt-core: the geometry, camera, scenes and render loop of the `rt` ray tracer.
//!
//! The conventions every module follows (left-handed world, camera axes,
//! view plane, ray parameters, normals, the self-intersection rule, colours)
//! are written out in the repository's `docs/conventions.md`.
//!
//! One folder per stage of a pixel's path, in the order of the course design:
//!
//! 1. [`files`]: a RON scene file ([`files::scene_file`]) and the models it
//!    loads become a [`LoadedScene`]: the world, its camera, and the
//!    [`RenderSettings`] ([`render::settings`]).
//! 2. [`scene`]: the world, read-only: objects, materials, lights, the
//!    environment, the BVH, and the ray queries over them; [`scene::effects`]
//!    decides which kinds of rays a render needs.
//! 3. [`camera`]: camera space from position, centre of interest and up;
//!    the view plane ([`camera::view_plane`]) maps a pixel and a film
//!    position to a 3D point and a camera ray.
//! 4. [`sampling`]: the [`sampling::sampler::Sampler`] hands out each pixel
//!    sample's film position and random numbers.
//! 5. [`geometry`]: rays against primitives ([`geometry::primitive`]: sphere,
//!    plane, box, triangle, polygon, mesh), hits, and points on surfaces
//!    with error bounds; [`bvh`] finds the closest hit among all objects.
//! 6. [`materials`]: how surfaces and insides scatter light (BSDFs, media,
//!    textures); [`lights`]: where light comes from, through one interface.
//! 7. [`integrators`]: a hit becomes a surface interaction and light
//!    transport turns it into radiance: direct lighting, or path tracing with
//!    random walks through translucent objects.
//! 8. [`render`]: pixels → samples → camera rays → the integrator → colours
//!    → rows → image, in parallel with rayon.
//!
//! All geometry is in world units with [`Real`] precision (f32, or f64 with
//! the `f64` feature); numerical tolerances live in [`math::real`]. The
//! reference ray sets that score the intersection routines are in
//! `accuracy` (tests and the `accuracy` feature).
//!
//! The names most programs need are re-exported here: build or load a
//! [`Scene`], render it through a [`Camera`] with [`RenderSettings`] by a
//! [`Renderer`] into a [`Frame`], or query it with a [`Ray`] for a [`Hit`].

#![deny(missing_docs)]

pub mod math;

pub mod bvh;
pub mod camera;
pub mod explain;
pub mod files;
pub mod geometry;
pub mod integrators;
pub mod lights;
pub mod materials;
pub mod render;
pub mod sampling;
pub mod scene;

#[cfg(any(test, feature = "accuracy"))]
pub mod accuracy;
#[cfg(test)]
mod testing;

pub use camera::view_plane::ViewPlane;
pub use camera::{Camera, CameraError, Projection};
pub use files::scene_file::{LoadedScene, SceneError, load_scene, parse_scene};
pub use geometry::hit::Hit;
pub use geometry::object::Object;
pub use geometry::primitive::Primitive;
pub use lights::light::Light;
pub use materials::material::Material;
pub use math::color::Color;
pub use math::ray::{Interval, Ray};
pub use math::real::{Real, Vec3};
pub use render::settings::{ImageSize, RenderSettings, SamplesPerPixel, SettingsError};
pub use render::{Frame, RenderError, Renderer};
pub use scene::effects::{EffectPlan, Effects, RayCounts};
pub use scene::{MaterialEditError, Scene, SceneBuildError, SceneBuilder};
