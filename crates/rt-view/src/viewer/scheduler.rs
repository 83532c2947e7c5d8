//! Which render runs, and the image it streams into.
//!
//! Any change cancels the job in flight and starts a new one with a new
//! generation, and a new [`Canvas`] for that generation: first a preview at
//! 1/[`PREVIEW_DIVISOR`] of the size with one sample, then, once the input
//! has been still for [`REFINE_AFTER`] (holding the mouse button without
//! moving counts as still), the full-resolution job. Each frame, the rows
//! that arrived are applied to their canvas and uploaded to the texture.
//!
//! What is on screen never mixes two views: a preview renders off screen
//! and replaces the image only when complete (a preview takes a frame or
//! two); the full-resolution job of the same view then streams its rows
//! over it (over the preview as far as it got, black below, if the full job
//! starts before the preview finished); a new scene starts from black.

use std::time::{Duration, Instant};

use egui::{TextureHandle, TextureOptions};

use super::canvas::Canvas;
use super::display::Display;
use super::interaction::Interaction;
use super::render_job::{JobSpec, RenderJob};

/// Preview jobs render at 1/PREVIEW_DIVISOR of the width and height.
pub const PREVIEW_DIVISOR: u32 = 4;
/// How long input must be still before the full-resolution render starts.
pub const REFINE_AFTER: Duration = Duration::from_millis(150);

/// What a job is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// A quick low-resolution render while the view moves.
    Preview,
    /// The full-resolution render with every sample.
    Full,
    /// The full render of a scene just (re)loaded: nothing of the old scene stays on screen.
    NewScene,
}

/// Statistics of the last completed full-resolution frame.
#[derive(Clone, Copy, Debug)]
struct FrameStats {
    seconds: f64,
    mrays_per_s: f64,
    /// Pixel samples (camera rays and everything they lead to) per second, millions.
    msamples_per_s: f64,
}

/// The current job, the image on screen and its texture, and when to refine.
#[derive(Default)]
pub(super) struct Scheduler {
    job: Option<RenderJob>,
    job_is_preview: bool,
    /// The image on screen.
    shown: Option<Canvas>,
    /// A preview being rendered off screen, shown once complete.
    pending: Option<Canvas>,
    texture: Option<TextureHandle>,
    filter: Option<TextureOptions>,
    next_generation: u64,
    /// A preview is on screen and a full render is due once input is still.
    refine_pending: bool,
    last_change: Option<Instant>,
    last_full: Option<FrameStats>,
    /// The display transform every canvas shows its image through.
    display: Display,
}

impl Scheduler {
    /// Starts the job for this frame's input, if one is due: a preview when
    /// something changed, the full render once nothing has changed or been
    /// dragged for [`REFINE_AFTER`]. `spec` gives the full-resolution job.
    /// Returns why a job could not start.
    pub fn schedule(
        &mut self,
        ctx: &egui::Context,
        input: Interaction,
        spec: impl FnOnce() -> Option<JobSpec>,
    ) -> Result<(), String> {
        let now = Instant::now();
        if input.changed {
            self.last_change = Some(now);
            self.refine_pending = true;
            return self.start(ctx, spec, Kind::Preview);
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
        self.start(ctx, spec, Kind::Full)
    }

    /// Cancels the job in flight and starts `spec` as a job of `kind` (at
    /// preview size with one sample for a preview), with a canvas of its own.
    pub fn start(
        &mut self,
        ctx: &egui::Context,
        spec: impl FnOnce() -> Option<JobSpec>,
        kind: Kind,
    ) -> Result<(), String> {
        let Some(mut spec) = spec() else { return Ok(()) };
        if kind == Kind::Preview {
            spec.width = (spec.width / PREVIEW_DIVISOR).max(1);
            spec.height = (spec.height / PREVIEW_DIVISOR).max(1);
            spec.spp = 1;
        }
        if kind == Kind::NewScene {
            self.refine_pending = false;
        }
        let (width, height) = (spec.width, spec.height);
        self.next_generation += 1;
        let generation = self.next_generation;
        let repaint = ctx.clone();
        let job = RenderJob::start(spec, generation, move || repaint.request_repaint())
            .map_err(|e| format!("cannot render: {e}"))?;
        self.job = Some(job); // Dropping the old job cancels it.
        self.job_is_preview = kind == Kind::Preview;
        let max_side = ctx.input(|i| i.max_texture_side);
        match kind {
            Kind::Preview => self.pending = Some(Canvas::new(generation, width, height, max_side)),
            Kind::Full => {
                // The full render streams over its own view's preview: the
                // one still being rendered if it did not finish in time
                // (its missing rows black), else the one on screen. Never
                // over an image of another view.
                let preview = self.pending.take();
                let base = preview.as_ref().or(self.shown.as_ref());
                let canvas = Canvas::replacing(base, generation, width, height, max_side);
                self.show(ctx, canvas);
            }
            Kind::NewScene => {
                self.pending = None;
                self.show(ctx, Canvas::new(generation, width, height, max_side));
            }
        }
        Ok(())
    }

    /// Puts `canvas` on screen, in a new texture if the size changed.
    fn show(&mut self, ctx: &egui::Context, mut canvas: Canvas) {
        let options = self.texture_options();
        match &mut self.texture {
            Some(t) if t.size() == canvas.display_size() => {
                let size = canvas.display_size();
                // The same texture, all of it replaced (the placeholder).
                let image = canvas.to_texture_image();
                t.set(egui::ColorImage::new(size, image), options);
            }
            _ => self.texture = Some(canvas.to_texture(ctx, options)),
        }
        self.shown = Some(canvas);
    }

    /// Nearest-neighbour for a magnified image and the blocky preview,
    /// linear otherwise.
    fn texture_options(&self) -> TextureOptions {
        self.filter.unwrap_or(if self.job_is_preview {
            TextureOptions::NEAREST
        } else {
            TextureOptions::LINEAR
        })
    }

    /// Shows the image with `options` from now on (the image view asks for
    /// nearest-neighbour when it magnifies the image).
    pub fn set_filter(&mut self, options: TextureOptions) {
        if self.filter == Some(options) {
            return;
        }
        self.filter = Some(options);
        if let (Some(t), Some(c)) = (&mut self.texture, &self.shown) {
            t.set(egui::ColorImage::new(c.display_size(), c.display_image()), options);
        }
    }

    /// Shows every image through `display` from now on (the canvases make
    /// their texels again, once, if it changed).
    pub fn set_display(&mut self, display: Display) {
        self.display = display;
        for canvas in [&mut self.shown, &mut self.pending].into_iter().flatten() {
            canvas.set_display(&self.display);
        }
    }

    /// Applies the rows that arrived since the last frame and uploads them;
    /// a preview that is complete goes on screen.
    pub fn apply_rows(&mut self, ctx: &egui::Context) {
        // Canvases started since the last `set_display` take the transform
        // before their first row.
        for canvas in [&mut self.shown, &mut self.pending].into_iter().flatten() {
            canvas.set_display(&self.display);
        }
        let Some(job) = &self.job else { return };
        for row in job.try_rows() {
            let row = match &mut self.pending {
                Some(c) => c.take(row),
                None => Err(row),
            };
            if let (Err(row), Some(c)) = (row, &mut self.shown) {
                let _ = c.take(row); // A row of no canvas shown is dropped.
            }
        }
        if self.pending.as_ref().is_some_and(Canvas::is_complete) {
            let preview = self.pending.take().expect("checked");
            self.show(ctx, preview);
        }
        let options = self.texture_options();
        let (Some(canvas), Some(texture)) = (&mut self.shown, &mut self.texture) else { return };
        canvas.upload_pending(texture, options);
        if canvas.is_complete()
            && !self.job_is_preview
            && canvas.generation() == job_generation(&self.job)
            && let Some(job) = &self.job
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

    /// The image on screen.
    pub fn canvas(&self) -> Option<&Canvas> {
        self.shown.as_ref()
    }

    /// The job whose rows make the image on screen, if it is the current one.
    pub fn shown_job(&self) -> Option<&RenderJob> {
        let job = self.job.as_ref()?;
        (self.shown.as_ref()?.generation() == job.generation()).then_some(job)
    }

    /// The texture the image is uploaded to.
    pub fn texture(&self) -> Option<&TextureHandle> {
        self.texture.as_ref()
    }

    /// Whether the full-resolution image has all its samples.
    pub fn frame_is_final(&self) -> bool {
        let complete = self.shown.as_ref().is_some_and(Canvas::is_complete);
        complete
            && !self.job_is_preview
            && self.pending.is_none()
            && self.job.as_ref().is_some_and(|j| j.elapsed().is_some())
    }

    /// The status line: progress of the job in flight (pass, rows, time,
    /// the pass's remaining time, rays per second) and the last full frame.
    pub fn status_ui(&self, ui: &mut egui::Ui) {
        let mut parts = Vec::new();
        if let Some(job) = &self.job {
            let spec = job.spec();
            let kind = if self.job_is_preview { "preview" } else { "full" };
            let p = job.progress();
            if job.elapsed().is_some() {
                parts.push(format!("{kind} {}×{} done, {} spp", spec.width, spec.height, spec.spp));
            } else {
                let mut s = format!("{kind} {}×{}", spec.width, spec.height);
                if p.passes > 1 {
                    s += &format!(
                        ", pass {}/{} ({}–{} spp)",
                        p.pass + 1,
                        p.passes,
                        p.samples.start,
                        p.samples.end
                    );
                }
                s += &format!(", rows {}/{}, {:.1} s", p.rows, p.height, p.elapsed.as_secs_f64());
                if let Some(eta) = p.pass_eta {
                    s += &format!(", pass ends in {:.1} s", eta.as_secs_f64());
                }
                s += &format!(", {:.2} Mrays/s", p.rays_per_second / 1e6);
                parts.push(s);
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

/// The generation of `job`, or 0 (no canvas has it) without one.
fn job_generation(job: &Option<RenderJob>) -> u64 {
    job.as_ref().map_or(0, RenderJob::generation)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Renderer;

    fn spec(position: rt_core::Vec3) -> JobSpec {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/showcase.ron");
        let scene = std::sync::Arc::new(rt_core::load_scene(&path).unwrap());
        let c = scene.camera;
        let camera = rt_core::Camera::new(
            position,
            c.center_of_interest(),
            c.up(),
            c.fov_y(),
            c.near(),
            c.projection(),
        )
        .unwrap();
        JobSpec { scene, camera, width: 160, height: 90, spp: 1, toggles: Default::default() }
    }

    fn wait(
        ctx: &egui::Context,
        s: &mut Scheduler,
        until: impl Fn(&Scheduler) -> bool,
        check: impl Fn(&Scheduler),
    ) {
        let deadline = Instant::now() + Duration::from_secs(30);
        while !until(s) {
            assert!(Instant::now() < deadline, "timed out");
            s.apply_rows(ctx);
            check(s);
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    #[test]
    fn a_change_of_view_never_shows_rows_of_two_views_at_once() {
        // Before, a change without dragging streamed the new view's rows
        // over the old image: a seam between two views until it finished.
        let ctx = egui::Context::default();
        let mut s = Scheduler::default();
        let first = spec(rt_core::Vec3::new(0.0, 2.0, -8.0));
        let moved = spec(rt_core::Vec3::new(3.0, 2.0, -8.0));
        s.start(&ctx, || Some(first.clone()), Kind::NewScene).unwrap();
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        let old = s.canvas().unwrap().pixels().to_vec();
        let settings = first.scene.settings.overridden(Some(160), Some(90), Some(1)).unwrap();
        let expected_old: Vec<egui::Color32> = Renderer::new(&first.scene.scene, first.camera, &settings)
            .unwrap()
            .render(|_| {})
            .to_rgb8()
            .iter()
            .map(|&[r, g, b]| egui::Color32::from_rgb(r, g, b))
            .collect();
        assert_eq!(old, expected_old);

        // The camera moves (a typed value, no drag): a preview renders off
        // screen; until it is complete the old image stays whole.
        s.schedule(&ctx, Interaction { changed: true, dragging: false }, || Some(moved.clone())).unwrap();
        wait(
            &ctx,
            &mut s,
            |s| s.canvas().is_some_and(|c| c.size() == [40, 22]),
            |s| {
                let c = s.canvas().unwrap();
                assert!(c.size() == [40, 22] || c.pixels() == old, "old and new rows mixed");
            },
        );
        assert!(s.canvas().unwrap().is_complete(), "a preview is shown only complete");
        // Still for REFINE_AFTER: the full render of the new view streams over its preview.
        std::thread::sleep(REFINE_AFTER);
        s.schedule(&ctx, Interaction::default(), || Some(moved.clone())).unwrap();
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        assert_eq!(s.canvas().unwrap().size(), [160, 90]);
        assert_ne!(s.canvas().unwrap().pixels(), &old[..]);

        // The view moves back, and the full render starts before its preview
        // finished (a slow preview, or input still for REFINE_AFTER sooner):
        // it streams over that unfinished preview, not over the image of the
        // view before, so from its start no pixel of the old view is shown.
        let shown_before = s.canvas().unwrap().display_image();
        s.schedule(&ctx, Interaction { changed: true, dragging: false }, || Some(first.clone())).unwrap();
        s.start(&ctx, || Some(first.clone()), Kind::Full).unwrap();
        let start = s.canvas().unwrap().display_image();
        assert!(
            start.iter().all(|&p| p == egui::Color32::BLACK),
            "the full render started over another view"
        );
        assert_ne!(start, shown_before);
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        assert_eq!(s.canvas().unwrap().pixels(), &old[..]);
        drop(s);
        ctx.tex_manager().write().take_delta().clear();
    }
}
