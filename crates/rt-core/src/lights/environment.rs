//! The environment: the light that arrives along rays that leave the scene.
//!
//! Either one constant radiance in every direction (a scene file's
//! `background`; Mitsuba 3's `constant` emitter) or an image of it, an
//! environment map, perhaps with a sun ([`crate::lights::environment_map`];
//! a sky is a map made from a sky model, [`crate::lights::sky`]). It is
//! what a camera ray that hits nothing shows, and, under global
//! illumination, a light that next-event estimation samples like any other
//! ([`crate::lights::light_source`]).

use std::sync::Arc;

use crate::lights::environment_map::EnvironmentMap;
use crate::math::color::Color;
use crate::math::real::{Real, Vec3};
use crate::sampling::sampler::{uniform_sphere, uniform_sphere_pdf};

/// The light arriving from outside the scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Environment {
    /// The same radiance from every direction.
    Constant(Color),
    /// An equirectangular image of the radiance, perhaps with a sun; shared,
    /// since a map can be large.
    Map(Arc<EnvironmentMap>),
}

impl Default for Environment {
    /// Black: no light from outside.
    fn default() -> Self {
        Self::Constant(Color::ZERO)
    }
}

impl Environment {
    /// The radiance arriving along a ray that leaves the scene in direction `_dir`.
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Color {
        match self {
            Self::Constant(c) => *c,
            Self::Map(map) => map.radiance(dir),
        }
    }

    /// A unit direction for `u` ∈ [0,1)² and its density over solid angle,
    /// or `None` where there is none: for a constant environment, uniform
    /// over the sphere ([`uniform_sphere`]); for a map, by its brightness
    /// ([`EnvironmentMap::sample`]).
    #[inline]
    pub fn sample(&self, u: (Real, Real)) -> Option<(Vec3, Real)> {
        match self {
            Self::Constant(_) => Some((uniform_sphere(u), uniform_sphere_pdf())),
            Self::Map(map) => map.sample(u),
        }
    }

    /// The density over solid angle with which [`Environment::sample`] picks unit `wi`.
    #[inline]
    pub fn pdf(&self, wi: Vec3) -> Real {
        match self {
            Self::Constant(_) => uniform_sphere_pdf(),
            Self::Map(map) => map.pdf(wi),
        }
    }

    /// The power it sends into a scene that fits in a sphere of radius
    /// `radius`, for choosing among lights: `4π·π·R²·L` (radiance L from
    /// every direction through the sphere's cross-section πR²; the mean of
    /// the colour channels); for a map, `πR²·∫L dω`.
    pub fn power(&self, radius: Real) -> Real {
        let pi = std::f64::consts::PI as Real;
        match self {
            Self::Constant(c) => 4.0 * pi * pi * radius * radius * (c.element_sum() / 3.0) as Real,
            Self::Map(map) => pi * radius * radius * map.radiance_integral() as Real,
        }
    }
}

#[cfg(test)]
mod tests {

    use crate::files::environment_image::write_hdr;
    use crate::files::scene_file::{LoadedScene, parse_scene};
    use crate::math::color::Color;
    use crate::testing::test_support::renderer;

    /// A scene of `objects` under `environment` with global illumination of
    /// `bounces` bounces; maps are written to a temporary folder first.
    fn scene(environment: &str, objects: &str, bounces: u32) -> LoadedScene {
        let dir = std::env::temp_dir().join(format!("rt-env-render-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        write_hdr(&dir.join("white.hdr"), 16, 8, &[Color::ONE; 128]).unwrap();
        write_hdr(&dir.join("grey.hdr"), 16, 8, &[Color::new(0.25, 0.5, 0.75); 128]).unwrap();
        let text = format!(
            r#"(
    camera: (position: (0, 1, -4), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 45, near: 1),
    image: (width: 16, height: 16),
    {environment}
    materials: {{ "white": (color: (1, 1, 1)), "grey": (color: (0.5, 0.5, 0.5)), "red": (color: (0.8, 0.2, 0.1)) }},
    objects: [ {objects} ],
    effects: (global_illumination: (max_bounces: {bounces})),
)"#
        );
        parse_scene(&text, "env.ron", &dir).unwrap()
    }

    #[test]
    fn a_white_sphere_disappears_under_a_white_map() {
        // The white furnace: a closed white diffuse object under radiance 1
        // from every direction sends back 1 everywhere (up to the bounces
        // left: with 20 bounces and no roulette-free loss, < 1e-6 short).
        let s = scene(
            r#"environment: Map(file: "white.hdr"),"#,
            r#"Sphere(center: (0, 0, 0), radius: 1, material: "white")"#,
            20,
        );
        let frame = renderer(&s, 16, 16, 64).render(|_| {});
        let mean = frame.pixels.iter().copied().sum::<Color>() / frame.pixels.len() as f32;
        for p in &frame.pixels {
            assert!((p.x - 1.0).abs() < 0.08, "{p}");
        }
        assert!((mean - Color::ONE).abs().max_element() < 0.01, "{mean}");
    }

    #[test]
    fn a_constant_map_renders_as_the_constant_background_within_noise() {
        // A diffuse sphere on a grey floor under radiance (0.25, 0.5, 0.75),
        // once as a map and once as the background: each image's mean is
        // within 4 standard errors of the other's (errors from pixels).
        let objects = r#"Sphere(center: (0, 0, 0), radius: 1, material: "red"),
            Plane(normal: (0, 1, 0), d: -1, material: "grey")"#;
        let map = scene(r#"environment: Map(file: "grey.hdr"),"#, objects, 3);
        let constant = scene("background: (0.25, 0.5, 0.75),", objects, 3);
        let (a, b) =
            (renderer(&map, 16, 16, 64).render(|_| {}), renderer(&constant, 16, 16, 64).render(|_| {}));
        let diff: Vec<Color> = a.pixels.iter().zip(&b.pixels).map(|(x, y)| *x - *y).collect();
        let n = diff.len() as f32;
        let mean = diff.iter().copied().sum::<Color>() / n;
        let var = diff.iter().map(|d| (*d - mean) * (*d - mean)).sum::<Color>() / (n - 1.0);
        let error = (var / n).powf(0.5);
        assert!((mean.abs() - 4.0 * error).max_element() < 0.0, "difference {mean} ± {error}");
        // The background's pixels are the same exactly: both give the texel.
        assert!((a.pixels[0] - b.pixels[0]).abs().max_element() < 1e-6);
    }
}
