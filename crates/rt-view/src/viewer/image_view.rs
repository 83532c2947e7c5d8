//! The image on screen, fitted to the central panel, and the mouse on it:
//! drag to orbit, shift-, right- or middle-drag to pan, wheel to zoom.

use egui::{Color32, PointerButton, Rect, Sense, TextureHandle, Vec2, pos2};
use rt_core::Real;

use super::camera_panel::CameraPanel;
use super::interaction::Interaction;

/// Radians of orbit per point of mouse movement.
const ORBIT_PER_POINT: f32 = 0.01;
/// Zoom factor exponent per point of scrolling: `exp(−scroll·k)`.
const ZOOM_PER_POINT: f32 = 0.0015;

/// Draws `texture` (an image of `size` pixels, full resolution) as large as
/// fits, keeping its proportions, and turns mouse input on it into camera edits.
#[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
pub(super) fn image_ui(
    ui: &mut egui::Ui,
    texture: Option<&TextureHandle>,
    (w, h): (u32, u32),
    camera: &mut CameraPanel,
) -> Interaction {
    let available = ui.available_rect_before_wrap();
    let fit = (available.width() / w as f32).min(available.height() / h as f32).max(0.01);
    let rect = Rect::from_center_size(available.center(), Vec2::new(w as f32 * fit, h as f32 * fit));
    let response = ui.allocate_rect(rect, Sense::click_and_drag());
    if let Some(texture) = texture {
        let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0));
        ui.painter().image(texture.id(), rect, uv, Color32::WHITE);
    }
    let delta = response.drag_delta();
    let shift = ui.input(|i| i.modifiers.shift);
    let panning = response.dragged_by(PointerButton::Secondary)
        || response.dragged_by(PointerButton::Middle)
        || (shift && response.dragged_by(PointerButton::Primary));
    let mut changed = false;
    if panning {
        changed |= camera.edit(|s| {
            let k = s.world_per_pixel(rect.height() as Real) as f32;
            s.pan((-delta.x * k) as Real, (delta.y * k) as Real)
        });
    } else if response.dragged_by(PointerButton::Primary) {
        changed |= camera
            .edit(|s| s.orbit((-delta.x * ORBIT_PER_POINT) as Real, (-delta.y * ORBIT_PER_POINT) as Real));
    }
    let scroll = if response.hovered() { ui.input(|i| i.smooth_scroll_delta.y) } else { 0.0 };
    if scroll != 0.0 {
        changed |= camera.edit(|s| s.zoom((-scroll * ZOOM_PER_POINT).exp() as Real));
    }
    Interaction { changed, dragging: response.dragged() || scroll != 0.0 }
}
