//! The render loop: pixels → samples → primary rays → [`Tracer`] (or, under
//! global illumination, [`PathTracer`]) → colours → rows → image.
//!
//! Rows are independent: [`Renderer::render_row`] fills one, and
//! [`Renderer::render`] fills all of them in parallel with rayon. Every
//! sample draws its random numbers from a stream seeded by (pixel, sample)
//! ([`SampleRng`]), so the result does not depend on the number of threads or
//! the order rows finish in, bit for bit.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use thiserror::Error;

use crate::camera::Camera;
use crate::effects::{EffectPlan, RayCounts};
use crate::material::{Color, ColorSpace};
use crate::path_tracer::PathTracer;
use crate::sampler::{MAX_SAMPLES_PER_PIXEL, SampleRng, subpixel_offset};
use crate::scene::Scene;
use crate::tracer::Tracer;
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

/// A finished image in linear colour: `pixels[y * width + x]`, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major linear colours (mean of each pixel's samples), top row first.
    pub pixels: Vec<Color>,
    /// How the pixels are to be encoded into 8 bits (the scene's choice).
    pub color_space: ColorSpace,
    /// The rays the render cast, by kind.
    pub rays: RayCounts,
}

impl Frame {
    /// The pixels encoded in the frame's colour space.
    pub fn to_rgb8(&self) -> Vec<Rgb8> {
        self.pixels.iter().map(|&c| self.color_space.encode(c)).collect()
    }
}

/// Renders one scene at one image size and sample count.
#[derive(Clone, Copy, Debug)]
pub struct Renderer<'s> {
    tracer: Tracer<'s>,
    /// Under global illumination, the path tracer that replaces `tracer`.
    path_tracer: Option<PathTracer<'s>>,
    view: ViewPlane,
    spp: u32,
    seed: u64,
    color_space: ColorSpace,
}

impl<'s> Renderer<'s> {
    /// A renderer for `scene` seen by its own camera at `width`×`height` with
    /// `spp` samples per pixel, simulating the effects the scene asks for.
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
        Self::with_plan(scene, camera, width, height, spp, scene.effect_plan())
    }

    /// A renderer that simulates what `plan` allows (the viewer's toggles).
    pub fn with_plan(
        scene: &'s Scene,
        camera: Camera,
        width: u32,
        height: u32,
        spp: u32,
        plan: EffectPlan,
    ) -> Result<Self, RenderError> {
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&spp) {
            return Err(RenderError::SamplesPerPixel(spp));
        }
        Ok(Self {
            tracer: Tracer::new(scene, plan),
            path_tracer: plan.global_illumination.map(|gi| PathTracer::new(scene, gi)),
            view: ViewPlane::new(camera, width, height)?,
            spp,
            seed: 0,
            color_space: scene.color_space,
        })
    }

    /// The same renderer drawing its random numbers for seed `seed`
    /// ([`SampleRng::seeded`]): an independent estimate of the same image.
    /// Seed 0 is the default.
    pub fn with_seed(self, seed: u64) -> Self {
        Self { seed, ..self }
    }

    /// The view plane rays are generated from.
    pub fn view_plane(&self) -> &ViewPlane {
        &self.view
    }

    /// The effects this renderer simulates.
    pub fn plan(&self) -> &EffectPlan {
        self.tracer.plan()
    }

    /// Samples per pixel.
    pub fn samples_per_pixel(&self) -> u32 {
        self.spp
    }

    /// The colour space pixels are encoded in.
    pub fn color_space(&self) -> ColorSpace {
        self.color_space
    }

    /// Sample `k` of pixel (x, y): one primary ray through its sub-pixel
    /// offset ([`crate::sampler::subpixel_offset`]; the centre when spp = 1), traced.
    pub fn sample(&self, x: u32, y: u32, k: u32, counts: &mut RayCounts) -> Color {
        let ray = if self.spp == 1 {
            self.view.center_ray(x, y)
        } else {
            let (sx, sy) = subpixel_offset(x, y, k, self.spp, self.seed);
            self.view.primary_ray(x, y, sx, sy)
        };
        let rng = &mut SampleRng::seeded(x, y, k, self.seed);
        match &self.path_tracer {
            Some(path_tracer) => path_tracer.trace_primary(&ray, rng, counts),
            None => self.tracer.trace_primary(&ray, rng, counts),
        }
    }

    /// The mean colour of pixel (x, y) over its samples, summed in order
    /// 0, 1, … from zero (as [`Renderer::accumulate_row`] does).
    pub fn pixel(&self, x: u32, y: u32, counts: &mut RayCounts) -> Color {
        let sum = (0..self.spp).fold(Color::ZERO, |sum, k| sum + self.sample(x, y, k, counts));
        sum / self.spp as f32
    }

    /// Adds samples `samples` of each pixel of row `y` to `sums`, in order:
    /// after adding `0..spp` in any number of steps, `sums[x] / spp` is
    /// exactly [`Renderer::pixel`] (the viewer refines an image this way).
    pub fn accumulate_row(&self, y: u32, samples: Range<u32>, sums: &mut [Color]) -> RayCounts {
        let mut counts = RayCounts::default();
        for (x, sum) in sums.iter_mut().enumerate() {
            for k in samples.clone() {
                *sum += self.sample(x as u32, y, k, &mut counts);
            }
        }
        counts
    }

    /// Fills `row` (one linear colour per column) with row `y` of the image.
    pub fn render_row(&self, y: u32, row: &mut [Color]) -> RayCounts {
        let mut counts = RayCounts::default();
        for (x, out) in row.iter_mut().enumerate() {
            *out = self.pixel(x as u32, y, &mut counts);
        }
        counts
    }

    /// Renders every row in parallel (rayon's current pool), calling
    /// `row_done` once after each row is finished, from the worker thread.
    pub fn render(&self, row_done: impl Fn(u32) + Sync) -> Frame {
        self.render_until(row_done, &AtomicBool::new(false)).expect("never stopped")
    }

    /// Like [`Renderer::render`], but rows not yet started are skipped once
    /// `stop` is set (Ctrl-C); returns `None` if any row was skipped.
    pub fn render_until(&self, row_done: impl Fn(u32) + Sync, stop: &AtomicBool) -> Option<Frame> {
        let (width, height) = (self.view.width(), self.view.height());
        let mut pixels = vec![Color::ZERO; width as usize * height as usize];
        let rays = pixels
            .par_chunks_mut(width as usize)
            .enumerate()
            .map(|(y, row)| {
                if stop.load(Ordering::Relaxed) {
                    return RayCounts::default();
                }
                let counts = self.render_row(y as u32, row);
                row_done(y as u32);
                counts
            })
            .sum();
        (!stop.load(Ordering::Relaxed)).then_some(Frame {
            width,
            height,
            pixels,
            color_space: self.color_space,
            rays,
        })
    }
}

/// Clamps each component to [0, 1] and rounds it to 8 bits, with no transfer
/// curve (NaN becomes 0): [`ColorSpace::Linear`], the flat-colour encoding.
pub fn to_rgb8(c: Color) -> Rgb8 {
    ColorSpace::Linear.encode(c)
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
        assert_eq!(f.to_rgb8()[12 * 32 + 16], [255, 0, 0]);
        assert_eq!(f.to_rgb8()[0], [0, 0, 255]);
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
        let f = r.render(|_| {}).to_rgb8();
        let blended = f.iter().filter(|p| p[0] > 0 && p[2] > 0).count();
        assert!(blended > 0, "no anti-aliased edge pixels");
        assert_eq!(f[12 * 32 + 16], [255, 0, 0]);
    }

    #[test]
    fn the_image_is_the_same_for_one_and_for_two_threads() {
        let s = scene();
        let r = Renderer::new(&s, 32, 24, 4).unwrap();
        let run = |threads| crate::test_support::render_on_threads(&r, threads);
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
    fn a_scene_without_lights_casts_exactly_one_primary_ray_per_sample_and_nothing_else() {
        let s = scene();
        for spp in [1, 3, 16] {
            let f = Renderer::new(&s, 32, 24, spp).unwrap().render(|_| {});
            assert_eq!(f.rays, RayCounts { primary: 32 * 24 * spp as u64, ..RayCounts::default() });
        }
    }

    #[test]
    fn accumulating_samples_in_steps_gives_the_pixel_exactly() {
        let s = scene();
        let r = Renderer::new(&s, 32, 24, 7).unwrap();
        let mut sums = vec![Color::ZERO; 32];
        for range in [0..1, 1..4, 4..7] {
            r.accumulate_row(11, range, &mut sums);
        }
        let mut row = vec![Color::ZERO; 32];
        r.render_row(11, &mut row);
        assert_eq!(sums.iter().map(|&c| c / 7.0).collect::<Vec<_>>(), row);
    }
}
