//! Real glTF files' JSON damaged by structure (numbers changed, keys
//! dropped, types swapped, indices past the end; the mutations of
//! `crates/rt-core/src/files/gltf_mutation.rs`), the fuzzer's bytes choosing
//! the file and every mutation: loading the model, its lights and its camera
//! must never panic, and a model that loads has finite vertices and
//! materials that exist. The byte-level `gltf` target rarely gets past the
//! JSON parser; this one starts from documents that parse.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rt_core::Vec3;
use rt_core::files::gltf_model;

// Only `Choices::Bytes` is used here; the unit tests use `Seeded`.
#[allow(dead_code)]
#[path = "../../crates/rt-core/src/files/gltf_mutation.rs"]
mod gltf_mutation;

use gltf_mutation::{Choices, mutate};

/// The real files mutated: `.glb` (JSON chunk mutated, BIN chunk kept) and
/// `.gltf` texts.
const FILES: [&[u8]; 5] = [
    include_bytes!("../corpus/gltf/blender-like.glb"),
    include_bytes!("../corpus/gltf/meshopt.glb"),
    include_bytes!("../corpus/gltf/triangle.glb"),
    include_bytes!("../corpus/gltf/blender-like.gltf"),
    include_bytes!("../corpus/gltf/triangle.gltf"),
];

/// The JSON and BIN chunks of a `.glb`, or the whole text of a `.gltf`.
fn split(file: &[u8]) -> Option<(serde_json::Value, Option<Vec<u8>>)> {
    if !file.starts_with(b"glTF") {
        return serde_json::from_slice(file).ok().map(|v| (v, None));
    }
    let length = u32::from_le_bytes(file.get(12..16)?.try_into().ok()?) as usize;
    let json = serde_json::from_slice(file.get(20..20 + length)?).ok()?;
    Some((json, Some(file.get(28 + length..).unwrap_or_default().to_vec())))
}

fuzz_target!(|data: &[u8]| {
    let mut choices = Choices::Bytes(data);
    let Some((mut doc, bin)) = split(FILES[choices.below(FILES.len())]) else { return };
    let count = 1 + choices.below(6);
    mutate(&mut doc, count, &mut choices);
    let bytes = match &bin {
        Some(bin) => gltf_model::encode_glb(&doc.to_string(), bin),
        None => doc.to_string().into_bytes(),
    };
    // External buffers and images resolve under a folder that does not exist.
    let name = Path::new("/nonexistent-fuzz-dir/model.glb");
    if let Ok(model) = gltf_model::from_slice(&bytes, name, 1.0, Vec3::ZERO) {
        for (mesh, material) in &model.parts {
            assert!(mesh.bounds().min().is_finite() && mesh.bounds().max().is_finite());
            assert!(material.is_none_or(|m| m < model.materials.len()));
        }
    }
    // Lights and cameras are read from a file on disk.
    let dir = std::env::temp_dir().join(format!("rt-fuzz-gltf-json-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(if bin.is_some() { "model.glb" } else { "model.gltf" });
    if std::fs::write(&path, &bytes).is_ok() {
        let _ = gltf_model::load_with_lights(&path, 1.0, Vec3::ZERO, true);
        let _ = gltf_model::camera(&path, 0, 1.0, Vec3::ZERO);
    }
});
