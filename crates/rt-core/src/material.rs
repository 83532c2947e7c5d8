//! Materials: what colour a hit gets.

/// An RGB colour, components nominally in [0, 1], always `f32` whatever
/// [`crate::real::Real`] is. Written to 8-bit images as given (no gamma curve).
pub type Color = glam::Vec3;

/// A surface's appearance. Without lights (pure ray casting) a hit shows
/// `color` flat.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Base colour.
    pub color: Color,
}
