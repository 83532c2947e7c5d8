//! The virtual view plane: its size in world units, its upper-left corner, the
//! 3D point of any pixel, and the primary ray through it.
//!
//! The plane sits `near` units in front of C along cam_z, parallel to cam_x and
//! cam_y, with the image's proportions (`docs/conventions.md`):
//!
//! ```text
//! plane_h = 2 · near · tan(fov_y / 2)          plane_w = plane_h · W / H
//! O       = C + near·cam_z + (plane_h/2)·cam_y − (plane_w/2)·cam_x     (pixel corner (0,0))
//! P(ix+sx, iy+sy) = O + (ix+sx)·(plane_w/W)·cam_x − (iy+sy)·(plane_h/H)·cam_y
//! ```
//!
//! Row 0 is the top row; (sx, sy) ∈ [0,1)² is the sub-pixel offset, (0.5, 0.5)
//! the pixel centre.

use thiserror::Error;

use crate::camera::{Camera, Projection};
use crate::math::ray::Ray;
use crate::math::real::{MIN_PIXEL_ULPS, Real, Vec3};
use crate::sampling::sampler::concentric_disk;

/// Largest accepted image side, in pixels.
pub const MAX_IMAGE_SIDE: u32 = 1 << 15;
/// Largest accepted pixel count (W·H): 2²⁷ ≈ 134 M pixels, 400 MiB as 8-bit RGB.
pub const MAX_PIXELS: u64 = 1 << 27;

/// Why an image size or view plane cannot be used.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ViewPlaneError {
    /// Width or height is zero or above [`MAX_IMAGE_SIDE`], or W·H is above [`MAX_PIXELS`].
    #[error(
        "image size {width}x{height} is out of range: each side must be 1 to {MAX_IMAGE_SIDE} \
         and the image at most {MAX_PIXELS} pixels"
    )]
    ImageSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// Pixels too small for neighbouring pixels to get different rays.
    #[error(
        "the view plane's pixels ({pixel_w} x {pixel_h} world units) are smaller than {smallest}, \
         too small for neighbouring pixels to get different rays: widen camera.fov_y{hint}"
    )]
    PixelsTooSmall {
        /// Pixel width in world units.
        pixel_w: Real,
        /// Pixel height in world units.
        pixel_h: Real,
        /// The smallest pixel the camera can resolve.
        smallest: Real,
        /// Extra advice for orthographic cameras.
        hint: &'static str,
    },
    /// The plane (or a pixel of it) is too large to represent.
    #[error(
        "the view plane ({plane_w} x {plane_h} world units) is too large to represent: reduce camera.near"
    )]
    PlaneTooLarge {
        /// Plane width in world units.
        plane_w: Real,
        /// Plane height in world units.
        plane_h: Real,
    },
}

/// Checks an image size against [`MAX_IMAGE_SIDE`] and [`MAX_PIXELS`].
pub fn check_image_size(width: u32, height: u32) -> Result<(), ViewPlaneError> {
    let side_ok = |s: u32| (1..=MAX_IMAGE_SIDE).contains(&s);
    if side_ok(width) && side_ok(height) && width as u64 * height as u64 <= MAX_PIXELS {
        Ok(())
    } else {
        Err(ViewPlaneError::ImageSize { width, height })
    }
}

/// The view plane of a camera for a W×H-pixel image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewPlane {
    camera: Camera,
    width: u32,
    height: u32,
    plane_w: Real,
    plane_h: Real,
    /// `(plane_w / W, plane_h / H)`, divided once here rather than per ray.
    pixel: (Real, Real),
}

impl ViewPlane {
    /// The view plane of `camera` for a `width`×`height` image.
    pub fn new(camera: Camera, width: u32, height: u32) -> Result<Self, ViewPlaneError> {
        check_image_size(width, height)?;
        let plane_h = camera.view_plane_height();
        let plane_w = plane_h * (width as Real / height as Real);
        let pixel = (plane_w / width as Real, plane_h / height as Real);
        let view = Self { camera, width, height, plane_w, plane_h, pixel };
        let (pixel_w, pixel_h) = view.pixel_size();
        if !(plane_w.is_finite() && plane_h.is_finite()) {
            return Err(ViewPlaneError::PlaneTooLarge { plane_w, plane_h });
        }
        // Perspective rays differ in direction `near·cam_z + offset`; orthographic
        // rays in origin `C + near·cam_z + offset`, resolved at C's magnitude too.
        let (magnitude, hint) = match camera.projection() {
            Projection::Perspective => (camera.near(), ""),
            Projection::Orthographic => (
                camera.near().max(camera.position().abs().max_element()),
                " (an orthographic camera far from the origin needs a wider view)",
            ),
        };
        let smallest = MIN_PIXEL_ULPS * Real::EPSILON * magnitude;
        if pixel_w.is_nan() || pixel_h.is_nan() || pixel_w.min(pixel_h) < smallest {
            return Err(ViewPlaneError::PixelsTooSmall { pixel_w, pixel_h, smallest, hint });
        }
        Ok(view)
    }

    /// The camera this plane belongs to.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }
    /// Image width W in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }
    /// Image height H in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }
    /// `(plane_w, plane_h)`: the plane's size in world units.
    pub fn size(&self) -> (Real, Real) {
        (self.plane_w, self.plane_h)
    }
    /// `(plane_w / W, plane_h / H)`: one pixel's size in world units.
    pub fn pixel_size(&self) -> (Real, Real) {
        self.pixel
    }

    /// The angle one pixel subtends at a perspective camera's eye,
    /// `atan(plane_h / (near·H))` = `atan(2·tan(fov_y/2)/H)` (radians): the
    /// spread of a pixel's ray cone ([`crate::materials::texture_lod`]);
    /// 0 for an orthographic camera, whose rays are parallel.
    pub fn spread_angle(&self) -> Real {
        match self.camera.projection() {
            Projection::Perspective => (self.pixel.1 / self.camera.near()).atan(),
            Projection::Orthographic => 0.0,
        }
    }

    /// `O`, the world point of pixel corner (0, 0): the plane's upper-left corner.
    pub fn upper_left(&self) -> Vec3 {
        self.point(0, 0, 0.0, 0.0)
    }

    /// The world point of pixel (ix, iy) at sub-pixel offset (sx, sy).
    ///
    /// Pixel indices past the image are allowed (they extrapolate the plane).
    pub fn point(&self, ix: u32, iy: u32, sx: Real, sy: Real) -> Vec3 {
        self.camera.position() + self.offset_from_eye(ix, iy, sx, sy)
    }

    /// The primary ray through pixel (ix, iy) at sub-pixel offset (sx, sy).
    ///
    /// Perspective: origin C, direction `P − C` (not unit; |dir| ≥ near).
    /// Orthographic: origin P, direction cam_z (unit).
    pub fn primary_ray(&self, ix: u32, iy: u32, sx: Real, sy: Real) -> Ray {
        let offset = self.offset_from_eye(ix, iy, sx, sy);
        let eye = self.camera.position();
        match self.camera.projection() {
            Projection::Perspective => Ray::new(eye, offset),
            Projection::Orthographic => Ray::new(eye + offset, self.camera.basis().z),
        }
    }

    /// The camera's ray for film position `film` in pixel (ix, iy) and lens
    /// position `lens`, both in [0,1)²: what every camera answers. Without
    /// a lens (radius 0) it is [`ViewPlane::primary_ray`] at sub-pixel
    /// offset `film`, bit for bit, and `lens` is ignored.
    ///
    /// Through a thin lens of radius A focused at f ([`crate::camera::Lens`];
    /// pbrt-v4 §5.2.3), `lens` goes to the disc by Shirley and Chiu's
    /// concentric map ([`concentric_disk`]), `(dx, dy)` in the unit disc:
    ///
    /// ```text
    /// perspective:   origin C + A·(dx·cam_x + dy·cam_y)
    ///                direction (P − C)·f/near − A·(dx·cam_x + dy·cam_y)
    ///                (towards P − C scaled to the plane in focus, f from C)
    /// orthographic:  origin P + A·(dx·cam_x + dy·cam_y)
    ///                direction f·cam_z − A·(dx·cam_x + dy·cam_y)
    ///                (the plane in focus is f beyond the view plane, where
    ///                orthographic rays start: pbrt-v4's OrthographicCamera)
    /// ```
    ///
    /// so every ray of a pixel meets the others on the plane in focus, and
    /// a point off it spreads over a circle of confusion
    /// ([`crate::camera::Lens::circle_of_confusion`]).
    #[inline(always)]
    pub fn camera_ray(&self, ix: u32, iy: u32, film: (Real, Real), lens: (Real, Real)) -> Ray {
        let thin = self.camera.lens();
        if !thin.is_thin_lens() {
            return self.primary_ray(ix, iy, film.0, film.1);
        }
        let offset = self.offset_from_eye(ix, iy, film.0, film.1);
        let b = self.camera.basis();
        let (dx, dy) = concentric_disk(lens);
        let on_lens = thin.radius * (dx * b.x + dy * b.y);
        let eye = self.camera.position();
        match self.camera.projection() {
            Projection::Perspective => {
                Ray::new(eye + on_lens, offset * (thin.focus_distance / self.camera.near()) - on_lens)
            }
            Projection::Orthographic => Ray::new(eye + offset + on_lens, thin.focus_distance * b.z - on_lens),
        }
    }

    /// Whether the camera's rays depend on the lens position: only through
    /// a thin lens of radius > 0, not for either pinhole projection.
    pub fn has_lens(&self) -> bool {
        self.camera.lens().is_thin_lens()
    }

    /// The primary ray through the centre of pixel (ix, iy): the camera's
    /// ray for film position (0.5, 0.5).
    pub fn center_ray(&self, ix: u32, iy: u32) -> Ray {
        self.camera_ray(ix, iy, (0.5, 0.5), (0.5, 0.5))
    }

    /// `P − C`, the formula above with C taken out; computed relative to the
    /// eye so that a camera far from the origin loses no precision in it.
    fn offset_from_eye(&self, ix: u32, iy: u32, sx: Real, sy: Real) -> Vec3 {
        let b = self.camera.basis();
        let (pixel_w, pixel_h) = self.pixel_size();
        let right = (ix as Real + sx) * pixel_w - 0.5 * self.plane_w;
        let up = 0.5 * self.plane_h - (iy as Real + sy) * pixel_h;
        self.camera.near() * b.z + right * b.x + up * b.y
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::scale_pow2;

    fn assert_close(a: Vec3, b: Vec3, tol: Real) {
        assert!((a - b).abs().max_element() <= tol, "{a} != {b}");
    }

    fn plane(c: Vec3, coi: Vec3, fov: Real, near: Real, w: u32, h: u32) -> ViewPlane {
        let cam = Camera::new(c, coi, Vec3::Y, fov, near, Projection::Perspective).unwrap();
        ViewPlane::new(cam, w, h).unwrap()
    }

    #[test]
    fn fov_90_near_1_square_image_spans_minus_one_to_one() {
        // plane_h = 2·1·tan 45° = 2, plane_w = 2·4/4 = 2, O = (0,0,0) + (0,0,1) + (0,1,0) − (1,0,0).
        let v = plane(Vec3::ZERO, Vec3::Z, 90.0, 1.0, 4, 4);
        let (w, h) = v.size();
        assert!((w - 2.0).abs() < 1e-6 && (h - 2.0).abs() < 1e-6);
        assert_close(v.upper_left(), Vec3::new(-1.0, 1.0, 1.0), 1e-6);
        assert_close(v.point(4, 0, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0), 1e-6);
        assert_close(v.point(0, 4, 0.0, 0.0), Vec3::new(-1.0, -1.0, 1.0), 1e-6);
        assert_close(v.point(4, 4, 0.0, 0.0), Vec3::new(1.0, -1.0, 1.0), 1e-6);
        // Pixel (1,1)'s lower-right corner is the plane's centre.
        assert_close(v.point(1, 1, 1.0, 1.0), Vec3::new(0.0, 0.0, 1.0), 1e-6);
        // Pixel (0,0)'s centre: one pixel is 0.5 wide, so (−0.75, 0.75, 1).
        assert_close(v.center_ray(0, 0).dir, Vec3::new(-0.75, 0.75, 1.0), 1e-6);
    }

    #[test]
    fn fov_60_near_2_wide_image_from_a_displaced_camera() {
        // C = (1,2,3) looking along +z. plane_h = 2·2·tan 30° = 4/√3 ≈ 2.309401,
        // plane_w = plane_h · 640/480 ≈ 3.079201. O = C + (0,0,2) + (0, h/2, 0) − (w/2, 0, 0).
        let v = plane(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 10.0), 60.0, 2.0, 640, 480);
        let h = 4.0 / (3.0 as Real).sqrt();
        let w = h * 640.0 / 480.0;
        let (pw, ph) = v.size();
        assert!((pw - w).abs() < 1e-5 && (ph - h).abs() < 1e-5);
        let o = Vec3::new(1.0 - w / 2.0, 2.0 + h / 2.0, 5.0);
        assert_close(v.upper_left(), o, 1e-5);
        assert_close(v.point(640, 0, 0.0, 0.0), o + Vec3::new(w, 0.0, 0.0), 1e-5);
        assert_close(v.point(0, 480, 0.0, 0.0), o - Vec3::new(0.0, h, 0.0), 1e-5);
        assert_close(v.point(640, 480, 0.0, 0.0), o + Vec3::new(w, -h, 0.0), 1e-5);
        // The centre of the image (pixel corner (320, 240)) lies on the view axis.
        assert_close(v.point(320, 240, 0.0, 0.0), Vec3::new(1.0, 2.0, 5.0), 1e-5);
    }

    #[test]
    fn oblique_camera_puts_the_centre_pixel_on_the_view_axis() {
        // Odd size: the centre of pixel (2,1) of a 5×3 image is the plane centre.
        let c = Vec3::new(-4.0, 3.0, 2.0);
        let coi = Vec3::new(1.0, -1.0, 7.0);
        let v = plane(c, coi, 45.0, 0.5, 5, 3);
        let expected = c + 0.5 * (coi - c).normalize();
        assert_close(v.point(2, 1, 0.5, 0.5), expected, 1e-5);
        // Moving right one pixel moves along cam_x by one pixel width.
        let step = v.point(3, 1, 0.5, 0.5) - v.point(2, 1, 0.5, 0.5);
        assert_close(step, v.pixel_size().0 * v.camera().basis().x, 1e-5);
    }

    #[test]
    fn perspective_rays_start_at_the_eye_and_orthographic_rays_travel_along_cam_z() {
        let v = plane(Vec3::new(0.0, 1.0, -5.0), Vec3::new(0.0, 1.0, 0.0), 90.0, 1.0, 4, 2);
        let p = v.center_ray(0, 0);
        assert_eq!(p.origin, Vec3::new(0.0, 1.0, -5.0));
        assert_close(p.origin + p.dir, v.point(0, 0, 0.5, 0.5), 1e-6);

        let cam = v.camera().with_projection(Projection::Orthographic);
        let o = ViewPlane::new(cam, 4, 2).unwrap();
        let r = o.center_ray(0, 0);
        assert_close(r.origin, v.point(0, 0, 0.5, 0.5), 1e-6);
        assert_eq!(r.dir, Vec3::Z);
        // Orthographic rays are parallel: all have the same direction.
        assert_eq!(o.center_ray(3, 1).dir, r.dir);
    }

    #[test]
    fn image_sizes_outside_the_limits_are_refused() {
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0, 1.0, Projection::Perspective).unwrap();
        for (w, h) in [(0, 10), (10, 0), (MAX_IMAGE_SIDE + 1, 1), (MAX_IMAGE_SIDE, MAX_IMAGE_SIDE)] {
            assert_eq!(ViewPlane::new(cam, w, h), Err(ViewPlaneError::ImageSize { width: w, height: h }));
        }
    }

    #[test]
    fn a_field_of_view_too_narrow_to_separate_pixels_is_refused() {
        // 1e-30° over 4000 pixels: each pixel is ~1e-36 of near, far below one ulp.
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 1e-30, 1e-6, Projection::Perspective);
        match cam {
            Ok(cam) => {
                assert!(matches!(ViewPlane::new(cam, 4000, 4000), Err(ViewPlaneError::PixelsTooSmall { .. })))
            }
            Err(e) => assert!(matches!(e, crate::camera::CameraError::ViewPlaneUnrepresentable { .. })),
        }
    }

    #[test]
    fn huge_near_distances_work_until_the_plane_itself_overflows() {
        // near = MAX/10: plane_h = 2·near·tan 20° ≈ 0.07·MAX, representable; rays finite.
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, Real::MAX / 10.0, Projection::Perspective)
            .unwrap();
        let v = ViewPlane::new(cam, 640, 480).unwrap();
        assert!(v.center_ray(0, 0).dir.is_finite());
        // near = MAX/3, fov 90°: plane_h ≈ 0.67·MAX fits, but a 2:1 plane is 1.33·MAX wide.
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, Real::MAX / 3.0, Projection::Perspective)
            .unwrap();
        assert!(matches!(ViewPlane::new(cam, 200, 100), Err(ViewPlaneError::PlaneTooLarge { .. })));
    }

    #[test]
    fn an_orthographic_camera_far_away_must_resolve_its_pixel_origins() {
        // 64 pixels across 0.1 units at x = 2²⁰ (f32; 2⁴⁹ in f64), where numbers
        // are 0.0625 apart (0.125 in f64), so neighbouring origins would nearly
        // coincide. Refused; a wider view is accepted.
        let far = Vec3::new(scale_pow2(1.0, 20 + Real::MANTISSA_DIGITS as i32 - 24), 0.0, 0.0);
        let narrow =
            Camera::new(far, far + 100.0 * Vec3::Z, Vec3::Y, 5.7, 1.0, Projection::Orthographic).unwrap();
        assert!(matches!(ViewPlane::new(narrow, 64, 64), Err(ViewPlaneError::PixelsTooSmall { .. })));
        let wide =
            Camera::new(far, far + 100.0 * Vec3::Z, Vec3::Y, 170.0, 10.0, Projection::Orthographic).unwrap();
        let v = ViewPlane::new(wide, 64, 64).unwrap();
        assert_ne!(v.center_ray(0, 0).origin, v.center_ray(1, 0).origin);
        // The same narrow view in perspective is fine: rays differ in direction.
        assert!(ViewPlane::new(narrow.with_projection(Projection::Perspective), 64, 64).is_ok());
    }

    #[test]
    fn the_narrowest_accepted_field_of_view_still_gives_distinct_neighbouring_rays() {
        // Find (by bisection on the exponent) about the smallest fov that is accepted
        // for 1000 pixels, and check that pixels 0 and 1 still get different rays.
        let mut fov: Real = 1.0;
        let mut last_ok = None;
        while fov > 1e-30 {
            let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, fov, 1.0, Projection::Perspective).unwrap();
            if let Ok(v) = ViewPlane::new(cam, 1000, 1000) {
                last_ok = Some(v);
            }
            fov *= 0.5;
        }
        let v = last_ok.unwrap();
        assert_ne!(v.center_ray(0, 0).dir, v.center_ray(1, 0).dir);
        assert_ne!(v.center_ray(0, 0).dir, v.center_ray(0, 1).dir);
    }

    fn lens_plane(radius: Real, focus: Real, projection: Projection) -> ViewPlane {
        let cam = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0, 1.0, projection).unwrap();
        ViewPlane::new(cam.with_lens(crate::camera::Lens::new(radius, focus).unwrap()), 64, 48).unwrap()
    }

    #[test]
    fn a_lens_of_radius_zero_is_the_pinhole_bit_for_bit() {
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let v = lens_plane(0.0, 3.0, projection);
            assert!(!v.has_lens());
            for (x, y, film, lens) in [(0, 0, (0.5, 0.5), (0.0, 0.0)), (13, 40, (0.1, 0.9), (0.99, 0.3))] {
                let (a, b) = (v.camera_ray(x, y, film, lens), v.primary_ray(x, y, film.0, film.1));
                assert_eq!((a.origin, a.dir), (b.origin, b.dir));
            }
        }
    }

    #[test]
    fn every_ray_of_a_film_point_starts_on_the_lens_and_meets_the_others_on_the_plane_in_focus() {
        // Perspective: focus 5 from the eye; orthographic: 5 beyond the view plane.
        for (projection, plane_z) in [(Projection::Perspective, 5.0), (Projection::Orthographic, 6.0)] {
            let v = lens_plane(0.25, 5.0, projection);
            assert!(v.has_lens());
            let pinhole = v.camera_ray(20, 7, (0.3, 0.6), (0.5, 0.5));
            let sharp = pinhole.origin + pinhole.dir * ((plane_z - pinhole.origin.z) / pinhole.dir.z);
            let start = if projection == Projection::Perspective { Vec3::ZERO } else { pinhole.origin };
            for k in 0..64 {
                let lens = ((k % 8) as Real / 8.0 + 0.05, (k / 8) as Real / 8.0 + 0.05);
                let r = v.camera_ray(20, 7, (0.3, 0.6), lens);
                let across = r.origin - start;
                assert!(across.z.abs() < 1e-6 && across.length() <= 0.25 + 1e-6, "{across}");
                let at = r.origin + r.dir * ((plane_z - r.origin.z) / r.dir.z);
                assert_close(at, sharp, 1e-5);
            }
        }
    }

    #[test]
    fn a_point_off_the_plane_in_focus_spreads_over_the_thin_lens_circle_of_confusion() {
        // Lens radius A = 0.1 focused at f = 5, view plane at near = 1; a
        // point Q at depth d on the axis. The centre film point's rays
        // through the lens rim cross depth d on a circle of radius
        // A·|d − f|/f; projected through the eye onto the view plane (×
        // near/d) that is the circle of confusion's radius, half of
        // 2A·near·|d − f|/(f·d) (so for d = 10: 0.01 on the plane, 0.1 at Q).
        let v = lens_plane(0.1, 5.0, Projection::Perspective);
        let lens = v.camera().lens();
        for d in [2.0, 10.0, 40.0] {
            let mut widest: Real = 0.0;
            for k in 0..256 {
                // The rim: u on the square's edge maps to the disc's edge.
                let t = k as Real / 256.0;
                let rim = [(t, 0.0), (t, 1.0 - 1e-7), (0.0, t), (1.0 - 1e-7, t)][k % 4];
                let r = v.camera_ray(32, 24, (0.0, 0.0), rim);
                let at = r.origin + r.dir * ((d - r.origin.z) / r.dir.z);
                widest = widest.max(Vec3::new(at.x, at.y, 0.0).length());
            }
            let on_plane = 2.0 * widest * v.camera().near() / d;
            let expected = 2.0 * 0.1 * 1.0 * (d - 5.0).abs() / (5.0 * d);
            assert!((lens.circle_of_confusion(d, 1.0) - expected).abs() < 1e-6);
            assert!(
                (on_plane - expected).abs() < 1e-4 * expected.max(1.0),
                "d {d}: {on_plane} against {expected}"
            );
        }
    }
}
