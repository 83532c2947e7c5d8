//! `rt-view export SCENE -o OUT.json`: the scene as rt-view reads it, every
//! default filled in, as JSON for outside tools (the Mitsuba 3 comparison
//! script, `bench/mitsuba_compare.py`).
//!
//! Spheres and planes are written as such. Boxes, triangles, polygons and
//! meshes are written as triangle lists in world space, each in an OBJ file
//! beside the JSON (`OUT.object-N.obj`), wound so that `(b − a) × (c − a)`
//! is the normal rt-view uses: outward for boxes, the winding normal for
//! polygons and triangles. Positions are in rt-view's left-handed world
//! (`docs/conventions.md`); converting to a right-handed renderer is the
//! reader's job. Materials and lights are in the units of `docs/effects.md`.
//! What the export leaves out is said in the JSON: `textured` on a material
//! with a texture (its `color` is the untextured factor) and `smooth` on a
//! mesh with vertex normals (written with its flat faces). An environment
//! map, or a sky baked into one, is written as a Radiance `.hdr` beside the
//! JSON (`OUT.environment.hdr`) with its strength, rotation and sun; the
//! camera's thin lens as its `aperture` (radius) and `focus_distance`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::Args;
use rt_core::files::environment_image::encode_hdr;
use rt_core::lights::emitter::Emitter;
use rt_core::lights::environment::Environment;
use rt_core::lights::environment_map::EnvironmentMap;
use rt_core::lights::light::LightKind;
use rt_core::math::real::to_f64;
use rt_core::{Color, Primitive, Vec3};
use serde::Serialize;

use crate::image_out::PendingFile;

/// `rt-view export`.
#[derive(Debug, Args)]
pub struct ExportArgs {
    /// The scene file (RON).
    pub scene: PathBuf,
    /// Output file (.json); OBJ files for triangle objects go beside it.
    #[arg(short, long, value_name = "OUT.json")]
    pub output: PathBuf,
}

#[derive(Serialize)]
struct SceneJson {
    camera: CameraJson,
    width: u32,
    height: u32,
    samples_per_pixel: u32,
    /// The constant environment; black when there is a map.
    background: [f32; 3],
    /// An environment map (or a baked sky) with its sun, if there is one.
    #[serde(skip_serializing_if = "Option::is_none")]
    environment: Option<EnvironmentJson>,
    color_space: &'static str,
    ambient: [f32; 3],
    max_depth: u32,
    global_illumination: Option<GiJson>,
    materials: Vec<MaterialJson>,
    objects: Vec<ObjectJson>,
    lights: Vec<LightJson>,
}

#[derive(Serialize)]
struct CameraJson {
    position: [f64; 3],
    center_of_interest: [f64; 3],
    up: [f64; 3],
    fov_y: f64,
    near: f64,
    projection: &'static str,
    /// Thin-lens radius, world units (0: a pinhole).
    aperture: f64,
    /// Distance along the view direction of the plane in focus (from the
    /// eye; for an orthographic camera, from the view plane).
    focus_distance: f64,
}

/// An equirectangular map in rt-view's convention (`docs/scene-format.md`:
/// u = 1/2 is +z, u = 1/4 is −x, the top row +y; Mitsuba's `envmap` after
/// the x mirror, with its rotation about +y by −`rotation_degrees`).
#[derive(Serialize)]
struct EnvironmentJson {
    /// A Radiance `.hdr` beside the JSON, texels as the scene gives them
    /// (`strength` not applied).
    file: String,
    width: usize,
    height: usize,
    strength: f32,
    rotation_degrees: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    sun: Option<SunJson>,
}

/// A disc light at infinity, in the map's world frame (not rotated with it).
#[derive(Serialize)]
struct SunJson {
    direction: [f64; 3],
    angular_radius_degrees: f64,
    /// At normal incidence; the disc's radiance is this over π sin²α.
    irradiance: [f32; 3],
}

#[derive(Serialize)]
struct GiJson {
    max_bounces: u32,
    russian_roulette: bool,
    max_walk_steps: u32,
}

#[derive(Serialize)]
struct MaterialJson {
    name: String,
    color: [f32; 3],
    diffuse: f32,
    specular: f32,
    /// Tint of the glossy and mirror lobes.
    specular_color: [f32; 3],
    shininess: f32,
    /// The GGX α the glossy lobe uses.
    roughness: f32,
    reflectivity: f32,
    transparency: f32,
    ior: f32,
    emission: [f32; 3],
    /// Whether a texture multiplies `color` (the texture is not exported).
    textured: bool,
    /// The medium inside, if translucent.
    #[serde(skip_serializing_if = "Option::is_none")]
    subsurface: Option<SubsurfaceJson>,
    /// The physically based parameters, for such a material (then `color`
    /// is its base colour and the weights above are unused).
    #[serde(skip_serializing_if = "Option::is_none")]
    physical: Option<PhysicalJson>,
}

#[derive(Serialize)]
struct PhysicalJson {
    metallic: f32,
    roughness: f32,
    transmission: f32,
    attenuation_color: [f32; 3],
    /// `None` (null) for a clear inside.
    attenuation_distance: Option<f32>,
    clearcoat: f32,
    clearcoat_roughness: f32,
    specular: f32,
    specular_color: [f32; 3],
}

#[derive(Serialize)]
struct SubsurfaceJson {
    albedo: [f32; 3],
    /// Per channel, scene units; σt = 1/mean_free_path.
    mean_free_path: [f32; 3],
    anisotropy: f32,
}

#[derive(Serialize)]
#[serde(tag = "kind")]
enum ObjectJson {
    Sphere {
        center: [f64; 3],
        radius: f64,
        material: String,
    },
    Plane {
        normal: [f64; 3],
        d: f64,
        material: String,
    },
    Triangles {
        file: String,
        triangles: usize,
        material: String,
        /// A mesh with vertex normals, written with its flat faces.
        smooth: bool,
    },
}

#[derive(Serialize)]
#[serde(tag = "kind")]
enum LightJson {
    /// Intensity `power` (W/sr) from a point.
    Point { position: [f64; 3], power: [f32; 3], shadows: bool },
    /// Axial intensity `power` (W/sr) from a point, into the cone about
    /// `direction`: full out to the angle whose cosine is `cos_inner`, falling
    /// as the square of a ramp in cos θ to nothing at `cos_outer`.
    Spot {
        position: [f64; 3],
        direction: [f64; 3],
        cos_inner: f64,
        cos_outer: f64,
        power: [f32; 3],
        shadows: bool,
    },
    /// Irradiance `power` (W/m²) travelling along `direction`.
    Directional { direction: [f64; 3], power: [f32; 3], shadows: bool },
    /// A sphere of radiance `power/(π·radius²)`.
    Sphere { center: [f64; 3], radius: f64, power: [f32; 3], shadows: bool },
}

fn v3(v: Vec3) -> [f64; 3] {
    let d = rt_core::math::real::widen(v);
    [d.x, d.y, d.z]
}

fn c3(c: Color) -> [f32; 3] {
    c.to_array()
}

/// Writes the scene's JSON and its OBJ files.
pub fn run(args: &ExportArgs) -> anyhow::Result<()> {
    let loaded = crate::scene_cache::load_scene(&args.scene)?;
    let (scene, settings) = (&loaded.scene, &loaded.settings);
    let json = PendingFile::create(&args.output)?;
    let stem = args.output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let dir = args.output.parent().unwrap_or(Path::new("."));
    let names = scene.material_names();
    let mut objects = Vec::new();
    for (i, object) in scene.objects().iter().enumerate() {
        let material = names[object.material].clone();
        let json_object = match &object.primitive {
            Primitive::Sphere(s) => {
                ObjectJson::Sphere { center: v3(s.center()), radius: to_f64(s.radius()), material }
            }
            Primitive::Plane(p) => ObjectJson::Plane { normal: v3(p.normal()), d: to_f64(p.d()), material },
            other => {
                let triangles = triangles_of(other)?;
                let file = format!("{stem}.object-{i}.obj");
                write_obj(&dir.join(&file), &triangles)?;
                let smooth = matches!(other, Primitive::Mesh(m) if m.has_vertex_normals());
                ObjectJson::Triangles { file, triangles: triangles.len(), material, smooth }
            }
        };
        objects.push(json_object);
    }
    let materials = scene
        .materials()
        .iter()
        .zip(names)
        .map(|(m, name)| MaterialJson {
            name: name.clone(),
            color: c3(m.color),
            diffuse: m.diffuse,
            specular: m.specular,
            specular_color: c3(m.specular_color),
            shininess: m.shininess,
            roughness: m.roughness(),
            reflectivity: m.reflectivity,
            transparency: m.transparency,
            ior: m.ior,
            emission: c3(m.emission),
            textured: m.base_color_texture.is_some(),
            subsurface: m.subsurface.map(|s| SubsurfaceJson {
                albedo: c3(s.albedo),
                mean_free_path: c3(s.mean_free_path),
                anisotropy: s.anisotropy,
            }),
            physical: m.physical.map(|p| PhysicalJson {
                metallic: p.metallic,
                roughness: p.roughness,
                transmission: p.transmission,
                attenuation_color: c3(p.attenuation_color),
                attenuation_distance: p.attenuation_distance.is_finite().then_some(p.attenuation_distance),
                clearcoat: p.clearcoat,
                clearcoat_roughness: p.clearcoat_roughness,
                specular: p.specular,
                specular_color: c3(p.specular_color),
            }),
        })
        .collect();
    let lights = scene
        .lights()
        .iter()
        .map(|l| {
            let (power, shadows) = (c3(l.power), l.shadows);
            match l.kind {
                LightKind::Point { position } => LightJson::Point { position: v3(position), power, shadows },
                LightKind::Spot { position, direction, cos_inner, cos_outer } => LightJson::Spot {
                    position: v3(position),
                    direction: v3(direction),
                    cos_inner: to_f64(cos_inner),
                    cos_outer: to_f64(cos_outer),
                    power,
                    shadows,
                },
                LightKind::Directional { direction } => {
                    LightJson::Directional { direction: v3(direction), power, shadows }
                }
                LightKind::Sphere { center, radius, .. } => {
                    LightJson::Sphere { center: v3(center), radius: to_f64(radius), power, shadows }
                }
            }
        })
        .collect();
    let environment = match scene.environment() {
        Environment::Constant(_) => None,
        Environment::Map(map) => Some(export_map(map, &dir.join(format!("{stem}.environment.hdr")), &stem)?),
    };
    let c = &loaded.camera;
    let out = SceneJson {
        camera: CameraJson {
            position: v3(c.position()),
            center_of_interest: v3(c.center_of_interest()),
            up: v3(c.up()),
            fov_y: c.fov_y() as f64,
            near: c.near() as f64,
            projection: match c.projection() {
                rt_core::Projection::Perspective => "Perspective",
                rt_core::Projection::Orthographic => "Orthographic",
            },
            aperture: to_f64(c.lens().radius),
            focus_distance: to_f64(c.lens().focus_distance),
        },
        width: settings.image.width(),
        height: settings.image.height(),
        samples_per_pixel: settings.samples.get(),
        background: c3(match scene.environment() {
            Environment::Constant(c) => *c,
            Environment::Map(_) => Color::ZERO,
        }),
        environment,
        color_space: match settings.color_space {
            rt_core::math::color::ColorSpace::Linear => "Linear",
            rt_core::math::color::ColorSpace::Srgb => "Srgb",
        },
        ambient: c3(scene.ambient()),
        max_depth: settings.effects.max_depth,
        global_illumination: settings.effects.global_illumination.map(|g| GiJson {
            max_bounces: g.max_bounces,
            russian_roulette: g.russian_roulette,
            max_walk_steps: g.max_walk_steps,
        }),
        materials,
        objects,
        lights,
    };
    let text = serde_json::to_string_pretty(&out)?;
    json.write_bytes(text.as_bytes())?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

/// Writes `map`'s image (its texels over its strength) to `path` and says
/// what the JSON holds about it; `stem` names the file beside the JSON.
fn export_map(map: &EnvironmentMap, path: &Path, stem: &str) -> anyhow::Result<EnvironmentJson> {
    let (width, height) = map.size();
    let unscale = if map.strength() > 0.0 { 1.0 / map.strength() } else { 0.0 };
    let texels: Vec<Color> = map.texels().iter().map(|t| *t * unscale).collect();
    let mut bytes = Vec::new();
    encode_hdr(&mut bytes, width, height, &texels).context("cannot encode the environment map")?;
    PendingFile::create(path)?.write_bytes(&bytes)?;
    Ok(EnvironmentJson {
        file: format!("{stem}.environment.hdr"),
        width,
        height,
        strength: map.strength(),
        rotation_degrees: to_f64(map.rotation_degrees()),
        sun: map.sun().map(|s| SunJson {
            direction: v3(s.direction()),
            angular_radius_degrees: to_f64(s.radius_degrees()),
            irradiance: c3(s.irradiance()),
        }),
    })
}

/// The triangles of a bounded, flat-faced primitive, wound like its normals.
fn triangles_of(p: &Primitive) -> anyhow::Result<Vec<[Vec3; 3]>> {
    // The emitter's triangulation is exactly what rt-view samples lights on.
    let emitter = Emitter::new(0, p, Color::ONE).context("cannot cut the object into triangles")?;
    Ok(emitter.triangles().to_vec())
}

/// Writes triangles as an OBJ file (three vertices each, faces in order).
fn write_obj(path: &Path, triangles: &[[Vec3; 3]]) -> anyhow::Result<()> {
    let mut text = String::new();
    for t in triangles {
        for p in t {
            let p = v3(*p);
            writeln!(text, "v {} {} {}", p[0], p[1], p[2])?;
        }
    }
    for i in 0..triangles.len() {
        writeln!(text, "f {} {} {}", 3 * i + 1, 3 * i + 2, 3 * i + 3)?;
    }
    PendingFile::create(path)?.write_bytes(text.as_bytes())
}
