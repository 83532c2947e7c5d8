//! The render loop: pixels → samples → primary rays → the render's
//! [`Integrator`] → colours → rows → image.
//!
//! Rows are independent: [`Renderer::render_row`] fills one, and
//! [`Renderer::render`] fills all of them in parallel with rayon, in bands
//! of [`BAND_ROWS`] whose primary rays go out in square tiles. Every
//! sample draws its random numbers by (pixel, sample, seed) alone
//! ([`Sampler`]), so the result does not depend on the number of threads or
//! the order rows finish in, bit for bit.

pub mod adaptive;
pub mod passes;
mod record_sample;
pub mod settings;
pub mod view_transform;

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;
use thiserror::Error;

use crate::bvh::PACKET_RAYS;
use crate::camera::Camera;
use crate::camera::view_plane::{ViewPlane, ViewPlaneError};
use crate::geometry::hit::Hit;
use crate::integrators::Integrator;
use crate::materials::texture_lod::RayCone;
use crate::math::color::{Color, ColorSpace};
use crate::math::ray::Ray;
use crate::math::real::Vec3;
use crate::render::passes::{FEATURE_SALT, FeatureFrame, FeatureSums, SampleFeatures};
use crate::render::settings::RenderSettings;
use crate::sampling::sampler::{PixelSample, SampleRng, Sampler};
use crate::scene::Scene;
use crate::scene::effects::{EffectPlan, RayCounts};

/// The most rows [`Renderer::render`] renders together, their rays cast in
/// tiles eight pixels square at one sample per pixel (fewer rows at more
/// than eight samples per pixel, one at 64 or more).
pub const BAND_ROWS: u32 = 8;

/// How many rows a band holds when each of its pixels takes `samples`
/// samples: as many as a packet's worth of samples fills, from one (at
/// [`PACKET_RAYS`] samples or more a pixel fills packets on its own, and
/// single rows share the work out more finely among the threads) to
/// [`BAND_ROWS`].
pub fn band_rows(samples: u32) -> u32 {
    (PACKET_RAYS as u32 / samples.max(1)).clamp(1, BAND_ROWS)
}

/// A sample's colour with its pixel's index in the region rendered
/// (row-major), as [`Renderer::accumulate_region_packets`] hands them out.
pub type RegionColour = (usize, Color);

/// An 8-bit RGB pixel.
pub type Rgb8 = [u8; 3];

/// Why a render cannot start (its settings are valid by construction).
#[derive(Clone, Debug, Error, PartialEq)]
pub enum RenderError {
    /// The camera's view plane at the image size is unusable.
    #[error(transparent)]
    ViewPlane(#[from] ViewPlaneError),
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

/// Renders one scene through one camera with one set of [`RenderSettings`].
#[derive(Clone, Copy, Debug)]
pub struct Renderer<'s> {
    scene: &'s Scene,
    /// The effects simulated.
    plan: EffectPlan,
    integrator: Integrator<'s>,
    view: ViewPlane,
    spp: u32,
    /// Where each sample's film position and random numbers come from.
    sampler: Sampler,
    color_space: ColorSpace,
}

impl<'s> Renderer<'s> {
    /// A renderer for `scene` seen by `camera` with `settings`, simulating
    /// the effects the settings ask for that the scene has something for
    /// ([`Scene::effect_plan`]), less those the settings' toggles switch off.
    pub fn new(scene: &'s Scene, camera: Camera, settings: &RenderSettings) -> Result<Self, RenderError> {
        let plan = scene.effect_plan(&settings.effects).restricted(settings.toggles);
        let spp = settings.samples.get();
        let view = ViewPlane::new(camera, settings.image.width(), settings.image.height())?;
        Ok(Self {
            scene,
            plan,
            integrator: Integrator::new(scene, plan).with_cone(RayCone::of_pixel(&view)),
            view,
            spp,
            sampler: Sampler::new(spp, settings.seed).with_kind(settings.sampler),
            color_space: settings.color_space,
        })
    }

    /// This renderer for a render whose sample count is not fixed in
    /// advance (the viewer's "no limit"): film positions come from
    /// [`Sampler::open_ended`], stratified within blocks of samples
    /// ([`crate::sampling::sampler::open_ended_block`]) rather than over
    /// the settings' samples per pixel, so any number of whole blocks is an
    /// unbiased estimate. Everything else is as before; images differ from
    /// a fixed-count render's, which stratifies over its count.
    pub fn open_ended(self) -> Self {
        Self { sampler: self.sampler.to_open_ended(), ..self }
    }

    /// The view plane rays are generated from.
    pub fn view_plane(&self) -> &ViewPlane {
        &self.view
    }

    /// The effects this renderer simulates.
    pub fn plan(&self) -> &EffectPlan {
        &self.plan
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
    /// offset ([`crate::sampling::sampler::subpixel_offset`]; the centre when spp = 1), traced.
    pub fn sample(&self, x: u32, y: u32, k: u32, counts: &mut RayCounts) -> Color {
        let mut sampler = self.sampler;
        let ray = self.primary_ray(&mut sampler, x, y, k);
        let start = sampler.pixel_sample();
        self.shade_sample(&mut sampler, start, &ray, self.scene.cast(&ray), counts)
    }

    /// The primary ray of sample `k` of pixel (x, y), its film and lens
    /// positions from `sampler` (a copy of this renderer's, kept over a
    /// run of pixels: a Sobol sampler keeps each pixel's sequences).
    // Inlined into the packet loop, where the sample count's stratification
    // is loop-invariant: as a call it cost 14 % of a flat 64-spp render.
    #[inline(always)]
    fn primary_ray(&self, sampler: &mut Sampler, x: u32, y: u32, k: u32) -> Ray {
        sampler.start_pixel_sample(x, y, k);
        let film = sampler.film();
        // A pinhole ignores the lens position: no hash for it.
        let lens = if self.view.has_lens() { sampler.lens() } else { (0.5, 0.5) };
        self.view.camera_ray(x, y, film, lens)
    }

    /// The colour of the pixel sample `start` (as the sampler that made its
    /// primary ray started it), whose primary ray `ray` was cast already and
    /// gave `hit`, its random numbers from `sampler` (a copy of this
    /// renderer's, as for [`Renderer::primary_ray`]).
    fn shade_sample(
        &self,
        sampler: &mut Sampler,
        start: PixelSample,
        ray: &Ray,
        hit: Option<Hit>,
        counts: &mut RayCounts,
    ) -> Color {
        sampler.resume_pixel_sample(start);
        self.integrator.radiance(ray, hit, sampler, counts)
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
    ///
    /// The row's primary rays, pixel by pixel and sample by sample, are cast
    /// in packets of [`PACKET_RAYS`] ([`Scene::cast_all`]): a pixel's
    /// samples, or a run of neighbouring pixels at one sample each. The hits,
    /// and so the colours, are the ones [`Renderer::sample`] gives one by one.
    pub fn accumulate_row(&self, y: u32, samples: Range<u32>, sums: &mut [Color]) -> RayCounts {
        self.accumulate_rows(y..y + 1, samples, sums)
    }

    /// [`Renderer::accumulate_row`] for the rows `rows` together, `sums`
    /// holding them one after the other: each pixel gets the same sums, bit
    /// for bit.
    ///
    /// The rows are cut into tiles as wide as make a tile's rays (pixels ×
    /// samples) fill a packet, eight pixels square for eight rows at one
    /// sample; the packets go tile after tile, left to right, each tile's
    /// pixels row by row and each pixel's samples in order. A square of
    /// pixels is a tighter packet than a run of a row: on a million-triangle
    /// mesh, where a pixel sees about one triangle, 8 × 8 tiles trace 1.5×
    /// faster than runs of 64 ([`Renderer::render`] uses bands of
    /// [`BAND_ROWS`]).
    ///
    /// # Panics
    /// If `sums` does not hold exactly the rows' pixels (`rows.len()` times
    /// the image width); [`Renderer::accumulate_row`] likewise wants one
    /// row's.
    pub fn accumulate_rows(&self, rows: Range<u32>, samples: Range<u32>, sums: &mut [Color]) -> RayCounts {
        self.accumulate_region(rows, 0..self.view.width(), samples, sums)
    }

    /// [`Renderer::accumulate_rows`] for the columns `columns` of the rows
    /// `rows` only (a region of the image), `sums` holding the region's
    /// rows one after the other, each `columns.len()` long. Each pixel gets
    /// the same sums as from [`Renderer::accumulate_rows`], bit for bit: a
    /// sample's colour depends on its pixel and index alone, and the tiles
    /// just start at the region's left edge.
    ///
    /// # Panics
    /// If `sums` does not hold exactly the region's pixels, or the columns
    /// reach past the image's width.
    pub fn accumulate_region(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        sums: &mut [Color],
    ) -> RayCounts {
        assert_eq!(sums.len(), rows.len() * columns.len(), "one sum per pixel of the region");
        self.accumulate_region_with(rows, columns, samples, |at, colour| sums[at] += colour)
    }

    /// [`Renderer::accumulate_region`], handing each sample's colour to
    /// `add` with its pixel's index in the region (row-major) instead of
    /// adding it to an `f32` sum: for sums kept another way, such as the
    /// exact sums that let a render split over machines merge bit for bit.
    /// The samples come in the order `accumulate_region` adds them (a
    /// pixel's in increasing index), cast in the same packets, so
    /// `|at, c| sums[at] += c` is `accumulate_region` exactly.
    ///
    /// # Panics
    /// If the columns reach past the image's width.
    #[inline]
    pub fn accumulate_region_with(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        mut add: impl FnMut(usize, Color),
    ) -> RayCounts {
        self.accumulate_region_packets(rows, columns, samples, &mut |colours| {
            colours.iter().for_each(|&(at, c)| add(at, c))
        })
    }

    /// [`Renderer::accumulate_region_with`], handing the colours to `add` a
    /// packet at a time (at most [`PACKET_RAYS`], each with its pixel's
    /// index in the region), in the same order.
    ///
    /// Why a packet at a time: the tracing loop is compiled here, once,
    /// where the camera ray, the integrator and the shading are inlined
    /// into it (as in [`Renderer::accumulate_region`]). A generic loop
    /// instantiated in another crate cannot inline this crate's plain
    /// functions (without link-time optimisation): each sample then paid
    /// three calls, which made a flat 8-spp render through exact sums 45 %
    /// slower. One dynamic call per packet costs nothing measurable.
    ///
    /// # Panics
    /// If the columns reach past the image's width.
    pub fn accumulate_region_packets(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        add: &mut dyn FnMut(&[RegionColour]),
    ) -> RayCounts {
        self.region_packets(rows, columns, samples, add, &mut NoFeatures)
    }

    /// [`Renderer::accumulate_region_packets`] that also adds each sample's
    /// [`SampleFeatures`] to `features` (one per pixel of the region, row by
    /// row), as [`Renderer::accumulate_region_with_features`] does: the
    /// colours handed out are the same, bit for bit and in the same order.
    ///
    /// # Panics
    /// If the columns reach past the image's width, or `features` is not one
    /// per pixel of the region.
    pub fn accumulate_region_packets_with_features(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        add: &mut dyn FnMut(&[RegionColour]),
        features: &mut [FeatureSums],
    ) -> RayCounts {
        assert_eq!(features.len(), rows.len() * columns.len(), "one feature sum per pixel of the region");
        self.region_packets(rows, columns, samples, add, &mut Features(features))
    }

    /// The packet loop of [`Renderer::accumulate_region_packets`], with
    /// features or without (compiled away).
    #[inline(always)]
    fn region_packets(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        add: &mut dyn FnMut(&[RegionColour]),
        features: &mut impl FeatureSink,
    ) -> RayCounts {
        let mut colours = [(0, Color::ZERO); PACKET_RAYS];
        let mut n = 0;
        let counts = self.sample_region(
            rows,
            columns,
            samples,
            |_| true,
            |at, _, c| {
                colours[n] = (at, c);
                n += 1;
                if n == PACKET_RAYS {
                    add(&colours);
                    n = 0;
                }
            },
            features,
        );
        if n > 0 {
            add(&colours[..n]);
        }
        counts
    }

    /// [`Renderer::accumulate_region`] that also adds each sample's
    /// [`SampleFeatures`] to `features` (one per pixel of the region, laid
    /// out as `sums`), from the same primary rays and hits: the colour sums
    /// are the same, bit for bit.
    ///
    /// # Panics
    /// As [`Renderer::accumulate_region`]; also if `features` is not as long
    /// as `sums`.
    pub fn accumulate_region_with_features(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        sums: &mut [Color],
        features: &mut [FeatureSums],
    ) -> RayCounts {
        assert_eq!(sums.len(), rows.len() * columns.len(), "one sum per pixel of the region");
        assert_eq!(features.len(), sums.len(), "one feature sum per pixel of the region");
        self.sample_region(
            rows,
            columns,
            samples,
            |_| true,
            |at, _, c| sums[at] += c,
            &mut Features(features),
        )
    }

    /// The features of sample `k` of pixel (x, y), whose primary ray `ray`
    /// was cast already and gave `hit` ([`SampleFeatures::of_camera_ray`]).
    pub fn sample_features(&self, x: u32, y: u32, k: u32, ray: &Ray, hit: Option<Hit>) -> SampleFeatures {
        let mut rng = SampleRng::seeded(x, y, k, self.sampler.seed() ^ FEATURE_SALT);
        SampleFeatures::of_camera_ray(self.scene, ray, hit, &mut rng)
    }

    /// The samples `samples` of each pixel of the region (`rows` ×
    /// `columns`) for which `wanted` (given the pixel's index in the region,
    /// row by row) says so, traced in packets as
    /// [`Renderer::accumulate_region`] says, each handed to `add` with its
    /// pixel's index and sample index, in the order given there, and its
    /// features to `features` (nothing, compiled away, for [`NoFeatures`]).
    #[inline(always)]
    fn sample_region(
        &self,
        rows: Range<u32>,
        columns: Range<u32>,
        samples: Range<u32>,
        wanted: impl Fn(usize) -> bool,
        mut add: impl FnMut(usize, u32, Color),
        features: &mut impl FeatureSink,
    ) -> RayCounts {
        assert!(columns.end <= self.view.width(), "columns {columns:?} past the image's width");
        let width = columns.len();
        let per_pixel = rows.len() * samples.len();
        let tile = (PACKET_RAYS / per_pixel.max(1)).clamp(1, width.max(1)) as u32;
        let mut counts = RayCounts::default();
        let mut packet = [PixelSample::default(); PACKET_RAYS];
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET_RAYS];
        let mut hits = [None; PACKET_RAYS];
        let mut n = 0;
        // One sampler for the camera rays and one for the paths, each kept
        // over the region: a pixel's samples follow one another, and a
        // Sobol sampler makes the pixel's sequences once.
        let (mut camera, mut shading) = (self.sampler, self.sampler);
        let mut flush = |n: usize, packet: &[PixelSample], rays: &[Ray]| {
            self.scene.cast_all(&rays[..n], &mut hits[..n]);
            for i in 0..n {
                let PixelSample { x, y, sample: k, .. } = packet[i];
                let at = (y - rows.start) as usize * width + (x - columns.start) as usize;
                add(at, k, self.shade_sample(&mut shading, packet[i], &rays[i], hits[i], &mut counts));
                features.add(at, || self.sample_features(x, y, k, &rays[i], hits[i]));
            }
        };
        for x0 in columns.clone().step_by(tile as usize) {
            for y in rows.clone() {
                for x in x0..(x0 + tile).min(columns.end) {
                    if !wanted((y - rows.start) as usize * width + (x - columns.start) as usize) {
                        continue;
                    }
                    for k in samples.clone() {
                        rays[n] = self.primary_ray(&mut camera, x, y, k);
                        packet[n] = camera.pixel_sample();
                        n += 1;
                        if n == PACKET_RAYS {
                            flush(n, &packet, &rays);
                            n = 0;
                        }
                    }
                }
            }
        }
        flush(n, &packet, &rays);
        counts
    }

    /// [`Renderer::render_until`] that also records the feature passes
    /// ([`FeatureFrame`]) in the same loop; the frame is the same, bit for bit.
    pub fn render_with_features_until(
        &self,
        row_done: impl Fn(u32) + Sync,
        stop: &AtomicBool,
    ) -> Option<(Frame, FeatureFrame)> {
        let (width, height) = (self.view.width(), self.view.height());
        let mut pixels = vec![Color::ZERO; width as usize * height as usize];
        let mut features = vec![FeatureSums::default(); pixels.len()];
        let band_rows = band_rows(self.spp);
        let band = width as usize * band_rows as usize;
        let rays = pixels
            .par_chunks_mut(band)
            .zip(features.par_chunks_mut(band))
            .enumerate()
            .map(|(band, (sums, features))| {
                if stop.load(Ordering::Relaxed) {
                    return RayCounts::default();
                }
                let first = band as u32 * band_rows;
                let rows = first..(first + band_rows).min(height);
                let counts =
                    self.accumulate_region_with_features(rows.clone(), 0..width, 0..self.spp, sums, features);
                for out in sums.iter_mut() {
                    *out /= self.spp as f32;
                }
                rows.for_each(&row_done);
                counts
            })
            .sum();
        (!stop.load(Ordering::Relaxed)).then(|| {
            let frame = Frame { width, height, pixels, color_space: self.color_space, rays };
            (frame, FeatureFrame { width, height, samples: self.spp, pixels: features })
        })
    }

    /// Fills `row` (one linear colour per column) with row `y` of the image:
    /// [`Renderer::pixel`] for each, computed as [`Renderer::accumulate_row`]
    /// does.
    pub fn render_row(&self, y: u32, row: &mut [Color]) -> RayCounts {
        row.fill(Color::ZERO);
        let counts = self.accumulate_row(y, 0..self.spp, row);
        for out in row.iter_mut() {
            *out /= self.spp as f32;
        }
        counts
    }

    /// Renders every row in parallel (rayon's current pool), calling
    /// `row_done` once after each row is finished, from the worker thread.
    /// Rows go in bands of up to [`BAND_ROWS`], whose rays are cast in tiles
    /// ([`Renderer::accumulate_rows`]).
    pub fn render(&self, row_done: impl Fn(u32) + Sync) -> Frame {
        self.render_until(row_done, &AtomicBool::new(false)).expect("never stopped")
    }

    /// Like [`Renderer::render`], but bands of rows not yet started are
    /// skipped once `stop` is set (Ctrl-C); returns `None` if any was skipped.
    pub fn render_until(&self, row_done: impl Fn(u32) + Sync, stop: &AtomicBool) -> Option<Frame> {
        let (width, height) = (self.view.width(), self.view.height());
        let mut pixels = vec![Color::ZERO; width as usize * height as usize];
        let band_rows = band_rows(self.spp);
        let rays = pixels
            .par_chunks_mut(width as usize * band_rows as usize)
            .enumerate()
            .map(|(band, sums)| {
                if stop.load(Ordering::Relaxed) {
                    return RayCounts::default();
                }
                let first = band as u32 * band_rows;
                let rows = first..(first + band_rows).min(height);
                let counts = self.accumulate_rows(rows.clone(), 0..self.spp, sums);
                for out in sums.iter_mut() {
                    *out /= self.spp as f32;
                }
                rows.for_each(&row_done);
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

/// Where [`Renderer::accumulate_into`] puts each sample's features.
trait FeatureSink {
    /// Adds the features `features()` gives to pixel `at` of the region.
    fn add(&mut self, at: usize, features: impl FnOnce() -> SampleFeatures);
}

/// No features: nothing is computed.
struct NoFeatures;

impl FeatureSink for NoFeatures {
    #[inline(always)]
    fn add(&mut self, _: usize, _: impl FnOnce() -> SampleFeatures) {}
}

/// The region's per-pixel feature sums.
struct Features<'a>(&'a mut [FeatureSums]);

impl FeatureSink for Features<'_> {
    #[inline]
    fn add(&mut self, at: usize, features: impl FnOnce() -> SampleFeatures) {
        self.0[at].add(&features());
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
    use crate::testing::test_support::renderer;
    use std::path::Path;

    const SCENE: &str = r#"(
        camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1),
        image: (width: 32, height: 24),
        background: (0, 0, 1),
        materials: { "red": (color: (1, 0, 0)) },
        objects: [ Sphere(center: (0, 0, 0), radius: 1, material: "red") ],
    )"#;

    fn scene() -> crate::LoadedScene {
        crate::parse_scene(SCENE, "test.ron", Path::new(".")).unwrap()
    }

    #[test]
    fn centre_pixel_shows_the_sphere_and_the_corner_the_background() {
        let s = scene();
        let f = renderer(&s, 32, 24, 1).render(|_| {});
        assert_eq!(f.to_rgb8()[12 * 32 + 16], [255, 0, 0]);
        assert_eq!(f.to_rgb8()[0], [0, 0, 255]);
    }

    #[test]
    fn every_row_is_reported_once() {
        let s = scene();
        let seen = std::sync::Mutex::new(vec![0; 24]);
        renderer(&s, 32, 24, 1).render(|y| seen.lock().unwrap()[y as usize] += 1);
        assert_eq!(seen.into_inner().unwrap(), vec![1; 24]);
    }

    #[test]
    fn edge_pixels_blend_with_several_samples() {
        let s = scene();
        let r = renderer(&s, 32, 24, 16);
        let f = r.render(|_| {}).to_rgb8();
        let blended = f.iter().filter(|p| p[0] > 0 && p[2] > 0).count();
        assert!(blended > 0, "no anti-aliased edge pixels");
        assert_eq!(f[12 * 32 + 16], [255, 0, 0]);
    }

    #[test]
    fn the_image_is_the_same_for_one_and_for_two_threads() {
        let s = scene();
        let r = renderer(&s, 32, 24, 4);
        let run = |threads| crate::testing::test_support::render_on_threads(&r, threads);
        assert_eq!(run(1), run(2));
    }

    #[test]
    fn a_sobol_render_is_the_same_for_one_and_two_threads_and_in_steps_and_differs_by_seed() {
        // Global illumination through a lens: every dimension from Sobol points, which
        // depend on pixel, sample and seed alone.
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut s = crate::load_scene(&scenes.join("depth_of_field.ron")).unwrap();
        s.settings.sampler = crate::sampling::sampler::SamplerKind::Sobol;
        let r = renderer(&s, 24, 18, 8);
        let run = |threads| crate::testing::test_support::render_on_threads(&r, threads);
        let one = run(1);
        assert_eq!(one, run(2));
        let mut sums = vec![Color::ZERO; 24];
        for range in [0..1, 1..2, 2..8] {
            r.accumulate_row(9, range, &mut sums);
        }
        let row: Vec<Color> = sums.iter().map(|&c| c / 8.0).collect();
        assert_eq!(row, one.pixels[9 * 24..10 * 24]);
        let file = crate::load_scene(&scenes.join("depth_of_field.ron")).unwrap();
        assert_ne!(one.pixels, renderer(&file, 24, 18, 8).render(|_| {}).pixels);
        s.settings.seed = 1;
        assert_ne!(one.pixels, renderer(&s, 24, 18, 8).render(|_| {}).pixels);
    }

    #[test]
    fn a_stopped_render_returns_nothing() {
        let s = scene();
        let r = renderer(&s, 32, 24, 1);
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
    fn a_scene_without_lights_casts_exactly_one_primary_ray_per_sample_and_nothing_else() {
        let s = scene();
        for spp in [1, 3, 16] {
            let f = renderer(&s, 32, 24, spp).render(|_| {});
            assert_eq!(f.rays, RayCounts { primary: 32 * 24 * spp as u64, ..RayCounts::default() });
        }
    }

    #[test]
    fn rows_and_bands_cast_in_packets_give_the_pixels_cast_ray_by_ray() {
        // Meshes, a sphere and a plane, lit, with and without global
        // illumination: every pixel of a row (its primary rays cast as
        // packets) equals the pixel rendered ray by ray, bit for bit.
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        for gi in ["", "global_illumination: (max_bounces: 3),"] {
            let text = format!(
                r#"(
                camera: (position: (0.3, 1.6, -4.5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 45, near: 1),
                image: (width: 40, height: 30),
                background: (0.2, 0.3, 0.4),
                lights: [Point(position: (3, 5, -4), color: (1, 1, 1), intensity: 40)],
                effects: ( {gi} ),
                materials: {{ "jade": (color: (0.3, 0.75, 0.5)), "red": (color: (0.8, 0.1, 0.1), specular: 0.5) }},
                objects: [
                    Mesh(file: "meshes/icosphere.obj", scale: 0.9, translate: (-1.1, 0, 0.5), material: "jade"),
                    Mesh(file: "meshes/torus.obj", scale: 0.9, translate: (1.2, 0, -0.3), material: "red"),
                    Sphere(center: (0, 0.6, 1.5), radius: 0.5, material: "red"),
                    Plane(normal: (0, 1, 0), d: -1, material: "jade"),
                ],
            )"#
            );
            let s = crate::parse_scene(&text, "packets.ron", &scenes).unwrap();
            for spp in [1, 5, 70] {
                let r = renderer(&s, 40, 30, spp);
                let mut row = vec![Color::ZERO; 40];
                for y in [3, 14, 15, 22] {
                    r.render_row(y, &mut row);
                    let one_by_one: Vec<Color> =
                        (0..40).map(|x| r.pixel(x, y, &mut RayCounts::default())).collect();
                    assert_eq!(row, one_by_one, "spp {spp}, row {y}, {gi}");
                }
                // Whole bands of rows, cast in tiles (30 rows: the last band
                // is short), give every row's pixels.
                let frame = r.render(|_| {});
                for y in 0..30 {
                    r.render_row(y, &mut row);
                    assert_eq!(frame.pixels[y as usize * 40..][..40], row, "spp {spp}, band row {y}, {gi}");
                }
            }
        }
    }

    #[test]
    fn a_region_gets_the_sums_of_the_whole_rows_bit_for_bit() {
        // Regions at the edges and inside, one pixel to all columns, fixed
        // and open-ended sampling, samples added in steps.
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let s = crate::load_scene(&scenes.join("showcase.ron")).unwrap();
        for spp in [1, 5, 70] {
            let fixed = renderer(&s, 40, 30, spp);
            for r in [fixed, fixed.open_ended()] {
                let rows = 6..14;
                let mut whole = vec![Color::ZERO; 40 * rows.len()];
                for step in [0..1, 1..spp] {
                    r.accumulate_rows(rows.clone(), step, &mut whole);
                }
                for columns in [0..40, 0..1, 39..40, 3..17, 25..40] {
                    let mut region = vec![Color::ZERO; columns.len() * rows.len()];
                    for step in [0..1, 1..spp] {
                        r.accumulate_region(rows.clone(), columns.clone(), step, &mut region);
                    }
                    let expected: Vec<Color> = (0..rows.len())
                        .flat_map(|y| {
                            whole[y * 40..][columns.start as usize..columns.end as usize].iter().copied()
                        })
                        .collect();
                    assert_eq!(region, expected, "spp {spp}, columns {columns:?}");
                }
            }
        }
    }

    #[test]
    fn an_open_ended_render_differs_from_the_fixed_one_only_in_its_film_positions() {
        // Flat colours: every sample of a pixel inside the sphere is red
        // either way; edge pixels blend differently (other positions).
        let s = scene();
        let (fixed, open) = (renderer(&s, 32, 24, 16), renderer(&s, 32, 24, 16).open_ended());
        let (a, b) = (fixed.render(|_| {}).to_rgb8(), open.render(|_| {}).to_rgb8());
        assert_eq!(a[12 * 32 + 16], b[12 * 32 + 16]);
        assert_ne!(a, b);
    }

    #[test]
    fn a_region_hands_out_each_sample_as_its_sums_add_them() {
        let s = scene();
        let r = renderer(&s, 32, 24, 70);
        let (rows, columns) = (5..9, 10..15);
        let mut sums = vec![Color::ZERO; 4 * 5];
        let counts = r.accumulate_region(rows.clone(), columns.clone(), 3..70, &mut sums);
        let mut each = vec![Vec::new(); 4 * 5];
        let counts_with = r.accumulate_region_with(rows, columns, 3..70, |at, c| each[at].push(c));
        assert_eq!(counts_with, counts);
        assert!(each.iter().all(|samples| samples.len() == 67));
        let added: Vec<Color> = each.iter().map(|c| c.iter().fold(Color::ZERO, |a, &b| a + b)).collect();
        assert_eq!(added, sums);
    }

    #[test]
    fn accumulating_samples_in_steps_gives_the_pixel_exactly() {
        let s = scene();
        let r = renderer(&s, 32, 24, 7);
        let mut sums = vec![Color::ZERO; 32];
        for range in [0..1, 1..4, 4..7] {
            r.accumulate_row(11, range, &mut sums);
        }
        let mut row = vec![Color::ZERO; 32];
        r.render_row(11, &mut row);
        assert_eq!(sums.iter().map(|&c| c / 7.0).collect::<Vec<_>>(), row);
    }
}
