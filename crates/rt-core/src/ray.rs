//! Rays: `p(t) = origin + t·dir`, in world units.

use crate::real::{Real, Vec3};

/// A ray `p(t) = origin + t·dir`.
///
/// `dir` need not be unit length: every `t` this crate reports is for the
/// ray's own `dir`, so the world-space distance of a hit is `t·|dir|`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts (t = 0), in world units.
    pub origin: Vec3,
    /// Direction of travel; not necessarily normalised.
    pub dir: Vec3,
}

impl Ray {
    /// A ray from `origin` along `dir`.
    pub const fn new(origin: Vec3, dir: Vec3) -> Self {
        Self { origin, dir }
    }

    /// The point `origin + t·dir`.
    #[inline]
    pub fn at(&self, t: Real) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// The open interval of ray parameters `(min, max)` a query accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interval {
    /// Hits at `t <= min` are ignored.
    pub min: Real,
    /// Hits at `t >= max` are ignored.
    pub max: Real,
}

impl Interval {
    /// The interval `(min, max)`.
    pub const fn new(min: Real, max: Real) -> Self {
        Self { min, max }
    }

    /// Whether `min < t < max` (false for NaN).
    #[inline]
    pub fn contains(&self, t: Real) -> bool {
        t > self.min && t < self.max
    }
}
