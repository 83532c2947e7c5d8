//! The `environment` field: an environment map image or a sky, in place of
//! the constant `background`.
//!
//! ```ron
//! environment: Map(file: "studio.hdr", strength: 1.0, rotation: 0.0),
//! environment: Sky(sun_direction: (0.4, 0.6, 0.7), turbidity: 3.0, strength: 1.0,
//!                  sun_irradiance: (10, 9.5, 8.5), ground_albedo: 0.3),
//! ```
//!
//! Numbers are checked where they are read; the image is read once the
//! whole file is parsed (its path is relative to the scene file's folder).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;

use super::values::{ColorDesc, Finite, V3};
use crate::files::environment_image::read_environment_image;
use crate::lights::environment::Environment;
use crate::lights::environment_map::EnvironmentMap;
use crate::lights::sky::{SkyParameters, TURBIDITY_RANGE, sky_map};
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, normalize_robust, to_f32};

/// A field that is either absent (`None`, with `#[serde(default)]`) or
/// written plainly, without RON's `Some(…)`: whether `background` or
/// `environment` was written at all matters, since only one may be.
pub(super) fn present<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

/// The environment as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) enum EnvironmentDesc {
    /// An equirectangular `.hdr` or `.exr` image.
    Map {
        /// The image, relative to the scene file's folder.
        file: PathBuf,
        /// Factor on its texels.
        #[serde(default = "one")]
        strength: Strength,
        /// Degrees about +y.
        #[serde(default)]
        rotation: Finite,
    },
    /// A Preetham sky with a sun.
    Sky {
        /// Towards the sun.
        sun_direction: SunDirection,
        /// Atmospheric turbidity.
        #[serde(default = "clear")]
        turbidity: Turbidity,
        /// Factor on sky and sun.
        #[serde(default = "one")]
        strength: Strength,
        /// The sun's irradiance at normal incidence (0: no sun).
        #[serde(default = "noon_sun")]
        sun_irradiance: ColorDesc,
        /// The ground's albedo below the horizon.
        #[serde(default = "grey_ground")]
        ground_albedo: Albedo,
    },
}

/// A factor ≥ 0.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "Finite")]
pub(super) struct Strength(f32);

impl TryFrom<Finite> for Strength {
    type Error = String;
    fn try_from(v: Finite) -> Result<Self, String> {
        if v.0 < 0.0 {
            Err(format!("strength must not be negative, got {}", v.0))
        } else {
            Ok(Self(to_f32(v.0)))
        }
    }
}

fn one() -> Strength {
    Strength(1.0)
}

/// A turbidity in [`TURBIDITY_RANGE`].
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "Finite")]
pub(super) struct Turbidity(Real);

impl TryFrom<Finite> for Turbidity {
    type Error = String;
    fn try_from(v: Finite) -> Result<Self, String> {
        let (lo, hi) = TURBIDITY_RANGE;
        if (lo..=hi).contains(&v.0) {
            Ok(Self(v.0))
        } else {
            Err(format!(
                "turbidity must be {lo} to {hi} (the range the sky model was fitted on), got {}",
                v.0
            ))
        }
    }
}

fn clear() -> Turbidity {
    Turbidity(3.0)
}

/// A unit direction above the horizon.
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "V3")]
pub(super) struct SunDirection(Vec3);

impl TryFrom<V3> for SunDirection {
    type Error = String;
    fn try_from(v: V3) -> Result<Self, String> {
        let d = normalize_robust(Vec3::from(v)).ok_or("sun_direction must not be zero")?;
        // The sky model is for a sun above the horizon (y > 0; the sine of 1°).
        if d.y < 0.0175 {
            return Err(format!("sun_direction must point at least 1° above the horizon (y > 0), got {d}"));
        }
        Ok(Self(d))
    }
}

/// An albedo in [0, 1].
#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(try_from = "Finite")]
pub(super) struct Albedo(f32);

impl TryFrom<Finite> for Albedo {
    type Error = String;
    fn try_from(v: Finite) -> Result<Self, String> {
        if (0.0..=1.0).contains(&v.0) {
            Ok(Self(to_f32(v.0)))
        } else {
            Err(format!("ground_albedo must be 0 to 1, got {}", v.0))
        }
    }
}

fn grey_ground() -> Albedo {
    Albedo(0.3)
}

/// A sun that gives 10 units of irradiance, slightly warm (ten times the
/// sky's zenith radiance at T = 3 with the sun at 45°, about the ratio of
/// sun to sky in daylight).
fn noon_sun() -> ColorDesc {
    ColorDesc(Color::new(10.0, 9.5, 8.5))
}

impl EnvironmentDesc {
    /// The environment, with the warnings its image gave (each prefixed by
    /// the path as written), or why there is none. Paths are relative to `base_dir`.
    pub(super) fn build(&self, base_dir: &Path) -> Result<(Environment, Vec<String>), String> {
        match self {
            Self::Map { file, strength, rotation } => {
                let written = file.display().to_string();
                let image = read_environment_image(&base_dir.join(file))
                    .map_err(|e| format!("environment: {written}: {e}"))?;
                let warnings =
                    image.warnings.iter().map(|w| format!("environment: {written}: {w}")).collect();
                let map =
                    EnvironmentMap::new(image.width, image.height, image.texels, strength.0, rotation.0);
                Ok((Environment::Map(Arc::new(map)), warnings))
            }
            Self::Sky { sun_direction, turbidity, strength, sun_irradiance, ground_albedo } => {
                let p = SkyParameters {
                    sun_direction: sun_direction.0,
                    turbidity: turbidity.0,
                    strength: strength.0,
                    sun_irradiance: sun_irradiance.0 * strength.0,
                    ground_albedo: ground_albedo.0,
                };
                Ok((Environment::Map(Arc::new(sky_map(&p))), Vec::new()))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::files::environment_image::write_hdr;
    use crate::files::scene_file::parse_scene;
    use crate::lights::environment::Environment;
    use crate::math::color::Color;

    fn scene(environment: &str, dir: &Path) -> Result<crate::files::scene_file::LoadedScene, String> {
        let text = format!(
            r#"(
    camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
    image: (width: 8, height: 6),
    {environment}
    materials: {{}},
    objects: [],
)"#
        );
        parse_scene(&text, "env.ron", dir).map_err(|e| e.to_string())
    }

    fn dir() -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("rt-env-scene-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_map_is_read_relative_to_the_scene_file_with_its_strength_and_rotation() {
        let d = dir();
        let mut texels = vec![Color::splat(0.5); 8];
        texels[0] = Color::new(f32::NAN, 1.0, 1.0);
        write_hdr(&d.join("m.hdr"), 4, 2, &texels).unwrap();
        let loaded = scene(r#"environment: Map(file: "m.hdr", strength: 2, rotation: 90),"#, &d).unwrap();
        let Environment::Map(map) = loaded.scene.environment() else { panic!("a map") };
        assert_eq!((map.size(), map.strength(), map.rotation_degrees()), ((4, 2), 2.0, 90.0));
        // RGBE has no NaN: the encoder wrote something finite; nothing to warn about.
        assert!(loaded.scene.warnings().is_empty(), "{:?}", loaded.scene.warnings());
        // A file the scene was read from (hashed by split renders, watched by the viewer).
        assert_eq!(loaded.scene.source_files(), [d.join("m.hdr")]);
    }

    #[test]
    fn a_missing_map_names_the_file_and_a_bad_value_its_field() {
        let e = scene(r#"environment: Map(file: "nowhere.hdr"),"#, &dir()).unwrap_err();
        assert!(e.contains("env.ron") && e.contains("nowhere.hdr") && e.contains("cannot read"), "{e}");
        let e = scene(r#"environment: Map(file: "m.hdr", strength: -1),"#, &dir()).unwrap_err();
        assert!(e.contains("strength must not be negative"), "{e}");
        let e = scene("environment: Sky(sun_direction: (1, -0.2, 0)),", &dir()).unwrap_err();
        assert!(e.contains("above the horizon"), "{e}");
        let e = scene("environment: Sky(sun_direction: (1, 1, 0), turbidity: 20),", &dir()).unwrap_err();
        assert!(e.contains("turbidity must be"), "{e}");
    }

    #[test]
    fn a_sky_has_a_sun_scaled_by_the_strength() {
        let loaded = scene(
            "environment: Sky(sun_direction: (1, 1, 0), strength: 0.5, sun_irradiance: (4, 4, 4)),",
            &dir(),
        )
        .unwrap();
        let Environment::Map(map) = loaded.scene.environment() else { panic!("a map") };
        assert_eq!(map.sun().unwrap().irradiance(), Color::splat(2.0));
    }

    #[test]
    fn background_and_environment_together_are_refused() {
        let e =
            scene("background: (1, 1, 1), environment: Sky(sun_direction: (1, 1, 0)),", &dir()).unwrap_err();
        assert!(e.contains("background") && e.contains("environment"), "{e}");
    }
}
