//! rt-core: the geometry, camera, scenes and render loop of the `rt` ray tracer.
//!
//! One pixel's path through the crate, in the order of the course design:
//!
//! 1. [`scene_file`] reads a RON scene file into a validated [`scene::Scene`].
//! 2. [`camera`] derives the camera's axes from position, centre of interest and up.
//! 3. [`view_plane`] sizes the virtual view plane and maps pixel (ix, iy) to a
//!    3D point and its primary [`ray::Ray`].
//! 4. [`primitive`] dispatches the ray to each object's geometry ([`sphere`],
//!    [`plane`], [`aabb`], [`triangle`], [`polygon`], [`mesh`]); the closest
//!    [`hit::Hit`] wins ([`scene::Scene::closest_hit`]), found through a
//!    [`bvh`] built once per scene.
//! 5. [`effects`] decides once which kinds of rays the scene needs; [`tracer`]
//!    turns hits into colours: flat [`material`] colours without lights, else
//!    [`light`]s, [`shading`] formulas, shadows, reflection, refraction and
//!    ambient occlusion, with secondary rays leaving each surface safely
//!    ([`surface`]).
//! 6. [`render`] turns pixels into samples and rows into an image, in
//!    parallel with rayon; [`sampler`] places the samples.
//!
//! All geometry is in world units with [`real::Real`] precision (f32, or f64
//! with the `f64` feature); numerical tolerances live in [`real`].

pub mod aabb;
pub mod bvh;
pub mod camera;
pub mod effects;
pub mod hard_cases;
pub mod hit;
pub mod light;
pub mod material;
pub mod mesh;
pub mod method;
pub mod plane;
pub mod polygon;
pub mod primitive;
pub mod ray;
pub mod ray_text;
pub mod real;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod scene_file;
pub mod shading;
pub mod sphere;
pub mod surface;
pub mod tracer;
pub mod triangle;
pub mod view_plane;

#[cfg(test)]
mod test_support;

pub use camera::{Camera, CameraBasis, CameraError, Projection};
pub use hit::Hit;
pub use ray::{Interval, Ray};
pub use real::{Real, Vec3};
pub use render::{Frame, Renderer};
pub use scene::Scene;
pub use scene_file::{SceneError, load_scene, parse_scene};
pub use view_plane::ViewPlane;
