//! Arbitrary bytes as a glTF file (JSON or binary): loading must never
//! panic, hang or allocate without bound, and a model that loads has finite
//! vertices, unit or zero shading normals and materials the scene accepts.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rt_core::Vec3;

fuzz_target!(|data: &[u8]| {
    // External buffers and images resolve under a folder that does not exist.
    let name = Path::new("/nonexistent-fuzz-dir/model.glb");
    let Ok(model) = rt_core::files::gltf_model::from_slice(data, name, 1.0, Vec3::ZERO) else { return };
    for (mesh, material) in &model.parts {
        assert!(mesh.bounds().min().is_finite() && mesh.bounds().max().is_finite());
        assert!(material.is_none_or(|m| m < model.materials.len()));
        for i in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(i);
            let centre = (a + b + c) / 3.0;
            if let Some(n) = mesh.shading_normal(i, centre) {
                assert!((n.length() - 1.0).abs() < 1e-3, "shading normal {n}");
            }
        }
    }
    for (_, m) in &model.materials {
        assert!(m.color.max_element() <= 1.0 && m.specular_color.max_element() <= 1.0);
        assert!(m.reflectivity + m.transparency <= 1.0 + 1e-6);
        assert!(m.texture_slots().all(|s| (s.texture as usize) < model.textures.len()));
    }
});
