//! The image on screen and the mouse on it.
//!
//! The image is shown fitted to the panel, at 1:1 (one image pixel per
//! screen pixel), or at any zoom, independent of the camera; magnified, it
//! is drawn nearest-neighbour so pixels stay square. The mouse:
//!
//! | input | does |
//! |---|---|
//! | drag | orbit the camera (fly navigation: turn the view) |
//! | shift-drag, right- or middle-drag | pan the camera |
//! | wheel | zoom the camera |
//! | ctrl + wheel | zoom the image about the cursor |
//! | ctrl + drag | pan the image |
//! | hover | inspect the pixel under the cursor |
//! | click | pin the inspection to that pixel (Esc unpins) |
//! | drag, with the region tool on (B) | choose a region to render |
//! | drag the split line | move it (A/B view: render left, reference right) |
//!
//! The zoom is shown in a strip above the image, never over it.
//!
//! A drag counts as moving only in frames where the pointer moved: holding
//! the button still lets the full-resolution render start.

use egui::{Align2, Color32, FontId, PointerButton, Pos2, Rect, Sense, TextureHandle, Vec2, pos2};
use rt_core::Real;

use super::camera_panel::CameraPanel;
use super::fly;
use super::interaction::Interaction;
use super::region::Region;

/// Radians of orbit per point of mouse movement.
const ORBIT_PER_POINT: f32 = 0.01;
/// Zoom factor exponent per point of scrolling: `exp(−scroll·k)`.
const ZOOM_PER_POINT: f32 = 0.0015;
/// The image zoom's limits, in screen points per image pixel.
const SCALE_RANGE: (f32, f32) = (0.02, 64.0);
/// Height of the strip above the image that shows the zoom, in points.
const LABEL_STRIP: f32 = 18.0;
/// Half the width of the split line's handle, in points.
const SPLIT_GRAB: f32 = 5.0;

/// How the image is scaled on screen.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) enum Zoom {
    /// As large as fits, whole.
    #[default]
    Fit,
    /// `scale` screen points per image pixel, the image point `center` in
    /// the middle of the panel.
    Scale { scale: f32, center: Pos2 },
}

/// The image view's state: zoom, the inspected pixel, the region tool and
/// the A/B split.
pub(super) struct ImageView {
    zoom: Zoom,
    /// The pixel clicked, inspected until Esc.
    pinned: Option<[u32; 2]>,
    /// The region tool: a primary drag chooses a region instead of orbiting.
    region_tool: bool,
    /// Where the region drag started, in image pixels.
    region_from: Option<Pos2>,
    /// A region dragged out, in image pixels, not yet taken.
    dragged_region: Option<[[f32; 2]; 2]>,
    /// The region rendered on the image, outlined.
    outline: Option<Region>,
    /// The reference shown right of the split line, if the A/B view is on.
    reference: Option<TextureHandle>,
    /// Where the split line is, as a fraction of the image's width.
    split: f32,
}

impl Default for ImageView {
    fn default() -> Self {
        Self {
            zoom: Zoom::Fit,
            pinned: None,
            region_tool: false,
            region_from: None,
            dragged_region: None,
            outline: None,
            reference: None,
            split: 0.5,
        }
    }
}

impl ImageView {
    /// Shows the whole image as large as fits.
    pub fn fit(&mut self) {
        self.zoom = Zoom::Fit;
    }

    /// Shows the image at one image pixel per screen pixel, centred.
    pub fn one_to_one(&mut self, pixels_per_point: f32, (w, h): (u32, u32)) {
        let center = pos2(w as f32 / 2.0, h as f32 / 2.0);
        self.zoom = Zoom::Scale { scale: 1.0 / pixels_per_point, center };
    }

    /// Shows `reference` right of the split line (the render left of it),
    /// or the render alone for `None`.
    pub fn set_reference(&mut self, reference: Option<TextureHandle>) {
        self.reference = reference;
    }

    /// Whether a reference is shown right of the split line.
    #[cfg(test)]
    pub fn has_reference(&self) -> bool {
        self.reference.is_some()
    }

    /// Where the split line is, as a fraction of the image's width.
    #[cfg(test)]
    pub fn split(&self) -> f32 {
        self.split
    }

    /// Forgets the pinned pixel.
    pub fn unpin(&mut self) {
        self.pinned = None;
    }

    /// The pinned pixel, if any.
    pub fn pinned(&self) -> Option<[u32; 2]> {
        self.pinned
    }

    /// Pins the inspection to `pixel`.
    pub fn pin(&mut self, pixel: [u32; 2]) {
        self.pinned = Some(pixel);
    }

    /// Turns the region tool on or off: while on, a drag on the image
    /// chooses a region to render (and turns the tool off) instead of
    /// orbiting the camera.
    pub fn toggle_region_tool(&mut self) {
        self.region_tool = !self.region_tool;
        self.region_from = None;
    }

    /// Whether the region tool is on.
    pub fn region_tool(&self) -> bool {
        self.region_tool
    }

    /// The corners of a region dragged out since the last call, in image
    /// pixels (fractions, any order), if one was.
    pub fn take_dragged_region(&mut self) -> Option<[[f32; 2]; 2]> {
        self.dragged_region.take()
    }

    /// Outlines `region` on the image (`None`: no outline).
    pub fn outline_region(&mut self, region: Option<Region>) {
        self.outline = region;
    }

    /// The zoom in force.
    #[cfg(test)]
    pub fn zoom(&self) -> Zoom {
        self.zoom
    }

    /// Draws `texture` (an image of `size` pixels at full resolution) and
    /// turns mouse input on it into camera edits, image zoom and pan, and
    /// inspection. `inspect` describes a pixel. Returns the interaction and
    /// whether the image is magnified (drawn larger than its pixels).
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        texture: Option<&TextureHandle>,
        (w, h): (u32, u32),
        camera: &mut CameraPanel,
        inspect: impl FnOnce([u32; 2]) -> String,
    ) -> (Interaction, bool) {
        let whole = ui.available_rect_before_wrap();
        let (strip, available) = whole.split_top_bottom_at_y(whole.top() + LABEL_STRIP);
        let response = ui.allocate_rect(available, Sense::click_and_drag());
        let size = Vec2::new(w as f32, h as f32);
        let (scale, center) = match self.zoom {
            Zoom::Fit => {
                let fit = (available.width() / size.x).min(available.height() / size.y).max(1e-3);
                (fit, pos2(size.x / 2.0, size.y / 2.0))
            }
            Zoom::Scale { scale, center } => (scale, center),
        };
        let rect = Rect::from_min_size(available.center() - center.to_vec2() * scale, size * scale);
        let painter = ui.painter_at(available);
        let split = self.reference.as_ref().map(|_| rect.left() + rect.width() * self.split);
        if let Some(texture) = texture {
            let right = split.unwrap_or(rect.right());
            let part = Rect::from_x_y_ranges(rect.left()..=right, rect.y_range());
            let uv = Rect::from_min_max(pos2(0.0, 0.0), pos2(self.split_or_whole(), 1.0));
            painter.image(texture.id(), part, uv, Color32::WHITE);
        }
        if let (Some(reference), Some(x)) = (&self.reference, split) {
            let part = Rect::from_x_y_ranges(x..=rect.right(), rect.y_range());
            let uv = Rect::from_min_max(pos2(self.split, 0.0), pos2(1.0, 1.0));
            painter.image(reference.id(), part, uv, Color32::WHITE);
            let top = rect.top().max(available.top());
            let bottom = rect.bottom().min(available.bottom());
            painter.line_segment([pos2(x, top), pos2(x, bottom)], (1.5, Color32::WHITE));
            // The handle: dragging it moves the line, never the camera.
            let handle = Rect::from_x_y_ranges(x - SPLIT_GRAB..=x + SPLIT_GRAB, top..=bottom);
            let grab = ui.interact(handle, ui.make_persistent_id("split line"), Sense::drag());
            if grab.hovered() || grab.dragged() {
                ui.ctx().set_cursor_icon(egui::CursorIcon::ResizeHorizontal);
            }
            if grab.dragged()
                && let Some(p) = grab.interact_pointer_pos()
            {
                self.split = ((p.x - rect.left()) / rect.width()).clamp(0.0, 1.0);
            }
            painter.text(
                pos2(x - 6.0, top + 4.0),
                Align2::RIGHT_TOP,
                "render",
                FontId::proportional(12.0),
                Color32::WHITE,
            );
            painter.text(
                pos2(x + 6.0, top + 4.0),
                Align2::LEFT_TOP,
                "reference",
                FontId::proportional(12.0),
                Color32::WHITE,
            );
        }
        let to_pixel = |p: Pos2| {
            let q = (p - rect.min) / scale;
            (q.x >= 0.0 && q.y >= 0.0 && q.x < size.x && q.y < size.y).then_some([q.x as u32, q.y as u32])
        };

        let (ctrl, shift) = ui.input(|i| (i.modifiers.command, i.modifiers.shift));
        let delta = response.drag_delta();
        let mut changed = false;
        let image_point = |p: Pos2| (p - rect.min) / scale;
        if self.region_tool && !ctrl && response.dragged_by(PointerButton::Primary) {
            // Choose a region: the rectangle from the press to the pointer.
            let origin = ui.input(|i| i.pointer.press_origin());
            if self.region_from.is_none() {
                self.region_from = origin.map(|p| image_point(p).to_pos2());
            }
            if let (Some(from), Some(to)) = (self.region_from, response.interact_pointer_pos()) {
                let corners = Rect::from_two_pos(rect.min + from.to_vec2() * scale, to);
                painter.rect_stroke(corners, 0.0, (1.5, Color32::YELLOW), egui::StrokeKind::Middle);
            }
        } else if ctrl && response.dragged_by(PointerButton::Primary) {
            // Pan the image: the point under the cursor follows it.
            self.zoom = Zoom::Scale { scale, center: center - delta / scale };
        } else if response.dragged_by(PointerButton::Secondary)
            || response.dragged_by(PointerButton::Middle)
            || (shift && response.dragged_by(PointerButton::Primary))
        {
            changed |= camera.edit(|s| {
                let k = s.world_per_pixel(rect.height() as Real) as f32;
                s.pan((-delta.x * k) as Real, (delta.y * k) as Real)
            });
        } else if response.dragged_by(PointerButton::Primary) && camera.flying() {
            // Fly: the view turns the way the mouse moves.
            let look = |d: f32| (d * fly::LOOK_PER_POINT) as Real;
            changed |= camera.edit(|s| fly::look(&s, look(delta.x), look(-delta.y)));
        } else if response.dragged_by(PointerButton::Primary) {
            changed |= camera.edit(|s| {
                s.orbit((-delta.x * ORBIT_PER_POINT) as Real, (-delta.y * ORBIT_PER_POINT) as Real)
            });
        }
        let hovered = response.hovered();
        let scroll = if hovered { ui.input(|i| i.smooth_scroll_delta.y) } else { 0.0 };
        // Ctrl+wheel (and a pinch) reach egui as a zoom factor, not as
        // scrolling: it zooms the image, never the camera.
        let mut factor = if hovered { ui.input(|i| i.zoom_delta()) } else { 1.0 };
        if scroll != 0.0 {
            if ctrl {
                factor *= (scroll * 0.003).exp();
            } else {
                changed |= camera.edit(|s| s.zoom((-scroll * ZOOM_PER_POINT).exp() as Real));
            }
        }
        if factor != 1.0 {
            let cursor = response.hover_pos().unwrap_or(available.center());
            self.zoom = zoom_about(scale, center, cursor - available.center(), factor);
        }
        if response.drag_stopped()
            && let Some(from) = self.region_from.take()
            && let Some(to) = response.interact_pointer_pos()
        {
            let to = image_point(to);
            self.dragged_region = Some([[from.x, from.y], [to.x, to.y]]);
            self.region_tool = false;
        }
        if let Some(r) = &self.outline {
            let corner = |x: u32, y: u32| rect.min + Vec2::new(x as f32, y as f32) * scale;
            let outline =
                Rect::from_min_max(corner(r.columns.start, r.rows.start), corner(r.columns.end, r.rows.end));
            painter.rect_stroke(
                outline,
                0.0,
                (1.0, Color32::from_rgb(255, 200, 0)),
                egui::StrokeKind::Outside,
            );
        }
        if response.clicked() {
            self.pinned = response.interact_pointer_pos().and_then(to_pixel);
        }
        if ui.input(|i| i.key_pressed(egui::Key::Escape)) {
            self.pinned = None;
        }
        let inspected = self.pinned.or_else(|| response.hover_pos().and_then(to_pixel));
        if let Some(pixel) = inspected {
            let text = inspect(pixel);
            let galley = painter.layout_no_wrap(text, FontId::monospace(12.0), Color32::WHITE);
            let at = available.left_bottom() + Vec2::new(8.0, -8.0 - galley.size().y);
            let frame = Rect::from_min_size(at, galley.size()).expand(4.0);
            painter.rect_filled(frame, 4.0, Color32::from_black_alpha(190));
            painter.galley(at, galley, Color32::WHITE);
            if let Some([x, y]) = self.pinned {
                let marker = rect.min + Vec2::new(x as f32 + 0.5, y as f32 + 0.5) * scale;
                painter.circle_stroke(marker, (scale * 0.5).max(4.0), (1.5, Color32::YELLOW));
            }
        }
        let zoom_text = format!("{:.0} %", scale * ui.ctx().pixels_per_point() * 100.0);
        ui.painter_at(strip).text(
            strip.right_center() + Vec2::new(-8.0, 0.0),
            Align2::RIGHT_CENTER,
            zoom_text,
            FontId::proportional(12.0),
            Color32::from_white_alpha(160),
        );
        let moving = delta != Vec2::ZERO || scroll != 0.0;
        let magnified = scale * ui.ctx().pixels_per_point() > 1.0;
        (interaction(changed, response.dragged(), moving), magnified)
    }
}

impl ImageView {
    /// How far across the image the render is shown: to the split line in
    /// the A/B view, else all of it.
    fn split_or_whole(&self) -> f32 {
        if self.reference.is_some() { self.split } else { 1.0 }
    }
}

/// The image zoomed by `factor` about the cursor, `offset` from the view's
/// centre: the image point under the cursor stays under it. The image is
/// drawn at `scale` screen points per pixel with image point `center` at the
/// view's centre; the new scale is kept within [`SCALE_RANGE`].
fn zoom_about(scale: f32, center: Pos2, offset: Vec2, factor: f32) -> Zoom {
    let new_scale = (scale * factor).clamp(SCALE_RANGE.0, SCALE_RANGE.1);
    let under = center + offset / scale;
    Zoom::Scale { scale: new_scale, center: under - offset / new_scale }
}

/// What a frame of mouse input did: a new render is due if the camera
/// `changed`; a preview is wanted only while the pointer is `dragged` and
/// actually `moving` (held still, the full render may start).
pub(super) fn interaction(changed: bool, dragged: bool, moving: bool) -> Interaction {
    Interaction { changed, dragging: dragged && moving }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holding_the_button_still_is_not_dragging() {
        // Before, any frame with the button down counted as dragging, so the
        // full-resolution render waited for the button's release.
        assert_eq!(interaction(false, true, false), Interaction { changed: false, dragging: false });
        assert_eq!(interaction(true, true, true), Interaction { changed: true, dragging: true });
        assert_eq!(interaction(false, false, true), Interaction { changed: false, dragging: false });
    }

    #[test]
    fn zooming_about_the_cursor_keeps_the_image_point_under_it() {
        let offset = Vec2::new(120.0, -40.0);
        let Zoom::Scale { scale, center } = zoom_about(0.5, pos2(320.0, 240.0), offset, 4.0) else {
            panic!()
        };
        assert_eq!(scale, 2.0);
        // The image point under the cursor, before and after.
        assert_eq!(pos2(320.0, 240.0) + offset / 0.5, center + offset / scale);
        let Zoom::Scale { scale, .. } = zoom_about(SCALE_RANGE.1, pos2(0.0, 0.0), offset, 10.0) else {
            panic!()
        };
        assert_eq!(scale, SCALE_RANGE.1);
    }

    /// The image view's zoom and the camera's position after a few frames
    /// of `events` (sent in the first, with `modifiers` held), the pointer
    /// over the middle of a 640×480 view.
    fn after_events(events: Vec<egui::Event>, modifiers: egui::Modifiers) -> (Zoom, rt_core::Vec3) {
        let ctx = egui::Context::default();
        let camera = rt_core::Camera::new(
            rt_core::Vec3::new(0.0, 0.0, -5.0),
            rt_core::Vec3::ZERO,
            rt_core::Vec3::Y,
            40.0,
            1.0,
            rt_core::Projection::Perspective,
        )
        .unwrap();
        let mut panel = CameraPanel::new(&camera);
        let mut view = ImageView::default();
        let screen = Rect::from_min_size(pos2(0.0, 0.0), Vec2::new(640.0, 480.0));
        let mut frame = |events: Vec<egui::Event>| {
            let input = egui::RawInput { screen_rect: Some(screen), events, ..Default::default() };
            let mut output = ctx.run_ui(input, |ui| {
                view.ui(ui, None, (640, 480), &mut panel, |_| String::new());
            });
            output.textures_delta.clear();
            ctx.tex_manager().write().take_delta().clear();
        };
        frame(vec![egui::Event::ModifiersChanged(modifiers), egui::Event::PointerMoved(pos2(320.0, 240.0))]);
        frame(events);
        // The wheel is smoothed over a few frames.
        for _ in 0..30 {
            frame(Vec::new());
        }
        (view.zoom(), panel.settings().position)
    }

    #[test]
    fn ctrl_wheel_and_a_pinch_zoom_the_image_and_the_wheel_zooms_the_camera() {
        let position = after_events(Vec::new(), egui::Modifiers::NONE).1;
        let wheel = |modifiers| egui::Event::MouseWheel {
            unit: egui::MouseWheelUnit::Point,
            delta: Vec2::new(0.0, 60.0),
            modifiers,
            phase: egui::TouchPhase::Move,
            source: egui::MouseWheelSource::Wheel,
        };
        // Ctrl+wheel: egui turns it into a zoom factor; the image is
        // magnified, the camera stays.
        let (zoom, moved) = after_events(vec![wheel(egui::Modifiers::COMMAND)], egui::Modifiers::COMMAND);
        assert!(matches!(zoom, Zoom::Scale { scale, .. } if scale > 1.0), "{zoom:?}");
        assert_eq!(moved, position);
        // A pinch (a zoom event) does the same.
        let (zoom, moved) = after_events(vec![egui::Event::Zoom(1.5)], egui::Modifiers::NONE);
        assert!(matches!(zoom, Zoom::Scale { scale, .. } if scale > 1.0), "{zoom:?}");
        assert_eq!(moved, position);
        // The plain wheel moves the camera, not the image.
        let (zoom, moved) = after_events(vec![wheel(egui::Modifiers::NONE)], egui::Modifiers::NONE);
        assert_eq!(zoom, Zoom::Fit);
        assert_ne!(moved, position);
    }

    /// A 640×480 window showing a 640×480 image fitted, its render a red
    /// texture and, with `split`, a blue reference right of the split line.
    struct Window {
        ctx: egui::Context,
        view: ImageView,
        panel: CameraPanel,
        render: TextureHandle,
        reference: TextureHandle,
    }

    impl Window {
        fn new(split: bool) -> Self {
            let ctx = egui::Context::default();
            let image = |c| egui::ColorImage::new([64, 48], vec![c; 64 * 48]);
            let render = ctx.load_texture("render", image(Color32::RED), Default::default());
            let reference = ctx.load_texture("reference", image(Color32::BLUE), Default::default());
            let camera = rt_core::Camera::new(
                rt_core::Vec3::new(0.0, 0.0, -5.0),
                rt_core::Vec3::ZERO,
                rt_core::Vec3::Y,
                40.0,
                1.0,
                rt_core::Projection::Perspective,
            )
            .unwrap();
            let mut view = ImageView::default();
            if split {
                view.set_reference(Some(reference.clone()));
            }
            Self { ctx, view, panel: CameraPanel::new(&camera), render, reference }
        }

        /// One frame with `events`: what was drawn.
        fn frame(&mut self, events: Vec<egui::Event>) -> egui::FullOutput {
            let screen = Rect::from_min_size(pos2(0.0, 0.0), Vec2::new(640.0, 480.0));
            let input = egui::RawInput { screen_rect: Some(screen), events, ..Default::default() };
            let (view, panel, render) = (&mut self.view, &mut self.panel, &self.render);
            let mut output = self.ctx.run_ui(input, |ui| {
                view.ui(ui, Some(render), (640, 480), panel, |_| String::new());
            });
            output.textures_delta.clear();
            self.ctx.tex_manager().write().take_delta().clear();
            output
        }

        /// The screen x range covered by `texture` in `output`, if drawn.
        fn x_range(&self, output: &egui::FullOutput, texture: &TextureHandle) -> Option<(f32, f32)> {
            let primitives = self.ctx.tessellate(output.shapes.clone(), output.pixels_per_point);
            let xs: Vec<f32> = primitives
                .iter()
                .filter_map(|p| match &p.primitive {
                    egui::epaint::Primitive::Mesh(m) if m.texture_id == texture.id() => Some(m),
                    _ => None,
                })
                .flat_map(|m| m.vertices.iter().map(|v| v.pos.x))
                .collect();
            let min = xs.iter().copied().reduce(f32::min)?;
            Some((min, xs.iter().copied().reduce(f32::max)?))
        }
    }

    impl Drop for Window {
        fn drop(&mut self) {
            self.ctx.tex_manager().write().take_delta().clear();
        }
    }

    #[test]
    fn the_split_view_shows_the_render_left_of_the_line_and_the_reference_right() {
        let mut w = Window::new(true);
        w.frame(Vec::new());
        let output = w.frame(Vec::new());
        let (render, reference) = (w.x_range(&output, &w.render), w.x_range(&output, &w.reference));
        let ((r0, r1), (f0, f1)) = (render.expect("render drawn"), reference.expect("reference drawn"));
        // Fitted below the zoom strip: 616 points wide from x = 12; the line at its middle.
        assert!((r1 - 320.0).abs() <= 1.0 && (f0 - 320.0).abs() <= 1.0, "{render:?} {reference:?}");
        assert!(r0 < 20.0 && f1 > 620.0, "{render:?} {reference:?}");

        // Dragging the line moves it (and not the camera) ...
        let position = w.panel.settings().position;
        let at = |x| pos2(x, 240.0);
        let button = |x, pressed| egui::Event::PointerButton {
            pos: at(x),
            button: PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        };
        w.frame(vec![egui::Event::PointerMoved(at(320.0))]);
        w.frame(vec![button(320.0, true)]);
        w.frame(vec![egui::Event::PointerMoved(at(420.0))]);
        w.frame(vec![egui::Event::PointerMoved(at(474.0))]);
        w.frame(vec![button(474.0, false)]);
        assert!((w.view.split() - 0.75).abs() < 0.01, "{}", w.view.split());
        assert_eq!(w.panel.settings().position, position, "the drag orbited the camera");
        let output = w.frame(Vec::new());
        let (_, r1) = w.x_range(&output, &w.render).unwrap();
        assert!((r1 - 474.0).abs() <= 1.0, "{r1}");

        // ... and without a reference the render fills the image.
        let mut alone = Window::new(false);
        let output = alone.frame(Vec::new());
        assert!(alone.x_range(&output, &alone.reference).is_none());
        let (r0, r1) = alone.x_range(&output, &alone.render).unwrap();
        assert!(r0 < 20.0 && r1 > 620.0, "{r0} {r1}");
    }

    #[test]
    fn the_zoom_label_never_covers_the_image() {
        // Before, "100 %" was drawn in the image's top right corner.
        let mut w = Window::new(false);
        let output = w.frame(Vec::new());
        let (x0, x1) = w.x_range(&output, &w.render).unwrap();
        let primitives = w.ctx.tessellate(output.shapes.clone(), output.pixels_per_point);
        let image_clip = primitives
            .iter()
            .find(
                |p| matches!(&p.primitive, egui::epaint::Primitive::Mesh(m) if m.texture_id == w.render.id()),
            )
            .expect("the image")
            .clip_rect;
        let label = output
            .shapes
            .iter()
            .find_map(|s| match &s.shape {
                egui::Shape::Text(t) if t.galley.text().ends_with(" %") => Some(t.visual_bounding_rect()),
                _ => None,
            })
            .expect("the zoom label");
        let image = Rect::from_x_y_ranges(x0..=x1, image_clip.y_range()).intersect(image_clip);
        assert!(!label.intersects(image), "label {label:?} over image {image:?}");
        assert!(label.right() > x1 - 100.0, "the label stays at the right: {label:?}");
    }

    #[test]
    fn one_to_one_shows_one_image_pixel_per_screen_pixel_and_fit_goes_back() {
        let mut v = ImageView::default();
        v.one_to_one(2.0, (640, 480));
        assert_eq!(v.zoom(), Zoom::Scale { scale: 0.5, center: pos2(320.0, 240.0) });
        v.fit();
        assert_eq!(v.zoom(), Zoom::Fit);
    }

    #[test]
    fn with_the_region_tool_a_drag_gives_a_region_and_leaves_the_camera() {
        let ctx = egui::Context::default();
        let camera = rt_core::Camera::new(
            rt_core::Vec3::new(0.0, 0.0, -5.0),
            rt_core::Vec3::ZERO,
            rt_core::Vec3::Y,
            40.0,
            1.0,
            rt_core::Projection::Perspective,
        )
        .unwrap();
        let mut panel = CameraPanel::new(&camera);
        let mut view = ImageView::default();
        view.toggle_region_tool();
        // The zoom strip above, then the image at one point per pixel.
        let screen = Rect::from_min_size(pos2(0.0, 0.0), Vec2::new(640.0, 480.0 + LABEL_STRIP));
        let mut frame = |view: &mut ImageView, events: Vec<egui::Event>| {
            let input = egui::RawInput { screen_rect: Some(screen), events, ..Default::default() };
            let mut output = ctx.run_ui(input, |ui| {
                view.ui(ui, None, (640, 480), &mut panel, |_| String::new());
            });
            output.textures_delta.clear();
            ctx.tex_manager().write().take_delta().clear();
        };
        let button = |pos, pressed| egui::Event::PointerButton {
            pos,
            button: PointerButton::Primary,
            pressed,
            modifiers: egui::Modifiers::NONE,
        };
        let (from, to) = (pos2(100.0, 120.0 + LABEL_STRIP), pos2(260.0, 200.0 + LABEL_STRIP));
        frame(&mut view, vec![egui::Event::PointerMoved(from)]);
        frame(&mut view, vec![button(from, true)]);
        for k in 1..=4 {
            frame(&mut view, vec![egui::Event::PointerMoved(from + (to - from) * k as f32 / 4.0)]);
        }
        frame(&mut view, vec![button(to, false)]);
        frame(&mut view, vec![]);
        let corners = view.take_dragged_region().expect("a region");
        let region = Region::spanning(corners[0], corners[1], 640, 480).unwrap();
        assert_eq!(region, Region { columns: 100..260, rows: 120..200 });
        assert!(!view.region_tool(), "the tool is used once");
        assert_eq!(panel.settings().position, camera.position(), "the camera orbited");
        assert_eq!(view.take_dragged_region(), None);
    }
}
