//! Rays: `p(t) = origin + t·dir`, in world units.

use crate::math::real::{Real, Vec3, exponent_of, scale_pow2};

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

    /// The same ray with its direction multiplied by a power of two `2ᵏ` so
    /// that its largest component lies in [1, 2) (up to rounding of the
    /// exponent), and `k`. Scaling by a power of two is exact, so a hit at
    /// `t'` on the rescaled ray is at exactly `t = t'·2ᵏ` on this one
    /// ([`rescale_t`]). This keeps `|dir|²` and the intersection formulas
    /// finite for directions like 10⁻³⁰ or 10²⁰. `None` for a zero or
    /// non-finite direction or a non-finite origin.
    pub fn rescaled(&self) -> Option<(Ray, i32)> {
        let m = self.dir.abs().max_element();
        if !(m > 0.0 && m.is_finite() && self.origin.is_finite()) {
            return None;
        }
        let k = -exponent_of(m);
        let dir = Vec3::new(scale_pow2(self.dir.x, k), scale_pow2(self.dir.y, k), scale_pow2(self.dir.z, k));
        Some((Ray::new(self.origin, dir), k))
    }
}

/// `t'·2ᵏ`: the parameter on the original ray of a hit at `t'` on the ray
/// [`Ray::rescaled`] returned with `k`. `None` if it overflows.
pub fn rescale_t(t: Real, k: i32) -> Option<Real> {
    Some(scale_pow2(t, k)).filter(|t| t.is_finite())
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
