//! The `effects` block: recursion depth, ambient occlusion and global
//! illumination.

use serde::Deserialize;

use super::values::{Finite, check_count, present};
use crate::scene::effects::{
    AmbientOcclusion, GlobalIllumination, MAX_BOUNCES, MAX_DEPTH, MAX_EFFECT_SAMPLES, MAX_WALK_STEPS,
};

/// `effects: (max_depth: 5, ambient_occlusion: (samples: 16, radius: 1.5),
/// global_illumination: (max_bounces: 8))`; every field optional.
#[derive(Default, Deserialize)]
#[serde(deny_unknown_fields, rename = "Effects")]
pub(super) struct EffectsDesc {
    #[serde(default)]
    pub(super) max_depth: DepthDesc,
    #[serde(default, deserialize_with = "present")]
    pub(super) ambient_occlusion: Option<AoDesc>,
    #[serde(default, deserialize_with = "present")]
    pub(super) global_illumination: Option<GiDesc>,
}

/// Reflection/refraction recursion depth, 0 to [`MAX_DEPTH`]; 5 when absent.
#[derive(Deserialize)]
#[serde(try_from = "u32")]
pub(super) struct DepthDesc(pub(super) u32);

impl Default for DepthDesc {
    fn default() -> Self {
        Self(5)
    }
}

impl TryFrom<u32> for DepthDesc {
    type Error = String;
    fn try_from(n: u32) -> Result<Self, String> {
        check_count("effects.max_depth", 0..=MAX_DEPTH, n).map(Self)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "AmbientOcclusion")]
pub(super) struct AoFields {
    samples: u32,
    radius: Finite,
}

#[derive(Deserialize)]
#[serde(try_from = "AoFields")]
pub(super) struct AoDesc(pub(super) AmbientOcclusion);

impl TryFrom<AoFields> for AoDesc {
    type Error = String;
    fn try_from(f: AoFields) -> Result<Self, String> {
        let samples = check_count("ambient_occlusion.samples", 1..=MAX_EFFECT_SAMPLES, f.samples)?;
        if f.radius.0 <= 0.0 {
            return Err(format!("ambient_occlusion.radius must be positive, got {}", f.radius.0));
        }
        Ok(Self(AmbientOcclusion { samples, radius: f.radius.0 }))
    }
}

/// `global_illumination: (max_bounces: 8, russian_roulette: true,
/// max_walk_steps: 4096)`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "GlobalIllumination")]
struct GiFields {
    #[serde(default = "default_bounces")]
    max_bounces: u32,
    #[serde(default = "super::values::yes")]
    russian_roulette: bool,
    #[serde(default = "default_walk_steps")]
    max_walk_steps: u32,
}

/// The walk cap a scene gets unless it sets one.
fn default_walk_steps() -> u32 {
    crate::scene::effects::DEFAULT_WALK_STEPS
}

/// Eight bounces: enough for the light of most interiors.
fn default_bounces() -> u32 {
    8
}

#[derive(Deserialize)]
#[serde(try_from = "GiFields")]
pub(super) struct GiDesc(pub(super) GlobalIllumination);

impl TryFrom<GiFields> for GiDesc {
    type Error = String;
    fn try_from(f: GiFields) -> Result<Self, String> {
        let max_bounces = check_count("global_illumination.max_bounces", 0..=MAX_BOUNCES, f.max_bounces)?;
        let max_walk_steps =
            check_count("global_illumination.max_walk_steps", 1..=MAX_WALK_STEPS, f.max_walk_steps)?;
        Ok(Self(GlobalIllumination { max_bounces, russian_roulette: f.russian_roulette, max_walk_steps }))
    }
}
