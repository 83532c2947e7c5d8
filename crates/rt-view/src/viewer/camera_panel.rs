//! The camera section of the side panel: field of view (or, orthographic,
//! the view's height in world units), near, position, look-at, projection,
//! orbit or fly navigation, Reset, Undo and Redo, Frame (the pinned
//! object), and the camera saved into the scene file or copied as RON, over
//! the pure functions of [`super::camera_controls`], [`super::fly`],
//! [`super::camera_history`] and [`super::camera_in_file`].
//!
//! The panel owns the viewer's camera: the image view's orbit, pan and zoom
//! edit it through [`CameraPanel::edit`], and a newly loaded scene replaces
//! it through [`CameraPanel::scene_loaded`]. Every edit is checked by
//! [`CameraSettings::accept`], so the camera is always valid. Once a frame,
//! [`CameraPanel::end_frame`] tells the history which gesture is under way,
//! so that a drag, a wheel burst, a held fly key or a typed field is one
//! step of undo.

use std::path::Path;

use rt_core::{Camera, Projection, Real, Vec3};

use super::camera_controls::{APERTURE_RANGE, CameraSettings, FOV_RANGE, NEAR_RANGE};
use super::camera_history::{CameraHistory, Gesture};
use super::camera_in_file::{camera_ron, save_camera};
use super::fly::{self, FlyKeys};
use super::interaction::Interaction;

/// Decimals of every length and angle shown in the panel.
const DECIMALS: usize = 3;

/// A wheel turn this recent (seconds) belongs to the same burst: one undo step.
const WHEEL_BURST: f64 = 0.4;

/// How the mouse and keys move the camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Navigation {
    /// Dragging orbits the eye about the centre of interest.
    Orbit,
    /// WASD/QE move the eye, dragging turns the view ([`super::fly`]).
    Fly,
}

/// The viewer's camera and the scene file's, for Reset.
pub(super) struct CameraPanel {
    settings: CameraSettings,
    /// The camera as the scene file gave it.
    file_camera: Camera,
    /// Set when the last edit was refused; cleared by the next accepted one,
    /// Reset, or a new scene.
    refused: bool,
    history: CameraHistory,
    navigation: Navigation,
    /// When the wheel last scrolled (egui's time, seconds).
    last_wheel: Option<f64>,
    /// Frame was clicked: the app frames the pinned object.
    frame_requested: bool,
    /// Focus was pressed: the app sets the focus distance to the pinned
    /// pixel's depth.
    focus_requested: bool,
    /// What Save to file or Copy did.
    message: Option<String>,
    /// Where the position's fields were drawn (tests click them).
    #[cfg(test)]
    field_rects: [egui::Rect; 3],
}

impl CameraPanel {
    /// The panel for a scene seen by `camera`.
    pub fn new(camera: &Camera) -> Self {
        let settings = CameraSettings::from_camera(camera);
        Self {
            settings,
            file_camera: *camera,
            refused: false,
            history: CameraHistory::new(settings),
            navigation: Navigation::Orbit,
            last_wheel: None,
            frame_requested: false,
            focus_requested: false,
            message: None,
            #[cfg(test)]
            field_rects: [egui::Rect::NOTHING; 3],
        }
    }

    /// The camera settings in force (always a valid camera).
    pub fn settings(&self) -> &CameraSettings {
        &self.settings
    }

    /// A scene with `camera` was loaded: the view starts from it if `reset`
    /// (another file was opened) or if the file's camera changed; otherwise
    /// the user's edits are kept.
    /// Another file starts a new undo history; a reload that moved the
    /// camera is a step of it.
    pub fn scene_loaded(&mut self, camera: &Camera, reset: bool) {
        let before = self.settings;
        if reset || *camera != self.file_camera {
            self.settings = CameraSettings::from_camera(camera);
        }
        self.file_camera = *camera;
        self.refused = false;
        if reset {
            self.history = CameraHistory::new(self.settings);
            self.message = None;
        } else {
            self.history.record(before, self.settings);
        }
    }

    /// The scene file's camera, as settings.
    pub fn file_settings(&self) -> CameraSettings {
        CameraSettings::from_camera(&self.file_camera)
    }

    /// Starts from `view` (a remembered camera) instead of the file's, if it
    /// is a valid camera (fov and near brought into the controls' ranges).
    pub fn restore(&mut self, view: CameraSettings) {
        self.settings = self.settings.accept(view);
        self.history = CameraHistory::new(self.settings);
    }

    /// Back to the scene file's camera; returns whether that changed it.
    pub fn reset(&mut self) -> bool {
        self.refused = false;
        let file = CameraSettings::from_camera(&self.file_camera);
        self.set_step(file)
    }

    /// `camera` in force as a step of its own (Reset, Frame); returns
    /// whether that changed the camera.
    fn set_step(&mut self, camera: CameraSettings) -> bool {
        let before = self.settings;
        self.settings = camera;
        self.history.record(before, camera);
        camera != before
    }

    /// Undoes the last camera step; returns whether the camera changed.
    pub fn undo(&mut self) -> bool {
        let Some(camera) = self.history.undo(self.settings) else { return false };
        let changed = camera != self.settings;
        self.settings = camera;
        self.refused = false;
        changed
    }

    /// Redoes the last undone camera step; returns whether the camera changed.
    pub fn redo(&mut self) -> bool {
        let Some(camera) = self.history.redo(self.settings) else { return false };
        let changed = camera != self.settings;
        self.settings = camera;
        self.refused = false;
        changed
    }

    /// Whether the mouse and keys fly rather than orbit.
    pub fn flying(&self) -> bool {
        self.navigation == Navigation::Fly
    }

    /// Switches between orbit and fly navigation.
    pub fn toggle_navigation(&mut self) {
        self.navigation = match self.navigation {
            Navigation::Orbit => Navigation::Fly,
            Navigation::Fly => Navigation::Orbit,
        };
    }

    /// One frame of fly keys (when flying and no text field has the keys):
    /// moves the camera at the speed `scene` calls for, and keeps frames
    /// coming while a key is held. Moving counts as dragging, so previews
    /// render until the keys are released.
    pub fn fly_keys(&mut self, ctx: &egui::Context, scene: &rt_core::Scene) -> Interaction {
        if !self.flying() || ctx.egui_wants_keyboard_input() {
            return Interaction::default();
        }
        let (keys, dt) = ctx.input(|i| (FlyKeys::held(i), i.stable_dt));
        if !keys.moving() {
            return Interaction::default();
        }
        ctx.request_repaint();
        let distance = fly::speed(fly::scene_size(scene), &self.settings) * fly::step_seconds(dt);
        let changed = self.edit(|s| fly::fly(&s, keys, distance));
        Interaction { changed, dragging: true }
    }

    /// The camera moved so that the box `bounds` fills the view of an image
    /// `aspect` (width / height) wide ([`CameraSettings::framing`] of its
    /// bounding sphere); returns whether the camera changed.
    pub fn frame_box(&mut self, min: Vec3, max: Vec3, aspect: Real) -> bool {
        let (center, radius) = (0.5 * (min + max), 0.5 * (max - min).length());
        let framed = self.settings.framing(center, radius, aspect);
        self.set_step(framed)
    }

    /// Whether Frame was clicked since the last call.
    pub fn take_frame_request(&mut self) -> bool {
        std::mem::take(&mut self.frame_requested)
    }

    /// Whether Focus was clicked since the last call.
    pub fn take_focus_request(&mut self) -> bool {
        std::mem::take(&mut self.focus_requested)
    }

    /// The end of a frame: tells the history which gesture is changing the
    /// camera (a text field with the keys, a mouse button held, fly keys
    /// held, the wheel turned a moment ago), so that each is one step.
    pub fn end_frame(&mut self, ctx: &egui::Context) {
        let (time, scrolling, pointer, keys) =
            ctx.input(|i| (i.time, i.is_scrolling(), i.pointer.any_down(), FlyKeys::held(i).moving()));
        if scrolling {
            self.last_wheel = Some(time);
        }
        let wheel = self.last_wheel.is_some_and(|t| time - t < WHEEL_BURST);
        let typing =
            ctx.egui_wants_keyboard_input().then(|| ctx.memory(|m| m.focused()).map_or(0, |id| id.value()));
        let gesture = if let Some(id) = typing {
            Some(Gesture::Typing(id))
        } else if pointer {
            Some(Gesture::Pointer)
        } else if keys && self.flying() {
            Some(Gesture::Fly)
        } else if wheel {
            Some(Gesture::Wheel)
        } else {
            None
        };
        self.history.observe(self.settings, gesture);
    }

    /// Writes the camera into the scene file at `path` (keeping the rest of
    /// the file as it is); the file's camera is then this one, so the
    /// reload the write triggers keeps the view.
    pub fn save_to_file(&mut self, path: &Path) {
        let name =
            path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into());
        self.message = Some(match save_camera(path, &self.settings) {
            Ok(changed) => {
                if let Ok(camera) = self.settings.to_camera() {
                    self.file_camera = camera;
                }
                if changed {
                    format!("saved the camera into {name}")
                } else {
                    format!("{name} already has this camera")
                }
            }
            Err(e) => format!("camera not saved: {e}"),
        });
    }

    /// Puts the camera on the clipboard as a scene file's `camera: ( … ),` line.
    pub fn copy_as_ron(&mut self, ctx: &egui::Context) {
        let text = camera_ron(&self.settings);
        ctx.copy_text(text.clone());
        self.message = Some(format!("copied {text}"));
    }

    /// Where the position's x, y and z fields were last drawn.
    #[cfg(test)]
    pub fn field_rects(&self) -> [egui::Rect; 3] {
        self.field_rects
    }

    /// What Save to file or Copy did.
    #[cfg(test)]
    pub fn message(&self) -> Option<&str> {
        self.message.as_deref()
    }

    /// Whether the last edit was refused (it would have made the camera degenerate).
    #[cfg(test)]
    pub fn refused(&self) -> bool {
        self.refused
    }

    /// Applies an edit (orbit, pan, zoom, a control) if it keeps the camera
    /// valid; returns whether the camera changed.
    pub fn edit(&mut self, edit: impl FnOnce(CameraSettings) -> CameraSettings) -> bool {
        let candidate = edit(self.settings);
        let accepted = self.settings.accept(candidate);
        if candidate != self.settings {
            self.refused = accepted != candidate;
        }
        let changed = accepted != self.settings;
        self.settings = accepted;
        changed
    }

    /// The camera controls; `scene_file` is where Save to file writes
    /// (`None`: the built-in scene, which has no file), `selected` names the
    /// pinned object that Frame frames, if any.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        scene_file: Option<&Path>,
        selected: Option<&str>,
    ) -> Interaction {
        let mut s = self.settings;
        let mut dragging = false;
        ui.heading("Camera");
        egui::Grid::new("camera").num_columns(2).spacing([8.0, 4.0]).show(ui, |ui| {
            match s.projection {
                Projection::Perspective => {
                    ui.label("FOV y (°)");
                    let r = ui.add(
                        egui::Slider::new(&mut s.fov_y, FOV_RANGE)
                            .logarithmic(true)
                            .smart_aim(false)
                            .max_decimals(DECIMALS),
                    );
                    dragging |= r.dragged();
                }
                Projection::Orthographic => {
                    ui.label("view height");
                    let mut height = s.view_height();
                    let speed = 0.005 * height;
                    let r = ui
                        .add(
                            egui::DragValue::new(&mut height)
                                .speed(speed)
                                .range(1e-6..=1e9)
                                .max_decimals(DECIMALS)
                                .custom_formatter(shown),
                        )
                        .on_hover_text("How tall the view is, in world units");
                    if r.changed() {
                        s = s.with_view_height(height);
                    }
                    dragging |= r.dragged();
                }
            }
            ui.end_row();
            ui.label("near");
            let r = ui.add(
                egui::Slider::new(&mut s.near, NEAR_RANGE)
                    .logarithmic(true)
                    .smart_aim(false)
                    .max_decimals(DECIMALS),
            );
            dragging |= r.dragged();
            ui.end_row();
            dragging |= lens_ui(ui, &mut s);
            ui.label("position");
            let (dragged, _rects) = vector_ui(ui, &mut s.position);
            dragging |= dragged;
            #[cfg(test)]
            {
                self.field_rects = _rects;
            }
            ui.end_row();
            ui.label("look at");
            dragging |= vector_ui(ui, &mut s.center_of_interest).0;
            ui.end_row();
        });
        let mut projection = s.projection;
        ui.horizontal(|ui| {
            ui.radio_value(&mut projection, Projection::Perspective, "perspective");
            ui.radio_value(&mut projection, Projection::Orthographic, "orthographic");
        });
        // What is in view at the centre of interest stays in view.
        s = s.with_projection(projection);
        ui.horizontal(|ui| {
            ui.label("navigate");
            let mut navigation = self.navigation;
            ui.radio_value(&mut navigation, Navigation::Orbit, "orbit")
                .on_hover_text("Drag orbits about the centre of interest (V switches)");
            ui.radio_value(&mut navigation, Navigation::Fly, "fly")
                .on_hover_text("WASD move, Q/E down and up, Shift faster; drag to look around (V switches)");
            self.navigation = navigation;
        });
        let mut changed = false;
        ui.horizontal(|ui| {
            if ui.button("Reset").on_hover_text("Back to the scene file's camera (R)").clicked() {
                changed |= self.reset();
            }
            let undo = ui.add_enabled(self.history.can_undo(&s), egui::Button::new("Undo"));
            if undo.on_hover_text("Undo the last camera change (Ctrl+Z)").clicked() {
                changed |= self.undo();
            }
            let redo = ui.add_enabled(self.history.can_redo(&s), egui::Button::new("Redo"));
            if redo.on_hover_text("Redo (Ctrl+Shift+Z or Ctrl+Y)").clicked() {
                changed |= self.redo();
            }
            let frame = ui.add_enabled(selected.is_some(), egui::Button::new("Frame"));
            let what = selected
                .map_or("Click a pixel of an object first".to_owned(), |o| format!("Fill the view with {o}"));
            if frame.on_hover_text(format!("{what} (.)")).clicked() {
                self.frame_requested = true;
            }
            let focus = ui.add_enabled(selected.is_some(), egui::Button::new("Focus"));
            let what = selected.map_or("Click a pixel of an object first".to_owned(), |o| {
                format!("Set the focus distance to the pinned pixel's depth, on {o}")
            });
            if focus.on_hover_text(format!("{what} (Alt+click)")).clicked() {
                self.focus_requested = true;
            }
        });
        if changed {
            s = self.settings;
        }
        ui.horizontal(|ui| {
            let save = ui.add_enabled(scene_file.is_some(), egui::Button::new("Save to scene file"));
            let hover = scene_file.map_or("The built-in scene has no file".to_owned(), |p| {
                format!("Write this camera into {} (only its camera block changes)", p.display())
            });
            if let (true, Some(path)) = (save.on_hover_text(hover).clicked(), scene_file) {
                self.save_to_file(path);
            }
            if ui.button("Copy as RON").on_hover_text("The camera block, for a scene file").clicked() {
                self.copy_as_ron(ui.ctx());
            }
        });
        if let Some(message) = &self.message {
            ui.label(message);
        }
        changed |= self.edit(|_| s);
        if self.refused {
            ui.label("that edit would make the camera degenerate: kept the last valid one");
        }
        Interaction { changed, dragging }
    }
}

/// The lens rows of the camera grid: the aperture (lens radius; 0 is the
/// pinhole, logarithmic above) and the focus distance along cam_z. Returns
/// whether one is being dragged.
fn lens_ui(ui: &mut egui::Ui, s: &mut CameraSettings) -> bool {
    ui.label("aperture");
    let r = ui
        .add(
            egui::Slider::new(&mut s.aperture, APERTURE_RANGE)
                .logarithmic(true)
                .smallest_positive(1e-3)
                .smart_aim(false)
                .max_decimals(DECIMALS),
        )
        .on_hover_text("Lens radius in world units: 0 is a pinhole, everything sharp");
    let mut dragging = r.dragged();
    ui.end_row();
    ui.label("focus distance");
    let speed = 0.005 * s.focus_distance.max(1e-3);
    let r = ui
        .add_enabled(
            s.aperture > 0.0,
            egui::DragValue::new(&mut s.focus_distance)
                .speed(speed)
                .range(1e-3..=1e9)
                .max_decimals(DECIMALS)
                .custom_formatter(shown),
        )
        .on_hover_text(
            "Distance along the view direction that is in focus (Alt+click a pixel to focus on it)",
        );
    dragging |= r.dragged();
    ui.end_row();
    dragging
}

/// Three drag values in a row; returns whether one is being dragged, and
/// where the fields were drawn.
fn vector_ui(ui: &mut egui::Ui, v: &mut Vec3) -> (bool, [egui::Rect; 3]) {
    ui.horizontal(|ui| {
        let speed = 0.01 * v.abs().max_element().max(1.0);
        let mut dragging = false;
        let mut rects = [egui::Rect::NOTHING; 3];
        for (axis, rect) in rects.iter_mut().enumerate() {
            let value: &mut Real = &mut v[axis];
            let r = ui
                .add(egui::DragValue::new(value).speed(speed).max_decimals(DECIMALS).custom_formatter(shown));
            dragging |= r.dragged();
            *rect = r.rect;
        }
        (dragging, rects)
    })
    .inner
}

/// How a field shows `value` with `decimals`, as egui would, except that a
/// value that rounds to zero shows `0.000`, never `-0.000`.
fn shown(value: f64, decimals: std::ops::RangeInclusive<usize>) -> String {
    let text = egui::emath::format_with_decimals_in_range(value, decimals);
    match text.strip_prefix('-') {
        Some(unsigned) if unsigned.chars().all(|c| c == '0' || c == '.') => unsigned.to_owned(),
        _ => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn copy_as_ron_puts_the_camera_block_on_the_clipboard() {
        let ctx = egui::Context::default();
        let mut panel = CameraPanel::new(&camera(Projection::Orthographic));
        let mut output = ctx.run_ui(egui::RawInput::default(), |ui| panel.copy_as_ron(ui.ctx()));
        output.textures_delta.clear();
        let copied: Vec<_> = output
            .platform_output
            .commands
            .iter()
            .filter_map(|c| match c {
                egui::OutputCommand::CopyText(text) => Some(text.as_str()),
                _ => None,
            })
            .collect();
        let expected = "camera: (position: (0, 1, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), \
                        fov_y: 45, near: 1, projection: Orthographic),";
        assert_eq!(copied, [expected]);
    }

    #[test]
    fn a_value_that_rounds_to_zero_shows_no_minus_sign() {
        assert_eq!(shown(-0.0001, 0..=DECIMALS), "0.000");
        assert_eq!(shown(-0.0, 0..=DECIMALS), "0");
        assert_eq!(shown(-0.25, 0..=DECIMALS), "-0.25");
        assert_eq!(shown(-3.0, 0..=DECIMALS), "-3");
    }

    fn camera(projection: Projection) -> Camera {
        Camera::new(Vec3::new(0.0, 1.0, -5.0), Vec3::ZERO, Vec3::Y, 45.0, 1.0, projection).unwrap()
    }

    #[test]
    fn opening_another_scene_takes_its_camera_and_projection() {
        let mut panel = CameraPanel::new(&camera(Projection::Perspective));
        panel.edit(|s| s.orbit(0.3, 0.1));
        let ortho =
            Camera::new(Vec3::new(-4.0, 3.0, -6.0), Vec3::ZERO, Vec3::Y, 30.0, 1.0, Projection::Orthographic)
                .unwrap();
        panel.scene_loaded(&ortho, true);
        assert_eq!(*panel.settings(), CameraSettings::from_camera(&ortho));
    }

    #[test]
    fn the_lens_controls_edit_the_camera_and_undo_takes_an_aperture_change_back() {
        let ctx = egui::Context::default();
        let mut panel = CameraPanel::new(&camera(Projection::Perspective));
        let run = |panel: &mut CameraPanel, events: Vec<egui::Event>| {
            let input = egui::RawInput { events, ..Default::default() };
            let mut output = ctx.run_ui(input, |ui| {
                egui::CentralPanel::default().show(ui, |ui| panel.ui(ui, None, None));
                panel.end_frame(ui.ctx());
            });
            output.textures_delta.clear();
        };
        run(&mut panel, vec![]);
        assert_eq!(panel.settings().to_camera().unwrap().lens().radius, 0.0, "a pinhole at first");
        assert!(panel.edit(|s| CameraSettings { aperture: 0.2, focus_distance: 3.0, ..s }));
        run(&mut panel, vec![]);
        let lens = panel.settings().to_camera().unwrap().lens();
        assert_eq!((lens.radius, lens.focus_distance), (0.2, 3.0), "the render's camera has the lens");
        assert!(panel.undo());
        assert_eq!(panel.settings().aperture, 0.0, "undo: the pinhole again");
        assert!(panel.redo());
        assert_eq!(panel.settings().aperture, 0.2);
    }

    #[test]
    fn a_reload_keeps_the_users_camera_unless_the_file_changed_it() {
        let file = camera(Projection::Perspective);
        let mut panel = CameraPanel::new(&file);
        panel.edit(|s| s.orbit(0.3, 0.1));
        let edited = *panel.settings();
        panel.scene_loaded(&file, false);
        assert_eq!(*panel.settings(), edited);
        let moved =
            Camera::new(Vec3::new(0.0, 2.0, -5.0), Vec3::ZERO, Vec3::Y, 45.0, 1.0, Projection::Perspective)
                .unwrap();
        panel.scene_loaded(&moved, false);
        assert_eq!(*panel.settings(), CameraSettings::from_camera(&moved));
    }

    #[test]
    fn the_refused_edit_notice_clears_on_reset_on_the_next_good_edit_and_on_a_new_scene() {
        let mut panel = CameraPanel::new(&camera(Projection::Perspective));
        let degenerate = |s: CameraSettings| CameraSettings { center_of_interest: s.position, ..s };
        assert!(!panel.edit(degenerate));
        assert!(panel.refused());
        panel.reset();
        assert!(!panel.refused());
        panel.edit(degenerate);
        assert!(panel.edit(|s| s.orbit(0.1, 0.0)));
        assert!(!panel.refused());
        panel.edit(degenerate);
        panel.scene_loaded(&camera(Projection::Perspective), false);
        assert!(!panel.refused());
    }
}
