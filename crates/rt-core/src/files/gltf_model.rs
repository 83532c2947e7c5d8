//! glTF 2.0 files (`.gltf` with its buffers and images, or `.glb`) as a
//! [`Model`], read with the `gltf` crate.
//!
//! **What is read.** Every mesh primitive of the file's default scene (or
//! its first scene), placed by its node's transform composed with its
//! parents' (glTF 2.0 §3.5.3): positions, normals (as shading normals),
//! `TEXCOORD_0`, indices. Triangle lists, strips and fans are read; points
//! and lines are an error.
//!
//! **Coordinates.** glTF's world is right-handed with +Y up and a model's
//! front facing +Z; rt-view's is left-handed ([`crate::camera`]). Every
//! point is mirrored in z, `(x, y, z) → (x, y, −z)`, so the model stands
//! the same way up, seen from the front by a camera at negative z looking
//! at the origin (as the scenes' cameras are), and nothing is mirror-
//! imaged. A mirror turns a triangle's winding round, so the corners are
//! stored in reverse wherever the transform (mirror included) has a
//! negative determinant, and `(b−a)×(c−a)` keeps pointing out of the model.
//! Normals go through the inverse transpose of the transform. The scene's
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
//! normal, occlusion and emissive textures (and the extensions' textures), a base-colour texture on
//! another coordinate set than 0, alpha (`alphaMode` is treated as
//! `OPAQUE`), and every other extension the file uses. An extension the file
//! *requires* and rt-view does not know is an error. Samplers' filters are
//! not used: textures are always filtered bilinearly.
//!
//! **Bad input.** Every accessor is checked before it is read (type, count,
//! stride, and that it lies inside its buffer view and buffer), every index
//! against the vertex count, and the node hierarchy's depth and instance
//! count are bounded, so a malformed or truncated file is an
//! error naming the mesh and primitive, never a panic. A base-colour texture
//! that cannot be read is a warning; the material keeps its factor.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::mesh::Mode;
use ::gltf::texture::WrappingMode;
use glam::{DMat3, DMat4, DVec3};

use crate::files::model::{Model, ModelError};
use crate::geometry::mesh::{MAX_MESH_TRIANGLES, Mesh};
use crate::materials::material::Material;
use crate::materials::principled::Principled;
use crate::materials::texture::{Texture, Wrap};
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
const KNOWN_EXTENSIONS: [&str; 6] = [
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_volume",
    "KHR_materials_clearcoat",
];

/// Reads the glTF file at `path`, then scales every vertex by `scale` and
/// moves it by `translate`.
pub fn load(path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    let bytes = read_limited(path, MAX_GLTF_BYTES)
        .map_err(|reason| ModelError::Gltf { path: path.to_owned(), reason })?;
    from_slice(&bytes, path, scale, translate)
}

/// [`load`] for a file's bytes already read; `path` names it in errors, and
/// its folder is where the files it refers to are looked for.
pub fn from_slice(bytes: &[u8], path: &Path, scale: Real, translate: Vec3) -> Result<Model, ModelError> {
    read(bytes, path, scale, translate, true)
}

/// The glTF file at `path` as one mesh, for a scene that gives it its own
/// material: [`load`] without reading the materials or decoding textures,
/// the parts concatenated in their order; with the files it refers to
/// ([`Model::files`]).
pub fn load_geometry(path: &Path, scale: Real, translate: Vec3) -> Result<(Mesh, Vec<PathBuf>), ModelError> {
    let err = |reason: String| ModelError::Gltf { path: path.to_owned(), reason };
    let bytes = read_limited(path, MAX_GLTF_BYTES).map_err(err)?;
    let model = read(&bytes, path, scale, translate, false)?;
    let mesh = Mesh::concat(model.parts.into_iter().map(|(m, _)| m).collect())
        .ok_or_else(|| err("it has too many vertices".into()))?;
    Ok((mesh, model.files))
}

/// [`from_slice`], reading the materials and textures only `with_materials`.
fn read(
    bytes: &[u8],
    path: &Path,
    scale: Real,
    translate: Vec3,
    with_materials: bool,
) -> Result<Model, ModelError> {
    let err = |reason: String| ModelError::Gltf { path: path.to_owned(), reason };
    let ::gltf::Gltf { document, blob } = ::gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| err(format!("it cannot be read as glTF ({e}): a truncated or damaged file?")))?;
    // gltf-json's validation indexes the accessors with a POSITION
    // attribute's index unchecked (1.4.1, `primitive_validate_hook`): check
    // those first, then validate.
    let json = document.into_json();
    for required in &json.extensions_required {
        if !KNOWN_EXTENSIONS.contains(&required.as_str()) {
            return Err(err(format!("it requires the extension {required}, which rt-view does not support")));
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
            return Err(err(format!("{what} {k}: its URI {uri:?} is not percent-encoded UTF-8")));
        }
    }
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (k, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&::gltf::json::validation::Checked::Valid(::gltf::Semantic::Positions));
            if position.is_some_and(|a| a.value() >= json.accessors.len()) {
                return Err(err(format!("mesh {m} primitive {k}: its POSITION accessor does not exist")));
            }
        }
    }
    let gltf =
        ::gltf::Gltf { document: ::gltf::Document::from_json(json).map_err(|e| err(e.to_string()))?, blob };
    let mut warnings = Vec::new();
    for used in gltf.extensions_used() {
        if !KNOWN_EXTENSIONS.contains(&used) {
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
    let buffer_data = ::gltf::import_buffers(&document, Some(base), blob)
        .map_err(|e| err(format!("its buffers cannot be read: {e}")))?;
    let buffers: Vec<&[u8]> = buffer_data.iter().map(|b| &b.0[..]).collect();

    let Some(scene) = document.default_scene().or_else(|| document.scenes().next()) else {
        return Err(err("it has no scene".into()));
    };
    // glTF's world → rt-view's: mirror z, then the scene's scale.
    let mirror = DMat4::from_scale(DVec3::new(1.0, 1.0, -1.0));
    let place = DMat4::from_scale(DVec3::splat(to_f64(scale)));
    let mut groups: Vec<Group> = Vec::new();
    let mut group_of: HashMap<Option<usize>, usize> = HashMap::new();
    let mut triangles = 0usize;
    let mut stack: Vec<(::gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, place * mirror, 1)).collect();
    let mut visits = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > MAX_NODE_DEPTH {
            return Err(err(format!("its node hierarchy is deeper than {MAX_NODE_DEPTH} levels (a cycle?)")));
        }
        // A node may be reached along many paths (a child listed twice, or
        // by several parents): each is an instance. Bound the work.
        visits += 1;
        if visits > MAX_NODE_INSTANCES {
            return Err(err(format!(
                "its node hierarchy places more than {MAX_NODE_INSTANCES} node instances"
            )));
        }
        let matrix = parent * DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        if let Some(mesh) = node.mesh() {
            for primitive in mesh.primitives() {
                let at = || {
                    format!(
                        "mesh {} primitive {}",
                        describe(Some(mesh.index()), mesh.name()),
                        primitive.index()
                    )
                };
                let material = primitive.material().index();
                let g = *group_of.entry(material).or_insert_with(|| {
                    groups.push(Group { material, ..Group::default() });
                    groups.len() - 1
                });
                let added = read_primitive(&primitive, &buffers, &matrix, translate, &mut groups[g])
                    .map_err(|reason| err(format!("{}: {reason}", at())))?;
                triangles += added;
                if triangles > MAX_MESH_TRIANGLES {
                    return Err(err(format!("it has more than {MAX_MESH_TRIANGLES} triangles")));
                }
            }
        }
        stack.extend(node.children().map(|c| (c, matrix, depth + 1)));
    }
    if groups.is_empty() {
        return Err(err("its scene has no meshes".into()));
    }
    // Parts in the order of the file's materials, faces without one last.
    groups.sort_by_key(|g| g.material.map_or(usize::MAX, |m| m));

    let mut materials = Vec::new();
    let mut textures = Vec::new();
    let mut texture_of: HashMap<usize, Option<u32>> = HashMap::new();
    let mut parts = Vec::new();
    for g in groups {
        let mesh = Mesh::new(g.positions, g.triangles)
            .and_then(|m| m.with_vertex_attributes(g.normals, g.uvs))
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
        if let Some(info) = m.pbr_metallic_roughness().base_color_texture() {
            if info.tex_coord() != 0 {
                notes.push(format!("its base colour texture uses TEXCOORD_{}", info.tex_coord()));
            } else {
                let t = info.texture();
                material.texture = *texture_of.entry(t.index()).or_insert_with(|| {
                    match read_texture(&t, base, &buffer_data) {
                        Ok(texture) => {
                            textures.push(texture);
                            Some(textures.len() as u32 - 1)
                        }
                        Err(reason) => {
                            warnings.push(format!(
                                "texture {}: {reason}: its materials show their base colour factor instead",
                                t.index()
                            ));
                            None
                        }
                    }
                });
            }
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
    files.extend(document.images().filter_map(|i| match i.source() {
        ::gltf::image::Source::Uri { uri, .. } => base_file(Some(uri)),
        ::gltf::image::Source::View { .. } => None,
    }));
    Ok(Model { parts, materials, textures, warnings, files })
}

/// The faces of one material, gathered over every primitive that uses it.
#[derive(Default)]
struct Group {
    material: Option<usize>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<[f32; 2]>,
    triangles: Vec<[u32; 3]>,
    /// Whether any primitive so far had normals / texture coordinates.
    has_normals: bool,
    has_uvs: bool,
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
    check_accessor(&position, "POSITION", Dimensions::Vec3, &[DataType::F32], buffers)?;
    let normal = primitive.get(&::gltf::Semantic::Normals);
    if let Some(a) = &normal {
        check_accessor(a, "NORMAL", Dimensions::Vec3, &[DataType::F32], buffers)?;
    }
    let texcoord = primitive.get(&::gltf::Semantic::TexCoords(0));
    if let Some(a) = &texcoord {
        check_accessor(
            a,
            "TEXCOORD_0",
            Dimensions::Vec2,
            &[DataType::F32, DataType::U8, DataType::U16],
            buffers,
        )?;
        if a.data_type() != DataType::F32 && !a.normalized() {
            return Err("TEXCOORD_0 of integers must be normalized".into());
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
    for (i, p) in reader.read_positions().ok_or("POSITION cannot be read")?.enumerate() {
        let q = matrix.transform_point3(DVec3::from_array(p.map(f64::from))) + t;
        let q = narrow(q);
        if !q.is_finite() {
            return Err(format!("vertex {i} is not finite"));
        }
        group.positions.push(q);
    }
    match reader.read_normals() {
        Some(normals) => {
            if !group.has_normals {
                group.normals.resize(base, Vec3::ZERO);
                group.has_normals = true;
            }
            group
                .normals
                .extend(normals.map(|n| narrow(normal_matrix * DVec3::from_array(n.map(f64::from)))));
        }
        None if group.has_normals => group.normals.resize(base + count, Vec3::ZERO),
        None => {}
    }
    match reader.read_tex_coords(0) {
        Some(uvs) => {
            if !group.has_uvs {
                group.uvs.resize(base, [0.0; 2]);
                group.has_uvs = true;
            }
            group.uvs.extend(uvs.into_f32());
        }
        None if group.has_uvs => group.uvs.resize(base + count, [0.0; 2]),
        None => {}
    }
    if group.positions.len() != base + count
        || (group.has_normals && group.normals.len() != base + count)
        || (group.has_uvs && group.uvs.len() != base + count)
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
    let [r, g, b, _] = pbr.base_color_factor();
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
    let material =
        Material { ior, emission: Color::new(e(r), e(g), e(b)) * strength, ..Material::principled(base, p) };
    let mut notes = notes.into_inner();
    if pbr.metallic_roughness_texture().is_some() {
        notes.push("metallicRoughnessTexture".to_owned());
    }
    if m.normal_texture().is_some() {
        notes.push("normalTexture".to_owned());
    }
    if m.occlusion_texture().is_some() {
        notes.push("occlusionTexture".to_owned());
    }
    if m.emissive_texture().is_some() {
        notes.push("emissiveTexture".to_owned());
    }
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
    if m.alpha_mode() != ::gltf::material::AlphaMode::Opaque {
        notes.push(format!("alphaMode {:?} (the surface is opaque)", m.alpha_mode()));
    }
    (material, notes)
}

/// The texture's image, decoded, with its sampler's wrap modes.
fn read_texture(
    t: &::gltf::Texture,
    base: &Path,
    buffers: &[::gltf::buffer::Data],
) -> Result<Texture, String> {
    let image = t.source();
    if let ::gltf::image::Source::View { view, .. } = image.source() {
        let inside = view
            .offset()
            .checked_add(view.length())
            .is_some_and(|end| end <= buffers.get(view.buffer().index()).map_or(0, |b| b.0.len()));
        if !inside {
            return Err(format!("image {} runs past the end of its buffer", image.index()));
        }
    }
    let decoded =
        ::gltf::image::Data::from_source(image.source(), Some(base), buffers).map_err(|e| e.to_string())?;
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
    let wrap = |m: WrappingMode| match m {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
    };
    let sampler = t.sampler();
    Texture::from_srgb(decoded.width, decoded.height, channels, &values)
        .map(|tex| tex.with_wrap([wrap(sampler.wrap_s()), wrap(sampler.wrap_t())]))
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
                "pbrMetallicRoughness": { "baseColorFactor": [1.0, 0.5, 0.25, 1.0], "metallicFactor": 0.5, "roughnessFactor": 0.3 },
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
        assert_eq!(model.warnings.len(), 2, "{:?}", model.warnings);
        assert!(model.warnings[0].contains("KHR_texture_transform"));
        assert!(model.warnings[1].contains("alphaMode Blend"));
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
        assert_eq!(model.materials[0].1.texture, Some(0));
        let t = &model.textures[0];
        // Clamped in u: far right is the white texel, far left the black one.
        assert_eq!(t.sample(5.0, 0.5), Color::ONE);
        assert_eq!(t.sample(-5.0, 0.5), Color::ZERO);
    }

    #[test]
    fn a_missing_texture_file_is_a_warning_and_the_factor_stays() {
        let bytes = triangle_glb(|doc, _| {
            doc["images"] = json!([{ "uri": "nowhere.png" }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
        });
        let model = load_bytes(&bytes).unwrap();
        assert_eq!(model.materials[0].1.texture, None);
        assert_eq!(model.materials[0].1.color, Color::new(0.5, 0.25, 1.0));
        assert!(
            model.warnings.iter().any(|w| w.starts_with("texture 0:") && w.contains("base colour factor")),
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
        let (mesh, files) = load_geometry(&path, 1.0, Vec3::ZERO).unwrap();
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
        let e = error_of(|doc, _| doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]));
        assert!(e.contains("requires the extension KHR_draco_mesh_compression"), "{e}");
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
