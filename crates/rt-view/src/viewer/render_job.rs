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
//! Cancelling (or dropping the job, or dropping its receiver) stops the
//! workers after the band of rows each is on; rows already in the channel keep their
//! old generation, and [`super::canvas::Canvas`] refuses them.

use std::ops::Range;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::atomic::{AtomicBool, AtomicU32, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, TryIter};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use egui::Color32;
use rt_core::math::color::Color;
use rt_core::render::{BAND_ROWS, RenderError};
use rt_core::scene::effects::{EffectToggles, RayCounts};
use rt_core::{Camera, LoadedScene, RenderSettings, Renderer, SettingsError};

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

/// One band's running sums (its rows one after the other) and how many
/// samples they hold: every row of a band is rendered with the others.
struct BandSums {
    samples: u32,
    sums: Vec<Color>,
}

/// The band function: adds `samples` of the rows `rows` to `sums`, which
/// holds them one after the other (tests replace it).
type BandFn = dyn Fn(&Renderer, Range<u32>, Range<u32>, &mut [Color]) -> RayCounts + Send + Sync;

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
    /// Samples per pixel.
    pub spp: u32,
    /// The effects the user switched off (the rest of the settings are the file's).
    pub toggles: EffectToggles,
}

impl JobSpec {
    fn renderer(&self) -> Result<Renderer<'_>, JobError> {
        let settings = RenderSettings { toggles: self.toggles, ..self.scene.settings }.overridden(
            Some(self.width),
            Some(self.height),
            Some(self.spp),
        )?;
        Ok(Renderer::new(&self.scene.scene, self.camera, &settings)?)
    }
}

/// Why a job cannot start.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum JobError {
    /// The size or sample count is out of range.
    #[error(transparent)]
    Settings(#[from] SettingsError),
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
    /// One colour per column, encoded in the scene's colour space (what
    /// the display shows at exposure 0).
    pub pixels: Vec<Color32>,
    /// One linear colour per column: the mean of its samples so far
    /// (scene-referred radiance, not clamped).
    pub linear: Vec<[f32; 3]>,
}

/// A running (or finished, or cancelled) render.
pub struct RenderJob {
    spec: JobSpec,
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
    /// How many passes the job makes.
    pub passes: usize,
    /// The samples the pass adds to each pixel.
    pub samples: Range<u32>,
    /// Rows of the pass finished.
    pub rows: u32,
    /// Rows of the image.
    pub height: u32,
    /// Time since the job started.
    pub elapsed: Duration,
    /// Time the pass will still take at the rate so far (`None` before
    /// the first row, and once the pass is done).
    pub pass_eta: Option<Duration>,
    /// Rays of all kinds per second so far.
    pub rays_per_second: f64,
}

/// What the workers report to the job's handle.
struct Shared {
    /// Each band's running sums of linear colour (bands of [`BAND_ROWS`]).
    bands: Vec<Mutex<BandSums>>,
    /// Set to stop the workers after their current band of rows.
    cancel: AtomicBool,
    /// Rays cast so far, all kinds.
    rays: AtomicU64,
    /// Rows finished so far, over all passes.
    rows_rendered: AtomicU32,
    /// Wall time from start to the last row, once every row is rendered.
    elapsed: Mutex<Option<Duration>>,
    /// "rows A–B: message" of the first band that panicked.
    failure: Mutex<Option<String>>,
}

impl Shared {
    fn new(width: u32, height: u32) -> Self {
        Self {
            bands: (0..height)
                .step_by(BAND_ROWS as usize)
                .map(|y| {
                    let pixels = (BAND_ROWS.min(height - y) * width) as usize;
                    Mutex::new(BandSums { samples: 0, sums: vec![Color::ZERO; pixels] })
                })
                .collect(),
            cancel: AtomicBool::new(false),
            rays: AtomicU64::new(0),
            rows_rendered: AtomicU32::new(0),
            elapsed: Mutex::new(None),
            failure: Mutex::new(None),
        }
    }

    fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
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
            Box::new(|renderer, rows, samples, sums| renderer.accumulate_rows(rows, samples, sums)),
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
        let shared = Arc::new(Shared::new(spec.width, spec.height));
        let (tx, rows) = mpsc::channel();
        let worker =
            Worker { spec: spec.clone(), generation, shared: shared.clone(), tx, on_row, render_band };
        std::thread::Builder::new()
            .name(format!("render-job-{generation}"))
            .spawn(move || worker.run())
            .expect("the OS can start a thread");
        Ok(Self { spec, rows, shared, started: Instant::now(), generation })
    }

    /// The generation its rows carry.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The linear colour of pixel (x, y) so far (the mean of its samples)
    /// and how many samples it has; `None` outside the image or before its
    /// row's first pass.
    pub fn linear(&self, x: u32, y: u32) -> Option<(Color, u32)> {
        if x >= self.spec.width {
            return None;
        }
        let band = self.shared.bands.get((y / BAND_ROWS) as usize)?.lock().unwrap_or_else(|e| e.into_inner());
        let sum = *band.sums.get(((y % BAND_ROWS) * self.spec.width + x) as usize)?;
        (band.samples > 0).then(|| (sum / band.samples as f32, band.samples))
    }

    /// Rays cast so far, all kinds together.
    pub fn rays(&self) -> u64 {
        self.shared.rays.load(Ordering::Relaxed)
    }

    /// The pass in progress and how many of its rows are finished, the time
    /// so far, the time the pass still needs, and the rate of rays.
    ///
    /// The estimate counts work in samples × rows: the rate so far is the
    /// work done over the time taken, and the pass needs its remaining rows
    /// times its samples at that rate.
    pub fn progress(&self) -> Progress {
        let passes = sample_passes(self.spec.spp);
        let height = self.spec.height;
        let done = self.shared.rows_rendered.load(Ordering::Relaxed);
        let pass = ((done / height) as usize).min(passes.len() - 1);
        let rows = (done - pass as u32 * height).min(height);
        let elapsed = self.elapsed().unwrap_or_else(|| self.started.elapsed());
        let seconds = elapsed.as_secs_f64().max(1e-9);
        let len = |r: &Range<u32>| (r.end - r.start) as f64;
        let work: f64 = passes[..pass].iter().map(|r| len(r) * height as f64).sum::<f64>()
            + len(&passes[pass]) * rows as f64;
        let remaining = len(&passes[pass]) * (height - rows) as f64;
        let pass_eta =
            (work > 0.0 && remaining > 0.0).then(|| Duration::from_secs_f64(remaining * seconds / work));
        Progress {
            pass,
            passes: passes.len(),
            samples: passes[pass].clone(),
            rows,
            height,
            elapsed,
            pass_eta,
            rays_per_second: self.rays() as f64 / seconds,
        }
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

    /// Rows that have arrived since the last call, without waiting.
    pub fn try_rows(&self) -> TryIter<'_, Row> {
        self.rows.try_iter()
    }

    /// Waits for the next row; `None` once the job has ended and every row
    /// has been taken (used by tests and headless callers).
    pub fn next_row_blocking(&self) -> Option<Row> {
        self.rows.recv().ok()
    }

    /// Wall time from start to the last row, once every row is rendered
    /// (`None` while running or if cancelled).
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
    on_row: F,
    render_band: Box<BandFn>,
}

impl<F: Fn() + Send + Sync> Worker<F> {
    fn run(self) {
        let s = &self.spec;
        let renderer = s.renderer().expect("validated before the thread started");
        let passes = sample_passes(s.spp);
        let start = Instant::now();
        let bands = s.height.div_ceil(BAND_ROWS) as u64;
        let tasks = passes.len() as u64 * bands;
        let next_task = AtomicU64::new(0);
        rayon::broadcast(|_| {
            while !self.shared.cancelled() {
                let task = next_task.fetch_add(1, Ordering::Relaxed);
                if task >= tasks {
                    break;
                }
                let (pass, band) = ((task / bands) as usize, (task % bands) as u32);
                if !self.render(&renderer, band, passes[pass].clone()) {
                    break;
                }
            }
        });
        if !self.shared.cancelled() {
            *self.shared.elapsed.lock().unwrap_or_else(|e| e.into_inner()) = Some(start.elapsed());
            (self.on_row)();
        }
    }

    /// Adds `samples` to the sums of band `band` and sends each of its
    /// rows' new mean; false when the job is to stop (cancelled, the
    /// receiver gone, or a panic).
    fn render(&self, renderer: &Renderer, band: u32, samples: Range<u32>) -> bool {
        let rows = band * BAND_ROWS..((band + 1) * BAND_ROWS).min(self.spec.height);
        let cell = &self.shared.bands[band as usize];
        // This band's previous pass may still be running on another thread.
        let mut sums = loop {
            let sums = cell.lock().unwrap_or_else(|e| e.into_inner());
            if sums.samples == samples.start || self.shared.cancelled() {
                break sums;
            }
            drop(sums);
            std::thread::yield_now();
        };
        if sums.samples != samples.start {
            return false; // Cancelled while waiting.
        }
        let rendered = catch_unwind(AssertUnwindSafe(|| {
            (self.render_band)(renderer, rows.clone(), samples.clone(), &mut sums.sums)
        }));
        let counts = match rendered {
            Ok(counts) => counts,
            Err(payload) => {
                let mut failure = self.shared.failure.lock().unwrap_or_else(|e| e.into_inner());
                let (first, last) = (rows.start, rows.end - 1);
                failure.get_or_insert_with(|| format!("rows {first}–{last}: {}", panic_message(&*payload)));
                self.shared.cancel.store(true, Ordering::Relaxed);
                (self.on_row)(); // Wake the UI so it shows the failure.
                return false;
            }
        };
        sums.samples = samples.end;
        // The means exactly as `Renderer::pixel` computes them.
        let count = samples.end as f32;
        let color_space = renderer.color_space();
        let finished: Vec<Row> = rows
            .zip(sums.sums.chunks_exact(self.spec.width as usize))
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
        for row in finished {
            self.shared.rows_rendered.fetch_add(1, Ordering::Relaxed);
            if self.shared.cancelled() || self.tx.send(row).is_err() {
                self.shared.cancel.store(true, Ordering::Relaxed);
                return false;
            }
        }
        drop(sums);
        for _ in 0..sent {
            (self.on_row)();
        }
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
        JobSpec { camera: scene.camera, scene, width, height, spp: 1, toggles: EffectToggles::default() }
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
    fn progress_estimates_the_rest_of_the_pass_from_the_rate_so_far() {
        let mut s = spec(64, 2000);
        s.spp = 4;
        let job = RenderJob::start(s, 1, || {}).unwrap();
        // Wait for part of the first pass.
        let mut taken = 0;
        while taken < 100 {
            job.next_row_blocking().unwrap();
            taken += 1;
        }
        let p = job.progress();
        assert_eq!((p.passes, p.height), (2, 2000));
        if p.pass == 0 && p.rows < 2000 {
            assert!(p.pass_eta.is_some(), "{p:?}");
        }
        assert!(p.rays_per_second > 0.0 && p.elapsed > Duration::ZERO);
        job.cancel();
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
            Box::new(|r, rows, samples, sums| {
                if rows.contains(&7) {
                    panic!("boom at seven");
                }
                r.accumulate_rows(rows, samples, sums)
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
    fn invalid_specs_are_refused_before_a_thread_starts() {
        let mut s = spec(10, 10);
        s.spp = 0;
        assert!(matches!(
            RenderJob::start(s, 1, || {}),
            Err(JobError::Settings(SettingsError::SamplesPerPixel(0)))
        ));
    }
}
