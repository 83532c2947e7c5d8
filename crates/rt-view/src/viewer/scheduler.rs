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
//!
//! A region render ([`Scheduler::start_region`]) renders a rectangle of the
//! image on screen again: its rows go into the same canvas, the rest of the
//! image stays as it was. Any other job ends it.

use std::time::{Duration, Instant};

use egui::{Color32, TextureHandle, TextureOptions};

use super::canvas::Canvas;
use super::display::Display;
use super::interaction::Interaction;
use super::region::Region;
use super::render_job::{JobSpec, RenderJob, Row};

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
    /// The job had ended before rows were last taken: every row it sent
    /// is applied (its end is set after its last row is sent).
    job_drained: bool,
    /// The display transform every canvas shows its image through.
    display: Display,
}

/// `seconds` as the status line shows it: "4.2 s", "3 min 05 s", "2 h 07 min".
pub(super) fn duration_text(seconds: f64) -> String {
    let s = seconds.max(0.0);
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        format!("{} min {:02} s", (s / 60.0) as u64, (s % 60.0) as u64)
    } else {
        format!("{} h {:02} min", (s / 3600.0) as u64, (s % 3600.0 / 60.0) as u64)
    }
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
            // Dragging stays fast: the full render after it is denoised.
            spec.denoise = false;
        }
        if kind == Kind::NewScene {
            self.refine_pending = false;
            // The figures were the old scene's.
            self.last_full = None;
        }
        let (width, height) = (spec.width, spec.height);
        self.next_generation += 1;
        let generation = self.next_generation;
        let repaint = ctx.clone();
        let job = RenderJob::start(spec, generation, move || repaint.request_repaint())
            .map_err(|e| format!("cannot render: {e}"))?;
        self.job = Some(job); // Dropping the old job cancels it.
        self.job_drained = false;
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

    /// Renders `region` of the full-resolution image on screen again with
    /// `spec` (the current view's full job): the job in flight stops, its
    /// rows go into the image on screen, and the rest of the image stays
    /// as it was. Refused while no full-resolution image of the current
    /// view is on screen (a preview, or a region that does not fit).
    pub fn start_region(
        &mut self,
        ctx: &egui::Context,
        mut spec: JobSpec,
        region: Region,
    ) -> Result<(), String> {
        let Some(canvas) = &self.shown else { return Err("no image to render a region of".into()) };
        // Every row of the full image once, so the rest stays as it is.
        let on_screen = canvas.size() == [spec.width as usize, spec.height as usize] && canvas.is_complete();
        if self.job_is_preview || self.pending.is_some() || self.refine_pending || !on_screen {
            return Err("a region renders once the full image's first pass is on screen; try again".into());
        }
        spec.region = Some(region);
        // The canvas's own generation: its rows are this image's.
        let generation = canvas.generation();
        let repaint = ctx.clone();
        let job = RenderJob::start(spec, generation, move || repaint.request_repaint())
            .map_err(|e| format!("cannot render the region: {e}"))?;
        self.job = Some(job);
        self.job_drained = false;
        Ok(())
    }

    /// The region being rendered or rendered last, if the image on screen has one.
    pub fn region(&self) -> Option<&Region> {
        self.shown_job()?.spec().region.as_ref()
    }

    /// Ends the job in flight as it stands (a render with no sample limit
    /// ends only so): what is on screen becomes the finished image once its
    /// last rows arrive, if every row has arrived once.
    pub fn stop(&mut self) {
        if let Some(job) = &self.job {
            job.stop();
        }
    }

    /// Whether a job is in flight that [`Scheduler::stop`] would end.
    pub fn can_stop(&self) -> bool {
        self.job.as_ref().is_some_and(|j| j.elapsed().is_none() && !j.stopped() && j.failure().is_none())
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
        let region_start = job.spec().region.as_ref().map(|r| r.columns.start as usize);
        let ended = job.elapsed().is_some();
        for row in job.try_rows() {
            if let (Some(x), Some(c)) = (region_start, &mut self.shown) {
                let _ = c.take(whole_row(c, x, row));
                continue;
            }
            let row = match &mut self.pending {
                Some(c) => c.take(row),
                None => Err(row),
            };
            if let (Err(row), Some(c)) = (row, &mut self.shown) {
                let _ = c.take(row); // A row of no canvas shown is dropped.
            }
        }
        self.job_drained |= ended;
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
            && job.spec().region.is_none()
            && self.job_drained
            && let Some(elapsed) = job.elapsed()
        {
            let rays = job.rays() as f64;
            let samples = job.pixel_samples() as f64;
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

    /// The job in flight (or finished), and whether it is a preview.
    pub fn job(&self) -> Option<(&RenderJob, bool)> {
        Some((self.job.as_ref()?, self.job_is_preview))
    }

    /// The texture the image is uploaded to.
    pub fn texture(&self) -> Option<&TextureHandle> {
        self.texture.as_ref()
    }

    /// Whether the full-resolution image has all its samples (or those it
    /// had when stopped), every row the job sent applied.
    pub fn frame_is_final(&self) -> bool {
        let complete = self.shown.as_ref().is_some_and(Canvas::is_complete);
        complete && !self.job_is_preview && self.pending.is_none() && self.job_drained
    }

    /// The status line: a Stop button while a job runs, its progress
    /// (pass, samples per pixel so far, rows, time, the time to the pass's
    /// end, to the last pass's and to `target` samples per pixel, rays per
    /// second) and the last full frame.
    pub fn status_ui(&mut self, ui: &mut egui::Ui, target: Option<u32>) {
        ui.horizontal_wrapped(|ui| {
            if self.can_stop()
                && ui.button("Stop").on_hover_text("Space: keep the image as it stands").clicked()
            {
                self.stop();
            }
            ui.label(self.status_text(target));
        });
    }

    /// The text of the status line ([`Scheduler::status_ui`]).
    pub fn status_text(&self, target: Option<u32>) -> String {
        let mut parts = Vec::new();
        if let Some(job) = &self.job {
            let spec = job.spec();
            let kind = match (self.job_is_preview, &spec.region) {
                (true, _) => "preview".to_owned(),
                (false, None) => "full".to_owned(),
                (false, Some(r)) => format!("region {}×{} of", r.width(), r.height()),
            };
            let p = job.progress();
            let limit = if p.open_ended { " no limit,".to_owned() } else { String::new() };
            if job.elapsed().is_some() {
                let how = if job.stopped() { "stopped" } else { "done" };
                parts.push(format!("{kind} {}×{}{limit} {how}, {} spp", spec.width, spec.height, p.spp));
            } else if job.stopped() {
                parts.push(format!(
                    "{kind} {}×{}{limit} stopping, {}",
                    spec.width,
                    spec.height,
                    duration_text(p.elapsed.as_secs_f64())
                ));
            } else {
                let mut s = format!("{kind} {}×{}{limit} {} spp", spec.width, spec.height, p.spp);
                if p.open_ended {
                    s += &format!(", pass {} ({}–{} spp)", p.pass + 1, p.samples.start, p.samples.end);
                } else if p.passes > 1 {
                    s += &format!(
                        ", pass {}/{} ({}–{} spp)",
                        p.pass + 1,
                        p.passes,
                        p.samples.start,
                        p.samples.end
                    );
                }
                s += &format!(", rows {}/{}, {}", p.rows, p.height, duration_text(p.elapsed.as_secs_f64()));
                match p.pass_eta {
                    Some(eta) => s += &format!(", pass ends in {}", duration_text(eta.as_secs_f64())),
                    None if p.pass == 0 && !self.job_is_preview => s += ", estimating the time left",
                    None => {}
                }
                if let Some(eta) = p.eta.filter(|_| p.passes > p.pass + 1) {
                    s += &format!(", done in {}", duration_text(eta.as_secs_f64()));
                }
                if let Some(target) = target.filter(|&t| t > p.spp && !self.job_is_preview)
                    && let Some(eta) = job.eta_to(target)
                {
                    s += &format!(", {target} spp in {}", duration_text(eta.as_secs_f64()));
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
        parts.join("  ·  ")
    }
}

/// `row`, `x` columns in, as a whole row of `canvas` (its other pixels as
/// they are on screen): a region job's rows applied to the image.
fn whole_row(canvas: &Canvas, x: usize, row: Row) -> Row {
    let [width, _] = canvas.size();
    let mut pixels = canvas.pixel_row(row.y).map_or_else(|| vec![Color32::TRANSPARENT; width], <[_]>::to_vec);
    let mut linear = canvas.linear_row(row.y).map_or_else(|| vec![[0.0; 3]; width], <[_]>::to_vec);
    if let Some(span) = pixels.get_mut(x..x + row.pixels.len()) {
        span.copy_from_slice(&row.pixels);
    }
    if let Some(span) = linear.get_mut(x..x + row.linear.len()) {
        span.copy_from_slice(&row.linear);
    }
    Row { pixels, linear, ..row }
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
        JobSpec {
            scene,
            camera,
            width: 160,
            height: 90,
            spp: 1,
            open_ended: false,
            region: None,
            toggles: Default::default(),
            denoise: false,
        }
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

    /// The `spec`'s image as `Renderer::render` makes it.
    fn headless(spec: &JobSpec) -> Vec<egui::Color32> {
        let settings =
            spec.scene.settings.overridden(Some(spec.width), Some(spec.height), Some(spec.spp)).unwrap();
        Renderer::new(&spec.scene.scene, spec.camera, &settings)
            .unwrap()
            .render(|_| {})
            .to_rgb8()
            .iter()
            .map(|&[r, g, b]| egui::Color32::from_rgb(r, g, b))
            .collect()
    }

    fn clear_textures(ctx: &egui::Context, s: Scheduler) {
        drop(s);
        ctx.tex_manager().write().take_delta().clear();
    }

    #[test]
    fn a_region_renders_only_its_pixels_into_the_image_on_screen_and_the_rest_stays() {
        let ctx = egui::Context::default();
        let mut s = Scheduler::default();
        let view = spec(rt_core::Vec3::new(0.0, 2.0, -8.0));
        s.start(&ctx, || Some(view.clone()), Kind::NewScene).unwrap();
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        let one = headless(&view);
        assert_eq!(s.canvas().unwrap().pixels(), &one[..]);
        // More samples, in a region only (as if spp changed and a region
        // were drawn before the full render restarted).
        let region = Region { columns: 30..95, rows: 20..61 };
        let nine = JobSpec { spp: 9, ..view.clone() };
        s.start_region(&ctx, nine.clone(), region.clone()).unwrap();
        let generation = s.canvas().unwrap().generation();
        assert!(!s.frame_is_final());
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        assert_eq!((s.region(), s.canvas().unwrap().generation()), (Some(&region), generation));
        let nine = headless(&nine);
        let shown = s.canvas().unwrap().pixels();
        for y in 0..90 {
            for x in 0..160 {
                let (i, inside) = (y * 160 + x, region.contains(x as u32, y as u32));
                let expected = if inside { nine[i] } else { one[i] };
                assert!(shown[i] == expected, "pixel ({x}, {y}), inside {inside}");
            }
        }
        assert!(
            s.status_text(None).starts_with("region 65×41 of 160×90 done, 9 spp"),
            "{}",
            s.status_text(None)
        );
        // The display (texture) image shows it too.
        assert_eq!(s.canvas().unwrap().display_image(), shown);
        // A change of view ends the region; a preview refuses a new one.
        s.schedule(&ctx, Interaction { changed: true, dragging: false }, || Some(view.clone())).unwrap();
        assert_eq!(s.region(), None);
        assert!(s.start_region(&ctx, view.clone(), region).is_err());
        clear_textures(&ctx, s);
    }

    #[test]
    fn a_render_with_no_limit_goes_on_until_stopped_and_is_then_final() {
        let ctx = egui::Context::default();
        let mut s = Scheduler::default();
        let view =
            JobSpec { width: 16, height: 9, open_ended: true, ..spec(rt_core::Vec3::new(0.0, 2.0, -8.0)) };
        s.start(&ctx, || Some(view.clone()), Kind::NewScene).unwrap();
        // Past the fixed cap of 1024 samples per pixel.
        wait(&ctx, &mut s, |s| s.shown_job().unwrap().progress().spp > 1024, |_| {});
        assert!(!s.frame_is_final() && s.can_stop());
        let text = s.status_text(Some(1 << 20));
        assert!(text.contains("no limit") && text.contains(" spp in "), "{text}");
        s.stop();
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        assert!(!s.can_stop());
        let text = s.status_text(None);
        assert!(text.contains("no limit, stopped") && !text.contains("last full frame: —"), "{text}");
        clear_textures(&ctx, s);
    }

    #[test]
    fn the_image_is_final_only_once_the_rows_sent_before_the_jobs_end_are_applied() {
        // Before, a finished job made the image final at once, though its
        // last rows could still wait in the channel (Save then wrote them
        // without their last pass).
        let ctx = egui::Context::default();
        let mut s = Scheduler::default();
        let view = JobSpec { spp: 64, ..spec(rt_core::Vec3::new(0.0, 2.0, -8.0)) };
        s.start(&ctx, || Some(view.clone()), Kind::NewScene).unwrap();
        wait(&ctx, &mut s, |s| s.canvas().unwrap().is_complete(), |_| {});
        while s.job.as_ref().unwrap().elapsed().is_none() {
            std::thread::sleep(Duration::from_millis(1));
        }
        assert!(!s.frame_is_final(), "final with rows of the last pass not applied");
        s.apply_rows(&ctx);
        assert!(s.frame_is_final());
        assert_eq!(s.canvas().unwrap().pixels(), &headless(&view)[..]);
        clear_textures(&ctx, s);
    }

    #[test]
    fn a_new_scene_clears_the_last_full_frames_figures() {
        // Before, "last full frame" kept the previous scene's figures.
        let ctx = egui::Context::default();
        let mut s = Scheduler::default();
        let view = spec(rt_core::Vec3::new(0.0, 2.0, -8.0));
        s.start(&ctx, || Some(view.clone()), Kind::NewScene).unwrap();
        wait(&ctx, &mut s, Scheduler::frame_is_final, |_| {});
        s.apply_rows(&ctx);
        assert!(s.status_text(None).contains("last full frame 0."), "{}", s.status_text(None));
        s.start(&ctx, || Some(view.clone()), Kind::NewScene).unwrap();
        assert!(s.status_text(None).contains("last full frame: —"), "{}", s.status_text(None));
        clear_textures(&ctx, s);
    }

    #[test]
    fn durations_read_in_seconds_minutes_or_hours() {
        assert_eq!(duration_text(4.23), "4.2 s");
        assert_eq!(duration_text(185.0), "3 min 05 s");
        assert_eq!(duration_text(7650.0), "2 h 07 min");
    }
}
