//! The value types every part of a scene file is read with: finite numbers,
//! 3-vectors, colours, and bounded counts.

use serde::Deserialize;

use crate::math::color::Color;
use crate::math::real::{Real, Vec3};

/// A number that must be finite (RON also reads `NaN` and `inf`); 0 by default.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Finite(pub(super) Real);

impl<'de> Deserialize<'de> for Finite {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = Real::deserialize(d)?;
        if v.is_finite() {
            Ok(Self(v))
        } else {
            Err(serde::de::Error::custom(format!("expected a finite number, found {v}")))
        }
    }
}

/// A point or vector written `(x, y, z)`.
#[derive(Clone, Copy, Debug, Deserialize)]
pub(super) struct V3(pub(super) Finite, pub(super) Finite, pub(super) Finite);

impl From<V3> for Vec3 {
    fn from(v: V3) -> Self {
        Vec3::new(v.0.0, v.1.0, v.2.0)
    }
}

impl Default for V3 {
    fn default() -> Self {
        V3(Finite(0.0), Finite(0.0), Finite(0.0))
    }
}

/// A colour written `(r, g, b)`, each finite and ≥ 0.
#[derive(Clone, Copy, Debug, Default, Deserialize)]
#[serde(try_from = "V3")]
pub(super) struct ColorDesc(pub(super) Color);

impl TryFrom<V3> for ColorDesc {
    type Error = String;
    #[allow(clippy::unnecessary_cast)] // `Real` is f64 with the `f64` feature.
    fn try_from(v: V3) -> Result<Self, String> {
        let c = Vec3::from(v);
        if c.cmplt(Vec3::ZERO).any() {
            return Err(format!("colour components must not be negative, got {c}"));
        }
        Ok(Self(Color::new(c.x as f32, c.y as f32, c.z as f32)))
    }
}

/// `n` if it is in `range`, else "`what` must be LO to HI, got N".
pub(super) fn check_count(what: &str, range: std::ops::RangeInclusive<u32>, n: u32) -> Result<u32, String> {
    if range.contains(&n) {
        Ok(n)
    } else {
        Err(format!("{what} must be {} to {}, got {n}", range.start(), range.end()))
    }
}

/// 1, the default of weights, intensities and scales.
pub(super) fn unit_scale() -> Finite {
    Finite(1.0)
}

/// White, the default colour of a light.
pub(super) fn white() -> ColorDesc {
    ColorDesc(Color::ONE)
}

/// `true`, for boolean fields that default to on.
pub(super) fn yes() -> bool {
    true
}

/// A field that is `None` when absent and read as its plain value (no
/// `Some(…)`) when present.
pub(super) fn present<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}
