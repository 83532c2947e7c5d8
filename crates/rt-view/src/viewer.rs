//! The progressive viewer: `rt-view [SCENE]`.
//!
//! The app struct owns the UI state (camera settings, paths, messages) and a
//! handle to the current [`RenderJob`]; rows stream from the job into the
//! [`Canvas`] and from there into an egui texture, a batch per frame. Any
//! change of view cancels the job in flight and starts a new one with a new
//! generation; while the user drags, jobs render at 1/4 resolution and a
//! full-resolution job follows once the input has been still for
//! [`REFINE_AFTER`].

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context as _, anyhow};
use egui::{Color32, PointerButton, Rect, Sense, TextureHandle, TextureOptions, Vec2, pos2};
use rt_core::effects::{EffectPlan, EffectToggles};
use rt_core::{Projection, Real, Scene};

use crate::camera_controls::{CameraSettings, FOV_RANGE, NEAR_RANGE};
use crate::canvas::Canvas;
use crate::image_out::PendingImage;
use crate::render_job::{JobSpec, RenderJob};
use crate::scene_watch::SceneWatcher;

/// The built-in default scene's text (`scenes/default.ron`).
pub const DEFAULT_SCENE: &str = include_str!("../../../scenes/default.ron");
/// The name the built-in scene goes by in messages.
pub const DEFAULT_SCENE_NAME: &str = "<built-in default scene>";
/// Preview jobs render at 1/PREVIEW_DIVISOR of the width and height.
pub const PREVIEW_DIVISOR: u32 = 4;
/// How long input must be still before the full-resolution render starts.
pub const REFINE_AFTER: Duration = Duration::from_millis(150);
/// A scene file event is acted on after this much quiet (editors write in bursts).
const RELOAD_DEBOUNCE: Duration = Duration::from_millis(100);
/// Screenshot mode gives up after this long.
const SCREENSHOT_TIMEOUT: Duration = Duration::from_secs(120);

/// How the viewer is started.
#[derive(Clone, Debug, Default)]
pub struct ViewerOptions {
    /// Scene file to open; the built-in default scene when `None`.
    pub scene: Option<PathBuf>,
    /// Save a screenshot of the window here once the first full-resolution
    /// frame is complete, then exit (used by the smoke test).
    pub screenshot: Option<PathBuf>,
}

/// Loads the scene (the built-in one for `None`).
pub fn load(path: Option<&Path>) -> Result<Scene, rt_core::SceneError> {
    match path {
        Some(p) => rt_core::load_scene(p),
        None => rt_core::parse_scene(DEFAULT_SCENE, DEFAULT_SCENE_NAME, Path::new(".")),
    }
}

/// Opens the window and runs until it is closed.
pub fn run(options: ViewerOptions) -> anyhow::Result<()> {
    // A scene that cannot be read at start-up is an error on the command line;
    // later reloads show their errors in the window instead.
    let scene = load(options.scene.as_deref())?;
    if let Some(out) = &options.screenshot {
        // Check the output path now, not after the window has run.
        drop(PendingImage::png(out)?);
    }
    let outcome = Arc::new(Mutex::new(None));
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1180.0, 720.0])
            .with_min_inner_size([640.0, 400.0])
            .with_title("rt-view"),
        ..Default::default()
    };
    let app_outcome = outcome.clone();
    eframe::run_native(
        "rt-view",
        native,
        Box::new(move |cc| Ok(Box::new(Viewer::new(&cc.egui_ctx, scene, options, app_outcome)))),
    )
    .map_err(|e| anyhow!("cannot open the viewer window: {e}"))?;
    let result = outcome.lock().unwrap().take();
    result.unwrap_or(Ok(())).map_err(|e: String| anyhow!(e))
}

/// Statistics of the last completed full-resolution frame.
#[derive(Clone, Copy, Debug)]
struct FrameStats {
    seconds: f64,
    mrays_per_s: f64,
}

/// Screenshot mode's progress.
enum Screenshot {
    /// Waiting for a complete full-resolution frame; counts frames drawn since.
    Waiting { path: PathBuf, frames_since_complete: u32, started: Instant },
    /// Asked egui for the pixels; the callback finishes the job.
    Requested,
}

/// The viewer app: UI state plus a handle to the render in flight.
pub struct Viewer {
    scene_path: Option<PathBuf>,
    scene: Arc<Scene>,
    /// The camera as the scene file gave it: a reload that changes it resets the view.
    file_camera: rt_core::Camera,
    settings: CameraSettings,
    resolution_scale: f32,
    /// Samples per pixel of full renders (the scene's until the user changes it).
    spp: u32,
    /// Effects the user has switched off.
    toggles: EffectToggles,
    job: Option<RenderJob>,
    job_is_preview: bool,
    canvas: Option<Canvas>,
    texture: Option<TextureHandle>,
    next_generation: u64,
    refine_pending: bool,
    last_change: Instant,
    last_full: Option<FrameStats>,
    /// Why the scene could not be (re)loaded; stays until a load succeeds.
    error: Option<String>,
    /// Why the current render job stopped (a panic in a worker), if it did.
    render_failure: Option<String>,
    notice: Option<String>,
    watcher: Option<SceneWatcher>,
    reload_at: Option<Instant>,
    open_path: String,
    save_path: String,
    screenshot: Option<Screenshot>,
    outcome: Arc<Mutex<Option<Result<(), String>>>>,
}

impl Viewer {
    fn new(
        ctx: &egui::Context,
        scene: Scene,
        options: ViewerOptions,
        outcome: Arc<Mutex<Option<Result<(), String>>>>,
    ) -> Self {
        let settings = CameraSettings::from_camera(&scene.camera);
        let settings_spp = scene.samples_per_pixel;
        let mut viewer = Self {
            open_path: options.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
            scene_path: options.scene.clone(),
            file_camera: scene.camera,
            scene: Arc::new(scene),
            settings,
            resolution_scale: 1.0,
            spp: settings_spp,
            toggles: EffectToggles::default(),
            job: None,
            job_is_preview: false,
            canvas: None,
            texture: None,
            next_generation: 1,
            refine_pending: false,
            last_change: Instant::now(),
            last_full: None,
            error: None,
            render_failure: None,
            notice: None,
            watcher: None,
            reload_at: None,
            save_path: "render.png".to_owned(),
            screenshot: options.screenshot.map(|path| Screenshot::Waiting {
                path,
                frames_since_complete: 0,
                started: Instant::now(),
            }),
            outcome,
        };
        viewer.watch(ctx);
        viewer.start_job(ctx, false);
        viewer
    }

    /// Full-resolution image size: the scene's, times the resolution scale.
    fn full_size(&self) -> (u32, u32) {
        let scale = |n: u32| {
            ((n as f32 * self.resolution_scale).round() as u32).clamp(1, rt_core::view_plane::MAX_IMAGE_SIDE)
        };
        (scale(self.scene.width), scale(self.scene.height))
    }

    /// Cancels the job in flight and starts a new one for the current settings.
    fn start_job(&mut self, ctx: &egui::Context, preview: bool) {
        let Ok(camera) = self.settings.to_camera() else { return };
        let (mut width, mut height) = self.full_size();
        if preview {
            width = (width / PREVIEW_DIVISOR).max(1);
            height = (height / PREVIEW_DIVISOR).max(1);
        }
        let spp = if preview { 1 } else { self.spp };
        let generation = self.next_generation;
        self.next_generation += 1;
        let plan = EffectPlan::for_scene(&self.scene).restricted(self.toggles);
        let spec = JobSpec { scene: self.scene.clone(), camera, width, height, spp, plan };
        let repaint = ctx.clone();
        match RenderJob::start(spec, generation, move || repaint.request_repaint()) {
            Ok(job) => {
                self.job = Some(job); // Dropping the old job cancels it.
                let mut canvas = Canvas::replacing(self.canvas.as_ref(), generation, width, height);
                let same_size = self.texture.as_ref().is_some_and(|t| t.size() == canvas.size());
                // A new texture when the size or the filter changes; otherwise
                // the texture already shows the placeholder.
                if !same_size || preview != self.job_is_preview {
                    self.texture = Some(canvas.to_texture(ctx, texture_options(preview)));
                }
                self.job_is_preview = preview;
                self.canvas = Some(canvas);
            }
            Err(e) => self.error = Some(format!("cannot render: {e}")),
        }
    }

    /// Applies the rows that arrived since the last frame and uploads them.
    fn apply_rows(&mut self) {
        let (Some(job), Some(canvas), Some(texture)) = (&self.job, &mut self.canvas, &mut self.texture)
        else {
            return;
        };
        for row in job.try_rows() {
            canvas.apply(&row);
        }
        // Keep what is on screen; the next change of view starts a new job.
        self.render_failure =
            job.failure().map(|f| format!("render failed at {f}; change the view to try again"));
        canvas.upload_pending(texture, texture_options(self.job_is_preview));
        if canvas.is_complete()
            && !self.job_is_preview
            && let Some(elapsed) = job.elapsed()
        {
            let rays = job.rays() as f64;
            let seconds = elapsed.as_secs_f64();
            self.last_full = Some(FrameStats { seconds, mrays_per_s: rays / seconds.max(1e-9) / 1e6 });
        }
    }

    /// Starts watching the scene file, if there is one.
    fn watch(&mut self, ctx: &egui::Context) {
        self.watcher = None;
        if let Some(path) = &self.scene_path {
            let repaint = ctx.clone();
            match SceneWatcher::new(path, move || repaint.request_repaint()) {
                Ok(w) => self.watcher = Some(w),
                Err(e) => self.notice = Some(format!("not watching {}: {e}", path.display())),
            }
        }
    }

    /// Reloads after the scene file changed on disk (debounced).
    fn poll_watcher(&mut self, ctx: &egui::Context) {
        if self.watcher.as_ref().is_some_and(SceneWatcher::changed) {
            self.reload_at = Some(Instant::now() + RELOAD_DEBOUNCE);
        }
        if let Some(at) = self.reload_at {
            let now = Instant::now();
            if now >= at {
                self.reload_at = None;
                self.reload(ctx, false);
            } else {
                ctx.request_repaint_after(at - now);
            }
        }
    }

    /// Loads the scene file again. The user's camera edits are kept unless
    /// the file's camera changed (or `reset_camera`). On error the last good
    /// scene and image stay, and the error is shown.
    fn reload(&mut self, ctx: &egui::Context, reset_camera: bool) {
        match load(self.scene_path.as_deref()) {
            Ok(scene) => {
                if reset_camera || scene.camera != self.file_camera {
                    self.settings = CameraSettings::from_camera(&scene.camera);
                }
                if reset_camera || scene.samples_per_pixel != self.scene.samples_per_pixel {
                    self.spp = scene.samples_per_pixel;
                }
                self.file_camera = scene.camera;
                self.scene = Arc::new(scene);
                self.error = None;
                self.start_job(ctx, false);
            }
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    fn open(&mut self, ctx: &egui::Context) {
        let path = PathBuf::from(self.open_path.trim());
        let previous = self.scene_path.replace(path);
        match load(self.scene_path.as_deref()) {
            Ok(_) => {
                self.reload(ctx, true);
                self.watch(ctx);
            }
            Err(e) => {
                self.scene_path = previous;
                self.error = Some(e.to_string());
            }
        }
    }

    fn save(&mut self) {
        let Some(canvas) = self.canvas.as_ref().filter(|_| self.frame_is_final()) else {
            return;
        };
        let path = PathBuf::from(self.save_path.trim());
        let [width, height] = canvas.size();
        let saved = PendingImage::png(&path)
            .and_then(|png| png.write_rgb8(width as u32, height as u32, &canvas.rgb8()));
        self.notice = Some(match saved {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("not saved: {e:#}"),
        });
    }

    /// The side panel. Returns whether the view changed and whether a
    /// control is being dragged.
    fn controls_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) -> (bool, bool) {
        let mut s = self.settings;
        let mut dragging = false;
        let mut changed_scale = false;

        ui.heading("Scene");
        let name =
            self.scene_path.as_ref().map_or(DEFAULT_SCENE_NAME.to_owned(), |p| p.display().to_string());
        ui.label(name).on_hover_text("The scene file shown; it reloads when saved on disk.");
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.open_path)
                    .hint_text("path/to/scene.ron")
                    .desired_width(150.0),
            );
            if ui.button("Open").clicked() {
                self.open(ctx);
            }
        });
        if self.scene_path.is_some() && ui.button("Reload").clicked() {
            self.reload(ctx, false);
        }

        ui.separator();
        ui.heading("Camera");
        let mut fov = s.fov_y;
        let r = ui.add(egui::Slider::new(&mut fov, FOV_RANGE).text("FOV y (°)"));
        dragging |= r.dragged();
        s.fov_y = fov;
        let mut near = s.near;
        let r = ui.add(egui::Slider::new(&mut near, NEAR_RANGE).logarithmic(true).text("near"));
        dragging |= r.dragged();
        s.near = near;
        dragging |= vector_ui(ui, "position", &mut s.position);
        dragging |= vector_ui(ui, "look at", &mut s.center_of_interest);
        ui.horizontal(|ui| {
            ui.radio_value(&mut s.projection, Projection::Perspective, "perspective");
            ui.radio_value(&mut s.projection, Projection::Orthographic, "orthographic");
        });
        if ui.button("Reset camera").on_hover_text("Back to the scene file's camera").clicked() {
            s = CameraSettings::from_camera(&self.file_camera);
        }

        ui.separator();
        ui.heading("Image");
        let r = ui.add(egui::Slider::new(&mut self.resolution_scale, 0.25..=2.0).text("resolution scale"));
        dragging |= r.dragged();
        changed_scale |= r.changed();
        let (w, h) = self.full_size();
        ui.label(format!("{w} × {h} pixels"));
        let r = ui
            .add(egui::Slider::new(&mut self.spp, 1..=1024).logarithmic(true).text("samples per pixel"))
            .on_hover_text("Anti-aliasing and soft-shadow quality: shows 1 sample first, then refines");
        dragging |= r.dragged();
        changed_scale |= r.changed();
        changed_scale |= self.effects_ui(ui);
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path).desired_width(150.0));
            let ready = self.frame_is_final();
            if ui.add_enabled(ready, egui::Button::new("Save PNG")).clicked() {
                self.save();
            }
        });

        for e in [&self.error, &self.render_failure].into_iter().flatten() {
            ui.separator();
            ui.colored_label(Color32::from_rgb(220, 60, 50), e);
        }
        if let Some(n) = &self.notice {
            ui.separator();
            ui.label(n);
        }
        ui.separator();
        ui.small("Drag: orbit · Shift/right drag: pan · Wheel: zoom");

        let accepted = self.settings.accept(s);
        let changed = accepted != self.settings || changed_scale;
        if s != accepted && s != self.settings {
            self.notice = Some("that edit would make the camera degenerate: kept the last valid one".into());
        }
        self.settings = accepted;
        (changed, dragging)
    }

    /// Checkboxes for the effects the scene asks for (the others are shown
    /// disabled). Returns whether one changed.
    fn effects_ui(&mut self, ui: &mut egui::Ui) -> bool {
        let asked = EffectPlan::for_scene(&self.scene);
        let before = self.toggles;
        let t = &mut self.toggles;
        ui.horizontal_wrapped(|ui| {
            ui.add_enabled(asked.shadows, egui::Checkbox::new(&mut t.shadows, "shadows"));
            ui.add_enabled(asked.reflection, egui::Checkbox::new(&mut t.reflection, "reflection"));
            ui.add_enabled(asked.refraction, egui::Checkbox::new(&mut t.refraction, "refraction"));
            ui.add_enabled(
                asked.ambient_occlusion.is_some(),
                egui::Checkbox::new(&mut t.ambient_occlusion, "ambient occlusion"),
            );
        });
        if !asked.shading {
            ui.small("No lights: flat colours (pure ray casting).");
        }
        self.toggles != before
    }

    /// Whether the full-resolution image has all its samples.
    fn frame_is_final(&self) -> bool {
        let complete = self.canvas.as_ref().is_some_and(Canvas::is_complete);
        complete && !self.job_is_preview && self.job.as_ref().is_some_and(|j| j.elapsed().is_some())
    }

    /// The image, fitted to the panel, with mouse orbit, pan and zoom.
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
    fn image_ui(&mut self, ui: &mut egui::Ui) -> (bool, bool) {
        let (w, h) = self.full_size();
        let available = ui.available_rect_before_wrap();
        let fit = (available.width() / w as f32).min(available.height() / h as f32).max(0.01);
        let rect = Rect::from_center_size(available.center(), Vec2::new(w as f32 * fit, h as f32 * fit));
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        if let Some(texture) = &self.texture {
            let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
            ui.painter().image(texture.id(), rect, uv, Color32::WHITE);
        }
        let before = self.settings;
        let delta = response.drag_delta();
        let shift = ui.input(|i| i.modifiers.shift);
        let panning = response.dragged_by(PointerButton::Secondary)
            || response.dragged_by(PointerButton::Middle)
            || (shift && response.dragged_by(PointerButton::Primary));
        if panning {
            let k = self.settings.world_per_pixel(rect.height() as Real) as f32;
            self.settings = self.settings.pan((-delta.x * k) as Real, (delta.y * k) as Real);
        } else if response.dragged_by(PointerButton::Primary) {
            self.settings = self.settings.orbit((-delta.x * 0.01) as Real, (-delta.y * 0.01) as Real);
        }
        let scroll = if response.hovered() { ui.input(|i| i.smooth_scroll_delta.y) } else { 0.0 };
        if scroll != 0.0 {
            self.settings = self.settings.zoom((-scroll * 0.0015).exp() as Real);
        }
        (self.settings != before, response.dragged() || scroll != 0.0)
    }

    fn status_ui(&self, ui: &mut egui::Ui) {
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
            Some(f) => {
                parts.push(format!("last full frame {:.3} s, {:.2} Mrays/s", f.seconds, f.mrays_per_s))
            }
            None => parts.push("last full frame: —".into()),
        }
        ui.label(parts.join("  ·  "));
    }

    /// Screenshot mode: once a full frame has been on screen for two frames,
    /// ask for the window's pixels, save them and close.
    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let complete = self.frame_is_final();
        let Some(Screenshot::Waiting { path, frames_since_complete, started }) = &mut self.screenshot else {
            return;
        };
        if started.elapsed() > SCREENSHOT_TIMEOUT {
            *self.outcome.lock().unwrap() =
                Some(Err("screenshot: the frame did not complete in time".into()));
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        if !complete {
            ctx.request_repaint_after(Duration::from_millis(20));
            return;
        }
        *frames_since_complete += 1;
        if *frames_since_complete < 3 {
            ctx.request_repaint();
            return;
        }
        let path = path.clone();
        let outcome = self.outcome.clone();
        let close = ctx.clone();
        ctx.request_screenshot(move |image| {
            let result = save_screenshot(&path, &image).map_err(|e| format!("{e:#}"));
            *outcome.lock().unwrap() = Some(result);
            close.send_viewport_cmd(egui::ViewportCommand::Close);
            close.request_repaint();
        });
        self.screenshot = Some(Screenshot::Requested);
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.poll_watcher(&ctx);
        let (controls_changed, controls_dragging) = egui::Panel::left("controls")
            .resizable(false)
            .default_size(270.0)
            .show(ui, |ui| self.controls_ui(ui, &ctx))
            .inner;
        egui::Panel::bottom("status").show(ui, |ui| self.status_ui(ui));
        let (image_changed, image_dragging) =
            egui::CentralPanel::default().show(ui, |ui| self.image_ui(ui)).inner;

        let now = Instant::now();
        let dragging = controls_dragging || image_dragging;
        if controls_changed || image_changed {
            self.last_change = now;
            self.start_job(&ctx, dragging);
            self.refine_pending = dragging;
        } else if self.refine_pending && !dragging {
            let still = now - self.last_change;
            if still >= REFINE_AFTER {
                self.refine_pending = false;
                self.start_job(&ctx, false);
            } else {
                ctx.request_repaint_after(REFINE_AFTER - still);
            }
        }
        self.apply_rows();
        self.screenshot_step(&ctx);
    }
}

/// Three drag values in a row; returns whether one is being dragged.
fn vector_ui(ui: &mut egui::Ui, label: &str, v: &mut rt_core::Vec3) -> bool {
    ui.horizontal(|ui| {
        ui.label(label);
        let speed = 0.01 * v.abs().max_element().max(1.0);
        let mut dragging = false;
        for axis in 0..3 {
            let mut value = v[axis];
            let r = ui.add(egui::DragValue::new(&mut value).speed(speed).max_decimals(3));
            dragging |= r.dragged();
            v[axis] = value;
        }
        dragging
    })
    .inner
}

/// Nearest-neighbour magnification for the blocky preview, linear otherwise.
fn texture_options(preview: bool) -> TextureOptions {
    if preview { TextureOptions::NEAREST } else { TextureOptions::LINEAR }
}

/// Writes a window screenshot as an RGB PNG, atomically.
fn save_screenshot(path: &Path, image: &egui::ColorImage) -> anyhow::Result<()> {
    let [width, height] = image.size;
    let pixels: Vec<_> = image.pixels.iter().map(|c| [c.r(), c.g(), c.b()]).collect();
    PendingImage::png(path)?.write_rgb8(width as u32, height as u32, &pixels).context("screenshot")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Drives `viewer` until its full-resolution canvas is complete.
    fn finish_render(viewer: &mut Viewer) {
        let deadline = Instant::now() + Duration::from_secs(30);
        while !viewer.canvas.as_ref().is_some_and(Canvas::is_complete) {
            assert!(Instant::now() < deadline, "render did not complete");
            viewer.apply_rows();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn a_reload_that_fails_shows_the_error_and_keeps_the_last_good_image() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let good =
            std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere.ron"))
                .unwrap()
                .replace("width: 320, height: 240", "width: 64, height: 48");
        std::fs::write(&path, &good).unwrap();

        let ctx = egui::Context::default();
        let options = ViewerOptions { scene: Some(path.clone()), screenshot: None };
        let mut viewer = Viewer::new(&ctx, load(Some(&path)).unwrap(), options, Arc::default());
        finish_render(&mut viewer);
        let image = viewer.canvas.as_ref().unwrap().pixels().to_vec();
        assert!(image.contains(&Color32::from_rgb(230, 38, 26)), "the sphere is not in the image");

        std::fs::write(&path, good.replace("radius: 1.2", "radius: -1.2")).unwrap();
        viewer.reload(&ctx, false);
        let error = viewer.error.clone().expect("the error is shown");
        assert!(error.contains("scene.ron:") && error.contains("sphere radius must be positive"), "{error}");
        viewer.apply_rows();
        assert_eq!(viewer.canvas.as_ref().unwrap().pixels(), &image[..], "the last good image changed");

        // Fixing the file clears the error and renders again.
        std::fs::write(&path, good.replace("(0.9, 0.15, 0.1)", "(0.1, 0.9, 0.1)")).unwrap();
        viewer.reload(&ctx, false);
        assert_eq!(viewer.error, None);
        finish_render(&mut viewer);
        assert!(viewer.canvas.as_ref().unwrap().pixels().contains(&Color32::from_rgb(26, 230, 26)));

        drop(viewer);
        ctx.tex_manager().write().take_delta().clear();
    }
}
