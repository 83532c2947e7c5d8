//! glTF 2.0 files (`.gltf` with its buffers and images, or `.glb`) as a
//! [`Model`], read with the `gltf` crate.
//!
//! **What is read.** Every mesh primitive of the file's default scene (or
//! its first scene), placed by its node's transform composed with its
//! parents' (glTF 2.0 §3.5.3): positions, normals (as shading normals),
//! tangents (for normal maps; generated with MikkTSpace where absent,
//! [`Mesh::with_generated_tangents`]), `TEXCOORD_0`, indices. Triangle lists, strips and fans are read; points
//! and lines are an error. Attributes may be quantized
//! (`KHR_mesh_quantization`: 8- and 16-bit integers, normalized or not,
//! `read_vectors`) and compressed (`EXT_meshopt_compression`,
//! [`meshopt_views`]). Draco-compressed meshes
//! (`KHR_draco_mesh_compression`) are refused with a way out when required,
//! read from their uncompressed data when not.
//!
//! **Lights and cameras.** `KHR_lights_punctual` lights are placed by their
//! nodes ([`load_with_lights`]; candela and lux over [`LUMENS_PER_WATT`]);
//! a camera of the file is placed by its node on request ([`camera`]).
//! Animations, skins, morph targets, other vertex attributes, and cameras
//! and lights not asked for are warnings naming them.
//!
//! **Coordinates.** glTF's world is right-handed with +Y up and a model's
//! front facing +Z; rt-view's is left-handed ([`crate::camera`]). Every
//! point is mirrored in z, `(x, y, z) → (x, y, −z)`, so the model stands
//! the same way up, seen from the front by a camera at negative z looking
//! at the origin (as the scenes' cameras are), and nothing is mirror-
//! imaged. A mirror turns a triangle's winding round, so the corners are
//! stored in reverse wherever the transform (mirror included) has a
//! negative determinant, and `(b−a)×(c−a)` keeps pointing out of the model.
//! Normals go through the inverse transpose of the transform, tangents
//! through the transform itself with their handedness `w` negated where
//! its determinant is negative (glTF's bitangent `w·(N × T)`, mirrored, is
//! `−w·(N' × T')`). The scene's
//! `scale` and `translate` apply last. Texture coordinates keep glTF's
//! convention, `v` down the image, which is [`crate::materials::texture`]'s.
//!
//! **Materials** (metallic-roughness, glTF 2.0 §3.9) become physically
//! based materials ([`crate::materials::principled`], the BSDF glTF's
//! Appendix B defines), factor for factor:
//!
//! | glTF | rt-view |
//! |---|---|
//! | `baseColorFactor` (RGB) | `color` (the base colour) |
//! | `baseColorTexture` | `texture` (sRGB, bilinear, the sampler's wrap modes), multiplying `color` |
//! | `baseColorFactor[3]` × the texture's alpha, `alphaMode`, `alphaCutoff` | `alpha`, `alpha_mode` ([`crate::materials::alpha`]) |
//! | `normalTexture`, its `scale` | `normal_texture` (linear), `normal_scale` ([`crate::materials::normal_map`]) |
//! | `metallicFactor`, `roughnessFactor` | `metallic`, `roughness` (α = roughness²) |
//! | `emissiveFactor` × `KHR_materials_emissive_strength` | `emission` |
//! | `KHR_materials_transmission` | `transmission` |
//! | `KHR_materials_volume` | `attenuation_color`, `attenuation_distance` (the thickness is not needed: rays measure it) |
//! | `KHR_materials_ior` | `ior` (default 1.5) |
//! | `KHR_materials_specular` | `specular`, `specular_color` |
//! | `KHR_materials_clearcoat` | `clearcoat`, `clearcoat_roughness` |
//!
//! A factor that is not a number or out of its range is replaced by its
//! default or clamped, and named in the warnings. Not used, and named in
//! the model's warnings: the metallic-roughness,
//! occlusion and emissive textures (and the extensions' textures), a
//! base-colour or normal texture on another coordinate set than 0, a normal
//! texture on a mesh without texture coordinates, and every other extension
//! the file uses. An extension the file
//! *requires* and rt-view does not know is an error. Samplers' filters are
//! not used: textures are always filtered bilinearly.
//!
//! **Bad input.** The `gltf` crate's validation runs on every file, its
//! errors turned into a sentence naming the JSON paths (`parse`); what it
//! does not check but would unwrap is checked first (an image in a buffer
//! view without a MIME type, among others). Every accessor is checked before it is read (type, count,
//! stride, and that it lies inside its buffer view and buffer), every index
//! against the vertex count, and the node hierarchy's depth and instance
//! count are bounded, so a malformed or truncated file is an
//! error naming the mesh and primitive, never a panic. A texture that
//! cannot be read is a warning naming it and the material; the material
//! keeps its factor.
//!
//! **Textures.** A material's base-colour, metallic-roughness, emissive and
//! occlusion textures become [`TextureSlot`]s: the texture's sampler
//! (filters, wraps), its `texCoord` set (0 or 1) and `KHR_texture_transform`.
//! Each image is decoded once per [`Encoding`] its uses need (sRGB for
//! colour, linear for data) and shared by every material and sampler that
//! uses it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::texture::WrappingMode;
use glam::{DMat3, DMat4, DVec3};

use crate::camera::{Camera, Projection};
use crate::files::meshopt_views::{self, CompressedView};
use crate::files::model::{Model, ModelError};
use crate::geometry::mesh::{MAX_MESH_TRIANGLES, Mesh};
use crate::lights::light::{Light, LightKind};
use crate::materials::alpha::{AlphaMode, DEFAULT_ALPHA_CUTOFF};
use crate::materials::material::Material;
use crate::materials::principled::Principled;
use crate::materials::texture::{MAX_TEXTURE_SIDE, Texture};
use crate::materials::texture_slot::{Encoding, Sampler, TextureSlot, UvTransform, Wrap};
use crate::math::color::Color;
use crate::math::real::{Real, Vec3, narrow, to_f64};

/// Largest glTF file read, checked before reading: 2 GiB, as for OBJ files.
pub const MAX_GLTF_BYTES: u64 = 1 << 31;
/// Deepest node hierarchy followed (deeper is most likely a cycle).
pub const MAX_NODE_DEPTH: usize = 64;
/// Most node instances placed: a hierarchy that reuses nodes can place a
/// mesh exponentially often in its depth.
pub const MAX_NODE_INSTANCES: usize = 1 << 20;

/// The extensions whose data is used.
const KNOWN_EXTENSIONS: [&str; 9] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_mesh_quantization",
    "KHR_lights_punctual",
    meshopt_views::EXTENSION,
    "KHR_materials_specular",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
];

/// The mesh-compression extensions rt-view does not decode: Draco, for
/// which no well-kept Rust decoder exists (`draco_decoder` 0.0.31 calls
/// itself work in progress). A file that requires it is refused with a way
/// out; one that only uses it (its uncompressed data present) is read from
/// that data.
const COMPRESSION_EXTENSIONS: [&str; 1] = ["KHR_draco_mesh_compression"];

/// Luminous efficacy of the SI definition of the candela, 683 lm/W
/// (monochromatic light of 540 THz): glTF's photometric light units
/// (candela, lux) divided by it are radiometric (W/sr, W/m²), rt-view's
/// units ([`crate::lights::light`]). Blender's glTF exporter and importer
/// use the same factor (`PBR_WATTS_TO_LUMENS`) in their standard mode.
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Reads the glTF file at `path`, then scales every vertex by `scale` and
/// moves it by `translate`.
pub fn load(path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    load_with_lights(path, scale, translate, false).map(|(model, _)| model)
}

/// [`load`], with the file's `KHR_lights_punctual` lights placed in the
/// scene `with_lights` (without, a file with lights has a warning saying
/// they are not used).
pub fn load_with_lights(
    path: &Path,
    scale: Real,
    translate: Vec3,
    with_lights: bool,
) -> Result<(Model, Vec<Light>), ModelError> {
    let bytes = read_limited(path, MAX_GLTF_BYTES)
        .map_err(|reason| ModelError::Gltf { path: path.to_owned(), reason })?;
    let (mut model, lights) = read(&bytes, path, scale, translate, true)?;
    if !with_lights && !lights.is_empty() {
        model.warnings.push(format!(
            "its {} KHR_lights_punctual light(s) are not used: add `lights: true` to its Mesh entry to use them",
            lights.len()
        ));
        return Ok((model, Vec::new()));
    }
    Ok((model, lights))
}

/// [`load`] for a file's bytes already read; `path` names it in errors, and
/// its folder is where the files it refers to are looked for.
pub fn from_slice(bytes: &[u8], path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    read(bytes, path, scale, translate, true).map(|(model, _)| model)
}

/// The glTF file at `path` as one mesh, for a scene that gives it its own
/// material: [`load`] without reading the materials or decoding textures,
/// the parts concatenated in their order; with the files it refers to
/// ([`Model::files`]) and its lights.
pub fn load_geometry(
    path: &Path,
    scale: Real,
    translate: Vec3,
) -> Result<(Mesh, Vec<PathBuf>, Vec<Light>), ModelError> {
    let err = |reason: String| ModelError::Gltf { path: path.to_owned(), reason };
    let bytes = read_limited(path, MAX_GLTF_BYTES).map_err(err)?;
    let (model, lights) = read(&bytes, path, scale, translate, false)?;
    let mesh = Mesh::concat(model.parts.into_iter().map(|(m, _)| m).collect())
        .ok_or_else(|| err("it has too many vertices".into()))?;
    Ok((mesh, model.files, lights))
}

/// Camera `index` of the glTF file at `path` (its `cameras` list), placed
/// by the first node of the file's scene that holds it, in rt-view's world
/// as [`load`] places the model with the same `scale` and `translate`.
///
/// A glTF camera looks along its node's −z with +y up (glTF 2.0 §3.10.1);
/// the mirror into rt-view's left-handed world keeps its right on the
/// image's right (docs/conventions.md: cam_x = up × cam_z). The centre of
/// interest is where the view line passes closest to the model's origin
/// (the scene's `translate`), or one unit ahead when that is behind the
/// camera; glTF gives no distance. Perspective: `fov_y` = `yfov` in
/// degrees, `near` = `znear`·scale. Orthographic: a view plane `2·ymag`·scale
/// high where glTF's starts, `znear`·scale ahead of the node: with `near`
/// = `znear`·scale and `fov_y` = 2·atan(ymag/znear) when `znear` ≥ `ymag`;
/// else (the usual case, and `znear` may be 0 where rt-view's near is
/// positive) with C stepped back along the view so that `near` =
/// `ymag`·scale and `fov_y` = 90°, the rays starting on the same plane. The
/// image's aspect is the scene's image size: `aspectRatio` and `xmag`
/// are not used, `zfar` neither (nothing is clipped far away).
pub fn camera(path: &Path, index: usize, scale: Real, translate: Vec3) -> Result<Camera, ModelError> {
    let err = |reason: String| ModelError::Gltf { path: path.to_owned(), reason };
    let bytes = read_limited(path, MAX_GLTF_BYTES).map_err(err)?;
    let (gltf, _) = parse(&bytes).map_err(err)?;
    let json = gltf.document.as_json();
    let Some(desc) = json.cameras.get(index) else {
        return Err(err(format!("it has no camera {index} (it has {})", json.cameras.len())));
    };
    let at = || format!("camera {}", describe(Some(index), desc.name.as_deref()));
    let Some(scene) = gltf.document.default_scene().or_else(|| gltf.document.scenes().next()) else {
        return Err(err("it has no scene".into()));
    };
    let mut placed = None;
    walk(&scene, to_rt_view(scale), |node, matrix| {
        if placed.is_none() && node.camera().is_some_and(|c| c.index() == index) {
            placed = Some(*matrix);
        }
        Ok(())
    })
    .map_err(err)?;
    let matrix = placed.ok_or_else(|| err(format!("{}: no node of its scene holds it", at())))?;
    let t = crate::math::real::widen(translate);
    let mut eye = matrix.transform_point3(DVec3::ZERO) + t;
    let forward = matrix.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = matrix.transform_vector3(DVec3::Y);
    let along = (t - eye).dot(forward);
    let center = eye + forward * if along > 0.0 && along.is_finite() { along } else { 1.0 };
    let s = to_f64(scale);
    use ::gltf::json::camera::Type;
    use ::gltf::json::validation::Checked;
    let (fov_y, near, projection) = match (&desc.type_, &desc.perspective, &desc.orthographic) {
        (Checked::Valid(Type::Perspective), Some(p), _) => {
            (f64::from(p.yfov).to_degrees(), f64::from(p.znear) * s, Projection::Perspective)
        }
        (Checked::Valid(Type::Orthographic), _, Some(o)) => {
            let half = f64::from(o.ymag).abs() * s;
            let start = f64::from(o.znear).max(0.0) * s;
            if start >= half {
                (2.0 * (half / start).atan().to_degrees(), start, Projection::Orthographic)
            } else {
                // Rays start on the plane at `znear` either way; the eye
                // steps back so the view is 90° wide, not nearly 180°.
                eye -= forward * (half - start);
                (90.0, half, Projection::Orthographic)
            }
        }
        (Checked::Valid(ty), _, _) => {
            return Err(err(format!("{}: its type is {ty:?} but it has no {ty:?} properties", at())));
        }
        (Checked::Invalid, _, _) => return Err(err(format!("{}: its type is unknown", at()))),
    };
    Camera::new(narrow(eye), narrow(center), narrow(up), fov_y as Real, near as Real, projection)
        .map_err(|e| err(format!("{}: {e}", at())))
}

/// [`from_slice`], reading the materials and textures only `with_materials`;
/// with the file's lights.
fn read(
    bytes: &[u8],
    path: &Path,
    scale: Real,
    translate: Vec3,
    with_materials: bool,
) -> Result<(Model, Vec<Light>), ModelError> {
    let err = |reason: String| ModelError::Gltf { path: path.to_owned(), reason };
    let (gltf, compressed) = parse(bytes).map_err(err)?;
    let mut warnings = Vec::new();
    for used in gltf.extensions_used() {
        if COMPRESSION_EXTENSIONS.contains(&used) {
            warnings.push(format!("extension {used} is not decoded: its uncompressed fallback data is read"));
        } else if !KNOWN_EXTENSIONS.contains(&used) {
            warnings.push(format!("extension {used} is not used"));
        }
    }
    let base = path.parent().unwrap_or(Path::new("."));
    let ::gltf::Gltf { document, blob } = gltf;
    // A buffer file that cannot be read is named (the crate's error does not).
    for buffer in document.buffers() {
        if let ::gltf::buffer::Source::Uri(uri) = buffer.source()
            && !uri.contains(':')
            && let Err(e) = std::fs::metadata(base.join(percent_decode(uri).unwrap_or_default()))
        {
            return Err(err(format!("buffer {} ({uri}) cannot be read: {e}", buffer.index())));
        }
    }
    let mut buffer_data = ::gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| err(format!("its buffers cannot be read: {e}")))?;
    meshopt_views::decode(&compressed, &mut buffer_data).map_err(err)?;
    let buffers: Vec<&[u8]> = buffer_data.iter().map(|b| &b.0[..]).collect();

    let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) else {
        return Err(err("it has no scene".into()));
    };
    let mut groups: Vec<Group> = Vec::new();
    let mut group_of: HashMap<Option<usize>, usize> = HashMap::new();
    let mut triangles = 0usize;
    let mut lights = Vec::new();
    let json = document.as_json();
    walk(&scene, to_rt_view(scale), |node, matrix| {
        if let Some(light) = node_light(json, node.index()) {
            lights.push(place_light(light, matrix, translate).map_err(|e| {
                format!(
                    "light {}: {e}",
                    describe(Some(node_light_index(json, node.index())), light.name.as_deref())
                )
            })?);
        }
        let Some(mesh) = node.mesh() else { return Ok(()) };
        for primitive in mesh.primitives() {
            let at = || {
                format!("mesh {} primitive {}", describe(Some(mesh.index()), mesh.name()), primitive.index())
            };
            let material = primitive.material().index();
            let g = *group_of.entry(material).or_insert_with(|| {
                groups.push(Group { material, ..Group::default() });
                groups.len() - 1
            });
            let added = read_primitive(&primitive, &buffers, matrix, translate, &mut groups[g])
                .map_err(|reason| format!("{}: {reason}", at()))?;
            triangles += added;
            if triangles > MAX_MESH_TRIANGLES {
                return Err(format!("it has more than {MAX_MESH_TRIANGLES} triangles"));
            }
        }
        Ok(())
    })
    .map_err(err)?;
    warnings.extend(unused_features(&document));
    if groups.is_empty() {
        return Err(err("its scene has no meshes".into()));
    }
    // Parts in the order of the file's materials, faces without one last.
    groups.sort_by_key(|g| g.material.map_or(usize::MAX, |m| m));

    let mut materials = Vec::new();
    let mut textures = Vec::new();
    // Each image decoded once per encoding its uses need, shared.
    let mut decoded: HashMap<(usize, Encoding), Option<u32>> = HashMap::new();
    let mut parts = Vec::new();
    for g in groups {
        let mesh = Mesh::new(g.positions, g.triangles)
            .and_then(|m| m.with_vertex_attributes(g.normals, g.uvs))
            .and_then(|m| m.with_second_uvs(g.uvs1))
            .and_then(|m| m.with_tangents(g.tangents))
            .ok_or_else(|| err("a mesh has no triangles".into()))?;
        let Some(index) = g.material.filter(|_| with_materials) else {
            parts.push((mesh, None));
            continue;
        };
        let Some(m) = document.materials().nth(index) else {
            parts.push((mesh, None));
            continue;
        };
        // Its name, unless another material has it too; else its index.
        let name = m
            .name()
            .filter(|n| document.materials().filter(|o| o.name() == Some(n)).count() == 1)
            .map_or_else(|| format!("material {index}"), str::to_owned);
        let (mut material, mut notes) = map_material(&m);
        let mut images = Images {
            document: document.as_json(),
            base,
            buffers: &buffer_data,
            textures: &mut textures,
            decoded: &mut decoded,
            warnings: &mut warnings,
            uv_sets: [mesh.has_uv_set(0), mesh.has_uv_set(1)],
            material: &name,
            notes: &mut notes,
        };
        let pbr = m.pbr_metallic_roughness();
        let transform = "KHR_texture_transform";
        material.base_color_texture = pbr.base_color_texture().and_then(|i| {
            let ext = i.extension_value(transform);
            images.slot("baseColorTexture", &i.texture(), i.tex_coord(), ext, Encoding::Srgb)
        });
        material.metallic_roughness_texture = pbr.metallic_roughness_texture().and_then(|i| {
            let ext = i.extension_value(transform);
            images.slot("metallicRoughnessTexture", &i.texture(), i.tex_coord(), ext, Encoding::Linear)
        });
        material.emissive_texture = m.emissive_texture().and_then(|i| {
            let ext = i.extension_value(transform);
            images.slot("emissiveTexture", &i.texture(), i.tex_coord(), ext, Encoding::Srgb)
        });
        material.occlusion_texture = m.occlusion_texture().and_then(|i| {
            let ext = i.extension_value(transform);
            let slot = images.slot("occlusionTexture", &i.texture(), i.tex_coord(), ext, Encoding::Linear)?;
            let strength = i.strength();
            Some(TextureSlot {
                scale: if strength.is_finite() { strength.clamp(0.0, 1.0) } else { 1.0 },
                ..slot
            })
        });
        material.normal_texture = m.normal_texture().and_then(|i| {
            let ext = i.extension_value(transform);
            let slot = images.slot("normalTexture", &i.texture(), i.tex_coord(), ext, Encoding::Linear)?;
            Some(TextureSlot { scale: map_normal_scale(i.scale(), images.notes), ..slot })
        });
        if material.occlusion_texture.is_some() {
            notes.push(
                "occlusionTexture (read, not applied: global illumination computes the occlusion it bakes)"
                    .into(),
            );
        }
        if !notes.is_empty() {
            warnings.push(format!("material \"{name}\": not used: {}", notes.join(", ")));
        }
        parts.push((mesh, Some(materials.len())));
        materials.push((name, material));
    }
    // External buffers and images, to watch.
    let base_file = |uri: Option<&str>| uri.filter(|u| !u.contains(':')).map(|u| base.join(u));
    let mut files: Vec<PathBuf> = document
        .buffers()
        .filter_map(|b| match b.source() {
            ::gltf::buffer::Source::Uri(u) => base_file(Some(u)),
            ::gltf::buffer::Source::Bin => None,
        })
        .collect();
    // From the JSON: `Image::source` unwraps what may be missing.
    files.extend(
        document
            .as_json()
            .images
            .iter()
            .filter(|i| i.buffer_view.is_none())
            .filter_map(|i| base_file(i.uri.as_deref())),
    );
    let cameras = document.cameras().len();
    Ok((Model { parts, materials, textures, warnings, files, cameras }, lights))
}

/// glTF's world → rt-view's: mirror z, then scale by `scale` (the scene's
/// `translate` is added to each point after).
fn to_rt_view(scale: Real) -> DMat4 {
    DMat4::from_scale(DVec3::splat(to_f64(scale))) * DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0))
}

/// What the file holds that nothing here reads, a sentence each (the
/// materials' own are named with each material; lights and cameras where
/// they are offered).
fn unused_features(document: &::gltf::Document) -> Vec<String> {
    let mut out = Vec::new();
    let count = |n: usize, what: &str, why: &str| (n > 0).then(|| format!("{n} {what} not used: {why}"));
    out.extend(count(
        document.animations().count(),
        "animation(s)",
        "the model is shown as its nodes place it",
    ));
    out.extend(count(document.skins().count(), "skin(s)", "skinned meshes are shown in their bind pose"));
    let json = document.as_json();
    let morphs = json
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .filter(|p| p.targets.as_ref().is_some_and(|t| !t.is_empty()))
        .count();
    out.extend(count(morphs, "primitive(s) with morph targets", "the base shape is shown"));
    let mut attributes: Vec<String> = json
        .meshes
        .iter()
        .flat_map(|m| &m.primitives)
        .flat_map(|p| p.attributes.keys())
        .filter_map(|k| match k {
            ::gltf::json::validation::Checked::Valid(semantic) => match semantic {
                ::gltf::Semantic::Positions
                | ::gltf::Semantic::Normals
                | ::gltf::Semantic::Tangents
                | ::gltf::Semantic::TexCoords(0) => None,
                other => Some(other.to_string()),
            },
            ::gltf::json::validation::Checked::Invalid => None,
        })
        .collect();
    attributes.sort();
    attributes.dedup();
    if !attributes.is_empty() {
        out.push(format!("vertex attributes not used: {}", attributes.join(", ")));
    }
    out
}

/// The `KHR_lights_punctual` light on node `node`, if it has one that exists.
fn node_light(
    json: &::gltf::json::Root,
    node: usize,
) -> Option<&::gltf::json::extensions::scene::khr_lights_punctual::Light> {
    let lights = json.extensions.as_ref()?.khr_lights_punctual.as_ref()?;
    lights.lights.get(node_light_index(json, node))
}

/// The index of node `node`'s light (past the end if it has none).
fn node_light_index(json: &::gltf::json::Root, node: usize) -> usize {
    json.nodes
        .get(node)
        .and_then(|n| n.extensions.as_ref())
        .and_then(|e| e.khr_lights_punctual.as_ref())
        .map_or(usize::MAX, |l| l.light.value())
}

/// A `KHR_lights_punctual` light placed by its node's `matrix` (glTF's
/// world to rt-view's, [`to_rt_view`], included) and moved by `translate`.
/// It shines along its node's −z. Intensity: candela (point, spot) or lux
/// (directional) over [`LUMENS_PER_WATT`], times its colour. `range` is
/// ignored: the specification lets a renderer light beyond it (its falloff
/// "should" reach zero there, but inverse-square is what is physical).
fn place_light(
    light: &::gltf::json::extensions::scene::khr_lights_punctual::Light,
    matrix: &DMat4,
    translate: Vec3,
) -> Result<Light, String> {
    use ::gltf::json::extensions::scene::khr_lights_punctual::Type;
    let color = light.color.map(|c| if c.is_finite() { c.max(0.0) } else { f32::NAN });
    let intensity = light.intensity;
    if !(intensity.is_finite() && intensity >= 0.0) || color.iter().any(|c| c.is_nan()) {
        return Err(format!(
            "its intensity {intensity} or colour {:?} is not a non-negative number",
            light.color
        ));
    }
    let power = Color::from_array(color) * (intensity / LUMENS_PER_WATT);
    let position = narrow(matrix.transform_point3(DVec3::ZERO) + crate::math::real::widen(translate));
    let direction = narrow(matrix.transform_vector3(DVec3::NEG_Z));
    let direction = crate::math::real::normalize_robust(direction);
    let kind = match light.type_ {
        ::gltf::json::validation::Checked::Valid(Type::Point) => LightKind::Point { position },
        ::gltf::json::validation::Checked::Valid(Type::Directional) => LightKind::Directional {
            direction: direction.ok_or("its node's transform has no direction (a zero scale?)")?,
        },
        ::gltf::json::validation::Checked::Valid(Type::Spot) => {
            let spot = light.spot.as_ref().ok_or("a spot light without its spot cone")?;
            let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
            if !(0.0 <= inner && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
                return Err(format!(
                    "its cone angles must satisfy 0 <= innerConeAngle < outerConeAngle <= π/2, got {inner} and {outer}"
                ));
            }
            LightKind::Spot {
                position,
                direction: direction.ok_or("its node's transform has no direction (a zero scale?)")?,
                cos_inner: Real::from(inner).cos(),
                cos_outer: Real::from(outer).cos(),
            }
        }
        ::gltf::json::validation::Checked::Invalid => {
            return Err("its type is not point, spot or directional".into());
        }
    };
    if !position.is_finite() {
        return Err("its position is not finite".into());
    }
    Ok(Light { kind, power, shadows: true })
}

/// The file's JSON parsed and validated: by the `gltf` crate's own
/// validation (every index in range, every enumeration value known, every
/// required property present), and by the checks that validation lacks
/// before something this loader calls would unwrap (gltf 1.4.1): a
/// POSITION index (validated unchecked), a relative URI that is not
/// percent-encoded UTF-8. What is wrong with an image, camera or light
/// is checked where it is read.
fn parse(bytes: &[u8]) -> Result<(::gltf::Gltf, Vec<CompressedView>), String> {
    let ::gltf::Gltf { document, blob } =
        ::gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| match e {
            ::gltf::Error::Deserialize(e) => format!("its JSON is not a glTF 2.0 document: {e}"),
            e => format!("it cannot be read as glTF ({e}): a truncated or damaged file?"),
        })?;
    let mut json = document.into_json();
    for required in &json.extensions_required {
        if COMPRESSION_EXTENSIONS.contains(&required.as_str()) {
            return Err(format!(
                "its meshes are compressed with {required}, which rt-view does not decode: \
                 write it uncompressed (Blender: glTF export, Data > Compression off; or \
                 `gltf-transform copy` / `gltfpack -noq` without compression)"
            ));
        }
        if !KNOWN_EXTENSIONS.contains(&required.as_str()) {
            return Err(format!("it requires the extension {required}, which rt-view does not support"));
        }
    }
    // gltf 1.4.1 unwraps the percent-decoding of a relative URI: refuse one
    // that does not decode to UTF-8 before it is read.
    let buffers = json.buffers.iter().enumerate().map(|(k, b)| ("buffer", k, b.uri.as_deref()));
    for (what, k, uri) in
        buffers.chain(json.images.iter().enumerate().map(|(k, i)| ("image", k, i.uri.as_deref())))
    {
        if let Some(uri) = uri
            && !uri.contains(':')
            && percent_decode(uri).is_none()
        {
            return Err(format!("{what} {k}: its URI {uri:?} is not percent-encoded UTF-8"));
        }
    }
    // Compressed buffer views read decoded data from buffers of their own.
    let compressed = meshopt_views::redirect(&mut json)?;
    // Every required extension is known here (checked above); the crate's
    // validation would refuse those it has no feature for
    // (KHR_mesh_quantization, whose data is only numbers read here).
    json.extensions_required.clear();
    // gltf-json's validation indexes the accessors with a POSITION
    // attribute's index unchecked (1.4.1, `primitive_validate_hook`): check
    // those first, then validate.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (k, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions));
            if position.is_some_and(|a| a.value() >= json.accessors.len()) {
                return Err(format!("mesh {m} primitive {k}: its POSITION accessor does not exist"));
            }
        }
    }
    let document = ::gltf::Document::from_json(json).map_err(|e| match e {
        ::gltf::Error::Validation(errors) => validation_message(&errors),
        other => other.to_string(),
    })?;
    Ok((::gltf::Gltf { document, blob }, compressed))
}

/// The validation errors as a sentence: each JSON path with what is wrong
/// there, the first few of them.
fn validation_message(errors: &[(::gltf::json::Path, ::gltf::json::validation::Error)]) -> String {
    use ::gltf::json::validation::Error;
    const SHOWN: usize = 4;
    let what = |e: &Error| match e {
        Error::IndexOutOfBounds => "an index past the end of its list",
        Error::Invalid => "an invalid value",
        Error::Missing => "a required property is missing",
        Error::Oversize => "a size beyond what can be held",
        Error::Unsupported => "an unsupported extension",
    };
    let listed: Vec<String> = errors.iter().take(SHOWN).map(|(p, e)| format!("{p}: {}", what(e))).collect();
    let more = errors.len().saturating_sub(SHOWN);
    let tail = if more > 0 { format!(" (and {more} more)") } else { String::new() };
    format!("it is not valid glTF 2.0: {}{tail}", listed.join("; "))
}

/// Visits every node instance of `scene` with its matrix, `root` times the
/// transforms from the scene's root down (glTF 2.0 §3.5.3), parents before
/// children; the depth and the instance count are bounded.
fn walk<'a>(
    scene: &::gltf::Scene<'a>,
    root: DMat4,
    mut visit: impl FnMut(&::gltf::Node<'a>, &DMat4) -> Result<(), String>,
) -> Result<(), String> {
    let mut stack: Vec<(::gltf::Node, DMat4, usize)> = scene.nodes().map(|n| (n, root, 1)).collect();
    let mut visits = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_NODE_DEPTH {
            return Err(format!("its node hierarchy is deeper than {MAX_NODE_DEPTH} levels (a cycle?)"));
        }
        // A node may be reached along many paths (a child listed twice, or
        // by several parents): each is an instance. Bound the work.
        visits += 1;
        if visits > MAX_NODE_INSTANCES {
            return Err(format!("its node hierarchy places more than {MAX_NODE_INSTANCES} node instances"));
        }
        let matrix = parent * DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        visit(&node, &matrix)?;
        stack.extend(node.children().map(|c| (c, matrix, depth + 1)));
    }
    Ok(())
}

/// The faces of one material, gathered over every primitive that uses it.
#[derive(Default)]
struct Group {
    material: Option<usize>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<[f32; 2]>,
    /// `TEXCOORD_1`, kept beside `uvs` the same way.
    uvs1: Vec<[f32; 2]>,
    /// `TANGENT`s, mirrored with the points (see [`read_primitive`]).
    tangents: Vec<[f32; 4]>,
    triangles: Vec<[u32; 3]>,
    /// Whether any primitive so far had normals / texture coordinates
    /// (sets 0 and 1) / tangents.
    has_normals: bool,
    has_uvs: bool,
    has_uvs1: bool,
    has_tangents: bool,
}

/// `uri` with its `%XX` escapes decoded, if that is UTF-8 text.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (bytes[i], bytes.get(i + 1).and_then(|&b| hex(b)), bytes.get(i + 2).and_then(|&b| hex(b))) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    String::from_utf8(out).ok()
}

/// "3 (name)" or "3".
fn describe(index: Option<usize>, name: Option<&str>) -> String {
    match (index, name) {
        (Some(i), Some(n)) => format!("{i} (\"{n}\")"),
        (Some(i), None) => i.to_string(),
        (None, Some(n)) => format!("\"{n}\""),
        (None, None) => "without index".into(),
    }
}

/// Reads the file whole, refusing one larger than `limit`; the error gives
/// the OS's reason.
fn read_limited(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let bytes = std::fs::metadata(path).map_err(|e| format!("cannot open it: {e}"))?.len();
    if bytes > limit {
        return Err(format!("it is {bytes} bytes, more than the limit of {limit}"));
    }
    std::fs::read(path).map_err(|e| format!("cannot read it: {e}"))
}

/// Appends `primitive`'s triangles, placed by `matrix` and moved by
/// `translate`, to `group`; returns how many.
fn read_primitive(
    primitive: &::gltf::Primitive,
    buffers: &[&[u8]],
    matrix: &DMat4,
    translate: Vec3,
    group: &mut Group,
) -> Result<usize, String> {
    let mode = primitive.mode();
    if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
        return Err(format!("its mode is {mode:?}: only triangles, strips and fans can be rendered"));
    }
    let position = primitive.get(&::gltf::Semantic::Positions).ok_or("it has no POSITION attribute")?;
    // The component types glTF 2.0 allows (§3.7.2.1), with those
    // `KHR_mesh_quantization` adds; every other combination is refused.
    use DataType::{F32, I8, I16, U8, U16};
    check_accessor(&position, "POSITION", Dimensions::Vec3, &[F32, I8, U8, I16, U16], buffers)?;
    let normal = primitive.get(&::gltf::Semantic::Normals);
    if let Some(a) = &normal {
        check_accessor(a, "NORMAL", Dimensions::Vec3, &[F32, I8, I16], buffers)?;
        if a.data_type() != F32 && !a.normalized() {
            return Err("NORMAL of integers must be normalized".into());
        }
    }
    let texcoord = primitive.get(&::gltf::Semantic::TexCoords(0));
    if let Some(a) = &texcoord {
        check_accessor(a, "TEXCOORD_0", Dimensions::Vec2, &[F32, I8, U8, I16, U16], buffers)?;
    }
    let texcoord1 = primitive.get(&::gltf::Semantic::TexCoords(1));
    if let Some(a) = &texcoord1 {
        check_accessor(a, "TEXCOORD_1", Dimensions::Vec2, &[F32, I8, U8, I16, U16], buffers)?;
    }
    let tangent = primitive.get(&::gltf::Semantic::Tangents);
    if let Some(a) = &tangent {
        check_accessor(a, "TANGENT", Dimensions::Vec4, &[F32, I8, I16], buffers)?;
        if a.data_type() != F32 && !a.normalized() {
            return Err("TANGENT of integers must be normalized".into());
        }
    }
    if let Some(a) = primitive.indices() {
        check_accessor(
            &a,
            "indices",
            Dimensions::Scalar,
            &[DataType::U8, DataType::U16, DataType::U32],
            buffers,
        )?;
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).copied());
    let count = position.count();
    if normal.as_ref().is_some_and(|a| a.count() != count)
        || texcoord.as_ref().is_some_and(|a| a.count() != count)
        || texcoord1.as_ref().is_some_and(|a| a.count() != count)
        || tangent.as_ref().is_some_and(|a| a.count() != count)
    {
        return Err("its attributes have different counts".into());
    }
    let base = group.positions.len();
    if base + count > u32::MAX as usize {
        return Err("it has too many vertices".into());
    }
    let linear = DMat3::from_mat4(*matrix);
    let flip = linear.determinant() < 0.0;
    let normal_matrix = linear.inverse().transpose();
    let t = crate::math::real::widen(translate);
    for (i, p) in read_vectors::<3>(&position, buffers).into_iter().enumerate() {
        let q = matrix.transform_point3(DVec3::from_array(p)) + t;
        let q = narrow(q);
        if !q.is_finite() {
            return Err(format!("vertex {i} is not finite"));
        }
        group.positions.push(q);
    }
    match &normal {
        Some(a) => {
            if !group.has_normals {
                group.normals.resize(base, Vec3::ZERO);
                group.has_normals = true;
            }
            group.normals.extend(
                read_vectors::<3>(a, buffers)
                    .into_iter()
                    .map(|n| narrow(normal_matrix * DVec3::from_array(n))),
            );
        }
        None if group.has_normals => group.normals.resize(base + count, Vec3::ZERO),
        None => {}
    }
    read_uv_set(texcoord.as_ref(), buffers, &mut group.uvs, &mut group.has_uvs, base, count);
    read_uv_set(texcoord1.as_ref(), buffers, &mut group.uvs1, &mut group.has_uvs1, base, count);
    // A tangent is a direction along the surface: it goes through the
    // transform itself. A mirror turns the frame's handedness round, so
    // `w` changes sign with the determinant (glTF's bitangent
    // `w·(N × T)`, mirrored, is `−w·(N' × T')`).
    match &tangent {
        Some(a) => {
            if !group.has_tangents {
                group.tangents.resize(base, [0.0; 4]);
                group.has_tangents = true;
            }
            let sign = if flip { -1.0 } else { 1.0 };
            group.tangents.extend(read_vectors::<4>(a, buffers).into_iter().map(|[x, y, z, w]| {
                let t = linear * DVec3::new(x, y, z);
                [t.x as f32, t.y as f32, t.z as f32, (sign * w) as f32]
            }));
        }
        None if group.has_tangents => group.tangents.resize(base + count, [0.0; 4]),
        None => {}
    }
    if group.positions.len() != base + count
        || (group.has_normals && group.normals.len() != base + count)
        || (group.has_uvs && group.uvs.len() != base + count)
        || (group.has_uvs1 && group.uvs1.len() != base + count)
        || (group.has_tangents && group.tangents.len() != base + count)
    {
        return Err("an attribute holds fewer values than its count".into());
    }
    // A later primitive with attributes pads the earlier ones of the group.
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..count as u32).collect(),
    };
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(format!("index {bad} is out of range ({count} vertices)"));
    }
    let corners: Vec<[u32; 3]> = match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|k| {
                let [a, b, c] = [indices[k - 2], indices[k - 1], indices[k]];
                if k % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len()).map(|k| [indices[0], indices[k - 1], indices[k]]).collect(),
        _ => indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    };
    let before = group.triangles.len();
    let b = base as u32;
    group.triangles.extend(
        corners.into_iter().map(|[x, y, z]| if flip { [b + x, b + z, b + y] } else { [b + x, b + y, b + z] }),
    );
    Ok(group.triangles.len() - before)
}

/// Appends one primitive's texture coordinates of one set (`count`
/// vertices from `base`) to a group's `uvs`: zeros for a primitive without
/// them once any primitive of the group had them (earlier ones padded then).
fn read_uv_set(
    accessor: Option<&::gltf::Accessor>,
    buffers: &[&[u8]],
    uvs: &mut Vec<[f32; 2]>,
    has: &mut bool,
    base: usize,
    count: usize,
) {
    match accessor {
        Some(a) => {
            if !*has {
                uvs.resize(base, [0.0; 2]);
                *has = true;
            }
            uvs.extend(read_vectors::<2>(a, buffers).into_iter().map(|uv| uv.map(|x| x as f32)));
        }
        None if *has => uvs.resize(base + count, [0.0; 2]),
        None => {}
    }
}

/// The `N`-vectors of accessor `a`, which [`check_accessor`] accepted (so
/// every element lies inside its buffer), as numbers: floats as they are,
/// integers as they are or, when `normalized`, mapped to [0, 1] (unsigned)
/// or [−1, 1] (signed) as glTF 2.0 §3.11 specifies — `c/255`, `c/65535`,
/// `max(c/127, −1)`, `max(c/32767, −1)` — which is how
/// `KHR_mesh_quantization`'s attributes are read. (The `gltf` crate's
/// readers take positions and normals as floats whatever their type.)
fn read_vectors<const N: usize>(a: &::gltf::Accessor, buffers: &[&[u8]]) -> Vec<[f64; N]> {
    let Some(view) = a.view() else { return Vec::new() };
    let Some(data) = buffers.get(view.buffer().index()) else { return Vec::new() };
    let (ty, normalized) = (a.data_type(), a.normalized());
    let width = ty.size();
    let stride = view.stride().unwrap_or(a.size());
    let start = view.offset() + a.offset();
    let component = |at: usize| -> f64 {
        let Some(b) = data.get(at..at + width) else { return f64::NAN };
        let (value, max) = match ty {
            DataType::I8 => (f64::from(b[0] as i8), 127.0),
            DataType::U8 => (f64::from(b[0]), 255.0),
            DataType::I16 => (f64::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
            DataType::U16 => (f64::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
            DataType::U32 => (f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])), 4294967295.0),
            DataType::F32 => return f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
        };
        if normalized { (value / max).max(-1.0) } else { value }
    };
    (0..a.count()).map(|i| std::array::from_fn(|c| component(start + i * stride + c * width))).collect()
}

/// Checks that `a` has the expected shape and lies inside its buffer view
/// and buffer, so reading it cannot go out of bounds.
fn check_accessor(
    a: &::gltf::Accessor,
    what: &str,
    dimensions: Dimensions,
    types: &[DataType],
    buffers: &[&[u8]],
) -> Result<(), String> {
    if a.sparse().is_some() {
        return Err(format!("{what}: sparse accessors are not supported"));
    }
    if a.dimensions() != dimensions || !types.contains(&a.data_type()) {
        return Err(format!("{what}: accessor {} is {:?} of {:?}", a.index(), a.dimensions(), a.data_type()));
    }
    let view = a.view().ok_or_else(|| format!("{what}: accessor {} has no buffer view", a.index()))?;
    if a.count() == 0 {
        return Err(format!("{what}: accessor {} is empty", a.index()));
    }
    let size = a.size();
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(format!(
            "{what}: buffer view {} has a stride of {stride}, under the element size {size}",
            view.index()
        ));
    }
    let buffer = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
    let view_end = view.offset().checked_add(view.length());
    let end = (a.count() - 1)
        .checked_mul(stride)
        .and_then(|n| n.checked_add(a.offset()))
        .and_then(|n| n.checked_add(size));
    match (view_end, end) {
        (Some(v), Some(e)) if v <= buffer && e <= view.length() => Ok(()),
        _ => Err(format!(
            "{what}: accessor {} runs past the end of its buffer view or buffer (a truncated file?)",
            a.index()
        )),
    }
}

/// The material's physically based parameters (see the table in the
/// module documentation), and what of it is not used.
fn map_material(m: &::gltf::Material) -> (Material, Vec<String>) {
    let notes = std::cell::RefCell::new(Vec::new());
    // A factor that is not a number, or out of its range, is named and
    // replaced (by its default, or clamped into the range).
    let factor = |name: &str, v: f32, default: f32, range: std::ops::RangeInclusive<f32>| {
        if !v.is_finite() {
            notes.borrow_mut().push(format!("{name} {v} (not a number: {default} instead)"));
            default
        } else if !range.contains(&v) {
            let c = v.clamp(*range.start(), *range.end());
            notes.borrow_mut().push(format!("{name} {v} (out of range: {c} instead)"));
            c
        } else {
            v
        }
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let base = Color::new(
        factor("baseColorFactor", r, 1.0, 0.0..=1.0),
        factor("baseColorFactor", g, 1.0, 0.0..=1.0),
        factor("baseColorFactor", b, 1.0, 0.0..=1.0),
    );
    let mut p = Principled {
        metallic: factor("metallicFactor", pbr.metallic_factor(), 1.0, 0.0..=1.0),
        roughness: factor("roughnessFactor", pbr.roughness_factor(), 1.0, 0.0..=1.0),
        ..Principled::DIELECTRIC
    };
    if let Some(t) = m.transmission() {
        p.transmission = factor("transmissionFactor", t.transmission_factor(), 0.0, 0.0..=1.0);
    }
    if let Some(v) = m.volume() {
        let [r, g, b] = v.attenuation_color();
        let c = |v: f32| factor("attenuationColor", v, 1.0, f32::MIN_POSITIVE..=1.0);
        p.attenuation_color = Color::new(c(r), c(g), c(b));
        let d = v.attenuation_distance();
        p.attenuation_distance = if d > 0.0 { d } else { f32::INFINITY };
    }
    if let Some(s) = m.specular() {
        p.specular = factor("specularFactor", s.specular_factor(), 1.0, 0.0..=1.0);
        let [r, g, b] = s.specular_color_factor();
        let c = |v: f32| factor("specularColorFactor", v, 1.0, 0.0..=100.0);
        p.specular_color = Color::new(c(r), c(g), c(b));
    }
    if let Some(coat) = m.extension_value("KHR_materials_clearcoat") {
        let number = |key: &str| coat.get(key).and_then(|v| v.as_f64()).map(|v| v as f32);
        p.clearcoat = factor("clearcoatFactor", number("clearcoatFactor").unwrap_or(0.0), 0.0, 0.0..=1.0);
        p.clearcoat_roughness = factor(
            "clearcoatRoughnessFactor",
            number("clearcoatRoughnessFactor").unwrap_or(0.0),
            0.0,
            0.0..=1.0,
        );
        for texture in ["clearcoatTexture", "clearcoatRoughnessTexture", "clearcoatNormalTexture"] {
            if coat.get(texture).is_some() {
                notes.borrow_mut().push(texture.to_owned());
            }
        }
    }
    let [r, g, b] = m.emissive_factor();
    let e = |v: f32| factor("emissiveFactor", v, 0.0, 0.0..=1.0);
    let strength = factor("emissiveStrength", m.emissive_strength().unwrap_or(1.0), 1.0, 0.0..=f32::MAX);
    let ior = factor("ior", m.ior().unwrap_or(1.5), 1.5, 1.0..=100.0);
    use ::gltf::material::AlphaMode as Mode;
    let alpha_mode = match m.alpha_mode() {
        Mode::Opaque => AlphaMode::Opaque,
        Mode::Mask => AlphaMode::Mask {
            cutoff: factor("alphaCutoff", m.alpha_cutoff().unwrap_or(DEFAULT_ALPHA_CUTOFF), 0.5, 0.0..=1.0),
        },
        Mode::Blend => AlphaMode::Blend,
    };
    let material = Material {
        ior,
        emission: Color::new(e(r), e(g), e(b)) * strength,
        alpha: factor("baseColorFactor", a, 1.0, 0.0..=1.0),
        alpha_mode,
        ..Material::principled(base, p)
    };
    let mut notes = notes.into_inner();
    if m.transmission().is_some_and(|t| t.transmission_texture().is_some()) {
        notes.push("transmissionTexture".to_owned());
    }
    if m.volume().is_some_and(|v| v.thickness_texture().is_some()) {
        notes.push("thicknessTexture".to_owned());
    }
    if let Some(s) = m.specular() {
        if s.specular_texture().is_some() {
            notes.push("specularTexture".to_owned());
        }
        if s.specular_color_texture().is_some() {
            notes.push("specularColorTexture".to_owned());
        }
    }
    (material, notes)
}

/// What reading a material's textures needs: the file, the textures
/// decoded so far (each image once per [`Encoding`]) and where to say what
/// went wrong.
struct Images<'a> {
    document: &'a ::gltf::json::Root,
    base: &'a Path,
    buffers: &'a [::gltf::buffer::Data],
    textures: &'a mut Vec<Texture>,
    decoded: &'a mut HashMap<(usize, Encoding), Option<u32>>,
    warnings: &'a mut Vec<String>,
    /// Which texture-coordinate sets the material's mesh has.
    uv_sets: [bool; 2],
    /// The material's name, and its notes (what it holds that is not used).
    material: &'a str,
    notes: &'a mut Vec<String>,
}

impl Images<'_> {
    /// The slot of the material's `field`, a use of texture `t` through
    /// coordinate set `tex_coord` and the `KHR_texture_transform` extension
    /// value `transform`, its image decoded by `encoding`: `None`, with a
    /// note or a warning naming the field, when the transform is malformed,
    /// the set is one meshes here do not keep or this mesh lacks, or the
    /// image cannot be read.
    fn slot(
        &mut self,
        field: &str,
        t: &::gltf::Texture,
        tex_coord: u32,
        transform: Option<&::gltf::json::Value>,
        encoding: Encoding,
    ) -> Option<TextureSlot> {
        let (transform, tex_coord) = match transform.map(texture_transform) {
            None => (UvTransform::IDENTITY, tex_coord),
            Some(Ok((transform, set))) => (transform, set.unwrap_or(tex_coord)),
            Some(Err(reason)) => {
                self.notes.push(format!("{field} (its KHR_texture_transform {reason})"));
                return None;
            }
        };
        if tex_coord > 1 {
            self.notes
                .push(format!("{field} (it reads TEXCOORD_{tex_coord}: only TEXCOORD_0 and _1 are kept)"));
            return None;
        }
        if !self.uv_sets[tex_coord as usize] {
            self.notes.push(format!("{field} (it reads TEXCOORD_{tex_coord}, which the meshes do not have)"));
            return None;
        }
        let image = t.source().index();
        let decoded = *self.decoded.entry((image, encoding)).or_insert_with(|| {
            match read_image(t, self.document, self.base, self.buffers, encoding) {
                Ok(texture) => {
                    self.textures.push(texture);
                    Some(self.textures.len() as u32 - 1)
                }
                Err(reason) => {
                    self.warnings.push(format!(
                        "texture {}: {reason}: material \"{}\" shows its {field} factor instead",
                        t.index(),
                        self.material
                    ));
                    None
                }
            }
        });
        let texture = decoded?;
        let sampler = t.sampler();
        let wrap = |m: WrappingMode| match m {
            WrappingMode::Repeat => Wrap::Repeat,
            WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let sampler = Sampler::from_gl(
            sampler.mag_filter().map(|f| f.as_gl_enum()),
            sampler.min_filter().map(|f| f.as_gl_enum()),
            [wrap(sampler.wrap_s()), wrap(sampler.wrap_t())],
        );
        Some(TextureSlot { texture, tex_coord, transform, sampler, scale: 1.0 })
    }
}

/// A `KHR_texture_transform` object: its transform (`offset`, `rotation`,
/// `scale`, defaults (0, 0), 0, (1, 1)) and its `texCoord` override, or
/// what is wrong with it.
fn texture_transform(value: &::gltf::json::Value) -> Result<(UvTransform, Option<u32>), String> {
    let pair = |key: &str, default: [f32; 2]| match value.get(key) {
        None => Ok(default),
        Some(v) => match v.as_array().map(|a| a.iter().map(|x| x.as_f64()).collect::<Vec<_>>()).as_deref() {
            Some([Some(x), Some(y)]) => Ok([*x as f32, *y as f32]),
            _ => Err(format!("{key} is not two numbers")),
        },
    };
    let rotation = match value.get("rotation") {
        None => 0.0,
        Some(v) => v.as_f64().ok_or("rotation is not a number")? as f32,
    };
    let tex_coord = match value.get("texCoord") {
        None => None,
        Some(v) => Some(v.as_u64().and_then(|n| u32::try_from(n).ok()).ok_or("texCoord is not a set index")?),
    };
    let transform = UvTransform::new(pair("offset", [0.0; 2])?, rotation, pair("scale", [1.0; 2])?)
        .ok_or("is not finite")?;
    Ok((transform, tex_coord))
}

/// A normal texture's `scale`, or 1 (named in `notes`) where it is not a number.
fn map_normal_scale(scale: f32, notes: &mut Vec<String>) -> f32 {
    if scale.is_finite() {
        scale
    } else {
        notes.push(format!("normalTexture.scale {scale} (not a number: 1 instead)"));
        1.0
    }
}

/// The texture's image, decoded by `encoding`.
fn read_image(
    t: &::gltf::Texture,
    document: &::gltf::json::Root,
    base: &Path,
    buffers: &[::gltf::buffer::Data],
    encoding: Encoding,
) -> Result<Texture, String> {
    let image = t.source();
    // `Image::source` unwraps a missing `mimeType` beside a `bufferView`,
    // and a missing `uri` when there is no `bufferView` (gltf 1.4.1); its
    // validation checks neither. glTF 2.0 §5.20 requires exactly one of
    // the two, and the MIME type with a buffer view.
    let Some(json) = document.images.get(image.index()) else {
        return Err(format!("image {} does not exist", image.index()));
    };
    match (&json.buffer_view, &json.uri, &json.mime_type) {
        (Some(_), None, Some(_)) | (None, Some(_), _) => {}
        (Some(_), None, None) => {
            return Err(format!("image {} is in a buffer view but has no mimeType", image.index()));
        }
        (Some(_), Some(_), _) => {
            return Err(format!("image {} has both a uri and a bufferView", image.index()));
        }
        (None, None, _) => return Err(format!("image {} has neither a uri nor a bufferView", image.index())),
    }
    if let ::gltf::image::Source::View { view, .. } = image.source() {
        let inside = view
            .offset()
            .checked_add(view.length())
            .is_some_and(|end| end <= buffers.get(view.buffer().index()).map_or(0, |b| b.0.len()));
        if !inside {
            return Err(format!("image {} runs past the end of its buffer", image.index()));
        }
    }
    let decoded = ::gltf::image::Data::from_source(image.source(), Some(base), buffers).map_err(|e| {
        match &json.uri {
            Some(uri) if !uri.starts_with("data:") => format!("image {} ({uri}): {e}", image.index()),
            _ => format!("image {}: {e}", image.index()),
        }
    })?;
    use ::gltf::image::Format;
    let (channels, wide) = match decoded.format {
        Format::R8 => (1, false),
        Format::R8G8 => (2, false),
        Format::R8G8B8 => (3, false),
        Format::R8G8B8A8 => (4, false),
        Format::R16 => (1, true),
        Format::R16G16 => (2, true),
        Format::R16G16B16 => (3, true),
        Format::R16G16B16A16 => (4, true),
        other => return Err(format!("its pixel format {other:?} is not an sRGB colour format")),
    };
    let values: Vec<f32> = if wide {
        decoded
            .pixels
            .chunks_exact(2)
            .map(|b| f32::from(u16::from_ne_bytes([b[0], b[1]])) / 65535.0)
            .collect()
    } else {
        decoded.pixels.iter().map(|&b| f32::from(b) / 255.0).collect()
    };
    if decoded.width.max(decoded.height) > MAX_TEXTURE_SIDE {
        return Err(format!(
            "it is {}×{} texels, more than the {MAX_TEXTURE_SIDE} a side may have",
            decoded.width, decoded.height
        ));
    }
    Texture::from_values(decoded.width, decoded.height, channels, &values, encoding)
        .ok_or_else(|| "its decoded size does not match its pixels".into())
}

/// A binary glTF (`.glb`, glTF 2.0 §4.4) of the JSON document `json` and
/// the binary chunk `bin`: a 12-byte header, then the JSON chunk padded
/// with spaces and the BIN chunk padded with zeros to 4 bytes. For tools
/// that write models (the sample models, `rt-view bench`'s terrains).
pub fn encode_glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut bin = bin.to_vec();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::texture::srgb_decode;
    use std::f64::consts::FRAC_1_SQRT_2;

    use proptest::prelude::*;
    use serde_json::{Value, json};

    /// A one-primitive glTF: a right triangle in glTF's z = 0 plane with
    /// normals and texture coordinates, under one node; `edit` changes the
    /// document before it is written.
    fn triangle_glb(edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Vec<u8> {
        let mut bin = Vec::new();
        let floats = |bin: &mut Vec<u8>, v: &[f32]| bin.extend(v.iter().flat_map(|f| f.to_le_bytes()));
        floats(&mut bin, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 0..36 positions
        floats(&mut bin, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]); // 36..72 normals
        floats(&mut bin, &[0.0, 0.0, 1.0, 0.0, 0.0, 1.0]); // 72..96 uvs
        bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes())); // 96..104 indices (+pad)
        let mut doc = json!({
            "asset": { "version": "2.0" },
            "scene": 0, "scenes": [{ "nodes": [0] }],
            "nodes": [{ "mesh": 0 }],
            "meshes": [{ "primitives": [{ "attributes": { "POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2 }, "indices": 3, "material": 0 }] }],
            "materials": [{ "name": "paint", "pbrMetallicRoughness": { "baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.0 } }],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
                { "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3" },
                { "bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2" },
                { "bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR" }
            ],
            "bufferViews": [
                { "buffer": 0, "byteOffset": 0, "byteLength": 36 },
                { "buffer": 0, "byteOffset": 36, "byteLength": 36 },
                { "buffer": 0, "byteOffset": 72, "byteLength": 24 },
                { "buffer": 0, "byteOffset": 96, "byteLength": 6 }
            ],
            "buffers": [{ "byteLength": 104 }]
        });
        edit(&mut doc, &mut bin);
        encode_glb(&doc.to_string(), &bin)
    }

    fn load_bytes(bytes: &[u8]) -> Result<Model, ModelError> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.glb");
        std::fs::write(&path, bytes).unwrap();
        load(&path, 1.0, Vec3::ZERO)
    }

    #[test]
    fn a_triangle_is_mirrored_in_z_and_its_winding_and_normals_follow() {
        let model = load_bytes(&triangle_glb(|_, _| {})).unwrap();
        assert_eq!(model.parts.len(), 1);
        let (mesh, material) = &model.parts[0];
        assert_eq!(*material, Some(0));
        // glTF's counter-clockwise triangle facing +z faces −z here, and its
        // geometric normal agrees with the mirrored vertex normal.
        let [a, b, c] = mesh.triangle(0);
        assert_eq!([a, b, c], [Vec3::ZERO, Vec3::Y, Vec3::X]);
        assert_eq!(mesh.normal(0), Vec3::new(0.0, 0.0, -1.0));
        let n = mesh.shading_normal(0, Vec3::new(0.2, 0.2, 0.0)).unwrap();
        assert!((n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6, "{n}");
        // Texture coordinates are glTF's own: (x, y) ↦ (x, y) here.
        let (u, v) = mesh.uv(0, Vec3::new(0.25, 0.5, 0.0)).unwrap();
        assert!((u - 0.25).abs() < 1e-6 && (v - 0.5).abs() < 1e-6, "{u} {v}");
        assert_eq!(model.materials[0].0, "paint");
        assert_eq!(model.materials[0].1.color, Color::new(0.5, 0.25, 1.0));
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    }

    #[test]
    fn node_transforms_compose_from_the_root_down_before_the_scene_scale() {
        let bytes = triangle_glb(|doc, _| {
            // Root: move +2 in x; child: scale 3 and turn 90° about +z
            // (glTF's x → y); the child holds the mesh.
            doc["nodes"] = json!([
                { "translation": [2.0, 0.0, 0.0], "children": [1] },
                { "mesh": 0, "scale": [3.0, 3.0, 3.0], "rotation": [0.0, 0.0, 0.5f64.sqrt(), 0.5f64.sqrt()] }
            ]);
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.glb");
        std::fs::write(&path, bytes).unwrap();
        let model = load(&path, 0.5, Vec3::new(0.0, 0.0, 10.0)).unwrap();
        let [a, b, c] = model.parts[0].0.triangle(0);
        let near = |p: Vec3, q: Vec3| (p - q).length() < 1e-5;
        // (0,0,0) → (2,0,0)·0.5 + (0,0,10); (1,0,0) → (2,3,0)·0.5; (0,1,0) → (−1,0,0)·0.5.
        assert!(near(a, Vec3::new(1.0, 0.0, 10.0)), "{a}");
        assert!(near(b, Vec3::new(-0.5, 0.0, 10.0)) && near(c, Vec3::new(1.0, 1.5, 10.0)), "{b} {c}");
        assert_eq!(model.parts[0].0.normal(0), Vec3::new(0.0, 0.0, -1.0));
    }

    #[test]
    fn every_factor_of_the_material_and_its_extensions_maps_exactly() {
        let bytes = triangle_glb(|doc, _| {
            doc["extensionsUsed"] = json!([
                "KHR_materials_transmission",
                "KHR_materials_ior",
                "KHR_materials_emissive_strength",
                "KHR_materials_specular",
                "KHR_materials_volume",
                "KHR_materials_clearcoat",
                "KHR_texture_transform"
            ]);
            doc["materials"] = json!([{
                "pbrMetallicRoughness": { "baseColorFactor": [1.0, 0.5, 0.25, 0.75], "metallicFactor": 0.5, "roughnessFactor": 0.3 },
                "emissiveFactor": [1.0, 0.5, 0.0],
                "alphaMode": "BLEND",
                "extensions": {
                    "KHR_materials_transmission": { "transmissionFactor": 0.8 },
                    "KHR_materials_ior": { "ior": 1.33 },
                    "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 },
                    "KHR_materials_specular": { "specularFactor": 0.7, "specularColorFactor": [1.0, 0.9, 0.8] },
                    "KHR_materials_volume": { "attenuationColor": [0.5, 0.6, 0.7], "attenuationDistance": 2.5 },
                    "KHR_materials_clearcoat": { "clearcoatFactor": 0.6, "clearcoatRoughnessFactor": 0.2 }
                }
            }]);
        });
        let model = load_bytes(&bytes).unwrap();
        let m = model.materials[0].1;
        assert_eq!(
            (m.color, m.ior, m.emission),
            (Color::new(1.0, 0.5, 0.25), 1.33, Color::new(4.0, 2.0, 0.0))
        );
        let expected = Principled {
            metallic: 0.5,
            roughness: 0.3,
            transmission: 0.8,
            attenuation_color: Color::new(0.5, 0.6, 0.7),
            attenuation_distance: 2.5,
            clearcoat: 0.6,
            clearcoat_roughness: 0.2,
            specular: 0.7,
            specular_color: Color::new(1.0, 0.9, 0.8),
        };
        assert_eq!(m.physical, Some(expected));
        assert_eq!((m.alpha, m.alpha_mode), (0.75, AlphaMode::Blend));
        assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
        assert!(model.warnings[0].contains("KHR_texture_transform"));
        // MASK with its cutoff, or glTF's default 0.5.
        for (cutoff, expected) in [(json!(0.25), 0.25), (Value::Null, 0.5)] {
            let bytes = triangle_glb(|doc, _| {
                doc["materials"] = json!([{ "alphaMode": "MASK" }]);
                if !cutoff.is_null() {
                    doc["materials"][0]["alphaCutoff"] = cutoff;
                }
            });
            let model = load_bytes(&bytes).unwrap();
            assert_eq!(model.materials[0].1.alpha_mode, AlphaMode::Mask { cutoff: expected });
            assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        }
        // Without extensions: glTF's defaults (metallic and roughness 1).
        let bytes = triangle_glb(|doc, _| doc["materials"] = json!([{}]));
        let m = load_bytes(&bytes).unwrap().materials[0].1;
        let p = m.physical.unwrap();
        assert_eq!((m.color, p.metallic, p.roughness, p.transmission), (Color::ONE, 1.0, 1.0, 0.0));
    }

    #[test]
    fn a_factor_out_of_range_is_clamped_and_named() {
        let bytes = triangle_glb(|doc, _| {
            doc["materials"] = json!([{
                "pbrMetallicRoughness": { "baseColorFactor": [1.5, 0.5, -0.25, 1.0], "metallicFactor": -1.0, "roughnessFactor": 7.0 },
            }]);
        });
        let model = load_bytes(&bytes).unwrap();
        let m = model.materials[0].1;
        let p = m.physical.unwrap();
        assert_eq!((m.color, p.metallic, p.roughness), (Color::new(1.0, 0.5, 0.0), 0.0, 1.0));
        let all = model.warnings.join("\n");
        for name in ["baseColorFactor 1.5", "baseColorFactor -0.25", "metallicFactor -1", "roughnessFactor 7"]
        {
            assert!(all.contains(name), "{name}: {all}");
        }
    }

    #[test]
    fn an_embedded_texture_is_decoded_with_its_samplers_wrap_modes() {
        let bytes = triangle_glb(|doc, bin| {
            let mut png = Vec::new();
            image::RgbImage::from_fn(2, 1, |x, _| {
                if x == 0 { image::Rgb([0, 0, 0]) } else { image::Rgb([255, 255, 255]) }
            })
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
            let offset = bin.len();
            bin.extend_from_slice(&png);
            doc["bufferViews"]
                .as_array_mut()
                .unwrap()
                .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": png.len() }));
            doc["buffers"][0]["byteLength"] = json!(bin.len());
            doc["images"] = json!([{ "bufferView": 4, "mimeType": "image/png" }]);
            doc["samplers"] = json!([{ "wrapS": 33071, "wrapT": 33648 }]);
            doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
            doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
        });
        let model = load_bytes(&bytes).unwrap();
        assert_eq!(model.materials[0].1.base_color_texture.map(|s| s.texture), Some(0));
        let t = &model.textures[0];
        let slot = model.materials[0].1.base_color_texture.unwrap();
        assert_eq!(slot.sampler.wrap, [Wrap::ClampToEdge, Wrap::MirroredRepeat]);
        // Clamped in u: far right is the white texel, far left the black one.
        assert_eq!(t.lookup(5.0, 0.5, 0.0, &slot.sampler), Color::ONE);
        assert_eq!(t.lookup(-5.0, 0.5, 0.0, &slot.sampler), Color::ZERO);
    }

    #[test]
    fn a_missing_texture_file_is_a_warning_and_the_factor_stays() {
        let bytes = triangle_glb(|doc, _| {
            doc["images"] = json!([{ "uri": "nowhere.png" }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
        });
        let model = load_bytes(&bytes).unwrap();
        assert_eq!(model.materials[0].1.base_color_texture, None);
        assert_eq!(model.materials[0].1.color, Color::new(0.5, 0.25, 1.0));
        assert!(
            model.warnings.iter().any(|w| w.starts_with("texture 0: image 0 (nowhere.png): ")
                && w.contains("material \"paint\" shows its baseColorTexture factor instead")),
            "{:?}",
            model.warnings
        );
    }

    #[test]
    fn geometry_alone_is_the_models_parts_in_one_mesh_without_reading_textures() {
        // A texture that cannot be decoded: a warning for the model, not even
        // read for the geometry.
        let bytes = triangle_glb(|doc, _| {
            doc["images"] = json!([{ "uri": "nowhere.png" }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.glb");
        std::fs::write(&path, bytes).unwrap();
        let model = load(&path, 1.0, Vec3::ZERO).unwrap();
        assert_eq!(model.warnings.len(), 1);
        let (mesh, files, _) = load_geometry(&path, 1.0, Vec3::ZERO).unwrap();
        assert_eq!(mesh, model.parts[0].0);
        assert_eq!(files, model.files);
    }

    /// The error `edit` leads to.
    fn error_of(edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> String {
        load_bytes(&triangle_glb(edit)).unwrap_err().to_string()
    }

    #[test]
    fn malformed_files_are_errors_that_say_what_and_where() {
        let e = error_of(|doc, _| doc["meshes"][0]["primitives"][0]["mode"] = json!(1));
        assert!(e.contains("mesh 0 primitive 0: its mode is Lines"), "{e}");
        let e = error_of(|doc, _| doc["accessors"][0]["count"] = json!(4));
        assert!(e.contains("mesh 0 primitive 0: POSITION: accessor 0 runs past the end"), "{e}");
        let e = error_of(|_, bin| bin[96..98].copy_from_slice(&7u16.to_le_bytes()));
        assert!(e.contains("index 7 is out of range (3 vertices)"), "{e}");
        let e = error_of(|doc, _| doc["accessors"][0]["type"] = json!("VEC2"));
        assert!(e.contains("POSITION: accessor 0 is Vec2"), "{e}");
        let e = error_of(|doc, _| doc["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]));
        assert!(
            e.contains("requires the extension EXT_mesh_gpu_instancing, which rt-view does not support"),
            "{e}"
        );
        let e = error_of(|doc, _| doc["nodes"] = json!([{ "mesh": 0, "children": [0] }]));
        assert!(e.starts_with("glTF file ") && e.contains("m.glb: "), "{e}");
        let e = error_of(|doc, _| doc["buffers"][0]["uri"] = json!("data%AA.bin"));
        assert!(e.contains("buffer 0: its URI \"data%AA.bin\" is not percent-encoded UTF-8"), "{e}");
        // 40 levels, each node listing the next twice: 2⁴⁰ instances.
        let e = error_of(|doc, _| {
            let mut nodes: Vec<Value> = (0..40).map(|k| json!({ "children": [k + 1, k + 1] })).collect();
            nodes.push(json!({ "mesh": 0 }));
            doc["nodes"] = json!(nodes);
        });
        assert!(e.contains("more than 1048576 node instances"), "{e}");
        let e = error_of(|doc, _| doc["buffers"][0]["uri"] = json!("gone.bin"));
        assert!(
            e.ends_with("buffer 0 (gone.bin) cannot be read: No such file or directory (os error 2)"),
            "{e}"
        );
        let e = error_of(|doc, _| doc["scenes"] = json!([{ "nodes": [] }]));
        assert!(e.ends_with("its scene has no meshes"), "{e}");
        // Truncated anywhere: an error, never a panic.
        let good = triangle_glb(|_, _| {});
        for cut in [0, 11, 12, 20, 40, good.len() / 2, good.len() - 60, good.len() - 1] {
            let e = load_bytes(&good[..cut]).unwrap_err().to_string();
            assert!(e.starts_with("glTF file "), "cut at {cut}: {e}");
        }
        let e = load(Path::new("/nonexistent/m.glb"), 1.0, Vec3::ZERO).unwrap_err().to_string();
        assert!(e.contains("cannot open it: No such file"), "{e}");
    }

    /// A 2×2 PNG (orange and blue checks), as Blender embeds its textures.
    /// [`triangle_glb`] with a 1×1 normal map of texel `rgb` (linear)
    /// and, if given, `TANGENT`s.
    fn normal_mapped_glb(rgb: [u8; 3], tangent: Option<[f32; 4]>) -> Vec<u8> {
        triangle_glb(|doc, bin| {
            let mut png = Vec::new();
            image::RgbImage::from_pixel(1, 1, image::Rgb(rgb))
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
                .unwrap();
            let offset = bin.len();
            bin.extend_from_slice(&png);
            let views = doc["bufferViews"].as_array_mut().unwrap();
            views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": png.len() }));
            if let Some(t) = tangent {
                while bin.len() % 4 != 0 {
                    bin.push(0);
                }
                let offset = bin.len();
                (0..3).for_each(|_| bin.extend(t.iter().flat_map(|f| f.to_le_bytes())));
                views.push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": 48 }));
                doc["accessors"].as_array_mut().unwrap().push(json!(
                    { "bufferView": 5, "componentType": 5126, "count": 3, "type": "VEC4" }
                ));
                doc["meshes"][0]["primitives"][0]["attributes"]["TANGENT"] = json!(4);
            }
            doc["buffers"][0]["byteLength"] = json!(bin.len());
            doc["images"] = json!([{ "bufferView": 4, "mimeType": "image/png" }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["materials"][0]["normalTexture"] = json!({ "index": 0, "scale": 1.0 });
        })
    }

    /// The shading normal a ray along +z sees at (0.25, 0.25) on `model`'s
    /// triangle (glTF's, mirrored: it faces −z here).
    fn mapped_normal_of(model: Model) -> Vec3 {
        let mut builder = crate::SceneBuilder::new();
        for t in model.textures {
            builder = builder.texture(std::sync::Arc::new(t));
        }
        let (mesh, _) = model.parts.into_iter().next().unwrap();
        let (name, material) = model.materials[0].clone();
        let scene = builder
            .material(name.clone(), material)
            .object(crate::Primitive::Mesh(mesh), name)
            .build()
            .unwrap();
        let ray = crate::math::ray::Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        let hit = scene.cast(&ray).unwrap();
        let mut scratch = std::mem::MaybeUninit::uninit();
        let si = crate::integrators::interaction::SurfaceInteraction::new(&scene, &ray, &hit, &mut scratch)
            .unwrap();
        si.shading_normal.unwrap()
    }

    #[test]
    fn a_normal_map_tilts_the_normal_towards_u_and_up_the_image_through_the_mirror() {
        // The triangle's u runs along glTF's +x and v along +y, so up the
        // image (decreasing v) is −y; mirrored in z, x and y stay. A texel
        // of red 1 tilts the normal 45° towards +u, one of green 1 45° up
        // the image: with MikkTSpace's tangents, and with the file's that
        // say the same (w = −1: glTF's bitangent w·(N × T) = −(z × x) is −y).
        let n = Vec3::new(0.0, 0.0, -1.0);
        let tilted = |d: Vec3| (n + d).normalize();
        for tangent in [None, Some([1.0, 0.0, 0.0, -1.0])] {
            let model = load_bytes(&normal_mapped_glb([255, 128, 255], tangent)).unwrap();
            assert!(model.warnings.is_empty(), "{:?}", model.warnings);
            let m = model.materials[0].1;
            assert_eq!(m.normal_texture.map(|s| (s.texture, s.scale)), Some((0, 1.0)));
            let got = mapped_normal_of(model);
            assert!((got - tilted(Vec3::X)).length() < 0.01, "tangent {tangent:?}: {got}");
            let got = mapped_normal_of(load_bytes(&normal_mapped_glb([128, 255, 255], tangent)).unwrap());
            assert!((got - tilted(-Vec3::Y)).length() < 0.01, "tangent {tangent:?}: {got}");
        }
        // The file's handedness is what counts: w = +1 makes its bitangent
        // z × x = +y, and green tilts that way, through the mirror.
        let model = load_bytes(&normal_mapped_glb([128, 255, 255], Some([1.0, 0.0, 0.0, 1.0]))).unwrap();
        let got = mapped_normal_of(model);
        assert!((got - tilted(Vec3::Y)).length() < 0.01, "{got}");
    }

    #[test]
    fn bad_tangents_are_errors_naming_the_attribute_or_are_replaced_never_a_panic() {
        let edit = |f: fn(&mut Value)| {
            let bytes = normal_mapped_glb([128, 128, 255], Some([1.0, 0.0, 0.0, 1.0]));
            let mut doc = json_of(&bytes);
            f(&mut doc);
            load_bytes(&encode_glb(&doc.to_string(), &bin_of(&bytes)))
        };
        let e = edit(|d| d["accessors"][4]["type"] = json!("VEC3")).unwrap_err().to_string();
        assert!(e.contains("TANGENT: accessor 4 is Vec3"), "{e}");
        let e = edit(|d| d["accessors"][4]["count"] = json!(2)).unwrap_err().to_string();
        assert!(e.contains("attributes have different counts"), "{e}");
        let e = edit(|d| d["accessors"][4]["count"] = json!(4)).unwrap_err().to_string();
        assert!(e.contains("runs past the end"), "{e}");
        // Not-a-number tangents are no tangents: MikkTSpace's stand in.
        let bytes = normal_mapped_glb([128, 255, 255], Some([f32::NAN, 0.0, 0.0, 1.0]));
        let n = mapped_normal_of(load_bytes(&bytes).unwrap());
        assert!((n - Vec3::new(0.0, -1.0, -1.0).normalize()).length() < 0.01, "{n}");
    }

    #[test]
    fn a_normal_map_on_a_mesh_without_texture_coordinates_is_a_warning_naming_material_and_field() {
        let mut bytes = normal_mapped_glb([128, 128, 255], None);
        let mut doc = json_of(&bytes);
        doc["meshes"][0]["primitives"][0]["attributes"].as_object_mut().unwrap().remove("TEXCOORD_0");
        bytes = encode_glb(&doc.to_string(), &bin_of(&bytes));
        let model = load_bytes(&bytes).unwrap();
        assert_eq!(model.materials[0].1.normal_texture, None);
        let w = model.warnings.join("\n");
        // As for every texture slot (the scene prefixes the model's file).
        assert!(
            w.contains("material \"paint\": not used: normalTexture (it reads TEXCOORD_0, which the meshes do not have)"),
            "{w}"
        );
    }

    fn png() -> Vec<u8> {
        let mut png = Vec::new();
        image::RgbImage::from_fn(2, 2, |x, y| {
            if (x + y) % 2 == 0 { image::Rgb([230, 120, 20]) } else { image::Rgb([20, 60, 200]) }
        })
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
        png
    }

    /// [`triangle_glb`] as Blender's exporter writes a textured model: an
    /// embedded PNG in a buffer view used by the base-colour,
    /// metallic-roughness and normal textures with a sampler, a camera, a
    /// light, a second node and the material extensions it writes.
    fn blender_like(doc: &mut Value, bin: &mut Vec<u8>) {
        let png = png();
        let offset = bin.len();
        bin.extend_from_slice(&png);
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": png.len() }));
        doc["buffers"][0]["byteLength"] = json!(bin.len());
        doc["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_materials_ior", "KHR_materials_specular"]);
        doc["images"] = json!([{ "bufferView": 4, "mimeType": "image/png", "name": "checker" }]);
        doc["samplers"] = json!([{ "magFilter": 9729, "minFilter": 9987 }]);
        doc["textures"] = json!([{ "source": 0, "sampler": 0 }]);
        doc["materials"] = json!([{
            "name": "pbr",
            "pbrMetallicRoughness": {
                "baseColorTexture": { "index": 0 },
                "metallicRoughnessTexture": { "index": 0 },
                "metallicFactor": 1.0
            },
            "normalTexture": { "index": 0, "scale": 0.8 },
            "alphaMode": "MASK",
            "alphaCutoff": 0.4,
            "extensions": { "KHR_materials_ior": { "ior": 1.45 }, "KHR_materials_specular": { "specularFactor": 0.5 } }
        }]);
        doc["cameras"] = json!([{ "name": "Camera", "type": "perspective", "perspective": { "yfov": 0.6911, "znear": 0.1, "zfar": 100.0, "aspectRatio": 1.7778 } }]);
        doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
            { "name": "Spot", "type": "spot", "color": [1.0, 0.9, 0.8], "intensity": 500.0, "spot": { "innerConeAngle": 0.3, "outerConeAngle": 0.6 } }
        ] } });
        doc["nodes"] = json!([
            { "name": "Suzanne", "mesh": 0 },
            { "name": "Camera", "camera": 0, "translation": [0.0, 0.0, 5.0] },
            { "name": "Light", "translation": [0.0, 4.0, 0.0], "rotation": [-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2], "extensions": { "KHR_lights_punctual": { "light": 0 } } }
        ]);
        doc["scenes"] = json!([{ "name": "Scene", "nodes": [0, 1, 2] }]);
    }

    #[test]
    fn every_texture_slot_is_read_with_its_encoding_set_transform_and_sampler_and_images_decode_once() {
        let bytes = triangle_glb(every_texture);
        let model = load_bytes(&bytes).unwrap();
        let m = model.materials[0].1;
        let (base, mr, emissive, occlusion) = (
            m.base_color_texture.unwrap(),
            m.metallic_roughness_texture.unwrap(),
            m.emissive_texture.unwrap(),
            m.occlusion_texture.unwrap(),
        );
        // One image, two encodings: decoded twice, each shared by its uses.
        assert_eq!(model.textures.len(), 2, "{:?}", model.warnings);
        assert_eq!((base.texture, emissive.texture), (0, 0));
        assert_eq!((mr.texture, occlusion.texture), (1, 1));
        let (srgb, linear) = (model.textures[0].sample(0.25, 0.25), model.textures[1].sample(0.25, 0.25));
        assert!(
            (srgb.x - srgb_decode(230.0 / 255.0)).abs() < 1e-6 && (linear.x - 230.0 / 255.0).abs() < 1e-6
        );
        // Sets, transform, samplers, strength.
        assert_eq!((base.tex_coord, mr.tex_coord, emissive.tex_coord, occlusion.tex_coord), (0, 1, 1, 0));
        assert!(base.transform.is_identity() && !emissive.transform.is_identity());
        let (u, v) = emissive.transformed((1.0, 0.0));
        assert!(u.abs() < 1e-6 && (v - 0.5).abs() < 1e-6, "({u}, {v})");
        assert_eq!(base.sampler, Sampler::DEFAULT);
        assert_eq!(mr.sampler.mip, None);
        assert_eq!(mr.sampler.wrap, [Wrap::ClampToEdge, Wrap::Repeat]);
        assert_eq!(occlusion.scale, 0.5);
        let all = model.warnings.join("\n");
        assert!(!all.contains("metallicRoughnessTexture") && !all.contains("emissiveTexture"), "{all}");
        assert!(all.contains("occlusionTexture (read, not applied"), "{all}");
    }

    #[test]
    fn a_texture_reading_a_set_the_mesh_lacks_or_a_broken_transform_is_named_and_not_applied() {
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            let m = &mut doc["materials"][0];
            m["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0, "texCoord": 1 });
            m["pbrMetallicRoughness"]["metallicRoughnessTexture"] =
                json!({ "index": 0, "extensions": { "KHR_texture_transform": { "scale": [1.0] } } });
            m["emissiveTexture"] = json!({ "index": 0, "texCoord": 3 });
        });
        let model = load_bytes(&bytes).unwrap();
        let m = model.materials[0].1;
        assert_eq!(
            (m.base_color_texture, m.metallic_roughness_texture, m.emissive_texture),
            (None, None, None)
        );
        let all = model.warnings.join("\n");
        for says in [
            "baseColorTexture (it reads TEXCOORD_1, which the meshes do not have)",
            "metallicRoughnessTexture (its KHR_texture_transform scale is not two numbers)",
            "emissiveTexture (it reads TEXCOORD_3: only TEXCOORD_0 and _1 are kept)",
        ] {
            assert!(all.contains(says), "{says}: {all}");
        }
    }

    /// [`blender_like`] with every texture slot used: a second coordinate
    /// set, two samplers of one image, an emissive texture with
    /// `KHR_texture_transform` and an occlusion texture.
    fn every_texture(doc: &mut Value, bin: &mut Vec<u8>) {
        blender_like(doc, bin);
        // A second coordinate set, and two textures of one image with
        // different samplers.
        let offset = bin.len();
        bin.extend([0.0f32, 0.0, 0.5, 0.0, 0.0, 0.5].iter().flat_map(|f| f.to_le_bytes()));
        doc["buffers"][0]["byteLength"] = json!(bin.len());
        doc["bufferViews"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": 24 }));
        doc["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({ "bufferView": 5, "componentType": 5126, "count": 3, "type": "VEC2" }));
        doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = json!(4);
        doc["samplers"] = json!([{ "magFilter": 9729, "minFilter": 9987 }, { "magFilter": 9728, "minFilter": 9728, "wrapS": 33071 }]);
        doc["textures"] = json!([{ "source": 0, "sampler": 0 }, { "source": 0, "sampler": 1 }]);
        let m = &mut doc["materials"][0];
        m["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({ "index": 1, "texCoord": 1 });
        m["emissiveTexture"] = json!({ "index": 0, "extensions": { "KHR_texture_transform": {
            "offset": [0.0, 1.0], "rotation": std::f64::consts::FRAC_PI_2, "scale": [0.5, 0.5], "texCoord": 1 } } });
        m["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
        m["occlusionTexture"] = json!({ "index": 1, "strength": 0.5 });
    }

    /// Loads `bytes` as a file named `name` in a folder that holds `extra`
    /// files; whatever it returns, it must return.
    fn load_named(
        bytes: &[u8],
        name: &str,
        extra: &[(&str, &[u8])],
    ) -> Result<(Model, Vec<Light>), ModelError> {
        let dir = tempfile::tempdir().unwrap();
        for (file, data) in extra {
            std::fs::write(dir.path().join(file), data).unwrap();
        }
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        load_with_lights(&path, 1.0, Vec3::ZERO, true)
    }

    #[test]
    fn an_image_in_a_buffer_view_without_a_mime_type_is_a_warning_naming_it_not_a_panic() {
        // gltf 1.4.1's `Image::source` unwraps the missing mimeType.
        for (image, says) in [
            (json!({ "bufferView": 4 }), "image 0 is in a buffer view but has no mimeType"),
            (json!({ "name": "nothing" }), "image 0 has neither a uri nor a bufferView"),
            (
                json!({ "bufferView": 4, "uri": "a.png", "mimeType": "image/png" }),
                "image 0 has both a uri and a bufferView",
            ),
        ] {
            let bytes = triangle_glb(|doc, bin| {
                blender_like(doc, bin);
                doc["images"][0] = image.clone();
            });
            let model = load_bytes(&bytes).unwrap();
            assert_eq!(model.materials[0].1.base_color_texture, None);
            assert!(
                model.warnings.iter().any(|w| w.starts_with("texture 0: ") && w.contains(says)),
                "{:?}",
                model.warnings
            );
        }
        // The well-formed file decodes its texture, once as colour and once
        // as the (linear) normal map, and reads its alpha mode.
        let model = load_bytes(&triangle_glb(blender_like)).unwrap();
        let m = model.materials[0].1;
        let (base, normal) = (m.base_color_texture.unwrap(), m.normal_texture.unwrap());
        assert_eq!((base.texture, normal.texture, normal.scale), (0, 1, 0.8));
        assert_eq!(m.alpha_mode, AlphaMode::Mask { cutoff: 0.4 });
        assert_eq!(model.textures.len(), 2);
    }

    #[test]
    fn the_crates_validation_errors_name_the_json_path_and_what_is_wrong() {
        let e = error_of(|doc, _| doc["meshes"][0]["primitives"][0]["material"] = json!(3));
        assert!(
            e.contains("it is not valid glTF 2.0: meshes[0].primitives[0].material: an index past the end of its list"),
            "{e}"
        );
        let e = error_of(|doc, _| doc["accessors"][1]["componentType"] = json!(1));
        assert!(e.contains("accessors[1].componentType: an invalid value"), "{e}");
    }

    #[test]
    fn draco_compressed_meshes_are_refused_naming_the_extension_and_a_way_out_unless_their_data_is_there() {
        let ext = "KHR_draco_mesh_compression";
        let e = error_of(|doc, _| {
            doc["extensionsUsed"] = json!([ext]);
            doc["extensionsRequired"] = json!([ext]);
        });
        assert!(
            e.contains(&format!("its meshes are compressed with {ext}, which rt-view does not decode")),
            "{e}"
        );
        assert!(e.contains("uncompressed"), "{e}");
        let model = load_bytes(&triangle_glb(|doc, _| doc["extensionsUsed"] = json!([ext]))).unwrap();
        assert_eq!(
            model.warnings,
            [format!("extension {ext} is not decoded: its uncompressed fallback data is read")]
        );
    }

    /// [`triangle_glb`] as `gltfpack -cc` writes it (`EXT_meshopt_compression`):
    /// the positions, octahedral-filtered normals and indices compressed in
    /// the GLB's buffer, their views in a fallback buffer without data.
    fn meshopt_compressed(doc: &mut Value, bin: &mut Vec<u8>) {
        let positions: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let normals = meshopt::encode_filter_oct::<i8>(&[[0.0, 0.0, 1.0, 0.0]; 3], 8);
        let streams = [
            meshopt::encode_vertex_buffer(&positions).unwrap(),
            meshopt::encode_vertex_buffer(&normals).unwrap(),
            meshopt::encode_index_buffer(&[0, 1, 2], 3).unwrap(),
        ];
        bin.clear();
        let mut at = Vec::new();
        for s in &streams {
            at.push(bin.len());
            bin.extend(s);
            bin.resize(bin.len().next_multiple_of(4), 0);
        }
        let ext = |k: usize, stride: usize, mode: &str, filter: &str| {
            json!({ "EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": at[k], "byteLength": streams[k].len(),
                "byteStride": stride, "count": 3, "mode": mode, "filter": filter
            } })
        };
        doc["extensionsUsed"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
        doc["buffers"] = json!([
            { "byteLength": bin.len() },
            { "byteLength": 54, "extensions": { "EXT_meshopt_compression": { "fallback": true } } }
        ]);
        doc["bufferViews"] = json!([
            { "buffer": 1, "byteOffset": 0, "byteLength": 36, "byteStride": 12, "extensions": ext(0, 12, "ATTRIBUTES", "NONE") },
            { "buffer": 1, "byteOffset": 36, "byteLength": 12, "byteStride": 4, "extensions": ext(1, 4, "ATTRIBUTES", "OCTAHEDRAL") },
            { "buffer": 1, "byteOffset": 48, "byteLength": 6, "extensions": ext(2, 2, "TRIANGLES", "NONE") }
        ]);
        doc["accessors"] = json!([
            { "bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ]);
        doc["meshes"][0]["primitives"][0]["attributes"] = json!({ "POSITION": 0, "NORMAL": 1 });
        doc["meshes"][0]["primitives"][0]["indices"] = json!(2);
    }

    #[test]
    fn meshopt_compressed_views_are_decoded_and_read_as_the_uncompressed_file() {
        let model = load_bytes(&triangle_glb(meshopt_compressed)).unwrap();
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        let mesh = &model.parts[0].0;
        assert_eq!(mesh.triangle(0), [Vec3::ZERO, Vec3::Y, Vec3::X]);
        let n = mesh.shading_normal(0, Vec3::new(0.2, 0.2, 0.0)).unwrap();
        assert!((n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-2, "{n}");
        // What the specification forbids (and meshoptimizer would assert)
        // is refused, naming the view; a stream that does not decode too.
        for (edit, says) in [
            (
                json!({ "byteStride": 6 }),
                "buffer view 0 (EXT_meshopt_compression): byteStride 6 is not allowed in mode Attributes",
            ),
            (json!({ "mode": "TRIANGLES" }), "byteStride 12 is not allowed in mode Triangles"),
            (json!({ "filter": "QUATERNION" }), "filter Quaternion does not apply to byteStride 12"),
            (json!({ "count": 4 }), "4 elements of 12 bytes do not fill the view's byteLength 36"),
            (json!({ "buffer": 7 }), "its buffer 7 does not exist"),
            (json!({ "mode": "POINTS" }), "its mode Some(\"POINTS\") is not ATTRIBUTES"),
            (json!({ "byteLength": 100000 }), "its compressed data runs past the end of its buffer"),
            (json!({ "byteLength": 3 }), "meshoptimizer cannot decode it"),
        ] {
            let e = error_of(|doc, bin| {
                meshopt_compressed(doc, bin);
                let ext =
                    doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"].as_object_mut().unwrap();
                for (k, v) in edit.as_object().unwrap() {
                    ext.insert(k.clone(), v.clone());
                }
            });
            assert!(e.contains(says), "{edit}: {e}");
        }
    }

    /// Writes `values` with `write` each, padding each vertex to `stride` bytes.
    fn packed<T: Copy>(
        values: &[[T; 3]],
        dims: usize,
        stride: usize,
        write: impl Fn(T) -> Vec<u8>,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        for v in values {
            let start = out.len();
            for c in &v[..dims] {
                out.extend(write(*c));
            }
            out.resize(start + stride, 0);
        }
        out
    }

    /// [`triangle_glb`] quantized (`KHR_mesh_quantization`).
    /// Positions as unnormalized i16 (stride 8), scaled back by the node
    /// (1/1000) as gltfpack writes them; normals as normalized i8
    /// (stride 4); texture coordinates as normalized i16.
    fn quantized(doc: &mut Value, bin: &mut Vec<u8>) {
        bin.clear();
        bin.extend(packed(&[[0i16, 0, 0], [1000, 0, 0], [0, 1000, 0]], 3, 8, |c| c.to_le_bytes().to_vec())); // 0..24
        bin.extend(packed(&[[0i8, 0, 127], [0, 0, 127], [0, -128, 0]], 3, 4, |c| vec![c as u8])); // 24..36
        bin.extend(packed(&[[0i16, 0, 0], [32767, 0, 0], [0, -32768, 0]], 2, 4, |c| {
            c.to_le_bytes().to_vec()
        })); // 36..48
        bin.extend([0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes())); // 48..56
        doc["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
        doc["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
        doc["nodes"][0]["scale"] = json!([0.001, 0.001, 0.001]);
        doc["accessors"] = json!([
            { "bufferView": 0, "componentType": 5122, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1000, 1000, 0] },
            { "bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3" },
            { "bufferView": 2, "componentType": 5122, "normalized": true, "count": 3, "type": "VEC2" },
            { "bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR" }
        ]);
        doc["bufferViews"] = json!([
            { "buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8 },
            { "buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 36, "byteLength": 12, "byteStride": 4 },
            { "buffer": 0, "byteOffset": 48, "byteLength": 6 }
        ]);
        doc["buffers"][0]["byteLength"] = json!(bin.len());
    }

    #[test]
    fn quantized_positions_normals_and_texture_coordinates_are_dequantized_as_the_extension_specifies() {
        let bytes = triangle_glb(quantized);
        let model = load_bytes(&bytes).unwrap();
        assert!(model.warnings.is_empty(), "{:?}", model.warnings);
        let mesh = &model.parts[0].0;
        let near = |p: Vec3, q: Vec3| (p - q).length() < 1e-5;
        let [a, b, c] = mesh.triangle(0);
        assert!(near(a, Vec3::ZERO) && near(b, Vec3::Y) && near(c, Vec3::X), "{a} {b} {c}");
        // At corner 0 (glTF's origin): normal 127/127 along +z, mirrored.
        let n = mesh.shading_normal(0, Vec3::new(1e-4, 1e-4, 0.0)).unwrap();
        assert!((n - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-2, "{n}");
        // At glTF's (0, 1, 0): v = max(−32768/32767, −1) = −1; at (1, 0, 0): u = 1.
        let (u, v) = mesh.uv(0, Vec3::new(0.0, 1.0, 0.0)).unwrap();
        assert!(u.abs() < 1e-5 && (v + 1.0).abs() < 1e-6, "{u} {v}");
        let (u, v) = mesh.uv(0, Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!((u - 1.0).abs() < 1e-6 && v.abs() < 1e-6, "{u} {v}");
        // A NORMAL of integers that is not normalized is refused; texture
        // coordinates that are not normalized are read as integers.
        let e = error_of(|doc, _| {
            doc["accessors"][1] =
                json!({ "bufferView": 1, "componentType": 5120, "count": 3, "type": "VEC3" })
        });
        assert!(e.contains("mesh 0 primitive 0: NORMAL of integers must be normalized"), "{e}");
        let bytes = triangle_glb(|doc, bin| {
            quantized(doc, bin);
            doc["accessors"][2]["normalized"] = json!(false);
        });
        let (u, _) = load_bytes(&bytes).unwrap().parts[0].0.uv(0, Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!((u - 32767.0).abs() < 1e-2, "{u}");
    }

    #[test]
    fn punctual_lights_are_placed_by_their_nodes_in_watts_from_candela_and_lux() {
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["extensions"]["KHR_lights_punctual"]["lights"] = json!([
                { "type": "spot", "color": [1.0, 0.5, 0.0], "intensity": 683.0, "spot": { "innerConeAngle": 0.25, "outerConeAngle": 0.5 } },
                { "type": "point", "intensity": 1366.0 },
                { "type": "directional", "color": [0.5, 0.5, 0.5], "intensity": 6830.0 }
            ]);
            // Each light's node turns −z (its shining direction) to −y, at (1, 4, 2).
            let down = json!([-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2]);
            doc["nodes"] = json!([
                { "mesh": 0 },
                { "translation": [1.0, 4.0, 2.0], "rotation": down, "extensions": { "KHR_lights_punctual": { "light": 0 } } },
                { "translation": [1.0, 4.0, 2.0], "extensions": { "KHR_lights_punctual": { "light": 1 } } },
                { "rotation": down, "extensions": { "KHR_lights_punctual": { "light": 2 } } }
            ]);
            doc["scenes"] = json!([{ "nodes": [0, 1, 2, 3] }]);
        });
        let (model, lights) = load_named(&bytes, "m.glb", &[]).unwrap();
        assert!(!model.warnings.iter().any(|w| w.contains("light")), "{:?}", model.warnings);
        let mut kinds: Vec<Light> = lights;
        kinds.sort_by_key(|l| match l.kind {
            LightKind::Spot { .. } => 0,
            LightKind::Point { .. } => 1,
            _ => 2,
        });
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        // glTF (1, 4, 2) is rt-view's (1, 4, −2).
        let LightKind::Spot { position, direction, cos_inner, cos_outer } = kinds[0].kind else {
            panic!("{kinds:?}")
        };
        assert!(close(position, Vec3::new(1.0, 4.0, -2.0)) && close(direction, -Vec3::Y), "{kinds:?}");
        assert!(
            (cos_inner - (0.25 as Real).cos()).abs() < 1e-6 && (cos_outer - (0.5 as Real).cos()).abs() < 1e-6
        );
        assert!((kinds[0].power - Color::new(1.0, 0.5, 0.0)).abs().max_element() < 1e-6, "{:?}", kinds[0]);
        assert!(
            matches!(kinds[1].kind, LightKind::Point { position } if close(position, Vec3::new(1.0, 4.0, -2.0)))
        );
        assert!((kinds[1].power - Color::splat(2.0)).abs().max_element() < 1e-6);
        assert!(
            matches!(kinds[2].kind, LightKind::Directional { direction } if close(direction, -Vec3::Y)),
            "{kinds:?}"
        );
        assert!((kinds[2].power - Color::splat(5.0)).abs().max_element() < 1e-5);
        // Without `lights: true` they are a warning.
        let model = load_bytes(&bytes).unwrap();
        assert!(
            model.warnings.iter().any(|w| w.contains("3 KHR_lights_punctual light(s) are not used")),
            "{:?}",
            model.warnings
        );
        // A spot cone the specification forbids is an error naming the light.
        let e = error_of(|doc, bin| {
            blender_like(doc, bin);
            doc["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"]["innerConeAngle"] = json!(0.9);
        });
        assert!(e.contains("light 0 (\"Spot\"): its cone angles must satisfy"), "{e}");
    }

    #[test]
    fn a_files_camera_is_placed_by_its_node_looking_along_its_minus_z() {
        let bytes = triangle_glb(blender_like);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.glb");
        std::fs::write(&path, &bytes).unwrap();
        // At glTF (0, 0, 5) looking at the origin: rt-view's (0, 0, −5)
        // looking along +z, 5 from the model's origin; scaled by 2 and moved.
        let c = camera(&path, 0, 2.0, Vec3::new(1.0, 0.0, 0.0)).unwrap();
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-4;
        assert!(close(c.position(), Vec3::new(1.0, 0.0, -10.0)), "{}", c.position());
        assert!(close(c.center_of_interest(), Vec3::new(1.0, 0.0, 0.0)), "{}", c.center_of_interest());
        assert!(close(c.up(), Vec3::new(0.0, 2.0, 0.0)), "{}", c.up());
        assert!((c.fov_y() - (0.6911 as Real).to_degrees()).abs() < 1e-3 && (c.near() - 0.2).abs() < 1e-6);
        assert_eq!(c.projection(), Projection::Perspective);
        // Orthographic: a view plane 2·ymag high.
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["cameras"][0] = json!({ "type": "orthographic", "orthographic": { "xmag": 3.0, "ymag": 2.0, "znear": 0.5, "zfar": 10.0 } });
        });
        std::fs::write(&path, &bytes).unwrap();
        let c = camera(&path, 0, 1.0, Vec3::ZERO).unwrap();
        assert_eq!(c.projection(), Projection::Orthographic);
        let half = c.near() * (c.fov_y().to_radians() / 2.0).tan();
        assert!((half - 2.0).abs() < 1e-4 && (c.fov_y() - 90.0).abs() < 1e-4, "{half}");
        // Its rays start where glTF's do: 0.5 in front of the node, at z = −4.5.
        let start = c.position() + c.near() * Vec3::Z;
        assert!((start - Vec3::new(0.0, 0.0, -4.5)).length() < 1e-5, "{start}");
        // A near plane farther than the half height: the eye stays, the view narrows.
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["cameras"][0] = json!({ "type": "orthographic", "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 2.0, "zfar": 10.0 } });
        });
        std::fs::write(&path, &bytes).unwrap();
        let c = camera(&path, 0, 1.0, Vec3::ZERO).unwrap();
        assert!((c.position() - Vec3::new(0.0, 0.0, -5.0)).length() < 1e-5 && (c.near() - 2.0).abs() < 1e-6);
        let half = c.near() * (c.fov_y().to_radians() / 2.0).tan();
        assert!((half - 1.0).abs() < 1e-4, "{half}");
        // A type without its properties, a camera that is not there, one no node holds.
        for (edit, says) in [
            (
                json!({ "type": "orthographic", "perspective": { "yfov": 1.0, "znear": 0.1 } }),
                "camera 0: its type is Orthographic but it has no Orthographic properties",
            ),
            (
                json!({ "type": "perspective", "perspective": { "yfov": 4.0, "znear": 0.1 } }),
                "camera 0: camera.fov_y must be strictly between 0 and 180",
            ),
        ] {
            let bytes = triangle_glb(|doc, bin| {
                blender_like(doc, bin);
                doc["cameras"][0] = edit.clone();
            });
            std::fs::write(&path, &bytes).unwrap();
            let e = camera(&path, 0, 1.0, Vec3::ZERO).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
        let e = camera(&path, 1, 1.0, Vec3::ZERO).unwrap_err().to_string();
        assert!(e.contains("it has no camera 1 (it has 1)"), "{e}");
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["scenes"][0]["nodes"] = json!([0]);
        });
        std::fs::write(&path, &bytes).unwrap();
        let e = camera(&path, 0, 1.0, Vec3::ZERO).unwrap_err().to_string();
        assert!(e.contains("camera 0 (\"Camera\"): no node of its scene holds it"), "{e}");
    }

    #[test]
    fn what_the_file_holds_and_is_not_used_is_named() {
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"] = json!(0);
            doc["meshes"][0]["primitives"][0]["targets"] = json!([{ "POSITION": 0 }]);
            doc["animations"] = json!([{ "channels": [], "samplers": [] }]);
            doc["extensionsUsed"].as_array_mut().unwrap().push(json!("KHR_materials_sheen"));
        });
        let model = load_bytes(&bytes).unwrap();
        assert_eq!(model.cameras, 1, "the file's cameras are counted for the scene to mention");
        let w = model.warnings;
        for says in [
            "extension KHR_materials_sheen is not used",
            "1 animation(s) not used",
            "1 primitive(s) with morph targets not used",
            "vertex attributes not used: COLOR_0",
            "1 KHR_lights_punctual light(s) are not used",
        ] {
            assert!(w.iter().any(|x| x.contains(says)), "{says}: {w:?}");
        }
    }

    /// The `.gltf` text of [`blender_like`] with its buffer in `m.bin`
    /// beside it, and that buffer.
    fn blender_like_text() -> (Value, Vec<u8>) {
        let mut doc = Value::Null;
        let mut bin = Vec::new();
        let _ = triangle_glb(|d, b| {
            blender_like(d, b);
            d["buffers"][0]["uri"] = json!("m.bin");
            doc = d.clone();
            bin = b.clone();
        });
        (doc, bin)
    }

    /// The JSON chunk of a `.glb`.
    fn json_of(glb: &[u8]) -> Value {
        let length = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice(&glb[20..20 + length]).unwrap()
    }

    /// The BIN chunk of a `.glb` made by [`encode_glb`].
    fn bin_of(glb: &[u8]) -> Vec<u8> {
        let length = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        glb[28 + length..].to_vec()
    }

    #[test]
    fn thousands_of_damaged_json_documents_never_panic() {
        // Each mutant: 1 to 4 structure-aware changes (numbers, dropped
        // keys, swapped types, indices past the end) of a Blender-like file,
        // as .glb and as .gltf text with an external buffer, or of a
        // meshopt-compressed one, or of one using every texture slot. The mutants
        // that load must be consistent. A longer run by hand:
        // RT_GLTF_MUTANTS=200000 cargo test -p rt-core --lib thousands_of_damaged
        use crate::files::gltf_mutation::{Choices, mutate};
        let runs: u64 = std::env::var("RT_GLTF_MUTANTS").ok().and_then(|n| n.parse().ok()).unwrap_or(3000);
        let glb = triangle_glb(blender_like);
        let (glb_doc, glb_bin) = (json_of(&glb), bin_of(&glb));
        let (text_doc, text_bin) = blender_like_text();
        let packed = triangle_glb(meshopt_compressed);
        let (packed_doc, packed_bin) = (json_of(&packed), bin_of(&packed));
        let textured = triangle_glb(every_texture);
        let (textured_doc, textured_bin) = (json_of(&textured), bin_of(&textured));
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("m.bin"), &text_bin).unwrap();
        let (mut loaded, mut refused) = (0, 0);
        for seed in 0..runs {
            let mut choices = Choices::Seeded(seed);
            let as_text = seed % 4 == 1;
            let (mut doc, bin) = match seed % 4 {
                0 => (glb_doc.clone(), &glb_bin),
                1 => (text_doc.clone(), &glb_bin),
                2 => (packed_doc.clone(), &packed_bin),
                _ => (textured_doc.clone(), &textured_bin),
            };
            let count = 1 + choices.below(4);
            mutate(&mut doc, count, &mut choices);
            let (bytes, name) = if as_text {
                (doc.to_string().into_bytes(), "m.gltf")
            } else {
                (encode_glb(&doc.to_string(), bin), "m.glb")
            };
            let path = dir.path().join(name);
            let result = std::panic::catch_unwind(|| {
                let model = from_slice(&bytes, &path, 1.0, Vec3::ZERO);
                let camera = std::fs::write(&path, &bytes).map(|()| camera(&path, 0, 1.0, Vec3::ZERO));
                let lights = load_with_lights(&path, 1.0, Vec3::ZERO, true);
                (model, camera, lights)
            });
            let Ok((model, _, _)) = result else {
                std::fs::write(dir.path().join("panicked.json"), doc.to_string()).unwrap();
                panic!("seed {seed} ({name}) panicked: {doc}");
            };
            match model {
                Ok(model) => {
                    loaded += 1;
                    for (mesh, material) in &model.parts {
                        assert!(
                            mesh.bounds().min().is_finite() && mesh.bounds().max().is_finite(),
                            "seed {seed}"
                        );
                        assert!(material.is_none_or(|m| m < model.materials.len()), "seed {seed}");
                    }
                }
                Err(e) => {
                    refused += 1;
                    if std::env::var("RT_GLTF_SHOW").is_ok() {
                        eprintln!("{seed} {name}: {e}");
                    }
                }
            }
        }
        // Some mutants still load (the damage is local); most are refused,
        // by the JSON schema or by validation. (RT_GLTF_SHOW=1 lists why.)
        assert!(loaded > runs / 20 && refused > runs / 2, "{loaded} loaded, {refused} refused");
    }

    #[test]
    fn the_fuzz_corpus_and_its_regressions_load_or_are_refused_without_a_panic() {
        let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/gltf");
        let mut seen = 0;
        for entry in std::fs::read_dir(&corpus).unwrap() {
            let path = entry.unwrap().path();
            let bytes = std::fs::read(&path).unwrap();
            let name = Path::new("/nonexistent-fuzz-dir").join(path.file_name().unwrap());
            let _ = from_slice(&bytes, &name, 1.0, Vec3::ZERO);
            seen += 1;
        }
        assert!(seen >= 4, "{seen} files in {}", corpus.display());
        // The two files the issue's panics came from: a texture's image in a
        // buffer view with no mimeType.
        let bytes = std::fs::read(corpus.join("image-view-without-mime-type.glb")).unwrap();
        let model = from_slice(&bytes, Path::new("/nonexistent-fuzz-dir/m.glb"), 1.0, Vec3::ZERO).unwrap();
        assert!(model.warnings.iter().any(|w| w.contains("has no mimeType")), "{:?}", model.warnings);
    }

    /// Writes the regression corpus's generated files (run by hand when
    /// they need to change: `cargo test -p rt-core --lib write_gltf_corpus -- --ignored`).
    #[test]
    #[ignore]
    fn write_gltf_corpus() {
        let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/gltf");
        std::fs::write(corpus.join("blender-like.glb"), triangle_glb(blender_like)).unwrap();
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["images"][0] = json!({ "bufferView": 4 });
        });
        std::fs::write(corpus.join("image-view-without-mime-type.glb"), bytes).unwrap();
        let bytes = triangle_glb(|doc, bin| {
            blender_like(doc, bin);
            doc["images"][0] = json!({ "name": "neither uri nor view" });
        });
        std::fs::write(corpus.join("image-without-source.glb"), bytes).unwrap();
        let (doc, _) = blender_like_text();
        std::fs::write(corpus.join("blender-like.gltf"), doc.to_string()).unwrap();
        std::fs::write(corpus.join("meshopt.glb"), triangle_glb(meshopt_compressed)).unwrap();
        std::fs::write(corpus.join("every-texture.glb"), triangle_glb(every_texture)).unwrap();
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]
        /// Bytes changed anywhere in a valid file (header, JSON, binary
        /// chunk): the loader answers with a model or an error, never a
        /// panic, and a model it returns has finite vertices.
        #[test]
        fn corrupted_files_never_panic(edits in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)) {
            let mut bytes = triangle_glb(|_, _| {});
            for (at, value) in edits {
                let i = at.index(bytes.len());
                bytes[i] = value;
            }
            if let Ok(model) = load_bytes(&bytes) {
                for (mesh, _) in &model.parts {
                    prop_assert!(mesh.bounds().min().is_finite() && mesh.bounds().max().is_finite());
                }
            }
        }
    }
}
