//! A render running in the background, streaming finished rows.
//!
//! The job knows nothing about the UI beyond its row type: each finished row
//! is its pixels' linear colours (the mean of their samples so far) and the
//! same encoded as [`egui::Color32`], tagged with the job's generation, sent over
//! a channel, followed by a call to the `on_row` hook (the viewer passes
//! `request_repaint`). Workers take bands of [`BAND_ROWS`] rows from a shared
//! counter, so rows finish roughly top to bottom, like the course's
//! line-at-a-time renderer, while every rayon thread is busy; a band's rays
//! go out in square tiles ([`Renderer::accumulate_rows`]), tighter packets
//! than runs of one row.
//!
//! With several samples per pixel the image refines progressively: the job
//! runs passes over the whole image with samples `0..1`, `1..4`, `4..16`, …
//! up to spp ([`sample_passes`]), adding each pass to per-row sums and
//! streaming each row again with the mean so far. The first pass is a full
//! 1-spp image; the last equals the headless render bit for bit, because
//! the samples are added in the same order.
//!
//! With no sample limit ([`JobSpec::open_ended`]) the passes go on until the
//! job is stopped or cancelled: the same growing passes up to 1024 samples,
//! then passes of 1024 ([`open_ended_passes`]), sampled with
//! [`Renderer::open_ended`] (each pass stratified over the pixel on its own,
//! so the image after any whole pass is unbiased).
//!
//! A job may render a [`Region`] of the image only: its rows then hold the
//! region's columns, and each of its pixels equals the whole image's bit for
//! bit ([`Renderer::accumulate_region`]).
//!
//! A band's pass renders into a copy of its sums, [`CHUNK_SAMPLES`] samples
//! at a time: the sums stay readable meanwhile (inspection never waits for
//! a worker), and a long pass (1024 samples of eight rows can take seconds)
//! can be abandoned between chunks, its band keeping the previous pass.
//!
//! With denoising on ([`JobSpec::denoise`], a whole-image job, and OIDN
//! present: [`crate::denoise`]) the bands also sum the feature passes
//! ([`Renderer::accumulate_region_with_features`]), and once every band
//! has finished a pass a thread of its own denoises the whole
//! image (OIDN fed albedo and normal) and sends all its rows: the first
//! pass streams in noisy as usual, later passes show only denoised images,
//! one per pass, so what is on screen (and what Save writes) is the
//! denoised image of the last whole pass.
//!
//! [`RenderJob::stop`] ends a job as it stands: once the first pass is
//! complete, workers abandon the passes in flight and take no more, each
//! band keeping the samples of its last whole pass (on screen already), and
//! the job counts as done. Cancelling (or dropping the job, or dropping its
//! receiver) abandons the work in flight likewise, and rows already in the
//! channel keep their old generation, so [`super::canvas::Canvas`] refuses them.

use std::ops::Range;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryIter};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use egui::Color32;
use rt_core::math::color::Color;
use rt_core::render::passes::FeatureSums;
use rt_core::render::{BAND_ROWS, RenderError};
use rt_core::sampling::sampler::{MAX_OPEN_ENDED_SAMPLES, open_ended_block};
use rt_core::scene::effects::{EffectToggles, RayCounts};
use rt_core::{Camera, LoadedScene, RenderSettings, Renderer, SettingsError};

use crate::denoise::{self, AuxImages, Oidn};

use super::eta::{self, BandCost};
use super::region::Region;

/// The sample ranges of the progressive passes for `spp` samples per pixel:
/// `0..1`, then ranges four times longer than all before them together
/// (`1..4`, `4..16`, `16..64`, …), the last one cut at `spp`.
pub fn sample_passes(spp: u32) -> Vec<Range<u32>> {
    let mut passes = Vec::new();
    passes.push(0..1.min(spp));
    let mut start = 1;
    while start < spp {
        let end = start.saturating_mul(4).min(spp);
        passes.push(start..end);
        start = end;
    }
    passes
}

/// The most samples per pixel a worker adds to a band before it checks
/// whether the job is to end.
pub const CHUNK_SAMPLES: u32 = 64;

/// The sample ranges of an open-ended render's passes, pass after pass:
/// its sampler's blocks ([`open_ended_block`]), `0..1`, `1..4`, … `256..1024`
/// (those of [`sample_passes`]`(1024)`), then `1024..2048`, `2048..3072`, …
/// up to [`MAX_OPEN_ENDED_SAMPLES`], where sample streams would repeat.
pub fn open_ended_passes() -> Vec<Range<u32>> {
    let mut passes = Vec::new();
    let mut start = 0;
    while start < MAX_OPEN_ENDED_SAMPLES {
        let block = open_ended_block(start);
        start = block.end;
        passes.push(block);
    }
    passes
}

/// One band's running sums (its rows one after the other) and how many
/// samples they hold: every row of a band is rendered with the others.
struct BandSums {
    samples: u32,
    sums: Vec<Color>,
    /// The feature passes' sums, pixel by pixel as `sums`, when the job
    /// denoises (else empty).
    features: Vec<FeatureSums>,
}

/// The band function: adds `samples` of the pixels in `columns` of the rows
/// `rows` to `sums`, which holds them row after row (tests replace it).
type BandFn = dyn Fn(&Renderer, Range<u32>, Range<u32>, Range<u32>, &mut [Color]) -> RayCounts + Send + Sync;

/// What to render: a scene seen by a camera at a size and sample count.
#[derive(Clone, Debug)]
pub struct JobSpec {
    /// The scene (shared with the UI, never copied).
    pub scene: Arc<LoadedScene>,
    /// The camera to render with (the viewer's, not necessarily the file's).
    pub camera: Camera,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel (unused by an open-ended job beyond its check).
    pub spp: u32,
    /// No sample limit: passes go on until the job is stopped, sampled with
    /// [`Renderer::open_ended`] (its images differ from a fixed count's).
    pub open_ended: bool,
    /// Render only these pixels (`None`: the whole image).
    pub region: Option<Region>,
    /// The effects the user switched off (the rest of the settings are the file's).
    pub toggles: EffectToggles,
    /// Denoise each whole pass with OIDN (whole-image jobs only, where
    /// OIDN is present; see the module's documentation).
    pub denoise: bool,
}

impl JobSpec {
    /// OIDN, where this job denoises: asked for, the whole image, and the
    /// library present.
    fn denoiser(&self) -> Option<&'static Oidn> {
        (self.denoise && self.region.is_none()).then(denoise::find_and_load).and_then(Result::ok)
    }

    fn renderer(&self) -> Result<Renderer<'_>, JobError> {
        let settings = RenderSettings { toggles: self.toggles, ..self.scene.settings }.overridden(
            Some(self.width),
            Some(self.height),
            Some(self.spp),
        )?;
        let renderer = Renderer::new(&self.scene.scene, self.camera, &settings)?;
        Ok(if self.open_ended { renderer.open_ended() } else { renderer })
    }

    /// The pixels the job renders: its region, or the whole image.
    pub fn area(&self) -> Region {
        self.region.clone().unwrap_or(Region::whole(self.width, self.height))
    }

    /// The sample ranges of the job's passes.
    pub fn passes(&self) -> Vec<Range<u32>> {
        if self.open_ended { open_ended_passes() } else { sample_passes(self.spp) }
    }
}

/// Why a job cannot start.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum JobError {
    /// The size or sample count is out of range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The region is not inside the image.
    #[error("the region {0:?} is not inside the image")]
    Region(Region),
    /// The camera's view plane at that size is unusable.
    #[error(transparent)]
    Render(#[from] RenderError),
}

/// One finished row.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// The generation of the job that rendered it.
    pub generation: u64,
    /// Row index, 0 at the top.
    pub y: u32,
    /// Samples per pixel the row's colours are the mean of so far.
    pub samples: u32,
    /// One colour per column (per column of the job's region, if it has
    /// one), encoded in the scene's colour space (what the display shows at
    /// exposure 0).
    pub pixels: Vec<Color32>,
    /// One linear colour per column: the mean of its samples so far
    /// (scene-referred radiance, not clamped).
    pub linear: Vec<[f32; 3]>,
}

/// A running (or finished, or cancelled) render.
pub struct RenderJob {
    spec: JobSpec,
    /// The pixels rendered: the region, or the whole image.
    area: Region,
    passes: Vec<Range<u32>>,
    rows: Receiver<Row>,
    shared: Arc<Shared>,
    started: Instant,
    generation: u64,
}

/// How far a job has got.
#[derive(Clone, Debug, PartialEq)]
pub struct Progress {
    /// The pass in progress (0-based; the last one once done).
    pub pass: usize,
    /// How many passes the job makes at most.
    pub passes: usize,
    /// Whether the passes go on until the job is stopped (no sample limit).
    pub open_ended: bool,
    /// Samples per pixel every pixel has: those of the passes finished.
    pub spp: u32,
    /// The samples the pass adds to each pixel.
    pub samples: Range<u32>,
    /// Rows of the pass finished.
    pub rows: u32,
    /// Rows the job renders (the image's or its region's).
    pub height: u32,
    /// Time since the job started.
    pub elapsed: Duration,
    /// Time the pass will still take, each band of rows priced at its own
    /// cost ([`eta::time_to`]; `None` during the first pass, before every
    /// band's cost is known, and once the pass is done).
    pub pass_eta: Option<Duration>,
    /// Time until the last pass is done, likewise (`None` without a limit).
    pub eta: Option<Duration>,
    /// Rays of all kinds per second so far.
    pub rays_per_second: f64,
}

/// What the workers report to the job's handle.
struct Shared {
    /// Each band's running sums of linear colour (bands of [`BAND_ROWS`]).
    bands: Vec<Mutex<BandSums>>,
    /// Signalled when a band's pass is done (its next pass may start).
    band_done: Vec<Condvar>,
    /// Each band's samples per pixel so far, read without waiting for its lock.
    band_samples: Vec<AtomicU32>,
    /// Each band's thread time per sample in its last pass, nanoseconds as
    /// `f64` bits (0: not rendered yet).
    band_cost: Vec<AtomicU64>,
    /// Thread time spent rendering bands so far, nanoseconds.
    busy: AtomicU64,
    /// Set to stop the workers after their current band of rows.
    cancel: AtomicBool,
    /// Set to stop the workers after their current band, the job then done.
    stop: AtomicBool,
    /// Rays cast so far, all kinds.
    rays: AtomicU64,
    /// Rows finished so far, over all passes.
    rows_rendered: AtomicU32,
    /// Wall time from start to the last row, once every row is rendered.
    elapsed: Mutex<Option<Duration>>,
    /// The samples of the last pass denoised and sent (0: none yet),
    /// locked while a worker denoises and sends, so denoised images go out
    /// one at a time and in pass order.
    denoised_through: Mutex<u32>,
    /// "rows A–B: message" of the first band that panicked.
    failure: Mutex<Option<String>>,
}

impl Shared {
    fn new(width: u32, height: u32, features: bool) -> Self {
        let bands = height.div_ceil(BAND_ROWS) as usize;
        Self {
            bands: (0..height)
                .step_by(BAND_ROWS as usize)
                .map(|y| {
                    let pixels = (BAND_ROWS.min(height - y) * width) as usize;
                    let features = if features { vec![FeatureSums::default(); pixels] } else { Vec::new() };
                    Mutex::new(BandSums { samples: 0, sums: vec![Color::ZERO; pixels], features })
                })
                .collect(),
            band_done: (0..bands).map(|_| Condvar::new()).collect(),
            band_samples: (0..bands).map(|_| AtomicU32::new(0)).collect(),
            band_cost: (0..bands).map(|_| AtomicU64::new(0)).collect(),
            busy: AtomicU64::new(0),
            cancel: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            rays: AtomicU64::new(0),
            rows_rendered: AtomicU32::new(0),
            elapsed: Mutex::new(None),
            denoised_through: Mutex::new(0),
            failure: Mutex::new(None),
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// Whether workers are to take no new band (cancelled or stopped).
    fn ending(&self) -> bool {
        self.cancelled() || self.stop.load(Ordering::Relaxed)
    }

    /// Whether a pass starting at sample `start` is to be abandoned: the
    /// job is cancelled, or stopped and the pass is not the first (which
    /// completes, so a stopped job still has every row).
    fn abandons(&self, start: u32) -> bool {
        self.cancelled() || (start > 0 && self.stop.load(Ordering::Relaxed))
    }

    /// What the estimate knows of each band now.
    fn band_costs(&self) -> Vec<BandCost> {
        self.band_samples
            .iter()
            .zip(&self.band_cost)
            .map(|(samples, cost)| {
                let nanos = f64::from_bits(cost.load(Ordering::Relaxed));
                BandCost {
                    samples: samples.load(Ordering::Relaxed),
                    seconds_per_sample: (nanos > 0.0).then_some(nanos * 1e-9),
                }
            })
            .collect()
    }
}

/// The text of a panic's payload (`panic!` gives a `&str` or a `String`).
fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    match (payload.downcast_ref::<&str>(), payload.downcast_ref::<String>()) {
        (Some(s), _) => (*s).to_owned(),
        (_, Some(s)) => s.clone(),
        _ => "a panic with no message".to_owned(),
    }
}

impl RenderJob {
    /// Starts rendering `spec` on rayon's global pool from a thread of its
    /// own, so the caller never waits. `on_row` runs after each row is sent.
    pub fn start(
        spec: JobSpec,
        generation: u64,
        on_row: impl Fn() + Send + Sync + 'static,
    ) -> Result<Self, JobError> {
        Self::spawn(
            spec,
            generation,
            on_row,
            Box::new(|renderer, rows, columns, samples, sums| {
                renderer.accumulate_region(rows, columns, samples, sums)
            }),
        )
    }

    /// [`RenderJob::start`] with the band function as a parameter (tests use
    /// it to make a band panic). A panic while rendering a band is caught: the
    /// job stops, and [`RenderJob::failure`] reports the panic's message.
    fn spawn(
        spec: JobSpec,
        generation: u64,
        on_row: impl Fn() + Send + Sync + 'static,
        render_band: Box<BandFn>,
    ) -> Result<Self, JobError> {
        // Validate on the caller's thread, so errors are returned, not lost.
        spec.renderer()?;
        let area = spec.area();
        if !area.fits(spec.width, spec.height) {
            return Err(JobError::Region(area));
        }
        let shared = Arc::new(Shared::new(area.width(), area.height(), spec.denoiser().is_some()));
        let (tx, rows) = mpsc::channel();
        let denoiser = spec.denoiser();
        let worker = Worker {
            spec: spec.clone(),
            generation,
            shared: shared.clone(),
            tx,
            on_row: Arc::new(on_row),
            render_band,
            denoiser,
        };
        std::thread::Builder::new()
            .name(format!("render-job-{generation}"))
            .spawn(move || worker.run())
            .expect("the OS can start a thread");
        let passes = spec.passes();
        Ok(Self { spec, area, passes, rows, shared, started: Instant::now(), generation })
    }

    /// The generation its rows carry.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The linear colour of pixel (x, y) so far (the mean of its samples)
    /// and how many samples it has; `None` outside the image or before its
    /// row's first pass.
    pub fn linear(&self, x: u32, y: u32) -> Option<(Color, u32)> {
        let area = &self.area;
        if !area.contains(x, y) {
            return None;
        }
        let (x, y) = (x - area.columns.start, y - area.rows.start);
        let band = self.shared.bands.get((y / BAND_ROWS) as usize)?.lock().unwrap_or_else(|e| e.into_inner());
        let sum = *band.sums.get(((y % BAND_ROWS) * area.width() + x) as usize)?;
        (band.samples > 0).then(|| (sum / band.samples as f32, band.samples))
    }

    /// Rays cast so far, all kinds together.
    pub fn rays(&self) -> u64 {
        self.shared.rays.load(Ordering::Relaxed)
    }

    /// The pass in progress and how many of its rows are finished, the time
    /// so far, the time the pass and the job still need, and the rate of rays.
    ///
    /// Rows finish top to bottom and differ in cost many times over, so the
    /// estimates price each band's remaining samples at that band's own cost
    /// in its last pass ([`eta::time_to`]), not at the rate of the rows so far.
    pub fn progress(&self) -> Progress {
        let passes = &self.passes;
        let height = self.area.height();
        let done = self.shared.rows_rendered.load(Ordering::Relaxed);
        let pass = ((done / height) as usize).min(passes.len() - 1);
        let rows = (done - pass as u32 * height).min(height);
        let elapsed = self.elapsed().unwrap_or_else(|| self.started.elapsed());
        let seconds = elapsed.as_secs_f64().max(1e-9);
        let spp = if rows == height { passes[pass].end } else { passes[pass].start };
        let last = passes.last().expect("at least one pass").end;
        Progress {
            pass,
            passes: passes.len(),
            open_ended: self.spec.open_ended,
            spp,
            samples: passes[pass].clone(),
            rows,
            height,
            elapsed,
            pass_eta: self.eta_to(passes[pass].end),
            eta: if self.spec.open_ended { None } else { self.eta_to(last) },
            rays_per_second: self.rays() as f64 / seconds,
        }
    }

    /// Time until every pixel has `samples` samples (the end of the pass
    /// that reaches them), each band priced at its own cost ([`eta::time_to`]);
    /// `None` during the first pass, once done, or once the job has ended.
    pub fn eta_to(&self, samples: u32) -> Option<Duration> {
        if self.elapsed().is_some() || self.shared.ending() {
            return None;
        }
        let end = self.passes.iter().find(|p| p.end >= samples).map_or(samples, |p| p.end);
        let busy = self.shared.busy.load(Ordering::Relaxed) as f64 * 1e-9;
        eta::time_to(end, &self.shared.band_costs(), busy, self.started.elapsed().as_secs_f64())
    }

    /// Pixel samples taken so far (pixels × their samples), over the
    /// bands' finished passes.
    pub fn pixel_samples(&self) -> u64 {
        let (width, height) = (self.area.width() as u64, self.area.height() as u64);
        let samples = self.shared.band_samples.iter().map(|s| s.load(Ordering::Relaxed) as u64);
        samples
            .enumerate()
            .map(|(band, n)| (BAND_ROWS as u64).min(height - band as u64 * BAND_ROWS as u64) * width * n)
            .sum()
    }

    /// The pixels the job renders: its region, or the whole image.
    pub fn area(&self) -> &Region {
        &self.area
    }

    /// Why the job stopped on its own, if a band panicked: "rows A–B: message".
    pub fn failure(&self) -> Option<String> {
        self.shared.failure.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// What this job renders.
    pub fn spec(&self) -> &JobSpec {
        &self.spec
    }

    /// Asks the workers to stop after their current band of rows.
    pub fn cancel(&self) {
        self.shared.cancel.store(true, Ordering::Relaxed);
    }

    /// Ends the job as it stands: the workers finish and send their current
    /// bands and take no more, and the job then counts as done
    /// ([`RenderJob::elapsed`]), each row with the samples it reached.
    pub fn stop(&self) {
        self.shared.stop.store(true, Ordering::Relaxed);
    }

    /// Whether [`RenderJob::stop`] was called.
    pub fn stopped(&self) -> bool {
        self.shared.stop.load(Ordering::Relaxed)
    }

    /// Rows that have arrived since the last call, without waiting.
    pub fn try_rows(&self) -> TryIter<'_, Row> {
        self.rows.try_iter()
    }

    /// Waits for the next row; `None` once the job has ended and every row
    /// has been taken (used by tests and headless callers).
    pub fn next_row_blocking(&self) -> Option<Row> {
        self.rows.recv().ok()
    }

    /// Wall time from start to the last row, once every row is rendered or
    /// the job was stopped and its last rows sent (`None` while running or
    /// if cancelled).
    pub fn elapsed(&self) -> Option<Duration> {
        *self.shared.elapsed.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// The job's background thread: hands (pass, band) tasks to every rayon
/// thread in order, so rows finish roughly top to bottom, pass after pass.
struct Worker<F> {
    spec: JobSpec,
    generation: u64,
    shared: Arc<Shared>,
    tx: Sender<Row>,
    /// Shared with the threads that denoise.
    on_row: Arc<F>,
    render_band: Box<BandFn>,
    /// OIDN, where the job denoises ([`JobSpec::denoiser`]): the bands
    /// then sum features with [`Renderer::accumulate_region_with_features`]
    /// instead of `render_band`.
    denoiser: Option<&'static Oidn>,
}

impl<F: Fn() + Send + Sync + 'static> Worker<F> {
    fn run(self) {
        let s = &self.spec;
        let renderer = s.renderer().expect("validated before the thread started");
        let passes = s.passes();
        let start = Instant::now();
        let bands = s.area().height().div_ceil(BAND_ROWS) as u64;
        let tasks = passes.len() as u64 * bands;
        let next_task = AtomicU64::new(0);
        rayon::broadcast(|_| {
            while !self.shared.cancelled() {
                let task = next_task.fetch_add(1, Ordering::Relaxed);
                if task >= tasks {
                    break;
                }
                let (pass, band) = ((task / bands) as usize, (task % bands) as u32);
                if self.shared.abandons(passes[pass].start)
                    || !self.render(&renderer, band, passes[pass].clone())
                {
                    break;
                }
            }
        });
        if !self.shared.cancelled() {
            *self.shared.elapsed.lock().unwrap_or_else(|e| e.into_inner()) = Some(start.elapsed());
            (*self.on_row)();
        }
    }

    /// Adds `samples` to the sums of band `band` and sends each of its
    /// rows' new mean; false when the job is to end (cancelled, stopped, the
    /// receiver gone, or a panic).
    fn render(&self, renderer: &Renderer, band: u32, samples: Range<u32>) -> bool {
        let area = self.spec.area();
        let first = area.rows.start + band * BAND_ROWS;
        let rows = first..(first + BAND_ROWS).min(area.rows.end);
        let (cell, done) = (&self.shared.bands[band as usize], &self.shared.band_done[band as usize]);
        let lock = || cell.lock().unwrap_or_else(|e| e.into_inner());
        // This band's previous pass may still be running on another thread.
        let mut sums = lock();
        while sums.samples != samples.start && !self.shared.abandons(samples.start) {
            // Woken when that pass is done; the timeout sees a cancel.
            let wait = done.wait_timeout(sums, Duration::from_millis(10));
            sums = wait.unwrap_or_else(|e| e.into_inner()).0;
        }
        if sums.samples != samples.start || self.shared.abandons(samples.start) {
            return false; // Ended while waiting.
        }
        // A copy, so the sums stay readable while the pass renders.
        let mut pass_sums = sums.sums.clone();
        let mut pass_features = sums.features.clone();
        drop(sums);
        let started = Instant::now();
        let mut counts = RayCounts::default();
        let mut k = samples.start;
        while k < samples.end {
            if self.shared.abandons(samples.start) {
                return false; // The band keeps its previous pass.
            }
            let chunk = k..(k + CHUNK_SAMPLES).min(samples.end);
            k = chunk.end;
            let rendered = catch_unwind(AssertUnwindSafe(|| {
                let columns = area.columns.clone();
                match self.denoiser {
                    Some(_) => renderer.accumulate_region_with_features(
                        rows.clone(),
                        columns,
                        chunk,
                        &mut pass_sums,
                        &mut pass_features,
                    ),
                    None => (self.render_band)(renderer, rows.clone(), columns, chunk, &mut pass_sums),
                }
            }));
            match rendered {
                Ok(c) => counts += c,
                Err(payload) => {
                    let mut failure = self.shared.failure.lock().unwrap_or_else(|e| e.into_inner());
                    let (first, last) = (rows.start, rows.end - 1);
                    failure
                        .get_or_insert_with(|| format!("rows {first}–{last}: {}", panic_message(&*payload)));
                    self.shared.cancel.store(true, Ordering::Relaxed);
                    (*self.on_row)(); // Wake the UI so it shows the failure.
                    return false;
                }
            }
        }
        let nanos = started.elapsed().as_nanos() as u64;
        let mut sums = lock();
        sums.sums = pass_sums;
        sums.features = pass_features;
        sums.samples = samples.end;
        done.notify_all();
        let per_sample = nanos as f64 / samples.len().max(1) as f64;
        self.shared.band_cost[band as usize].store(per_sample.max(1.0).to_bits(), Ordering::Relaxed);
        self.shared.band_samples[band as usize].store(samples.end, Ordering::Relaxed);
        self.shared.busy.fetch_add(nanos, Ordering::Relaxed);
        // The means exactly as `Renderer::pixel` computes them.
        let count = samples.end as f32;
        let color_space = renderer.color_space();
        let finished: Vec<Row> = rows
            .zip(sums.sums.chunks_exact(area.width() as usize))
            .map(|(y, row)| {
                let linear: Vec<[f32; 3]> = row.iter().map(|&sum| (sum / count).to_array()).collect();
                let pixels = linear
                    .iter()
                    .map(|&mean| {
                        let [r, g, b] = color_space.encode(Color::from_array(mean));
                        Color32::from_rgb(r, g, b)
                    })
                    .collect();
                Row { generation: self.generation, y, samples: samples.end, pixels, linear }
            })
            .collect();
        self.shared.rays.fetch_add(counts.total(), Ordering::Relaxed);
        // Sent before the band is unlocked (the channel never blocks): its
        // next pass waits for the lock, so cannot send its rows first. A
        // band's rows arrive in pass order, and the last applied is the final.
        let sent = finished.len();
        // Denoising, later passes show the denoised image only.
        let show = self.denoiser.is_none() || samples.start == 0;
        for row in finished {
            self.shared.rows_rendered.fetch_add(1, Ordering::Relaxed);
            if self.shared.cancelled() || (show && self.tx.send(row).is_err()) {
                self.shared.cancel.store(true, Ordering::Relaxed);
                return false;
            }
        }
        drop(sums);
        for _ in 0..sent {
            (*self.on_row)();
        }
        match self.denoiser {
            Some(oidn) if self.pass_is_whole(samples.end) => {
                self.send_denoised(oidn, renderer, samples.end, samples.start == 0)
            }
            _ => true,
        }
    }

    /// Whether every band has `samples` now.
    fn pass_is_whole(&self, samples: u32) -> bool {
        self.shared.band_samples.iter().all(|b| b.load(Ordering::Relaxed) >= samples)
    }

    /// Denoises the image as the bands hold it (each band's mean over its
    /// own samples so far: at least those of the pass just whole) and sends
    /// every row of it, unless a denoising of this pass (but the first) or
    /// a later one went first. On a thread of its own: OIDN takes a while
    /// and uses every core, and a rayon worker blocked in it would hold up
    /// the next job's start (a camera move). A failure of OIDN is the job's
    /// failure.
    fn send_denoised(
        &self,
        oidn: &'static Oidn,
        renderer: &Renderer,
        samples: u32,
        first_pass: bool,
    ) -> bool {
        let (area, generation, color_space) = (self.spec.area(), self.generation, renderer.color_space());
        let (shared, tx, on_row) = (self.shared.clone(), self.tx.clone(), self.on_row.clone());
        let denoise = move || {
            let mut through = shared.denoised_through.lock().unwrap_or_else(|e| e.into_inner());
            // The first pass's noisy rows of a band may go out after another
            // worker sent that pass denoised: then it is denoised again.
            if *through > samples || (*through == samples && !first_pass) || shared.cancelled() {
                return;
            }
            *through = samples;
            let (width, height) = (area.width(), area.height());
            let pixels = width as usize * height as usize;
            let (mut color, mut albedo, mut normal) =
                (Vec::with_capacity(pixels), Vec::with_capacity(pixels), Vec::with_capacity(pixels));
            for cell in &shared.bands {
                let band = cell.lock().unwrap_or_else(|e| e.into_inner());
                let n = band.samples.max(1);
                color.extend(band.sums.iter().map(|&c| c / n as f32));
                for f in &band.features {
                    let (a, m) = f.means(n);
                    albedo.push(a);
                    normal.push(m);
                }
            }
            let aux = AuxImages { albedo: Some(&albedo), normal: Some(&normal) };
            let clean = match oidn.denoise(width, height, &color, aux) {
                Ok(clean) => clean,
                Err(e) => {
                    let mut failure = shared.failure.lock().unwrap_or_else(|e| e.into_inner());
                    failure.get_or_insert_with(|| format!("denoising: {e}"));
                    shared.cancel.store(true, Ordering::Relaxed);
                    on_row();
                    return;
                }
            };
            for (y, row) in area.rows.clone().zip(clean.chunks_exact(width as usize)) {
                let linear: Vec<[f32; 3]> = row.iter().map(|c| c.to_array()).collect();
                let pixels = row
                    .iter()
                    .map(|&c| {
                        let [r, g, b] = color_space.encode(c);
                        Color32::from_rgb(r, g, b)
                    })
                    .collect();
                let row = Row { generation, y, samples, pixels, linear };
                if shared.cancelled() || tx.send(row).is_err() {
                    return;
                }
            }
            on_row();
        };
        std::thread::Builder::new()
            .name(format!("denoise-{generation}"))
            .spawn(denoise)
            .expect("the OS can start a thread");
        true
    }
}

impl Drop for RenderJob {
    fn drop(&mut self) {
        self.cancel();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn spec(width: u32, height: u32) -> JobSpec {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/showcase.ron");
        let scene = Arc::new(rt_core::load_scene(&path).unwrap());
        JobSpec {
            camera: scene.camera,
            scene,
            width,
            height,
            spp: 1,
            open_ended: false,
            region: None,
            toggles: EffectToggles::default(),
            denoise: false,
        }
    }

    #[test]
    fn every_row_is_delivered_exactly_once_with_the_jobs_generation() {
        let job = RenderJob::start(spec(60, 40), 7, || {}).unwrap();
        let mut seen = vec![0; 40];
        while let Some(row) = job.next_row_blocking() {
            assert_eq!((row.generation, row.pixels.len()), (7, 60));
            seen[row.y as usize] += 1;
        }
        assert_eq!(seen, vec![1; 40]);
        assert!(job.elapsed().is_some());
    }

    #[test]
    fn streamed_rows_equal_the_headless_render_bit_for_bit() {
        let s = spec(80, 45);
        let frame = Renderer::new(
            &s.scene.scene,
            s.camera,
            &s.scene.settings.overridden(Some(80), Some(45), Some(1)).unwrap(),
        )
        .unwrap()
        .render(|_| {});
        let job = RenderJob::start(s, 1, || {}).unwrap();
        let mut image = vec![Color32::BLACK; 80 * 45];
        let mut linear = vec![[0.0; 3]; 80 * 45];
        while let Some(row) = job.next_row_blocking() {
            let y = row.y as usize;
            image[y * 80..(y + 1) * 80].copy_from_slice(&row.pixels);
            linear[y * 80..(y + 1) * 80].copy_from_slice(&row.linear);
        }
        let expected: Vec<Color32> =
            frame.to_rgb8().iter().map(|&[r, g, b]| Color32::from_rgb(r, g, b)).collect();
        assert!(image == expected, "streamed image differs from `render`");
        let expected: Vec<[f32; 3]> = frame.pixels.iter().map(|c| c.to_array()).collect();
        assert!(linear == expected, "streamed linear colours differ from `render`");
    }

    #[test]
    fn passes_start_with_one_sample_and_end_at_spp() {
        assert_eq!(sample_passes(1), vec![0..1]);
        assert_eq!(sample_passes(2), vec![0..1, 1..2]);
        assert_eq!(sample_passes(16), vec![0..1, 1..4, 4..16]);
        assert_eq!(sample_passes(100), vec![0..1, 1..4, 4..16, 16..64, 64..100]);
    }

    #[test]
    fn a_progressive_render_streams_every_pass_and_ends_equal_to_the_headless_render() {
        let mut s = spec(48, 27);
        s.spp = 9;
        let frame = Renderer::new(
            &s.scene.scene,
            s.camera,
            &s.scene.settings.overridden(Some(48), Some(27), Some(9)).unwrap(),
        )
        .unwrap()
        .render(|_| {});
        let job = RenderJob::start(s, 1, || {}).unwrap();
        let mut image = vec![Color32::BLACK; 48 * 27];
        let mut seen = vec![Vec::new(); 27];
        while let Some(row) = job.next_row_blocking() {
            let y = row.y as usize;
            seen[y].push(row.samples);
            image[y * 48..(y + 1) * 48].copy_from_slice(&row.pixels);
        }
        assert!(seen.iter().all(|s| s == &[1, 4, 9]), "{seen:?}");
        let expected: Vec<Color32> =
            frame.to_rgb8().iter().map(|&[r, g, b]| Color32::from_rgb(r, g, b)).collect();
        assert!(image == expected, "final pass differs from `render`");
        let p = job.progress();
        assert_eq!((p.pass, p.passes, p.samples, p.rows, p.height, p.pass_eta), (2, 3, 4..9, 27, 27, None));
        assert_eq!(job.rays(), 48 * 27 * 9);
    }

    #[test]
    fn a_denoising_job_shows_the_first_pass_noisy_then_each_whole_pass_denoised_ending_as_the_denoised_render()
     {
        let mut s = spec(48, 27);
        (s.spp, s.denoise) = (9, true);
        let renderer = Renderer::new(
            &s.scene.scene,
            s.camera,
            &s.scene.settings.overridden(Some(48), Some(27), Some(9)).unwrap(),
        )
        .unwrap();
        let (frame, features) = renderer.render_with_features_until(|_| {}, &AtomicBool::new(false)).unwrap();
        let job = RenderJob::start(s, 1, || {}).unwrap();
        let mut image = vec![[0.0; 3]; 48 * 27];
        let mut seen = vec![Vec::new(); 27];
        while let Some(row) = job.next_row_blocking() {
            let y = row.y as usize;
            seen[y].push(row.samples);
            image[y * 48..(y + 1) * 48].copy_from_slice(&row.linear);
        }
        assert_eq!(job.failure(), None);
        let linear = |pixels: &[Color]| pixels.iter().map(|c| c.to_array()).collect::<Vec<_>>();
        match denoise::find_and_load() {
            Ok(oidn) => {
                // Pass 1 noisy, then denoised images of whole passes in
                // order (a pass whose wholeness a later one overtook is
                // skipped), the last one's at the end.
                for s in &seen {
                    assert!(
                        s[0] == 1 && s.windows(2).all(|w| w[0] <= w[1]) && s.last() == Some(&9),
                        "{seen:?}"
                    );
                }
                let aux = AuxImages { albedo: Some(&features.albedo()), normal: Some(&features.normal()) };
                let clean = oidn.denoise(48, 27, &frame.pixels, aux).unwrap();
                assert!(image == linear(&clean), "the last image is not the denoised render");
            }
            Err(e) => {
                // No OIDN: the job renders as without denoising.
                eprintln!("{e}: checked the job renders on without it");
                assert!(seen.iter().all(|s| s == &[1, 4, 9]), "{seen:?}");
                assert!(image == linear(&frame.pixels));
            }
        }
    }

    #[test]
    fn progress_estimates_the_rest_once_every_band_has_a_cost_and_not_before() {
        let mut s = spec(64, 2000);
        s.spp = 16;
        let job = RenderJob::start(s, 1, || {}).unwrap();
        // Part of the first pass: no band below has a cost yet, no estimate.
        for _ in 0..100 {
            job.next_row_blocking().unwrap();
        }
        let p = job.progress();
        assert_eq!((p.passes, p.height, p.open_ended), (3, 2000, false));
        if p.pass == 0 && p.rows < 2000 {
            assert_eq!((p.pass_eta, p.eta, p.spp), (None, None, 0), "{p:?}");
        }
        // Once the first pass's last band is in, in the second pass, every
        // band has a cost: the pass's end and the job's come before the last pass.
        let p = loop {
            let row = job.next_row_blocking().unwrap();
            let p = job.progress();
            if p.pass_eta.is_some() {
                break p;
            }
            assert!(row.samples < 16, "no estimate before the last pass: {p:?}");
        };
        assert_eq!((p.pass, p.spp), (1, 1), "{p:?}");
        assert!(p.pass_eta.unwrap() < p.eta.unwrap(), "{p:?}");
        assert!(p.rays_per_second > 0.0 && p.elapsed > Duration::ZERO);
        job.cancel();
    }

    #[test]
    fn open_ended_passes_grow_as_the_fixed_ones_to_1024_then_go_by_1024_to_the_cap() {
        let passes = open_ended_passes();
        assert_eq!(passes[..6], sample_passes(1024)[..]);
        assert_eq!(passes[6..8], [1024..2048, 2048..3072]);
        assert!(passes.windows(2).all(|w| w[0].end == w[1].start));
        assert_eq!(passes.last().unwrap().end, MAX_OPEN_ENDED_SAMPLES);
    }

    /// Every row a job sends, in order, with the image its last rows make.
    fn collect(job: &RenderJob, width: usize, until: impl Fn(&Row) -> bool) -> Vec<Row> {
        let mut rows = Vec::new();
        while let Some(row) = job.next_row_blocking() {
            assert_eq!(row.pixels.len(), width);
            let done = until(&row);
            rows.push(row);
            if done {
                job.stop();
            }
        }
        rows
    }

    #[test]
    fn an_open_ended_job_goes_past_the_fixed_limit_until_stopped_and_each_row_is_its_samples_mean() {
        let mut s = spec(8, 4);
        s.open_ended = true;
        let job = RenderJob::start(s.clone(), 1, || {}).unwrap();
        let rows = collect(&job, 8, |row| row.samples > 2048);
        // Stopped: the job is done, each row at the samples it reached.
        assert!(job.elapsed().is_some() && job.stopped());
        let ends: Vec<u32> = open_ended_passes().iter().map(|p| p.end).collect();
        for y in 0..4 {
            let seen: Vec<u32> = rows.iter().filter(|r| r.y == y).map(|r| r.samples).collect();
            assert_eq!(seen, ends[..seen.len()], "row {y}");
            assert!(*seen.last().unwrap() >= 2048, "row {y} stopped at {seen:?}");
        }
        // Each row's last colours are the mean of samples 0..n of the
        // open-ended sampler, added pass by pass.
        let settings = s.scene.settings.overridden(Some(8), Some(4), Some(1)).unwrap();
        let r = Renderer::new(&s.scene.scene, s.camera, &settings).unwrap().open_ended();
        for y in 0..4 {
            let last = rows.iter().rfind(|row| row.y == y).unwrap();
            let mut sums = vec![Color::ZERO; 8];
            for pass in open_ended_passes().into_iter().take_while(|p| p.end <= last.samples) {
                r.accumulate_row(y, pass, &mut sums);
            }
            let expected: Vec<Color32> = sums
                .iter()
                .map(|&c| {
                    let [r, g, b] = r.color_space().encode(c / last.samples as f32);
                    Color32::from_rgb(r, g, b)
                })
                .collect();
            assert_eq!(last.pixels, expected, "row {y}");
        }
    }

    #[test]
    fn a_region_job_renders_only_its_pixels_and_they_equal_the_headless_render() {
        let mut s = spec(48, 27);
        s.spp = 9;
        s.region = Some(Region { columns: 5..21, rows: 3..14 });
        let frame = Renderer::new(
            &s.scene.scene,
            s.camera,
            &s.scene.settings.overridden(Some(48), Some(27), Some(9)).unwrap(),
        )
        .unwrap()
        .render(|_| {});
        let job = RenderJob::start(s, 1, || {}).unwrap();
        let rows = collect(&job, 16, |_| false);
        assert_eq!(rows.len(), 11 * 3, "each of the region's rows once a pass");
        let rgb = frame.to_rgb8();
        for y in 3..14 {
            let last = rows.iter().rfind(|row| row.y == y).unwrap();
            assert_eq!(last.samples, 9);
            let expected: Vec<Color32> =
                rgb[y as usize * 48..][5..21].iter().map(|&[r, g, b]| Color32::from_rgb(r, g, b)).collect();
            assert_eq!(last.pixels, expected, "row {y}");
        }
        assert_eq!(job.rays(), 16 * 11 * 9);
        let (inside, outside) = (job.linear(5, 3).unwrap(), job.linear(4, 3));
        assert_eq!((inside.0, inside.1, outside), (frame.pixels[3 * 48 + 5], 9, None));
        let mut bad = spec(48, 27);
        bad.region = Some(Region { columns: 40..49, rows: 0..1 });
        assert!(matches!(RenderJob::start(bad, 2, || {}), Err(JobError::Region(_))));
    }

    #[test]
    fn a_cancelled_job_stops_early_and_reports_no_time() {
        // Large enough that two threads cannot finish it before the cancel lands.
        let job = RenderJob::start(spec(2000, 2000), 3, || {}).unwrap();
        job.cancel();
        let mut delivered = 0;
        while job.next_row_blocking().is_some() {
            delivered += 1;
        }
        assert!(delivered < 2000, "all {delivered} rows rendered despite the cancel");
        assert_eq!(job.elapsed(), None);
    }

    #[test]
    fn after_a_restart_no_row_of_the_old_job_reaches_the_new_canvas() {
        use crate::viewer::canvas::Canvas;
        let old = RenderJob::start(spec(400, 300), 1, || {}).unwrap();
        // Let some old rows arrive, as they would while the user drags.
        let first = old.next_row_blocking().unwrap();
        let mut canvas = Canvas::new(1, 400, 300, 4096);
        assert!(canvas.apply(&first));
        // The view changes: a new job and a new canvas replace the old ones.
        let new = RenderJob::start(spec(400, 300), 2, || {}).unwrap();
        old.cancel();
        let mut canvas = Canvas::replacing(Some(&canvas), 2, 400, 300, 4096);
        // Everything the old job still delivers is refused ...
        let mut stale = 0;
        while let Some(row) = old.next_row_blocking() {
            assert!(!canvas.apply(&row), "a row of the old job was applied");
            stale += 1;
        }
        // ... and the new job completes the canvas on its own.
        while let Some(row) = new.next_row_blocking() {
            assert!(canvas.apply(&row));
        }
        assert!(canvas.is_complete());
        assert!(stale < 300, "the old job was not cancelled");
    }

    #[test]
    fn a_panic_in_a_band_stops_the_job_and_is_reported_not_propagated() {
        let job = RenderJob::spawn(
            spec(50, 40),
            1,
            || {},
            Box::new(|r, rows, columns, samples, sums| {
                if rows.contains(&7) {
                    panic!("boom at seven");
                }
                r.accumulate_region(rows, columns, samples, sums)
            }),
        )
        .unwrap();
        let mut delivered = 0;
        while job.next_row_blocking().is_some() {
            delivered += 1;
        }
        assert!(delivered < 40);
        assert_eq!(job.failure().as_deref(), Some("rows 0–7: boom at seven"));
        assert_eq!(job.elapsed(), None);
        // The pool survives: the next job renders every row.
        let next = RenderJob::start(spec(50, 40), 2, || {}).unwrap();
        let mut rows = 0;
        while next.next_row_blocking().is_some() {
            rows += 1;
        }
        assert_eq!((rows, next.failure()), (40, None));
    }

    #[test]
    fn a_pass_in_flight_leaves_the_sums_readable_and_stop_abandons_it_between_chunks() {
        // One band of rows; the pass 256..1024 is 12 chunks, and its first
        // chunk is held inside the band function until the test lets it go.
        // Before, the band stayed locked for a whole pass (inspection waited
        // for it) and Stop waited for the pass to end. No timing decides
        // the outcome: a watchdog frees the held chunk after 5 s, so an
        // inspection that waits for the chunk returns only then.
        let calls = Arc::new(AtomicU32::new(0));
        let counted = calls.clone();
        let (entered_tx, entered) = mpsc::channel::<()>();
        let (release, release_rx) = mpsc::channel::<()>();
        let release_rx = Mutex::new(release_rx);
        let mut s = spec(8, 8);
        s.spp = 1024;
        let job = RenderJob::spawn(
            s,
            1,
            || {},
            Box::new(move |r, rows, columns, samples, sums| {
                counted.fetch_add(1, Ordering::Relaxed);
                if samples.start >= 256 {
                    entered_tx.send(()).ok();
                    // Held until released, or every sender is gone.
                    release_rx.lock().unwrap().recv().ok();
                }
                r.accumulate_region(rows, columns, samples, sums)
            }),
        )
        .unwrap();
        while job.next_row_blocking().unwrap().samples < 256 {}
        entered.recv_timeout(Duration::from_secs(60)).expect("the pass from 256 samples began");
        let (done, watched) = mpsc::channel::<()>();
        let watchdog_release = release.clone();
        let watchdog = std::thread::spawn(move || {
            if watched.recv_timeout(Duration::from_secs(5)).is_err() {
                watchdog_release.send(()).ok();
            }
        });
        let asked = Instant::now();
        assert_eq!(job.linear(3, 3).map(|(_, n)| n), Some(256));
        let inspection = asked.elapsed();
        done.send(()).unwrap();
        watchdog.join().unwrap();
        assert!(inspection < Duration::from_secs(5), "inspection waited for the chunk in flight");
        job.stop();
        let at_stop = calls.load(Ordering::Relaxed);
        drop(release);
        let mut last = Vec::new();
        while let Some(row) = job.next_row_blocking() {
            last.push(row.samples);
        }
        assert_eq!(calls.load(Ordering::Relaxed), at_stop, "a chunk began after Stop");
        assert!(last.iter().all(|&n| n == 256), "{last:?}");
        assert!(job.elapsed().is_some());
        assert_eq!(job.linear(3, 3).map(|(_, n)| n), Some(256));
    }

    #[test]
    fn a_job_stopped_in_its_first_pass_completes_that_pass() {
        let mut s = spec(64, 400);
        s.spp = 16;
        let job = RenderJob::start(s, 1, || {}).unwrap();
        job.stop();
        let mut seen = vec![0; 400];
        while let Some(row) = job.next_row_blocking() {
            seen[row.y as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n >= 1), "rows missing after a stop in the first pass");
        assert!(job.elapsed().is_some() && job.stopped());
    }

    #[test]
    fn invalid_specs_are_refused_before_a_thread_starts() {
        let mut s = spec(10, 10);
        s.spp = 0;
        assert!(matches!(
            RenderJob::start(s, 1, || {}),
            Err(JobError::Settings(SettingsError::SamplesPerPixel(0)))
        ));
    }
}
