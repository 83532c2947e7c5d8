//! The viewer app: composes the parts of the window, handles the keyboard
//! shortcuts, passes each frame's input from the parts to the
//! [`Scheduler`], and gathers what the parts remember between runs into one
//! [`Remembered`] for eframe to save (and hands it back out at the start).
//!
//! The side panel (scrollable, fixed width) stacks the scene source, the
//! camera panel, the image settings, Save, and the display and reference
//! sections ([`DisplayPanel`]); the status line and the image
//! view come from the scheduler and [`ImageView`]. No part renders or
//! waits: a change of view only asks the scheduler for a new job.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use egui::{Color32, Key, KeyboardShortcut, Modifiers};
use rt_core::ViewPlane;

use super::camera_controls::CameraSettings;
use super::camera_panel::CameraPanel;
use super::display_panel::DisplayPanel;
use super::image_settings::ImageSettings;
use super::image_view::ImageView;
use super::interaction::Interaction;
use super::material_panel::MaterialPanel;
use super::region::Region;
use super::remembered::{LastScene, Remembered, absolute};
use super::render_job::{JobSpec, RenderJob};
use super::scene_source::{SceneChange, SceneSource, load};
use super::scene_view::{SceneView, ViewInput};
use super::scheduler::{Kind, Scheduler};
use super::screenshot::{Outcome, Screenshot};
use super::trace::{self, Trace};
use crate::image_out::{Format, PendingImage};

/// How the viewer is started.
#[derive(Clone, Debug, Default)]
pub struct ViewerOptions {
    /// Scene file to open; when `None`, the scene shown when the viewer last
    /// closed (if it still loads), else the built-in default scene.
    pub scene: Option<PathBuf>,
    /// Save a screenshot of the window here once the first full-resolution
    /// frame is complete, then exit (used by the smoke test).
    pub screenshot: Option<PathBuf>,
}

/// The scene the window opens with.
pub(super) struct Opening {
    /// Its file (`None`: the built-in scene).
    pub path: Option<PathBuf>,
    /// The scene.
    pub scene: rt_core::LoadedScene,
    /// Why the last scene shown did not open again, if it did not.
    pub note: Option<String>,
}

impl Opening {
    /// The scene `named` on the command line (its path and the scene read
    /// from it); else the `last` one shown, if it still loads; else the
    /// built-in scene.
    pub fn choose(
        named: Option<(PathBuf, rt_core::LoadedScene)>,
        last: Option<&LastScene>,
    ) -> Result<Self, rt_core::SceneError> {
        if let Some((path, scene)) = named {
            return Ok(Self { path: Some(path), scene, note: None });
        }
        let mut note = None;
        if let Some(last) = last {
            match load(Some(&last.path)) {
                Ok(scene) => return Ok(Self { path: Some(last.path.clone()), scene, note: None }),
                Err(e) => {
                    let why = format!("the last scene did not open again: {e}");
                    eprintln!("warning: {why}");
                    note = Some(why);
                }
            }
        }
        Ok(Self { path: None, scene: load(None)?, note })
    }
}

/// How long a notice (a save's result, a render that could not start) stays.
const NOTICE_FOR: Duration = Duration::from_secs(8);
/// Width of the side panel, in points.
const PANEL_WIDTH: f32 = 300.0;

/// The keyboard shortcuts, as the help overlay and the docs list them.
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("R", "reset the camera to the scene file's"),
    ("Ctrl+Z", "undo a camera change"),
    ("Ctrl+Shift+Z or Ctrl+Y", "redo a camera change"),
    ("V", "switch between orbit and fly navigation"),
    ("W A S D, Q E", "fly: forward, left, back, right, down, up (Shift: faster)"),
    (".", "frame the pinned object: it fills the view"),
    ("Alt+click", "pin the pixel and focus the lens on what it sees"),
    ("F", "fit the image to the window"),
    ("3", "show or hide the scene view: the scene in 3D, the camera and the pinned pixel's path"),
    ("1", "show the image 1:1 (one image pixel per screen pixel)"),
    ("Ctrl+S", "save the finished image (PNG or EXR, by the path's extension)"),
    ("Ctrl+O", "open a scene file"),
    ("F5", "reload the scene file"),
    ("P", "show or hide the side panel"),
    ("Space", "stop the render, keeping the image as it stands (the way a no-limit render ends)"),
    ("B", "region tool: the next drag on the image renders only that rectangle (B again: cancel)"),
    ("Shift+B", "clear the region: render the whole image again"),
    ("F1 or ?", "show or hide this help"),
    ("Esc", "unpin the inspected pixel, close this help"),
];

/// A message that fades: what a save did, why a render could not start.
struct Notice {
    text: String,
    at: Instant,
}

/// The viewer app: its parts, and what the window reports when it closes.
pub struct Viewer {
    source: SceneSource,
    camera: CameraPanel,
    image: ImageSettings,
    scheduler: Scheduler,
    view: ImageView,
    /// The scene in 3D beside the image.
    scene_view: SceneView,
    /// Exposure, channel views, histogram, reference and comparison.
    display: DisplayPanel,
    /// The pinned object's material, and its live edits.
    materials: MaterialPanel,
    /// The path Save PNG and Save EXR write to (with their extension).
    save_path: String,
    notice: Option<Notice>,
    show_panel: bool,
    show_help: bool,
    screenshot: Option<Screenshot>,
    outcome: Outcome,
    /// The frame-by-frame trace `RT_VIEW_TRACE` asks for (tests of the window).
    trace: Option<Trace>,
    /// Where Save PNG was last drawn (tests check that it can be reached).
    #[cfg(test)]
    save_button: Option<egui::Rect>,
}

impl Viewer {
    /// The viewer on the `opening` scene, as `remembered` left it, its first
    /// render started; `screenshot`: save the window there once rendered.
    ///
    /// The remembered camera comes back only for the same scene file, with
    /// the file's camera unchanged ([`LastScene::camera_for`]).
    pub(super) fn new(
        ctx: &egui::Context,
        opening: Opening,
        screenshot: Option<PathBuf>,
        remembered: Remembered,
        outcome: Outcome,
    ) -> Self {
        let Opening { path, scene, note } = opening;
        let mut camera = CameraPanel::new(&scene.camera);
        if let (Some(path), Some(last)) = (&path, &remembered.last_scene)
            && let Some(view) = last.camera_for(path, &camera.file_settings())
        {
            camera.restore(view);
        }
        let mut image = ImageSettings::new(&scene);
        image.set_resolution_scale(remembered.resolution_scale);
        let mut display = DisplayPanel::default();
        display.scene_loaded(scene.settings.display, scene.settings.display, true);
        let mut viewer = Self {
            camera,
            image,
            source: SceneSource::new(path, scene, remembered.recent, ctx),
            scheduler: Scheduler::default(),
            view: ImageView::default(),
            scene_view: SceneView::default(),
            display,
            materials: MaterialPanel::default(),
            save_path: "render.png".to_owned(),
            notice: None,
            show_panel: remembered.show_panel,
            show_help: false,
            screenshot: screenshot.map(Screenshot::new),
            outcome,
            trace: Trace::from_env(),
            #[cfg(test)]
            save_button: None,
        };
        viewer.start(ctx, Kind::NewScene);
        if let Some(note) = note {
            viewer.notify(note);
        }
        viewer
    }

    /// What to remember of this run: the parts' state gathered into one value.
    fn remembered(&self) -> Remembered {
        Remembered {
            recent: self.source.recent().clone(),
            show_panel: self.show_panel,
            resolution_scale: self.image.resolution_scale(),
            last_scene: self.source.path().map(|path| LastScene {
                path: absolute(path),
                camera: *self.camera.settings(),
                file_camera: self.camera.file_settings(),
            }),
        }
    }

    /// The full-resolution job for the current scene, camera and settings.
    fn job_spec(&self) -> Option<JobSpec> {
        let scene = self.source.scene();
        // The panel's camera, its lens (aperture, focus distance) included.
        let camera = self.camera.settings().to_camera().ok()?;
        let (width, height) = self.image.full_size(scene);
        let toggles = self.image.toggles();
        let (spp, open_ended) = (self.image.spp(), self.image.no_limit());
        let denoise = self.image.denoise();
        Some(JobSpec {
            scene: scene.clone(),
            camera,
            width,
            height,
            spp,
            open_ended,
            region: None,
            toggles,
            denoise,
        })
    }

    /// Starts a job of `kind` now.
    fn start(&mut self, ctx: &egui::Context, kind: Kind) {
        let spec = self.job_spec();
        if let Err(e) = self.scheduler.start(ctx, || spec, kind) {
            self.notify(e);
        }
    }

    /// Hands this frame's input to the scheduler.
    fn schedule(&mut self, ctx: &egui::Context, input: Interaction) {
        let spec = self.job_spec();
        if let Err(e) = self.scheduler.schedule(ctx, input, || spec) {
            self.notify(e);
        }
    }

    fn notify(&mut self, text: String) {
        self.notice = Some(Notice { text, at: Instant::now() });
    }

    /// A new scene is in place: the camera and settings follow it, old
    /// notices go, and its render starts from a black image.
    fn scene_changed(&mut self, ctx: &egui::Context, change: SceneChange) {
        let scene = self.source.scene().clone();
        self.camera.scene_loaded(&scene.camera, change.opened);
        let scale_note = self.image.scene_loaded(&scene, &change.previous, change.opened);
        self.display.scene_loaded(scene.settings.display, change.previous.settings.display, change.opened);
        self.notice = None;
        if let Some(note) = scale_note {
            self.notify(note);
        }
        if self.materials.scene_loaded() {
            self.notify("material edits dropped: the scene was loaded from its file again".into());
        }
        self.view.unpin();
        self.scene_view.scene_changed();
        self.start(ctx, Kind::NewScene);
    }

    /// The object under the pinned pixel, as the camera now sees it.
    fn pinned_object(&self) -> Option<usize> {
        let [x, y] = self.view.pinned()?;
        let (w, h) = self.image.full_size(self.source.scene());
        let view = ViewPlane::new(self.camera.settings().to_camera().ok()?, w, h).ok()?;
        self.source.scene().scene.cast(&view.center_ray(x, y)).map(|hit| hit.object)
    }

    /// Focus: the focus distance becomes the depth, along cam_z from the
    /// eye, of what the pinned pixel's centre ray hits (the ray the
    /// inspection casts). Returns whether the camera changed.
    fn focus_on_pinned(&mut self) -> bool {
        let Some([x, y]) = self.view.pinned() else {
            self.notify("nothing to focus on: click a pixel first".into());
            return false;
        };
        let (w, h) = self.image.full_size(self.source.scene());
        let Some(camera) = self.camera.settings().to_camera().ok() else { return false };
        let Ok(view) = ViewPlane::new(camera, w, h) else { return false };
        let ray = view.center_ray(x, y);
        let Some(hit) = self.source.scene().scene.cast(&ray) else {
            self.notify("the pinned pixel sees no object: nothing to focus on".into());
            return false;
        };
        let depth = (ray.at(hit.t) - camera.position()).dot(camera.basis().z);
        self.camera.edit(|s| CameraSettings { focus_distance: depth, ..s })
    }

    /// Frame: the camera moves so that the pinned object fills the view,
    /// and the pin moves to the image's centre, on the object. Returns
    /// whether the camera changed.
    fn frame_pinned(&mut self) -> bool {
        let Some(object) = self.pinned_object() else {
            self.notify("nothing to frame: click a pixel of an object first".into());
            return false;
        };
        let scene = self.source.scene().clone();
        let Some(bounds) = scene.scene.objects()[object].primitive.bounds() else {
            self.notify(format!("{} is unbounded: nothing to frame", describe_object(&scene.scene, object)));
            return false;
        };
        let (w, h) = self.image.full_size(&scene);
        let changed =
            self.camera.frame_box(bounds.min(), bounds.max(), w as rt_core::Real / h as rt_core::Real);
        self.view.pin([w / 2, h / 2]);
        changed
    }

    /// Renders `region` of the image on screen again (the rest stays).
    fn render_region(&mut self, ctx: &egui::Context, corners: [[f32; 2]; 2]) {
        let Some(spec) = self.job_spec() else { return };
        let Some(region) = Region::spanning(corners[0], corners[1], spec.width, spec.height) else {
            self.notify("no region: the rectangle misses the image".into());
            return;
        };
        if let Err(e) = self.scheduler.start_region(ctx, spec, region) {
            self.notify(e);
        }
    }

    /// Ends a region render: the whole image renders again.
    fn clear_region(&mut self, ctx: &egui::Context) {
        if self.scheduler.region().is_some() {
            self.start(ctx, Kind::Full);
        }
    }

    /// The region row of the side panel: the tool, and Clear.
    fn region_ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        ui.horizontal(|ui| {
            let tool = self.view.region_tool();
            if ui
                .selectable_label(tool, "Region")
                .on_hover_text("B: drag a rectangle on the image to render only it")
                .clicked()
            {
                self.view.toggle_region_tool();
            }
            let region = self.scheduler.region().cloned();
            if ui
                .add_enabled(region.is_some(), egui::Button::new("Clear region"))
                .on_hover_text("Shift+B")
                .clicked()
            {
                self.clear_region(&ctx);
            }
            if let Some(r) = region {
                ui.small(format!("{}×{} at ({}, {})", r.width(), r.height(), r.columns.start, r.rows.start));
            } else if tool {
                ui.small("drag on the image");
            }
        });
    }

    /// Writes the finished image to the Save path, atomically: `.png` as
    /// 8 bits in the scene's colour space (exposure and views not applied),
    /// `.exr` as the linear colours, full float.
    fn save(&mut self) {
        let Some(canvas) = self.scheduler.canvas().filter(|_| self.scheduler.frame_is_final()) else {
            self.notify("not saved: the image is not finished yet".into());
            return;
        };
        let path = save_path_for(self.save_path.trim(), self.source.path());
        let [width, height] = [canvas.size()[0] as u32, canvas.size()[1] as u32];
        let saved = PendingImage::create(&path).and_then(|out| match out.format() {
            Format::Png => out.write_rgb8(width, height, &canvas.rgb8_displayed()),
            Format::Exr => out.write_linear(width, height, &canvas.linear()),
        });
        self.notify(match saved {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => format!("not saved: {e:#}"),
        });
    }

    /// Saves to the Save path with its extension made `extension`.
    fn save_as(&mut self, extension: &str) {
        let path = PathBuf::from(self.save_path.trim()).with_extension(extension);
        self.save_path = path.display().to_string();
        self.save();
    }

    /// The keyboard shortcuts ([`SHORTCUTS`]), unless a text field has the keys.
    fn shortcuts(&mut self, ctx: &egui::Context) -> Interaction {
        let mut input = Interaction::default();
        if ctx.egui_wants_keyboard_input() {
            return input;
        }
        let pressed =
            |key| ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(Modifiers::NONE, key)));
        let command =
            |key| ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(Modifiers::COMMAND, key)));
        if command(Key::S) {
            self.save();
        }
        if command(Key::O) {
            self.source.browse();
        }
        if pressed(Key::F5) {
            self.source.reload(ctx);
        }
        if pressed(Key::R) {
            input.changed |= self.camera.reset();
        }
        // Ctrl+Shift+Z before Ctrl+Z, which would match it too.
        let redo = KeyboardShortcut::new(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
        if ctx.input_mut(|i| i.consume_shortcut(&redo)) || command(Key::Y) {
            input.changed |= self.camera.redo();
        }
        if command(Key::Z) {
            input.changed |= self.camera.undo();
        }
        if pressed(Key::V) {
            self.camera.toggle_navigation();
        }
        if pressed(Key::Period) {
            input.changed |= self.frame_pinned();
        }
        if pressed(Key::F) {
            self.view.fit();
        }
        if pressed(Key::Num3) {
            self.scene_view.toggle();
        }
        if pressed(Key::Num1) {
            let size = self.image.full_size(self.source.scene());
            self.view.one_to_one(ctx.pixels_per_point(), size);
        }
        if pressed(Key::P) {
            self.show_panel = !self.show_panel;
        }
        if pressed(Key::Space) {
            self.scheduler.stop();
        }
        // Shift+B first: a plain shortcut matches whatever Shift does.
        if ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(Modifiers::SHIFT, Key::B))) {
            self.clear_region(ctx);
        }
        if pressed(Key::B) {
            self.view.toggle_region_tool();
        }
        if pressed(Key::F1)
            || ctx.input(|i| i.events.iter().any(|e| matches!(e, egui::Event::Text(t) if t == "?")))
        {
            self.show_help = !self.show_help;
        }
        if self.show_help && pressed(Key::Escape) {
            self.show_help = false;
        }
        input
    }

    /// The side panel, top to bottom.
    fn side_panel(&mut self, ui: &mut egui::Ui) -> Interaction {
        let mut input = Interaction::default();
        self.source.ui(ui);
        ui.separator();
        let pinned = self.pinned_object();
        let selected = pinned.map(|o| describe_object(&self.source.scene().scene, o));
        input = input | self.camera.ui(ui, self.source.path(), selected.as_deref());
        ui.separator();
        if let Some(edit) = self.materials.ui(ui, &self.source.scene().clone(), pinned) {
            self.source.show_edited(edit.scene);
            input = input | edit.interaction;
        }
        ui.separator();
        input = input | self.image.ui(ui, &self.source.scene().clone());
        self.region_ui(ui);
        self.scene_view.toggle_ui(ui);
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path).desired_width(140.0));
            let ready = self.scheduler.frame_is_final();
            let button = ui
                .add_enabled(ready, egui::Button::new("Save PNG"))
                .on_hover_text("Ctrl+S: 8 bits through the exposure and view transform shown");
            #[cfg(test)]
            {
                self.save_button = Some(button.rect);
            }
            if button.clicked() {
                self.save_as("png");
            }
            let exr =
                ui.add_enabled(ready, egui::Button::new("EXR")).on_hover_text("Save EXR: linear, full float");
            if exr.clicked() {
                self.save_as("exr");
            }
        });
        if let Some(failure) = self.scheduler.failure() {
            ui.separator();
            ui.colored_label(Color32::from_rgb(220, 60, 50), failure);
        }
        if let Some(n) = &self.notice {
            ui.separator();
            ui.label(&n.text);
        }
        ui.separator();
        self.display.ui(ui, self.scheduler.canvas());
        ui.separator();
        ui.small("Drag: orbit · Shift/right drag: pan · Wheel: zoom\nCtrl+wheel, Ctrl+drag: zoom and pan the image\nSpace: stop · B: region · F1: all shortcuts");
        input
    }

    /// The shortcuts overlay.
    fn help_ui(&mut self, ctx: &egui::Context) {
        let mut open = self.show_help;
        egui::Window::new("Keyboard and mouse").open(&mut open).collapsible(false).show(ctx, |ui| {
            egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                for (keys, what) in SHORTCUTS {
                    ui.monospace(*keys);
                    ui.label(*what);
                    ui.end_row();
                }
            });
            ui.separator();
            ui.label("Drag: orbit · Shift-, right- or middle-drag: pan · Wheel: zoom the camera");
            ui.label("Ctrl+wheel: zoom the image · Ctrl+drag: pan the image");
            ui.label("Hover: inspect a pixel · Click: pin it · Drop a .ron file: open it");
        });
        self.show_help = open;
    }

    /// One frame of the whole window.
    fn frame(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        if let Some(change) = self.source.poll(&ctx) {
            self.scene_changed(&ctx, change);
        }
        self.source.take_dropped(&ctx);
        let mut input = self.shortcuts(&ctx);
        input = input | self.camera.fly_keys(&ctx, &self.source.scene().scene);
        if self.notice.as_ref().is_some_and(|n| n.at.elapsed() > NOTICE_FOR) {
            self.notice = None;
        }
        if self.show_panel {
            input = input
                | egui::Panel::left("controls")
                    .resizable(false)
                    .exact_size(PANEL_WIDTH)
                    .show(ui, |ui| {
                        egui::ScrollArea::vertical()
                            .id_salt("side panel")
                            .show(ui, |ui| self.side_panel(ui))
                            .inner
                    })
                    .inner;
        }
        let target = self.image.target_spp();
        egui::Panel::bottom("status").show(ui, |ui| self.scheduler.status_ui(ui, target));
        let size = self.image.full_size(self.source.scene());
        let color_space = self.source.scene().settings.color_space;
        self.scheduler.set_display(self.display.display(color_space));
        self.view.set_reference(self.display.split_texture(&ctx, color_space));
        if self.scene_view.is_open() {
            self.scene_view_ui(ui, size);
        }
        let texture = self.scheduler.texture().cloned();
        let shown = egui::CentralPanel::default().show(ui, |ui| {
            let (scene, scheduler) = (self.source.scene().clone(), &self.scheduler);
            let settings = *self.camera.settings();
            let inspect = |p| inspect(&scene, &settings, size, scheduler.shown_job(), p);
            self.view.outline_region(scheduler.region().cloned());
            self.view.ui(ui, texture.as_ref(), size, &mut self.camera, inspect)
        });
        let (image_rect, (view_input, magnified)) = (shown.response.rect, shown.inner);
        input = input | view_input;
        if self.camera.take_frame_request() {
            input.changed |= self.frame_pinned();
        }
        // Alt+click on the image pins the pixel (the view does) and focuses on it.
        // (The button's release carries the modifiers held; a drag is no click.)
        let alt_click = ctx.input(|i| {
            i.pointer.primary_clicked()
                && i.events.iter().any(|e| {
                    matches!(e, egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed: false, modifiers }
                        if modifiers.alt && image_rect.contains(*pos))
                })
        });
        if self.camera.take_focus_request() || alt_click {
            input.changed |= self.focus_on_pinned();
        }
        self.camera.end_frame(&ctx);
        if let Some(corners) = self.view.take_dragged_region() {
            self.render_region(&ctx, corners);
        }
        self.source.browser_ui(&ctx);
        self.help_ui(&ctx);
        if input.changed {
            self.notice = None;
        }
        let filter = if magnified { egui::TextureOptions::NEAREST } else { egui::TextureOptions::LINEAR };
        self.scheduler.set_filter(filter);
        self.display.set_filter(filter);
        self.schedule(&ctx, input);
        self.scheduler.apply_rows(&ctx);
        let full_size = [size.0 as usize, size.1 as usize];
        self.display.update(&ctx, self.scheduler.canvas(), full_size);
        if let Some(screenshot) = &mut self.screenshot {
            screenshot.step(&ctx, self.scheduler.frame_is_final(), &self.outcome);
        }
    }
}

impl Viewer {
    /// The scene view, right of the image, half the space left by default.
    fn scene_view_ui(&mut self, ui: &mut egui::Ui, image_size: (u32, u32)) {
        let width = ui.available_width();
        let scene = self.source.scene().clone();
        let input = ViewInput {
            scene: &scene,
            camera: self.camera.settings().to_camera().ok(),
            image_size,
            pinned: self.view.pinned(),
            spec: self.job_spec(),
        };
        egui::Panel::right("scene view")
            .resizable(true)
            .default_size(width * 0.5)
            .size_range(200.0..=(width - 200.0).max(200.0))
            .show(ui, |ui| self.scene_view.ui(ui, &input));
    }
}

/// Where Save writes `typed`: a relative path is taken next to the scene
/// file (the built-in scene, which has none, keeps the folder the viewer
/// was started in); an absolute one as it is.
fn save_path_for(typed: &str, scene_file: Option<&std::path::Path>) -> PathBuf {
    let typed = PathBuf::from(typed);
    match scene_file.and_then(|f| f.parent()) {
        Some(dir) if typed.is_relative() => dir.join(typed),
        _ => typed,
    }
}

/// How the panel names object `index` of `scene`: "object 3 (sphere)".
fn describe_object(scene: &rt_core::Scene, index: usize) -> String {
    format!("object {index} ({})", scene.objects()[index].primitive.kind())
}

/// What pixel (x, y) of the `size` image of `scene` seen with `settings`
/// shows and hits: its linear colour from `job` (if that rendered the full
/// image), and its primary ray's hit as `rt-view cast --pixels` reports it.
fn inspect(
    scene: &rt_core::LoadedScene,
    settings: &CameraSettings,
    (w, h): (u32, u32),
    job: Option<&RenderJob>,
    [x, y]: [u32; 2],
) -> String {
    let mut lines = vec![format!("pixel ({x}, {y})")];
    match job.filter(|j| (j.spec().width, j.spec().height) == (w, h)) {
        Some(job) => match job.linear(x, y) {
            Some((c, n)) => lines.push(format!("linear ({:.4}, {:.4}, {:.4}), {n} spp", c.x, c.y, c.z)),
            None => lines.push("not rendered yet".into()),
        },
        None => lines.push("(preview: linear colour once the full image renders)".into()),
    }
    let view = settings.to_camera().ok().and_then(|c| ViewPlane::new(c, w, h).ok());
    if let Some(view) = view {
        let ray = view.center_ray(x, y);
        match scene.scene.cast(&ray) {
            Some(hit) => {
                let object = &scene.scene.objects()[hit.object];
                let material = &scene.scene.material_names()[object.material];
                let distance = hit.t * ray.dir.length();
                lines.push(format!(
                    "object {} ({}, material \"{material}\"), primitive {}",
                    hit.object,
                    object.primitive.kind(),
                    hit.primitive
                ));
                lines.push(format!("t {}, distance {distance}", hit.t));
                lines.push(format!("normal ({}, {}, {})", hit.normal.x, hit.normal.y, hit.normal.z));
            }
            None => lines.push("no hit: background".into()),
        }
    }
    lines.join("\n")
}

impl Viewer {
    /// Appends the frame that began at `began` and took `update` (and the
    /// job it rendered, if new) to the trace; a trace that cannot be written
    /// stops, with a warning.
    fn trace_frame(&mut self, ui: &egui::Ui, began: Instant, update: Duration) {
        let Some(trace) = &mut self.trace else { return };
        let (width, _) = self.image.full_size(self.source.scene());
        let texture = self.scheduler.texture().map(egui::TextureHandle::id);
        let zoom = texture.and_then(|t| trace::drawn_zoom(ui.ctx(), ui.layer_id(), t, width));
        let frame = trace::Frame {
            scene: self.source.path(),
            loading: self.source.is_loading(),
            zoom,
            canvas: self.scheduler.canvas(),
            scene_view: self.scene_view.is_open().then(|| self.scene_view.renders_started()),
        };
        let written = match self.scheduler.job() {
            Some((job, preview)) => trace.job(job, preview),
            None => Ok(()),
        };
        if let Err(e) = written.and_then(|()| trace.frame(began, update, frame)) {
            eprintln!("warning: {e}; tracing stops");
            self.trace = None;
        }
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let began = Instant::now();
        self.frame(ui);
        if self.trace.is_some() {
            self.trace_frame(ui, began, began.elapsed());
        }
    }

    /// Called when the window closes and every 30 s.
    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        self.remembered().save(storage);
    }

    /// egui's own widget memory (scroll offsets, where the help window was,
    /// the zoom) is not kept: what is remembered is [`Remembered`] and the window.
    fn persist_egui_memory(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::time::{Duration, Instant};

    use super::*;
    use crate::viewer::canvas::Canvas;

    fn scenes() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
    }

    /// A viewer on `path` (the built-in scene for `None`) that remembers nothing.
    fn viewer(ctx: &egui::Context, path: Option<PathBuf>) -> Viewer {
        remembering(ctx, path, Remembered::default())
    }

    /// A viewer on `path` (the built-in scene for `None`) as `remembered` left it.
    fn remembering(ctx: &egui::Context, path: Option<PathBuf>, remembered: Remembered) -> Viewer {
        let scene = load(path.as_deref()).unwrap();
        let named = path.map(|p| (p, scene));
        let opening = Opening::choose(named, remembered.last_scene.as_ref()).unwrap();
        Viewer::new(ctx, opening, None, remembered, Outcome::default())
    }

    /// Runs one frame of the whole window, `size` points large, with `events`.
    fn frame(ctx: &egui::Context, v: &mut Viewer, size: egui::Vec2, events: Vec<egui::Event>) {
        let input = egui::RawInput {
            screen_rect: Some(egui::Rect::from_min_size(egui::Pos2::ZERO, size)),
            events,
            ..Default::default()
        };
        let mut output = ctx.run_ui(input, |ui| v.frame(ui));
        output.textures_delta.clear();
        ctx.tex_manager().write().take_delta().clear();
    }

    /// Drives `viewer` until its full-resolution canvas is complete.
    fn finish_render(ctx: &egui::Context, viewer: &mut Viewer) {
        let deadline = Instant::now() + Duration::from_secs(30);
        while !viewer.scheduler.frame_is_final() {
            assert!(Instant::now() < deadline, "render did not complete");
            viewer.scheduler.apply_rows(ctx);
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn opening_a_scene_returns_at_once_and_the_old_one_stays_until_the_new_one_is_loaded() {
        // The load runs on a thread of its own: `open` returns before the
        // scene is read, the window keeps drawing frames with the old scene
        // (mid-render here), and the new one arrives through `poll`. Loading
        // on the window's thread would have replaced the scene inside `open`.
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("effects.ron")));
        frame(&ctx, &mut v, egui::vec2(900.0, 600.0), Vec::new());
        let before = v.source.scene().clone();
        v.source.open(scenes().join("box.ron"), &ctx);
        assert!(std::sync::Arc::ptr_eq(v.source.scene(), &before), "open waited for the load");
        let deadline = Instant::now() + Duration::from_secs(60);
        while std::sync::Arc::ptr_eq(v.source.scene(), &before) {
            assert!(Instant::now() < deadline, "the new scene never arrived");
            frame(&ctx, &mut v, egui::vec2(900.0, 600.0), Vec::new());
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(v.source.path().is_some_and(|p| p.ends_with("box.ron")));
        // A file that cannot be loaded leaves the scene and says why, once loaded.
        let shown = v.source.scene().clone();
        v.source.open(scenes().join("no-such-scene.ron"), &ctx);
        assert!(v.source.wait_for_load(&ctx).is_none());
        assert!(std::sync::Arc::ptr_eq(v.source.scene(), &shown));
        assert!(v.source.error().is_some_and(|e| e.contains("no-such-scene.ron")), "{:?}", v.source.error());
    }

    /// What a file save does: reload, and render again if the scene changed.
    fn reload(viewer: &mut Viewer, ctx: &egui::Context) {
        viewer.source.reload(ctx);
        if let Some(change) = viewer.source.wait_for_load(ctx) {
            viewer.scene_changed(ctx, change);
        }
    }

    fn drop_textures(ctx: &egui::Context, viewer: Viewer) {
        drop(viewer);
        ctx.tex_manager().write().take_delta().clear();
    }

    #[test]
    fn a_reload_that_fails_shows_the_error_and_keeps_the_last_good_image() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let good = std::fs::read_to_string(scenes().join("sphere.ron"))
            .unwrap()
            .replace("width: 320, height: 240", "width: 64, height: 48");
        std::fs::write(&path, &good).unwrap();

        let ctx = egui::Context::default();
        let mut viewer = viewer(&ctx, Some(path.clone()));
        finish_render(&ctx, &mut viewer);
        let image = viewer.scheduler.canvas().unwrap().pixels().to_vec();
        assert!(image.contains(&Color32::from_rgb(230, 38, 26)), "the sphere is not in the image");

        std::fs::write(&path, good.replace("radius: 1.2", "radius: -1.2")).unwrap();
        reload(&mut viewer, &ctx);
        let error = viewer.source.error().expect("the error is shown").to_owned();
        assert!(error.contains("scene.ron:") && error.contains("sphere radius must be positive"), "{error}");
        viewer.scheduler.apply_rows(&ctx);
        assert_eq!(viewer.scheduler.canvas().unwrap().pixels(), &image[..], "the last good image changed");

        // Fixing the file clears the error and renders again.
        std::fs::write(&path, good.replace("(0.9, 0.15, 0.1)", "(0.1, 0.9, 0.1)")).unwrap();
        reload(&mut viewer, &ctx);
        assert_eq!(viewer.source.error(), None);
        finish_render(&ctx, &mut viewer);
        assert!(viewer.scheduler.canvas().unwrap().pixels().contains(&Color32::from_rgb(26, 230, 26)));
        drop_textures(&ctx, viewer);
    }

    #[test]
    fn open_takes_the_new_scenes_camera_and_projection_through_a_whole_frame() {
        // Before, the panel copied the camera at the start of a frame, Open
        // set the new one, and the end of the frame wrote the old copy back.
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        frame(&ctx, &mut v, egui::vec2(1000.0, 700.0), vec![]);
        for name in ["box.ron", "orthographic.ron"] {
            let path = scenes().join(name);
            v.source.open(path.clone(), &ctx);
            let change = v.source.wait_for_load(&ctx).unwrap();
            v.scene_changed(&ctx, change);
            frame(&ctx, &mut v, egui::vec2(1000.0, 700.0), vec![]);
            let file = rt_core::load_scene(&path).unwrap().camera;
            assert_eq!(v.camera.settings().to_camera().unwrap(), file, "{name}");
        }
        drop_textures(&ctx, v);
    }

    #[test]
    fn an_opened_scene_sets_the_display_to_its_files_exposure_and_view_transform() {
        use rt_core::render::view_transform::{self, ViewTransform};
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        v.display.set_exposure(2.0);
        let path = scenes().join("outdoor.ron");
        v.source.open(path.clone(), &ctx);
        let change = v.source.wait_for_load(&ctx).unwrap();
        v.scene_changed(&ctx, change);
        finish_render(&ctx, &mut v);
        frame(&ctx, &mut v, egui::vec2(1000.0, 700.0), vec![]);
        let file = rt_core::load_scene(&path).unwrap().settings.display;
        assert_eq!(
            (file.exposure, file.view_transform),
            (-1.0, ViewTransform::AgX),
            "outdoor.ron as assumed"
        );
        assert_eq!(v.display.view_transform(), ViewTransform::AgX);
        // The canvas shows the image through the file's exposure and AgX:
        // the bytes a PNG of it would hold.
        let canvas = v.scheduler.canvas().unwrap();
        let (display, space) = (canvas.display().clone(), v.source.scene().settings.color_space);
        assert_eq!((display.exposure, display.view_transform), (-1.0, ViewTransform::AgX));
        let png = view_transform::Display { exposure: -1.0, view_transform: ViewTransform::AgX };
        let expected: Vec<Color32> = canvas
            .linear()
            .iter()
            .map(|&c| png.encode(rt_core::math::color::Color::from_array(c), space))
            .map(|[r, g, b]| Color32::from_rgb(r, g, b))
            .collect();
        assert_eq!(canvas.display_image(), expected);
        // A panel choice stays while the same file reloads unchanged.
        v.display.set_exposure(0.5);
        v.display.scene_loaded(file, file, false);
        assert_eq!(v.display.display(space).exposure, 0.5);
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_side_panel_scrolls_at_the_smallest_window_size() {
        // At 640×400 the panel's contents are taller than the window. Before,
        // Save PNG was below the window's bottom edge and out of reach; now
        // scrolling the panel brings it into view.
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        let size = egui::vec2(640.0, 400.0);
        frame(&ctx, &mut v, size, vec![]);
        frame(&ctx, &mut v, size, vec![]);
        let below = v.save_button.expect("Save PNG was laid out");
        assert!(below.top() > size.y, "the window is taller than assumed: {below:?}");
        let over_panel = egui::pos2(100.0, 200.0);
        let scroll = egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, -2000.0),
            modifiers: Modifiers::NONE,
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Wheel,
        };
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(over_panel), scroll]);
        for _ in 0..30 {
            frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(over_panel)]);
        }
        let after = v.save_button.unwrap();
        assert!(after.bottom() <= size.y && after.top() >= 0.0, "Save PNG still out of reach: {after:?}");
        drop_textures(&ctx, v);
    }

    #[test]
    fn notices_clear_when_a_new_scene_opens_and_when_the_view_changes() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        v.save_path = "/no/such/dir/x.png".into();
        v.save();
        assert!(v.notice.as_ref().is_some_and(|n| n.text.starts_with("not saved")));
        v.source.open(scenes().join("box.ron"), &ctx);
        let change = v.source.wait_for_load(&ctx).unwrap();
        v.scene_changed(&ctx, change);
        assert!(v.notice.is_none(), "Open clears the notice");
        v.notify("not saved: something".into());
        // Pressing R (reset) changes the view after an edit.
        v.camera.edit(|s| s.orbit(0.2, 0.0));
        frame(&ctx, &mut v, egui::vec2(1000.0, 700.0), vec![key(Key::R)]);
        assert!(v.notice.is_none(), "a change of view clears the notice");
        drop_textures(&ctx, v);
    }

    fn key(key: Key) -> egui::Event {
        egui::Event::Key { key, physical_key: None, pressed: true, repeat: false, modifiers: Modifiers::NONE }
    }

    #[test]
    fn a_new_scene_never_shows_the_old_scenes_pixels() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        finish_render(&ctx, &mut v);
        v.source.open(scenes().join("sphere.ron"), &ctx);
        let change = v.source.wait_for_load(&ctx).unwrap();
        v.scene_changed(&ctx, change);
        // Before any row of the new scene, the image on screen is black.
        let canvas: &Canvas = v.scheduler.canvas().unwrap();
        assert_eq!(canvas.rows_done(), 0);
        drop_textures(&ctx, v);
    }

    /// The numbers in `text` after `prefix` on its line, up to `end`, split at
    /// ", " (the inspection's "(x, y, z)" lists).
    fn numbers_after<T: std::str::FromStr>(text: &str, prefix: &str, end: &str) -> Vec<T>
    where
        T::Err: std::fmt::Display,
    {
        let line =
            text.lines().find_map(|l| l.strip_prefix(prefix)).unwrap_or_else(|| panic!("{prefix}: {text}"));
        let list = line.split(end).next().unwrap();
        list.split(", ").map(|n| n.parse().unwrap_or_else(|e| panic!("{n:?} in {line:?}: {e}"))).collect()
    }

    #[test]
    fn inspecting_a_pixel_tells_what_cast_tells_and_its_linear_colour() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("sphere.ron")));
        finish_render(&ctx, &mut v);
        // sphere.ron is 320×240 with the sphere in the middle, flat colours (no lights).
        let scene = v.source.scene();
        let size = v.image.full_size(scene);
        assert_eq!(size, (320, 240));
        let job = v.scheduler.shown_job();
        let spp = job.expect("a finished job").spec().spp;
        let look = |p| inspect(scene, v.camera.settings(), size, job, p);
        // What `rt-view cast --pixels` prints for pixel (x, y): its CSV row
        // ox,oy,oz,dx,dy,dz,hit,t,object,primitive,nx,ny,nz, split.
        let view = rt_core::ViewPlane::new(scene.camera, size.0, size.1).unwrap();
        let cast = |x: u32, y: u32| -> Vec<String> {
            let row = crate::commands::cast::rays_rows(&scene.scene, &[view.center_ray(x, y)]);
            row.trim_end().split(',').map(str::to_owned).collect()
        };
        let hits = |x: u32, y: u32| cast(x, y)[6] == "1";
        let (mut hit_count, mut miss_count) = (0, 0);
        // Every 8th pixel, both ways, and the centre: 1200 pixels.
        let pixels = (0..240).step_by(8).flat_map(|y| (0..320).step_by(8).map(move |x| (x, y)));
        for (x, y) in pixels.chain([(160, 120)]) {
            let text = look([x, y]);
            let row = cast(x, y);
            assert!(text.starts_with(&format!("pixel ({x}, {y})\n")), "{text}");
            // Numbers printed with `{}` round-trip, so they compare exactly.
            let num = |i: usize| -> rt_core::Real { row[i].parse().unwrap() };
            let linear: Vec<f64> = numbers_after(&text, "linear (", ")");
            assert_eq!(linear.len(), 3, "{text}");
            assert!(text.contains(&format!("), {spp} spp\n")), "{text}");
            // Interior pixels (the four neighbours agree) are one flat colour:
            // the material's or the background's, printed to 4 decimals.
            let interior = [(x.saturating_sub(1), y), (x + 1, y), (x, y.saturating_sub(1)), (x, y + 1)]
                .iter()
                .all(|&(a, b)| a >= 320 || b >= 240 || cast(a, b)[6..9] == row[6..9]);
            if row[6] == "1" {
                hit_count += 1;
                let object: usize = row[8].parse().unwrap();
                let expected = format!(
                    "object {object} ({}, material \"{}\"), primitive {}",
                    scene.scene.objects()[object].primitive.kind(),
                    scene.scene.material_names()[scene.scene.objects()[object].material],
                    row[9]
                );
                let object_line = text.lines().find(|l| l.starts_with("object ")).expect("object line");
                assert_eq!(object_line, expected, "{text}");
                let t_line = text.lines().find_map(|l| l.strip_prefix("t ")).expect("t line");
                let (t, distance) = t_line.split_once(", distance ").expect("t, distance");
                let (t, distance): (rt_core::Real, rt_core::Real) =
                    (t.parse().unwrap(), distance.parse().unwrap());
                assert_eq!(t, num(7), "{text}");
                let dir = rt_core::Vec3::new(num(3), num(4), num(5));
                assert_eq!(distance, t * dir.length(), "{text}");
                let normal: Vec<rt_core::Real> = numbers_after(&text, "normal (", ")");
                assert_eq!(normal, [num(10), num(11), num(12)], "{text}");
                let color = scene.scene.materials()[scene.scene.objects()[object].material].color;
                if interior {
                    for (got, want) in linear.iter().zip(color.to_array()) {
                        assert!((got - want as f64).abs() <= 0.5e-4, "{text}: want {color}");
                    }
                }
            } else {
                miss_count += 1;
                assert!(text.ends_with("\nno hit: background"), "{text}");
                assert!(!text.contains("object ") && !text.contains("normal ("), "{text}");
                if interior {
                    for (got, want) in
                        linear.iter().zip(scene.scene.environment().radiance(rt_core::Vec3::Z).to_array())
                    {
                        assert!(
                            (got - want as f64).abs() <= 0.5e-4,
                            "{text}: want {}",
                            scene.scene.environment().radiance(rt_core::Vec3::Z)
                        );
                    }
                }
            }
        }
        assert!(hits(160, 120) && !hits(0, 0));
        assert!(hit_count > 100 && miss_count > 100, "{hit_count} hits, {miss_count} misses");
        drop_textures(&ctx, v);
    }

    /// What `v` would leave behind, saved as eframe saves it and read back.
    fn saved_and_read(v: &Viewer) -> Remembered {
        let text = ron::ser::to_string(&v.remembered()).unwrap();
        Remembered::from_ron(&text).unwrap()
    }

    #[test]
    fn started_again_without_a_scene_the_viewer_is_as_it_was_left() {
        let ctx = egui::Context::default();
        let path = scenes().join("box.ron");
        let mut v = viewer(&ctx, Some(path.clone()));
        v.camera.edit(|s| s.orbit(0.4, 0.1).zoom(0.8));
        v.image.set_resolution_scale(0.5);
        frame(&ctx, &mut v, egui::vec2(1000.0, 700.0), vec![key(Key::P)]);
        let (camera, file_camera) = (*v.camera.settings(), v.camera.file_settings());
        assert_ne!(camera, file_camera);
        let remembered = saved_and_read(&v);
        drop_textures(&ctx, v);

        let v = remembering(&ctx, None, remembered);
        let canonical = std::fs::canonicalize(&path).unwrap();
        assert_eq!(v.source.path(), Some(canonical.as_path()));
        assert_eq!(*v.camera.settings(), camera);
        assert_eq!(v.camera.file_settings(), file_camera, "Reset still goes to the file's camera");
        assert!(!v.show_panel);
        assert_eq!(v.image.full_size(v.source.scene()), (160, 120));
        assert_eq!(v.source.recent().files(), [canonical]);
        drop_textures(&ctx, v);
    }

    #[test]
    fn a_scene_named_on_the_command_line_wins_and_opens_with_its_own_camera() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        v.camera.edit(|s| s.orbit(0.4, 0.1));
        let remembered = saved_and_read(&v);
        drop_textures(&ctx, v);

        let sphere = scenes().join("sphere.ron");
        let v = remembering(&ctx, Some(sphere.clone()), remembered.clone());
        assert_eq!(v.source.path(), Some(sphere.as_path()));
        assert_eq!(v.camera.settings().to_camera().unwrap(), rt_core::load_scene(&sphere).unwrap().camera);
        assert_eq!(v.source.recent().files().len(), 2, "both are recent files");
        drop_textures(&ctx, v);
        // The same file named again: its view comes back.
        let v = remembering(&ctx, Some(scenes().join("box.ron")), remembered.clone());
        assert_eq!(Some(*v.camera.settings()), remembered.last_scene.map(|l| l.camera));
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_last_scene_opens_with_the_files_camera_once_the_file_changed_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let text = std::fs::read_to_string(scenes().join("sphere.ron")).unwrap();
        std::fs::write(&path, &text).unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(path.clone()));
        v.camera.edit(|s| s.orbit(0.4, 0.1));
        let remembered = saved_and_read(&v);
        drop_textures(&ctx, v);

        let moved = text.replacen("fov_y: ", "fov_y: 1", 1);
        assert_ne!(moved, text);
        std::fs::write(&path, moved).unwrap();
        let v = remembering(&ctx, None, remembered);
        assert_eq!(v.source.path(), Some(std::fs::canonicalize(&path).unwrap().as_path()));
        assert_eq!(v.camera.settings().to_camera().unwrap(), rt_core::load_scene(&path).unwrap().camera);
        drop_textures(&ctx, v);
    }

    #[test]
    fn a_last_scene_that_no_longer_loads_gives_the_built_in_scene_and_says_why() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        std::fs::copy(scenes().join("sphere.ron"), &path).unwrap();
        let ctx = egui::Context::default();
        let v = viewer(&ctx, Some(path.clone()));
        let remembered = saved_and_read(&v);
        drop_textures(&ctx, v);

        std::fs::remove_file(&path).unwrap();
        let v = remembering(&ctx, None, remembered);
        assert_eq!(v.source.path(), None);
        let notice = &v.notice.as_ref().expect("a notice says why").text;
        assert!(
            notice.starts_with("the last scene did not open again: ") && notice.contains("scene.ron"),
            "{notice}"
        );
        drop_textures(&ctx, v);
    }

    #[test]
    fn save_exr_writes_the_linear_image_and_reads_back_equal() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        finish_render(&ctx, &mut v);
        v.save_path = dir.path().join("out.png").display().to_string();
        v.save_as("exr");
        let path = dir.path().join("out.exr");
        assert_eq!(v.notice.as_ref().map(|n| n.text.clone()), Some(format!("saved {}", path.display())));
        let back = image::open(&path).unwrap().to_rgb32f();
        let canvas = v.scheduler.canvas().unwrap();
        assert_eq!([back.width() as usize, back.height() as usize], canvas.size());
        let back: Vec<[f32; 3]> = back.pixels().map(|p| p.0).collect();
        assert!(back == canvas.linear(), "the EXR differs from the linear image");
        // The headless render's floats, unclamped: the same numbers.
        let spec = v.job_spec().unwrap();
        let settings =
            spec.scene.settings.overridden(Some(spec.width), Some(spec.height), Some(spec.spp)).unwrap();
        let frame = rt_core::Renderer::new(&spec.scene.scene, spec.camera, &settings).unwrap().render(|_| {});
        assert!(back.iter().zip(&frame.pixels).all(|(a, b)| *a == b.to_array()));
        // Ctrl+S follows the extension: PNG stays 8-bit.
        v.save_as("png");
        assert!(image::open(dir.path().join("out.png")).unwrap().as_rgb8().is_some());
        drop_textures(&ctx, v);
    }

    #[test]
    fn exposure_and_the_reference_views_go_through_to_the_texels_and_the_metrics() {
        use crate::viewer::display_panel::Compare;
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        finish_render(&ctx, &mut v);
        frame(&ctx, &mut v, size, vec![]);
        let plain = v.scheduler.canvas().unwrap().display_image();
        v.display.set_exposure(1.0);
        frame(&ctx, &mut v, size, vec![]);
        let canvas = v.scheduler.canvas().unwrap();
        let display = canvas.display().clone();
        assert_eq!(display.exposure, 1.0);
        let expected: Vec<Color32> = canvas.linear().iter().map(|&c| display.texel(c)).collect();
        assert_eq!(canvas.display_image(), expected);
        assert_ne!(canvas.display_image(), plain);
        v.display.set_exposure(0.0);
        frame(&ctx, &mut v, size, vec![]);
        assert_eq!(v.scheduler.canvas().unwrap().display_image(), plain, "exposure 0 is the image as it was");

        // The render becomes the reference: no error, the A/B view on.
        v.display.use_render(v.scheduler.canvas());
        frame(&ctx, &mut v, size, vec![]);
        assert!(v.view.has_reference(), "the split view shows the reference");
        let m = v.display.metrics().expect("metrics of the finished render");
        assert_eq!((m.rmse, m.relative_mse), (0.0, 0.0));
        v.display.set_compare(Compare::Absolute);
        frame(&ctx, &mut v, size, vec![]);
        let black = v.scheduler.canvas().unwrap().display_image().iter().all(|&c| c == Color32::BLACK);
        assert!(black, "the render minus itself is black");
        // The camera moves: once the new full render is done, the error shows.
        v.camera.edit(|s| s.orbit(0.3, 0.0));
        v.start(&ctx, Kind::Full);
        finish_render(&ctx, &mut v);
        frame(&ctx, &mut v, size, vec![]);
        let m = v.display.metrics().unwrap();
        assert!(m.rmse > 0.01 && m.relative_mse > 0.0, "{m:?}");
        assert!(v.scheduler.canvas().unwrap().display_image().iter().any(|&c| c != Color32::BLACK));
        drop_textures(&ctx, v);
    }

    #[test]
    fn a_reference_of_another_size_or_unreadable_is_a_message_in_the_panel() {
        let dir = tempfile::tempdir().unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        let small = dir.path().join("small.png");
        image::RgbImage::new(7, 5).save(&small).unwrap();
        for (path, want) in [
            (small, "the reference is 7 × 5 pixels, the render 320 × 240: no comparison".to_owned()),
            (
                dir.path().join("none.exr"),
                format!("{}: cannot read the image", dir.path().join("none.exr").display()),
            ),
        ] {
            v.display.load(&ctx, path);
            let deadline = Instant::now() + Duration::from_secs(10);
            while !v.display.message().is_some_and(|m| m.starts_with(&want)) {
                assert!(Instant::now() < deadline, "no message: {:?}", v.display.message());
                frame(&ctx, &mut v, size, vec![]);
                std::thread::sleep(Duration::from_millis(2));
            }
        }
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_shortcuts_toggle_the_panel_and_the_help_and_fit_and_one_to_one_the_image() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        let size = egui::vec2(1000.0, 700.0);
        frame(&ctx, &mut v, size, vec![key(Key::P)]);
        assert!(!v.show_panel);
        frame(&ctx, &mut v, size, vec![key(Key::F1)]);
        assert!(v.show_help);
        frame(&ctx, &mut v, size, vec![key(Key::Escape)]);
        assert!(!v.show_help);
        frame(&ctx, &mut v, size, vec![key(Key::Num1)]);
        assert!(matches!(v.view.zoom(), super::super::image_view::Zoom::Scale { .. }));
        frame(&ctx, &mut v, size, vec![key(Key::F)]);
        assert_eq!(v.view.zoom(), super::super::image_view::Zoom::Fit);
        drop_textures(&ctx, v);
    }

    /// A key pressed (`down`) or released with `modifiers` held.
    fn key_with(key: Key, down: bool, modifiers: Modifiers) -> egui::Event {
        egui::Event::Key { key, physical_key: None, pressed: down, repeat: false, modifiers }
    }

    #[test]
    fn a_drag_on_the_image_is_one_undo_step_and_ctrl_z_and_ctrl_shift_z_undo_and_redo_it() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        let original = *v.camera.settings();
        let at = |x: f32| egui::pos2(600.0 + x, 300.0);
        let button = |down| egui::Event::PointerButton {
            pos: at(if down { 0.0 } else { 100.0 }),
            button: egui::PointerButton::Primary,
            pressed: down,
            modifiers: Modifiers::NONE,
        };
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(at(0.0))]);
        frame(&ctx, &mut v, size, vec![button(true)]);
        // Ten frames of dragging: ten camera changes, one step.
        for step in 1..=10 {
            frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(at(10.0 * step as f32))]);
        }
        frame(&ctx, &mut v, size, vec![button(false)]);
        frame(&ctx, &mut v, size, vec![]);
        let dragged = *v.camera.settings();
        assert_ne!(dragged, original, "the drag orbited");
        let ctrl_z = key_with(Key::Z, true, Modifiers::COMMAND);
        frame(&ctx, &mut v, size, vec![ctrl_z.clone()]);
        assert_eq!(*v.camera.settings(), original, "one undo goes back to before the drag");
        frame(&ctx, &mut v, size, vec![ctrl_z]);
        assert_eq!(*v.camera.settings(), original, "nothing before it");
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND | Modifiers::SHIFT)]);
        assert_eq!(*v.camera.settings(), dragged, "Ctrl+Shift+Z redoes it");
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        frame(&ctx, &mut v, size, vec![key_with(Key::Y, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), dragged, "and so does Ctrl+Y");
        // Opening another scene starts a new history.
        v.source.open(scenes().join("sphere.ron"), &ctx);
        let change = v.source.wait_for_load(&ctx).unwrap();
        v.scene_changed(&ctx, change);
        let sphere = *v.camera.settings();
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), sphere);
        drop_textures(&ctx, v);
    }

    #[test]
    fn a_burst_of_wheel_turns_is_one_undo_step() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        let over_image = egui::Event::PointerMoved(egui::pos2(600.0, 300.0));
        let wheel = egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: egui::vec2(0.0, 40.0),
            modifiers: Modifiers::NONE,
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Wheel,
        };
        let original = *v.camera.settings();
        let burst = |v: &mut Viewer| {
            // Three turns a few frames apart, then a second of stillness (egui's clock runs 1/60 s a frame).
            for _ in 0..3 {
                frame(&ctx, v, size, vec![over_image.clone(), wheel.clone()]);
                for _ in 0..5 {
                    frame(&ctx, v, size, vec![over_image.clone()]);
                }
            }
            for _ in 0..60 {
                frame(&ctx, v, size, vec![over_image.clone()]);
            }
            *v.camera.settings()
        };
        let first = burst(&mut v);
        let second = burst(&mut v);
        assert!(first != original && second != first, "the wheel zoomed");
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), first, "one undo takes back the whole second burst");
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), original);
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_keystrokes_typed_into_a_camera_field_are_one_undo_step() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        let original = *v.camera.settings();
        frame(&ctx, &mut v, size, vec![]);
        // The position's x field (box.ron: -4), found on the panel as drawn.
        let field = v.camera.field_rects()[0];
        let click = |down| egui::Event::PointerButton {
            pos: field.center(),
            button: egui::PointerButton::Primary,
            pressed: down,
            modifiers: Modifiers::NONE,
        };
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(field.center()), click(true)]);
        frame(&ctx, &mut v, size, vec![click(false)]);
        frame(&ctx, &mut v, size, vec![key_with(Key::A, true, Modifiers::COMMAND)]);
        for text in ["-", "2", ".", "5"] {
            frame(&ctx, &mut v, size, vec![egui::Event::Text(text.into())]);
        }
        frame(&ctx, &mut v, size, vec![key(Key::Enter)]);
        frame(&ctx, &mut v, size, vec![]);
        assert_eq!(v.camera.settings().position.x, -2.5, "typed");
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), original, "one undo takes back the whole field");
        drop_textures(&ctx, v);
    }

    #[test]
    fn held_fly_keys_move_the_camera_every_frame_and_stop_on_release() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        let start = *v.camera.settings();
        // In orbit mode W does nothing.
        frame(&ctx, &mut v, size, vec![key_with(Key::W, true, Modifiers::NONE)]);
        frame(&ctx, &mut v, size, vec![key_with(Key::W, false, Modifiers::NONE)]);
        assert_eq!(*v.camera.settings(), start);
        frame(&ctx, &mut v, size, vec![key(Key::V)]);
        assert!(v.camera.flying());
        frame(&ctx, &mut v, size, vec![key_with(Key::W, true, Modifiers::NONE)]);
        let mut positions = vec![v.camera.settings().position];
        for _ in 0..5 {
            frame(&ctx, &mut v, size, vec![]);
            positions.push(v.camera.settings().position);
        }
        let forward = (start.center_of_interest - start.position).normalize();
        for pair in positions.windows(2) {
            let step = pair[1] - pair[0];
            assert!(step.length() > 0.0, "a held key moves the camera in every frame: {positions:?}");
            assert!((step.normalize() - forward).length() < 1e-4, "along the view direction: {step}");
        }
        let moved = *v.camera.settings();
        let offset = |s: &CameraSettings| s.center_of_interest - s.position;
        assert!(
            (offset(&moved) - offset(&start)).length() < 1e-4,
            "the centre of interest moves with the eye"
        );
        frame(&ctx, &mut v, size, vec![key_with(Key::W, false, Modifiers::NONE)]);
        let released = *v.camera.settings();
        frame(&ctx, &mut v, size, vec![]);
        assert_eq!(*v.camera.settings(), released, "released, the camera stays");
        // The flight is one undo step.
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), start);
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_render_sees_through_the_scene_files_lens_wherever_the_camera_moves() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("depth_of_field.ron")));
        let lens = v.source.scene().camera.lens();
        assert!(lens.radius > 0.0, "depth_of_field.ron has an aperture");
        assert_eq!(v.job_spec().unwrap().camera.lens(), lens);
        v.camera.edit(|s| s.zoom(0.5));
        let spec = v.job_spec().unwrap();
        assert_ne!(spec.camera.position(), v.source.scene().camera.position(), "the camera moved");
        assert_eq!(spec.camera.lens(), lens);
        // The panel's aperture is the render's.
        v.camera.edit(|s| CameraSettings { aperture: 0.0, ..s });
        assert_eq!(v.job_spec().unwrap().camera.lens().radius, 0.0, "set to a pinhole in the panel");
        drop_textures(&ctx, v);
    }

    #[test]
    fn opening_a_scene_at_a_resolution_scale_other_than_one_says_so() {
        // Before, the scale carried over to the next scene unannounced.
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, None);
        v.image.set_resolution_scale(0.5);
        v.source.open(scenes().join("box.ron"), &ctx);
        let change = v.source.wait_for_load(&ctx).unwrap();
        v.scene_changed(&ctx, change);
        let text = &v.notice.as_ref().expect("a notice").text;
        assert!(text.starts_with("resolution scale 0.5× kept"), "{text}");
        drop_textures(&ctx, v);
    }

    #[test]
    fn space_stops_a_no_limit_render_and_the_image_can_then_be_saved() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        v.image.set_resolution_scale(0.25);
        let size = egui::vec2(1000.0, 700.0);
        frame(&ctx, &mut v, size, vec![]);
        // Tick "no limit" as a user would: the render starts over without a limit.
        v.image = {
            let mut image = ImageSettings::new(v.source.scene());
            image.set_resolution_scale(0.25);
            image.set_no_limit(true);
            image
        };
        v.start(&ctx, Kind::Full);
        let deadline = Instant::now() + Duration::from_secs(30);
        while v.scheduler.shown_job().is_none_or(|j| j.progress().spp < 16) {
            assert!(Instant::now() < deadline, "no pass finished");
            frame(&ctx, &mut v, size, vec![]);
        }
        assert!(!v.scheduler.frame_is_final());
        frame(&ctx, &mut v, size, vec![key(Key::Space)]);
        finish_render(&ctx, &mut v);
        assert!(v.scheduler.status_text(None).contains("stopped"), "{}", v.scheduler.status_text(None));
        drop_textures(&ctx, v);
    }

    #[test]
    fn frame_fills_the_view_with_the_pinned_object_and_keeps_the_view_direction() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        frame(&ctx, &mut v, size, vec![]);
        // Pin the amber box: its object's pixel, found by casting.
        let (w, h) = v.image.full_size(v.source.scene());
        let view = ViewPlane::new(v.camera.settings().to_camera().unwrap(), w, h).unwrap();
        let amber = (0..h)
            .flat_map(|y| (0..w).map(move |x| [x, y]))
            .find(|&[x, y]| {
                v.source.scene().scene.cast(&view.center_ray(x, y)).is_some_and(|hit| hit.object == 1)
            })
            .expect("the amber box is in view");
        v.view.pin(amber);
        let before = *v.camera.settings();
        frame(&ctx, &mut v, size, vec![key(Key::Period)]);
        let after = *v.camera.settings();
        let bounds = v.source.scene().scene.objects()[1].primitive.bounds().unwrap();
        assert!((after.center_of_interest - bounds.center()).length() < 1e-4, "{after:?}");
        let direction = |s: &CameraSettings| (s.center_of_interest - s.position).normalize();
        assert!((direction(&after) - direction(&before)).length() < 1e-4);
        assert_eq!(v.pinned_object(), Some(1), "the pin stays on the framed object");
        // Nothing pinned: nothing to frame, and the window says so.
        v.view.unpin();
        frame(&ctx, &mut v, size, vec![key(Key::Period)]);
        assert_eq!(*v.camera.settings(), after);
        assert!(v.notice.as_ref().is_some_and(|n| n.text.starts_with("nothing to frame")));
        drop_textures(&ctx, v);
    }

    #[test]
    fn alt_click_sets_the_focus_distance_to_the_depth_of_what_the_pixel_sees() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1000.0, 700.0);
        frame(&ctx, &mut v, size, vec![]);
        let before = *v.camera.settings();
        let click = |at, down, modifiers| egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed: down,
            modifiers,
        };
        // A plain click pins a pixel and leaves the lens alone.
        let at = egui::pos2(650.0, 330.0);
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(at), click(at, true, Modifiers::NONE)]);
        frame(&ctx, &mut v, size, vec![click(at, false, Modifiers::NONE)]);
        assert!(v.view.pinned().is_some(), "the click pinned a pixel");
        assert_eq!(*v.camera.settings(), before);
        let at = egui::pos2(700.0, 400.0);
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(at), click(at, true, Modifiers::ALT)]);
        frame(&ctx, &mut v, size, vec![click(at, false, Modifiers::ALT)]);
        let [x, y] = v.view.pinned().expect("the click pinned a pixel");
        let camera = before.to_camera().unwrap();
        let (w, h) = v.image.full_size(v.source.scene());
        let ray = ViewPlane::new(camera, w, h).unwrap().center_ray(x, y);
        let hit = v.source.scene().scene.cast(&ray).expect("box.ron: the pixel sees an object");
        let depth = (ray.at(hit.t) - camera.position()).dot(camera.basis().z);
        assert!(depth > 0.0 && depth != before.focus_distance, "{depth}");
        assert_eq!(v.camera.settings().focus_distance, depth);
        assert_eq!(CameraSettings { focus_distance: before.focus_distance, ..*v.camera.settings() }, before);
        frame(&ctx, &mut v, size, vec![key_with(Key::Z, true, Modifiers::COMMAND)]);
        assert_eq!(*v.camera.settings(), before, "one undo step");
        // Nothing pinned: nothing changes, and the window says why.
        v.view.unpin();
        assert!(!v.focus_on_pinned());
        assert!(v.notice.as_ref().is_some_and(|n| n.text.starts_with("nothing to focus on")));
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_camera_saved_into_the_scene_file_loads_again_and_its_reload_keeps_the_view() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let text = std::fs::read_to_string(scenes().join("sphere.ron")).unwrap();
        std::fs::write(&path, &text).unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(path.clone()));
        v.camera.edit(|s| s.orbit(0.4, 0.2).zoom(0.7));
        let edited = *v.camera.settings();
        v.camera.save_to_file(&path);
        assert_eq!(v.camera.message(), Some("saved the camera into scene.ron"));
        assert_eq!(rt_core::load_scene(&path).unwrap().camera, edited.to_camera().unwrap());
        // The view moves on before the reload that the write triggers arrives.
        v.camera.edit(|s| s.orbit(0.1, 0.0));
        let moved_on = *v.camera.settings();
        reload(&mut v, &ctx);
        assert_eq!(*v.camera.settings(), moved_on, "the reload kept the view");
        assert_eq!(v.camera.file_settings(), edited, "Reset now goes to the saved camera");
        // The comments are still there.
        let saved = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            saved.lines().filter(|l| l.contains("//")).count(),
            text.lines().filter(|l| l.contains("//")).count()
        );
        drop_textures(&ctx, v);
    }

    #[test]
    fn save_writes_next_to_the_scene_file_and_the_built_in_scene_keeps_the_launch_folder() {
        let scene = Path::new("/some/scenes/box.ron");
        assert_eq!(save_path_for("render.png", Some(scene)), Path::new("/some/scenes/render.png"));
        assert_eq!(save_path_for("out/x.png", Some(scene)), Path::new("/some/scenes/out/x.png"));
        assert_eq!(save_path_for("/tmp/x.png", Some(scene)), Path::new("/tmp/x.png"));
        assert_eq!(save_path_for("render.png", None), Path::new("render.png"));

        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let text = std::fs::read_to_string(scenes().join("sphere.ron"))
            .unwrap()
            .replace("width: 320, height: 240", "width: 32, height: 24");
        std::fs::write(&path, text).unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(path));
        finish_render(&ctx, &mut v);
        v.save();
        assert!(dir.path().join("render.png").is_file(), "{:?}", v.notice.as_ref().map(|n| &n.text));
        drop_textures(&ctx, v);
    }

    #[test]
    fn b_and_a_drag_render_a_region_and_shift_b_renders_the_whole_image_again() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        v.show_panel = false;
        let size = egui::vec2(1000.0, 700.0);
        frame(&ctx, &mut v, size, vec![]);
        finish_render(&ctx, &mut v);
        frame(&ctx, &mut v, size, vec![]);
        let camera = *v.camera.settings();
        let button = |pos, pressed| egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        };
        let (from, to) = (egui::pos2(400.0, 250.0), egui::pos2(600.0, 400.0));
        frame(&ctx, &mut v, size, vec![key(Key::B), egui::Event::PointerMoved(from)]);
        frame(&ctx, &mut v, size, vec![button(from, true)]);
        for k in 1..=4 {
            frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(from + (to - from) * k as f32 / 4.0)]);
        }
        frame(&ctx, &mut v, size, vec![button(to, false)]);
        let region = v.scheduler.region().cloned().expect("a region render");
        assert!(region.width() > 10 && region.height() > 10, "{region:?}");
        assert_eq!(*v.camera.settings(), camera, "the drag orbited the camera");
        finish_render(&ctx, &mut v);
        frame(&ctx, &mut v, size, vec![key_with(Key::B, true, Modifiers::SHIFT)]);
        assert_eq!(v.scheduler.region(), None);
        assert!(v.scheduler.status_text(None).starts_with("full "), "{}", v.scheduler.status_text(None));
        drop_textures(&ctx, v);
    }

    #[test]
    fn the_scene_view_renders_nothing_while_closed_and_its_job_stops_when_it_closes() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1100.0, 700.0);
        // A pinned pixel records nothing while the view is closed.
        v.view.pin([100, 80]);
        for _ in 0..5 {
            frame(&ctx, &mut v, size, vec![]);
        }
        assert!(!v.scene_view.is_open());
        assert_eq!(v.scene_view.renders_started(), 0, "a closed view started a render");
        assert!(!v.scene_view.rendering(), "a closed view runs a job");
        // Key 3 opens it: its first frame starts one flat render, and the
        // pinned pixel's record, which arrives off the UI thread.
        frame(&ctx, &mut v, size, vec![key(Key::Num3)]);
        assert!(v.scene_view.is_open());
        assert_eq!(v.scene_view.renders_started(), 1);
        assert!(v.scene_view.rendering());
        let deadline = Instant::now() + Duration::from_secs(30);
        while v.scene_view.record_pixel() != Some([100, 80]) {
            assert!(Instant::now() < deadline, "the record never arrived");
            frame(&ctx, &mut v, size, vec![]);
            std::thread::sleep(Duration::from_millis(5));
        }
        // Closed again: the job is dropped (cancelled), and no frame starts another.
        frame(&ctx, &mut v, size, vec![key(Key::Num3)]);
        assert!(!v.scene_view.is_open());
        assert!(!v.scene_view.rendering(), "the job outlived the view");
        for _ in 0..5 {
            frame(&ctx, &mut v, size, vec![]);
        }
        assert_eq!(v.scene_view.renders_started(), 1);
        drop_textures(&ctx, v);
    }

    #[test]
    fn dragging_in_the_scene_view_orbits_the_observer_and_leaves_the_render_camera() {
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(scenes().join("box.ron")));
        let size = egui::vec2(1100.0, 700.0);
        v.scene_view.set_open(true);
        frame(&ctx, &mut v, size, vec![]);
        frame(&ctx, &mut v, size, vec![]);
        let observer = *v.scene_view.observer().expect("framed on first show").settings();
        let camera = *v.camera.settings();
        // The scene view fills the right part of the window.
        let (from, to) = (egui::pos2(900.0, 350.0), egui::pos2(980.0, 380.0));
        let button = |pos, pressed| egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        };
        frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(from)]);
        frame(&ctx, &mut v, size, vec![button(from, true)]);
        for k in 1..=4 {
            frame(&ctx, &mut v, size, vec![egui::Event::PointerMoved(from + (to - from) * k as f32 / 4.0)]);
        }
        frame(&ctx, &mut v, size, vec![button(to, false)]);
        let moved = *v.scene_view.observer().unwrap().settings();
        assert_ne!(moved.position, observer.position, "the observer did not orbit");
        assert_eq!(moved.center_of_interest, observer.center_of_interest);
        assert_eq!(*v.camera.settings(), camera, "the drag moved the render camera");
        drop_textures(&ctx, v);
    }

    /// A press at `from`, a drag to `to` and a release there, a frame each.
    fn drag(ctx: &egui::Context, v: &mut Viewer, size: egui::Vec2, from: egui::Pos2, to: egui::Pos2) {
        let button = |pos, pressed| egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        };
        frame(ctx, v, size, vec![egui::Event::PointerMoved(from)]);
        frame(ctx, v, size, vec![button(from, true)]);
        frame(ctx, v, size, vec![egui::Event::PointerMoved(to)]);
        frame(ctx, v, size, vec![button(to, false)]);
    }

    #[test]
    fn a_material_edit_renders_the_pinned_objects_new_material_without_writing_the_file_and_revert_restores()
    {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("spheres.ron");
        let text = std::fs::read_to_string(scenes().join("metal_rough.ron"))
            .unwrap()
            .replace("image: (width: 320, height: 320)", "image: (width: 64, height: 64)")
            .replace("samples_per_pixel: 64", "samples_per_pixel: 2");
        std::fs::write(&path, &text).unwrap();
        let ctx = egui::Context::default();
        let mut v = viewer(&ctx, Some(path.clone()));
        // Tall enough that the whole side panel is on screen.
        let size = egui::vec2(1000.0, 2400.0);
        frame(&ctx, &mut v, size, vec![]);
        let loaded = v.source.scene().clone();
        // The centre sphere: "m0.5 r0.5".
        v.view.pin([32, 32]);
        let object = v.pinned_object().expect("the centre pixel sees a sphere");
        let index = loaded.scene.objects()[object].material;
        assert_eq!(loaded.scene.material_names()[index], "m0.5 r0.5");
        let roughness = |s: &rt_core::LoadedScene| s.scene.material(index).physical.unwrap().roughness;
        frame(&ctx, &mut v, size, vec![]);
        let slider = v.materials.drawn.roughness.expect("the roughness slider is drawn");
        let generation = v.scheduler.job().map(|(j, _)| j.generation());
        // Drag the slider from its left end (roughness 0) a quarter of its way.
        let from = egui::pos2(slider.left() + 1.0, slider.center().y);
        drag(&ctx, &mut v, size, from, from + egui::vec2(25.0, 0.0));
        let edited = v.source.scene().clone();
        assert!(!std::sync::Arc::ptr_eq(&edited, &loaded), "the edit made no new scene");
        assert!(roughness(&edited) < 0.45, "roughness {}", roughness(&edited));
        assert_eq!(roughness(&loaded), 0.5, "the loaded scene changed");
        assert!(v.materials.is_edited(index));
        // A new job renders the edited scene.
        let (job, _) = v.scheduler.job().expect("a job runs");
        assert_ne!(Some(job.generation()), generation, "no new job started");
        assert!(std::sync::Arc::ptr_eq(&job.spec().scene, &edited), "the job renders another scene");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), text, "the scene file was written");
        // Revert brings the loaded scene back, and renders it.
        frame(&ctx, &mut v, size, vec![]);
        let revert = v.materials.drawn.revert.expect("Revert is drawn");
        drag(&ctx, &mut v, size, revert.center(), revert.center());
        assert!(std::sync::Arc::ptr_eq(v.source.scene(), &loaded), "Revert did not restore the loaded scene");
        assert!(!v.materials.is_edited(index));
        assert!(std::sync::Arc::ptr_eq(&v.scheduler.job().unwrap().0.spec().scene, &loaded));
        // An edit is dropped, with a notice, when the file loads again.
        drag(&ctx, &mut v, size, from, from + egui::vec2(25.0, 0.0));
        assert!(v.materials.is_edited(index));
        reload(&mut v, &ctx);
        assert_eq!(roughness(v.source.scene()), 0.5);
        assert!(!v.materials.is_edited(index));
        assert!(v.notice.as_ref().is_some_and(|n| n.text.contains("material edits dropped")));
        drop_textures(&ctx, v);
    }
}
