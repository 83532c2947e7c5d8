//! Global illumination: unidirectional path tracing with next-event
//! estimation and multiple importance sampling, run when a scene asks for
//! `effects: (global_illumination: (…))`.
//!
//! A camera sample follows one path. At each surface it meets, with
//! throughput β (what the path so far passes on, per channel):
//!
//! 1. **Emission found.** If the surface is emissive and seen from its front,
//!    `β·w·L_e` is added. w = 1 for a camera ray or after a δ lobe (mirror,
//!    glass), which light sampling cannot produce; otherwise w is the power
//!    heuristic of the BSDF sample's density against the density with which
//!    step 3 would have sampled the same direction ([`bsdf::power_heuristic`]).
//!    A ray that leaves the scene finds the background the same way, as a
//!    constant environment.
//! 2. **Stop** after `max_bounces` surfaces have scattered the path.
//! 3. **Next-event estimation.** If the BSDF has smooth lobes, one light is
//!    chosen ([`LightSampler`]), a direction towards it sampled, and if a
//!    shadow ray finds nothing in the way, `β·f·cos θ·L·w/pdf` is added, w the
//!    power heuristic of the light's density against the BSDF's. Point,
//!    directional and sphere lights of the `lights` list cannot be hit by
//!    rays, so their samples get w = 1.
//! 4. **BSDF sampling.** A direction is drawn from the BSDF
//!    ([`Bsdf::sample`]) and β multiplied by `f·|cos θ|/pdf`; the path goes on
//!    along it (a *bounce* ray).
//! 5. **Russian roulette** from the [`ROULETTE_FROM`]th bounce on: the path
//!    ends with probability `q = 1 − max(β)` when `max(β) < 1`, and otherwise
//!    goes on with β/(1 − q), which keeps the estimate unbiased (pbrt-v4
//!    §14.1.5).
//!
//! This is the loop of pbrt-v4's `PathIntegrator` (§14.1) and of Mitsuba 3's
//! `path` integrator, whose `max_depth` is `max_bounces + 1`. Glass casts
//! light through itself and focuses it into caustics by this transport alone:
//! there is no special case for it.

use crate::bsdf::{self, Bsdf};
use crate::effects::{GlobalIllumination, RayCounts};
use crate::hit::Hit;
use crate::light_sampler::{LightSampler, Source};
use crate::material::Color;
use crate::ray::{Interval, Ray};
use crate::real::{Real, Vec3, normalize_robust, to_f32};
use crate::sampler::SampleRng;
use crate::scene::Scene;
use crate::surface::SurfacePoint;

/// Russian roulette may end a path from this bounce on (counting the first
/// surface the camera ray meets as bounce 1).
pub const ROULETTE_FROM: u32 = 3;

/// A shadow ray towards a sampled point on an emitter stops this fraction of
/// its length short, so that it does not find the emitter itself.
const SHADOW_SHORTEN: Real = 1e-4;

/// Traces paths through one scene.
#[derive(Clone, Copy, Debug)]
pub struct PathTracer<'s> {
    scene: &'s Scene,
    settings: GlobalIllumination,
}

/// What the path knows about the scattering that led to the current ray.
#[derive(Clone, Copy, Debug)]
enum Previous {
    /// The camera, or a δ lobe: light sampling could not have found this
    /// direction, so emission found along it counts in full.
    Specular,
    /// A smooth lobe at `p`, which drew the direction with density `pdf`.
    Smooth { p: Vec3, pdf: Real },
}

impl<'s> PathTracer<'s> {
    /// A path tracer for `scene` with `settings`.
    pub fn new(scene: &'s Scene, settings: GlobalIllumination) -> Self {
        Self { scene, settings }
    }

    /// The radiance arriving along a camera ray (the `cast` rule decides
    /// what counts as its hit); `rng` is this pixel sample's random stream.
    pub fn trace_primary(&self, ray: &Ray, rng: &mut SampleRng, counts: &mut RayCounts) -> Color {
        counts.primary += 1;
        let hit = self.scene.cast(ray);
        self.trace_path(*ray, hit, rng, counts)
    }

    fn trace_path(
        &self,
        mut ray: Ray,
        mut hit: Option<Hit>,
        rng: &mut SampleRng,
        counts: &mut RayCounts,
    ) -> Color {
        let scene = self.scene;
        let lights = scene.light_sampler();
        let mut radiance = Color::ZERO;
        let mut beta = Color::ONE;
        let mut previous = Previous::Specular;
        let mut bounce = 0;
        while let Some(d) = normalize_robust(ray.dir) {
            let Some(h) = hit else {
                // The background, as a constant environment light.
                let w = match previous {
                    Previous::Specular => 1.0,
                    Previous::Smooth { pdf, .. } => {
                        bsdf::power_heuristic(pdf, lights.environment_probability() * uniform_sphere_pdf())
                    }
                };
                radiance += beta * scene.background * to_f32(w);
                break;
            };
            let object = &scene.objects()[h.object];
            let m = scene.material(object.material);
            let sp = object.primitive.surface_point(h.primitive, h.normal, ray.at(h.t));
            let wo = -d;

            // 1. Emission found by this ray.
            if m.is_emissive() && wo.dot(sp.normal) > 0.0 {
                let w = match previous {
                    Previous::Specular => 1.0,
                    Previous::Smooth { p, pdf } => {
                        let light_pdf = match scene.emitter_of(h.object) {
                            Some(e) => {
                                let distance = (sp.p - p).length();
                                lights.object_probability(h.object) * e.pdf(p, d, distance, sp.normal)
                            }
                            None => 0.0,
                        };
                        bsdf::power_heuristic(pdf, light_pdf)
                    }
                };
                radiance += beta * m.emission * to_f32(w);
            }

            // 2. The last surface that may scatter.
            bounce += 1;
            if bounce > self.settings.max_bounces {
                break;
            }
            let bsdf = Bsdf::new(m, sp.normal, wo);

            // 3. Next-event estimation.
            if bsdf.has_smooth_lobes() {
                radiance += beta * self.next_event(&sp, &bsdf, wo, lights, rng, counts);
            }

            // 4. BSDF sampling.
            let (u, _) = rng.next_pair();
            let Some(s) = bsdf.sample(wo, u, rng.next_pair()) else { break };
            beta *= s.weight;
            if beta.max_element() <= 0.0 || !beta.is_finite() {
                break;
            }
            previous =
                if s.lobe.is_delta() { Previous::Specular } else { Previous::Smooth { p: sp.p, pdf: s.pdf } };

            // 5. Russian roulette.
            if self.settings.russian_roulette && bounce >= ROULETTE_FROM {
                let survive = beta.max_element();
                if survive < 1.0 {
                    let (u, _) = rng.next_pair();
                    if to_f32(u) >= survive {
                        break;
                    }
                    beta /= survive;
                }
            }

            counts.bounce += 1;
            ray = Ray::new(sp.spawn_origin(s.wi), s.wi);
            hit = scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY));
        }
        radiance
    }

    /// One light sample's contribution at `sp` (throughput not applied).
    fn next_event(
        &self,
        sp: &SurfacePoint,
        bsdf: &Bsdf,
        wo: Vec3,
        lights: &LightSampler,
        rng: &mut SampleRng,
        counts: &mut RayCounts,
    ) -> Color {
        let (u, _) = rng.next_pair();
        let uv = rng.next_pair();
        let Some((source, chosen)) = lights.choose(u) else { return Color::ZERO };
        let scene = self.scene;
        // (direction, distance to the light, what arrives over its density,
        // the density for MIS (None: the light cannot be hit), shadow test on)
        let (wi, distance, arriving, light_pdf, shadows) = match source {
            Source::Light(i) => {
                let light = &scene.lighting.lights[i];
                let Some(s) = light.sample_one(sp.p, uv) else { return Color::ZERO };
                (s.to_light, s.distance, s.irradiance, None, light.shadows)
            }
            Source::Emitter(i) => {
                let e = &scene.emitters()[i];
                let Some(s) = e.sample(sp.p, uv) else { return Color::ZERO };
                let distance = s.distance * (1.0 - SHADOW_SHORTEN);
                (s.wi, distance, s.radiance / to_f32(s.pdf), Some(s.pdf), true)
            }
            Source::Environment => {
                let wi = uniform_sphere(uv);
                let pdf = uniform_sphere_pdf();
                (wi, Real::INFINITY, scene.background / to_f32(pdf), Some(pdf), true)
            }
        };
        let f = bsdf.eval(wo, wi);
        if f == Color::ZERO {
            return Color::ZERO;
        }
        let w = match light_pdf {
            Some(pdf) => bsdf::power_heuristic(chosen * pdf, bsdf.pdf(wo, wi)),
            None => 1.0,
        };
        if shadows {
            counts.next_event += 1;
            let shadow = Ray::new(sp.spawn_origin(wi), wi);
            if scene.any_hit(&shadow, Interval::new(0.0, distance)) {
                return Color::ZERO;
            }
        }
        let cos = wi.dot(sp.normal).abs();
        f * arriving * to_f32(cos * w / chosen)
    }
}

/// A direction uniform over the unit sphere for (u, v) ∈ [0,1)².
fn uniform_sphere((u, v): (Real, Real)) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI as Real * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The density of [`uniform_sphere`] over solid angle, `1/(4π)`.
fn uniform_sphere_pdf() -> Real {
    1.0 / (4.0 * std::f64::consts::PI as Real)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{Frame, Renderer};
    use std::path::Path;

    fn scene(text: &str) -> Scene {
        crate::parse_scene(text, "test.ron", Path::new(".")).unwrap()
    }

    fn render(s: &Scene, width: u32, height: u32, spp: u32) -> Frame {
        Renderer::new(s, width, height, spp).unwrap().render(|_| {})
    }

    /// A diffuse sphere of albedo `albedo` filling most of the view, inside a
    /// background of radiance 1.
    fn furnace(albedo: f32, effects: &str) -> Scene {
        scene(&format!(
            r#"(
            camera: (position: (0, 0, -3), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 12, height: 12),
            background: (1, 1, 1),
            materials: {{ "m": (color: ({albedo}, {albedo}, {albedo})) }},
            objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
            effects: (global_illumination: ({effects})),
        )"#
        ))
    }

    #[test]
    fn a_white_sphere_in_a_white_furnace_disappears_at_any_bounce_count() {
        // Albedo 1 under uniform radiance 1: every point sends back exactly 1,
        // however many bounces are followed (a convex sphere only sees the
        // background, so one bounce already gathers it all).
        for effects in [
            "max_bounces: 1",
            "max_bounces: 2",
            "max_bounces: 5",
            "max_bounces: 50",
            "russian_roulette: false",
        ] {
            let f = render(&furnace(1.0, effects), 12, 12, 64);
            let mean: f32 = f.pixels.iter().map(|c| c.x).sum::<f32>() / f.pixels.len() as f32;
            // 64 samples of a bounded estimator: each pixel within a few
            // standard errors of 1, the mean much closer.
            assert!((mean - 1.0).abs() < 0.01, "{effects}: mean {mean}");
            for c in &f.pixels {
                assert!((c.x - 1.0).abs() < 0.1 && c.x == c.y && c.y == c.z, "{effects}: {c}");
            }
        }
    }

    #[test]
    fn a_grey_sphere_in_the_furnace_reflects_its_albedo() {
        let f = render(&furnace(0.5, "max_bounces: 3"), 12, 12, 64);
        // The centre pixels see the sphere: radiance 0.5·1.
        let centre = f.pixels[6 * 12 + 6];
        assert!((centre.x - 0.5).abs() < 0.05, "{centre}");
        // Without bounces the sphere is black; the background still shows.
        let f = render(&furnace(0.5, "max_bounces: 0"), 12, 12, 4);
        assert_eq!(f.pixels[6 * 12 + 6], Color::ZERO);
        assert_eq!(f.pixels[0], Color::ONE);
    }

    /// A grey floor lit by one point light, with `effects`.
    fn lit_floor(effects: &str) -> Scene {
        scene(&format!(
            r#"(
            camera: (position: (0, 3, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 50, near: 1),
            image: (width: 16, height: 12),
            materials: {{ "grey": (color: (0.6, 0.5, 0.4), specular: 0.3, shininess: 40), "red": (color: (0.8, 0.1, 0.1)) }},
            objects: [ Plane(normal: (0, 1, 0), d: 0, material: "grey"), Sphere(center: (0.5, 0.7, 0.5), radius: 0.7, material: "red") ],
            lights: [ Point(position: (-1, 4, -2), intensity: 30) ],
            {effects}
        )"#
        ))
    }

    #[test]
    fn one_bounce_of_global_illumination_is_the_direct_lighting_tracer() {
        // With a single point light, next-event estimation is deterministic
        // and the BSDF-sampled rays find nothing that glows: one bounce of
        // path tracing is exactly the direct-lighting part of the model.
        let direct = render(&lit_floor(""), 16, 12, 1);
        let gi = render(&lit_floor("effects: (global_illumination: (max_bounces: 1)),"), 16, 12, 1);
        for (a, b) in direct.pixels.iter().zip(&gi.pixels) {
            assert!((*a - *b).abs().max_element() <= 1e-5 * a.max_element().max(1.0), "{a} vs {b}");
        }
        // More bounces only add light (the red sphere lights the floor).
        let more = render(&lit_floor("effects: (global_illumination: (max_bounces: 4)),"), 16, 12, 16);
        let sum = |f: &Frame| f.pixels.iter().map(|c| c.element_sum()).sum::<f32>();
        assert!(sum(&more) > sum(&direct) * 1.01);
    }

    #[test]
    fn global_illumination_casts_its_rays_only_when_asked_for() {
        let direct = render(&lit_floor(""), 16, 12, 2).rays;
        assert_eq!((direct.bounce, direct.next_event), (0, 0));
        let gi = render(&lit_floor("effects: (global_illumination: (max_bounces: 2)),"), 16, 12, 2).rays;
        assert!(gi.bounce > 0 && gi.next_event > 0, "{gi:?}");
        assert_eq!((gi.shadow, gi.reflection, gi.refraction, gi.ambient_occlusion), (0, 0, 0, 0));
        assert_eq!(gi.primary, 16 * 12 * 2);
    }

    #[test]
    fn the_image_is_identical_for_one_and_for_two_threads() {
        let s = lit_floor("background: (0.2, 0.3, 0.4), effects: (global_illumination: (max_bounces: 5)),");
        let r = Renderer::new(&s, 16, 12, 4).unwrap();
        let run = |threads| crate::test_support::render_on_threads(&r, threads);
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn light_reaches_the_floor_through_a_glass_slab() {
        // A glass slab between a glowing sphere (and a point light) and a
        // floor; the camera looks at the floor under the slab from below it.
        // The direct tracer's shadow rays find the slab opaque: that floor is
        // black. Under global illumination light passes through the glass.
        let text = |effects: &str| {
            format!(
                r#"(
                camera: (position: (0, 0.5, -6), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 5, near: 1),
                image: (width: 3, height: 3),
                materials: {{
                    "floor": (color: (0.8, 0.8, 0.8)),
                    "glass": (color: (1, 1, 1), diffuse: 0, transparency: 1, ior: 1.5),
                    "lamp": (color: (0, 0, 0), emission: (10, 10, 10)),
                }},
                objects: [
                    Plane(normal: (0, 1, 0), d: 0, material: "floor"),
                    Aabb(min: (-3, 1, -3), max: (3, 1.2, 3), material: "glass"),
                    Sphere(center: (0, 5, 0), radius: 1, material: "lamp"),
                ],
                lights: [ Point(position: (0, 4, 0), intensity: 10) ],
                {effects}
            )"#
            )
        };
        let centre = 4;
        let direct = scene(&text(""));
        let d = Renderer::new(&direct, 3, 3, 1).unwrap().render(|_| {});
        assert_eq!(d.pixels[centre], Color::ZERO);
        let gi = scene(&text("effects: (global_illumination: (max_bounces: 4)),"));
        let f = Renderer::new(&gi, 3, 3, 512).unwrap().render(|_| {});
        assert!(f.pixels.iter().all(|c| c.is_finite()));
        // About (0.8/π)·10·(π·1²/5²)·T ≈ 0.3 with T ≈ 0.92 the slab's transmittance.
        assert!(f.pixels[centre].x > 0.1, "{}", f.pixels[centre]);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Random scenes of every primitive with random materials (every lobe,
        /// emissive or not), lit by a point light and the background: no
        /// sample of any pixel is NaN, infinite or negative.
        #[test]
        fn no_sample_is_nan_infinite_or_negative_on_random_scenes(
            parts in crate::test_support::random_parts(5.0, 6),
            materials in proptest::collection::vec(proptest::array::uniform8(0f32..1.0), 6),
            background in 0f32..2.0,
        ) {
            use crate::camera::{Camera, Projection};
            use crate::effects::Lighting;
            use crate::light::{Light, LightKind};
            use crate::material::Material;
            use crate::scene::SceneBuilder;
            let camera = Camera::new(Vec3::new(0.0, 0.0, -12.0), Vec3::ZERO, Vec3::Y, 60.0, 1.0, Projection::Perspective).unwrap();
            let lighting = Lighting {
                lights: vec![Light { kind: LightKind::Point { position: Vec3::new(1.0, 6.0, -3.0) }, power: Color::splat(20.0), shadows: true }],
                global_illumination: Some(GlobalIllumination { max_bounces: 6, russian_roulette: true }),
                ..Lighting::default()
            };
            let mut b = SceneBuilder::new(camera).image_size(6, 4).background(Color::splat(background)).lighting(lighting);
            for (i, [c, kd, ks, s, kr, kt, ior, e]) in materials.iter().copied().enumerate() {
                let (kr, kt) = if kr + kt > 1.0 { (kr / 2.0, kt / 2.0) } else { (kr, kt) };
                let m = Material {
                    color: Color::new(c, 1.0 - c, 0.5),
                    diffuse: kd,
                    specular: ks,
                    shininess: s * s * 10_000.0,
                    reflectivity: kr,
                    transparency: kt,
                    ior: 0.5 + 3.0 * ior,
                    emission: if e > 0.7 { Color::splat(e * 5.0) } else { Color::ZERO },
                };
                b = b.material(format!("m{i}"), m);
            }
            for (i, p) in crate::test_support::primitives_of(parts).into_iter().enumerate() {
                b = b.object(p, format!("m{}", i % 6));
            }
            // Some polygons cannot glow (self-crossing ones); skip those scenes.
            let Ok(s) = b.build() else { return Ok(()) };
            let r = Renderer::new(&s, 6, 4, 4).unwrap();
            for y in 0..4 {
                for x in 0..6 {
                    for k in 0..4 {
                        let c = r.sample(x, y, k, &mut RayCounts::default());
                        proptest::prop_assert!(c.is_finite() && c.min_element() >= 0.0, "pixel ({x}, {y}) sample {k}: {c}");
                    }
                }
            }
        }
    }
}
