//! The `camera`, `image` and `samples_per_pixel` fields: what is seen, and
//! at what resolution.

use std::path::PathBuf;

use serde::Deserialize;

use super::values::{Finite, V3};
use crate::camera::{Camera, CameraBasis, CameraError, Projection};
use crate::math::real::{Real, Vec3};
use crate::render::settings::{ImageSize, SamplesPerPixel, SettingsError};

/// The camera as written, validated field by field as it is read, so that an
/// error points at the field that makes the camera degenerate: `fov_y` and
/// `near` at their values, a position, centre of interest and up vector that
/// make no camera at whichever of the three is read last. Or a glTF file's
/// camera, `(gltf: FILE, index: N, scale: S, translate: T)`, read once the
/// scene file's folder is known ([`crate::files::gltf_model::camera`]).
pub(super) enum CameraDesc {
    /// The camera the fields describe.
    Ready(Camera),
    /// Camera `index` of glTF file `file`, placed as a Mesh entry with the
    /// same `scale` and `translate` places the model.
    Gltf { file: PathBuf, index: usize, scale: Real, translate: Vec3 },
}

/// The camera's field names.
#[derive(Deserialize)]
#[serde(field_identifier, rename_all = "snake_case")]
enum Field {
    Position,
    CenterOfInterest,
    Up,
    FovY,
    Near,
    Projection,
    Gltf,
    Index,
    Scale,
    Translate,
}

const FIELDS: &[&str] = &[
    "position",
    "center_of_interest",
    "up",
    "fov_y",
    "near",
    "projection",
    "gltf",
    "index",
    "scale",
    "translate",
];

impl<'de> Deserialize<'de> for CameraDesc {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_struct("Camera", FIELDS, CameraVisitor)
    }
}

struct CameraVisitor;

impl<'de> serde::de::Visitor<'de> for CameraVisitor {
    type Value = CameraDesc;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(
            "a camera: (position, center_of_interest, up, fov_y, near, projection) or (gltf, index, scale, translate)",
        )
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<CameraDesc, A::Error> {
        use serde::de::Error;
        let (mut position, mut center, mut up) = (None, None, None);
        let (mut fov_y, mut near, mut projection) = (None, None, None);
        let (mut gltf, mut index, mut scale, mut translate) = (None, None, None, None);
        while let Some(field) = map.next_key::<Field>()? {
            let duplicate = |name| A::Error::duplicate_field(name);
            match field {
                Field::Position if position.is_some() => return Err(duplicate("position")),
                Field::CenterOfInterest if center.is_some() => return Err(duplicate("center_of_interest")),
                Field::Up if up.is_some() => return Err(duplicate("up")),
                Field::FovY if fov_y.is_some() => return Err(duplicate("fov_y")),
                Field::Near if near.is_some() => return Err(duplicate("near")),
                Field::Projection if projection.is_some() => return Err(duplicate("projection")),
                Field::Position => position = Some(Vec3::from(map.next_value::<V3>()?)),
                Field::CenterOfInterest => center = Some(Vec3::from(map.next_value::<V3>()?)),
                Field::Up => up = Some(Vec3::from(map.next_value::<V3>()?)),
                Field::FovY => {
                    let v = map.next_value::<Finite>()?.0;
                    if !(v > 0.0 && v < 180.0) {
                        return Err(A::Error::custom(CameraError::FovOutOfRange(v)));
                    }
                    fov_y = Some(v);
                }
                Field::Near => {
                    let v = map.next_value::<Finite>()?.0;
                    if v <= 0.0 {
                        return Err(A::Error::custom(CameraError::NearNotPositive(v)));
                    }
                    near = Some(v);
                }
                Field::Projection => projection = Some(map.next_value::<Projection>()?),
                Field::Gltf if gltf.is_some() => return Err(duplicate("gltf")),
                Field::Index if index.is_some() => return Err(duplicate("index")),
                Field::Scale if scale.is_some() => return Err(duplicate("scale")),
                Field::Translate if translate.is_some() => return Err(duplicate("translate")),
                Field::Gltf => gltf = Some(map.next_value::<PathBuf>()?),
                Field::Index => index = Some(map.next_value::<usize>()?),
                Field::Scale => {
                    let v = map.next_value::<Finite>()?.0;
                    if v <= 0.0 {
                        return Err(A::Error::custom(format!("camera.scale must be positive, got {v}")));
                    }
                    scale = Some(v);
                }
                Field::Translate => translate = Some(Vec3::from(map.next_value::<V3>()?)),
            }
            // A glTF camera has none of the fields that describe one here.
            let own = [position.is_some(), center.is_some(), up.is_some(), fov_y.is_some(), near.is_some()];
            if (gltf.is_some() || index.is_some() || scale.is_some() || translate.is_some())
                && (own.contains(&true) || projection.is_some())
            {
                return Err(A::Error::custom(
                    "a camera is either described (position, center_of_interest, up, fov_y, near, projection) \
                     or taken from a glTF file (gltf, index, scale, translate), not both",
                ));
            }
            // As soon as the three points are known, check that they make a
            // camera: the error then points at the one just read.
            if matches!(field, Field::Position | Field::CenterOfInterest | Field::Up)
                && let (Some(p), Some(c), Some(u)) = (position, center, up)
            {
                CameraBasis::new(p, c, u).map_err(A::Error::custom)?;
            }
        }
        if let Some(file) = gltf {
            return Ok(CameraDesc::Gltf {
                file,
                index: index.unwrap_or(0),
                scale: scale.unwrap_or(1.0),
                translate: translate.unwrap_or(Vec3::ZERO),
            });
        }
        if index.is_some() || scale.is_some() || translate.is_some() {
            return Err(A::Error::missing_field("gltf"));
        }
        let position = position.ok_or_else(|| A::Error::missing_field("position"))?;
        let center = center.ok_or_else(|| A::Error::missing_field("center_of_interest"))?;
        let up = up.ok_or_else(|| A::Error::missing_field("up"))?;
        let fov_y = fov_y.ok_or_else(|| A::Error::missing_field("fov_y"))?;
        let near = near.ok_or_else(|| A::Error::missing_field("near"))?;
        let camera = Camera::new(position, center, up, fov_y, near, projection.unwrap_or_default())
            .map_err(A::Error::custom)?;
        Ok(CameraDesc::Ready(camera))
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
pub(super) struct ImageDesc(pub(super) ImageSize);

impl TryFrom<ImageFields> for ImageDesc {
    type Error = SettingsError;
    fn try_from(f: ImageFields) -> Result<Self, SettingsError> {
        ImageSize::new(f.width, f.height).map(Self)
    }
}

/// Samples per pixel ([`SamplesPerPixel`]); 1 when absent.
#[derive(Default, Deserialize)]
#[serde(try_from = "u32")]
pub(super) struct SamplesDesc(pub(super) SamplesPerPixel);

impl TryFrom<u32> for SamplesDesc {
    type Error = SettingsError;
    fn try_from(n: u32) -> Result<Self, SettingsError> {
        SamplesPerPixel::new(n).map(Self)
    }
}
