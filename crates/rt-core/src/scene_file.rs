//! Scene files: RON text → description types (serde) → a validated [`Scene`].
//!
//! Values are checked where they are read, so RON can point at them: every
//! number must be finite (a [`Finite`] reads it), and each camera, image size
//! and object is validated as soon as it is parsed (`#[serde(try_from)]`), so
//! its error carries the line and column where the value ends. What needs the
//! whole file (material names) or the disk (OBJ files) is checked afterwards
//! and names the object by its index.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;
use thiserror::Error;

use crate::aabb::Aabb;
use crate::camera::{Camera, CameraError, Projection};
use crate::material::{Color, Material};
use crate::mesh::{Mesh, MeshError};
use crate::plane::Plane;
use crate::polygon::Polygon;
use crate::primitive::{GeometryError, Primitive};
use crate::real::{Real, Vec3};
use crate::scene::{Object, Scene};
use crate::sphere::Sphere;
use crate::triangle::Triangle;
use crate::view_plane::{ViewPlaneError, check_image_size};

/// Largest accepted samples-per-pixel count.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 1 << 16;

/// Why a scene file cannot be loaded. `file` is the path as given.
#[derive(Debug, Error)]
pub enum SceneError {
    /// The file cannot be read.
    #[error("{file}: cannot read scene file: {reason}")]
    Read {
        /// The scene file.
        file: String,
        /// The I/O error (in the message, so not also a `source()`).
        reason: std::io::Error,
    },
    /// RON syntax, an unknown or missing field, a wrong type, or a value that
    /// failed validation where it was read.
    #[error("{file}:{line}:{column}: {message}")]
    Parse {
        /// The scene file.
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// An object names a material the file does not define.
    #[error("{file}: objects[{index}] ({kind}): unknown material \"{name}\" (defined: {defined})")]
    UnknownMaterial {
        /// The scene file.
        file: String,
        /// 0-based object index.
        index: usize,
        /// The object's variant.
        kind: &'static str,
        /// The missing name.
        name: String,
        /// The names that exist, comma-separated.
        defined: String,
    },
    /// A mesh's OBJ file cannot be used.
    #[error("{file}: objects[{index}] (Mesh): {reason}")]
    Mesh {
        /// The scene file.
        file: String,
        /// 0-based object index.
        index: usize,
        /// Why the mesh failed (in the message, so not also a `source()`).
        reason: MeshError,
    },
}

/// Reads and validates the scene file at `path`; OBJ paths are relative to
/// its directory.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let text =
        std::fs::read_to_string(path).map_err(|reason| SceneError::Read { file: file.clone(), reason })?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    parse_scene(&text, &file, base_dir)
}

/// Parses and validates scene text. `file` names it in errors; OBJ paths are
/// relative to `base_dir`.
pub fn parse_scene(text: &str, file: &str, base_dir: &Path) -> Result<Scene, SceneError> {
    let desc: SceneDesc = ron::from_str(text).map_err(|e| SceneError::Parse {
        file: file.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    })?;

    let material_names: Vec<String> = desc.materials.keys().cloned().collect();
    let materials = desc.materials.values().map(|m| Material { color: m.color.0 }).collect();
    let objects = desc
        .objects
        .into_iter()
        .enumerate()
        .map(|(index, entry)| {
            let kind = entry.shape.kind();
            let material =
                material_names.binary_search(&entry.material).map_err(|_| SceneError::UnknownMaterial {
                    file: file.to_owned(),
                    index,
                    kind,
                    name: entry.material.clone(),
                    defined: material_names.join(", "),
                })?;
            let primitive = match entry.shape {
                Shape::Ready(p) => p,
                Shape::Mesh { file: obj, scale, translate } => {
                    let mesh = Mesh::load_obj(&base_dir.join(obj), scale, translate)
                        .map_err(|reason| SceneError::Mesh { file: file.to_owned(), index, reason })?;
                    Primitive::Mesh(mesh)
                }
            };
            Ok(Object { primitive, material })
        })
        .collect::<Result<_, _>>()?;

    Ok(Scene::new(
        desc.camera.0,
        (desc.image.width, desc.image.height),
        desc.background.0,
        desc.samples_per_pixel.0,
        materials,
        material_names,
        objects,
    ))
}

/// A number that must be finite (RON also reads `NaN` and `inf`).
#[derive(Clone, Copy, Debug)]
struct Finite(Real);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Real::deserialize(d)?;
        if v.is_finite() {
            Ok(Self(v))
        } else {
            Err(serde::de::Error::custom(format!("expected a finite number, found {v}")))
        }
    }
}

/// A point or vector written `(x, y, z)`.
#[derive(Clone, Copy, Debug, Deserialize)]
struct V3(Finite, Finite, Finite);

impl From<V3> for Vec3 {
    fn from(v: V3) -> Self {
        Vec3::new(v.0.0, v.1.0, v.2.0)
    }
}

impl Default for V3 {
    fn default() -> Self {
        V3(Finite(0.0), Finite(0.0), Finite(0.0))
    }
}

/// A colour written `(r, g, b)`, each finite and ≥ 0.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(try_from = "V3")]
struct ColorDesc(Color);

impl TryFrom<V3> for ColorDesc {
    type Error = String;
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    fn try_from(v: V3) -> Result<Self, String> {
        let c = Vec3::from(v);
        if c.cmplt(Vec3::ZERO).any() {
            return Err(format!("colour components must not be negative, got {c}"));
        }
        Ok(Self(Color::new(c.x as f32, c.y as f32, c.z as f32)))
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
struct SceneDesc {
    camera: CameraDesc,
    image: ImageDesc,
    #[serde(default)]
    background: ColorDesc,
    #[serde(default)]
    samples_per_pixel: SamplesDesc,
    #[serde(deserialize_with = "unique_materials")]
    materials: BTreeMap<String, MaterialDesc>,
    objects: Vec<ObjectEntry>,
}

/// The materials map, refusing a name defined twice (a plain map would keep
/// the last one silently).
fn unique_materials<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, MaterialDesc>, D::Error> {
    struct Unique;
    impl<'de> serde::de::Visitor<'de> for Unique {
        type Value = BTreeMap<String, MaterialDesc>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map from material names to materials")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some((name, material)) = map.next_entry::<String, MaterialDesc>()? {
                if out.contains_key(&name) {
                    return Err(serde::de::Error::custom(format!("material \"{name}\" is defined twice")));
                }
                out.insert(name, material);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Unique)
}

/// Samples per pixel, 1 to [`MAX_SAMPLES_PER_PIXEL`]; 1 when absent.
#[derive(Deserialize)]
#[serde(try_from = "u32")]
struct SamplesDesc(u32);

impl Default for SamplesDesc {
    fn default() -> Self {
        Self(1)
    }
}

impl TryFrom<u32> for SamplesDesc {
    type Error = String;
    fn try_from(n: u32) -> Result<Self, String> {
        if (1..=MAX_SAMPLES_PER_PIXEL).contains(&n) {
            Ok(Self(n))
        } else {
            Err(format!("samples_per_pixel must be 1 to {MAX_SAMPLES_PER_PIXEL}, got {n}"))
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Camera")]
struct CameraFields {
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
struct CameraDesc(Camera);

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
struct ImageFields {
    width: u32,
    height: u32,
}

#[derive(Deserialize)]
#[serde(try_from = "ImageFields")]
struct ImageDesc {
    width: u32,
    height: u32,
}

impl TryFrom<ImageFields> for ImageDesc {
    type Error = ViewPlaneError;
    fn try_from(f: ImageFields) -> Result<Self, ViewPlaneError> {
        check_image_size(f.width, f.height)?;
        Ok(Self { width: f.width, height: f.height })
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
struct MaterialDesc {
    color: ColorDesc,
}

/// The object variants exactly as written in a scene file.
#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Object")]
enum ObjectDesc {
    Sphere {
        center: V3,
        radius: Finite,
        material: String,
    },
    Plane {
        normal: V3,
        d: Finite,
        material: String,
    },
    Aabb {
        min: V3,
        max: V3,
        material: String,
    },
    Triangle {
        a: V3,
        b: V3,
        c: V3,
        material: String,
    },
    Polygon {
        points: Vec<V3>,
        material: String,
    },
    Mesh {
        file: PathBuf,
        material: String,
        #[serde(default = "unit_scale")]
        scale: Finite,
        #[serde(default)]
        translate: V3,
    },
}

fn unit_scale() -> Finite {
    Finite(1.0)
}

/// An object whose geometry is validated, except a mesh's file, which is read later.
#[derive(Deserialize)]
#[serde(try_from = "ObjectDesc")]
struct ObjectEntry {
    shape: Shape,
    material: String,
}

enum Shape {
    Ready(Primitive),
    Mesh { file: PathBuf, scale: Real, translate: Vec3 },
}

impl Shape {
    fn kind(&self) -> &'static str {
        match self {
            Shape::Ready(p) => p.kind(),
            Shape::Mesh { .. } => "Mesh",
        }
    }
}

impl TryFrom<ObjectDesc> for ObjectEntry {
    type Error = String;
    fn try_from(o: ObjectDesc) -> Result<Self, String> {
        let ready = |p: Result<Primitive, GeometryError>, material| {
            p.map(|p| Self { shape: Shape::Ready(p), material }).map_err(|e| e.to_string())
        };
        match o {
            ObjectDesc::Sphere { center, radius, material } => {
                ready(Sphere::new(center.into(), radius.0).map(Primitive::Sphere), material)
            }
            ObjectDesc::Plane { normal, d, material } => {
                ready(Plane::new(normal.into(), d.0).map(Primitive::Plane), material)
            }
            ObjectDesc::Aabb { min, max, material } => {
                ready(Aabb::new(min.into(), max.into()).map(Primitive::Aabb), material)
            }
            ObjectDesc::Triangle { a, b, c, material } => {
                ready(Triangle::new(a.into(), b.into(), c.into()).map(Primitive::Triangle), material)
            }
            ObjectDesc::Polygon { points, material } => {
                let points = points.into_iter().map(Vec3::from).collect();
                ready(Polygon::new(points).map(Primitive::Polygon), material)
            }
            ObjectDesc::Mesh { file, material, scale, translate } => {
                if scale.0 <= 0.0 {
                    return Err(format!("mesh scale must be positive, got {}", scale.0));
                }
                Ok(Self {
                    shape: Shape::Mesh { file, scale: scale.0, translate: translate.into() },
                    material,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = r#"Scene(
    camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
    image: (width: 32, height: 24),
    materials: { "red": (color: (1, 0, 0)), "grey": (color: (0.5, 0.5, 0.5)) },
    objects: [
        Sphere(center: (0, 0, 0), radius: 1, material: "red"),
        Plane(normal: (0, 1, 0), d: -1, material: "grey"),
    ],
)"#;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        parse_scene(text, "bad.ron", Path::new("."))
    }

    /// The error for `GOOD` with `from` replaced by `to`, as text.
    fn error_after(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        parse(&GOOD.replacen(from, to, 1)).unwrap_err().to_string()
    }

    #[test]
    fn a_good_scene_loads_with_defaults_filled_in() {
        let s = parse(GOOD).unwrap();
        assert_eq!((s.width, s.height, s.samples_per_pixel), (32, 24, 1));
        assert_eq!(s.background, Color::ZERO);
        assert_eq!(s.material_names, ["grey", "red"]);
        assert_eq!(s.objects().len(), 2);
        assert_eq!(s.objects()[0].material, 1);
        assert_eq!(s.camera.projection(), Projection::Perspective);
    }

    #[test]
    fn syntax_errors_give_line_and_column() {
        assert_eq!(error_after("radius: 1,", "radius: 1,,"), "bad.ron:6:45: Expected identifier");
    }

    #[test]
    fn unknown_fields_are_refused_where_they_stand() {
        let e = error_after("radius: 1,", "radius: 1, colour: 3,");
        assert!(e.starts_with("bad.ron:6:46: Unexpected field named `colour` in `Sphere`"), "{e}");
        let e = error_after("image:", "imag:");
        assert!(e.starts_with("bad.ron:3:5: Unexpected field named `imag` in `Scene`"), "{e}");
    }

    #[test]
    fn missing_fields_and_unknown_kinds_are_refused() {
        let e = error_after("radius: 1, ", "");
        assert!(e.starts_with("bad.ron:6:") && e.contains("missing field named `radius`"), "{e}");
        let e = error_after("Sphere(", "Ball(");
        assert!(e.contains("Unexpected variant named `Ball` in enum `Object`"), "{e}");
    }

    #[test]
    fn a_material_defined_twice_is_refused_where_it_stands() {
        let e = error_after("\"grey\": (color: (0.5, 0.5, 0.5))", "\"red\": (color: (0.5, 0.5, 0.5))");
        assert!(e.starts_with("bad.ron:4:") && e.ends_with("material \"red\" is defined twice"), "{e}");
    }

    #[test]
    fn missing_material_names_the_object_and_the_choices() {
        let e = error_after("material: \"red\"", "material: \"blue\"");
        assert_eq!(e, "bad.ron: objects[0] (Sphere): unknown material \"blue\" (defined: grey, red)");
    }

    #[test]
    fn nan_and_infinite_numbers_are_refused_at_the_number() {
        assert_eq!(
            error_after("center: (0, 0, 0)", "center: (0, NaN, 0)"),
            "bad.ron:6:28: expected a finite number, found NaN"
        );
        let e = error_after("near: 1", "near: inf");
        assert!(e.starts_with("bad.ron:2:") && e.contains("expected a finite number, found inf"), "{e}");
    }

    #[test]
    fn negative_radius_is_refused_with_its_position() {
        let e = error_after("radius: 1", "radius: -1");
        assert_eq!(e, "bad.ron:6:62: sphere radius must be positive, got -1");
    }

    #[test]
    fn degenerate_cameras_name_the_field() {
        let cases = [
            ("up: (0, 1, 0)", "up: (0, 0, 2)", "camera.up is zero or parallel"),
            ("position: (0, 0, -5)", "position: (0, 0, 0)", "coincides with camera.position"),
            ("fov_y: 40", "fov_y: 180", "camera.fov_y must be strictly between 0 and 180"),
            ("fov_y: 40", "fov_y: 0", "camera.fov_y must be strictly between 0 and 180"),
            ("near: 1", "near: 0", "camera.near must be a positive finite number"),
        ];
        for (from, to, expected) in cases {
            let e = error_after(from, to);
            assert!(e.starts_with("bad.ron:2:") && e.contains(expected), "{to}: {e}");
        }
    }

    #[test]
    fn degenerate_polygons_triangles_and_boxes_are_refused() {
        let sphere = "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")";
        let cases = [
            (
                "Polygon(points: [(0,0,0), (1,0,0), (1,1,0.5), (0,1,0)], material: \"red\")",
                "polygon is not planar: point",
            ),
            ("Polygon(points: [(0,0,0), (1,0,0), (2,0,0)], material: \"red\")", "polygon has zero area"),
            (
                "Polygon(points: [(0,0,0), (1,0,0)], material: \"red\")",
                "polygon needs at least 3 points, got 2",
            ),
            ("Triangle(a: (0,0,0), b: (1,1,1), c: (2,2,2), material: \"red\")", "triangle has zero area"),
            ("Aabb(min: (1,0,0), max: (0,1,1), material: \"red\")", "box min must not exceed max"),
            ("Plane(normal: (0,0,0), d: 1, material: \"red\")", "plane normal must not be zero"),
            ("Mesh(file: \"m.obj\", scale: 0, material: \"red\")", "mesh scale must be positive"),
        ];
        for (object, expected) in cases {
            let e = error_after(sphere, object);
            assert!(e.starts_with("bad.ron:6:") && e.contains(expected), "{object}: {e}");
        }
    }

    #[test]
    fn bad_image_sizes_and_sample_counts_are_refused() {
        let e = error_after("width: 32", "width: 0");
        assert!(e.starts_with("bad.ron:3:") && e.contains("image size 0x24 is out of range"), "{e}");
        let e = error_after("width: 32", "width: -4");
        assert!(e.starts_with("bad.ron:3:"), "{e}");
        let e = error_after("image:", "samples_per_pixel: 0, image:");
        assert!(e.contains("samples_per_pixel must be 1 to"), "{e}");
    }

    #[test]
    fn a_missing_obj_file_names_the_object_and_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let text = GOOD.replace(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")",
            "Mesh(file: \"meshes/nope.obj\", material: \"red\")",
        );
        let e = parse_scene(&text, "bad.ron", dir.path()).unwrap_err().to_string();
        assert!(e.starts_with("bad.ron: objects[0] (Mesh): cannot load OBJ file"), "{e}");
        assert!(e.contains("meshes/nope.obj"), "{e}");
    }

    #[test]
    fn an_obj_file_is_found_relative_to_the_scene_file() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("meshes")).unwrap();
        std::fs::write(dir.path().join("meshes/t.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let text = GOOD.replace(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")",
            "Mesh(file: \"meshes/t.obj\", translate: (0, 0, 2), material: \"red\")",
        );
        let path = dir.path().join("scene.ron");
        std::fs::write(&path, text).unwrap();
        let scene = load_scene(&path).unwrap();
        assert!(matches!(&scene.objects()[0].primitive, Primitive::Mesh(m) if m.triangle_count() == 1));
    }

    #[test]
    fn an_unreadable_scene_file_is_an_error_naming_it() {
        let e = load_scene(Path::new("/nonexistent/scene.ron")).unwrap_err().to_string();
        assert!(e.starts_with("/nonexistent/scene.ron: cannot read scene file"), "{e}");
    }
}
