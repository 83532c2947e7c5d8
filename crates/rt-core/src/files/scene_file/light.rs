//! The `lights` list: point, spot, directional and sphere lights.

use serde::Deserialize;

use super::values::{ColorDesc, Finite, V3, check_count, unit_scale, white, yes};
use crate::lights::light::{Light, LightKind};
use crate::math::real::{normalize_robust, to_f32};
use crate::scene::effects::MAX_EFFECT_SAMPLES;

/// The lights exactly as written in a scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Light")]
pub(super) enum LightFields {
    Point {
        position: V3,
        #[serde(default = "white")]
        color: ColorDesc,
        #[serde(default = "unit_scale")]
        intensity: Finite,
        #[serde(default = "yes")]
        shadows: bool,
    },
    Spot {
        position: V3,
        direction: V3,
        #[serde(default = "zero")]
        inner_angle: Finite,
        #[serde(default = "forty_five")]
        outer_angle: Finite,
        #[serde(default = "white")]
        color: ColorDesc,
        #[serde(default = "unit_scale")]
        intensity: Finite,
        #[serde(default = "yes")]
        shadows: bool,
    },
    Directional {
        direction: V3,
        #[serde(default = "white")]
        color: ColorDesc,
        #[serde(default = "unit_scale")]
        intensity: Finite,
        #[serde(default = "yes")]
        shadows: bool,
    },
    Sphere {
        center: V3,
        radius: Finite,
        #[serde(default = "white")]
        color: ColorDesc,
        #[serde(default = "unit_scale")]
        intensity: Finite,
        #[serde(default = "sixteen")]
        samples: u32,
        #[serde(default = "yes")]
        shadows: bool,
    },
}

pub(super) fn sixteen() -> u32 {
    16
}

/// A spot light's inner cone angle when none is given: glTF's default, 0.
fn zero() -> Finite {
    Finite(0.0)
}

/// A spot light's outer cone angle when none is given: glTF's default, π/4.
fn forty_five() -> Finite {
    Finite(45.0)
}

#[derive(Deserialize)]
#[serde(try_from = "LightFields")]
pub(super) struct LightDesc(pub(super) Light);

impl TryFrom<LightFields> for LightDesc {
    type Error = String;
    fn try_from(f: LightFields) -> Result<Self, String> {
        let power = |color: ColorDesc, intensity: Finite| {
            if intensity.0 >= 0.0 {
                Ok(color.0 * to_f32(intensity.0))
            } else {
                Err(format!("light intensity must not be negative, got {}", intensity.0))
            }
        };
        let light = match f {
            LightFields::Point { position, color, intensity, shadows } => Light {
                kind: LightKind::Point { position: position.into() },
                power: power(color, intensity)?,
                shadows,
            },
            LightFields::Spot {
                position,
                direction,
                inner_angle,
                outer_angle,
                color,
                intensity,
                shadows,
            } => {
                let direction =
                    normalize_robust(direction.into()).ok_or("spot light direction must not be zero")?;
                let (inner, outer) = (inner_angle.0, outer_angle.0);
                if !(0.0 <= inner && inner < outer && outer <= 90.0) {
                    return Err(format!(
                        "spot light angles must satisfy 0 <= inner_angle < outer_angle <= 90 (degrees), got {inner} and {outer}"
                    ));
                }
                Light {
                    kind: LightKind::Spot {
                        position: position.into(),
                        direction,
                        cos_inner: inner.to_radians().cos(),
                        cos_outer: outer.to_radians().cos(),
                    },
                    power: power(color, intensity)?,
                    shadows,
                }
            }
            LightFields::Directional { direction, color, intensity, shadows } => {
                let direction = normalize_robust(direction.into())
                    .ok_or("directional light direction must not be zero")?;
                Light { kind: LightKind::Directional { direction }, power: power(color, intensity)?, shadows }
            }
            LightFields::Sphere { center, radius, color, intensity, samples, shadows } => {
                if radius.0 <= 0.0 {
                    return Err(format!("sphere light radius must be positive, got {}", radius.0));
                }
                check_count("sphere light samples", 1..=MAX_EFFECT_SAMPLES, samples)?;
                Light {
                    kind: LightKind::Sphere { center: center.into(), radius: radius.0, samples },
                    power: power(color, intensity)?,
                    shadows,
                }
            }
        };
        Ok(Self(light))
    }
}
