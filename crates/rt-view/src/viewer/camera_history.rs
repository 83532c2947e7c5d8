//! Undo and redo of camera changes.
//!
//! The viewer changes the camera a little every frame while the mouse drags,
//! the wheel turns, a fly key is held or a field is typed into. A step of
//! history is one such gesture, not one frame: the history is told each
//! frame which gesture (if any) is under way ([`Gesture`]), and records the
//! camera as it was when that gesture ended. A discrete change (Reset,
//! Frame) is recorded at once ([`CameraHistory::record`]). At most
//! [`HISTORY_LENGTH`] steps are kept; the oldest go first.

use std::collections::VecDeque;

use super::camera_controls::CameraSettings;

/// How many undo steps are kept.
pub const HISTORY_LENGTH: usize = 100;

/// What is changing the camera this frame: changes under one gesture make one
/// step. Two values that differ are two gestures (a drag, then the wheel;
/// typing into one field, then another).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Gesture {
    /// A mouse button is held (a drag on the image or on a control).
    Pointer,
    /// The wheel turned a moment ago.
    Wheel,
    /// Fly keys are held.
    Fly,
    /// A text field has the keyboard: the id of the field (a hash), so each
    /// field's keystrokes make one step.
    Typing(u64),
}

/// The camera's past and undone futures.
#[derive(Clone, Debug)]
pub struct CameraHistory {
    /// Earlier cameras, oldest first.
    undo: VecDeque<CameraSettings>,
    /// Undone cameras, the next redo last.
    redo: Vec<CameraSettings>,
    /// The camera as the last step left it.
    committed: CameraSettings,
    /// The camera and gesture seen in the last frame.
    last: CameraSettings,
    last_gesture: Option<Gesture>,
}

impl CameraHistory {
    /// A history that starts at `camera`, with nothing to undo.
    pub fn new(camera: CameraSettings) -> Self {
        Self { undo: VecDeque::new(), redo: Vec::new(), committed: camera, last: camera, last_gesture: None }
    }

    /// One frame: the camera is `camera`, changed by `gesture` if any. A
    /// gesture that ended (or gave way to another) becomes a step with the
    /// camera it left; a change with no gesture under way is a step at once.
    pub fn observe(&mut self, camera: CameraSettings, gesture: Option<Gesture>) {
        if gesture != self.last_gesture {
            self.commit(self.last);
        }
        if gesture.is_none() {
            self.commit(camera);
        }
        self.last = camera;
        self.last_gesture = gesture;
    }

    /// A discrete change: `camera` is a step of its own now (anything under
    /// way before it becomes the step before).
    pub fn record(&mut self, before: CameraSettings, camera: CameraSettings) {
        self.commit(before);
        self.commit(camera);
        self.last = camera;
    }

    /// The camera before the last step, if there is one; `camera` (the one
    /// in force) can then be redone. A gesture under way is ended first, so
    /// undo goes back to where it started.
    pub fn undo(&mut self, camera: CameraSettings) -> Option<CameraSettings> {
        self.commit(camera);
        let previous = self.undo.pop_back()?;
        self.redo.push(self.committed);
        self.set(previous);
        Some(previous)
    }

    /// The camera that the last undo left, if nothing changed since.
    pub fn redo(&mut self, camera: CameraSettings) -> Option<CameraSettings> {
        self.commit(camera);
        let next = self.redo.pop()?;
        self.push_undo(self.committed);
        self.set(next);
        Some(next)
    }

    /// Whether there is a step to undo, with `camera` in force.
    pub fn can_undo(&self, camera: &CameraSettings) -> bool {
        !self.undo.is_empty() || *camera != self.committed
    }

    /// Whether there is an undone step to redo, with `camera` in force.
    pub fn can_redo(&self, camera: &CameraSettings) -> bool {
        !self.redo.is_empty() && *camera == self.committed
    }

    /// `camera` is in force by undo or redo: the gesture state starts afresh.
    fn set(&mut self, camera: CameraSettings) {
        self.committed = camera;
        self.last = camera;
    }

    /// Makes `camera` a step if it differs from the last one; a new step
    /// forgets what was undone.
    fn commit(&mut self, camera: CameraSettings) {
        if camera != self.committed {
            self.push_undo(self.committed);
            self.committed = camera;
            self.redo.clear();
        }
    }

    fn push_undo(&mut self, camera: CameraSettings) {
        if self.undo.len() == HISTORY_LENGTH {
            self.undo.pop_front();
        }
        self.undo.push_back(camera);
    }
}

#[cfg(test)]
mod tests {
    use rt_core::{Projection, Real, Vec3};

    use super::*;

    /// A camera at x = `x`.
    fn at(x: Real) -> CameraSettings {
        CameraSettings {
            position: Vec3::new(x, 0.0, -5.0),
            center_of_interest: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 40.0,
            near: 1.0,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }

    #[test]
    fn a_drag_is_one_step_recorded_on_release() {
        let mut h = CameraHistory::new(at(0.0));
        for x in 1..=10 {
            h.observe(at(x as Real), Some(Gesture::Pointer));
        }
        h.observe(at(10.0), None);
        assert_eq!(h.undo(at(10.0)), Some(at(0.0)));
        assert_eq!(h.undo(at(0.0)), None, "one step only");
        assert_eq!(h.redo(at(0.0)), Some(at(10.0)));
        assert_eq!(h.redo(at(10.0)), None);
    }

    #[test]
    fn undo_in_the_middle_of_a_gesture_goes_back_to_where_it_started() {
        let mut h = CameraHistory::new(at(0.0));
        h.observe(at(1.0), Some(Gesture::Wheel));
        h.observe(at(2.0), Some(Gesture::Wheel));
        assert!(h.can_undo(&at(2.0)));
        assert_eq!(h.undo(at(2.0)), Some(at(0.0)));
        assert_eq!(h.redo(at(0.0)), Some(at(2.0)));
    }

    #[test]
    fn each_gesture_and_each_field_is_a_step_of_its_own() {
        let mut h = CameraHistory::new(at(0.0));
        h.observe(at(1.0), Some(Gesture::Pointer));
        h.observe(at(2.0), Some(Gesture::Wheel));
        h.observe(at(3.0), Some(Gesture::Wheel));
        h.observe(at(4.0), Some(Gesture::Typing(7)));
        h.observe(at(5.0), Some(Gesture::Typing(7)));
        h.observe(at(6.0), Some(Gesture::Typing(8)));
        h.observe(at(6.0), None);
        let mut back = vec![];
        let mut camera = at(6.0);
        while let Some(c) = h.undo(camera) {
            back.push(c.position.x);
            camera = c;
        }
        // The step into the next gesture holds the camera that the last frame of the previous one left.
        assert_eq!(back, [5.0, 3.0, 1.0, 0.0]);
    }

    #[test]
    fn a_change_without_a_gesture_is_a_step_at_once_and_forgets_the_undone_ones() {
        let mut h = CameraHistory::new(at(0.0));
        h.observe(at(1.0), None);
        h.observe(at(2.0), None);
        assert_eq!(h.undo(at(2.0)), Some(at(1.0)));
        assert!(h.can_redo(&at(1.0)));
        h.record(at(1.0), at(9.0));
        assert!(!h.can_redo(&at(9.0)));
        assert_eq!(h.redo(at(9.0)), None);
        assert_eq!(h.undo(at(9.0)), Some(at(1.0)));
        assert_eq!(h.undo(at(1.0)), Some(at(0.0)));
        assert!(!h.can_undo(&at(0.0)));
    }

    #[test]
    fn the_history_keeps_its_last_steps_only() {
        let mut h = CameraHistory::new(at(0.0));
        for x in 1..=(HISTORY_LENGTH + 20) {
            h.observe(at(x as Real), None);
        }
        let mut camera = at((HISTORY_LENGTH + 20) as Real);
        let mut steps = 0;
        while let Some(c) = h.undo(camera) {
            camera = c;
            steps += 1;
        }
        assert_eq!(steps, HISTORY_LENGTH);
        assert_eq!(camera, at(20.0));
    }
}
