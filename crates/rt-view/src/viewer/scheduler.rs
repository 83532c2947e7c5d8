//! Which render runs, and the image it streams into.
//!
//! Any change of view cancels the job in flight and starts a new one with a
//! new generation, and a new [`Canvas`] for that generation (starting from the
//! previous image, resampled). While the user drags, jobs render at
//! 1/[`PREVIEW_DIVISOR`] of the size with one sample; a full-resolution job
//! follows once the input has been still for [`REFINE_AFTER`]. Each frame,
//! the rows that arrived are applied to the canvas and uploaded to its
//! texture.

use std::time::{Duration, Instant};

use egui::{TextureHandle, TextureOptions};

use super::canvas::Canvas;
use super::interaction::Interaction;
use super::render_job::{JobSpec, RenderJob};

/// Preview jobs render at 1/PREVIEW_DIVISOR of the width and height.
pub const PREVIEW_DIVISOR: u32 = 4;
/// How long input must be still before the full-resolution render starts.
pub const REFINE_AFTER: Duration = Duration::from_millis(150);

/// Statistics of the last completed full-resolution frame.
#[derive(Clone, Copy, Debug)]
struct FrameStats {
    seconds: f64,
    mrays_per_s: f64,
    /// Pixel samples (camera rays and everything they lead to) per second, millions.
    msamples_per_s: f64,
}

/// The current job, its canvas and texture, and when to refine.
#[derive(Default)]
pub(super) struct Scheduler {
    job: Option<RenderJob>,
    job_is_preview: bool,
    canvas: Option<Canvas>,
    texture: Option<TextureHandle>,
    next_generation: u64,
    /// A preview is on screen and a full render is due once input is still.
    refine_pending: bool,
    last_change: Option<Instant>,
    last_full: Option<FrameStats>,
}

impl Scheduler {
    /// Starts the job for this frame's input, if one is due: a preview (or a
    /// full render when nothing is dragged) when the view `changed`, the full
    /// render once a preview has been still for [`REFINE_AFTER`]. `spec`
    /// gives the full-resolution job. Returns why a job could not start.
    pub fn schedule(
        &mut self,
        ctx: &egui::Context,
        input: Interaction,
        spec: impl FnOnce() -> Option<JobSpec>,
    ) -> Result<(), String> {
        let now = Instant::now();
        if input.changed {
            self.last_change = Some(now);
            self.refine_pending = input.dragging;
            return self.start(ctx, spec, input.dragging);
        }
        if !self.refine_pending || input.dragging {
            return Ok(());
        }
        let still = self.last_change.map_or(REFINE_AFTER, |t| now - t);
        if still < REFINE_AFTER {
            ctx.request_repaint_after(REFINE_AFTER - still);
            return Ok(());
        }
        self.refine_pending = false;
        self.start(ctx, spec, false)
    }

    /// Cancels the job in flight and starts `spec` (at preview size and one
    /// sample if `preview`), with a canvas of its own.
    pub fn start(
        &mut self,
        ctx: &egui::Context,
        spec: impl FnOnce() -> Option<JobSpec>,
        preview: bool,
    ) -> Result<(), String> {
        let Some(mut spec) = spec() else { return Ok(()) };
        if preview {
            spec.width = (spec.width / PREVIEW_DIVISOR).max(1);
            spec.height = (spec.height / PREVIEW_DIVISOR).max(1);
            spec.spp = 1;
        }
        let (width, height) = (spec.width, spec.height);
        self.next_generation += 1;
        let generation = self.next_generation;
        let repaint = ctx.clone();
        let job = RenderJob::start(spec, generation, move || repaint.request_repaint())
            .map_err(|e| format!("cannot render: {e}"))?;
        self.job = Some(job); // Dropping the old job cancels it.
        let mut canvas = Canvas::replacing(self.canvas.as_ref(), generation, width, height);
        let same_size = self.texture.as_ref().is_some_and(|t| t.size() == canvas.size());
        // A new texture when the size or the filter changes; otherwise the
        // texture already shows the placeholder.
        if !same_size || preview != self.job_is_preview {
            self.texture = Some(canvas.to_texture(ctx, texture_options(preview)));
        }
        self.job_is_preview = preview;
        self.canvas = Some(canvas);
        Ok(())
    }

    /// Applies the rows that arrived since the last frame and uploads them.
    pub fn apply_rows(&mut self) {
        let (Some(job), Some(canvas), Some(texture)) = (&self.job, &mut self.canvas, &mut self.texture)
        else {
            return;
        };
        for row in job.try_rows() {
            canvas.apply(&row);
        }
        canvas.upload_pending(texture, texture_options(self.job_is_preview));
        if canvas.is_complete()
            && !self.job_is_preview
            && let Some(elapsed) = job.elapsed()
        {
            let rays = job.rays() as f64;
            let spec = job.spec();
            let samples = spec.width as f64 * spec.height as f64 * spec.spp as f64;
            let seconds = elapsed.as_secs_f64().max(1e-9);
            self.last_full = Some(FrameStats {
                seconds,
                mrays_per_s: rays / seconds / 1e6,
                msamples_per_s: samples / seconds / 1e6,
            });
        }
    }

    /// Why the current job stopped, if a row panicked. What is on screen
    /// stays; the next change of view starts a new job.
    pub fn failure(&self) -> Option<String> {
        let failure = self.job.as_ref()?.failure()?;
        Some(format!("render failed at {failure}; change the view to try again"))
    }

    /// The image being shown.
    pub fn canvas(&self) -> Option<&Canvas> {
        self.canvas.as_ref()
    }

    /// The texture the image is uploaded to.
    pub fn texture(&self) -> Option<&TextureHandle> {
        self.texture.as_ref()
    }

    /// Whether the full-resolution image has all its samples.
    pub fn frame_is_final(&self) -> bool {
        let complete = self.canvas.as_ref().is_some_and(Canvas::is_complete);
        complete && !self.job_is_preview && self.job.as_ref().is_some_and(|j| j.elapsed().is_some())
    }

    /// The status line: progress of the job in flight and the last full frame's time.
    pub fn status_ui(&self, ui: &mut egui::Ui) {
        let mut parts = Vec::new();
        if let Some(c) = &self.canvas {
            let [w, h] = c.size();
            let kind = if self.job_is_preview { "preview" } else { "full" };
            match &self.job {
                Some(job) if job.spec().spp > 1 => {
                    let (samples, rows) = job.progress();
                    parts.push(format!("{samples}/{} spp, rows {rows}/{h} ({kind} {w}×{h})", job.spec().spp));
                }
                _ => parts.push(format!("rows {}/{h} ({kind} {w}×{h})", c.rows_done())),
            }
        }
        match self.last_full {
            Some(f) => parts.push(format!(
                "last full frame {:.3} s, {:.2} M samples/s, {:.2} Mrays/s",
                f.seconds, f.msamples_per_s, f.mrays_per_s
            )),
            None => parts.push("last full frame: —".into()),
        }
        ui.label(parts.join("  ·  "));
    }
}

/// Nearest-neighbour magnification for the blocky preview, linear otherwise.
fn texture_options(preview: bool) -> TextureOptions {
    if preview { TextureOptions::NEAREST } else { TextureOptions::LINEAR }
}
