//! rt-core: the geometry, camera, scenes and render loop of the `rt` ray tracer.
//!
//! The conventions every module follows (left-handed world, camera axes,
//! view plane, ray parameters, normals, the self-intersection rule, colours)
//! are written out in the repository's `docs/conventions.md`.
//!
//! One pixel's path through the crate, in the order of the course design:
//!
//! 1. [`scene_file`] reads a RON scene file into a validated world
//!    ([`scene::Scene`]; or a [`scene::SceneBuilder`] makes one in code), its
//!    camera, and the [`settings`] to render it with.
//! 2. [`camera`] derives the camera's axes from position, centre of interest and up.
//! 3. [`view_plane`] sizes the virtual view plane and maps pixel (ix, iy) to a
//!    3D point and its primary [`ray::Ray`].
//! 4. [`primitive`] dispatches the ray to each [`object`]'s geometry ([`sphere`],
//!    [`plane`], [`aabb`], [`triangle`], [`polygon`], [`mesh`]; each refuses
//!    bad parameters with a [`geometry_error::GeometryError`]); the closest
//!    [`hit::Hit`] wins ([`scene::Scene::closest_hit`]), found through a
//!    [`bvh`] built once per scene.
//! 5. [`effects`] decides once which kinds of rays the scene needs; [`tracer`]
//!    turns hits into colours: flat [`material`] colours without lights, else
//!    the direct lighting of [`light`]s through each material's [`bsdf`]
//!    ([`shading`] holds the optics formulas), shadows, reflection,
//!    refraction and ambient occlusion; under global illumination the
//!    [`path_tracer`] follows paths instead, sampling [`emitter`]s and the
//!    background through the [`light_sampler`]. Secondary rays leave each
//!    surface safely ([`surface`]).
//! 6. [`render`] turns pixels into samples and rows into an image, in
//!    parallel with rayon; [`sampler`] places the samples.
//!
//! All geometry is in world units with [`real::Real`] precision (f32, or f64
//! with the `f64` feature); numerical tolerances live in [`real`]. The
//! intersection routine of each primitive is a knob ([`method`]); the fixed
//! ray sets of [`hard_cases`] score them, and [`ray_text`] reads rays written
//! as text (the `cast` command's input).
//!
//! The names most programs need are re-exported here: build or load a
//! [`Scene`], render it through a [`Camera`] with [`RenderSettings`] by a
//! [`Renderer`] into a [`Frame`], or query it with a [`Ray`] for a [`Hit`].

#![deny(missing_docs)]

pub mod aabb;
pub mod bsdf;
pub mod bvh;
pub mod camera;
#[cfg(test)]
pub(crate) mod chi_square;
pub mod color;
pub mod double_double;
pub mod effects;
pub mod emitter;
pub mod environment;
pub mod geometry_error;
pub mod gltf_model;
pub mod hard_cases;
pub mod hit;
pub mod integrator;
pub mod interaction;
pub mod light;
pub mod light_sampler;
pub mod light_source;
pub mod material;
pub mod medium;
pub mod mesh;
pub mod method;
pub mod model;
pub mod mtl;
pub mod obj_model;
pub mod object;
pub mod path_tracer;
pub mod plane;
pub mod polygon;
pub mod primitive;
pub(crate) mod random_walk;
pub mod ray;
pub mod ray_text;
pub mod real;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod scene_file;
pub mod settings;
pub mod shading;
pub mod sphere;
pub mod surface;
pub mod texture;
pub mod tracer;
pub mod triangle;
pub mod view_plane;

#[cfg(test)]
mod test_support;

pub use camera::{Camera, CameraError, Projection};
pub use color::Color;
pub use effects::{EffectPlan, Effects, RayCounts};
pub use hit::Hit;
pub use light::Light;
pub use material::Material;
pub use object::Object;
pub use primitive::Primitive;
pub use ray::{Interval, Ray};
pub use real::{Real, Vec3};
pub use render::{Frame, RenderError, Renderer};
pub use scene::{Scene, SceneBuildError, SceneBuilder};
pub use scene_file::{LoadedScene, SceneError, load_scene, parse_scene};
pub use settings::{ImageSize, RenderSettings, SamplesPerPixel, SettingsError};
pub use view_plane::ViewPlane;
