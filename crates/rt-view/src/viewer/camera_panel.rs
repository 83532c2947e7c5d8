//! The camera section of the side panel: field of view (or, orthographic,
//! the view's height in world units), near, position, look-at, projection
//! and Reset, over the pure functions of [`super::camera_controls`].
//!
//! The panel owns the viewer's camera: the image view's orbit, pan and zoom
//! edit it through [`CameraPanel::edit`], and a newly loaded scene replaces
//! it through [`CameraPanel::scene_loaded`]. Every edit is checked by
//! [`CameraSettings::accept`], so the camera is always valid.

use rt_core::{Camera, Projection, Real, Vec3};

use super::camera_controls::{CameraSettings, FOV_RANGE, NEAR_RANGE};
use super::interaction::Interaction;

/// Decimals of every length and angle shown in the panel.
const DECIMALS: usize = 3;

/// The viewer's camera and the scene file's, for Reset.
pub(super) struct CameraPanel {
    settings: CameraSettings,
    /// The camera as the scene file gave it.
    file_camera: Camera,
    /// Set when the last edit was refused; cleared by the next accepted one,
    /// Reset, or a new scene.
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

    /// The scene file's camera, as settings.
    pub fn file_settings(&self) -> CameraSettings {
        CameraSettings::from_camera(&self.file_camera)
    }

    /// Starts from `view` (a remembered camera) instead of the file's, if it
    /// is a valid camera (fov and near brought into the controls' ranges).
    pub fn restore(&mut self, view: CameraSettings) {
        self.settings = self.settings.accept(view);
    }

    /// Back to the scene file's camera; returns whether that changed it.
    pub fn reset(&mut self) -> bool {
        self.refused = false;
        let file = CameraSettings::from_camera(&self.file_camera);
        let changed = file != self.settings;
        self.settings = file;
        changed
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

    /// The camera controls.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> Interaction {
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
                                .max_decimals(DECIMALS),
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
            ui.label("position");
            dragging |= vector_ui(ui, &mut s.position);
            ui.end_row();
            ui.label("look at");
            dragging |= vector_ui(ui, &mut s.center_of_interest);
            ui.end_row();
        });
        let mut projection = s.projection;
        ui.horizontal(|ui| {
            ui.radio_value(&mut projection, Projection::Perspective, "perspective");
            ui.radio_value(&mut projection, Projection::Orthographic, "orthographic");
        });
        // What is in view at the centre of interest stays in view.
        s = s.with_projection(projection);
        let mut changed = false;
        if ui.button("Reset camera").on_hover_text("Back to the scene file's camera (R)").clicked() {
            changed |= self.reset();
            s = self.settings;
        }
        changed |= self.edit(|_| s);
        if self.refused {
            ui.label("that edit would make the camera degenerate: kept the last valid one");
        }
        Interaction { changed, dragging }
    }
}

/// Three drag values in a row; returns whether one is being dragged.
fn vector_ui(ui: &mut egui::Ui, v: &mut Vec3) -> bool {
    ui.horizontal(|ui| {
        let speed = 0.01 * v.abs().max_element().max(1.0);
        let mut dragging = false;
        for axis in 0..3 {
            let value: &mut Real = &mut v[axis];
            let r = ui.add(egui::DragValue::new(value).speed(speed).max_decimals(DECIMALS));
            dragging |= r.dragged();
        }
        dragging
    })
    .inner
}

#[cfg(test)]
mod tests {
    use super::*;

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
