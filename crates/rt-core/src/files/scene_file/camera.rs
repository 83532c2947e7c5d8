//! The `camera`, `image`, `samples_per_pixel` and `exposure` fields: what
//! is seen, at what resolution, and how brightly.

use std::path::PathBuf;

use serde::Deserialize;

use super::values::{Finite, V3};
use crate::camera::{Camera, CameraBasis, CameraError, Lens, Projection};
use crate::math::real::{Real, Vec3, to_f32};
use crate::render::settings::{ImageSize, SamplesPerPixel, SettingsError};
use crate::render::view_transform::MAX_EXPOSURE_STOPS;

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
    Aperture,
    FocusDistance,
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
    "aperture",
    "focus_distance",
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
            "a camera: (position, center_of_interest, up, fov_y, near, projection, aperture, focus_distance) \
             or (gltf, index, scale, translate)",
        )
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<CameraDesc, A::Error> {
        use serde::de::Error;
        let (mut position, mut center, mut up) = (None, None, None);
        let (mut fov_y, mut near, mut projection) = (None, None, None);
        let (mut gltf, mut index, mut scale, mut translate) = (None, None, None, None);
        let (mut aperture, mut focus_distance) = (None, None);
        while let Some(field) = map.next_key::<Field>()? {
            let duplicate = |name| A::Error::duplicate_field(name);
            match field {
                Field::Position if position.is_some() => return Err(duplicate("position")),
                Field::CenterOfInterest if center.is_some() => return Err(duplicate("center_of_interest")),
                Field::Up if up.is_some() => return Err(duplicate("up")),
                Field::FovY if fov_y.is_some() => return Err(duplicate("fov_y")),
                Field::Near if near.is_some() => return Err(duplicate("near")),
                Field::Projection if projection.is_some() => return Err(duplicate("projection")),
                Field::Aperture if aperture.is_some() => return Err(duplicate("aperture")),
                Field::FocusDistance if focus_distance.is_some() => return Err(duplicate("focus_distance")),
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
                Field::Aperture if aperture.is_some() => return Err(duplicate("aperture")),
                Field::FocusDistance if focus_distance.is_some() => return Err(duplicate("focus_distance")),
                Field::Aperture => {
                    let v = map.next_value::<Finite>()?.0;
                    if v < 0.0 {
                        return Err(A::Error::custom(CameraError::ApertureNotValid(v)));
                    }
                    aperture = Some(v);
                }
                Field::FocusDistance => {
                    let v = map.next_value::<Finite>()?.0;
                    if v <= 0.0 {
                        return Err(A::Error::custom(CameraError::FocusDistanceNotPositive(v)));
                    }
                    focus_distance = Some(v);
                }
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
            let lens = aperture.is_some() || focus_distance.is_some();
            if (gltf.is_some() || index.is_some() || scale.is_some() || translate.is_some())
                && (own.contains(&true) || projection.is_some() || lens)
            {
                return Err(A::Error::custom(
                    "a camera is either described (position, center_of_interest, up, fov_y, near, projection, \
                     aperture, focus_distance) or taken from a glTF file (gltf, index, scale, translate), not both",
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
        // The lens: a pinhole unless `aperture` (its radius) is above 0; in
        // focus at the centre of interest unless `focus_distance` is given
        // (C to COI lies along cam_z, so its length is that distance).
        let lens = match aperture {
            Some(radius) if radius > 0.0 => {
                let focus = focus_distance.unwrap_or_else(|| (center - position).length());
                Lens::new(radius, focus).map_err(A::Error::custom)?
            }
            _ => Lens { focus_distance: focus_distance.unwrap_or(1.0), ..Lens::PINHOLE },
        };
        let camera = camera.with_lens(lens);
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

/// Exposure in stops, within ±[`MAX_EXPOSURE_STOPS`]; 0 when absent.
#[derive(Default, Deserialize)]
#[serde(try_from = "Finite")]
pub(super) struct ExposureDesc(pub(super) f32);

impl TryFrom<Finite> for ExposureDesc {
    type Error = String;
    fn try_from(v: Finite) -> Result<Self, String> {
        let stops = to_f32(v.0);
        if stops.abs() <= MAX_EXPOSURE_STOPS {
            Ok(Self(stops))
        } else {
            Err(format!("exposure must be -{MAX_EXPOSURE_STOPS} to {MAX_EXPOSURE_STOPS} stops, got {stops}"))
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::files::scene_file::parse_scene;

    const SCENE: &str = r#"(
    camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1LENS),
    image: (width: 8, height: 6),
    materials: {},
    objects: [],
)"#;

    fn parse(lens: &str) -> Result<crate::files::scene_file::LoadedScene, String> {
        parse_scene(&SCENE.replace("LENS", lens), "lens.ron", Path::new(".")).map_err(|e| e.to_string())
    }

    #[test]
    fn a_camera_without_an_aperture_is_a_pinhole() {
        assert!(!parse("").unwrap().camera.lens().is_thin_lens());
        assert!(!parse(", aperture: 0").unwrap().camera.lens().is_thin_lens());
    }

    #[test]
    fn a_lens_focuses_on_the_centre_of_interest_unless_told_otherwise() {
        let lens = parse(", aperture: 0.2").unwrap().camera.lens();
        assert_eq!((lens.radius, lens.focus_distance), (0.2, 5.0));
        let lens = parse(", aperture: 0.2, focus_distance: 3.5").unwrap().camera.lens();
        assert_eq!((lens.radius, lens.focus_distance), (0.2, 3.5));
    }

    #[test]
    fn a_negative_aperture_or_a_focus_distance_not_above_zero_is_refused_by_name() {
        let e = parse(", aperture: -0.1").unwrap_err();
        assert!(e.contains("camera.aperture") && e.contains("-0.1"), "{e}");
        let e = parse(", aperture: 0.1, focus_distance: 0").unwrap_err();
        assert!(e.contains("camera.focus_distance"), "{e}");
    }

    #[test]
    fn exposure_and_view_transform_are_read_and_an_absurd_exposure_refused() {
        use crate::render::view_transform::{Display, ViewTransform};
        let text =
            SCENE.replace("LENS", "").replace("image:", "exposure: -1.5, view_transform: AgX,\n    image:");
        let loaded = parse_scene(&text, "x.ron", Path::new(".")).unwrap();
        assert_eq!(loaded.settings.display, Display { exposure: -1.5, view_transform: ViewTransform::AgX });
        let text = SCENE.replace("LENS", "").replace("image:", "exposure: 100,\n    image:");
        let e = parse_scene(&text, "x.ron", Path::new(".")).unwrap_err().to_string();
        assert!(e.contains("exposure must be"), "{e}");
    }
}
