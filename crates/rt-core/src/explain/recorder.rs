//! The hook the integrators call while they compute a sample: next to each
//! ray they cast and each term they add. A render passes [`NoRecorder`],
//! whose methods are empty and inlined, so the calls compile away (the
//! closures that build an [`Event`] are never called); `rt-view explain`
//! passes a [`crate::explain::path_recorder::PathRecorder`], which writes the
//! [`crate::explain::record::PathRecord`].
//!
//! The recorder keeps a *current* segment: the ray whose hit is being
//! shaded. [`Recorder::ray`] adds a ray that continues the path (it becomes
//! current), [`Recorder::returned`] goes back to its parent (direct
//! lighting's recursion), [`Recorder::probe`] adds a ray that only tests
//! visibility (it stays a child of the current one), and contributions and
//! events belong to the current segment.

use crate::explain::record::{ContributionKind, Event, SegmentKind};
use crate::geometry::hit::Hit;
use crate::math::color::Color;
use crate::math::ray::Ray;
use crate::math::real::Real;

/// What an integrator tells about the sample it computes. Every method does
/// nothing by default.
pub trait Recorder {
    /// Whether this recorder keeps anything: integrators skip work that only
    /// a record needs when it is `false`.
    const ACTIVE: bool;

    /// A ray that continues the path (`kind` primary, reflection, refraction,
    /// bounce, walk step or exit), from the current segment's hit, and what
    /// it hit (`hit`, `None` if not known yet: [`Recorder::found`]);
    /// `weight` as [`crate::explain::record::Segment::weight`]. It becomes
    /// the current segment; returns its index.
    #[inline(always)]
    fn ray(&mut self, kind: SegmentKind, ray: &Ray, hit: Option<&Hit>, weight: Option<Color>) -> usize {
        let _ = (kind, ray, hit, weight);
        0
    }

    /// What the current segment's ray hit, found after [`Recorder::ray`].
    #[inline(always)]
    fn found(&mut self, hit: Option<&Hit>) {
        let _ = hit;
    }

    /// The current segment brought back `radiance` (direct lighting); its
    /// parent becomes current again.
    #[inline(always)]
    fn returned(&mut self, radiance: Color) {
        let _ = radiance;
    }

    /// A visibility ray from the current segment's hit (`kind` shadow,
    /// ambient occlusion or next event), searched up to `t_max`; the kind
    /// says whether it was blocked.
    #[inline(always)]
    fn probe(&mut self, kind: SegmentKind, ray: &Ray, t_max: Real) {
        let _ = (kind, ray, t_max);
    }

    /// A term `value` added towards the sample, at the current segment.
    #[inline(always)]
    fn contribution(&mut self, kind: ContributionKind, value: Color) {
        let _ = (kind, value);
    }

    /// A decision at the current segment's hit; `make` is called only by a
    /// recorder that keeps it.
    #[inline(always)]
    fn event(&mut self, make: impl FnOnce() -> Event) {
        let _ = make;
    }
}

/// The recorder of a render: keeps nothing, costs nothing.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoRecorder;

impl Recorder for NoRecorder {
    const ACTIVE: bool = false;
}
