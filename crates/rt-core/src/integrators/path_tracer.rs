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
//!    ([`HitBsdf::sample`]) and β multiplied by `f·|cos θ|/pdf`; the path goes on
//!    along it (a *bounce* ray). The BSDF is built once per surface, as the
//!    Lambert lobe alone where the material has nothing else (most of a
//!    room), else as the whole model ([`crate::materials::bsdf::Bsdf`]):
//!    the same bits either way, less set-up for the first.
//! 5. **Russian roulette** from the [`ROULETTE_FROM`]th bounce on that
//!    sampled a smooth lobe (δ bounces, mirrors and clear glass, do not
//!    count): the path ends with probability `q = 1 − max(β)·η²` when
//!    `max(β)·η² < 1`, and otherwise goes on with β/(1 − q), which keeps the
//!    estimate unbiased for any such q (pbrt-v4 §14.1.5). `η²` is the product
//!    of the squared relative indices of the refractions so far
//!    ([`BsdfSample::eta`](crate::materials::bsdf::BsdfSample::eta)): each
//!    refraction's weight carries `1/η²` (radiance is compressed entering
//!    glass and spread out leaving it), which says nothing of how much the
//!    path can still bring, so roulette takes it back out, as pbrt-v4
//!    (`etaScale`) and Mitsuba 3 (`eta`) do. Not counting δ bounces keeps
//!    roulette off the paths that reach a light through glass or a mirror,
//!    which next-event estimation cannot find and which carry much of the
//!    light of a caustic: ending them early adds the most noise for the
//!    least time saved (docs/performance.md has the measurements).
//!
//! This is the loop of pbrt-v4's `PathIntegrator` (§14.1) and of Mitsuba 3's
//! `path` integrator, whose `max_depth` is `max_bounces + 1`. Glass casts
//! light through itself and focuses it into caustics by this transport alone:
//! there is no special case for it.

use std::mem::MaybeUninit;

use crate::explain::record::{ContributionKind, Event, SegmentKind};
use crate::explain::recorder::Recorder;
use crate::geometry::hit::Hit;
use crate::geometry::surface::SurfacePoint;
use crate::integrators::interaction::SurfaceInteraction;
use crate::integrators::random_walk::{RandomWalk, WalkEnd};
use crate::lights::light_sampler::{LightSampler, Source};
use crate::lights::light_source::LightSample;
use crate::materials::bsdf;
use crate::materials::hit_bsdf::HitBsdf;
use crate::materials::texture_lod::RayCone;
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, normalize_robust, to_f32};
use crate::sampling::sampler::Sampler;
use crate::scene::Scene;
use crate::scene::effects::{GlobalIllumination, RayCounts};

/// Russian roulette may end a path from this bounce on, counting only the
/// bounces that sampled a smooth (non-δ) lobe (the first surface the camera
/// ray meets is bounce 1 if it scatters the path that way).
pub const ROULETTE_FROM: u32 = 3;

/// Traces paths through one scene.
#[derive(Clone, Copy, Debug)]
pub struct PathTracer<'s> {
    scene: &'s Scene,
    settings: GlobalIllumination,
    /// Whether translucent objects get random walks (else their materials
    /// act as plain surfaces).
    subsurface: bool,
    /// A camera ray's cone, for texture level of detail.
    cone: RayCone,
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
    /// A path tracer for `scene` with `settings`; `subsurface` says whether
    /// translucent objects get random walks ([`crate::EffectPlan::subsurface`]).
    pub fn new(scene: &'s Scene, settings: GlobalIllumination, subsurface: bool) -> Self {
        Self { scene, settings, subsurface, cone: RayCone::POINT }
    }

    /// This path tracer with camera rays of cone `cone` (one pixel's,
    /// [`RayCone::of_pixel`]): textures are read at the level of detail
    /// its footprint asks for, along the whole path
    /// ([`crate::materials::texture_lod`]).
    pub fn with_cone(self, cone: RayCone) -> Self {
        Self { cone, ..self }
    }

    /// The radiance arriving along a camera ray already cast: `hit` is what
    /// [`Scene::cast`] gave for `ray`; `sampler` hands out this pixel
    /// sample's random numbers; `rec` is told every ray and term
    /// ([`crate::explain::recorder::NoRecorder`] for a render).
    pub fn trace_primary_hit<R: Recorder>(
        &self,
        ray: &Ray,
        hit: Option<Hit>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        counts.primary += 1;
        rec.ray(SegmentKind::Primary, ray, hit.as_ref(), Some(Color::ONE));
        self.trace_path(*ray, hit, sampler, counts, rec)
    }

    fn trace_path<R: Recorder>(
        &self,
        mut ray: Ray,
        mut hit: Option<Hit>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        let scene = self.scene;
        let lights = scene.light_sampler();
        let mut radiance = Color::ZERO;
        let mut beta = Color::ONE;
        let mut previous = Previous::Specular;
        let mut bounce = 0;
        // Roulette's count (bounces that sampled a smooth lobe) and the
        // refractions' radiance scale it takes back out of β (step 5).
        let mut smooth_bounces = 0;
        let mut eta_scale: f32 = 1.0;
        // The path's length so far: its ray cone's width grows with it.
        let mut travelled: Real = 0.0;
        while let Some(d) = normalize_robust(ray.dir) {
            let Some(h) = hit else {
                // 1. The environment found by this ray.
                let environment = scene.light_source(Source::Environment);
                let w = found_light_weight(previous, |p| {
                    lights.probability(Source::Environment) * environment.pdf(p, d, Real::INFINITY, -d)
                });
                let term = beta * scene.environment().radiance(d) * to_f32(w);
                radiance += term;
                rec.event(|| Event::LightFound { radiance: scene.environment().radiance(d), mis_weight: w });
                rec.contribution(ContributionKind::Environment, term);
                break;
            };
            travelled += h.t * ray.dir.length();
            // Where a texture changes the material, the interaction's copy
            // of it lives here (the scene's own is borrowed otherwise).
            let mut scratch = MaybeUninit::uninit();
            let si = SurfaceInteraction::along_cone(
                scene,
                &ray,
                d,
                &h,
                self.cone.width_at(travelled),
                &mut scratch,
            );
            let (sp, wo) = (si.point, si.wo);
            // A translucent object's surface is its dielectric boundary; the
            // medium inside does the rest (step 6).
            let medium = si.material.subsurface.filter(|_| self.subsurface);
            let boundary;
            let m = if medium.is_some() {
                boundary = si.material.boundary();
                &boundary
            } else {
                si.material
            };

            // A path inside a physically based object with an absorbing
            // volume keeps e^(−σ·distance) (Beer–Lambert).
            if !si.front()
                && let Some(p) = m.physical
            {
                beta *= p.transmittance(to_f32(h.t * ray.dir.length()));
            }

            // 1. Emission found by this ray.
            if m.is_emissive() && si.front() {
                let w = found_light_weight(previous, |p| match scene.emitter_index(h.object) {
                    Some(i) => {
                        let distance = (sp.p - p).length();
                        let source = Source::Emitter(i);
                        lights.probability(source) * scene.light_source(source).pdf(p, d, distance, sp.normal)
                    }
                    None => 0.0,
                });
                let term = beta * m.emission * to_f32(w);
                radiance += term;
                rec.event(|| Event::LightFound { radiance: m.emission, mis_weight: w });
                rec.contribution(ContributionKind::Emission, term);
            }

            // 2. The last surface that may scatter.
            bounce += 1;
            if bounce > self.settings.max_bounces {
                rec.event(|| Event::Stopped { reason: "max_bounces" });
                break;
            }
            sampler.start_bounce(bounce);
            // A translucent object's boundary stays flat: the walk's inside
            // and outside are the facets' (step 6).
            let bsdf = si.hit_bsdf_of(m, si.shading_normal.filter(|_| medium.is_none()));

            // 3. Next-event estimation, and 4. BSDF sampling. Both samples
            // are drawn before the shadow ray is cast (the sampler's values in
            // the order light, then BSDF): the light's direction is a chain of
            // square roots and divisions that the shadow ray waits for, and the
            // BSDF's sample does not depend on it, so the processor works on
            // both at once.
            let light = bsdf.has_smooth_lobes().then(|| {
                let u = sampler.get_1d();
                let uv = sampler.get_2d();
                self.light_sample(&sp, lights, u, uv)
            });
            let u = sampler.get_1d();
            let scattered = bsdf.sample(wo, u, sampler.get_2d());
            if let Some(light) = light {
                let term = beta * self.next_event(&sp, &bsdf, wo, light, counts, rec);
                radiance += term;
                rec.contribution(ContributionKind::NextEvent, term);
            }
            let Some(s) = scattered else {
                rec.event(|| Event::Stopped { reason: "no_scatter" });
                break;
            };
            beta *= s.weight;
            rec.event(|| Event::Scatter {
                direction: s.wi,
                pdf: s.pdf,
                delta: s.lobe.is_delta(),
                weight: s.weight,
                throughput: beta,
            });
            if beta.max_element() <= 0.0 || !beta.is_finite() {
                rec.event(|| Event::Stopped { reason: "zero_throughput" });
                break;
            }
            previous =
                if s.lobe.is_delta() { Previous::Specular } else { Previous::Smooth { p: sp.p, pdf: s.pdf } };
            if !s.lobe.is_delta() {
                smooth_bounces += 1;
            }
            if s.lobe.is_transmission() {
                eta_scale *= to_f32(s.eta * s.eta);
            }

            // 5. Russian roulette.
            if self.settings.russian_roulette && smooth_bounces >= ROULETTE_FROM {
                // Exactly max(β) without refractions (η² = 1).
                let survive = beta.max_element() * eta_scale;
                if survive < 1.0 {
                    let u = sampler.get_1d();
                    let survived = to_f32(u) < survive;
                    rec.event(|| Event::Roulette { survive: survive as Real, survived });
                    if to_f32(u) >= survive {
                        rec.event(|| Event::Stopped { reason: "roulette" });
                        break;
                    }
                    beta /= survive;
                }
            }

            // 6. Into a translucent object: a random walk to where the
            // light comes out.
            if let Some(medium) = medium
                && s.wi.dot(sp.normal) < 0.0
            {
                sampler.start_walk(bounce);
                let walk = RandomWalk::new(scene, self.settings);
                let end = walk.walk(h.object, &medium, m, &sp, s.wi, beta, sampler, counts, rec);
                // The walk leaves through the boundary it came in by: its
                // refraction out undoes the η² of the one in. (The walk's own
                // roulette weighs β as it is: taking η² out there too made
                // the subsurface scenes' samples 40–80 % dearer for about as
                // much less noise.)
                eta_scale /= to_f32(s.eta * s.eta);
                match end {
                    WalkEnd::Ended => {
                        rec.event(|| Event::Stopped { reason: "walk_ended" });
                        break;
                    }
                    WalkEnd::Out { ray: out, hit: out_hit, weight } => {
                        (ray, hit) = (out, out_hit);
                        beta *= weight;
                    }
                    WalkEnd::Escaped { ray: out, weight } => {
                        (ray, hit) = (out, None);
                        beta *= weight;
                    }
                }
                previous = Previous::Specular;
                continue;
            }

            counts.bounce += 1;
            ray = Ray::new(sp.spawn_origin(s.wi), s.wi);
            hit = scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY));
            rec.ray(SegmentKind::Bounce, &ray, hit.as_ref(), Some(beta));
        }
        radiance
    }

    /// The light sample of next-event estimation at `sp`: a light chosen by
    /// the [`LightSampler`] with `u`, and a direction towards it drawn with
    /// `uv` ([`crate::lights::light_source::LightSource::sample`]), with the
    /// light's choice probability; `None` where there is no light or no
    /// direction.
    #[inline(always)]
    fn light_sample(
        &self,
        sp: &SurfacePoint,
        lights: &LightSampler,
        u: Real,
        uv: (Real, Real),
    ) -> Option<(Source, Real, LightSample)> {
        let (source, chosen) = lights.choose(u)?;
        let s = self.scene.light_source(source).sample(sp.p, uv)?;
        Some((source, chosen, s))
    }

    /// One light sample's contribution at `sp` (throughput not applied):
    /// for `light`, what [`PathTracer::light_sample`] drew (`None` when it
    /// drew nothing), unless a shadow ray finds something in the way,
    /// `f·cos θ·weight·w/P(light)` with w the power heuristic of the light's
    /// density against the BSDF's (1 for a light no ray can find).
    fn next_event<R: Recorder>(
        &self,
        sp: &SurfacePoint,
        bsdf: &HitBsdf,
        wo: Vec3,
        light: Option<(Source, Real, LightSample)>,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        let Some((source, chosen, s)) = light else { return Color::ZERO };
        let f = bsdf.eval(wo, s.wi);
        if f == Color::ZERO {
            return Color::ZERO;
        }
        let w = match s.pdf {
            Some(pdf) => bsdf::power_heuristic(chosen * pdf, bsdf.pdf(wo, s.wi)),
            None => 1.0,
        };
        rec.event(|| Event::NextEvent {
            light: match source {
                Source::Light(i) => format!("light {i}"),
                Source::Emitter(i) => format!("emitter {i}"),
                Source::Environment => "environment".to_owned(),
            },
            probability: chosen,
            light_pdf: s.pdf,
            bsdf_pdf: bsdf.pdf(wo, s.wi),
            mis_weight: w,
            bsdf: f,
            segment: None,
        });
        if s.shadows {
            counts.next_event += 1;
            let shadow = Ray::new(sp.spawn_origin(s.wi), s.wi);
            let blocked = self.scene.any_hit(&shadow, Interval::new(0.0, s.distance));
            rec.probe(SegmentKind::NextEvent { blocked }, &shadow, s.distance);
            if blocked {
                return Color::ZERO;
            }
        }
        f * s.weight * to_f32(bsdf.cosine(s.wi) * w / chosen)
    }
}

/// The multiple-importance weight of light that a ray drawn by `previous`
/// found (step 1): 1 after the camera or a δ lobe, which light sampling
/// cannot produce; else the power heuristic of the BSDF's density against
/// `light_pdf(p)`, the density with which next-event estimation from the
/// previous point p would have sampled the same direction (the light's
/// choice probability times its own density).
fn found_light_weight(previous: Previous, light_pdf: impl FnOnce(Vec3) -> Real) -> Real {
    match previous {
        Previous::Specular => 1.0,
        Previous::Smooth { p, pdf } => bsdf::power_heuristic(pdf, light_pdf(p)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::scene_file::LoadedScene;
    use crate::materials::material::Material;
    use crate::materials::texture_slot::TextureSlot;
    use crate::render::Frame;
    use crate::render::settings::{ImageSize, RenderSettings};
    use crate::scene::effects::Effects;
    use crate::testing::test_support::{renderer, renderer_of};
    use std::path::Path;

    fn scene(text: &str) -> LoadedScene {
        crate::parse_scene(text, "test.ron", Path::new(".")).unwrap()
    }

    fn render(s: &LoadedScene, width: u32, height: u32, spp: u32) -> Frame {
        renderer(s, width, height, spp).render(|_| {})
    }

    /// A diffuse sphere of albedo `albedo` filling most of the view, inside a
    /// background of radiance 1.
    fn furnace(albedo: f32, effects: &str) -> LoadedScene {
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

    /// A closed room seen from inside, every wall Lambertian of albedo
    /// `albedo` and glowing with radiance `emission` towards the inside, with
    /// the camera at (0.3, −0.2, 0.1) looking at the wall beyond (0, 0, 1).
    /// `room` 0 is a regular icosahedron of circumradius 1.9 as one mesh
    /// wound inwards (one emitter of 20 triangles); `room` 1 is the box
    /// [−1, 1]×[−1.2, 1.2]×[−1.5, 1.5] as six inward-facing polygons (six
    /// emitters, chosen by area). The background (0.3) lies outside: it
    /// must never show, and next-event estimation still samples it, its
    /// shadow rays always blocked.
    fn glowing_room(room: usize, albedo: f32, emission: f32, gi: GlobalIllumination) -> LoadedScene {
        glowing_room_around(room, albedo, emission, gi, Vec::new())
    }

    /// [`glowing_room`] with `inside` (primitives and their materials, none
    /// glowing) in it too.
    fn glowing_room_around(
        room: usize,
        albedo: f32,
        emission: f32,
        gi: GlobalIllumination,
        inside: Vec<(crate::geometry::primitive::Primitive, Material)>,
    ) -> LoadedScene {
        use crate::camera::{Camera, Projection};
        use crate::geometry::mesh::Mesh;
        use crate::geometry::polygon::Polygon;
        use crate::geometry::primitive::Primitive;
        use crate::scene::SceneBuilder;
        let camera = Camera::new(
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::Y,
            100.0,
            0.5,
            Projection::Perspective,
        )
        .unwrap();
        let settings = RenderSettings {
            image: ImageSize::new(8, 8).unwrap(),
            effects: Effects { global_illumination: Some(gi), ..Effects::default() },
            ..RenderSettings::default()
        };
        let wall = Material { emission: Color::splat(emission), ..Material::flat(Color::splat(albedo)) };
        let b = SceneBuilder::new().background(Color::splat(0.3)).material("wall", wall);
        let primitives = if room == 0 {
            let (corners, faces) = crate::geometry::mesh::icosahedron();
            // Corner 0 is (−1, φ, 0), at the circumradius.
            let scale = 1.9 / corners[0].iter().map(|x| x * x).sum::<f64>().sqrt();
            let positions = corners
                .iter()
                .map(|c| Vec3::new(c[0] as Real, c[1] as Real, c[2] as Real) * scale as Real)
                .collect();
            // Reversed: (b−a)×(c−a) points inwards, where the walls glow.
            let inward = faces.iter().map(|&[a, b, c]| [a, c, b]).collect();
            vec![Primitive::Mesh(Mesh::new(positions, inward).unwrap())]
        } else {
            let half = Vec3::new(1.0, 1.2, 1.5);
            (0..6)
                .map(|face| {
                    let (axis, sign) = (face / 2, if face % 2 == 0 { -1.0 } else { 1.0 });
                    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
                    let corner = |a: Real, b: Real| {
                        let mut c = Vec3::ZERO;
                        c[axis] = sign * half[axis];
                        c[u] = a * half[u];
                        c[v] = b * half[v];
                        c
                    };
                    let square =
                        vec![corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
                    // Wound about +axis; a wall at +axis must face −axis.
                    let square = if sign > 0.0 { square.into_iter().rev().collect() } else { square };
                    Primitive::Polygon(Polygon::new(square).unwrap())
                })
                .collect()
        };
        for p in &primitives {
            // Every wall faces the room's centre.
            if let Primitive::Polygon(q) = p {
                assert!(q.normal().dot(q.points()[0]) < 0.0, "{:?}", q.points());
            }
        }
        let b = primitives.into_iter().fold(b, |b, p| b.object(p, "wall"));
        let b = inside.into_iter().enumerate().fold(b, |b, (i, (p, m))| {
            let name = format!("inside {i}");
            b.material(&name, m).object(p, &name)
        });
        LoadedScene { scene: b.build().unwrap(), camera, settings }
    }

    /// A perfect mirror ball and a glass ball (index 1.5) of colour `tint`
    /// (1: clear, absorbing nothing), in front of [`glowing_room`]'s camera.
    fn mirror_and_glass(tint: f32) -> Vec<(crate::geometry::primitive::Primitive, Material)> {
        use crate::geometry::primitive::Primitive;
        use crate::geometry::sphere::Sphere;
        let ball = |x: Real| Primitive::Sphere(Sphere::new(Vec3::new(x, -0.1, 0.9), 0.35).unwrap());
        let mirror = Material { diffuse: 0.0, reflectivity: 1.0, ..Material::flat(Color::ONE) };
        let glass =
            Material { diffuse: 0.0, transparency: 1.0, ior: 1.5, ..Material::flat(Color::splat(tint)) };
        vec![(ball(-0.3), mirror), (ball(0.45), glass)]
    }

    /// Every sample of every pixel of an 8×8 image of `s`, `spp` each.
    fn every_sample(s: &LoadedScene, spp: u32) -> (Vec<Color>, RayCounts) {
        let r = renderer(s, 8, 8, spp);
        let mut counts = RayCounts::default();
        let samples = (0..8)
            .flat_map(|y| (0..8).flat_map(move |x| (0..spp).map(move |k| (x, y, k))))
            .map(|(x, y, k)| r.sample(x, y, k, &mut counts))
            .collect();
        (samples, counts)
    }

    #[test]
    fn a_glowing_room_seen_from_inside_sums_the_bounces_of_its_emission() {
        // Inside a closed room whose walls all have albedo ρ and glow with
        // L_e, the radiance L_k reaching any point after k scatterings is the
        // same everywhere (the walls are Lambertian, so L_(k+1) = ρ·L_k over
        // the whole closed sphere of directions): following at most N
        // scatterings, a camera ray gathers L_e·(1 + ρ + … + ρ^N) =
        // L_e·(1 − ρ^(N+1))/(1 − ρ), whatever the room's shape, for any
        // N ≥ 0 (N = 0: the emission it meets), with Russian roulette or
        // without. Emission is met at every bounce, both by BSDF sampling
        // and by next-event estimation, so this checks their MIS weights
        // (and, with six walls, the probability of choosing each), the
        // bounce count, and roulette's reweighting past ROULETTE_FROM.
        //
        // Estimator: the mean of n = 8·8·spp samples; σ is measured from the
        // samples themselves (their standard error, `mean_and_error`), and
        // the bound is 5σ (+ 1e-5 relative for the f32 sums), a false
        // failure < 6e-7 per check, 2e-5 over the 28 checks. Without roulette
        // the bound also tells N from N ± 1 (asserted).
        for room in 0..2 {
            for albedo in [0.5f32, 0.8] {
                for (max_bounces, russian_roulette, spp) in [
                    (0, false, 4),
                    (1, false, 256),
                    (2, false, 256),
                    (5, false, 256),
                    (5, true, 512),
                    (40, false, 64),
                    (1024, true, 512),
                ] {
                    let gi = GlobalIllumination { max_bounces, russian_roulette, max_walk_steps: 16 };
                    let s = glowing_room(room, albedo, 1.0, gi);
                    let (samples, counts) = every_sample(&s, spp);
                    let (mean, error) = mean_and_error(&samples);
                    let exact = |n: u32| (1.0 - (albedo as f64).powi(n as i32 + 1)) / (1.0 - albedo as f64);
                    let bound = 5.0 * error.x as f64 + 1e-5 * exact(max_bounces);
                    let what = format!(
                        "room {room}, ρ {albedo}, N {max_bounces}, roulette {russian_roulette}: {mean} ± {error}, exact {}",
                        exact(max_bounces)
                    );
                    assert_eq!(counts.bounce == 0, max_bounces == 0, "{what}");
                    assert!(mean.x == mean.y && mean.y == mean.z, "{what}");
                    assert!((mean.x as f64 - exact(max_bounces)).abs() < bound, "{what}");
                    if max_bounces < 40 && !russian_roulette {
                        // The bound tells N from N ± 1 (the nearer, N + 1, is
                        // ρ^(N+1) away); roulette's paths are noisier (σ per
                        // sample 0.6 against 0.15 at ρ = 0.5, 3.9 against 0.33 at
                        // ρ = 0.8), its bound 3 to 8 times wider with twice the samples.
                        let gap = exact(max_bounces + 1) - exact(max_bounces);
                        assert!(2.0 * bound < gap, "{what}: bound {bound} cannot tell N ± 1 apart");
                    }
                }
            }
        }
    }

    #[test]
    fn a_sphere_in_the_furnace_reflects_its_albedo_in_every_pixel() {
        // A diffuse sphere of albedo ρ under a uniform background of 1: each
        // of its points sees only the background (it is convex), so sends
        // back exactly ρ, for any bounce count ≥ 1, with or without roulette
        // (which never acts: paths leave after their first bounce). ρ = 1
        // is the white furnace: the sphere disappears.
        //
        // Each sample's primary ray is cast here, so each sample is known to
        // see the sphere or the background. The background is exactly 1.
        // The sphere's samples estimate ρ by one-sample MIS of the BSDF's
        // cosine-weighted direction and one light sample of the environment
        // (uniform over the sphere of directions); the environment is the
        // same in every direction, so the estimator's distribution is the
        // same at every point of the sphere, and its σ is measured once from
        // all of them (0.25·ρ; n ≈ 109 000 per image). Every pixel's mean
        // over its n_p sphere samples (up to 1024) is within 5σ/√n_p of ρ
        // (±3.9 % for a pixel inside the disk), and the mean of all within
        // 5σ/√n (±0.4 %): 145 checks per image at < 6e-7 each.
        use crate::camera::view_plane::ViewPlane;
        let spp = 1024;
        for (albedo, effects) in [
            (0.5f32, "max_bounces: 1"),
            (1.0, "max_bounces: 3"),
            (0.8, "max_bounces: 50, russian_roulette: false"),
        ] {
            let s = furnace(albedo, effects);
            let tracer = PathTracer::new(&s.scene, s.settings.effects.global_illumination.unwrap(), true);
            let view = ViewPlane::new(s.camera, 12, 12).unwrap();
            let mut counts = RayCounts::default();
            let mut pixels = Vec::new();
            for (x, y) in (0..12).flat_map(|y| (0..12).map(move |x| (x, y))) {
                let mut sphere = Vec::new();
                for k in 0..spp {
                    let (sx, sy) = crate::sampling::sampler::SampleRng::seeded(x, y, k, 7).next_pair();
                    let ray = view.primary_ray(x, y, sx, sy);
                    let hit = s.scene.cast(&ray);
                    let mut sampler = Sampler::new(1, 0);
                    sampler.start_pixel_sample(x, y, k);
                    let c = tracer.trace_primary_hit(
                        &ray,
                        hit,
                        &mut sampler,
                        &mut counts,
                        &mut crate::explain::recorder::NoRecorder,
                    );
                    match hit {
                        None => assert_eq!(c, Color::ONE, "{effects}: background at ({x}, {y})"),
                        Some(_) => sphere.push(c),
                    }
                }
                pixels.push(((x, y), sphere));
            }
            let all: Vec<Color> = pixels.iter().flat_map(|(_, p)| p.iter().copied()).collect();
            let (mean, error) = mean_and_error(&all);
            let sigma = error.x * (all.len() as f32).sqrt();
            let what = format!("ρ {albedo}, {effects}: {mean} ± {error} over {} samples", all.len());
            assert!(all.len() > 100_000 && sigma > 0.0, "{what}");
            assert!(mean.x == mean.y && mean.y == mean.z, "{what}");
            assert!((mean.x - albedo).abs() < 5.0 * error.x, "{what}");
            for ((x, y), p) in pixels.iter().filter(|(_, p)| !p.is_empty()) {
                let m = p.iter().map(|c| c.x).sum::<f32>() / p.len() as f32;
                let bound = 5.0 * sigma / (p.len() as f32).sqrt();
                assert!((m - albedo).abs() < bound, "{what}: pixel ({x}, {y}) {m} over {}", p.len());
            }
        }
        // Without bounces the sphere is black; the background still shows.
        let f = render(&furnace(0.5, "max_bounces: 0"), 12, 12, 4);
        assert_eq!(f.pixels[6 * 12 + 6], Color::ZERO);
        assert_eq!(f.pixels[0], Color::ONE);
    }

    #[test]
    fn a_glowing_room_sums_the_bounces_of_its_emission_with_sobol_samples_too() {
        // The room above, its samples drawn from Owen-scrambled Sobol
        // points: each bounce's dimensions of its own, roulette drawing
        // or not. The estimate stays unbiased (the mean within 5 standard
        // errors of the exact sum; the error, measured as if the samples
        // were independent, overstates a stratified estimate's, so the
        // check is if anything looser than 5σ).
        use crate::sampling::sampler::SamplerKind;
        for room in 0..2 {
            for (max_bounces, russian_roulette, spp) in [(2, false, 256), (5, true, 512), (1024, true, 512)] {
                let albedo = 0.8f32;
                let gi = GlobalIllumination { max_bounces, russian_roulette, max_walk_steps: 16 };
                let mut s = glowing_room(room, albedo, 1.0, gi);
                s.settings.sampler = SamplerKind::Sobol;
                let (samples, _) = every_sample(&s, spp);
                let (mean, error) = mean_and_error(&samples);
                let exact = (1.0 - (albedo as f64).powi(max_bounces as i32 + 1)) / (1.0 - albedo as f64);
                let what = format!(
                    "room {room}, N {max_bounces}, roulette {russian_roulette}: {mean} ± {error}, exact {exact}"
                );
                assert!((mean.x as f64 - exact).abs() < 5.0 * error.x as f64 + 1e-5 * exact, "{what}");
            }
        }
    }

    #[test]
    fn a_glowing_room_with_a_mirror_and_glass_inside_still_sums_every_bounce_with_roulette() {
        // Neither ball absorbs anything, so with them in the room the
        // radiance everywhere outside them is still the walls' uniform
        // L_e·(1 + ρ + ρ² + …) = L_e/(1 − ρ): the mirror shows other walls,
        // and the glass gives back what it gets (F reflected; 1 − F refracted
        // in with 1/η² and out again with η²). Paths here take δ bounces,
        // which roulette does not count, and refract, whose η² roulette takes
        // back out of β: whatever the survival probability, the estimate
        // must stay unbiased (the mean within 5σ of the exact sum, ρ^1025
        // far below the bound), with both samplers.
        use crate::sampling::sampler::SamplerKind;
        for albedo in [0.5f32, 0.8] {
            for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
                let gi = GlobalIllumination { max_bounces: 1024, russian_roulette: true, max_walk_steps: 16 };
                let mut s = glowing_room_around(1, albedo, 1.0, gi, mirror_and_glass(1.0));
                s.settings.sampler = kind;
                let (samples, counts) = every_sample(&s, 512);
                let (mean, error) = mean_and_error(&samples);
                let exact = 1.0 / (1.0 - albedo as f64);
                let what = format!("ρ {albedo}, {kind:?}: {mean} ± {error}, exact {exact}");
                assert!(counts.bounce > 0 && error.x > 0.0, "{what}");
                assert!(mean.x == mean.y && mean.y == mean.z, "{what}");
                assert!((mean.x as f64 - exact).abs() < 5.0 * error.x as f64 + 1e-5 * exact, "{what}");
            }
        }
    }

    #[test]
    fn roulette_waits_for_three_smooth_bounces_and_takes_the_refractions_eta_out_of_beta() {
        // Every event of 8·8·64 paths in the room with the mirror ball and a
        // glass ball that lets half the light through: each roulette comes
        // after at least ROULETTE_FROM bounces that sampled a smooth lobe,
        // however many δ bounces came first, and its survival probability
        // is max(β) times η² = 1.5² inside the glass (entered from the room:
        // β carries 1/η² there) and times 1 outside. (In clear glass, β is
        // max(β) = 1 just after a roulette times (1 − F)/η², so with η² taken
        // back out it would survive without a draw; the tint makes it draw.)
        use crate::camera::view_plane::ViewPlane;
        struct Events(Vec<Event>);
        impl Recorder for Events {
            const ACTIVE: bool = true;
            fn event(&mut self, make: impl FnOnce() -> Event) {
                self.0.push(make());
            }
        }
        let gi = GlobalIllumination { max_bounces: 64, russian_roulette: true, max_walk_steps: 16 };
        let s = glowing_room_around(1, 0.8, 1.0, gi, mirror_and_glass(0.5));
        let tracer = PathTracer::new(&s.scene, gi, true);
        let view = ViewPlane::new(s.camera, 8, 8).unwrap();
        let mut counts = RayCounts::default();
        let (mut outside, mut inside, mut after_delta) = (0, 0, 0);
        for (x, y) in (0..8).flat_map(|y| (0..8).map(move |x| (x, y))) {
            for k in 0..64 {
                let (sx, sy) = crate::sampling::sampler::SampleRng::seeded(x, y, k, 3).next_pair();
                let ray = view.primary_ray(x, y, sx, sy);
                let mut sampler = Sampler::new(1, 0);
                sampler.start_pixel_sample(x, y, k);
                let mut events = Events(Vec::new());
                tracer.trace_primary_hit(&ray, s.scene.cast(&ray), &mut sampler, &mut counts, &mut events);
                let (mut smooth, mut delta, mut beta) = (0, 0, Color::ZERO);
                for e in events.0 {
                    match e {
                        Event::Scatter { delta: d, throughput, .. } => {
                            if d {
                                delta += 1
                            } else {
                                smooth += 1
                            }
                            beta = throughput;
                        }
                        Event::Roulette { survive, .. } => {
                            assert!(
                                smooth >= ROULETTE_FROM,
                                "({x}, {y}) #{k}: roulette after {smooth} smooth bounces"
                            );
                            after_delta += usize::from(delta > 0);
                            let ratio = to_f32(survive) / beta.max_element();
                            if (ratio - 1.0).abs() < 1e-5 {
                                outside += 1;
                            } else {
                                assert!(
                                    (ratio - 2.25).abs() < 1e-5,
                                    "({x}, {y}) #{k}: survival {ratio}·max(β)"
                                );
                                inside += 1;
                            }
                        }
                        _ => {}
                    }
                }
            }
        }
        assert!(outside > 100 && inside > 0 && after_delta > 0, "{outside} {inside} {after_delta}");
    }

    /// A grey floor lit by one point light, with `effects`.
    fn lit_floor(effects: &str) -> LoadedScene {
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
        let r = renderer(&s, 16, 12, 4);
        let run = |threads| crate::testing::test_support::render_on_threads(&r, threads);
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
        let d = renderer(&direct, 3, 3, 1).render(|_| {});
        assert_eq!(d.pixels[centre], Color::ZERO);
        let gi = scene(&text("effects: (global_illumination: (max_bounces: 4)),"));
        let f = renderer(&gi, 3, 3, 512).render(|_| {});
        assert!(f.pixels.iter().all(|c| c.is_finite()));
        // About (0.8/π)·10·(π·1²/5²)·T ≈ 0.3 with T ≈ 0.92 the slab's transmittance.
        assert!(f.pixels[centre].x > 0.1, "{}", f.pixels[centre]);
    }

    #[test]
    fn light_through_a_physically_based_volume_keeps_e_to_the_minus_sigma_times_its_path_inside() {
        // An index-matched (ior 1), smooth, fully transmissive sphere of
        // radius 1 with attenuation colour (0.5, 0.25, 1) at distance 2, in
        // a background of radiance 1: the ray through the centre crosses 2
        // units inside and keeps exactly the attenuation colour
        // (Beer–Lambert, σ = −ln(colour)/distance); nothing reflects at an
        // index-matched boundary. Without attenuation it keeps everything.
        let text = |volume: &str| {
            format!(
                r#"(
                camera: (position: (0, 0, -4), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 10, near: 1),
                image: (width: 3, height: 3),
                background: (1, 1, 1),
                materials: {{ "m": (base_color: (1, 1, 1), roughness: 0, transmission: 1, ior: 1{volume}) }},
                objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "m") ],
                effects: (global_illumination: (max_bounces: 8)),
            )"#
            )
        };
        let centre = 4;
        let f =
            render(&scene(&text(", attenuation_color: (0.5, 0.25, 1), attenuation_distance: 2")), 3, 3, 1);
        let got = f.pixels[centre];
        assert!((got - Color::new(0.5, 0.25, 1.0)).abs().max_element() < 1e-4, "{got}");
        let clear = render(&scene(&text("")), 3, 3, 1).pixels[centre];
        assert!((clear - Color::ONE).abs().max_element() < 1e-5, "{clear}");
    }

    /// A scene with one translucent `object` of albedo `albedo`, mean free
    /// paths `mfp` and index `ior`, in a background of radiance 1 and
    /// nothing else, seen from −z.
    fn translucent(object: &str, albedo: [f32; 3], mfp: [f32; 3], ior: f32, fov: f32) -> LoadedScene {
        let v = |c: [f32; 3]| format!("({:?}, {:?}, {:?})", c[0], c[1], c[2]);
        scene(&format!(
            r#"(
            camera: (position: (0, 0, -4), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: {fov:?}, near: 1),
            image: (width: 8, height: 8),
            background: (1, 1, 1),
            materials: {{ "m": (color: (1, 1, 1), ior: {ior:?}, subsurface: (albedo: {}, mean_free_path: {})) }},
            objects: [ {object} ],
            effects: (global_illumination: (max_bounces: 1024)),
        )"#,
            v(albedo),
            v(mfp)
        ))
    }

    /// The mean and standard error per channel over every sample of every
    /// pixel of `f` (rendered with `spp` samples).
    fn mean_and_error(pixels: &[Color]) -> (Color, Color) {
        let n = pixels.len() as f32;
        let mean = pixels.iter().copied().sum::<Color>() / n;
        let var = pixels.iter().map(|&c| (c - mean) * (c - mean)).sum::<Color>() / (n - 1.0);
        (mean, (var / n).powf(0.5))
    }

    #[test]
    fn a_translucent_object_that_absorbs_nothing_returns_all_light_in_the_white_furnace() {
        // Albedo 1 in a background of radiance 1: whatever enters comes out,
        // after however many scattering events, so every pixel is 1 (within
        // noise) for a sphere and a box, index-matched or behind glass, with
        // equal and with very different mean free paths per channel.
        for object in [
            "Sphere(center: (0, 0, 0), radius: 1, material: \"m\")",
            "Aabb(min: (-0.8, -0.8, -0.8), max: (0.8, 0.8, 0.8), material: \"m\")",
        ] {
            for (mfp, ior) in
                [([0.2; 3], 1.0), ([0.2; 3], 1.5), ([0.05, 0.2, 0.6], 1.0), ([0.05, 0.2, 0.6], 1.33)]
            {
                let s = translucent(object, [1.0; 3], mfp, ior, 20.0);
                let r = renderer(&s, 8, 8, 1);
                // Every sample of every pixel, one by one, for the error bar.
                let mut counts = RayCounts::default();
                let samples: Vec<Color> = (0..8)
                    .flat_map(|y| (0..8).flat_map(move |x| (0..64).map(move |k| (x, y, k))))
                    .map(|(x, y, k)| r.sample(x, y, k, &mut counts))
                    .collect();
                let (mean, error) = mean_and_error(&samples);
                assert!(counts.walk_steps > 0, "{object}");
                for c in 0..3 {
                    assert!(
                        (mean[c] - 1.0).abs() < 4.0 * error[c] + 1e-3,
                        "{object}, mfp {mfp:?}, ior {ior}: {mean} ± {error}"
                    );
                }
            }
        }
    }

    #[test]
    fn unscattered_light_through_an_absorbing_slab_follows_beer_lambert() {
        // An index-matched slab 0.5 thick that absorbs whatever it meets
        // (albedo 0), looked through along its normal at a background of 1:
        // what arrives is T_c = exp(−σt_c·d) per channel.
        //
        // The walk draws its free flight with a hero channel chosen
        // uniformly (spectral MIS, `WalkWeight`): the light gets through with
        // probability p̄ = ⅓·Σ_c T_c and then carries T_c/p̄ in channel c,
        // else it is absorbed at its first scattering and carries 0. Each
        // sample is checked to be one of the two (to f32 rounding), and the
        // fraction f that got through, binomial, to be within 5σ of p̄:
        // n = 2²⁰ samples, σ = √(p̄(1 − p̄)/n) ≈ 4.7e-4 for p̄ ≈ 0.37, a
        // bound of ±0.64 % of each channel's transmittance.
        let slab = "Aabb(min: (-3, -3, -0.25), max: (3, 3, 0.25), material: \"m\")";
        let mfp = [0.25f32, 0.5, 1.0];
        let s = translucent(slab, [0.0; 3], mfp, 1.0, 0.5);
        let r = renderer(&s, 8, 8, 1);
        let exact = Color::new((-0.5 / mfp[0]).exp(), (-0.5 / mfp[1]).exp(), (-0.5 / mfp[2]).exp());
        let through = exact.element_sum() / 3.0;
        let carried = exact / through;
        let n = 1u32 << 20;
        let mut counts = RayCounts::default();
        let mut passed = 0u32;
        for k in 0..n {
            let c = r.sample(4, 4, k, &mut counts);
            if c != Color::ZERO {
                passed += 1;
                assert!((c - carried).abs().max_element() < 1e-4, "sample {k}: {c}, not 0 or {carried}");
            }
        }
        let fraction = passed as f64 / n as f64;
        let p = through as f64;
        let sigma = (p * (1.0 - p) / n as f64).sqrt();
        assert!((fraction - p).abs() < 5.0 * sigma, "{fraction} got through, exact {p} ± {sigma}");
    }

    /// Chandrasekhar's H-function of isotropic scattering with albedo ω at μ,
    /// from its integral equation `H(μ) = 1 + (ω/2)·μ·H(μ)·∫₀¹ H(μ')/(μ + μ') dμ'`
    /// (Chandrasekhar, *Radiative Transfer*, 1950, ch. V), solved by
    /// iteration on a 64-point Gauss–Legendre grid (H(1) = 2.9056 for ω = 1,
    /// against the tabulated 2.9078).
    fn chandrasekhar_h(omega: f64, mu: f64) -> f64 {
        // 64-point Gauss–Legendre nodes on [0, 1] by Newton's method.
        let n = 64;
        let mut nodes = Vec::new();
        for i in 1..=n {
            let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                x -= p1 / dp;
            }
            nodes.push(((x + 1.0) / 2.0, 1.0 / ((1.0 - x * x) * dp * dp)));
        }
        let mut h = vec![1.0; n];
        let next = |h: &[f64], m: f64| {
            1.0 / (1.0
                - omega / 2.0 * m * nodes.iter().zip(h).map(|(&(x, w), hx)| w * hx / (m + x)).sum::<f64>())
        };
        for _ in 0..2000 {
            h = nodes.iter().map(|&(x, _)| next(&h, x)).collect();
        }
        next(&h, mu)
    }

    #[test]
    fn an_optically_thick_slab_reflects_what_chandrasekhars_solution_says() {
        // A semi-infinite, index-matched, isotropically scattering medium
        // under uniform radiance 1, seen along its normal: by reciprocity the
        // pixel is the plane albedo for normal incidence, A(1) = 1 − H(1)·√(1 − ω).
        // The slab is 400 mean free paths deep and wide.
        //
        // Estimator: the mean of n samples of the centre pixel, σ measured
        // from them (per sample 0.32, 0.49 and 0.43 for ω = 0.5, 0.9, 0.99);
        // n = 2¹⁹, 2¹⁷ and 2¹⁵ (longer walks cost more) make 5σ ±1.9 %,
        // ±1.6 % and ±1.6 % of A(1). 1e-3 more covers the 64-point quadrature of
        // H (its worst error, at ω = 1, moves A by 2e-4 at ω = 0.99).
        assert!((chandrasekhar_h(1.0, 1.0) - 2.9078).abs() < 5e-3, "H(1) of a conservative medium");
        let slab = "Aabb(min: (-200, -200, 0), max: (200, 200, 400), material: \"m\")";
        for (omega, n) in [(0.5f32, 1 << 19), (0.9, 1 << 17), (0.99, 1 << 15)] {
            let s = translucent(slab, [omega; 3], [1.0; 3], 1.0, 0.5);
            let r = renderer(&s, 8, 8, 1);
            let mut counts = RayCounts::default();
            let samples: Vec<Color> = (0..n).map(|k| r.sample(4, 4, k, &mut counts)).collect();
            let (mean, error) = mean_and_error(&samples);
            let exact = (1.0 - chandrasekhar_h(omega as f64, 1.0) * (1.0 - omega as f64).sqrt()) as f32;
            assert!(
                (mean.x - exact).abs() < 5.0 * error.x + 1e-3,
                "ω {omega}: {} ± {}, exact {exact}",
                mean.x,
                error.x
            );
        }
    }

    #[test]
    fn walks_happen_only_where_asked_for() {
        // A scene without translucent materials casts no walk rays; one with
        // them casts them, unless the plan switches them off.
        let plain = render(&furnace(0.5, "max_bounces: 3"), 8, 8, 4).rays;
        assert_eq!((plain.subsurface, plain.walk_steps), (0, 0));
        let s = translucent(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"m\")",
            [0.9; 3],
            [0.2; 3],
            1.3,
            30.0,
        );
        let on = render(&s, 8, 8, 4).rays;
        assert!(on.subsurface > 0 && on.walk_steps > 0, "{on:?}");
        let toggles = crate::scene::effects::EffectToggles { subsurface: false, ..Default::default() };
        let settings = RenderSettings {
            toggles,
            image: ImageSize::new(8, 8).unwrap(),
            samples: crate::render::settings::SamplesPerPixel::new(4).unwrap(),
            ..s.settings
        };
        let off = crate::render::Renderer::new(&s.scene, s.camera, &settings).unwrap().render(|_| {}).rays;
        assert_eq!((off.subsurface, off.walk_steps), (0, 0));
        assert!(off.bounce > 0);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// Random scenes of every primitive with random materials (every lobe,
        /// emissive or not), lit by a point light and the background: no
        /// sample of any pixel is NaN, infinite or negative. Spheres and
        /// boxes whose material is drawn translucent get a random medium
        /// (albedo, mean free paths from 0.02 to 2 per channel, anisotropy),
        /// as does, in some scenes, a closed icosahedron; meshes carry
        /// tilted shading normals and texture coordinates, and some
        /// materials a random texture (with alpha), also as a strongly
        /// scaled normal map, and every alpha mode.
        #[test]
        fn no_sample_is_nan_infinite_or_negative_on_random_scenes(
            parts in crate::testing::test_support::random_parts(5.0, 6),
            materials in proptest::collection::vec(proptest::array::uniform8(0f32..1.0), 6),
            media in proptest::collection::vec(
                (proptest::bool::ANY, proptest::array::uniform3(0f32..1.0), proptest::array::uniform3(0.02f32..2.0), -0.9f32..0.9),
                6,
            ),
            textured in proptest::collection::vec(proptest::bool::ANY, 6),
            texels in proptest::array::uniform4(proptest::array::uniform3(0f32..1.0)),
            tilt in proptest::array::uniform3(-1.2f32..1.2),
            uv_scale in -3f32..3.0,
            icosahedron in proptest::option::of((proptest::array::uniform3(-4f32..4.0), 0.3f32..3.0, 0usize..6)),
            background in 0f32..2.0,
        ) {
            use crate::camera::{Camera, Projection};
            use crate::lights::light::{Light, LightKind};
            use crate::materials::material::Material;
            use crate::materials::medium::Subsurface;
            use crate::geometry::primitive::Primitive;
            use crate::scene::SceneBuilder;
            use crate::testing::test_support::{icosahedron_mesh, random_primitive_with_attributes, v};
            use crate::materials::texture::Texture;
            let camera = Camera::new(Vec3::new(0.0, 0.0, -12.0), Vec3::ZERO, Vec3::Y, 60.0, 1.0, Projection::Perspective).unwrap();
            let light = Light { kind: LightKind::Point { position: Vec3::new(1.0, 6.0, -3.0) }, power: Color::splat(20.0), shadows: true };
            let effects = Effects {
                global_illumination: Some(GlobalIllumination { max_bounces: 6, russian_roulette: true, max_walk_steps: 256 }),
                ..Effects::default()
            };
            let texture = Texture::new(2, 2, texels.iter().map(|&t| Color::from_array(t)).collect())
                .and_then(|t| t.with_alpha(texels.iter().map(|t| t[1]).collect()))
                .unwrap();
            let mut b = SceneBuilder::new()
                .background(Color::splat(background))
                .light(light)
                .texture(std::sync::Arc::new(texture));
            for (i, [c, kd, ks, s, kr, kt, ior, e]) in materials.iter().copied().enumerate() {
                let (kr, kt) = if kr + kt > 1.0 { (kr / 2.0, kt / 2.0) } else { (kr, kt) };
                let m = Material {
                    color: Color::new(c, 1.0 - c, 0.5),
                    diffuse: kd,
                    specular: ks,
                    specular_color: Color::new(1.0, c, 1.0 - c * 0.5),
                    shininess: s * s * 10_000.0,
                    reflectivity: kr,
                    transparency: kt,
                    ior: 0.5 + 3.0 * ior,
                    emission: if e > 0.7 { Color::splat(e * 5.0) } else { Color::ZERO },
                    subsurface: None,
                    base_color_texture: textured[i].then_some(crate::materials::texture_slot::TextureSlot::new(0)),
                    metallic_roughness_texture: None,
                    emissive_texture: None,
                    occlusion_texture: None,
                    // Half the materials physically based, from the same numbers.
                    physical: (ks > 0.5).then_some(crate::materials::principled::Principled {
                        metallic: kd,
                        roughness: s,
                        transmission: kt,
                        attenuation_color: Color::new(c, 0.5, 1.0).max(Color::splat(0.01)),
                        attenuation_distance: 0.1 + e,
                        clearcoat: kr,
                        clearcoat_roughness: s * 0.5,
                        specular: ior,
                        specular_color: Color::new(1.0, c, 0.5),
                    }),
                    // The texture as a normal map too, strongly scaled, and
                    // every alpha mode.
                    normal_texture: textured[i].then_some(TextureSlot {
                        scale: 1.0 + 4.0 * c,
                        ..TextureSlot::new(0)
                    }),
                    alpha: c,
                    alpha_mode: match (e * 3.0) as u32 {
                        0 => crate::materials::alpha::AlphaMode::Opaque,
                        1 => crate::materials::alpha::AlphaMode::Mask { cutoff: 0.3 },
                        _ => crate::materials::alpha::AlphaMode::Blend,
                    },
                };
                let (_, albedo, mfp, g) = media[i];
                let medium = Subsurface { albedo: Color::from_array(albedo), mean_free_path: Color::from_array(mfp), anisotropy: g };
                b = b.material(format!("m{i}"), m).material(format!("t{i}"), Material { subsurface: Some(medium), ..m });
            }
            for (i, (k, p, q, r)) in parts.into_iter().enumerate() {
                let Some(primitive) = random_primitive_with_attributes(k, p, q, r, tilt, uv_scale) else { continue };
                let closed = matches!(primitive, Primitive::Sphere(_) | Primitive::Aabb(_));
                let kind = if closed && media[i % 6].0 { "t" } else { "m" };
                b = b.object(primitive, format!("{kind}{}", i % 6));
            }
            if let Some((center, radius, material)) = icosahedron {
                b = b.object(Primitive::Mesh(icosahedron_mesh(v(center), radius as Real)), format!("t{material}"));
            }
            // Some polygons cannot glow (self-crossing ones); skip those scenes.
            let Ok(s) = b.build() else { return Ok(()) };
            let r = renderer_of(&s, camera, effects, (6, 4, 4));
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
