//! Arbitrary bytes as a scene file: loading must never panic, hang or allocate
//! without bound, and a scene that loads must render an 8×6 image and answer
//! rays with finite, consistent hits.
#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use rt_core::{Ray, Renderer, Vec3};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    // OBJ paths resolve under a folder that does not exist: no file is read.
    let Ok(loaded) = rt_core::parse_scene(text, "fuzz.ron", Path::new("/nonexistent-fuzz-dir")) else {
        return;
    };
    let scene = &loaded.scene;
    let settings = loaded.settings.overridden(Some(8), Some(6), Some(1)).expect("8x6 at 1 spp is in range");
    if let Ok(renderer) = Renderer::new(scene, loaded.camera, &settings) {
        let frame = renderer.render(|_| {});
        assert_eq!(frame.pixels.len(), 48);
    }
    for dir in [Vec3::X, -Vec3::Y, Vec3::new(0.3, -0.2, 1.0)] {
        let ray = Ray::new(loaded.camera.position(), dir);
        if let Some(hit) = scene.cast(&ray) {
            assert!(hit.t.is_finite() && hit.t > 0.0, "t = {}", hit.t);
            assert!((hit.normal.length() - 1.0).abs() < 1e-4, "normal {}", hit.normal);
            assert!(hit.object < scene.objects().len());
        }
    }
});
