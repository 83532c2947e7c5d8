//! The scene view's observer: a perspective camera apart from the render
//! camera, placed to see the render camera, its view plane and the scene
//! together, and orbited, panned and zoomed by the user with the same pure
//! edits as the render camera ([`CameraSettings::orbit`], `pan`, `zoom`).

use rt_core::{Camera, Projection, Real, Vec3};

use super::camera_controls::CameraSettings;

/// The observer's vertical field of view, degrees.
const OBSERVER_FOV: Real = 50.0;

/// The observer camera of the scene view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observer {
    settings: CameraSettings,
}

impl Observer {
    /// An observer that frames the render `camera` (its eye and centre of
    /// interest) and the scene's bounded objects (`bounds`, min and max
    /// corners, if any): it looks at the middle of them all from beside
    /// and above the render camera (to its right, a little behind), far
    /// enough to see their bounding sphere whole in a view `aspect` (width
    /// / height) wide.
    pub fn framing(camera: &Camera, bounds: Option<(Vec3, Vec3)>, aspect: Real) -> Self {
        let (c, coi) = (camera.position(), camera.center_of_interest());
        let (mut lo, mut hi) = (c.min(coi), c.max(coi));
        if let Some((min, max)) = bounds.filter(|(a, b)| a.is_finite() && b.is_finite()) {
            (lo, hi) = (lo.min(min), hi.max(max));
        }
        let target = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(camera.near() * 4.0).max(1e-3);
        // The narrower of the vertical and horizontal fields of view decides.
        let half_tan = (0.5 * OBSERVER_FOV.to_radians()).tan() * aspect.clamp(0.05, 1.0);
        let distance = radius / half_tan.atan().sin() * 1.1;
        Self::looking_at(camera, target, distance)
    }

    /// An observer `distance` from `target`, looking at it from where
    /// [`Observer::framing`] looks: beside and above the render `camera`
    /// (to its right, a little behind).
    pub fn looking_at(camera: &Camera, target: Vec3, distance: Real) -> Self {
        let b = camera.basis();
        let from =
            (1.0 * b.x + 0.7 * camera.up().normalize_or_zero() - 0.6 * b.z).try_normalize().unwrap_or(b.x);
        let settings = CameraSettings {
            position: target + distance * from,
            center_of_interest: target,
            up: camera.up(),
            fov_y: OBSERVER_FOV,
            near: distance * 1e-3,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus_distance: 1.0,
        };
        // A degenerate view (up along it) falls back to a side view.
        let settings = if settings.to_camera().is_ok() {
            settings
        } else {
            CameraSettings { position: target + distance * b.x, ..settings }
        };
        Self { settings }
    }

    /// The observer as an rt-core camera.
    pub fn camera(&self) -> Option<Camera> {
        self.settings.to_camera().ok()
    }

    /// The observer's settings (eye, target, field of view).
    pub fn settings(&self) -> &CameraSettings {
        &self.settings
    }

    /// Orbits about the target: `yaw` radians about up, `pitch` towards up.
    pub fn orbit(&mut self, yaw: Real, pitch: Real) {
        self.settings = self.settings.orbit(yaw, pitch);
        self.keep_near();
    }

    /// Pans by `right` and `up` screen heights (fractions of the view's
    /// height at the target).
    pub fn pan(&mut self, right: Real, up: Real) {
        let h = self.settings.view_height();
        self.settings = self.settings.pan(right * h, up * h);
    }

    /// Zooms by `factor` (< 1 is closer) towards the target.
    pub fn zoom(&mut self, factor: Real) {
        self.settings = self.settings.zoom(factor);
        self.keep_near();
    }

    /// `near` stays a small fraction of the distance to the target, so
    /// nothing in view is clipped and the view plane stays representable.
    fn keep_near(&mut self) {
        let distance = (self.settings.position - self.settings.center_of_interest).length();
        let near = distance * 1e-3;
        self.settings = self.settings.accept(CameraSettings { near, ..self.settings });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn render_camera() -> Camera {
        Camera::new(Vec3::new(0.0, 1.0, -6.0), Vec3::ZERO, Vec3::Y, 40.0, 1.0, Projection::Perspective)
            .unwrap()
    }

    #[test]
    fn the_first_observer_sees_the_render_camera_and_the_scene() {
        let camera = render_camera();
        let bounds = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let o = Observer::framing(&camera, Some(bounds), 0.5);
        let view = rt_core::ViewPlane::new(o.camera().unwrap(), 200, 400).unwrap();
        let p = super::super::projection::Projection::new(
            *view.camera(),
            [200, 400],
            egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(200.0, 400.0)),
        )
        .unwrap();
        for point in [camera.position(), camera.center_of_interest(), bounds.0, bounds.1] {
            let [x, y] = p.pixel_of(point).expect("in front of the observer");
            assert!((0.0..200.0).contains(&x) && (0.0..400.0).contains(&y), "{point} at {x}, {y}");
        }
    }

    #[test]
    fn orbiting_and_zooming_move_the_observer_and_keep_its_target() {
        let mut o = Observer::framing(&render_camera(), None, 1.5);
        let before = *o.settings();
        o.orbit(0.5, 0.2);
        assert_ne!(o.settings().position, before.position);
        assert_eq!(o.settings().center_of_interest, before.center_of_interest);
        let d = |s: &CameraSettings| (s.position - s.center_of_interest).length();
        let distance = d(o.settings());
        o.zoom(0.5);
        assert!((d(o.settings()) - 0.5 * distance).abs() < 1e-3 * distance);
        assert!((o.settings().near - d(o.settings()) * 1e-3).abs() < 1e-6);
        o.pan(0.1, 0.0);
        assert_ne!(o.settings().center_of_interest, before.center_of_interest);
    }
}
