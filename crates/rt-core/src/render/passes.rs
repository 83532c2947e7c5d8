//! Feature passes (arbitrary output variables): what a denoiser and a
//! compositor want besides the colour — the albedo and normal of the first
//! non-specular surface a camera ray meets, the depth of its first hit and
//! the object it hit.
//!
//! Albedo and normal follow the conventions of Intel Open Image Denoise
//! ("OIDN", its documentation's section "RT" filter, auxiliary images) and
//! of Cycles' denoising passes: through perfectly specular (δ-only)
//! surfaces — mirrors, clear glass — the camera ray goes on to the first
//! surface with a smooth lobe, and what it shows there is the feature. The
//! chain is drawn with random numbers of its own ([`SampleRng`] salted with
//! [`FEATURE_SALT`]), so the colour of a sample is the same, bit for bit,
//! whether the passes are recorded or not. The renderer records them in
//! the same loop as the colour, from the same primary ray and hit
//! ([`crate::render::Renderer::accumulate_region_with_features`]); a
//! render without them does no work for them.

use std::mem::MaybeUninit;

use crate::geometry::hit::Hit;
use crate::integrators::interaction::SurfaceInteraction;
use crate::math::color::Color;
use crate::math::ray::{Interval, Ray};
use crate::math::real::{Real, Vec3, normalize_robust, to_f32};
use crate::sampling::sampler::SampleRng;
use crate::scene::Scene;

/// The most δ bounces a feature ray follows before it gives up (a path
/// between two facing mirrors never meets a smooth surface): what it has
/// by then counts as nothing seen.
pub const MAX_SPECULAR_CHAIN: u32 = 8;

/// What sets the features' random numbers apart from the colour path's and
/// the film's (any odd constant; these are the first digits of √5).
pub const FEATURE_SALT: u64 = 0x23C6_EF37_2FE9_4F6B;

/// The features of one sample of one pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleFeatures {
    /// The directional albedo of the first non-specular surface, in [0, 1]
    /// per channel, times the tint of the δ surfaces on the way (their
    /// sample weights; a clear closed object's refractions in and out
    /// cancel): a one-sample estimate of ρ(ω_o) = ∫ f·|cos θ_i| dω_i, the
    /// BSDF sample's weight `f·|cos θ_i|/pdf` (exactly the colour for a
    /// Lambert surface). Zero where the ray leaves the scene.
    pub albedo: Color,
    /// The first non-specular surface's shading normal in world space, unit
    /// length, turned to the side the ray arrived from; zero where the ray
    /// leaves the scene.
    pub normal: Vec3,
    /// The distance from the camera ray's origin (the camera, or its point
    /// on the lens) to the first hit along the ray, in scene units: the
    /// ray's parameter times its direction's length, not the depth along
    /// the view axis. Infinite where the ray hits nothing.
    pub depth: Real,
    /// The index of the first object hit in the scene file's object list;
    /// `None` where the ray hits nothing.
    pub object: Option<usize>,
}

impl SampleFeatures {
    /// The features of the camera ray `ray`, whose first hit (by
    /// [`Scene::cast`]) is `hit`; `rng` draws the choices at δ surfaces
    /// that reflect and refract both (glass).
    pub fn of_camera_ray(scene: &Scene, ray: &Ray, hit: Option<Hit>, rng: &mut SampleRng) -> Self {
        let mut features =
            Self { albedo: Color::ZERO, normal: Vec3::ZERO, depth: Real::INFINITY, object: None };
        let Some(first) = hit else { return features };
        features.depth = first.t * ray.dir.length();
        features.object = Some(first.object);

        let (mut ray, mut hit, mut throughput) = (*ray, Some(first), Color::ONE);
        for _ in 0..=MAX_SPECULAR_CHAIN {
            let (Some(h), Some(d)) = (hit, normalize_robust(ray.dir)) else { break };
            let mut scratch = MaybeUninit::uninit();
            let si = SurfaceInteraction::along(scene, &ray, d, &h, &mut scratch);
            let bsdf = si.bsdf();
            let Some(s) = bsdf.sample(si.wo, rng.next_pair().0, rng.next_pair()) else {
                // No direction leaves (black, or seen from below its
                // shading normal): the surface is what is seen, dark.
                features.normal = bsdf.normal();
                break;
            };
            if bsdf.has_smooth_lobes() {
                features.albedo = (throughput * s.weight).clamp(Color::ZERO, Color::ONE);
                features.normal = bsdf.normal();
                break;
            }
            throughput *= s.weight;
            ray = Ray::new(si.point.spawn_origin(s.wi), s.wi);
            hit = scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY));
        }
        features
    }
}

/// Sums of a pixel's [`SampleFeatures`] over its samples so far, in the
/// order the colours are summed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FeatureSums {
    /// The sum of the samples' albedos.
    pub albedo: Color,
    /// The sum of the samples' normals (its direction is the mean normal's).
    pub normal: Color,
    /// The nearest first hit of any sample (infinite where none hit).
    pub depth: f32,
    /// The object of that nearest hit: depth and object are not averaged,
    /// since a mean of two depths or two indices across an edge names no
    /// surface (the nearest, as a z-buffer keeps).
    pub object: Option<usize>,
}

impl Default for FeatureSums {
    fn default() -> Self {
        Self { albedo: Color::ZERO, normal: Color::ZERO, depth: f32::INFINITY, object: None }
    }
}

impl FeatureSums {
    /// Adds one sample's features.
    #[inline]
    pub fn add(&mut self, f: &SampleFeatures) {
        self.albedo += f.albedo;
        self.normal += Color::new(to_f32(f.normal.x), to_f32(f.normal.y), to_f32(f.normal.z));
        let depth = to_f32(f.depth);
        if depth < self.depth {
            self.depth = depth;
            self.object = f.object;
        }
    }

    /// The pixel's mean albedo and mean normal over `samples` samples
    /// (`(albedo, normal)`; the mean normal is not renormalised: at an edge
    /// it is shorter, as OIDN expects of a filtered normal).
    pub fn means(&self, samples: u32) -> (Color, Color) {
        let n = samples.max(1) as f32;
        (self.albedo / n, self.normal / n)
    }
}

/// The feature passes of a whole image: one [`FeatureSums`] per pixel,
/// row-major, top row first, over `samples` samples each.
#[derive(Clone, Debug, PartialEq)]
pub struct FeatureFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples summed in each pixel.
    pub samples: u32,
    /// Per-pixel sums.
    pub pixels: Vec<FeatureSums>,
}

impl FeatureFrame {
    /// The mean albedo of each pixel.
    pub fn albedo(&self) -> Vec<Color> {
        self.pixels.iter().map(|p| p.means(self.samples).0).collect()
    }

    /// The mean normal of each pixel.
    pub fn normal(&self) -> Vec<Color> {
        self.pixels.iter().map(|p| p.means(self.samples).1).collect()
    }

    /// The depth of each pixel ([`FeatureSums::depth`]).
    pub fn depth(&self) -> Vec<f32> {
        self.pixels.iter().map(|p| p.depth).collect()
    }

    /// The object index of each pixel, −1 where none was hit (as a float,
    /// the form image files store; exact up to 2²⁴ objects).
    pub fn object_ids(&self) -> Vec<f32> {
        self.pixels.iter().map(|p| p.object.map_or(-1.0, |i| i as f32)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::ray::Interval;
    use crate::testing::test_support::renderer;
    use std::path::Path;

    /// Inside a closed diffuse sphere of radius 20 and colour `room`, a
    /// sphere of `material` at (0, 0, 3) ahead of the camera.
    fn room(material: &str) -> crate::LoadedScene {
        let text = format!(
            r#"(
            camera: (position: (0, 0, -3), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 60, near: 1),
            image: (width: 24, height: 16),
            materials: {{ "room": (color: (0.6, 0.4, 0.2)), "ball": {material} }},
            objects: [ Sphere(center: (0, 0, 0), radius: 20, material: "room"), Sphere(center: (0, 0, 3), radius: 2, material: "ball") ],
            effects: (global_illumination: (max_bounces: 4)),
        )"#
        );
        crate::parse_scene(&text, "room.ron", Path::new(".")).unwrap()
    }

    /// The features of every sample of every pixel of `s` (24 × 16, `spp`).
    fn all_features(s: &crate::LoadedScene, spp: u32) -> Vec<(u32, u32, Ray, SampleFeatures)> {
        let r = renderer(s, 24, 16, spp);
        let mut out = Vec::new();
        for (y, x, k) in (0..16).flat_map(|y| (0..24).flat_map(move |x| (0..spp).map(move |k| (y, x, k)))) {
            let film = (0.5, 0.5);
            let ray = r.view_plane().camera_ray(x, y, film, (0.5, 0.5));
            let hit = s.scene.cast(&ray);
            out.push((x, y, ray, r.sample_features(x, y, k, &ray, hit)));
        }
        out
    }

    #[test]
    fn a_diffuse_surface_gives_its_colour_its_shading_normal_its_distance_and_its_object() {
        let s = room(r#"(color: (0.1, 0.8, 0.3))"#);
        for (_, _, ray, f) in all_features(&s, 2) {
            let hit = s.scene.closest_hit(&ray, Interval::new(0.0, Real::INFINITY)).unwrap();
            let p = ray.at(hit.t);
            assert!((f.depth - (p - ray.origin).length()).abs() < 1e-4);
            let (albedo, outward) = match f.object {
                Some(0) => (Color::new(0.6, 0.4, 0.2), p / 20.0),
                Some(1) => (Color::new(0.1, 0.8, 0.3), (p - Vec3::new(0.0, 0.0, 3.0)) / 2.0),
                other => panic!("{other:?}"),
            };
            assert!((f.albedo - albedo).abs().max_element() < 1e-6, "{}", f.albedo);
            // Turned towards the ray: the room's inside, the ball's outside.
            let facing = if f.object == Some(0) { -outward } else { outward };
            assert!((f.normal - facing).length() < 1e-4, "{} vs {facing}", f.normal);
        }
    }

    #[test]
    fn through_clear_glass_the_albedo_and_normal_are_those_of_the_diffuse_surface_behind() {
        let s = room(r#"(color: (1, 1, 1), diffuse: 0, transparency: 1, ior: 1.5)"#);
        let features = all_features(&s, 4);
        let mut through = 0;
        for (_, _, _, f) in &features {
            // Refracted in and out, or reflected off the glass: every chain
            // ends on the room's wall (or, seldom, stays inside the ball).
            if f.normal == Vec3::ZERO {
                continue;
            }
            assert!((f.albedo - Color::new(0.6, 0.4, 0.2)).abs().max_element() < 1e-5, "{}", f.albedo);
            assert!((f.normal.length() - 1.0).abs() < 1e-5);
            through += usize::from(f.object == Some(1));
        }
        assert!(through > features.len() / 8, "{through} of {} through the glass", features.len());
        // A pane seen straight on shows the wall behind: its normal points back at the camera.
        let centre = features.iter().find(|(x, y, _, _)| (*x, *y) == (12, 8)).unwrap().3;
        assert!(centre.normal.z < -0.9, "{}", centre.normal);
    }

    #[test]
    fn a_mirror_shows_the_surface_it_reflects() {
        let s = room(r#"(color: (1, 1, 1), diffuse: 0, reflectivity: 1)"#);
        let centre = all_features(&s, 1).into_iter().find(|(x, y, _, _)| (*x, *y) == (12, 8)).unwrap().3;
        // Straight back off the ball to the room's wall behind the camera.
        assert_eq!(centre.object, Some(1));
        assert!((centre.albedo - Color::new(0.6, 0.4, 0.2)).abs().max_element() < 1e-6);
        assert!(centre.normal.z > 0.9, "{}", centre.normal);
    }

    #[test]
    fn a_ray_that_hits_nothing_has_no_features() {
        let text = r#"(camera: (position: (0, 0, -3), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 60, near: 1),
            image: (width: 4, height: 4), background: (1, 1, 1), materials: { "m": (color: (1, 1, 1)) },
            objects: [ Sphere(center: (0, 0, -10), radius: 1, material: "m") ])"#;
        let s = crate::parse_scene(text, "empty.ron", Path::new(".")).unwrap();
        let r = renderer(&s, 4, 4, 1);
        let ray = r.view_plane().camera_ray(1, 1, (0.5, 0.5), (0.5, 0.5));
        let f = r.sample_features(1, 1, 0, &ray, s.scene.cast(&ray));
        assert_eq!((f.albedo, f.normal, f.depth, f.object), (Color::ZERO, Vec3::ZERO, Real::INFINITY, None));
    }

    #[test]
    fn recording_features_leaves_the_colours_bit_for_bit_and_sums_every_sample() {
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        for file in ["cornell_box.ron", "glass.ron"] {
            let s = crate::load_scene(&scenes.join(file)).unwrap();
            let r = renderer(&s, 20, 12, 3);
            let plain = r.render(|_| {});
            let (frame, features) =
                r.render_with_features_until(|_| {}, &std::sync::atomic::AtomicBool::new(false)).unwrap();
            assert_eq!(frame, plain, "{file}");
            assert_eq!((features.width, features.height, features.samples), (20, 12, 3));
            // A region's features are the whole image's.
            let mut sums = vec![Color::ZERO; 4 * 2];
            let mut region = vec![FeatureSums::default(); 4 * 2];
            r.accumulate_region_with_features(5..7, 9..13, 0..3, &mut sums, &mut region);
            for (i, f) in region.iter().enumerate() {
                assert_eq!(*f, features.pixels[(5 + i / 4) * 20 + 9 + i % 4], "{file}, pixel {i}");
            }
            for (a, n) in features.albedo().iter().zip(features.normal()) {
                assert!(a.min_element() >= 0.0 && a.max_element() <= 1.0 && n.length() <= 1.0 + 1e-5);
            }
        }
    }
}
