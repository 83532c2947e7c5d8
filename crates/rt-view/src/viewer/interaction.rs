//! What a part of the window did to the view in one frame: the one fact each
//! part reports to the scheduler.

/// What a part of the UI did to the view this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Interaction {
    /// Something that changes the image was edited: a new render is due.
    pub changed: bool,
    /// A control or the mouse is being dragged: render a quick preview.
    pub dragging: bool,
}

impl std::ops::BitOr for Interaction {
    type Output = Self;
    fn bitor(self, o: Self) -> Self {
        Self { changed: self.changed || o.changed, dragging: self.dragging || o.dragging }
    }
}
