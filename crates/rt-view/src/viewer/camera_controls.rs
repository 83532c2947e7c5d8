//! The viewer's camera edits: sliders, orbit, pan and zoom, as pure functions.
//!
//! Every edit goes through [`CameraSettings::accept`]: an edit that would make
//! the camera degenerate (`docs/conventions.md`) is refused and the previous
//! camera kept, so the viewer can never produce NaN or a flipped image. Orbiting also keeps
//! the view direction at least [`MIN_POLAR_DEGREES`] away from the up vector.

use std::ops::RangeInclusive;

use rt_core::{Camera, CameraError, Projection, Real, Vec3};

/// Range of the vertical field-of-view slider, degrees.
pub const FOV_RANGE: RangeInclusive<Real> = 1.0..=179.0;
/// Range of the near-distance control, world units.
pub const NEAR_RANGE: RangeInclusive<Real> = 1e-3..=1e4;
/// Orbiting stops this close (degrees) to looking straight along ±up.
pub const MIN_POLAR_DEGREES: Real = 1.0;

/// The editable camera parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraSettings {
    /// Eye position C.
    pub position: Vec3,
    /// Centre of interest COI.
    pub center_of_interest: Vec3,
    /// General up vector (kept from the scene file).
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub fov_y: Real,
    /// View-plane distance.
    pub near: Real,
    /// Perspective or orthographic.
    pub projection: Projection,
}

impl CameraSettings {
    /// The settings of an existing camera.
    pub fn from_camera(c: &Camera) -> Self {
        Self {
            position: c.position(),
            center_of_interest: c.center_of_interest(),
            up: c.up(),
            fov_y: c.fov_y(),
            near: c.near(),
            projection: c.projection(),
        }
    }

    /// The camera these settings describe, or why there is none.
    pub fn to_camera(&self) -> Result<Camera, CameraError> {
        Camera::new(self.position, self.center_of_interest, self.up, self.fov_y, self.near, self.projection)
    }

    /// `candidate` with fov and near clamped to the control ranges if that
    /// makes a valid camera, else `self` unchanged.
    pub fn accept(&self, candidate: Self) -> Self {
        let clamped = Self {
            fov_y: candidate.fov_y.clamp(*FOV_RANGE.start(), *FOV_RANGE.end()),
            near: candidate.near.clamp(*NEAR_RANGE.start(), *NEAR_RANGE.end()),
            ..candidate
        };
        if clamped.to_camera().is_ok() { clamped } else { *self }
    }

    /// Orbits the eye around the centre of interest: `yaw` radians about the
    /// up axis, `pitch` radians towards up (the polar angle is clamped), at a
    /// constant distance.
    pub fn orbit(&self, yaw: Real, pitch: Real) -> Self {
        let up = self.up.normalize_or_zero();
        let offset = self.position - self.center_of_interest;
        let distance = offset.length();
        let along = offset.dot(up);
        let across = offset - along * up;
        let Some(heading) = across.try_normalize() else { return *self };
        let heading = heading * yaw.cos() + up.cross(heading) * yaw.sin();
        let min_polar = MIN_POLAR_DEGREES.to_radians();
        let polar = (along / distance).clamp(-1.0, 1.0).acos();
        let polar = (polar - pitch).clamp(min_polar, std::f64::consts::PI as Real - min_polar);
        let offset = distance * (polar.cos() * up + polar.sin() * heading);
        self.accept(Self { position: self.center_of_interest + offset, ..*self })
    }

    /// Moves eye and centre of interest together by `right` along cam_x and
    /// `up` along cam_y (world units).
    pub fn pan(&self, right: Real, up: Real) -> Self {
        let Ok(camera) = self.to_camera() else { return *self };
        let b = camera.basis();
        let shift = right * b.x + up * b.y;
        self.accept(Self {
            position: self.position + shift,
            center_of_interest: self.center_of_interest + shift,
            ..*self
        })
    }

    /// Zooms by `factor` (< 1 is closer): a perspective camera moves towards
    /// the centre of interest, an orthographic one narrows its view plane
    /// (moving it would change nothing but where rays start).
    pub fn zoom(&self, factor: Real) -> Self {
        match self.projection {
            Projection::Perspective => {
                let offset = (self.position - self.center_of_interest) * factor;
                self.accept(Self { position: self.center_of_interest + offset, ..*self })
            }
            Projection::Orthographic => {
                let half = (0.5 * self.fov_y.to_radians()).tan() * factor;
                self.accept(Self { fov_y: 2.0 * half.atan().to_degrees(), ..*self })
            }
        }
    }

    /// World units per pixel at the centre of interest, for an image `height`
    /// pixels tall on screen: how far a pan of one pixel should move.
    pub fn world_per_pixel(&self, height: Real) -> Real {
        let plane_h = 2.0 * self.near * (0.5 * self.fov_y.to_radians()).tan();
        let at_coi = match self.projection {
            Projection::Perspective => {
                plane_h * (self.position - self.center_of_interest).length() / self.near
            }
            Projection::Orthographic => plane_h,
        };
        at_coi / height.max(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> CameraSettings {
        CameraSettings {
            position: Vec3::new(0.0, 1.0, -5.0),
            center_of_interest: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 45.0,
            near: 1.0,
            projection: Projection::Perspective,
        }
    }

    #[test]
    fn orbiting_keeps_the_distance_and_the_centre_of_interest() {
        let s = settings();
        let d = (s.position - s.center_of_interest).length();
        let o = s.orbit(0.7, 0.3);
        assert_ne!(o.position, s.position);
        assert_eq!(o.center_of_interest, s.center_of_interest);
        assert!(((o.position - o.center_of_interest).length() - d).abs() < 1e-4);
    }

    #[test]
    fn orbiting_over_the_pole_stops_short_of_a_degenerate_camera() {
        let mut s = settings();
        for _ in 0..100 {
            s = s.orbit(0.0, 0.2);
            assert!(s.to_camera().is_ok());
        }
        let view = (s.center_of_interest - s.position).normalize();
        let angle_to_down = view.dot(-Vec3::Y).clamp(-1.0, 1.0).acos().to_degrees();
        assert!((angle_to_down - MIN_POLAR_DEGREES).abs() < 0.01, "{angle_to_down}");
    }

    #[test]
    fn panning_moves_eye_and_centre_of_interest_together_sideways() {
        let s = settings();
        let p = s.pan(2.0, 0.0);
        assert_eq!(p.position - s.position, p.center_of_interest - s.center_of_interest);
        // cam_x of a camera looking along +z is +x.
        assert!((p.center_of_interest - Vec3::new(2.0, 0.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn zoom_moves_a_perspective_eye_and_narrows_an_orthographic_plane() {
        let s = settings();
        let z = s.zoom(0.5);
        assert!((z.position - Vec3::new(0.0, 0.5, -2.5)).length() < 1e-5);
        let o = CameraSettings { projection: Projection::Orthographic, ..s }.zoom(0.5);
        assert_eq!(o.position, s.position);
        assert!(o.fov_y < s.fov_y);
    }

    #[test]
    fn edits_that_would_break_the_camera_are_refused() {
        let s = settings();
        // Eye onto the centre of interest.
        let onto = CameraSettings { position: s.center_of_interest, ..s };
        assert_eq!(s.accept(onto), s);
        // Looking straight down the up vector.
        let down = CameraSettings { position: Vec3::new(0.0, 5.0, 0.0), ..s };
        assert_eq!(s.accept(down), s);
        // Zooming to distance zero.
        assert_eq!(s.zoom(0.0), s);
    }

    #[test]
    fn fov_and_near_are_clamped_to_the_control_ranges() {
        let s = settings();
        let a = s.accept(CameraSettings { fov_y: 500.0, near: -3.0, ..s });
        assert_eq!((a.fov_y, a.near), (*FOV_RANGE.end(), *NEAR_RANGE.start()));
    }
}
