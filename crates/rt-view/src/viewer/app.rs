//! The viewer app: composes the parts of the window and passes each frame's
//! input from them to the [`Scheduler`].
//!
//! The side panel stacks the scene source, the camera panel, the image
//! settings and Save; the status line and the image view come from the
//! scheduler and [`image_view`](super::image_view). No part renders or
//! waits: a change of view only asks the scheduler for a new job.

use std::path::PathBuf;

use egui::Color32;

use super::camera_panel::CameraPanel;
use super::image_settings::ImageSettings;
use super::image_view::image_ui;
use super::interaction::Interaction;
use super::render_job::JobSpec;
use super::scene_source::{SceneChange, SceneSource};
use super::scheduler::Scheduler;
use super::screenshot::{Outcome, Screenshot};
use crate::image_out::PendingImage;

/// How the viewer is started.
#[derive(Clone, Debug, Default)]
pub struct ViewerOptions {
    /// Scene file to open; the built-in default scene when `None`.
    pub scene: Option<PathBuf>,
    /// Save a screenshot of the window here once the first full-resolution
    /// frame is complete, then exit (used by the smoke test).
    pub screenshot: Option<PathBuf>,
}

/// The viewer app: its parts, and what the window reports when it closes.
pub struct Viewer {
    source: SceneSource,
    camera: CameraPanel,
    image: ImageSettings,
    scheduler: Scheduler,
    /// The path Save PNG writes to.
    save_path: String,
    /// The result of the last save, or why a render could not start.
    notice: Option<String>,
    screenshot: Option<Screenshot>,
    outcome: Outcome,
}

impl Viewer {
    /// The viewer on `scene` (loaded from `options.scene`), its first render started.
    pub(super) fn new(
        ctx: &egui::Context,
        scene: rt_core::Scene,
        options: ViewerOptions,
        outcome: Outcome,
    ) -> Self {
        let mut viewer = Self {
            camera: CameraPanel::new(&scene.camera),
            image: ImageSettings::new(&scene),
            source: SceneSource::new(options.scene, scene, ctx),
            scheduler: Scheduler::default(),
            save_path: "render.png".to_owned(),
            notice: None,
            screenshot: options.screenshot.map(Screenshot::new),
            outcome,
        };
        viewer.schedule(ctx, Interaction { changed: true, dragging: false });
        viewer
    }

    /// The full-resolution job for the current scene, camera and settings.
    fn job_spec(&self) -> Option<JobSpec> {
        let scene = self.source.scene();
        let camera = self.camera.settings().to_camera().ok()?;
        let (width, height) = self.image.full_size(scene);
        let plan = self.image.plan(scene);
        Some(JobSpec { scene: scene.clone(), camera, width, height, spp: self.image.spp(), plan })
    }

    /// Hands this frame's input to the scheduler.
    fn schedule(&mut self, ctx: &egui::Context, input: Interaction) {
        let spec = self.job_spec();
        if let Err(e) = self.scheduler.schedule(ctx, input, || spec) {
            self.notice = Some(e);
        }
    }

    /// A new scene is in place: the camera and settings follow it.
    fn scene_changed(&mut self, change: SceneChange) -> Interaction {
        let scene = self.source.scene().clone();
        self.camera.scene_loaded(&scene.camera, change.opened);
        self.image.scene_loaded(&scene, &change.previous, change.opened);
        Interaction { changed: true, dragging: false }
    }

    /// Writes the finished image to the Save path, atomically.
    fn save(&mut self) {
        let Some(canvas) = self.scheduler.canvas().filter(|_| self.scheduler.frame_is_final()) else {
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

    /// The side panel, top to bottom.
    fn side_panel(&mut self, ui: &mut egui::Ui) -> Interaction {
        let mut input = Interaction::default();
        if let Some(change) = self.source.ui(ui) {
            input = input | self.scene_changed(change);
        }
        ui.separator();
        input = input | self.camera.ui(ui);
        ui.separator();
        input = input | self.image.ui(ui, &self.source.scene().clone());
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path).desired_width(150.0));
            let ready = self.scheduler.frame_is_final();
            if ui.add_enabled(ready, egui::Button::new("Save PNG")).clicked() {
                self.save();
            }
        });
        if let Some(failure) = self.scheduler.failure() {
            ui.separator();
            ui.colored_label(Color32::from_rgb(220, 60, 50), failure);
        }
        if let Some(n) = &self.notice {
            ui.separator();
            ui.label(n);
        }
        ui.separator();
        ui.small("Drag: orbit · Shift/right drag: pan · Wheel: zoom");
        input
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        let mut input = Interaction::default();
        if let Some(change) = self.source.poll(&ctx) {
            input = input | self.scene_changed(change);
        }
        input = input
            | egui::Panel::left("controls")
                .resizable(false)
                .default_size(270.0)
                .show(ui, |ui| self.side_panel(ui))
                .inner;
        egui::Panel::bottom("status").show(ui, |ui| self.scheduler.status_ui(ui));
        let size = self.image.full_size(self.source.scene());
        input = input
            | egui::CentralPanel::default()
                .show(ui, |ui| image_ui(ui, self.scheduler.texture(), size, &mut self.camera))
                .inner;
        self.schedule(&ctx, input);
        self.scheduler.apply_rows();
        if let Some(screenshot) = &mut self.screenshot {
            screenshot.step(&ctx, self.scheduler.frame_is_final(), &self.outcome);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::{Duration, Instant};

    use super::*;
    use crate::viewer::canvas::Canvas;
    use crate::viewer::scene_source::load;

    /// Drives `viewer` until its full-resolution canvas is complete.
    fn finish_render(viewer: &mut Viewer) {
        let deadline = Instant::now() + Duration::from_secs(30);
        while !viewer.scheduler.canvas().is_some_and(Canvas::is_complete) {
            assert!(Instant::now() < deadline, "render did not complete");
            viewer.scheduler.apply_rows();
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    /// What a file save does: reload, and render again if the scene changed.
    fn reload(viewer: &mut Viewer, ctx: &egui::Context) {
        if let Some(change) = viewer.source.reload() {
            let input = viewer.scene_changed(change);
            viewer.schedule(ctx, input);
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
        let mut viewer = Viewer::new(&ctx, load(Some(&path)).unwrap(), options, Outcome::default());
        finish_render(&mut viewer);
        let image = viewer.scheduler.canvas().unwrap().pixels().to_vec();
        assert!(image.contains(&Color32::from_rgb(230, 38, 26)), "the sphere is not in the image");

        std::fs::write(&path, good.replace("radius: 1.2", "radius: -1.2")).unwrap();
        reload(&mut viewer, &ctx);
        let error = viewer.source.error().expect("the error is shown").to_owned();
        assert!(error.contains("scene.ron:") && error.contains("sphere radius must be positive"), "{error}");
        viewer.scheduler.apply_rows();
        assert_eq!(viewer.scheduler.canvas().unwrap().pixels(), &image[..], "the last good image changed");

        // Fixing the file clears the error and renders again.
        std::fs::write(&path, good.replace("(0.9, 0.15, 0.1)", "(0.1, 0.9, 0.1)")).unwrap();
        reload(&mut viewer, &ctx);
        assert_eq!(viewer.source.error(), None);
        finish_render(&mut viewer);
        assert!(viewer.scheduler.canvas().unwrap().pixels().contains(&Color32::from_rgb(26, 230, 26)));

        drop(viewer);
        ctx.tex_manager().write().take_delta().clear();
    }
}
