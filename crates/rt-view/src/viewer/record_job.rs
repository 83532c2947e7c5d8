//! The record of the pinned pixel's chosen sample, computed off the UI
//! thread: the renderer the window's image is rendered with (the scene,
//! its settings with the user's effect toggles, the camera, size and
//! samples per pixel of the full-resolution job, and its open-ended
//! sampler when the render has no sample limit) runs that one sample
//! with a recorder ([`rt_core::Renderer::record_sample`]). Its record adds
//! up to the sample's value in the render bit for bit.

use std::sync::Arc;
use std::sync::mpsc::{self, Receiver};

use rt_core::explain::record::PathRecord;
use rt_core::{Camera, LoadedScene, RenderSettings, Renderer};

use super::render_job::JobSpec;

/// Which sample of which pixel of which render to record.
#[derive(Clone, Debug, PartialEq)]
pub struct RecordKey {
    scene: usize,
    camera: Camera,
    size: (u32, u32),
    spp: u32,
    open_ended: bool,
    toggles: rt_core::scene::effects::EffectToggles,
    /// The pixel.
    pub pixel: [u32; 2],
    /// The sample, below the samples per pixel.
    pub sample: u32,
}

impl RecordKey {
    /// Sample `sample` of `pixel` in the render `spec` describes.
    pub fn new(spec: &JobSpec, pixel: [u32; 2], sample: u32) -> Self {
        Self {
            scene: Arc::as_ptr(&spec.scene) as usize,
            camera: spec.camera,
            size: (spec.width, spec.height),
            spp: spec.spp,
            open_ended: spec.open_ended,
            toggles: spec.toggles,
            pixel,
            sample,
        }
    }
}

/// One record being computed on a thread of its own.
pub struct RecordJob {
    key: RecordKey,
    done: Receiver<Result<PathRecord, String>>,
}

impl RecordJob {
    /// Starts recording `key`'s sample of the render `spec` describes;
    /// `on_done` runs once the record is ready (the viewer repaints).
    pub fn start(spec: &JobSpec, key: RecordKey, on_done: impl FnOnce() + Send + 'static) -> Self {
        let (tx, done) = mpsc::channel();
        let (scene, toggles, camera) = (spec.scene.clone(), spec.toggles, spec.camera);
        let (width, height, spp) = (spec.width, spec.height, spec.spp);
        let open_ended = spec.open_ended;
        let [x, y] = key.pixel;
        let sample = key.sample;
        std::thread::Builder::new()
            .name("path-record".into())
            .spawn(move || {
                let record =
                    record(&scene, camera, toggles, (width, height, spp, open_ended), [x, y], sample);
                if tx.send(record).is_ok() {
                    on_done();
                }
            })
            .expect("the OS can start a thread");
        Self { key, done }
    }

    /// What it records.
    pub fn key(&self) -> &RecordKey {
        &self.key
    }

    /// The record (or why there is none), once ready; never waits.
    pub fn take(&self) -> Option<Result<PathRecord, String>> {
        self.done.try_recv().ok()
    }
}

/// Records sample `sample` of pixel (x, y) of `scene` rendered with
/// `camera` at `width`×`height`, `spp` samples per pixel (its first `spp`
/// samples, with the open-ended sampler if `open_ended`).
fn record(
    scene: &LoadedScene,
    camera: Camera,
    toggles: rt_core::scene::effects::EffectToggles,
    (width, height, spp, open_ended): (u32, u32, u32, bool),
    [x, y]: [u32; 2],
    sample: u32,
) -> Result<PathRecord, String> {
    let settings = RenderSettings { toggles, ..scene.settings }
        .overridden(Some(width), Some(height), Some(spp))
        .map_err(|e| e.to_string())?;
    let renderer = Renderer::new(&scene.scene, camera, &settings).map_err(|e| e.to_string())?;
    let renderer = if open_ended { renderer.open_ended() } else { renderer };
    renderer.record_sample(x, y, sample).ok_or_else(|| {
        format!("no sample {sample} of pixel ({x}, {y}) in a {width}×{height} image at {spp} spp")
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_record_is_the_samples_value_in_the_windows_render() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/box.ron");
        let scene = Arc::new(rt_core::load_scene(&path).unwrap());
        let spec = JobSpec {
            scene: scene.clone(),
            camera: scene.camera,
            width: 64,
            height: 48,
            spp: 1,
            open_ended: false,
            region: None,
            toggles: Default::default(),
            denoise: false,
        };
        let key = RecordKey::new(&spec, [32, 24], 0);
        let job = RecordJob::start(&spec, key.clone(), || ());
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
        let record = loop {
            if let Some(r) = job.take() {
                break r.unwrap();
            }
            assert!(std::time::Instant::now() < deadline);
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert_eq!(record.pixel, [32, 24]);
        // The render of the same job's first pass has that value at the pixel.
        let settings = scene.settings.overridden(Some(64), Some(48), Some(1)).unwrap();
        let frame = Renderer::new(&scene.scene, scene.camera, &settings).unwrap().render(|_| ());
        assert_eq!(frame.pixels[24 * 64 + 32], record.value);
        let beyond = RecordJob::start(&spec, RecordKey::new(&spec, [32, 24], 1), || ());
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
        let refused = loop {
            if let Some(r) = beyond.take() {
                break r;
            }
            assert!(std::time::Instant::now() < deadline);
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        assert!(refused.unwrap_err().contains("no sample 1"));
    }

    #[test]
    fn with_no_sample_limit_the_record_follows_the_open_ended_sampler_of_the_windows_render() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/antialiasing.ron");
        let scene = rt_core::load_scene(&path).unwrap();
        let settings = scene.settings.overridden(Some(48), Some(36), Some(4)).unwrap();
        let fixed = Renderer::new(&scene.scene, scene.camera, &settings).unwrap();
        let open = Renderer::new(&scene.scene, scene.camera, &settings).unwrap().open_ended();
        let mut differs = false;
        for y in (0..36).step_by(3) {
            for x in 0..48 {
                let toggles = Default::default();
                let got = record(&scene, scene.camera, toggles, (48, 36, 4, true), [x, y], 2).unwrap();
                assert_eq!(Some(got.value), open.record_sample(x, y, 2).map(|r| r.value), "pixel ({x}, {y})");
                differs |= fixed.record_sample(x, y, 2).map(|r| r.value) != Some(got.value);
            }
        }
        assert!(differs, "the two samplers never differ here: the test shows nothing");
    }
}
