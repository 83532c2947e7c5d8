//! The viewer's camera edits: sliders, orbit, pan and zoom, as pure functions.
//!
//! Every edit goes through [`CameraSettings::accept`]: an edit that would make
//! the camera degenerate (`docs/conventions.md`) is refused and the previous
//! camera kept, so the viewer can never produce NaN or a flipped image. Orbiting also keeps
//! the view direction at least [`MIN_POLAR_DEGREES`] away from the up vector.

use std::ops::RangeInclusive;

use rt_core::camera::Lens;
use rt_core::{Camera, CameraError, Projection, Real, Vec3};

/// Range of the vertical field-of-view slider, degrees.
pub const FOV_RANGE: RangeInclusive<Real> = 1.0..=179.0;
/// Range of the near-distance control, world units.
pub const NEAR_RANGE: RangeInclusive<Real> = 1e-3..=1e4;
/// Range of the aperture (lens radius) control, world units; 0 is the
/// pinhole.
pub const APERTURE_RANGE: RangeInclusive<Real> = 0.0..=10.0;
/// Orbiting stops this close (degrees) to looking straight along ±up.
pub const MIN_POLAR_DEGREES: Real = 1.0;

/// The editable camera parameters (remembered between runs as they are
/// named here, see `remembered.rs`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
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
    /// Lens radius, world units; 0 is the pinhole (absent in state
    /// remembered before the lens was editable: a pinhole).
    #[serde(default)]
    pub aperture: Real,
    /// Distance along cam_z of the plane in focus, world units (used only
    /// when `aperture` is above 0).
    #[serde(default = "unit_focus_distance")]
    pub focus_distance: Real,
}

/// The pinhole's focus distance, as [`Lens::PINHOLE`] has it.
fn unit_focus_distance() -> Real {
    Lens::PINHOLE.focus_distance
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
            aperture: c.lens().radius,
            focus_distance: c.lens().focus_distance,
        }
    }

    /// The camera these settings describe, lens included, or why there is
    /// none. A pinhole's focus distance is kept as it is (it is never
    /// used), as the scene loader keeps it.
    pub fn to_camera(&self) -> Result<Camera, CameraError> {
        let camera = Camera::new(
            self.position,
            self.center_of_interest,
            self.up,
            self.fov_y,
            self.near,
            self.projection,
        )?;
        let lens = if self.aperture == 0.0 {
            Lens { focus_distance: self.focus_distance, ..Lens::PINHOLE }
        } else {
            Lens::new(self.aperture, self.focus_distance)?
        };
        Ok(camera.with_lens(lens))
    }

    /// `candidate` with fov, near and aperture clamped to the control ranges if that
    /// makes a valid camera, else `self` unchanged.
    pub fn accept(&self, candidate: Self) -> Self {
        let clamped = Self {
            fov_y: candidate.fov_y.clamp(*FOV_RANGE.start(), *FOV_RANGE.end()),
            near: candidate.near.clamp(*NEAR_RANGE.start(), *NEAR_RANGE.end()),
            aperture: candidate.aperture.clamp(*APERTURE_RANGE.start(), *APERTURE_RANGE.end()),
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
        self.view_height() / height.max(1.0)
    }

    /// How tall the view is at the centre of interest, in world units: the
    /// height of what a perspective camera sees at the COI's distance D
    /// (`2·D·tan(fov_y/2)`), and of everything an orthographic camera sees
    /// (its view plane, `2·near·tan(fov_y/2)`).
    pub fn view_height(&self) -> Real {
        let tan = (0.5 * self.fov_y.to_radians()).tan();
        match self.projection {
            Projection::Perspective => 2.0 * (self.position - self.center_of_interest).length() * tan,
            Projection::Orthographic => 2.0 * self.near * tan,
        }
    }

    /// The same camera with the view `height` world units tall at the centre
    /// of interest ([`CameraSettings::view_height`]): the field of view is
    /// chosen for it; an orthographic camera whose field of view would pass
    /// the largest one moves its view plane out instead (its rays start
    /// there). Refused (self unchanged) if no valid camera has it.
    pub fn with_view_height(&self, height: Real) -> Self {
        if !(height > 0.0 && height.is_finite()) {
            return *self;
        }
        let max_half = (0.5 * FOV_RANGE.end().to_radians()).tan();
        let (distance, near) = match self.projection {
            Projection::Perspective => ((self.position - self.center_of_interest).length(), self.near),
            Projection::Orthographic => {
                let near = self.near.max(0.5 * height / max_half);
                (near, near)
            }
        };
        let fov_y = 2.0 * (0.5 * height / distance).atan().to_degrees();
        self.accept(Self { fov_y, near, ..*self })
    }

    /// The camera moved so that a sphere of `radius` about `center` fills
    /// the view of an image `aspect` (width / height) wide, looking the same
    /// way, the centre of interest on the sphere's centre. Perspective: the
    /// eye backs off until the sphere touches the narrower of the vertical
    /// and horizontal fields of view (distance `radius / sin(half angle)`).
    /// Orthographic: the view is made as tall as the sphere (or as wide, on
    /// a portrait image), the eye placed so that its view plane, where rays
    /// start, is in front of the sphere. Refused (self unchanged) if no
    /// valid camera does it.
    pub fn framing(&self, center: Vec3, radius: Real, aspect: Real) -> Self {
        let Some(direction) = (self.center_of_interest - self.position).try_normalize() else { return *self };
        if !(radius > 0.0 && radius.is_finite() && aspect > 0.0 && aspect.is_finite()) {
            return *self;
        }
        match self.projection {
            Projection::Perspective => {
                let half_y = 0.5 * self.fov_y.to_radians();
                let half_x = (aspect * half_y.tan()).atan();
                let distance = radius / half_y.min(half_x).sin();
                self.accept(Self {
                    position: center - distance * direction,
                    center_of_interest: center,
                    ..*self
                })
            }
            Projection::Orthographic => {
                let sized = self.with_view_height(2.0 * radius * Real::max(1.0, 1.0 / aspect));
                let distance = sized.near + 1.01 * radius;
                self.accept(Self {
                    position: center - distance * direction,
                    center_of_interest: center,
                    ..sized
                })
            }
        }
    }

    /// The same view in another projection: what is in view at the centre
    /// of interest stays in view ([`CameraSettings::view_height`] is kept).
    pub fn with_projection(&self, projection: Projection) -> Self {
        if projection == self.projection {
            return *self;
        }
        Self { projection, ..*self }.with_view_height(self.view_height())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switching_projection_keeps_what_is_in_view_at_the_centre_of_interest() {
        let s = settings();
        let h = s.view_height();
        for p in [Projection::Orthographic, Projection::Perspective] {
            let switched = s.with_projection(Projection::Orthographic).with_projection(p);
            assert!(
                (switched.view_height() - h).abs() < 1e-4 * h,
                "{p:?}: {} vs {h}",
                switched.view_height()
            );
            assert_eq!(switched.projection, p);
        }
        // Before, an orthographic camera with the perspective camera's near
        // and fov saw only its near plane's height.
        let ortho = s.with_projection(Projection::Orthographic);
        assert!(ortho.to_camera().is_ok());
        assert!((ortho.view_height() - h).abs() < 1e-4 * h);
    }

    #[test]
    fn a_wide_orthographic_view_moves_its_plane_out_rather_than_passing_the_widest_fov() {
        let ortho = CameraSettings { projection: Projection::Orthographic, near: 0.01, ..settings() };
        let wide = ortho.with_view_height(1000.0);
        assert!((wide.view_height() - 1000.0).abs() < 0.5, "{}", wide.view_height());
        assert!(wide.fov_y <= *FOV_RANGE.end() && wide.near > 0.01);
        assert_eq!(ortho.with_view_height(-1.0), ortho, "refused");
    }

    fn settings() -> CameraSettings {
        CameraSettings {
            position: Vec3::new(0.0, 1.0, -5.0),
            center_of_interest: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 45.0,
            near: 1.0,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus_distance: 1.0,
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
    fn framing_fits_the_sphere_to_the_narrower_field_of_view_and_keeps_the_view_direction() {
        let s = settings();
        let direction = (s.center_of_interest - s.position).normalize();
        let center = Vec3::new(3.0, 1.0, 2.0);
        let half_y = (0.5 * s.fov_y).to_radians();
        for aspect in [2.0, 0.5] {
            let f = s.framing(center, 1.5, aspect);
            assert_eq!(f.center_of_interest, center);
            let view = (f.center_of_interest - f.position).normalize();
            assert!((view - direction).length() < 1e-5, "{aspect}: {view}");
            // The sphere's edge is at the narrower half angle from the view direction.
            let half = if aspect >= 1.0 { half_y } else { (aspect * half_y.tan()).atan() };
            let distance = (f.position - center).length();
            assert!((1.5 / distance - half.sin()).abs() < 1e-5, "{aspect}: {distance}");
        }
        let ortho = CameraSettings { projection: Projection::Orthographic, ..s };
        let f = ortho.framing(center, 1.5, 0.5);
        assert!((f.view_height() - 6.0).abs() < 1e-3, "{}", f.view_height());
        // The view plane (where rays start) is in front of the sphere.
        assert!((f.position - center).length() - f.near > 1.5);
        assert_eq!(s.framing(center, 0.0, 1.0), s, "refused");
    }

    #[test]
    fn fov_and_near_are_clamped_to_the_control_ranges() {
        let s = settings();
        let a = s.accept(CameraSettings { fov_y: 500.0, near: -3.0, ..s });
        assert_eq!((a.fov_y, a.near), (*FOV_RANGE.end(), *NEAR_RANGE.start()));
    }
}
