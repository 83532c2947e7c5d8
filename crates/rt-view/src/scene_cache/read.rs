//! Reading a cache: the file mapped, checked section by section, and the
//! scene put back together from its parts ([`rt_core::Scene::from_parts`]).

use std::path::Path;
use std::sync::Arc;

use rt_core::bvh::parts::BvhArraysRef;
use rt_core::geometry::mesh::Mesh;
use rt_core::materials::texture::Texture;
use rt_core::scene::parts::SceneParts;
use rt_core::{Color, LoadedScene, Object, Primitive, Real, Scene, Vec3};

use super::cache_error::CacheError;
use super::format::{Kind, Reader};
use super::meta::{Meta, modified_ns, this_version};
use super::write::{Shape, Small};
use crate::content_hash::Fnv1a128;

/// The file at `path`, mapped into memory.
fn map(path: &Path) -> Result<memmap2::Mmap, CacheError> {
    let file = std::fs::File::open(path)?;
    // SAFETY: the map is read-only and private to this process; a file
    // changed under it by another process would change the bytes read,
    // which every read checks (checksums, then indices), never trusts.
    Ok(unsafe { memmap2::Mmap::map(&file)? })
}

/// The cache's record of where it came from, checked against this build
/// (format, number size, version) but not against the source files.
pub fn read_meta(path: &Path) -> Result<Meta, CacheError> {
    let file = map(path)?;
    let meta: Meta = Reader::new(&file)?.ron(Kind::Meta)?;
    check_version(&meta)?;
    Ok(meta)
}

fn check_version(meta: &Meta) -> Result<(), CacheError> {
    if meta.rt_view_version != this_version() {
        return Err(CacheError::Version { found: meta.rt_view_version.clone(), expected: this_version() });
    }
    Ok(())
}

/// The source files that are still there and differ from what the cache
/// was made of: of another length or content; one of the same length and
/// modification time is not read.
fn changed_sources(meta: &Meta) -> Vec<String> {
    meta.sources
        .iter()
        .filter_map(|s| {
            let metadata = std::fs::metadata(&s.path).ok()?;
            if metadata.len() == s.len && s.modified.is_some() && modified_ns(&metadata) == s.modified {
                return None;
            }
            let bytes = std::fs::read(&s.path).ok()?;
            let mut hash = Fnv1a128::default();
            hash.write(&bytes);
            (bytes.len() as u64 != s.len || hash.hex() != s.hash).then(|| s.path.display().to_string())
        })
        .collect()
}

/// Reads the cache at `path`: the loaded scene (equal to the one loaded
/// from the scene file) and where it came from.
pub fn read_cache(path: &Path) -> Result<(LoadedScene, Meta), CacheError> {
    let file = map(path)?;
    decode(&file)
}

/// [`read_cache`] of the cache's bytes.
pub fn decode(file: &[u8]) -> Result<(LoadedScene, Meta), CacheError> {
    let mut r = Reader::new(file)?;
    let meta: Meta = r.ron(Kind::Meta)?;
    check_version(&meta)?;
    let changed = changed_sources(&meta);
    if !changed.is_empty() {
        return Err(CacheError::Stale(changed));
    }
    let small: Small = r.cbor(Kind::Small)?;
    let corrupt = |what: String| CacheError::Corrupt(what);
    let vec3s = |v: &[Real]| v.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect::<Vec<_>>();
    let mut meshes = Vec::with_capacity(small.meshes.len());
    for (i, m) in small.meshes.iter().enumerate() {
        let count = |n: usize, k: usize| n.checked_mul(k).ok_or_else(|| corrupt(format!("mesh {i}: size")));
        let either = |has: bool, n: usize, k: usize| if has { count(n, k) } else { Ok(0) };
        let positions = vec3s(r.array::<Real>(Some(count(m.positions, 3)?))?);
        let triangles: Vec<[u32; 3]> = r
            .array::<u32>(Some(count(m.triangles, 3)?))?
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let normals = vec3s(r.array::<Real>(Some(count(m.triangles, 3)?))?);
        let vertex_normals = vec3s(r.array::<Real>(Some(either(m.vertex_normals, m.positions, 3)?))?);
        let uvs = r
            .array::<f32>(Some(either(m.uvs, m.positions, 2)?))?
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let uvs1 = r
            .array::<f32>(Some(either(m.uvs1, m.positions, 2)?))?
            .chunks_exact(2)
            .map(|c| [c[0], c[1]])
            .collect();
        let tangents = r
            .array::<f32>(Some(either(m.tangents, m.positions, 4)?))?
            .chunks_exact(4)
            .map(|c| [c[0], c[1], c[2], c[3]])
            .collect();
        let mesh =
            Mesh::from_arrays(positions, triangles, normals, m.bounds, vertex_normals, uvs, uvs1, tangents)
                .ok_or_else(|| {
                corrupt(format!("mesh {i}: an index out of range or a list of the wrong length"))
            })?;
        meshes.push(Some(mesh));
    }
    let mut textures = Vec::with_capacity(small.textures.len());
    for (i, t) in small.textures.iter().enumerate() {
        let mut levels = Vec::with_capacity(t.levels.len());
        for &(w, h, alpha) in &t.levels {
            let n =
                (w as usize).checked_mul(h as usize).ok_or_else(|| corrupt(format!("texture {i}: size")))?;
            let texels = r.array::<f32>(Some(n.saturating_mul(3)))?;
            let texels = texels.chunks_exact(3).map(|c| Color::new(c[0], c[1], c[2])).collect();
            let alpha = r.array::<f32>(Some(if alpha { n } else { 0 }))?.to_vec();
            levels.push((w, h, texels, alpha));
        }
        let texture = Texture::from_levels(levels, t.wrap)
            .ok_or_else(|| corrupt(format!("texture {i}: levels of the wrong sizes")))?;
        textures.push(Arc::new(texture));
    }
    let bvh = BvhArraysRef {
        node_bounds: r.array::<Real>(None)?,
        node_children: r.array::<u32>(None)?,
        leaf_corners: r.array::<Real>(None)?,
        leaf_ids: r.array::<u32>(None)?,
        unbounded: r.array::<u32>(None)?,
        bounds: small.bvh_bounds,
        sah_cost: small.sah_cost,
    };
    if !r.at_end() {
        return Err(corrupt("sections after the last one expected".into()));
    }
    let mut objects = Vec::with_capacity(small.objects.len());
    for (index, (shape, material)) in small.objects.into_iter().enumerate() {
        let primitive = match shape {
            Shape::Mesh(m) => {
                Primitive::Mesh(meshes.get_mut(m).and_then(Option::take).ok_or_else(|| {
                    corrupt(format!("objects[{index}]: mesh {m} is not there or used twice"))
                })?)
            }
            Shape::Primitive(p) => p,
        };
        objects.push(Object { primitive, material });
    }
    let parts = SceneParts {
        environment: small.environment,
        lights: small.lights,
        ambient: small.ambient,
        methods: small.methods,
        materials: small.materials,
        material_names: small.material_names,
        textures,
        objects,
        source_files: small.source_files,
        warnings: small.warnings,
    };
    let scene = Scene::from_parts(parts, bvh).map_err(|e| corrupt(e.to_string()))?;
    // The image size and samples checked as the scene file's are.
    let settings = small
        .settings
        .overridden(None, None, Some(small.settings.samples.get()))
        .map_err(|e| corrupt(format!("settings: {e}")))?;
    Ok((LoadedScene { scene, camera: small.camera, settings }, meta))
}
