//! The record of one pixel sample's light path: the data `rt-view explain`
//! prints as JSON and the viewer's scene view draws (`docs/explain.md`
//! describes every field).
//!
//! It is written by the renderer itself while it computes the sample: the
//! integrators call a [`crate::explain::recorder::Recorder`] next to each ray
//! they cast and each term they add, so the record holds the renderer's own
//! numbers, and the sample's value can be rebuilt from it bit for bit:
//!
//! - **path tracing** ([`IntegratorKind::Path`]): the sample is the sum, in
//!   order, from zero, of every [`Contribution::value`] (f32 additions);
//! - **direct lighting** ([`IntegratorKind::Direct`], Whitted): each
//!   segment's [`Segment::radiance`] is the sum, in order, from zero, of the
//!   values of the contributions made at its hit; a reflection's or
//!   refraction's contribution is `weight × radiance` of the child segment it
//!   names; the sample is the primary segment's radiance;
//! - **flat colours** ([`IntegratorKind::Flat`]): one contribution, the colour.
//!
//! Conventions are those of `docs/conventions.md`: a left-handed world,
//! camera axes `x` right, `y` up, `z` the viewing direction; pixel (0, 0) the
//! top-left one, the view plane's upper-left corner the origin of pixel
//! coordinates; ray parameters `t` for the ray's own (not necessarily unit)
//! direction; colours linear RGB.

use serde::Serialize;

use crate::geometry::hit_test::HitTest;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3};

/// Everything about one sample of one pixel.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PathRecord {
    /// The pixel, `[x, y]`, x to the right and y down from the top-left pixel.
    pub pixel: [u32; 2],
    /// The sample's index within the pixel (0-based).
    pub sample: u32,
    /// Samples per pixel of the render this sample belongs to (the
    /// stratification of film positions depends on it).
    pub samples_per_pixel: u32,
    /// The render's seed.
    pub seed: u64,
    /// Which light transport computed the sample.
    pub integrator: IntegratorKind,
    /// The render camera.
    pub camera: CameraRecord,
    /// Its view plane for the image size.
    pub view_plane: ViewPlaneRecord,
    /// The sample's position in its pixel, `[sx, sy]` ∈ [0, 1)² ((0.5, 0.5)
    /// the centre).
    pub film: [Real; 2],
    /// The sample's position on the lens, in [0, 1)² (unused by a pinhole).
    pub lens: [Real; 2],
    /// The sample's 3D point on the view plane:
    /// `O + (x + sx)·(plane_w/W)·CamX − (y + sy)·(plane_h/H)·CamY`.
    pub pixel_point: Vec3,
    /// Every ray of the path, in the order cast; segment 0 is the primary ray.
    pub segments: Vec<Segment>,
    /// Every term added towards the sample's value, in the order added.
    pub contributions: Vec<Contribution>,
    /// The sample's value (linear RGB radiance), as the render computed it.
    pub value: Color,
}

/// The light transport of a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    /// Ray casting without lights or shading: the hit's flat colour.
    Flat,
    /// Direct lighting with shadows, reflection and refraction (Whitted).
    Direct,
    /// Path tracing: next-event estimation, MIS, Russian roulette, random
    /// walks inside translucent objects.
    Path,
}

/// The camera: its definition and the camera space built from it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CameraRecord {
    /// C, the eye.
    pub position: Vec3,
    /// COI, the point looked at.
    pub center_of_interest: Vec3,
    /// The general up vector, as given.
    pub up: Vec3,
    /// CamX (right), unit.
    pub x: Vec3,
    /// CamY (true up), unit: `CamZ × CamX`.
    pub y: Vec3,
    /// CamZ (looking direction), unit: `normalize(COI − C)`.
    pub z: Vec3,
    /// Vertical field of view, degrees (perspective).
    pub fov_y: Real,
    /// Distance from C to the view plane along CamZ.
    pub near: Real,
    /// `"perspective"` or `"orthographic"`.
    pub projection: &'static str,
    /// Thin-lens aperture radius (0: a pinhole).
    pub lens_radius: Real,
    /// Thin-lens focus distance.
    pub focus_distance: Real,
}

/// The view plane: `near` in front of C, `plane_w × plane_h` world units,
/// `W × H` pixels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ViewPlaneRecord {
    /// `[W, H]` in pixels.
    pub image: [u32; 2],
    /// `[plane_w, plane_h]` in world units; `plane_h = 2·near·tan(fov_y/2)`
    /// (perspective), `plane_w = plane_h·W/H`.
    pub size: [Real; 2],
    /// One pixel's size in world units, `[plane_w/W, plane_h/H]`.
    pub pixel_size: [Real; 2],
    /// O, the upper-left corner: the origin of pixel coordinates.
    pub upper_left: Vec3,
    /// The upper-right corner.
    pub upper_right: Vec3,
    /// The lower-left corner.
    pub lower_left: Vec3,
    /// The lower-right corner.
    pub lower_right: Vec3,
    /// The centre, `C + near·CamZ`.
    pub center: Vec3,
}

/// One ray of the path.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Segment {
    /// The segment whose hit this ray leaves from (`None` for the primary ray).
    pub parent: Option<usize>,
    /// Its depth: 0 for the primary ray and the rays from its hit, one more
    /// for each reflection, refraction or bounce before it.
    pub depth: u32,
    /// What kind of ray it is, with what only that kind has.
    pub kind: SegmentKind,
    /// Origin o.
    pub origin: Vec3,
    /// Direction (not necessarily unit: t is in its units).
    pub direction: Vec3,
    /// Largest t searched (a shadow ray stops before the light); `None`:
    /// unbounded.
    pub t_max: Option<Real>,
    /// What it hit: for a shadow, next-event or occlusion ray, what blocked
    /// it (if anything); `None` for a ray that left the scene.
    pub hit: Option<SegmentHit>,
    /// Direct lighting: the radiance this ray brought back (the sum of the
    /// contributions at its hit). Path tracing: `None`.
    pub radiance: Option<Color>,
    /// Direct lighting: the factor its radiance is multiplied by in its
    /// parent's (`kr·s + kt·F` for reflection, `kt·(1 − F)·color·η²` for
    /// refraction). Path tracing: the throughput β of the path along this
    /// ray. `None` where it has none (visibility rays; the primary ray of
    /// direct lighting).
    pub weight: Option<Color>,
    /// What happened at its hit, in order: the numbers of each decision
    /// (next-event estimation, BSDF sampling, Russian roulette, the walk).
    pub events: Vec<Event>,
}

/// The kinds of rays.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum SegmentKind {
    /// The camera ray through the pixel's sample point.
    Primary,
    /// A Whitted shadow ray to sample `sample` of light `light` (index in
    /// the scene's `lights`).
    Shadow {
        /// The light's index in the scene's lights.
        light: usize,
        /// Which of its samples (area lights have several).
        sample: u32,
        /// Whether something is in the way.
        blocked: bool,
    },
    /// An ambient-occlusion ray.
    AmbientOcclusion {
        /// Whether something within the radius is in the way.
        blocked: bool,
    },
    /// A mirror reflection.
    Reflection,
    /// A refraction.
    Refraction,
    /// Path tracing: the ray towards a light sample (next-event estimation).
    NextEvent {
        /// Whether something is in the way.
        blocked: bool,
    },
    /// Path tracing: the ray along a direction drawn from the BSDF.
    Bounce,
    /// A step of a random walk inside a translucent object, towards the next
    /// scattering point or the object's surface.
    WalkStep,
    /// The ray a walk leaves its object along.
    WalkExit,
}

/// What a segment hit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SegmentHit {
    /// Ray parameter of the hit.
    pub t: Real,
    /// The object's index in the scene file's objects (0-based).
    pub object: usize,
    /// The triangle of a mesh (0-based); 0 for other primitives.
    pub primitive: usize,
    /// The kind of primitive, as scene files name it (`"Sphere"`, `"Plane"`,
    /// `"Aabb"`, `"Triangle"`, `"Polygon"`, `"Mesh"`).
    pub shape: &'static str,
    /// `o + t·dir`, as the renderer computes it.
    pub point: Vec3,
    /// The unit geometric normal, in the primitive's own orientation (not
    /// turned towards the ray).
    pub normal: Vec3,
    /// Whether the ray arrived on the side the normal points to.
    pub front: bool,
    /// The course's tests on this hit.
    pub test: Option<HitTest>,
}

/// A decision at a hit, with its numbers.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Event {
    /// Path tracing: light (emission or the environment) found by this ray,
    /// weighted by MIS against next-event estimation from the previous vertex.
    LightFound {
        /// The radiance found.
        radiance: Color,
        /// Its MIS weight (power heuristic; 1 after the camera or a δ lobe).
        mis_weight: Real,
    },
    /// Path tracing: next-event estimation at this hit.
    NextEvent {
        /// The light chosen (`"environment"`, `"light 2"`, `"emitter 0"`).
        light: String,
        /// The probability it was chosen with.
        probability: Real,
        /// The light's density for the direction (solid angle); `None` for a
        /// light no ray can hit (point, directional): MIS weight 1.
        light_pdf: Option<Real>,
        /// The BSDF's density for the same direction.
        bsdf_pdf: Real,
        /// The power-heuristic weight of light sampling.
        mis_weight: Real,
        /// The BSDF's value f.
        bsdf: Color,
        /// The index of the next-event segment (absent if no ray was cast).
        segment: Option<usize>,
    },
    /// Path tracing: the BSDF sampled for the next direction.
    Scatter {
        /// The unit direction drawn.
        direction: Vec3,
        /// Its density (for a δ lobe, the probability of choosing it).
        pdf: Real,
        /// Whether the lobe is a δ (mirror, glass).
        delta: bool,
        /// `f·|cos θ|/pdf`.
        weight: Color,
        /// The throughput β after it.
        throughput: Color,
    },
    /// Path tracing: Russian roulette.
    Roulette {
        /// The probability of going on, `max(β)`.
        survive: Real,
        /// Whether the path went on (β divided by `survive` then).
        survived: bool,
    },
    /// The path stopped here.
    Stopped {
        /// Why: `"max_bounces"`, `"no_scatter"`, `"zero_throughput"`,
        /// `"roulette"`, `"walk_ended"`, `"max_depth"`, `"min_weight"`.
        reason: &'static str,
    },
    /// A random walk's scattering point inside its object (after the step
    /// that reached it), with the walk's throughput there.
    WalkScatter {
        /// The point.
        point: Vec3,
        /// The walk's spectral weight so far.
        weight: Color,
    },
}

/// One term added towards the sample's value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Contribution {
    /// The segment at whose hit (or, for the environment, along which) it
    /// was found.
    pub segment: usize,
    /// What it is.
    pub kind: ContributionKind,
    /// The amount added (linear RGB), exactly as the renderer added it.
    pub value: Color,
}

/// The kinds of contributions.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ContributionKind {
    /// A flat colour (no lights: ray casting).
    Flat,
    /// The environment, seen by a ray that hit nothing.
    Environment,
    /// Emission of the surface hit.
    Emission,
    /// Ambient light times the unblocked fraction `occlusion`.
    Ambient {
        /// The unblocked fraction of the hemisphere (1 without AO).
        occlusion: Real,
    },
    /// Direct lighting: one sample of one light, `f·E·cos θ`.
    Light {
        /// The light's index in the scene's lights.
        light: usize,
        /// Which of its samples.
        sample: u32,
    },
    /// Direct lighting: what the reflected ray `child` brought back, times
    /// its weight.
    Reflection {
        /// The reflected segment.
        child: usize,
    },
    /// Direct lighting: what the refracted ray `child` brought back, times
    /// its weight.
    Refraction {
        /// The refracted segment.
        child: usize,
    },
    /// Path tracing: `β·f·cos θ·L·w/pdf` from next-event estimation.
    NextEvent,
}
