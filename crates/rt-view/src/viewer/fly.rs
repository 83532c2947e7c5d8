//! Fly navigation: moving the eye through the scene with the keyboard and
//! turning the view with the mouse, as pure functions on [`CameraSettings`].
//!
//! W/S move along the view direction, A/D along the camera's right (cam_x),
//! Q/E down and up along the world up vector; Shift moves
//! [`FAST`] times faster. The speed follows the scene's size, so crossing
//! the scene takes about [`CROSSING_SECONDS`] whatever its units. Dragging
//! the mouse turns the view: yaw about the world up, pitch towards it,
//! stopping [`MIN_POLAR_DEGREES`] short of looking straight up or down.
//! The centre of interest moves with the eye at the same distance, so the
//! camera stays a valid C/COI/up camera and orbiting afterwards turns about
//! a point in front of the eye.

use rt_core::{Real, Vec3};

use super::camera_controls::{CameraSettings, MIN_POLAR_DEGREES};

/// How many times faster Shift moves.
pub const FAST: Real = 4.0;
/// Seconds to cross the scene's bounding box at normal speed.
pub const CROSSING_SECONDS: Real = 4.0;
/// Radians of turn per point of mouse movement.
pub const LOOK_PER_POINT: f32 = 0.004;
/// The longest frame step a held key moves by, seconds: a stalled frame
/// does not throw the camera across the scene.
const MAX_STEP_SECONDS: f32 = 0.1;

/// Which fly keys are held: each axis −1, 0 or 1.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FlyKeys {
    /// D minus A.
    pub right: Real,
    /// E minus Q.
    pub up: Real,
    /// W minus S.
    pub forward: Real,
    /// Shift is held.
    pub fast: bool,
}

impl FlyKeys {
    /// The fly keys held in `input`; none while Ctrl (or Cmd) or Alt is
    /// held, so that Ctrl+S saves rather than moves.
    pub fn held(input: &egui::InputState) -> Self {
        if input.modifiers.command || input.modifiers.ctrl || input.modifiers.alt {
            return Self::default();
        }
        let axis = |plus, minus| {
            let down = |k| if input.key_down(k) { 1.0 } else { 0.0 };
            down(plus) - down(minus)
        };
        use egui::Key;
        Self {
            right: axis(Key::D, Key::A),
            up: axis(Key::E, Key::Q),
            forward: axis(Key::W, Key::S),
            fast: input.modifiers.shift,
        }
    }

    /// Whether any movement key is held.
    pub fn moving(&self) -> bool {
        self.right != 0.0 || self.up != 0.0 || self.forward != 0.0
    }
}

/// The seconds a frame of `dt` moves by (at most [`MAX_STEP_SECONDS`]).
pub fn step_seconds(dt: f32) -> Real {
    dt.clamp(0.0, MAX_STEP_SECONDS) as Real
}

/// Fly speed, world units per second, in a scene `scene_size` across (the
/// diagonal of its bounded objects' box); without one, the eye's distance
/// to the centre of interest stands in for it.
pub fn speed(scene_size: Option<Real>, camera: &CameraSettings) -> Real {
    let size = scene_size
        .filter(|s| *s > 0.0 && s.is_finite())
        .unwrap_or_else(|| (camera.position - camera.center_of_interest).length());
    size / CROSSING_SECONDS
}

/// The diagonal of the box around the scene's bounded objects (planes are
/// unbounded and left out); `None` if there is none.
pub fn scene_size(scene: &rt_core::Scene) -> Option<Real> {
    let bounds = scene.objects().iter().filter_map(|o| o.primitive.bounds()).reduce(|a, b| a.union(b))?;
    Some((bounds.max() - bounds.min()).length())
}

/// The camera moved `distance` world units in the direction of `keys`
/// (diagonals no faster than straight moves, Shift [`FAST`] times farther).
/// Eye and centre of interest move together.
pub fn fly(camera: &CameraSettings, keys: FlyKeys, distance: Real) -> CameraSettings {
    let Ok(c) = camera.to_camera() else { return *camera };
    let b = c.basis();
    let up = camera.up.normalize_or_zero();
    let forward = (camera.center_of_interest - camera.position).normalize_or_zero();
    let direction = (keys.right * b.x + keys.up * up + keys.forward * forward).normalize_or_zero();
    let distance = if keys.fast { distance * FAST } else { distance };
    let shift = direction * distance;
    camera.accept(CameraSettings {
        position: camera.position + shift,
        center_of_interest: camera.center_of_interest + shift,
        ..*camera
    })
}

/// The view turned from the eye: `yaw` radians about the world up (positive
/// turns right), `pitch` radians towards up (positive looks up), the angle
/// to ±up kept at least [`MIN_POLAR_DEGREES`]. The eye stays; the centre of
/// interest keeps its distance.
pub fn look(camera: &CameraSettings, yaw: Real, pitch: Real) -> CameraSettings {
    let up = camera.up.normalize_or_zero();
    let offset = camera.center_of_interest - camera.position;
    let distance = offset.length();
    let along = offset.dot(up);
    let Some(heading) = (offset - along * up).try_normalize() else { return *camera };
    // up × heading is the camera's right in the left-handed world.
    let heading = heading * yaw.cos() + up.cross(heading) * yaw.sin();
    let min_polar = MIN_POLAR_DEGREES.to_radians();
    let polar = (along / distance).clamp(-1.0, 1.0).acos();
    let polar = (polar - pitch).clamp(min_polar, std::f64::consts::PI as Real - min_polar);
    let direction: Vec3 = polar.cos() * up + polar.sin() * heading;
    camera.accept(CameraSettings { center_of_interest: camera.position + distance * direction, ..*camera })
}

#[cfg(test)]
mod tests {
    use rt_core::Projection;

    use super::*;

    fn settings() -> CameraSettings {
        CameraSettings {
            position: Vec3::new(0.0, 1.0, -5.0),
            center_of_interest: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y: 45.0,
            near: 1.0,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-4
    }

    #[test]
    fn w_moves_eye_and_centre_of_interest_forward_and_d_to_the_right() {
        let s = settings();
        let forward = fly(&s, FlyKeys { forward: 1.0, ..Default::default() }, 2.0);
        assert!(close(forward.position, Vec3::new(0.0, 1.0, -3.0)), "{forward:?}");
        assert!(close(forward.center_of_interest, Vec3::new(0.0, 1.0, 2.0)));
        // Left-handed, +y up, looking along +z: right is +x.
        let right = fly(&s, FlyKeys { right: 1.0, ..Default::default() }, 2.0);
        assert!(close(right.position, Vec3::new(2.0, 1.0, -5.0)), "{right:?}");
        let up = fly(&s, FlyKeys { up: -1.0, fast: true, ..Default::default() }, 0.5);
        assert!(close(up.position, Vec3::new(0.0, -1.0, -5.0)), "{up:?}");
        // A diagonal is no faster.
        let diagonal = fly(&s, FlyKeys { forward: 1.0, right: 1.0, ..Default::default() }, 2.0);
        assert!(((diagonal.position - s.position).length() - 2.0).abs() < 1e-4);
    }

    #[test]
    fn looking_turns_about_the_eye_and_keeps_the_distance() {
        let s = settings();
        let right = look(&s, std::f64::consts::FRAC_PI_2 as Real, 0.0);
        assert_eq!(right.position, s.position);
        assert!(close(right.center_of_interest, Vec3::new(5.0, 1.0, -5.0)), "{right:?}");
        let up = look(&s, 0.0, 0.3);
        assert!(up.center_of_interest.y > s.center_of_interest.y);
        assert!(((up.center_of_interest - up.position).length() - 5.0).abs() < 1e-4);
    }

    #[test]
    fn looking_up_stops_short_of_the_pole_and_the_camera_stays_valid() {
        let mut s = settings();
        for _ in 0..100 {
            s = look(&s, 0.01, 0.2);
            assert!(s.to_camera().is_ok());
        }
        let view = (s.center_of_interest - s.position).normalize();
        let to_up = view.dot(Vec3::Y).clamp(-1.0, 1.0).acos().to_degrees();
        assert!((to_up - MIN_POLAR_DEGREES).abs() < 0.01, "{to_up}");
        // Moving forward still works, looking almost straight up.
        let moved = fly(&s, FlyKeys { forward: 1.0, ..Default::default() }, 1.0);
        assert!(moved.position.y > s.position.y + 0.99);
    }

    #[test]
    fn the_speed_follows_the_scene_size_and_a_long_frame_moves_a_bounded_step() {
        let s = settings();
        assert_eq!(speed(Some(40.0), &s), 40.0 / CROSSING_SECONDS);
        assert_eq!(speed(None, &s), 5.0 / CROSSING_SECONDS);
        assert_eq!(speed(Some(Real::INFINITY), &s), 5.0 / CROSSING_SECONDS);
        assert_eq!(step_seconds(3.0), MAX_STEP_SECONDS as Real);
        let scene = rt_core::load_scene(
            &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/box.ron"),
        )
        .unwrap();
        // Boxes from (-1, 0, -2) to (2.5, 2, 2).
        let size = scene_size(&scene.scene).unwrap();
        assert!((size - Vec3::new(3.5, 2.0, 4.0).length()).abs() < 1e-4, "{size}");
    }
}
