//! Exact per-pixel sums of samples, so that a render split into parts
//! merges into the very image one machine renders, bit for bit.
//!
//! A sum of `f32` colours depends on the order it is added in: part 0's
//! samples summed, plus part 1's, rounds differently from all samples summed
//! one after the other. So samples are summed here in fixed point: each
//! sample component becomes an integer count of 2⁻⁶⁴ ([`fixed`]), and
//! integers add exactly, in any order and any grouping. A pixel's mean is
//! then one rounding of its exact sum ([`ExactColorSum::mean`]), whether
//! its samples were summed on one machine or on a hundred.
//!
//! # Range and resolution
//!
//! An `i128` holds 63 integer bits and [`FRACTION_BITS`] = 64 fraction bits.
//! A sample component is truncated (towards zero) to a multiple of 2⁻⁶⁴
//! ≈ 5.4·10⁻²⁰ — a change far below an `f32`'s resolution for any visible
//! light (an `f32` colour of 10⁻¹² has a step of 10⁻¹⁹) — and clamped to
//! ±[`SAMPLE_LIMIT`] = 2³¹, so that the sum of the most samples a pixel can
//! have (2³² − 1) never overflows. No render reaches the clamp: it is a
//! radiance of two billion in one sample. A NaN sample counts as 0 (the
//! `f32` sum it replaces turned the whole pixel NaN).

use rt_core::math::color::Color;

/// Fraction bits of the fixed-point sums: a sample is counted in units of 2⁻⁶⁴.
pub const FRACTION_BITS: i32 = 64;

/// The largest sample component a sum takes, 2³¹ (larger ones are clamped
/// to it): 2³² − 1 samples of it, in units of 2⁻⁶⁴, stay below 2¹²⁷.
pub const SAMPLE_LIMIT: f32 = 2147483648.0;

/// A sample component in units of 2⁻⁶⁴, truncated towards zero: exact for
/// every `f32` of magnitude 2⁻⁴⁰ and above (its 24 significant bits all lie
/// above 2⁻⁶⁴); clamped to ±[`SAMPLE_LIMIT`]; NaN is 0.
pub fn fixed(v: f32) -> i128 {
    if v.is_nan() {
        return 0;
    }
    if v.abs() >= SAMPLE_LIMIT {
        // One unit below the limit, so that 2³² − 1 of them fit in 127 bits.
        let max = (1i128 << (31 + FRACTION_BITS)) - 1;
        return if v > 0.0 { max } else { -max };
    }
    let bits = v.to_bits();
    let exponent = ((bits >> 23) & 0xff) as i32;
    let fraction = (bits & 0x7f_ffff) as i128;
    // v = significand · 2^power, with the implicit leading bit for normal numbers.
    let (significand, power) =
        if exponent == 0 { (fraction, -149) } else { (fraction | 0x80_0000, exponent - 150) };
    let shift = power + FRACTION_BITS;
    let magnitude = if shift >= 0 {
        significand << shift
    } else if shift > -24 {
        significand >> -shift
    } else {
        0
    };
    if bits >> 31 == 1 { -magnitude } else { magnitude }
}

/// The exact sum of a pixel's samples, per colour channel, in units of 2⁻⁶⁴.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ExactColorSum(pub [i128; 3]);

impl ExactColorSum {
    /// Bytes of [`ExactColorSum::to_le_bytes`].
    pub const BYTES: usize = 48;

    /// Adds one sample.
    #[inline]
    pub fn add(&mut self, c: Color) {
        for (sum, v) in self.0.iter_mut().zip(c.to_array()) {
            *sum += fixed(v);
        }
    }

    /// Adds `n` samples of colour `c`: exactly `n` calls of
    /// [`ExactColorSum::add`], converting `c` once (a flat render's pixel
    /// sees one colour in most of its samples).
    #[inline]
    pub fn add_times(&mut self, c: Color, n: u32) {
        for (sum, v) in self.0.iter_mut().zip(c.to_array()) {
            *sum += fixed(v) * n as i128;
        }
    }

    /// Adds another sum (of other samples of the same pixel): exact.
    pub fn merge(&mut self, other: &Self) {
        for (sum, v) in self.0.iter_mut().zip(other.0) {
            *sum += v;
        }
    }

    /// The mean of `count` samples whose sum this is: the exact sum rounded
    /// once to `f64` (nearest), divided by `count` and rounded to `f32`, so
    /// it depends on the exact sum alone. Zero samples give black.
    pub fn mean(&self, count: u32) -> Color {
        if count == 0 {
            return Color::ZERO;
        }
        let scale = (-FRACTION_BITS as f64).exp2();
        let [r, g, b] = self.0.map(|s| (s as f64 * scale / count as f64) as f32);
        Color::new(r, g, b)
    }

    /// The three sums as 16-byte little-endian two's-complement integers.
    pub fn to_le_bytes(&self) -> [u8; Self::BYTES] {
        let mut out = [0; Self::BYTES];
        for (chunk, v) in out.chunks_exact_mut(16).zip(self.0) {
            chunk.copy_from_slice(&v.to_le_bytes());
        }
        out
    }

    /// The sums [`ExactColorSum::to_le_bytes`] wrote.
    pub fn from_le_bytes(bytes: &[u8; Self::BYTES]) -> Self {
        let mut sums = [0; 3];
        for (sum, chunk) in sums.iter_mut().zip(bytes.chunks_exact(16)) {
            *sum = i128::from_le_bytes(chunk.try_into().expect("16 bytes"));
        }
        Self(sums)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_is_exact_for_every_float_from_two_to_the_minus_forty_up() {
        for v in
            [1.0f32, 0.5, 3.75, 1e-12, 2f32.powi(-40), 1e9, 0.1, 123.456, -7.25, f32::MIN_POSITIVE * 1e30]
        {
            let back = fixed(v) as f64 / 2f64.powi(FRACTION_BITS);
            assert_eq!(back, v as f64, "{v}");
        }
        // Below, truncated towards zero; subnormals vanish.
        assert_eq!(fixed(2f32.powi(-65)), 0);
        assert_eq!(fixed(3.0 * 2f32.powi(-65)), 1);
        assert_eq!(fixed(-3.0 * 2f32.powi(-65)), -1);
        assert_eq!(fixed(f32::from_bits(1)), 0);
        assert_eq!(fixed(0.0), 0);
        assert_eq!(fixed(-0.0), 0);
    }

    #[test]
    fn huge_infinite_and_nan_samples_are_clamped_and_cannot_overflow_a_sum() {
        let max = fixed(f32::INFINITY);
        assert_eq!(max, fixed(1e30));
        assert_eq!(fixed(f32::NEG_INFINITY), -max);
        assert_eq!(fixed(f32::NAN), 0);
        assert!(max.checked_mul(u32::MAX as i128).is_some());
        // Just below the limit, still exact.
        let below = f32::from_bits(SAMPLE_LIMIT.to_bits() - 1);
        assert_eq!(fixed(below) as f64 / 2f64.powi(FRACTION_BITS), below as f64);
    }

    #[test]
    fn sums_do_not_depend_on_order_or_grouping_where_f32_sums_do() {
        let samples: Vec<Color> = (0..1000)
            .map(|i| {
                let v = ((i * 7919) % 1009) as f32 / 7.0;
                Color::new(v, 1.0 / (v + 1e-3), v * v * 1e3)
            })
            .collect();
        let mut one = ExactColorSum::default();
        samples.iter().for_each(|&c| one.add(c));
        for cut in [1, 333, 500, 999] {
            let (mut a, mut b) = (ExactColorSum::default(), ExactColorSum::default());
            samples[..cut].iter().for_each(|&c| a.add(c));
            samples[cut..].iter().rev().for_each(|&c| b.add(c));
            b.merge(&a);
            assert_eq!(b, one, "cut at {cut}");
            assert_eq!(b.mean(1000), one.mean(1000));
        }
        // The f32 sum of the same halves is not the f32 sum of the whole.
        let f32_sum = |s: &[Color]| s.iter().fold(Color::ZERO, |a, &c| a + c);
        assert_ne!(f32_sum(&samples[..333]) + f32_sum(&samples[333..]), f32_sum(&samples));
    }

    #[test]
    fn adding_a_colour_n_times_at_once_is_adding_it_n_times() {
        for (c, n) in [(Color::new(0.1, 3.75, 1e-12), 7), (Color::splat(f32::INFINITY), 64), (Color::ZERO, 0)]
        {
            let (mut once, mut each) = (ExactColorSum::default(), ExactColorSum::default());
            once.add_times(c, n);
            (0..n).for_each(|_| each.add(c));
            assert_eq!(once, each, "{c} times {n}");
        }
    }

    #[test]
    fn the_mean_is_the_exact_mean_rounded() {
        let mut s = ExactColorSum::default();
        for v in [0.1f32, 0.2, 0.3] {
            s.add(Color::splat(v));
        }
        let exact = (0.1f32 as f64 + 0.2f32 as f64 + 0.3f32 as f64) / 3.0;
        assert_eq!(s.mean(3), Color::splat(exact as f32));
        assert_eq!(s.mean(0), Color::ZERO);
    }

    #[test]
    fn bytes_round_trip() {
        let s = ExactColorSum([1, -(1 << 100), i128::MAX]);
        assert_eq!(ExactColorSum::from_le_bytes(&s.to_le_bytes()), s);
    }
}
