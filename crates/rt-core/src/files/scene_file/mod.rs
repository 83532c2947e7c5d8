//! Scene files: RON text → description types (serde) → a validated
//! [`LoadedScene`]: the world ([`Scene`]), its camera, and the render
//! settings the file asks for ([`RenderSettings`]).
//!
//! Values are checked where they are read, so RON can point at them: every
//! number must be finite (a `values::Finite` reads it), and each camera, image size
//! and object is validated as soon as it is parsed (`#[serde(try_from)]`), so
//! its error carries the line and column where the value ends. What needs the
//! whole file (material names) or the disk (OBJ files) is checked afterwards
//! and names the object by its index.

mod camera;
mod effects;
mod environment;
mod light;
mod material;
mod model;
mod object;
mod values;

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;
use thiserror::Error;

use crate::camera::Camera;
use crate::files::model::ModelError;
use crate::geometry::method::Methods;
use crate::materials::texture::Texture;
use crate::materials::texture_slot::{Encoding, TextureSlot};
use crate::math::color::ColorSpace;
use crate::render::settings::{AdaptiveSampling, RenderSettings};
use crate::render::view_transform::{Display, ViewTransform};
use crate::sampling::sampler::SamplerKind;
use crate::scene::effects::Effects;
use crate::scene::{Scene, SceneBuildError, SceneBuilder};
use camera::{CameraDesc, ExposureDesc, ImageDesc, SamplesDesc};
use effects::EffectsDesc;
use environment::EnvironmentDesc;
use light::LightDesc;
use material::MaterialDesc;
use object::{ObjectEntry, Shape};
use values::ColorDesc;

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
    /// The parts do not make a scene: an object names a material the file
    /// does not define.
    #[error("{file}: {reason}")]
    Invalid {
        /// The scene file.
        file: String,
        /// What is wrong (in the message, so not also a `source()`).
        reason: SceneBuildError,
    },
    /// A material's texture cannot be read.
    #[error("{file}: {reason}")]
    Texture {
        /// The scene file.
        file: String,
        /// The material, its field, the image and why.
        reason: String,
    },
    /// The glTF file the camera is taken from cannot be used.
    #[error("{file}: camera: {reason}")]
    Camera {
        /// The scene file.
        file: String,
        /// Why the camera failed (in the message, so not also a `source()`).
        reason: ModelError,
    },
    /// A mesh's OBJ or glTF file cannot be used.
    #[error("{file}: objects[{index}] (Mesh): {reason}")]
    Model {
        /// The scene file.
        file: String,
        /// 0-based object index.
        index: usize,
        /// Why the model failed (in the message, so not also a `source()`).
        reason: ModelError,
    },
    /// The environment cannot be made: its image cannot be read or used,
    /// or it is given together with a `background`.
    #[error("{file}: {reason}")]
    Environment {
        /// The scene file.
        file: String,
        /// What is wrong, naming the image file where there is one.
        reason: String,
    },
}

/// What a scene file holds: the world, the camera it is seen through, and
/// how to render it. Each part is validated.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadedScene {
    /// The world.
    pub scene: Scene,
    /// The file's camera.
    pub camera: Camera,
    /// The file's image size, samples per pixel, colour space and effects
    /// (seed 0, nothing toggled off).
    pub settings: RenderSettings,
}

/// Reads and validates the scene file at `path`; OBJ paths are relative to
/// its directory.
pub fn load_scene(path: &Path) -> Result<LoadedScene, SceneError> {
    let file = path.display().to_string();
    let text =
        std::fs::read_to_string(path).map_err(|reason| SceneError::Read { file: file.clone(), reason })?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    parse_scene(&text, &file, base_dir)
}

/// Parses and validates scene text. `file` names it in errors; OBJ paths are
/// relative to `base_dir`.
pub fn parse_scene(text: &str, file: &str, base_dir: &Path) -> Result<LoadedScene, SceneError> {
    let desc: SceneDesc = ron::from_str(text).map_err(|e| SceneError::Parse {
        file: file.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: e.code.to_string(),
    })?;

    let effects = Effects {
        max_depth: desc.effects.max_depth.0,
        ambient_occlusion: desc.effects.ambient_occlusion.map(|a| a.0),
        global_illumination: desc.effects.global_illumination.map(|g| g.0),
    };
    let settings = RenderSettings {
        image: desc.image.0,
        samples: desc.samples_per_pixel.0,
        sampler: desc.sampler,
        adaptive: desc.adaptive_sampling.map(|a| a.0),
        color_space: desc.color_space,
        effects,
        display: Display { exposure: desc.exposure.0, view_transform: desc.view_transform },
        ..RenderSettings::default()
    };
    let mut scene = SceneBuilder::new()
        .background(desc.background.unwrap_or_default().0)
        .ambient(desc.ambient.0)
        .methods(desc.methods);
    if let Some(environment) = &desc.environment {
        let fail = |reason: String| SceneError::Environment { file: file.to_owned(), reason };
        if desc.background.is_some() {
            return Err(fail(String::from(
                "give either background (a constant colour) or environment, not both",
            )));
        }
        let (environment, warnings) = environment.build(base_dir).map_err(fail)?;
        scene = warnings.into_iter().fold(scene.environment(environment), SceneBuilder::warning);
        // The map is a file the scene is read from, as a mesh is.
        if let Some(EnvironmentDesc::Map { file: map, .. }) = &desc.environment {
            scene = scene.source_file(base_dir.join(map));
        }
    }
    for light in desc.lights {
        scene = scene.light(light.0);
    }
    // Each image decoded once per encoding, shared by the materials.
    let mut decoded: HashMap<(PathBuf, Encoding), u32> = HashMap::new();
    for (name, MaterialDesc(mut material, uses)) in desc.materials {
        for (field, image, encoding, slot) in uses.0 {
            let path = base_dir.join(&image);
            let texture = match decoded.get(&(path.clone(), encoding)) {
                Some(&t) => t,
                None => {
                    let texture = Texture::load_as(&path, encoding).map_err(|e| SceneError::Texture {
                        file: file.to_owned(),
                        reason: format!("material \"{name}\": {}: {e}", field.name()),
                    })?;
                    let index = scene.texture_count() as u32;
                    scene = scene.texture(Arc::new(texture)).source_file(&path);
                    decoded.insert((path, encoding), index);
                    index
                }
            };
            field.set(&mut material, TextureSlot { texture, ..slot });
        }
        scene = scene.material(name, material);
    }
    // A mesh with its file's materials adds an object per material: the
    // scene's object k came from the file's `entry_of[k]`.
    let mut entry_of = Vec::new();
    let camera_file = match &desc.camera {
        CameraDesc::Gltf { file: gltf, .. } => Some(base_dir.join(gltf)),
        CameraDesc::Ready(_) => None,
    };
    for (index, entry) in desc.objects.into_iter().enumerate() {
        match entry.0 {
            Shape::Ready { primitive, material } => scene = scene.object(primitive, material),
            Shape::Mesh { file: obj, scale, translate, material, lights } => {
                let path = base_dir.join(&obj);
                let written = obj.display().to_string();
                let added;
                (scene, added) = model::add_model(
                    scene,
                    &path,
                    &written,
                    (scale, translate),
                    material,
                    lights,
                    camera_file.as_deref() == Some(path.as_path()),
                )
                .map_err(|reason| SceneError::Model {
                    file: file.to_owned(),
                    index,
                    reason,
                })?;
                entry_of.extend(std::iter::repeat_n(index, added.saturating_sub(1)));
            }
        }
        entry_of.push(index);
    }
    let camera = match desc.camera {
        CameraDesc::Ready(camera) => camera,
        CameraDesc::Gltf { file: gltf, index, scale, translate } => {
            let path = base_dir.join(&gltf);
            scene = scene.source_file(&path);
            crate::files::gltf_model::camera(&path, index, scale, translate)
                .map_err(|reason| SceneError::Camera { file: file.to_owned(), reason })?
        }
    };
    let invalid = |reason: SceneBuildError| SceneError::Invalid {
        file: file.to_owned(),
        reason: reason.with_object_index(|k| entry_of.get(k).copied().unwrap_or(k)),
    };
    let scene = scene.build().map_err(invalid)?;
    // A translucent inside is simulated only by the path tracer.
    if effects.global_illumination.is_none()
        && let Some(index) =
            scene.objects().iter().position(|o| scene.material(o.material).subsurface.is_some())
    {
        let o = &scene.objects()[index];
        return Err(invalid(SceneBuildError::Subsurface {
            index,
            kind: o.primitive.kind(),
            material: scene.material_names()[o.material].clone(),
            reason: String::from(
                "which needs global illumination: add effects: (global_illumination: ()) to the scene",
            ),
        }));
    }
    Ok(LoadedScene { scene, camera, settings })
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, rename = "Scene")]
struct SceneDesc {
    camera: CameraDesc,
    image: ImageDesc,
    #[serde(default, deserialize_with = "environment::present")]
    background: Option<ColorDesc>,
    #[serde(default, deserialize_with = "environment::present")]
    environment: Option<EnvironmentDesc>,
    #[serde(default)]
    samples_per_pixel: SamplesDesc,
    #[serde(default)]
    sampler: SamplerKind,
    #[serde(default, deserialize_with = "environment::present")]
    adaptive_sampling: Option<AdaptiveDesc>,
    #[serde(default)]
    color_space: ColorSpace,
    #[serde(default)]
    exposure: ExposureDesc,
    #[serde(default)]
    view_transform: ViewTransform,
    #[serde(deserialize_with = "unique_materials")]
    materials: BTreeMap<String, MaterialDesc>,
    objects: Vec<ObjectEntry>,
    #[serde(default)]
    lights: Vec<LightDesc>,
    #[serde(default)]
    ambient: ColorDesc,
    #[serde(default)]
    effects: EffectsDesc,
    #[serde(default)]
    methods: Methods,
}

/// `adaptive_sampling: (noise_threshold: T, min_samples: N)`, `min_samples`
/// defaulting to [`AdaptiveSampling::DEFAULT_MIN_SAMPLES`], each checked by
/// [`AdaptiveSampling::new`].
#[derive(Deserialize)]
#[serde(try_from = "AdaptiveFields")]
struct AdaptiveDesc(AdaptiveSampling);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AdaptiveFields {
    noise_threshold: values::Finite,
    #[serde(default, deserialize_with = "environment::present")]
    min_samples: Option<u32>,
}

impl TryFrom<AdaptiveFields> for AdaptiveDesc {
    type Error = crate::render::settings::SettingsError;
    fn try_from(f: AdaptiveFields) -> Result<Self, Self::Error> {
        let min = f.min_samples.unwrap_or(AdaptiveSampling::DEFAULT_MIN_SAMPLES);
        AdaptiveSampling::new(crate::math::real::to_f32(f.noise_threshold.0), min).map(Self)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Projection;
    use crate::geometry::method::{BoxMethod, SphereMethod, TriangleMethod};
    use crate::geometry::primitive::Primitive;
    use crate::lights::light::{Light, LightKind};
    use crate::materials::material::Material;
    use crate::math::color::Color;
    use crate::math::real::Vec3;
    use crate::scene::effects::{AmbientOcclusion, GlobalIllumination};

    const GOOD: &str = r#"Scene(
    camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
    image: (width: 32, height: 24),
    materials: { "red": (color: (1, 0, 0)), "grey": (color: (0.5, 0.5, 0.5)) },
    objects: [
        Sphere(center: (0, 0, 0), radius: 1, material: "red"),
        Plane(normal: (0, 1, 0), d: -1, material: "grey"),
    ],
)"#;

    fn parse(text: &str) -> Result<LoadedScene, SceneError> {
        parse_scene(text, "bad.ron", Path::new("."))
    }

    /// The error for `GOOD` with `from` replaced by `to`, as text.
    fn error_after(from: &str, to: &str) -> String {
        assert!(GOOD.contains(from), "{from}");
        parse(&GOOD.replacen(from, to, 1)).unwrap_err().to_string()
    }

    #[test]
    fn a_good_scene_loads_with_defaults_filled_in() {
        let loaded = parse(GOOD).unwrap();
        let s = &loaded.scene;
        let image = loaded.settings.image;
        assert_eq!((image.width(), image.height(), loaded.settings.samples.get()), (32, 24, 1));
        assert_eq!(*s.environment(), crate::lights::environment::Environment::Constant(Color::ZERO));
        assert_eq!(s.material_names(), ["grey", "red"]);
        assert_eq!(s.objects().len(), 2);
        assert_eq!(s.objects()[0].material, 1);
        assert_eq!(loaded.camera.projection(), Projection::Perspective);
    }

    #[test]
    fn intersection_methods_default_to_the_careful_ones_and_can_be_chosen() {
        assert!(parse(GOOD).unwrap().scene.methods().is_default());
        let chosen = GOOD.replace("image:", "methods: (triangle: AreaRatio, box: SixPlane),\n    image:");
        let methods = parse(&chosen).unwrap().scene.methods();
        assert_eq!(
            methods,
            Methods {
                triangle: TriangleMethod::AreaRatio,
                sphere: SphereMethod::Careful,
                aabb: BoxMethod::SixPlane
            }
        );
        let e = error_after("image:", "methods: (sphere: Exact),\n    image:");
        assert!(e.starts_with("bad.ron:3:") && e.contains("Unexpected variant named `Exact`"), "{e}");
    }

    #[test]
    fn the_sampler_defaults_to_stratified_and_can_be_chosen() {
        assert_eq!(parse(GOOD).unwrap().settings.sampler, SamplerKind::Stratified);
        let sobol = GOOD.replace("image:", "sampler: Sobol,\n    image:");
        assert_eq!(parse(&sobol).unwrap().settings.sampler, SamplerKind::Sobol);
        let e = error_after("image:", "sampler: Halton,\n    image:");
        assert!(e.starts_with("bad.ron:3:") && e.contains("Unexpected variant named `Halton`"), "{e}");
        // Adaptive sampling: off unless asked for; a threshold, and a minimum or the default one.
        assert_eq!(parse(GOOD).unwrap().settings.adaptive, None);
        let on = GOOD.replace("image:", "adaptive_sampling: (noise_threshold: 0.02),\n    image:");
        let a = parse(&on).unwrap().settings.adaptive.unwrap();
        assert_eq!((a.threshold(), a.min_samples()), (0.02, AdaptiveSampling::DEFAULT_MIN_SAMPLES));
        let on =
            GOOD.replace("image:", "adaptive_sampling: (noise_threshold: 0.1, min_samples: 4),\n    image:");
        assert_eq!(parse(&on).unwrap().settings.adaptive, Some(AdaptiveSampling::new(0.1, 4).unwrap()));
        let e = error_after("image:", "adaptive_sampling: (noise_threshold: -1),\n    image:");
        assert!(
            e.starts_with("bad.ron:3:") && e.contains("noise threshold must be a finite number above 0"),
            "{e}"
        );
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
    fn camera_errors_point_at_the_field_not_the_end_of_the_camera() {
        // One field a line: the error's line is the field's.
        let text = |fields: [&str; 5]| {
            format!(
                "(\n camera: (\n  position: {},\n  center_of_interest: {},\n  up: {},\n  fov_y: {},\n  near: {},\n ),\n \
                 image: (width: 4, height: 4), materials: {{}}, objects: [],\n)",
                fields[0], fields[1], fields[2], fields[3], fields[4]
            )
        };
        let good = ["(0, 0, -5)", "(0, 0, 0)", "(0, 1, 0)", "40", "1"];
        let line_of = |field: usize, value: &str| {
            let mut f = good;
            f[field] = value;
            let e = parse(&text(f)).unwrap_err().to_string();
            let line: usize = e.split(':').nth(1).unwrap().parse().unwrap();
            (line, e)
        };
        // Lines: 3 position, 4 centre of interest, 5 up, 6 fov_y, 7 near.
        let (line, e) = line_of(3, "190");
        assert_eq!(line, 6, "{e}");
        assert!(e.contains("camera.fov_y must be strictly between 0 and 180"), "{e}");
        let (line, e) = line_of(4, "-2");
        assert_eq!(line, 7, "{e}");
        let (line, e) = line_of(2, "(0, 0, 3)");
        assert_eq!(line, 5, "up parallel to the view: at up, the last of the three read: {e}");
        let (line, e) = line_of(1, "(0, 0, -5)");
        assert_eq!(line, 5, "C = COI is found when up completes the three: {e}");
        assert!(e.contains("coincides with camera.position"), "{e}");
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
        assert!(e.contains("samples per pixel must be 1 to"), "{e}");
    }

    #[test]
    fn a_flat_scene_has_no_lights_and_plain_materials() {
        let loaded = parse(GOOD).unwrap();
        let s = &loaded.scene;
        assert!(s.lights().is_empty() && s.ambient() == Color::ZERO);
        assert_eq!(loaded.settings.effects, Effects { max_depth: 5, ..Effects::default() });
        assert_eq!(s.materials()[1], Material::flat(Color::new(1.0, 0.0, 0.0)));
        assert_eq!(loaded.settings.color_space, ColorSpace::Linear);
    }

    #[test]
    fn lights_materials_and_effects_are_read_with_their_defaults() {
        let text = GOOD
            .replace(
                "\"grey\": (color: (0.5, 0.5, 0.5))",
                "\"grey\": (color: (0.5, 0.5, 0.5), specular: 0.4, shininess: 64, transparency: 0.5, ior: 1.33)",
            )
            .replace(
                "objects: [",
                "color_space: Srgb, ambient: (0.1, 0.1, 0.1),
                lights: [
                    Point(position: (0, 5, 0)),
                    Directional(direction: (0, -2, 0), color: (1, 0.5, 0), intensity: 2, shadows: false),
                    Sphere(center: (1, 2, 3), radius: 0.5, samples: 9),
                    Spot(position: (0, 3, 0), direction: (0, -3, 0), outer_angle: 60),
                ],
                effects: (max_depth: 3, ambient_occlusion: (samples: 8, radius: 2)),
                objects: [",
            );
        let loaded = parse(&text).unwrap();
        let s = &loaded.scene;
        assert_eq!(loaded.settings.color_space, ColorSpace::Srgb);
        let grey = s.materials()[0];
        assert_eq!((grey.specular, grey.shininess, grey.transparency, grey.ior), (0.4, 64.0, 0.5, 1.33));
        assert_eq!((grey.diffuse, grey.reflectivity, grey.emission), (1.0, 0.0, Color::ZERO));
        assert_eq!(s.ambient(), Color::splat(0.1));
        let lights = s.lights();
        assert_eq!(
            lights[0],
            Light {
                kind: LightKind::Point { position: Vec3::new(0.0, 5.0, 0.0) },
                power: Color::ONE,
                shadows: true
            }
        );
        assert_eq!(lights[1].kind, LightKind::Directional { direction: -Vec3::Y });
        assert_eq!((lights[1].power, lights[1].shadows), (Color::new(2.0, 1.0, 0.0), false));
        assert_eq!(lights[2].sample_count(), 9);
        let LightKind::Spot { direction, cos_inner, cos_outer, .. } = lights[3].kind else {
            panic!("{lights:?}")
        };
        assert_eq!((direction, cos_inner), (-Vec3::Y, 1.0));
        assert!((cos_outer - 0.5).abs() < 1e-6, "{cos_outer}");
        let effects = loaded.settings.effects;
        assert_eq!(effects.max_depth, 3);
        assert_eq!(effects.ambient_occlusion, Some(AmbientOcclusion { samples: 8, radius: 2.0 }));
    }

    #[test]
    fn bad_materials_lights_and_effects_are_refused_where_they_stand() {
        let grey = "\"grey\": (color: (0.5, 0.5, 0.5))";
        let material =
            |fields: &str| error_after(grey, &format!("\"grey\": (color: (0.5, 0.5, 0.5), {fields})"));
        let e = material("reflectivity: 0.7, transparency: 0.6");
        assert!(
            e.starts_with("bad.ron:4:") && e.contains("reflectivity + transparency must not exceed 1"),
            "{e}"
        );
        assert!(material("ior: 0").contains("material ior must be above 0"));
        assert!(material("shininess: -1").contains("material shininess must be 0 to 10000, got -1"));
        // Energy conservation: every weight and colour component at most 1.
        assert!(material("diffuse: 1.5").contains("material diffuse must be 0 to 1, got 1.5"));
        assert!(material("specular: 2").contains("material specular must be 0 to 1, got 2"));
        let e = error_after(grey, "\"grey\": (color: (0.5, 1.2, 0.5))");
        assert!(e.starts_with("bad.ron:4:") && e.contains("material color is a reflectance"), "{e}");
        assert!(material("emission: (1, -1, 0)").contains("colour components must not be negative"));
        assert!(material("glow: 1").contains("Unexpected field named `glow`"));
        let lights = |l: &str| error_after("objects: [", &format!("lights: [{l}], objects: ["));
        let e = lights("Point(position: (0, 1, 0), intensity: -2)");
        assert!(
            e.starts_with("bad.ron:5:") && e.ends_with("light intensity must not be negative, got -2"),
            "{e}"
        );
        assert!(lights("Directional(direction: (0, 0, 0))").contains("direction must not be zero"));
        assert!(
            lights("Sphere(center: (0, 0, 0), radius: 0)").contains("sphere light radius must be positive")
        );
        assert!(
            lights("Sphere(center: (0, 0, 0), radius: 1, samples: 0)").contains("samples must be 1 to 4096")
        );
        assert!(lights("Cone(position: (0, 0, 0))").contains("Unexpected variant named `Cone`"));
        let e = lights("Spot(position: (0, 0, 0), direction: (0, -1, 0), inner_angle: 50, outer_angle: 40)");
        assert!(e.contains("0 <= inner_angle < outer_angle <= 90 (degrees), got 50 and 40"), "{e}");
        assert!(
            lights("Spot(position: (0, 0, 0), direction: (0, 0, 0))").contains("direction must not be zero")
        );
        let effects = |e: &str| error_after("objects: [", &format!("effects: ({e}), objects: ["));
        let e = effects("max_depth: 100");
        assert!(
            e.starts_with("bad.ron:5:") && e.ends_with("effects.max_depth must be 0 to 64, got 100"),
            "{e}"
        );
        assert!(effects("ambient_occlusion: (samples: 4, radius: -1)").contains("radius must be positive"));
        let e = effects("global_illumination: (max_bounces: 5000)");
        assert!(
            e.starts_with("bad.ron:5:")
                && e.ends_with("global_illumination.max_bounces must be 0 to 1024, got 5000"),
            "{e}"
        );
        assert!(effects("global_illumination: (bounces: 3)").contains("Unexpected field named `bounces`"));
        assert!(
            error_after("objects: [", "color_space: Gamma, objects: [")
                .contains("Unexpected variant named `Gamma`")
        );
    }

    #[test]
    fn global_illumination_is_read_with_its_defaults() {
        let gi = |fields: &str| {
            let text = GOOD
                .replace("objects: [", &format!("effects: (global_illumination: ({fields})), objects: ["));
            parse(&text).unwrap().settings.effects.global_illumination.unwrap()
        };
        assert_eq!(
            gi(""),
            GlobalIllumination { max_bounces: 8, russian_roulette: true, max_walk_steps: 4096 }
        );
        assert_eq!(
            gi("max_bounces: 3, russian_roulette: false, max_walk_steps: 20"),
            GlobalIllumination { max_bounces: 3, russian_roulette: false, max_walk_steps: 20 }
        );
        assert_eq!(parse(GOOD).unwrap().settings.effects.global_illumination, None);
    }

    #[test]
    fn a_subsurface_material_is_read_and_bad_coefficients_are_refused_at_the_field() {
        let gi = GOOD.replace("objects: [", "effects: (global_illumination: ()), objects: [");
        let with = |fields: &str| {
            gi.replace(
                "\"red\": (color: (1, 0, 0))",
                &format!("\"red\": (color: (1, 0, 0), subsurface: ({fields}))"),
            )
        };
        let s = parse(&with("albedo: (0.9, 0.8, 0.7), mean_free_path: (0.1, 0.2, 0.3), anisotropy: 0.4"))
            .unwrap();
        let m = s.scene.materials()[s.scene.objects()[0].material].subsurface.unwrap();
        assert_eq!(m.albedo, Color::new(0.9, 0.8, 0.7));
        assert_eq!(m.mean_free_path, Color::new(0.1, 0.2, 0.3));
        assert_eq!(m.anisotropy, 0.4);
        let g0 = parse(&with("albedo: (1, 1, 1), mean_free_path: (1, 1, 1)")).unwrap();
        assert_eq!(g0.scene.materials()[g0.scene.objects()[0].material].subsurface.unwrap().anisotropy, 0.0);
        let bad = |fields: &str| parse(&with(fields)).unwrap_err().to_string();
        let e = bad("albedo: (1.2, 1, 1), mean_free_path: (1, 1, 1)");
        assert!(
            e.starts_with("bad.ron:4:")
                && e.contains("subsurface.albedo is a fraction: each component must be 0 to 1, got 1.2"),
            "{e}"
        );
        assert!(bad("albedo: (1, -0.1, 1), mean_free_path: (1, 1, 1)").contains("got -0.1"));
        assert!(
            bad("albedo: (1, 1, 1), mean_free_path: (1, 0, 1)")
                .contains("subsurface.mean_free_path is a length")
        );
        assert!(bad("albedo: (1, 1, 1), mean_free_path: (1, -2, 1)").contains("got -2"));
        assert!(bad("albedo: (1, 1, 1), mean_free_path: (1, 1, inf)").contains("expected a finite number"));
        assert!(
            bad("albedo: (1, 1, 1), mean_free_path: (1, 1, 1), anisotropy: 1")
                .contains("subsurface.anisotropy must be between −1 and 1")
        );
        assert!(bad("albedo: (1, 1, 1), mean_free_path: (1, 1, 1), anisotropy: -1.5").contains("got -1.5"));
        assert!(bad("albedo: (1, 1, 1)").contains("mean_free_path"));
        assert!(
            bad("albedo: (1, 1, 1), mean_free_path: (1, 1, 1), sigma: 2")
                .contains("Unexpected field named `sigma`")
        );
    }

    #[test]
    fn only_closed_objects_may_be_translucent_and_only_under_global_illumination() {
        let gi = GOOD.replace("objects: [", "effects: (global_illumination: ()), objects: [");
        let translucent = |text: &str, name: &str| {
            text.replace(
                &format!("\"{name}\": (color: "),
                &format!("\"{name}\": (subsurface: (albedo: (1, 1, 1), mean_free_path: (1, 1, 1)), color: "),
            )
        };
        // A sphere is fine; a plane has no inside.
        assert!(parse(&translucent(&gi, "red")).is_ok());
        let e = parse(&translucent(&gi, "grey")).unwrap_err().to_string();
        assert_eq!(
            e,
            "bad.ron: objects[1] (Plane): material \"grey\" has a subsurface medium, but a Plane has no inside \
             (only spheres, boxes and closed meshes do)"
        );
        // Without global illumination there is nothing to walk with.
        let e = parse(&translucent(GOOD, "red")).unwrap_err().to_string();
        assert!(e.contains("objects[0] (Sphere): material \"red\" has a subsurface medium, which needs global illumination"), "{e}");
        // An open mesh names its hole.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("open.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\n",
        )
        .unwrap();
        let mesh = translucent(&gi, "red").replace(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")",
            "Mesh(file: \"open.obj\", material: \"red\")",
        );
        let e = parse_scene(&mesh, "bad.ron", dir.path()).unwrap_err().to_string();
        assert!(e.contains("objects[0] (Mesh): material \"red\" has a subsurface medium, but the mesh is not closed: the edge from"), "{e}");
        assert!(e.contains("belongs to one face only (a hole)"), "{e}");
        // Closing it makes it fine.
        std::fs::write(
            dir.path().join("open.obj"),
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
        )
        .unwrap();
        assert!(parse_scene(&mesh, "bad.ron", dir.path()).is_ok());
    }

    #[test]
    fn a_glowing_polygon_whose_edges_cross_is_refused_naming_it() {
        let star = "Polygon(points: [(0, 1, 0), (0.59, -0.81, 0), (-0.95, 0.31, 0), (0.95, 0.31, 0), (-0.59, -0.81, 0)], material: \"lamp\")";
        let text = GOOD
            .replace(
                "\"grey\": (color: (0.5, 0.5, 0.5))",
                "\"grey\": (color: (0.5, 0.5, 0.5)), \"lamp\": (color: (1, 1, 1), emission: (2, 2, 2))",
            )
            .replace("Sphere(center: (0, 0, 0), radius: 1, material: \"red\")", star);
        let e = parse(&text).unwrap_err().to_string();
        assert_eq!(
            e,
            "bad.ron: objects[0] (Polygon): an emissive polygon must be simple (its edges must not cross)"
        );
        // The same star that does not glow is fine (the even–odd rule fills it).
        assert!(parse(&text.replace("emission: (2, 2, 2)", "")).is_ok());
    }

    #[test]
    fn a_missing_obj_file_names_the_object_and_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let text = GOOD.replace(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")",
            "Mesh(file: \"meshes/nope.obj\", material: \"red\")",
        );
        let e = parse_scene(&text, "bad.ron", dir.path()).unwrap_err().to_string();
        assert!(e.starts_with("bad.ron: objects[0] (Mesh): cannot open OBJ file"), "{e}");
        assert!(e.contains("meshes/nope.obj: No such file or directory"), "{e}");
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
        assert!(matches!(&scene.scene.objects()[0].primitive, Primitive::Mesh(m) if m.triangle_count() == 1));
    }

    #[test]
    fn an_unreadable_scene_file_is_an_error_naming_it() {
        let e = load_scene(Path::new("/nonexistent/scene.ron")).unwrap_err().to_string();
        assert!(e.starts_with("/nonexistent/scene.ron: cannot read scene file"), "{e}");
    }

    #[test]
    fn a_mesh_without_a_material_brings_its_files_materials_as_one_object_each() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("m")).unwrap();
        std::fs::write(
            dir.path().join("m/two.obj"),
            "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 2 4 3\n",
        )
        .unwrap();
        std::fs::write(dir.path().join("m/two.mtl"), "newmtl a\nKd 1 0 0\nKa 1 1 1\nnewmtl b\nKd 0 0 1\n")
            .unwrap();
        let text = GOOD.replace(
            "Sphere(center: (0, 0, 0), radius: 1, material: \"red\")",
            "Mesh(file: \"m/two.obj\"), Mesh(file: \"m/two.obj\", material: \"red\")",
        );
        let path = dir.path().join("scene.ron");
        std::fs::write(&path, &text).unwrap();
        let scene = load_scene(&path).unwrap().scene;
        // Two parts, then the overridden mesh as one object, then the plane.
        let names: Vec<&str> =
            scene.objects().iter().map(|o| scene.material_names()[o.material].as_str()).collect();
        assert_eq!(names, ["m/two.obj:a", "m/two.obj:b", "red", "grey"]);
        assert_eq!(scene.material(scene.objects()[1].material).color, Color::new(0.0, 0.0, 1.0));
        assert_eq!(scene.warnings(), ["m/two.obj: material \"a\": not used: Ka"]);
        // The OBJ and its MTL file are watched by the viewer.
        assert!(scene.source_files().iter().any(|f| f.ends_with("m/two.obj")));
        assert!(scene.source_files().iter().any(|f| f.ends_with("m/two.mtl")));

        // An error about a later object names its place in the file, not
        // in the scene's longer list of objects.
        let bad = text.replace(
            "Mesh(file: \"m/two.obj\", material: \"red\")",
            "Mesh(file: \"m/two.obj\", material: \"nope\")",
        );
        std::fs::write(&path, bad).unwrap();
        let e = load_scene(&path).unwrap_err().to_string();
        assert!(e.contains("objects[1] (Mesh): unknown material \"nope\""), "{e}");

        // A bad value in the MTL file names the object, the file, the material and the field.
        std::fs::write(dir.path().join("m/two.mtl"), "newmtl a\nNi 0\nnewmtl b\n").unwrap();
        std::fs::write(&path, &text).unwrap();
        let e = load_scene(&path).unwrap_err().to_string();
        assert!(
            e.contains("objects[0] (Mesh): OBJ file ") && e.contains("two.obj: material \"a\": Ni"),
            "{e}"
        );
    }
}
