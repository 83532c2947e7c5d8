//! The render camera drawn in the scene view, the course's pictures of it:
//! its eye C, the axes CamX, CamY, CamZ (left-handed, `docs/conventions.md`)
//! in red, green and blue, the centre of interest and the general up
//! vector; the view plane at `near` with its width and height, its
//! upper-left corner O (pixel (0, 0)'s corner, the origin of the window's
//! pixels) and, once its pixels are large enough on screen, its pixel
//! grid; the frustum (perspective) or the parallel box (orthographic) out
//! to beyond the scene; and the lights. Every point goes through the
//! observer's [`Projection`], every corner comes from rt-core's
//! [`ViewPlane`], so what is drawn is the renderer's own camera math.

use egui::{Align2, Color32, FontId, Painter, Pos2, Stroke, vec2};
use rt_core::lights::light::LightKind;
use rt_core::{Projection as Kind, Real, Vec3, ViewPlane};

use super::projection::Projection;

/// CamX's colour.
pub const CAM_X: Color32 = Color32::from_rgb(235, 70, 60);
/// CamY's colour.
pub const CAM_Y: Color32 = Color32::from_rgb(90, 210, 90);
/// CamZ's colour.
pub const CAM_Z: Color32 = Color32::from_rgb(80, 140, 255);
/// The view plane's and the frustum's colour.
const PLANE: Color32 = Color32::from_rgb(240, 200, 80);
/// The lights' colour.
const LIGHT: Color32 = Color32::from_rgb(255, 240, 150);
/// Labels' size, points.
const LABEL: f32 = 12.0;
/// Pixel grid lines are drawn once a pixel is at least this many points
/// wide on screen.
const GRID_MIN_POINTS: f32 = 6.0;
/// The view plane's width and height are written on it once its top edge
/// is at least this many points long on screen.
const SIZE_LABELS_MIN_POINTS: f32 = 90.0;
/// No pixel grid for images with more lines than this (a grid that dense
/// is only ever seen partly; drawing all of it would cost frames).
const GRID_MAX_LINES: u32 = 1200;

/// What the course's camera pictures need: the render camera's view plane,
/// how far to draw the frustum (along cam_z from C), and the scene's lights.
pub struct CameraScene<'a> {
    /// The render camera's view plane at the image's size.
    pub view: &'a ViewPlane,
    /// Depth along cam_z to which the frustum is drawn.
    pub reach: Real,
    /// The lights.
    pub lights: &'a [rt_core::Light],
    /// Middle of the scene (where directional lights are drawn).
    pub middle: Vec3,
    /// A length that reads well in the scene (axes, arrows).
    pub unit: Real,
}

/// A line from `a` to `b` in 3D, clipped to what is in front of the observer.
pub fn line(painter: &Painter, p: &Projection, a: Vec3, b: Vec3, stroke: impl Into<Stroke>) {
    if let Some(s) = p.segment(a, b) {
        painter.line_segment(s, stroke);
    }
}

/// An arrow from `a` to `b` in 3D, its head drawn on screen.
pub fn arrow(painter: &Painter, p: &Projection, a: Vec3, b: Vec3, color: Color32) {
    let Some([sa, sb]) = p.segment(a, b) else { return };
    let stroke = Stroke::new(2.0, color);
    painter.line_segment([sa, sb], stroke);
    let along = sb - sa;
    if along.length() > 4.0 {
        let d = along.normalized() * 7.0;
        let side = vec2(-d.y, d.x) * 0.5;
        painter.line_segment([sb, sb - d + side], stroke);
        painter.line_segment([sb, sb - d - side], stroke);
    }
}

/// `text` at 3D point `at`, offset a little so it does not sit on the line.
pub fn label(painter: &Painter, p: &Projection, at: Vec3, text: &str, color: Color32) {
    if let Some(s) = p.point(at) {
        painter.text(s + vec2(4.0, -3.0), Align2::LEFT_BOTTOM, text, FontId::proportional(LABEL), color);
    }
}

/// A dot at 3D point `at`.
pub fn dot(painter: &Painter, p: &Projection, at: Vec3, radius: f32, color: Color32) -> Option<Pos2> {
    let s = p.point(at)?;
    painter.circle_filled(s, radius, color);
    Some(s)
}

/// Draws the render camera, its view plane, its frustum and the lights.
pub fn draw(painter: &Painter, p: &Projection, s: &CameraScene<'_>) {
    draw_frustum(painter, p, s);
    draw_view_plane(painter, p, s.view);
    draw_camera(painter, p, s);
    draw_lights(painter, p, s);
}

/// The view plane's corners, clockwise from the upper left: pixel corners
/// (0, 0), (W, 0), (W, H), (0, H).
pub fn plane_corners(view: &ViewPlane) -> [Vec3; 4] {
    let (w, h) = (view.width(), view.height());
    [
        view.point(0, 0, 0.0, 0.0),
        view.point(w, 0, 0.0, 0.0),
        view.point(w, h, 0.0, 0.0),
        view.point(0, h, 0.0, 0.0),
    ]
}

fn draw_camera(painter: &Painter, p: &Projection, s: &CameraScene<'_>) {
    let camera = s.view.camera();
    let (c, b) = (camera.position(), camera.basis());
    let axis = s.unit;
    for (dir, color, name) in [(b.x, CAM_X, "CamX"), (b.y, CAM_Y, "CamY"), (b.z, CAM_Z, "CamZ")] {
        arrow(painter, p, c, c + axis * dir, color);
        label(painter, p, c + axis * dir, name, color);
    }
    let up = camera.up().normalize_or_zero() * axis * 0.8;
    arrow(painter, p, c, c + up, Color32::from_gray(200));
    label(painter, p, c + up, "up", Color32::from_gray(200));
    let coi = camera.center_of_interest();
    line(painter, p, c, coi, Stroke::new(1.0, Color32::from_gray(150)));
    dot(painter, p, coi, 3.5, Color32::WHITE);
    label(painter, p, coi, "COI", Color32::WHITE);
    dot(painter, p, c, 4.5, Color32::WHITE);
    label(painter, p, c, "C", Color32::WHITE);
}

fn draw_view_plane(painter: &Painter, p: &Projection, view: &ViewPlane) {
    let corners = plane_corners(view);
    let on_screen: Option<Vec<Pos2>> = corners.iter().map(|&q| p.point(q)).collect();
    if let Some(points) = on_screen {
        painter.add(egui::Shape::convex_polygon(
            points,
            Color32::from_rgba_unmultiplied(240, 200, 80, 40),
            Stroke::NONE,
        ));
    }
    draw_grid(painter, p, view);
    for i in 0..4 {
        line(painter, p, corners[i], corners[(i + 1) % 4], Stroke::new(1.5, PLANE));
    }
    // The sizes are written once the plane is large enough on screen to hold them.
    let across = p.point(corners[0]).zip(p.point(corners[1])).map_or(0.0, |(a, b)| a.distance(b));
    if across >= SIZE_LABELS_MIN_POINTS {
        let (plane_w, plane_h) = view.size();
        let top = 0.5 * (corners[0] + corners[1]);
        label(painter, p, top, &format!("plane_w = {}", short(plane_w)), PLANE);
        let left = 0.5 * (corners[0] + corners[3]);
        label(painter, p, left, &format!("plane_h = {}", short(plane_h)), PLANE);
    }
    dot(painter, p, corners[0], 4.0, PLANE);
    label(painter, p, corners[0], "O (0,0)", PLANE);
}

/// The pixel grid, if a pixel is at least [`GRID_MIN_POINTS`] wide on screen.
fn draw_grid(painter: &Painter, p: &Projection, view: &ViewPlane) {
    let (w, h) = (view.width(), view.height());
    if w + h > GRID_MAX_LINES {
        return;
    }
    let (cx, cy) = (w / 2, h / 2);
    let size = |a: Vec3, b: Vec3| p.point(a).zip(p.point(b)).map(|(a, b)| a.distance(b));
    let pixel = size(view.point(cx, cy, 0.0, 0.0), view.point(cx + 1, cy, 0.0, 0.0))
        .zip(size(view.point(cx, cy, 0.0, 0.0), view.point(cx, cy + 1, 0.0, 0.0)))
        .map(|(a, b)| a.min(b));
    if pixel.is_none_or(|points| points < GRID_MIN_POINTS) {
        return;
    }
    let stroke = Stroke::new(0.5, Color32::from_rgba_unmultiplied(240, 200, 80, 110));
    for x in 1..w {
        line(painter, p, view.point(x, 0, 0.0, 0.0), view.point(x, h, 0.0, 0.0), stroke);
    }
    for y in 1..h {
        line(painter, p, view.point(0, y, 0.0, 0.0), view.point(w, y, 0.0, 0.0), stroke);
    }
}

fn draw_frustum(painter: &Painter, p: &Projection, s: &CameraScene<'_>) {
    let camera = s.view.camera();
    let (c, z, near) = (camera.position(), camera.basis().z, camera.near());
    let corners = plane_corners(s.view);
    let reach = s.reach.max(near * 1.5);
    let far: Vec<Vec3> = match camera.projection() {
        Kind::Perspective => corners.iter().map(|&q| c + (q - c) * (reach / near)).collect(),
        Kind::Orthographic => corners.iter().map(|&q| q + (reach - near) * z).collect(),
    };
    let edge = Stroke::new(1.0, PLANE.gamma_multiply(0.7));
    for i in 0..4 {
        match camera.projection() {
            Kind::Perspective => line(painter, p, c, far[i], edge),
            Kind::Orthographic => line(painter, p, corners[i], far[i], edge),
        }
        line(painter, p, far[i], far[(i + 1) % 4], Stroke::new(1.0, PLANE.gamma_multiply(0.4)));
    }
}

fn draw_lights(painter: &Painter, p: &Projection, s: &CameraScene<'_>) {
    for (i, light) in s.lights.iter().enumerate() {
        let name = format!("light {i}");
        match light.kind {
            LightKind::Point { position } => {
                star(painter, p, position);
                label(painter, p, position, &name, LIGHT);
            }
            LightKind::Spot { position, direction, .. } => {
                star(painter, p, position);
                arrow(painter, p, position, position + direction * s.unit, LIGHT);
                label(painter, p, position, &format!("{name} (spot)"), LIGHT);
            }
            LightKind::Directional { direction } => {
                let end = s.middle;
                let start = end - direction.normalize_or_zero() * s.unit * 1.5;
                arrow(painter, p, start, end, LIGHT);
                label(painter, p, start, &format!("{name} (directional)"), LIGHT);
            }
            LightKind::Sphere { center, radius, .. } => {
                if let (Some(a), Some(b)) =
                    (p.point(center), p.point(center + radius * p.view().camera().basis().x))
                {
                    painter.circle_stroke(a, a.distance(b).max(3.0), Stroke::new(1.5, LIGHT));
                }
                label(painter, p, center, &format!("{name} (sphere)"), LIGHT);
            }
        }
    }
}

/// A small eight-pointed star at a light's position.
fn star(painter: &Painter, p: &Projection, at: Vec3) {
    let Some(s) = p.point(at) else { return };
    let stroke = Stroke::new(1.5, LIGHT);
    for k in 0..4 {
        let a = k as f32 * std::f32::consts::FRAC_PI_4;
        let d = vec2(a.cos(), a.sin()) * 7.0;
        painter.line_segment([s - d, s + d], stroke);
    }
    painter.circle_filled(s, 3.0, LIGHT);
}

/// A number with four significant digits, for labels.
#[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
pub fn short(v: Real) -> String {
    let v = v as f64;
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if v.abs() >= 1e5 || v.abs() < 1e-3 {
        format!("{v:.3e}")
    } else {
        let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 6) as usize;
        let text = format!("{v:.digits$}");
        if text.contains('.') { text.trim_end_matches('0').trim_end_matches('.').to_owned() } else { text }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Camera;

    #[test]
    fn the_drawn_view_plane_corners_are_the_conventions_camera_math_for_both_projections() {
        // docs/conventions.md: plane_h = 2·near·tan(fov_y/2), plane_w = plane_h·W/H,
        // O = C + near·cam_z + (plane_h/2)·cam_y − (plane_w/2)·cam_x, and the
        // others along cam_x and −cam_y; the explain record's corners too.
        for projection in [Kind::Perspective, Kind::Orthographic] {
            let camera = Camera::new(
                Vec3::new(-4.0, 3.0, -6.0),
                Vec3::new(0.0, 0.5, 0.0),
                Vec3::Y,
                45.0,
                1.5,
                projection,
            )
            .unwrap();
            let view = ViewPlane::new(camera, 320, 240).unwrap();
            let b = camera.basis();
            let plane_h = 2.0 * 1.5 * (22.5 as Real).to_radians().tan();
            let plane_w = plane_h * 320.0 / 240.0;
            let o = camera.position() + 1.5 * b.z + 0.5 * plane_h * b.y - 0.5 * plane_w * b.x;
            let want = [o, o + plane_w * b.x, o + plane_w * b.x - plane_h * b.y, o - plane_h * b.y];
            let got = plane_corners(&view);
            for (g, w) in got.iter().zip(want) {
                assert!((*g - w).length() < 1e-5, "{projection:?}: {g} vs {w}");
            }
            let record = rt_core::explain::record::ViewPlaneRecord::of(&view);
            assert_eq!([record.upper_left, record.upper_right, record.lower_right, record.lower_left], got);
        }
    }

    #[test]
    fn labels_show_four_significant_digits() {
        assert_eq!(short(0.8284271), "0.8284");
        assert_eq!(short(1.1045695), "1.105");
        assert_eq!(short(2.0), "2");
        assert_eq!(short(123.456), "123.5");
        assert_eq!(short(1e-5), "1.000e-5");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(-0.5), "-0.5");
    }
}
