//! The cache gives the scene file's images bit for bit, and refuses what
//! it must: damage and truncation (never a panic), another format or
//! version, changed source files.

use std::path::{Path, PathBuf};

use super::format::{FORMAT_VERSION, MAGIC};
use super::read::decode;
use super::write::cache_bytes_as;
use super::*;

fn scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// The scene's pixels at a small size, from the scene file and from its cache.
fn both_renders(name: &str) -> (Vec<rt_core::Color>, Vec<rt_core::Color>) {
    let path = scenes().join(name);
    let loaded = rt_core::load_scene(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("scene.rtc");
    prepare(&path, &cache).unwrap();
    assert!(is_cache(&cache) && !is_cache(&path));
    let cached = load_scene(&cache).unwrap();
    assert_eq!(cached.camera, loaded.camera);
    assert_eq!(cached.settings, loaded.settings);
    assert_eq!(cached.scene.objects(), loaded.scene.objects());
    assert_eq!(cached.scene.materials(), loaded.scene.materials());
    assert_eq!(cached.scene.environment(), loaded.scene.environment());
    assert_eq!(cached.scene.emitters(), loaded.scene.emitters());
    assert_eq!(cached.scene.light_sampler(), loaded.scene.light_sampler());
    let render = |l: &rt_core::LoadedScene| {
        let settings = l.settings.overridden(Some(24), Some(18), Some(3)).unwrap();
        rt_core::Renderer::new(&l.scene, l.camera, &settings).unwrap().render(|_| {}).pixels
    };
    (render(&loaded), render(&cached))
}

fn bits(pixels: &[rt_core::Color]) -> Vec<[u32; 3]> {
    pixels.iter().map(|c| c.to_array().map(f32::to_bits)).collect()
}

#[test]
fn images_from_a_cache_equal_the_scene_files_bit_for_bit() {
    // Spheres and boxes, global illumination, an OBJ mesh with MTL
    // materials, a textured normal-mapped glTF model, an environment map.
    for name in
        ["box.ron", "cornell_box.ron", "mesh.ron", "models.ron", "cycles_normal_map.ron", "studio.ron"]
    {
        let (from_file, from_cache) = both_renders(name);
        assert_eq!(bits(&from_file), bits(&from_cache), "{name}");
    }
}

#[test]
fn the_bvh_from_a_cache_is_the_built_one() {
    let loaded = rt_core::load_scene(&scenes().join("models.ron")).unwrap();
    let bytes = cache_bytes(&scenes().join("models.ron"), &loaded).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("m.rtc");
    std::fs::write(&cache, bytes).unwrap();
    let cached = load_scene(&cache).unwrap();
    // Byte for byte: unused leaf lanes hold NaN corners.
    let (a, b) = (cached.scene.bvh_arrays(), loaded.scene.bvh_arrays());
    let bytes = |v: &[rt_core::Real]| bytemuck::cast_slice::<_, u8>(v).to_vec();
    assert!(
        bytes(&a.node_bounds) == bytes(&b.node_bounds) && bytes(&a.leaf_corners) == bytes(&b.leaf_corners)
    );
    assert!(a.node_children == b.node_children && a.leaf_ids == b.leaf_ids && a.unbounded == b.unbounded);
    assert_eq!((a.bounds, a.sah_cost), (b.bounds, b.sah_cost));
    let (a, b) = (cached.scene.bvh_stats(), loaded.scene.bvh_stats());
    assert_eq!(
        (a.nodes, a.leaves, a.leaf_blocks, a.depth, a.primitives),
        (b.nodes, b.leaves, b.leaf_blocks, b.depth, b.primitives)
    );
}

/// A real cache's bytes (a textured glTF model: meshes, textures and a BVH).
fn real_cache() -> Vec<u8> {
    let path = scenes().join("cycles_normal_map.ron");
    cache_bytes(&path, &rt_core::load_scene(&path).unwrap()).unwrap()
}

/// Decodes `bytes` from a file (mapped, as commands read caches).
fn decode_file(bytes: &[u8]) -> Result<(rt_core::LoadedScene, Meta), CacheError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("c.rtc");
    std::fs::write(&path, bytes).unwrap();
    read_cache(&path)
}

#[test]
fn a_truncated_cache_is_an_error_at_every_length() {
    let bytes = real_cache();
    assert!(decode_file(&bytes).is_ok());
    let step = (bytes.len() / 300).max(1);
    for len in (0..bytes.len()).step_by(step).chain([bytes.len() - 64, bytes.len() - 1]) {
        match decode_file(&bytes[..len]) {
            Err(CacheError::Corrupt(_)) => {}
            // Too short to hold the magic: not a cache at all.
            Err(CacheError::NotACache) if len < MAGIC.len() => {}
            // The last bytes are alignment padding.
            Ok(_) if bytes[len..].iter().all(|&b| b == 0) => {}
            other => panic!("truncated to {len} of {}: {:?}", bytes.len(), other.map(|_| ())),
        }
    }
}

#[test]
fn a_damaged_cache_is_an_error_never_a_panic() {
    let bytes = real_cache();
    let step = (bytes.len() / 400).max(1);
    let mut refused = 0;
    for at in (8..bytes.len()).step_by(step).chain(8..200) {
        let mut damaged = bytes.clone();
        damaged[at] ^= 0x5a;
        // Bytes between sections (alignment) are no part of the scene.
        match decode(&damaged) {
            Ok(_) => {}
            Err(
                CacheError::Corrupt(_) | CacheError::FormatVersion { .. } | CacheError::NumberSize { .. },
            ) => refused += 1,
            Err(e) => panic!("byte {at} flipped: {e}"),
        }
    }
    assert!(refused > 300, "{refused}");
}

#[test]
fn another_format_or_version_is_refused_by_name() {
    let mut bytes = real_cache();
    bytes[8..12].copy_from_slice(&(FORMAT_VERSION + 1).to_le_bytes());
    let e = decode(&bytes).map(|_| ()).unwrap_err();
    assert!(matches!(e, CacheError::FormatVersion { .. }), "{e}");
    assert!(e.to_string().contains("prepare it again"), "{e}");

    let path = scenes().join("box.ron");
    let old = cache_bytes_as(&path, &rt_core::load_scene(&path).unwrap(), "0.0.1").unwrap();
    let e = decode(&old).map(|_| ()).unwrap_err();
    assert!(e.to_string().contains("written by rt-view 0.0.1"), "{e}");

    let e = decode(b"(camera: ...)").map(|_| ()).unwrap_err();
    assert!(matches!(e, CacheError::NotACache), "{e}");
}

#[test]
fn a_cache_whose_mesh_changed_is_stale_and_names_it_but_one_whose_sources_are_gone_loads() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(scenes().join("mesh.ron"), dir.path().join("mesh.ron")).unwrap();
    std::fs::create_dir(dir.path().join("meshes")).unwrap();
    for mesh in ["icosphere.obj", "torus.obj"] {
        std::fs::copy(scenes().join("meshes").join(mesh), dir.path().join("meshes").join(mesh)).unwrap();
    }
    let cache = dir.path().join("mesh.rtc");
    prepare(&dir.path().join("mesh.ron"), &cache).unwrap();
    assert!(load_scene(&cache).is_ok());
    let torus = dir.path().join("meshes/torus.obj");
    let text = std::fs::read_to_string(&torus).unwrap();
    std::fs::write(&torus, text.replacen("v ", "v  ", 1)).unwrap();
    let e = read_cache(&cache).map(|_| ()).unwrap_err();
    assert!(
        matches!(&e, CacheError::Stale(files) if files.len() == 1 && files[0].ends_with("torus.obj")),
        "{e}"
    );
    let message = load_scene(&cache).map(|_| ()).unwrap_err().to_string();
    assert!(
        message.contains("mesh.rtc") && message.contains("stale") && message.contains("torus.obj"),
        "{message}"
    );
    // A task on a machine that has the cache alone.
    std::fs::remove_dir_all(dir.path().join("meshes")).unwrap();
    std::fs::remove_file(dir.path().join("mesh.ron")).unwrap();
    assert!(load_scene(&cache).is_ok());
}

#[test]
fn parts_from_a_cache_carry_the_scene_files_content_hash() {
    let path = scenes().join("models.ron");
    let loaded = rt_core::load_scene(&path).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("models.rtc");
    prepare(&path, &cache).unwrap();
    assert_eq!(scene_hash(&cache, &loaded.scene).unwrap(), scene_hash(&path, &loaded.scene).unwrap());
}
