//! Hits → colours, without global illumination: a Whitted-style recursive
//! ray tracer (Whitted, "An Improved Illumination Model for Shaded Display",
//! 1980) with area lights and ambient occlusion, that casts only the rays its
//! [`EffectPlan`] allows. With global illumination the
//! [`crate::integrators::path_tracer`] takes over.
//!
//! Without lights the colour of a primary ray is its hit's flat material
//! colour, exactly as in pure ray casting. With lights it is the
//! direct-lighting part of the radiometric model of [`crate::materials::bsdf`]: a hit
//! with material `m`, BSDF f, seen from direction ω_o, gets
//!
//! - `m.emission`, if ω_o is on the side the geometric normal points to;
//! - ambient: `ambient·ao·ρ`, with ρ the albedo of the Lambert lobe
//!   (`(1 − kr − kt)·(1 − ks)·kd·color`): uniform radiance `ambient` from
//!   every unblocked direction, reflected by a Lambert surface;
//! - direct light: `Σ vis·f(ω_o, ω_i)·cos θ_i·E` over every light sample
//!   ([`crate::lights::light::LightSample`]), `vis` 0 or 1 from a shadow ray;
//! - reflection: `(kr·s + kt·F)·L(reflected ray)`, s the `specular_color`;
//! - refraction: `kt·(1 − F)·color·η²·L(refracted ray)` (η = ηᵢ/ηₜ, see
//!   [`crate::materials::bsdf`]), nothing on total internal reflection (F = 1 then).
//!
//! A reflected or refracted ray is cast only while the recursion depth is
//! below `max_depth` and its weight in the pixel (the product of the
//! reflection and transmission factors along its path, largest channel) is at
//! least [`MIN_WEIGHT`]: adaptive depth control (Hall and Greenberg, "A
//! Testbed for Realistic Image Synthesis", 1983). Without it two glass
//! objects would branch into 2^max_depth rays; with it a path dies after a
//! few weak Fresnel reflections, and a mirror with kr = 1 still bounces up to
//! `max_depth` times.
//!
//! F is the exact dielectric Fresnel reflectance; a ray arriving on the side
//! the geometric normal points to enters a medium of index `m.ior`, one
//! arriving from behind leaves it for air (index 1). Shadow rays treat every
//! object as opaque, glass too. Secondary rays start at the hit point pushed
//! off the surface by its error bound ([`crate::geometry::surface`]).

use std::mem::MaybeUninit;

use crate::explain::record::{ContributionKind, SegmentKind};
use crate::explain::recorder::Recorder;
use crate::geometry::hit::Hit;
use crate::geometry::surface::SurfacePoint;
use crate::integrators::interaction::SurfaceInteraction;
use crate::materials::shading::{fresnel_dielectric, reflect, refract};
use crate::materials::texture_lod::RayCone;
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{MIN_WEIGHT, Real, Vec3, normalize_robust, to_f32};
use crate::sampling::sampler::{Sampler, Strata, cosine_hemisphere_in};
use crate::scene::Scene;
use crate::scene::effects::{EffectPlan, RayCounts};

/// Traces rays through one scene under one effect plan.
#[derive(Clone, Copy, Debug)]
pub struct Tracer<'s> {
    scene: &'s Scene,
    plan: EffectPlan,
    /// A camera ray's cone, for texture level of detail.
    cone: RayCone,
}

impl<'s> Tracer<'s> {
    /// A tracer for `scene` that simulates what `plan` allows.
    pub fn new(scene: &'s Scene, plan: EffectPlan) -> Self {
        Self { scene, plan, cone: RayCone::POINT }
    }

    /// This tracer with camera rays of cone `cone` (one pixel's,
    /// [`RayCone::of_pixel`]): textures are read at the level of detail
    /// its footprint asks for, reflected and refracted rays' too
    /// ([`crate::materials::texture_lod`]).
    pub fn with_cone(self, cone: RayCone) -> Self {
        Self { cone, ..self }
    }

    /// The plan in force.
    pub fn plan(&self) -> &EffectPlan {
        &self.plan
    }

    /// The colour seen along a camera ray already cast: `hit` is what
    /// [`Scene::cast`] gave for `ray` (packets of primary rays are cast
    /// together, [`Scene::cast_all`]); `sampler` hands out this pixel
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
        rec.ray(SegmentKind::Primary, ray, hit.as_ref(), None);
        let Some(hit) = hit else {
            let background = self.scene.environment().radiance(ray.dir);
            rec.contribution(ContributionKind::Environment, background);
            rec.returned(background);
            return background;
        };
        if !self.plan.shading {
            let flat = self.scene.hit_color(&hit, ray, self.cone.width_at(hit.t * ray.dir.length()));
            rec.contribution(ContributionKind::Flat, flat);
            rec.returned(flat);
            return flat;
        }
        let color =
            self.shade(ray, &hit, Path { depth: 0, weight: 1.0, travelled: 0.0 }, sampler, counts, rec);
        rec.returned(color);
        color
    }

    /// The colour seen along a reflected or refracted ray.
    fn trace_secondary<R: Recorder>(
        &self,
        ray: &Ray,
        path: Path,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        let hit = self.scene.closest_hit(ray, Interval::new(0.0, Real::INFINITY));
        rec.found(hit.as_ref());
        match hit {
            Some(hit) => self.shade(ray, &hit, path, sampler, counts, rec),
            None => {
                let background = self.scene.environment().radiance(ray.dir);
                rec.contribution(ContributionKind::Environment, background);
                background
            }
        }
    }

    fn shade<R: Recorder>(
        &self,
        ray: &Ray,
        hit: &Hit,
        path: Path,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> Color {
        let travelled = path.travelled + hit.t * ray.dir.length();
        let mut scratch = MaybeUninit::uninit();
        let Some(si) = normalize_robust(ray.dir).map(|d| {
            SurfaceInteraction::along_cone(
                self.scene,
                ray,
                d,
                hit,
                self.cone.width_at(travelled),
                &mut scratch,
            )
        }) else {
            let background = self.scene.environment().radiance(ray.dir);
            rec.contribution(ContributionKind::Environment, background);
            return background;
        };
        let path = Path { travelled, ..path };
        let (sp, m, wo, d) = (&si.point, si.material, si.wo, -si.wo);
        let front = si.front();
        let n = si.facing_normal();

        let mut color = si.emitted();
        if color != Color::ZERO {
            rec.contribution(ContributionKind::Emission, color);
        }
        let shading = si.shading_normal;
        let bsdf = si.bsdf();
        if bsdf.has_smooth_lobes() {
            let lambert = bsdf.diffuse_albedo();
            if lambert != Color::ZERO && self.scene.ambient() != Color::ZERO {
                let ao = self.ambient_occlusion(sp, n, sampler, counts, rec);
                let term = self.scene.ambient() * lambert * ao;
                color += term;
                rec.contribution(ContributionKind::Ambient { occlusion: ao as Real }, term);
            }
            for (index, light) in self.scene.lights().iter().enumerate() {
                let samples = light.sample_count();
                // Laid out once for all of the light's samples at this point.
                let strata = light.strata();
                for k in 0..samples {
                    let jitter = if samples > 1 { sampler.get_2d() } else { (0.5, 0.5) };
                    let Some(s) = light.sample_in(&strata, sp.p, k, jitter) else { continue };
                    let f = bsdf.eval(wo, s.to_light);
                    if f == Color::ZERO {
                        continue;
                    }
                    if self.plan.shadows && light.shadows {
                        counts.shadow += 1;
                        let shadow = si.spawn_ray(s.to_light);
                        let blocked = self.scene.any_hit(&shadow, Interval::new(0.0, s.distance));
                        rec.probe(
                            SegmentKind::Shadow { light: index, sample: k, blocked },
                            &shadow,
                            s.distance,
                        );
                        if blocked {
                            continue;
                        }
                    }
                    let term = f * s.irradiance * to_f32(bsdf.cosine(s.to_light));
                    color += term;
                    rec.contribution(ContributionKind::Light { light: index, sample: k }, term);
                }
            }
        }

        if path.depth < self.plan.max_depth && (self.plan.reflection || self.plan.refraction) {
            // Mirror and glass directions turn about the shading normal, as
            // long as they leave on the right side of the facet (else about
            // the facet's own normal): see `bsdf`'s "Shading normals".
            let ns = if shading.is_some() { bsdf.normal() } else { n };
            let (eta_i, eta_t) = if front { (1.0, m.ior as Real) } else { (m.ior as Real, 1.0) };
            let (reflected, transmitted) = bsdf.delta_weights(wo).unwrap_or_else(|| {
                let fresnel = if m.transparency > 0.0 {
                    to_f32(fresnel_dielectric(-d.dot(ns), eta_i, eta_t))
                } else {
                    0.0
                };
                (
                    m.reflectivity * m.specular_color + Color::splat(m.transparency * fresnel),
                    m.color * (m.transparency * (1.0 - fresnel)),
                )
            });
            let next = path.then(reflected.max_element());
            if self.plan.reflection && next.weight >= MIN_WEIGHT {
                counts.reflection += 1;
                let r = Some(reflect(d, ns)).filter(|r| r.dot(n) > 0.0).unwrap_or_else(|| reflect(d, n));
                let ray = si.spawn_ray(r);
                let child = rec.ray(SegmentKind::Reflection, &ray, None, Some(reflected));
                let brought = self.trace_secondary(&ray, next, sampler, counts, rec);
                rec.returned(brought);
                let term = reflected * brought;
                color += term;
                rec.contribution(ContributionKind::Reflection { child }, term);
            }
            // The η² factors of entering and leaving cancel along a path, so
            // they do not count towards a ray's weight in the pixel.
            let next = path.then(transmitted.max_element());
            let eta = to_f32(eta_i / eta_t);
            let transmitted = transmitted * (eta * eta);
            if self.plan.refraction
                && next.weight >= MIN_WEIGHT
                && let Some(t) = refract(d, ns, eta_i, eta_t)
                    .filter(|t| t.dot(n) < 0.0)
                    .or_else(|| refract(d, n, eta_i, eta_t))
            {
                counts.refraction += 1;
                let ray = si.spawn_ray(t);
                let child = rec.ray(SegmentKind::Refraction, &ray, None, Some(transmitted));
                let brought = self.trace_secondary(&ray, next, sampler, counts, rec);
                rec.returned(brought);
                let term = transmitted * brought;
                color += term;
                rec.contribution(ContributionKind::Refraction { child }, term);
            }
        }
        color
    }

    /// The unblocked fraction of the hemisphere about `n` within the AO
    /// radius, from cosine-distributed, stratified rays; 1 without AO.
    fn ambient_occlusion<R: Recorder>(
        &self,
        sp: &SurfacePoint,
        n: Vec3,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        rec: &mut R,
    ) -> f32 {
        let Some(ao) = self.plan.ambient_occlusion else {
            return 1.0;
        };
        let mut open = 0u32;
        // Laid out once for all of the point's rays (its square root and
        // cell order), and so is the frame about `n` (a division).
        let strata = Strata::new(ao.samples);
        let frame = n.any_orthonormal_pair();
        for k in 0..ao.samples {
            let dir = cosine_hemisphere_in(n, frame, strata.point(k, sampler.get_2d()));
            let ray = Ray::new(sp.spawn_origin(dir), dir);
            counts.ambient_occlusion += 1;
            let blocked = self.scene.any_hit(&ray, Interval::new(0.0, ao.radius));
            rec.probe(SegmentKind::AmbientOcclusion { blocked }, &ray, ao.radius);
            if !blocked {
                open += 1;
            }
        }
        open as f32 / ao.samples as f32
    }
}

/// Where a secondary ray is in its tree: bounces so far, and its weight in
/// the pixel (largest channel).
#[derive(Clone, Copy, Debug)]
struct Path {
    depth: u32,
    weight: f32,
    /// Distance from the camera to where the ray starts, along the path:
    /// its ray cone's width grows with it.
    travelled: Real,
}

impl Path {
    /// The path one bounce further, through a surface passing `factor`.
    fn then(self, factor: f32) -> Self {
        Self { depth: self.depth + 1, weight: self.weight * factor, ..self }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::files::scene_file::LoadedScene;
    use crate::testing::test_support::{renderer, renderer_of};
    use std::path::Path;

    /// A scene from RON text.
    fn scene(text: &str) -> LoadedScene {
        crate::parse_scene(text, "test.ron", Path::new(".")).unwrap()
    }

    /// A camera at (0, 0, −5) looking at a grey wall z = 0 that fills the view,
    /// lit by `lights`, plus `extra` objects and `effects`.
    fn wall(materials: &str, objects: &str, lights: &str, effects: &str) -> LoadedScene {
        scene(&format!(
            r#"(
            camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
            image: (width: 16, height: 12),
            materials: {{ "grey": (color: (0.5, 0.5, 0.5)), {materials} }},
            objects: [ Plane(normal: (0, 0, -1), d: 0, material: "grey"), {objects} ],
            lights: [ {lights} ],
            {effects}
        )"#
        ))
    }

    fn render(s: &LoadedScene, spp: u32) -> crate::render::Frame {
        let image = s.settings.image;
        renderer(s, image.width(), image.height(), spp).render(|_| {})
    }

    #[test]
    fn a_lit_wall_follows_lamberts_cosine_law() {
        for degrees in [0.0 as Real, 30.0, 60.0, 85.0] {
            let a = degrees.to_radians();
            // Light travelling into the wall (+z) tilted by `a`.
            let light = format!("Directional(direction: ({}, 0, {}), intensity: 2)", a.sin(), a.cos());
            let f = render(&wall("", "", &light, ""), 1);
            // Radiance (ρ/π)·E·cos θ with ρ = 0.5, E = 2.
            let expected = 0.5 / std::f32::consts::PI * 2.0 * to_f32(a.cos());
            for c in &f.pixels {
                assert!((c.x - expected).abs() < 1e-5, "{degrees}°: {c} vs {expected}");
            }
        }
    }

    #[test]
    fn a_wall_lit_from_behind_gets_only_ambient_light() {
        let f = render(&wall("", "", "Directional(direction: (0, 0, -1))", "ambient: (0.2, 0.2, 0.2),"), 1);
        assert!(f.pixels.iter().all(|c| (c.x - 0.1).abs() < 1e-6), "{}", f.pixels[0]);
    }

    #[test]
    fn a_point_light_falls_off_with_the_square_of_the_distance() {
        let at = |z: Real| {
            let light = format!("Point(position: (0, 0, {z}), intensity: 4, shadows: false)");
            let s = wall("", "", &light, "");
            // In a 15×11 image pixel (7, 5) is centred on the axis: the light is straight ahead.
            let r = renderer(&s, 15, 11, 1);
            r.pixel(7, 5, &mut RayCounts::default()).x
        };
        let lambert = 0.5 / std::f32::consts::PI;
        assert!((at(-1.0) - lambert * 4.0).abs() < 1e-6);
        assert!((at(-2.0) - lambert * 4.0 / 4.0).abs() < 1e-6);
    }

    #[test]
    fn each_kind_of_ray_is_cast_only_when_the_scene_asks_for_it() {
        let sphere = r#"Sphere(center: (0, 0, -1), radius: 0.5, material: "shiny")"#;
        let shiny = r#""shiny": (color: (1, 1, 1), reflectivity: 0.5)"#;
        let glass = r#""shiny": (color: (1, 1, 1), transparency: 0.9)"#;
        let point = "Point(position: (0, 3, -3), intensity: 9)";
        let no_shadow = "Point(position: (0, 3, -3), intensity: 9, shadows: false)";
        let ao = "ambient: (0.2, 0.2, 0.2), effects: (ambient_occlusion: (samples: 3, radius: 1)),";
        let counts = |s: LoadedScene| render(&s, 1).rays;
        let none = counts(wall(shiny, sphere, "", ao));
        assert_eq!(none, RayCounts { primary: 192, ..RayCounts::default() }, "no lights: casting only");
        let lit = counts(wall(shiny, sphere, no_shadow, ""));
        assert_eq!((lit.shadow, lit.refraction, lit.ambient_occlusion), (0, 0, 0));
        assert!(lit.reflection > 0);
        let shadows = counts(wall(shiny, sphere, point, ""));
        assert!(shadows.shadow > 0 && shadows.refraction == 0);
        let flat = counts(wall(r#""shiny": (color: (1, 1, 1))"#, sphere, point, ""));
        assert_eq!((flat.reflection, flat.refraction), (0, 0), "nothing reflects");
        let glassy = counts(wall(glass, sphere, point, ""));
        assert!(glassy.refraction > 0 && glassy.reflection > 0, "glass refracts and reflects");
        let shallow = counts(wall(glass, sphere, point, "effects: (max_depth: 0),"));
        assert_eq!((shallow.reflection, shallow.refraction), (0, 0), "max_depth 0");
        let occluded = counts(wall(shiny, sphere, point, ao));
        assert!(occluded.ambient_occlusion > 0);
        let dark =
            counts(wall(shiny, sphere, point, "effects: (ambient_occlusion: (samples: 3, radius: 1)),"));
        assert_eq!(dark.ambient_occlusion, 0, "AO without ambient light has nothing to darken");
    }

    #[test]
    fn ray_counts_are_exact_for_simple_scenes() {
        // Every pixel sees the wall, which faces the light: one shadow ray and
        // three AO rays per sample, W×H×spp primary rays.
        let s = wall(
            "",
            "",
            "Point(position: (0, 0, -3), intensity: 9)",
            "ambient: (0.1, 0.1, 0.1), effects: (ambient_occlusion: (samples: 3, radius: 1)),",
        );
        let f = render(&s, 4);
        let n = 16 * 12 * 4;
        assert_eq!(
            f.rays,
            RayCounts { primary: n, shadow: n, ambient_occlusion: 3 * n, ..RayCounts::default() }
        );
        // A sphere light of 5 samples: 5 shadow rays per sample.
        let s = wall("", "", "Sphere(center: (0, 0, -3), radius: 0.5, intensity: 9, samples: 5)", "");
        assert_eq!(render(&s, 1).rays, RayCounts { primary: 192, shadow: 5 * 192, ..RayCounts::default() });
    }

    #[test]
    fn many_glass_spheres_at_the_deepest_recursion_stay_cheap() {
        // Without adaptive depth, 2^64 rays per pixel.
        let spheres: Vec<String> = (0..12)
            .map(|i| {
                format!(
                    r#"Sphere(center: ({}, {}, -1), radius: 0.45, material: "glass")"#,
                    i % 4 - 2,
                    i / 4 - 1
                )
            })
            .collect();
        let s = wall(
            r#""glass": (color: (1, 1, 1), transparency: 1, ior: 1.5)"#,
            &spheres.join(", "),
            "Point(position: (0, 3, -3), intensity: 9)",
            "effects: (max_depth: 64),",
        );
        let rays = render(&s, 1).rays;
        assert!(rays.total() < 192 * 200, "{rays:?}");
    }

    #[test]
    fn two_facing_mirrors_recurse_exactly_max_depth_times() {
        // The camera looks through a hole-free view at a mirror wall with a
        // mirror behind the camera: every bounce hits a mirror again.
        for depth in [1, 3, 7] {
            let s = scene(&format!(
                r#"(
                camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 10, near: 1),
                image: (width: 4, height: 4),
                materials: {{ "mirror": (color: (1, 1, 1), reflectivity: 1) }},
                objects: [
                    Plane(normal: (0, 0, -1), d: 0, material: "mirror"),
                    Plane(normal: (0, 0, 1), d: -10, material: "mirror"),
                ],
                lights: [ Directional(direction: (0, -1, 0), shadows: false) ],
                effects: (max_depth: {depth}),
            )"#
            ));
            assert_eq!(render(&s, 1).rays.reflection, 16 * depth as u64, "depth {depth}");
        }
    }

    #[test]
    fn a_ray_through_a_glass_sphere_centre_goes_straight_through() {
        // Clear glass, no reflection: the pixel behind the sphere's centre
        // shows the lit wall dimmed by the two surfaces' Fresnel losses.
        let s = wall(
            r#""glass": (color: (1, 1, 1), transparency: 1, ior: 1.5)"#,
            r#"Sphere(center: (0, 0, -2), radius: 1, material: "glass")"#,
            "Directional(direction: (0, 0, 1), shadows: false)",
            "",
        );
        let r = renderer(&s, 15, 15, 1);
        let mut counts = RayCounts::default();
        let through = r.pixel(7, 7, &mut counts);
        // Refracted in at the front (4 % reflects off it); out at the back,
        // where 4 % reflects inside; that leaves through the front, where
        // its own 4 % would weigh 0.0015 < MIN_WEIGHT: the path ends there
        // although max_depth (5) would allow more.
        assert_eq!((counts.refraction, counts.reflection), (3, 2));
        let transmitted = (1.0 - 0.04) * (1.0 - 0.04);
        // The wall's radiance (0.5/π lit head-on by E = 1) is reached through
        // the sphere (the η² factors of entering and leaving cancel), plus a
        // little reflected background (black here).
        let wall = 0.5 / std::f32::consts::PI;
        assert!((through.x - wall * transmitted).abs() < 1e-3, "{through}");
    }

    #[test]
    fn the_image_is_identical_for_one_and_for_two_threads_with_every_effect() {
        let s = wall(
            r#""glass": (color: (0.9, 1, 0.9), transparency: 0.8, specular: 0.5), "mirror": (color: (1, 1, 1), reflectivity: 0.6)"#,
            r#"Sphere(center: (-0.6, 0, -1), radius: 0.5, material: "glass"), Sphere(center: (0.7, 0.2, -1), radius: 0.4, material: "mirror")"#,
            "Sphere(center: (1, 3, -3), radius: 0.7, intensity: 12, samples: 4), Point(position: (-2, 1, -4), intensity: 5)",
            "ambient: (0.2, 0.2, 0.2), effects: (ambient_occlusion: (samples: 4, radius: 1)),",
        );
        let r = renderer(&s, 48, 36, 4);
        let run = |threads| crate::testing::test_support::render_on_threads(&r, threads);
        let one = run(1);
        assert_eq!(one, run(2));
        let c = one.rays;
        assert!(c.shadow > 0 && c.reflection > 0 && c.refraction > 0 && c.ambient_occlusion > 0, "{c:?}");
    }

    /// Renders a plane and a sphere `distance` units from the origin, lit by a
    /// directional light with shadows, and counts pixels darker than the
    /// analytic shading allows: shadow acne shows up as such speckles.
    fn acne_pixels(distance: Real) -> usize {
        let o = Vec3::new(distance, distance * 0.5, distance);
        let p = |v: Vec3| format!("({}, {}, {})", v.x, v.y, v.z);
        let s = scene(&format!(
            r#"(
            camera: (position: {cam}, center_of_interest: {target}, up: (0, 1, 0), fov_y: 50, near: 1),
            image: (width: 64, height: 48),
            materials: {{ "m": (color: (1, 1, 1)) }},
            objects: [
                Plane(normal: (0, 1, 0), d: {floor}, material: "m"),
                Sphere(center: {centre}, radius: 2, material: "m"),
            ],
            lights: [ Directional(direction: (0.3, -1, 0.2)) ],
        )"#,
            cam = p(o + Vec3::new(0.0, 4.0, -12.0)),
            target = p(o),
            floor = o.y - 2.0,
            centre = p(o),
        ));
        let light = -Vec3::new(0.3, -1.0, 0.2).normalize();
        let r = renderer(&s, 64, 48, 1);
        let mut dark = 0;
        for y in 0..48 {
            for x in 0..64 {
                let ray = r.view_plane().center_ray(x, y);
                let Some(hit) = s.scene.cast(&ray) else { continue };
                let n = if hit.object == 1 { hit.normal } else { Vec3::Y };
                let cos = n.dot(light);
                // The floor under the sphere is legitimately in shadow: skip
                // floor points whose way to the light passes near the sphere.
                let point = ray.at(hit.t);
                let to_centre = o - point;
                let closest = to_centre - light * to_centre.dot(light);
                let shadowed = hit.object == 0 && to_centre.dot(light) > 0.0 && closest.length() < 2.2;
                if cos < 0.05 || shadowed {
                    continue;
                }
                // A white Lambert surface lit by E = 1: cos θ/π.
                let shade = r.pixel(x, y, &mut RayCounts::default()).x * std::f32::consts::PI;
                if shade < to_f32(cos) - 0.02 {
                    dark += 1;
                }
            }
        }
        dark
    }

    #[test]
    fn no_shadow_acne_far_from_the_origin() {
        for distance in [0.0, 1e4, 1e5] {
            assert_eq!(acne_pixels(distance), 0, "at {distance}");
        }
    }

    /// A lit sphere of radius 1 at the origin, as `primitive`, 48×48 pixels
    /// with a point light up and to the left (no shadows: only shading differs).
    fn lit_sphere(primitive: crate::geometry::primitive::Primitive) -> Vec<Color> {
        use crate::lights::light::{Light, LightKind};
        use crate::materials::material::Material;
        let camera = crate::testing::test_support::camera_at(Vec3::new(0.0, 0.0, -4.0), Vec3::ZERO, 35.0);
        let light = Light {
            kind: LightKind::Point { position: Vec3::new(-3.0, 3.0, -3.0) },
            power: Color::splat(40.0),
            shadows: false,
        };
        let scene = crate::scene::SceneBuilder::new()
            .light(light)
            .material("m", Material { specular: 0.3, shininess: 60.0, ..Material::flat(Color::splat(0.8)) })
            .object(primitive, "m")
            .build()
            .unwrap();
        renderer_of(&scene, camera, Default::default(), (48, 48, 1)).render(|_| {}).pixels
    }

    #[test]
    fn vertex_normals_shade_a_coarse_mesh_like_the_smooth_surface_it_stands_for() {
        use crate::geometry::mesh::Mesh;
        use crate::geometry::primitive::Primitive;
        use crate::geometry::sphere::Sphere;
        // A UV sphere of 12 × 6 quads, its vertices on the unit sphere; the
        // exact normal there is the position.
        let (around, up) = (12u32, 6u32);
        let mut positions = Vec::new();
        for j in 0..=up {
            let t = std::f64::consts::PI * j as f64 / up as f64;
            for i in 0..=around {
                let a = 2.0 * std::f64::consts::PI * i as f64 / around as f64;
                positions.push(crate::math::real::narrow(glam::DVec3::new(
                    t.sin() * a.cos(),
                    t.cos(),
                    t.sin() * a.sin(),
                )));
            }
        }
        let mut triangles = Vec::new();
        for j in 0..up {
            for i in 0..around {
                let (a, b) = (j * (around + 1) + i, j * (around + 1) + i + 1);
                triangles.extend([[a, b, b + around + 1], [a, b + around + 1, a + around + 1]]);
            }
        }
        let flat = Mesh::new(positions.clone(), triangles).unwrap();
        let smooth = flat.clone().with_vertex_attributes(positions, Vec::new()).unwrap();
        let exact = lit_sphere(Primitive::Sphere(Sphere::new(Vec3::ZERO, 1.0).unwrap()));
        let rmse = |img: &[Color]| {
            // Only pixels where both show the sphere (the silhouettes differ).
            let (mut sum, mut n) = (0.0f64, 0);
            for (a, b) in img.iter().zip(&exact) {
                if *a != Color::ZERO && *b != Color::ZERO {
                    sum += (*a - *b).length_squared() as f64;
                    n += 1;
                }
            }
            (sum / n as f64).sqrt()
        };
        let (e_flat, e_smooth) =
            (rmse(&lit_sphere(Primitive::Mesh(flat))), rmse(&lit_sphere(Primitive::Mesh(smooth))));
        assert!(e_smooth < e_flat / 3.0, "smooth {e_smooth} against flat {e_flat}");
    }

    /// The mean radiance of a normal-mapped square facing the camera (u
    /// along +x, up the image +y), its one-texel map holding `texel`, lit
    /// by a directional light arriving from `from` (towards the light),
    /// by the direct-lighting tracer or, with `gi`, the path tracer.
    fn mean_of_normal_mapped_square(texel: [f32; 3], from: Vec3, gi: bool) -> f32 {
        use crate::geometry::primitive::Primitive;
        use crate::lights::light::{Light, LightKind};
        use crate::materials::material::Material;
        use crate::materials::texture::Texture;
        use crate::scene::effects::{Effects, GlobalIllumination};
        let mesh = crate::testing::test_support::textured_square(0.0);
        let light = Light {
            kind: LightKind::Directional { direction: -from.normalize() },
            power: Color::splat(2.0),
            shadows: true,
        };
        let material = Material {
            normal_texture: Some(crate::materials::texture_slot::TextureSlot::new(0)),
            ..Material::flat(Color::splat(0.8))
        };
        let scene = crate::scene::SceneBuilder::new()
            .light(light)
            .texture(std::sync::Arc::new(Texture::from_linear(1, 1, 3, &texel).unwrap()))
            .material("m", material)
            .object(Primitive::Mesh(mesh), "m")
            .build()
            .unwrap();
        let camera = crate::testing::test_support::camera_at(Vec3::new(0.0, 0.0, -4.0), Vec3::ZERO, 20.0);
        let effects = Effects {
            global_illumination: gi.then_some(GlobalIllumination {
                max_bounces: 1,
                russian_roulette: false,
                max_walk_steps: 1,
            }),
            ..Effects::default()
        };
        let pixels = renderer_of(&scene, camera, effects, (8, 8, 4)).render(|_| {}).pixels;
        pixels.iter().map(|c| c.x).sum::<f32>() / pixels.len() as f32
    }

    #[test]
    fn a_normal_map_turns_the_surface_towards_the_light_it_leans_to_for_both_integrators() {
        // Leaning 37° towards +u (+x, red 0.8) or up the image (+y, green
        // 0.8), lit from that side at a slant: brighter than leaning away,
        // and than not leaning at all.
        for gi in [false, true] {
            for (towards, away, from) in [
                ([0.8, 0.5, 1.0], [0.2, 0.5, 1.0], Vec3::new(1.0, 0.0, -1.0)),
                ([0.5, 0.8, 1.0], [0.5, 0.2, 1.0], Vec3::new(0.0, 1.0, -1.0)),
            ] {
                let lit = mean_of_normal_mapped_square(towards, from, gi);
                let flat = mean_of_normal_mapped_square([0.5, 0.5, 1.0], from, gi);
                let dark = mean_of_normal_mapped_square(away, from, gi);
                assert!(lit > flat * 1.1 && flat > dark * 1.1, "gi {gi}, from {from}: {lit} {flat} {dark}");
            }
        }
    }
}
