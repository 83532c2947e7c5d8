//! The scene as the observer sees it: rt-core's own ray casts, flat-shaded,
//! at a modest resolution, rendered on a thread of its own.
//!
//! Each pixel's centre ray ([`ViewPlane::center_ray`]) is cast with
//! [`rt_core::Scene::cast`]; a hit shows its material's colour
//! ([`rt_core::Scene::hit_color`]) scaled by `AMBIENT + (1 − AMBIENT)·|n·d|`
//! (`d` the unit ray direction), so faces turned away from the observer
//! read darker and shapes stay legible without any light; a miss shows a
//! dark grey. No lights, shadows or bounces: the view is for seeing where
//! things are, the image beside it for how they look.
//!
//! [`ObserverJob`] renders one such image in the background and hands it
//! over whole; the UI thread only polls it ([`ObserverJob::take`]), never
//! waits. It renders on its own thread, row after row, not on rayon's pool:
//! the image's render job keeps every rayon thread busy until it is done,
//! and the scene view must not wait for it.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver};

use egui::{Color32, ColorImage};
use rt_core::{Camera, LoadedScene, Scene, ViewPlane};

/// The share of a surface's colour it shows when seen edge-on.
const AMBIENT: f32 = 0.3;
/// What a pixel that sees nothing shows.
const EMPTY: Color32 = Color32::from_rgb(40, 42, 46);

/// Renders `scene` seen by `camera` as a flat-shaded `size` image (see the
/// module's docs); `None` if `cancel` was set meanwhile or the camera has
/// no view plane at that size.
#[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
pub fn flat_render(scene: &Scene, camera: Camera, size: [u32; 2], cancel: &AtomicBool) -> Option<ColorImage> {
    let view = ViewPlane::new(camera, size[0], size[1]).ok()?;
    let (w, h) = (size[0] as usize, size[1] as usize);
    let mut pixels = vec![EMPTY; w * h];
    for (y, row) in pixels.chunks_mut(w).enumerate() {
        if cancel.load(Ordering::Relaxed) {
            return None;
        }
        for (x, pixel) in row.iter_mut().enumerate() {
            let ray = view.center_ray(x as u32, y as u32);
            if let Some(hit) = scene.cast(&ray) {
                let facing = hit.normal.dot(ray.dir.normalize_or_zero()).abs() as f32;
                let shade = AMBIENT + (1.0 - AMBIENT) * facing;
                let c = scene.hit_color(&hit, &ray, 0.0).to_array();
                let byte = |v: f32| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0 + 0.5) as u8;
                *pixel = Color32::from_rgb(byte(c[0] * shade), byte(c[1] * shade), byte(c[2] * shade));
            }
        }
    }
    (!cancel.load(Ordering::Relaxed)).then(|| ColorImage::new(size.map(|s| s as usize), pixels))
}

/// One flat render in the background.
pub struct ObserverJob {
    cancel: Arc<AtomicBool>,
    done: Receiver<ColorImage>,
}

impl ObserverJob {
    /// Starts rendering `scene` seen by `camera` at `size` on a thread of
    /// its own; `on_done` runs once the image is ready (the viewer asks
    /// for a repaint).
    pub fn start(
        scene: Arc<LoadedScene>,
        camera: Camera,
        size: [u32; 2],
        on_done: impl FnOnce() + Send + 'static,
    ) -> Self {
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, done) = mpsc::channel();
        let flag = cancel.clone();
        std::thread::Builder::new()
            .name("scene-view".into())
            .spawn(move || {
                if let Some(image) = flat_render(&scene.scene, camera, size, &flag)
                    && tx.send(image).is_ok()
                {
                    on_done();
                }
            })
            .expect("the OS can start a thread");
        Self { cancel, done }
    }

    /// The image, once it is ready (taken once); never waits.
    pub fn take(&self) -> Option<ColorImage> {
        self.done.try_recv().ok()
    }

    /// Whether the job has ended without an image left to take
    /// (cancelled, or its image already taken).
    pub fn ended(&self) -> bool {
        matches!(self.done.try_recv(), Err(mpsc::TryRecvError::Disconnected))
    }
}

impl Drop for ObserverJob {
    fn drop(&mut self) {
        self.cancel.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_flat_render_shows_what_the_centre_ray_of_each_pixel_hits() {
        let loaded = rt_view_scene("sphere.ron");
        let camera = loaded.camera;
        let image = flat_render(&loaded.scene, camera, [64, 48], &AtomicBool::new(false)).unwrap();
        let view = ViewPlane::new(camera, 64, 48).unwrap();
        for (x, y) in [(0, 0), (32, 24), (63, 47), (10, 30)] {
            let hit = loaded.scene.cast(&view.center_ray(x, y));
            let pixel = image.pixels[y as usize * 64 + x as usize];
            assert_eq!(hit.is_none(), pixel == EMPTY, "pixel ({x}, {y})");
        }
        // The sphere faces the camera in the middle: its colour, hardly darkened.
        let middle = image.pixels[24 * 64 + 32];
        assert!(middle.r() > 200 && middle.g() < 120, "{middle:?}");
        // A cancelled render gives no image.
        assert!(flat_render(&loaded.scene, camera, [64, 48], &AtomicBool::new(true)).is_none());
    }

    fn rt_view_scene(name: &str) -> LoadedScene {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes").join(name);
        rt_core::load_scene(&path).unwrap()
    }
}
