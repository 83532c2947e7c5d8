//! World → observer screen: where the scene view draws a 3D point, and the
//! part of a 3D segment in front of the observer.
//!
//! The observer is an rt-core perspective [`Camera`] whose [`ViewPlane`]
//! (`docs/conventions.md`) is the scene view's flat render; a point is drawn
//! where the primary ray through it crosses that plane, so overlays and the
//! rendered image agree pixel for pixel. With `d = p − C` in the observer's
//! basis (`x = d·cam_x`, `y = d·cam_y`, `z = d·cam_z`, left-handed), the
//! view-plane point `C + near·cam_z + (near·x/z)·cam_x + (near·y/z)·cam_y`
//! is, in image pixels (row 0 at the top, as `ViewPlane::point` has it),
//!
//! ```text
//! px = (near·x/z + plane_w/2) / (plane_w/W)
//! py = (plane_h/2 − near·y/z) / (plane_h/H)
//! ```
//!
//! and pixels map to screen points linearly onto the rectangle the image is
//! drawn in. Points with `z < near` (behind the observer or too close) have
//! no image; a segment is clipped to `z ≥ near` before it is drawn.

use egui::{Pos2, Rect, pos2};
use rt_core::{Camera, Real, Vec3, ViewPlane};

/// The projection of an observer camera onto a screen rectangle.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    view: ViewPlane,
    screen: Rect,
}

impl Projection {
    /// The projection of `observer` (perspective) rendered `size` pixels
    /// large and drawn into `screen`; `None` if the camera has no usable
    /// view plane at that size.
    pub fn new(observer: Camera, size: [u32; 2], screen: Rect) -> Option<Self> {
        let view = ViewPlane::new(observer, size[0], size[1]).ok()?;
        Some(Self { view, screen })
    }

    /// The observer's view plane (its image size is the flat render's).
    pub fn view(&self) -> &ViewPlane {
        &self.view
    }

    /// Distance along cam_z from the observer of `p`.
    pub fn depth(&self, p: Vec3) -> Real {
        (p - self.view.camera().position()).dot(self.view.camera().basis().z)
    }

    /// `p` in the observer's image, in pixels (fractional; row 0 at the
    /// top), or `None` if it is closer than `near` along cam_z.
    pub fn pixel_of(&self, p: Vec3) -> Option<[Real; 2]> {
        let camera = self.view.camera();
        let b = camera.basis();
        let d = p - camera.position();
        let z = d.dot(b.z);
        if z.is_nan() || z < camera.near() {
            return None;
        }
        let (plane_w, plane_h) = self.view.size();
        let (pixel_w, pixel_h) = self.view.pixel_size();
        let k = camera.near() / z;
        Some([(k * d.dot(b.x) + 0.5 * plane_w) / pixel_w, (0.5 * plane_h - k * d.dot(b.y)) / pixel_h])
    }

    /// Image pixels → screen points.
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
    pub fn pixels_to_screen(&self, [px, py]: [Real; 2]) -> Pos2 {
        let (w, h) = (self.view.width() as f32, self.view.height() as f32);
        let r = self.screen;
        pos2(r.left() + px as f32 / w * r.width(), r.top() + py as f32 / h * r.height())
    }

    /// Where `p` is drawn on screen, or `None` if it is behind the observer.
    pub fn point(&self, p: Vec3) -> Option<Pos2> {
        self.pixel_of(p).map(|px| self.pixels_to_screen(px))
    }

    /// The part of segment `a`–`b` in front of the observer (`z ≥ near`),
    /// on screen; `None` if none of it is.
    pub fn segment(&self, a: Vec3, b: Vec3) -> Option<[Pos2; 2]> {
        let [a, b] = self.clip(a, b)?;
        Some([self.point(a)?, self.point(b)?])
    }

    /// Segment `a`–`b` cut to `z ≥ near` (the cut end moved onto that plane,
    /// a hair in front of it so it still projects).
    pub fn clip(&self, a: Vec3, b: Vec3) -> Option<[Vec3; 2]> {
        let near = self.view.camera().near() * (1.0 + 1e-4);
        let (za, zb) = (self.depth(a), self.depth(b));
        match (za >= near, zb >= near) {
            (true, true) => Some([a, b]),
            (false, false) => None,
            (true, false) => Some([a, a + (b - a) * ((za - near) / (za - zb))]),
            (false, true) => Some([b + (a - b) * ((zb - near) / (zb - za)), b]),
        }
    }
}

/// The screen distance from `p` to segment `a`–`b`, in points (hovering).
pub fn distance_to_segment(p: Pos2, [a, b]: [Pos2; 2]) -> f32 {
    let ab = b - a;
    let t = if ab.length_sq() > 0.0 { ((p - a).dot(ab) / ab.length_sq()).clamp(0.0, 1.0) } else { 0.0 };
    (a + ab * t).distance(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rt_core::Projection as Kind;

    fn observer() -> Camera {
        Camera::new(
            Vec3::new(3.0, 2.0, -5.0),
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::Y,
            50.0,
            0.1,
            Kind::Perspective,
        )
        .unwrap()
    }

    #[test]
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 when rt-core's `f64` feature is on.
    fn a_point_of_the_observers_view_plane_projects_onto_its_own_pixel() {
        // What the overlay draws lines up with the flat render: the view-plane
        // point of pixel (ix+sx, iy+sy) and every point along its primary ray
        // land at those pixel coordinates, on screen scaled into the rectangle.
        let screen = Rect::from_min_size(pos2(100.0, 50.0), egui::vec2(640.0, 480.0));
        let p = Projection::new(observer(), [320, 240], screen).unwrap();
        for (ix, iy, sx, sy) in
            [(0, 0, 0.0, 0.0), (319, 239, 1.0, 1.0), (17, 200, 0.25, 0.75), (160, 120, 0.5, 0.5)]
        {
            let on_plane = p.view().point(ix, iy, sx, sy);
            let [px, py] = p.pixel_of(on_plane).unwrap();
            let tolerance = 1e-3;
            assert!(
                (px - (ix as Real + sx)).abs() < tolerance && (py - (iy as Real + sy)).abs() < tolerance,
                "{px} {py}"
            );
            let ray = p.view().primary_ray(ix, iy, sx, sy);
            let [qx, qy] = p.pixel_of(ray.at(7.5)).unwrap();
            assert!((qx - px).abs() < tolerance && (qy - py).abs() < tolerance);
            let s = p.point(on_plane).unwrap();
            let want = pos2(100.0 + (ix as f32 + sx as f32) * 2.0, 50.0 + (iy as f32 + sy as f32) * 2.0);
            assert!(s.distance(want) < 1e-2, "{s:?} {want:?}");
        }
    }

    #[test]
    fn points_behind_the_observer_have_no_image_and_segments_are_clipped_at_near() {
        let screen = Rect::from_min_size(Pos2::ZERO, egui::vec2(320.0, 240.0));
        let p = Projection::new(observer(), [320, 240], screen).unwrap();
        let c = observer().position();
        let z = observer().basis().z;
        assert!(p.point(c - z).is_none());
        assert!(p.point(c + 0.05 * z).is_none(), "closer than near");
        assert!(p.segment(c - z, c - 2.0 * z).is_none());
        // A segment from behind to the COI keeps its front part, cut at near.
        let [a, b] = p.clip(c - 3.0 * z, observer().center_of_interest()).unwrap();
        assert_eq!(b, observer().center_of_interest());
        assert!((p.depth(a) - 0.1).abs() < 1e-4, "{}", p.depth(a));
        let [sa, sb] = p.segment(c - 3.0 * z, observer().center_of_interest()).unwrap();
        // Along the view axis through the COI, everything lands on the centre.
        assert!(
            sa.distance(pos2(160.0, 120.0)) < 0.05 && sb.distance(pos2(160.0, 120.0)) < 0.05,
            "{sa:?} {sb:?}"
        );
    }

    #[test]
    fn distance_to_a_segment_is_to_its_nearest_point() {
        let seg = [pos2(0.0, 0.0), pos2(10.0, 0.0)];
        assert_eq!(distance_to_segment(pos2(5.0, 3.0), seg), 3.0);
        assert_eq!(distance_to_segment(pos2(13.0, 4.0), seg), 5.0);
    }
}
