//! The camera section of the side panel: FOV, near, position, look-at,
//! projection and Reset, over the pure functions of [`super::camera_controls`].
//!
//! The panel owns the viewer's camera: the image view's orbit, pan and zoom
//! edit it through [`CameraPanel::edit`], and a newly loaded scene replaces
//! it through [`CameraPanel::scene_loaded`]. Every edit is checked by
//! [`CameraSettings::accept`], so the camera is always valid.

use rt_core::{Camera, Projection, Vec3};

use super::camera_controls::{CameraSettings, FOV_RANGE, NEAR_RANGE};
use super::interaction::Interaction;

/// The viewer's camera and the scene file's, for Reset.
pub(super) struct CameraPanel {
    settings: CameraSettings,
    /// The camera as the scene file gave it.
    file_camera: Camera,
    /// Set when the last edit was refused; cleared by the next accepted one.
    refused: bool,
}

impl CameraPanel {
    /// The panel for a scene seen by `camera`.
    pub fn new(camera: &Camera) -> Self {
        Self { settings: CameraSettings::from_camera(camera), file_camera: *camera, refused: false }
    }

    /// The camera settings in force (always a valid camera).
    pub fn settings(&self) -> &CameraSettings {
        &self.settings
    }

    /// A scene with `camera` was loaded: the view starts from it if `reset`
    /// (another file was opened) or if the file's camera changed; otherwise
    /// the user's edits are kept.
    pub fn scene_loaded(&mut self, camera: &Camera, reset: bool) {
        if reset || *camera != self.file_camera {
            self.settings = CameraSettings::from_camera(camera);
        }
        self.file_camera = *camera;
        self.refused = false;
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

    /// The camera controls.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> Interaction {
        let mut s = self.settings;
        let mut dragging = false;
        ui.heading("Camera");
        let r = ui.add(egui::Slider::new(&mut s.fov_y, FOV_RANGE).text("FOV y (°)"));
        dragging |= r.dragged();
        let r = ui.add(egui::Slider::new(&mut s.near, NEAR_RANGE).logarithmic(true).text("near"));
        dragging |= r.dragged();
        dragging |= vector_ui(ui, "position", &mut s.position);
        dragging |= vector_ui(ui, "look at", &mut s.center_of_interest);
        ui.horizontal(|ui| {
            ui.radio_value(&mut s.projection, Projection::Perspective, "perspective");
            ui.radio_value(&mut s.projection, Projection::Orthographic, "orthographic");
        });
        if ui.button("Reset camera").on_hover_text("Back to the scene file's camera").clicked() {
            s = CameraSettings::from_camera(&self.file_camera);
            self.refused = false;
        }
        let changed = self.edit(|_| s);
        if self.refused {
            ui.label("that edit would make the camera degenerate: kept the last valid one");
        }
        Interaction { changed, dragging }
    }
}

/// Three drag values in a row; returns whether one is being dragged.
fn vector_ui(ui: &mut egui::Ui, label: &str, v: &mut Vec3) -> bool {
    ui.horizontal(|ui| {
        ui.label(label);
        let speed = 0.01 * v.abs().max_element().max(1.0);
        let mut dragging = false;
        for axis in 0..3 {
            let r = ui.add(egui::DragValue::new(&mut v[axis]).speed(speed).max_decimals(3));
            dragging |= r.dragged();
        }
        dragging
    })
    .inner
}
