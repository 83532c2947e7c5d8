//! The render loop: pixels → primary rays → closest hits → colours → rows → image.
//!
//! Rows are independent: [`Renderer::render_row`] fills one, and
//! [`Renderer::render`] fills all of them in parallel with rayon. The result
//! does not depend on the number of threads or the order rows finish in.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use thiserror::Error;

use crate::camera::Camera;
use crate::material::Color;
use crate::ray::Ray;
use crate::sampler::subpixel_offset;
use crate::scene::Scene;
use crate::scene_file::MAX_SAMPLES_PER_PIXEL;
use crate::view_plane::{ViewPlane, ViewPlaneError};

/// An 8-bit RGB pixel.
pub type Rgb8 = [u8; 3];

/// Why a render cannot start.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum RenderError {
    /// The image size or the view plane is unusable.
    #[error(transparent)]
    ViewPlane(#[from] ViewPlaneError),
    /// Samples per pixel out of range.
    #[error("samples per pixel must be 1 to {MAX_SAMPLES_PER_PIXEL}, got {0}")]
    SamplesPerPixel(u32),
}

/// A finished image: `pixels[y * width + x]`, row 0 at the top.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, top row first.
    pub pixels: Vec<Rgb8>,
}

/// Renders one scene at one image size and sample count.
#[derive(Clone, Copy, Debug)]
pub struct Renderer<'s> {
    scene: &'s Scene,
    view: ViewPlane,
    spp: u32,
}

impl<'s> Renderer<'s> {
    /// A renderer for `scene` seen by its own camera at `width`×`height` with
    /// `spp` samples per pixel.
    pub fn new(scene: &'s Scene, width: u32, height: u32, spp: u32) -> Result<Self, RenderError> {
        Self::with_camera(scene, scene.camera, width, height, spp)
    }

    /// A renderer for `scene` seen by another `camera` (the viewer's).
    pub fn with_camera(
        scene: &'s Scene,
        camera: Camera,
        width: u32,
        height: u32,
        spp: u32,
    ) -> Result<Self, RenderError> {
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&spp) {
            return Err(RenderError::SamplesPerPixel(spp));
        }
        Ok(Self { scene, view: ViewPlane::new(camera, width, height)?, spp })
    }

    /// The view plane rays are generated from.
    pub fn view_plane(&self) -> &ViewPlane {
        &self.view
    }

    /// The colour seen along a primary ray: the closest hit's material
    /// colour, or the background. Without lights this is all there is.
    pub fn trace(&self, ray: &Ray) -> Color {
        match self.scene.cast(ray) {
            Some(hit) => self.scene.hit_color(&hit),
            None => self.scene.background,
        }
    }

    /// The average colour of pixel (x, y) over its samples.
    pub fn pixel(&self, x: u32, y: u32) -> Color {
        if self.spp == 1 {
            return self.trace(&self.view.center_ray(x, y));
        }
        let sum: Color = (0..self.spp)
            .map(|k| {
                let (sx, sy) = subpixel_offset(x, y, k, self.spp);
                self.trace(&self.view.primary_ray(x, y, sx, sy))
            })
            .sum();
        sum / self.spp as f32
    }

    /// Fills `row` (one pixel per column) with row `y` of the image.
    pub fn render_row(&self, y: u32, row: &mut [Rgb8]) {
        for (x, out) in row.iter_mut().enumerate() {
            *out = to_rgb8(self.pixel(x as u32, y));
        }
    }

    /// Renders every row in parallel (rayon's global pool), calling
    /// `row_done` once after each row is finished, from the worker thread.
    pub fn render(&self, row_done: impl Fn(u32) + Sync) -> Frame {
        self.render_until(row_done, &AtomicBool::new(false)).expect("never stopped")
    }

    /// Like [`Renderer::render`], but rows not yet started are skipped once
    /// `stop` is set (Ctrl-C); returns `None` if any row was skipped.
    pub fn render_until(&self, row_done: impl Fn(u32) + Sync, stop: &AtomicBool) -> Option<Frame> {
        let (width, height) = (self.view.width(), self.view.height());
        let mut pixels = vec![[0u8; 3]; width as usize * height as usize];
        pixels.par_chunks_mut(width as usize).enumerate().for_each(|(y, row)| {
            if !stop.load(Ordering::Relaxed) {
                self.render_row(y as u32, row);
                row_done(y as u32);
            }
        });
        (!stop.load(Ordering::Relaxed)).then_some(Frame { width, height, pixels })
    }
}

/// Clamps each component to [0, 1] and rounds it to 8 bits (NaN becomes 0).
pub fn to_rgb8(c: Color) -> Rgb8 {
    c.to_array().map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const SCENE: &str = r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 32, height: 24),
        background: (0, 0, 1),
        materials: { "red": (color: (1, 0, 0)) },
        objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "red") ],
    )"#;

    fn scene() -> Scene {
        crate::parse_scene(SCENE, "test.ron", Path::new(".")).unwrap()
    }

    #[test]
    fn centre_pixel_shows_the_sphere_and_the_corner_the_background() {
        let s = scene();
        let f = Renderer::new(&s, 32, 24, 1).unwrap().render(|_| {});
        assert_eq!(f.pixels[12 * 32 + 16], [255, 0, 0]);
        assert_eq!(f.pixels[0], [0, 0, 255]);
    }

    #[test]
    fn every_row_is_reported_once() {
        let s = scene();
        let seen = std::sync::Mutex::new(vec![0; 24]);
        Renderer::new(&s, 32, 24, 1).unwrap().render(|y| seen.lock().unwrap()[y as usize] += 1);
        assert_eq!(seen.into_inner().unwrap(), vec![1; 24]);
    }

    #[test]
    fn edge_pixels_blend_with_several_samples() {
        let s = scene();
        let r = Renderer::new(&s, 32, 24, 16).unwrap();
        let f = r.render(|_| {});
        let blended = f.pixels.iter().filter(|p| p[0] > 0 && p[2] > 0).count();
        assert!(blended > 0, "no anti-aliased edge pixels");
        assert_eq!(f.pixels[12 * 32 + 16], [255, 0, 0]);
    }

    #[test]
    fn the_image_is_the_same_for_one_and_for_two_threads() {
        let s = scene();
        let r = Renderer::new(&s, 32, 24, 4).unwrap();
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| r.render(|_| {}))
        };
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn a_stopped_render_returns_nothing() {
        let s = scene();
        let r = Renderer::new(&s, 32, 24, 1).unwrap();
        let stop = AtomicBool::new(false);
        let frame = r.render_until(
            |y| {
                if y == 3 {
                    stop.store(true, Ordering::Relaxed)
                }
            },
            &stop,
        );
        assert_eq!(frame, None);
        assert!(r.render_until(|_| {}, &AtomicBool::new(false)).is_some());
    }

    #[test]
    fn bad_sample_counts_are_refused() {
        let s = scene();
        assert_eq!(Renderer::new(&s, 32, 24, 0).err(), Some(RenderError::SamplesPerPixel(0)));
    }

    #[test]
    fn to_rgb8_clamps_and_rounds() {
        assert_eq!(to_rgb8(Color::new(-1.0, 0.5, 2.0)), [0, 128, 255]);
        assert_eq!(to_rgb8(Color::new(f32::NAN, 0.0, 1.0)), [0, 0, 255]);
    }
}
