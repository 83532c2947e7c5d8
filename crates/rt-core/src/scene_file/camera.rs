//! The `camera`, `image` and `samples_per_pixel` fields: what is seen, and
//! at what resolution.

use serde::Deserialize;

use super::values::{Finite, V3, check_count};
use crate::camera::{Camera, CameraError, Projection};
use crate::sampler::MAX_SAMPLES_PER_PIXEL;
use crate::view_plane::{ViewPlaneError, check_image_size};

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
pub(super) struct CameraFields {
    position: V3,
    center_of_interest: V3,
    up: V3,
    fov_y: Finite,
    near: Finite,
    #[serde(default)]
    projection: Projection,
}

#[derive(Deserialize)]
#[serde(try_from = "CameraFields")]
pub(super) struct CameraDesc(pub(super) Camera);

impl TryFrom<CameraFields> for CameraDesc {
    type Error = CameraError;
    fn try_from(c: CameraFields) -> Result<Self, CameraError> {
        let camera = Camera::new(
            c.position.into(),
            c.center_of_interest.into(),
            c.up.into(),
            c.fov_y.0,
            c.near.0,
            c.projection,
        )?;
        Ok(Self(camera))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Image")]
pub(super) struct ImageFields {
    width: u32,
    height: u32,
}

#[derive(Deserialize)]
#[serde(try_from = "ImageFields")]
pub(super) struct ImageDesc {
    pub(super) width: u32,
    pub(super) height: u32,
}

impl TryFrom<ImageFields> for ImageDesc {
    type Error = ViewPlaneError;
    fn try_from(f: ImageFields) -> Result<Self, ViewPlaneError> {
        check_image_size(f.width, f.height)?;
        Ok(Self { width: f.width, height: f.height })
    }
}

/// Samples per pixel, 1 to [`MAX_SAMPLES_PER_PIXEL`]; 1 when absent.
#[derive(Deserialize)]
#[serde(try_from = "u32")]
pub(super) struct SamplesDesc(pub(super) u32);

impl Default for SamplesDesc {
    fn default() -> Self {
        Self(1)
    }
}

impl TryFrom<u32> for SamplesDesc {
    type Error = String;
    fn try_from(n: u32) -> Result<Self, String> {
        check_count("samples_per_pixel", 1..=MAX_SAMPLES_PER_PIXEL, n).map(Self)
    }
}
