//! Camera space: the camera's axes from position C, centre of interest COI and up.
//!
//! World space is left-handed: +x right, +y up, +z into the screen. With `×`
//! the usual component formula,
//!
//! ```text
//! cam_z = normalize(COI − C)        looking direction
//! cam_x = normalize(up × cam_z)     right
//! cam_y = cam_z × cam_x             true up
//! ```
//!
//! so C = (0,0,0), COI = (0,0,1), up = (0,1,0) gives cam_x = (1,0,0),
//! cam_y = (0,1,0), cam_z = (0,0,1).

pub mod view_plane;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::math::real::{MIN_UP_SINE, Real, Vec3, normalize_robust};

/// How primary rays leave the view plane.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Projection {
    /// Rays start at the eye C and pass through the pixel's view-plane point.
    #[default]
    Perspective,
    /// Rays start at the pixel's view-plane point and travel along cam_z.
    Orthographic,
}

/// Why a camera cannot be built. Each names the scene-file field at fault.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum CameraError {
    /// A coordinate or parameter is NaN or infinite.
    #[error("camera.{field} must be finite")]
    NotFinite {
        /// The offending field.
        field: &'static str,
    },
    /// C and COI coincide (to within rounding at their magnitude).
    #[error("camera.center_of_interest coincides with camera.position: there is no viewing direction")]
    NoViewDirection,
    /// `up` is zero or (nearly) parallel to the viewing direction.
    #[error(
        "camera.up is zero or parallel to the viewing direction (center_of_interest - position): \
         the camera's roll is undefined"
    )]
    UpParallelToView,
    /// `fov_y` is not strictly between 0 and 180 degrees.
    #[error("camera.fov_y must be strictly between 0 and 180 degrees, got {0}")]
    FovOutOfRange(Real),
    /// `near` is not a positive finite number.
    #[error("camera.near must be a positive finite number, got {0}")]
    NearNotPositive(Real),
    /// `aperture` is negative or not finite.
    #[error("camera.aperture (the lens radius, world units) must be 0 or a positive finite number, got {0}")]
    ApertureNotValid(Real),
    /// `focus_distance` is not a positive finite number.
    #[error("camera.focus_distance must be a positive finite number, got {0}")]
    FocusDistanceNotPositive(Real),
    /// The view plane would be too small or too large to represent.
    #[error(
        "camera.fov_y = {fov_y} with camera.near = {near} gives a view plane of height {height}, which cannot be represented"
    )]
    ViewPlaneUnrepresentable {
        /// Vertical field of view, degrees.
        fov_y: Real,
        /// Near distance.
        near: Real,
        /// The computed plane height.
        height: Real,
    },
}

/// An orthonormal camera frame (left-handed: `cam_y = cam_z × cam_x`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraBasis {
    /// Right.
    pub x: Vec3,
    /// True up.
    pub y: Vec3,
    /// Looking direction.
    pub z: Vec3,
}

impl CameraBasis {
    /// The basis of a camera at `position` looking at `center_of_interest`
    /// with the general `up` vector, or why there is none.
    pub fn new(position: Vec3, center_of_interest: Vec3, up: Vec3) -> Result<Self, CameraError> {
        check_finite("position", position)?;
        check_finite("center_of_interest", center_of_interest)?;
        check_finite("up", up)?;
        let view = center_of_interest - position;
        // Coordinates that differ by a few ulps give a direction made of rounding noise.
        let scale = position.abs().max_element().max(center_of_interest.abs().max_element());
        if view.abs().max_element() <= 8.0 * Real::EPSILON * scale {
            return Err(CameraError::NoViewDirection);
        }
        let z = normalize_robust(view).ok_or(CameraError::NoViewDirection)?;
        let up = normalize_robust(up).ok_or(CameraError::UpParallelToView)?;
        let right = up.cross(z);
        if right.length() < MIN_UP_SINE {
            return Err(CameraError::UpParallelToView);
        }
        // up × cam_z has rounding errors of about ε per component, which
        // near the threshold is ε/sin relative: enough to tilt cam_x out of
        // the plane across cam_z by 10⁻³ rad in f32. What of it lies along
        // cam_z is removed (one Gram–Schmidt step, no change in exact
        // arithmetic), so the basis is orthonormal to a few ε at any angle
        // accepted; only its roll keeps the ε/sin uncertainty of `up` itself.
        let x = right.reject_from_normalized(z).normalize();
        let y = z.cross(x);
        Ok(Self { x, y, z })
    }
}

/// A validated camera: every field finite, a well-defined basis, and a view
/// plane that can be represented.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Camera {
    position: Vec3,
    center_of_interest: Vec3,
    up: Vec3,
    fov_y: Real,
    near: Real,
    projection: Projection,
    basis: CameraBasis,
    lens: Lens,
}

/// A thin lens (pbrt-v4 §5.2.3; Kolb, Mitchell and Hanrahan, "A Realistic
/// Camera Model for Computer Graphics", 1995): a disc of radius `radius`
/// (world units, the scene file's `aperture`) centred on the eye C across
/// cam_z, that brings the plane at `focus_distance` along cam_z into focus.
/// Radius 0 is the pinhole.
///
/// A point at distance d along cam_z is seen, through a lens of radius A
/// focused at f, as a disc on the view plane (at `near`) of diameter
/// `c = 2A · near · |d − f| / (f · d)`: the thin-lens circle of confusion
/// with `near` as the image distance ([`Lens::circle_of_confusion`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Lens {
    /// Lens radius A, world units, ≥ 0 (0: a pinhole).
    pub radius: Real,
    /// Distance f along cam_z of the plane in focus, world units, > 0.
    pub focus_distance: Real,
}

impl Lens {
    /// The pinhole: no lens; its focus distance (1) is never used.
    pub const PINHOLE: Self = Self { radius: 0.0, focus_distance: 1.0 };

    /// A lens of radius `radius` focused at `focus_distance`, or which of
    /// the two is out of range.
    pub fn new(radius: Real, focus_distance: Real) -> Result<Self, CameraError> {
        if !(radius >= 0.0 && radius.is_finite()) {
            return Err(CameraError::ApertureNotValid(radius));
        }
        if !(focus_distance > 0.0 && focus_distance.is_finite()) {
            return Err(CameraError::FocusDistanceNotPositive(focus_distance));
        }
        Ok(Self { radius, focus_distance })
    }

    /// Whether rays depend on the lens position (radius > 0).
    pub fn is_thin_lens(&self) -> bool {
        self.radius > 0.0
    }

    /// The diameter, on a view plane at distance `near`, of the image of a
    /// point at distance `depth` along cam_z: `2A · near · |d − f| / (f · d)`
    /// (similar triangles through the lens: the cone of rays from the lens
    /// disc to the focused point, cut at `depth` and projected through C).
    pub fn circle_of_confusion(&self, depth: Real, near: Real) -> Real {
        let f = self.focus_distance;
        2.0 * self.radius * near * (depth - f).abs() / (f * depth)
    }
}

impl Camera {
    /// A camera at `position` (C) looking at `center_of_interest` (COI), with
    /// the general `up` vector, vertical field of view `fov_y` in degrees and
    /// view-plane distance `near` in world units.
    pub fn new(
        position: Vec3,
        center_of_interest: Vec3,
        up: Vec3,
        fov_y: Real,
        near: Real,
        projection: Projection,
    ) -> Result<Self, CameraError> {
        let basis = CameraBasis::new(position, center_of_interest, up)?;
        if !fov_y.is_finite() {
            return Err(CameraError::NotFinite { field: "fov_y" });
        }
        if !(fov_y > 0.0 && fov_y < 180.0) {
            return Err(CameraError::FovOutOfRange(fov_y));
        }
        if !(near > 0.0 && near.is_finite()) {
            return Err(CameraError::NearNotPositive(near));
        }
        let camera =
            Self { position, center_of_interest, up, fov_y, near, projection, basis, lens: Lens::PINHOLE };
        let height = camera.view_plane_height();
        // tan of an angle that rounds to π/2 is huge or negative; tiny angles underflow.
        if !(height.is_normal() && height > 0.0) {
            return Err(CameraError::ViewPlaneUnrepresentable { fov_y, near, height });
        }
        Ok(camera)
    }

    /// Eye position C.
    pub fn position(&self) -> Vec3 {
        self.position
    }
    /// Centre of interest COI.
    pub fn center_of_interest(&self) -> Vec3 {
        self.center_of_interest
    }
    /// The general up vector as given (not the true up: see [`CameraBasis::y`]).
    pub fn up(&self) -> Vec3 {
        self.up
    }
    /// Vertical field of view in degrees, in (0, 180).
    pub fn fov_y(&self) -> Real {
        self.fov_y
    }
    /// Distance from C to the view plane along cam_z, world units, > 0.
    pub fn near(&self) -> Real {
        self.near
    }
    /// Perspective or orthographic.
    pub fn projection(&self) -> Projection {
        self.projection
    }
    /// The camera's axes.
    pub fn basis(&self) -> CameraBasis {
        self.basis
    }
    /// `plane_h = 2 · near · tan(fov_y / 2)`, world units.
    pub fn view_plane_height(&self) -> Real {
        2.0 * self.near * (0.5 * self.fov_y).to_radians().tan()
    }

    /// The lens (radius 0: the pinhole).
    pub fn lens(&self) -> Lens {
        self.lens
    }

    /// The same camera seen through `lens`.
    pub fn with_lens(mut self, lens: Lens) -> Self {
        self.lens = lens;
        self
    }

    /// The same camera with another projection.
    pub fn with_projection(mut self, projection: Projection) -> Self {
        self.projection = projection;
        self
    }
}

fn check_finite(field: &'static str, v: Vec3) -> Result<(), CameraError> {
    if v.is_finite() { Ok(()) } else { Err(CameraError::NotFinite { field }) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_close(a: Vec3, b: Vec3) {
        assert!((a - b).abs().max_element() < 1e-6, "{a} != {b}");
    }

    fn camera(c: Vec3, coi: Vec3, up: Vec3) -> Result<Camera, CameraError> {
        Camera::new(c, coi, up, 60.0, 1.0, Projection::Perspective)
    }

    #[test]
    fn axis_aligned_camera_has_the_world_axes_in_a_left_handed_world() {
        let b = CameraBasis::new(Vec3::ZERO, Vec3::Z, Vec3::Y).unwrap();
        assert_eq!((b.x, b.y, b.z), (Vec3::X, Vec3::Y, Vec3::Z));
    }

    #[test]
    fn camera_looking_down_minus_z_has_right_pointing_to_minus_x() {
        // up × cam_z = (0,1,0) × (0,0,−1) = (1·(−1) − 0·0, 0·0 − 0·(−1), 0) = (−1, 0, 0).
        let b = CameraBasis::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y).unwrap();
        assert_close(b.x, -Vec3::X);
        assert_close(b.y, Vec3::Y);
        assert_close(b.z, -Vec3::Z);
    }

    #[test]
    fn oblique_camera_gets_an_orthonormal_basis_with_true_up_in_the_up_plane() {
        // C = (1,2,3), COI = (4,−2,3): view = (3,−4,0), cam_z = (0.6,−0.8,0).
        // up = (0,1,0): up × cam_z = (1·0 − 0·(−0.8), 0·0.6 − 0·0, 0·(−0.8) − 1·0.6) = (0,0,−0.6)
        // → cam_x = (0,0,−1); cam_y = cam_z × cam_x = ((−0.8)(−1) − 0, 0 − 0.6·(−1), 0) = (0.8,0.6,0).
        let b = CameraBasis::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, -2.0, 3.0), Vec3::Y).unwrap();
        assert_close(b.z, Vec3::new(0.6, -0.8, 0.0));
        assert_close(b.x, Vec3::new(0.0, 0.0, -1.0));
        assert_close(b.y, Vec3::new(0.8, 0.6, 0.0));
    }

    #[test]
    fn a_general_up_vector_only_needs_to_lean_the_right_way() {
        // A tilted up vector gives the same frame as the pure one when it lies
        // in the plane spanned by true up and the view direction.
        let a = CameraBasis::new(Vec3::ZERO, Vec3::Z, Vec3::Y).unwrap();
        let b = CameraBasis::new(Vec3::ZERO, Vec3::Z, Vec3::new(0.0, 2.0, -5.0)).unwrap();
        assert_close(a.x, b.x);
        assert_close(a.y, b.y);
    }

    #[test]
    fn up_parallel_to_the_view_direction_is_refused() {
        for up in [Vec3::Z, -Vec3::Z * 3.0, Vec3::new(1e-6, 0.0, 1.0), Vec3::ZERO] {
            assert_eq!(camera(Vec3::ZERO, Vec3::Z, up), Err(CameraError::UpParallelToView));
        }
    }

    #[test]
    fn position_equal_to_center_of_interest_is_refused_at_any_magnitude() {
        for p in [Vec3::ZERO, Vec3::splat(1e6), Vec3::new(-3.0, 1e-30, 7.0)] {
            assert_eq!(camera(p, p, Vec3::Y), Err(CameraError::NoViewDirection));
        }
        // One ulp apart at 1e6 is rounding noise, not a direction.
        let p = Vec3::splat(1e6);
        let q = Vec3::new(Real::from_bits(p.x.to_bits() + 1), p.y, p.z);
        assert_eq!(camera(p, q, Vec3::Y), Err(CameraError::NoViewDirection));
    }

    #[test]
    fn cameras_at_extreme_but_representable_scales_are_accepted() {
        // Far from the origin, tiny, and with a huge up vector: all valid.
        assert!(camera(Vec3::new(0.0, 0.0, -1e20), Vec3::ZERO, Vec3::Y).is_ok());
        assert!(camera(Vec3::new(0.0, 0.0, -1e-7), Vec3::ZERO, Vec3::Y).is_ok());
        assert!(camera(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, Vec3::new(0.0, 1e20, 0.0)).is_ok());
        assert!(camera(Vec3::new(0.0, 0.0, -5.0), Vec3::ZERO, Vec3::new(0.0, 1e-30, 0.0)).is_ok());
    }

    #[test]
    fn fov_outside_the_open_range_0_to_180_is_refused() {
        for fov in [0.0, -10.0, 180.0, 200.0] {
            let r = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, fov, 1.0, Projection::Perspective);
            assert_eq!(r, Err(CameraError::FovOutOfRange(fov)));
        }
        let r = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, Real::NAN, 1.0, Projection::Perspective);
        assert_eq!(r, Err(CameraError::NotFinite { field: "fov_y" }));
    }

    #[test]
    fn fov_just_inside_the_range_gives_a_finite_positive_plane_or_an_error() {
        for fov in [1e-30, 1e-6, 179.9999, 180.0 - 180.0 * Real::EPSILON] {
            match Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, fov, 1.0, Projection::Perspective) {
                Ok(c) => {
                    let h = c.view_plane_height();
                    assert!(h.is_finite() && h > 0.0, "fov {fov}: plane height {h}");
                }
                Err(e) => assert!(matches!(e, CameraError::ViewPlaneUnrepresentable { .. })),
            }
        }
    }

    #[test]
    fn near_must_be_positive_and_finite() {
        for near in [0.0, -1.0, Real::INFINITY, Real::NAN] {
            let r = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0, near, Projection::Perspective);
            assert!(matches!(r, Err(CameraError::NearNotPositive(_))), "{near}: {r:?}");
        }
    }

    #[test]
    fn non_finite_coordinates_name_their_field() {
        let nan = Vec3::new(Real::NAN, 0.0, 0.0);
        assert_eq!(camera(nan, Vec3::Z, Vec3::Y), Err(CameraError::NotFinite { field: "position" }));
        assert_eq!(
            camera(Vec3::ZERO, Vec3::Z, Vec3::splat(Real::INFINITY)),
            Err(CameraError::NotFinite { field: "up" })
        );
    }

    #[test]
    fn a_camera_keeps_the_fields_it_was_given() {
        let (c, coi, up) = (Vec3::new(1.0, 2.0, -3.0), Vec3::new(0.5, -1.0, 4.0), Vec3::new(0.1, 1.0, 0.2));
        let cam = Camera::new(c, coi, up, 37.5, 0.25, Projection::Orthographic).unwrap();
        assert_eq!((cam.position(), cam.center_of_interest(), cam.up()), (c, coi, up));
        assert_eq!((cam.fov_y(), cam.near()), (37.5, 0.25));
        assert_eq!(cam.projection(), Projection::Orthographic);
        assert_eq!(cam.basis(), CameraBasis::new(c, coi, up).unwrap());
    }

    #[test]
    fn view_plane_height_follows_the_tangent_formula() {
        // fov 90°, near 2: h = 2·2·tan 45° = 4.
        let c = Camera::new(Vec3::ZERO, Vec3::Z, Vec3::Y, 90.0, 2.0, Projection::Perspective).unwrap();
        assert!((c.view_plane_height() - 4.0).abs() < 1e-5);
    }

    proptest::proptest! {
        #[test]
        fn any_camera_is_either_refused_or_orthonormal_and_left_handed(
            c in proptest::array::uniform3(-1e4f32..1e4),
            coi in proptest::array::uniform3(-1e4f32..1e4),
            up in proptest::array::uniform3(-1f32..1.0),
        ) {
            let v = |a: [f32; 3]| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
            if let Ok(b) = CameraBasis::new(v(c), v(coi), v(up)) {
                for axis in [b.x, b.y, b.z] {
                    proptest::prop_assert!((axis.length() - 1.0).abs() < 1e-5);
                }
                proptest::prop_assert!(b.x.dot(b.y).abs() < 1e-5 && b.y.dot(b.z).abs() < 1e-5 && b.z.dot(b.x).abs() < 1e-5);
                proptest::prop_assert!((b.z.cross(b.x) - b.y).length() < 1e-5);
                // True up leans the same way as the given up.
                proptest::prop_assert!(b.y.dot(v(up)) >= 0.0);
            }
        }

        /// Up vectors at angles from 10⁻⁸ to 1 radian off the view direction
        /// (either way along it), where `up × cam_z` cancels: refused below
        /// half the threshold sine, accepted above twice it, and an accepted
        /// basis is orthonormal with true up along the part of `up` across
        /// the view, to within the cancellation's error ε/sin.
        #[test]
        fn a_nearly_parallel_up_is_refused_or_gives_the_roll_it_leans_towards(
            c in proptest::array::uniform3(-1e3f32..1e3),
            view in proptest::array::uniform3(-1f32..1.0),
            across in proptest::array::uniform3(-1f32..1.0),
            exponent in -8f32..0.0,
            backwards in proptest::bool::ANY,
        ) {
            let v = |a: [f32; 3]| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
            let Some(z) = normalize_robust(v(view)) else { return Ok(()) };
            let Some(w) = normalize_robust(v(across).reject_from(z)) else { return Ok(()) };
            let along = if backwards { -z } else { z };
            let up = along + w * (10.0 as Real).powf(exponent as Real);
            let (c, coi) = (v(c), v(c) + z * 10.0);
            // The sine the camera sees, exactly (in f64, from the rounded inputs).
            let (wide_up, wide_view) = (crate::math::real::widen(up), crate::math::real::widen(coi - c));
            let sine = wide_up.normalize().cross(wide_view.normalize()).length();
            let threshold = crate::math::real::to_f64(MIN_UP_SINE);
            match CameraBasis::new(c, coi, up) {
                Ok(b) => {
                    proptest::prop_assert!(sine > threshold / 2.0, "accepted at sine {sine:e}");
                    for axis in [b.x, b.y, b.z] {
                        proptest::prop_assert!((axis.length() - 1.0).abs() < 1e-5);
                    }
                    proptest::prop_assert!((b.z.cross(b.x) - b.y).length() < 1e-5);
                    proptest::prop_assert!(b.x.dot(b.z).abs() < 1e-5 && b.y.dot(b.z).abs() < 1e-5);
                    // up × cam_z loses log₂(1/sin) bits to cancellation.
                    let epsilon = crate::math::real::to_f64(Real::EPSILON);
                    let off = crate::math::real::to_f64((b.y - w).length());
                    proptest::prop_assert!(off <= 64.0 * epsilon / sine + 1e-5, "true up {} off {w} by {off:e} at sine {sine:e}", b.y);
                }
                Err(e) => {
                    proptest::prop_assert_eq!(e, CameraError::UpParallelToView);
                    proptest::prop_assert!(sine < 2.0 * threshold, "refused at sine {sine:e}");
                }
            }
        }
    }
}
