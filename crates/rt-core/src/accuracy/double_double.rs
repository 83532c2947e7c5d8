//! Double-double arithmetic: a number held as the unevaluated sum `hi + lo`
//! of two f64 with `|lo| ≤ ulp(hi)/2`, about 106 significant bits. It is
//! the independent, higher-precision reference of [`crate::accuracy::hard_cases`]:
//! with f64 geometry, a reference computed in f64 itself would only measure
//! the build against itself.
//!
//! The building blocks are exact transformations of IEEE 754 arithmetic
//! (round to nearest):
//! - `two_sum(a, b)`: `s = fl(a + b)` and the exact error `e = a + b − s`
//!   (Knuth, *TAOCP* vol. 2, §4.2.2, Theorem B; six operations, no branch);
//! - `two_prod(a, b)`: `p = fl(a·b)` and the exact error `e = fma(a, b, −p)`;
//! - addition, multiplication and division of double-doubles as in Hida, Li
//!   and Bailey, "Algorithms for quad-double precision floating point
//!   arithmetic" (ARITH 2001), the QD library's `ieee_add`, `mul` and the
//!   long division; the square root by one Newton step from the f64 root
//!   (Karp and Markstein, 1997).
//!
//! Relative errors (Joldes, Muller and Popescu, "Tight and rigorous error
//! bounds for basic building blocks of double-word arithmetic", *ACM TOMS*
//! 44(2), 2017; u = 2⁻⁵³): addition ≤ 3u², multiplication ≤ 5u², division
//! ≤ 10u², the square root a few u² — all near 2⁻¹⁰⁰, against an f64
//! rounding error of 2⁻⁵³. Nothing here handles overflow, infinities or NaN:
//! the hard cases stay far from them.

use std::cmp::Ordering;
use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::DVec3;

/// A double-double number `hi + lo`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DoubleDouble {
    hi: f64,
    lo: f64,
}

/// `(fl(a + b), a + b − fl(a + b))`, both exact (Knuth's TwoSum).
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// [`two_sum`] for `|a| ≥ |b|` (or a = 0): Dekker's FastTwoSum.
fn fast_two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    (s, b - (s - a))
}

/// `(fl(a·b), a·b − fl(a·b))`, both exact: the error by one fused multiply-add.
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    (p, a.mul_add(b, -p))
}

impl DoubleDouble {
    /// Zero.
    pub const ZERO: Self = Self { hi: 0.0, lo: 0.0 };

    /// `x` exactly.
    pub const fn new(x: f64) -> Self {
        Self { hi: x, lo: 0.0 }
    }

    /// The leading part, `hi + lo` rounded to the nearest f64.
    pub fn to_f64(self) -> f64 {
        self.hi + self.lo
    }

    /// The sum of two f64, exactly.
    pub fn sum(a: f64, b: f64) -> Self {
        let (hi, lo) = two_sum(a, b);
        Self { hi, lo }
    }

    /// The product of two f64, exactly.
    pub fn product(a: f64, b: f64) -> Self {
        let (hi, lo) = two_prod(a, b);
        Self { hi, lo }
    }

    /// `√self` for `self ≥ 0`: one Newton step `y = x + (a − x²)/(2x)` from
    /// the f64 root x, which doubles its 53 correct bits.
    pub fn sqrt(self) -> Self {
        if self.hi <= 0.0 {
            return Self::ZERO;
        }
        let x = self.hi.sqrt();
        let residual = self - Self::product(x, x);
        let (hi, lo) = fast_two_sum(x, residual.to_f64() / (2.0 * x));
        Self { hi, lo }
    }

    /// `|self|`.
    pub fn abs(self) -> Self {
        if self.hi < 0.0 { -self } else { self }
    }

    /// The smaller of two values.
    pub fn min(self, other: Self) -> Self {
        if other < self { other } else { self }
    }

    /// The larger of two values.
    pub fn max(self, other: Self) -> Self {
        if other > self { other } else { self }
    }

    /// Whether both parts are finite.
    pub fn is_finite(self) -> bool {
        self.hi.is_finite() && self.lo.is_finite()
    }
}

impl From<f64> for DoubleDouble {
    fn from(x: f64) -> Self {
        Self::new(x)
    }
}

impl Neg for DoubleDouble {
    type Output = Self;
    fn neg(self) -> Self {
        Self { hi: -self.hi, lo: -self.lo }
    }
}

impl Add for DoubleDouble {
    type Output = Self;
    /// QD's `ieee_add`: both parts summed with their errors, renormalised.
    fn add(self, b: Self) -> Self {
        let (s, e) = two_sum(self.hi, b.hi);
        let (t, f) = two_sum(self.lo, b.lo);
        let (s, e) = fast_two_sum(s, e + t);
        let (hi, lo) = fast_two_sum(s, e + f);
        Self { hi, lo }
    }
}

impl Sub for DoubleDouble {
    type Output = Self;
    fn sub(self, b: Self) -> Self {
        self + -b
    }
}

impl Mul for DoubleDouble {
    type Output = Self;
    /// The exact product of the leading parts plus the two cross terms
    /// (`lo·lo` is below the result's precision).
    fn mul(self, b: Self) -> Self {
        let (p, e) = two_prod(self.hi, b.hi);
        let (hi, lo) = fast_two_sum(p, e + (self.hi * b.lo + self.lo * b.hi));
        Self { hi, lo }
    }
}

impl Div for DoubleDouble {
    type Output = Self;
    /// Long division: three f64 quotient digits, each from the remainder
    /// left by the previous ones.
    fn div(self, b: Self) -> Self {
        let q1 = self.hi / b.hi;
        let r = self - b * Self::new(q1);
        let q2 = r.hi / b.hi;
        let r = r - b * Self::new(q2);
        let q3 = r.hi / b.hi;
        let (hi, lo) = fast_two_sum(q1, q2);
        Self { hi, lo } + Self::new(q3)
    }
}

impl PartialOrd for DoubleDouble {
    /// By the leading parts, then the trailing ones (both parts are
    /// normalised, so this is the order of the exact values).
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        match self.hi.partial_cmp(&other.hi)? {
            Ordering::Equal => self.lo.partial_cmp(&other.lo),
            order => Some(order),
        }
    }
}

/// A vector of three [`DoubleDouble`]s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DdVec3(pub [DoubleDouble; 3]);

impl DdVec3 {
    /// `v` exactly.
    pub fn new(v: DVec3) -> Self {
        Self(v.to_array().map(DoubleDouble::new))
    }

    /// `a − b` exactly.
    pub fn difference(a: DVec3, b: DVec3) -> Self {
        Self([0, 1, 2].map(|k| DoubleDouble::sum(a[k], -b[k])))
    }

    /// The dot product.
    pub fn dot(self, b: Self) -> DoubleDouble {
        let [x, y, z] = self.0;
        x * b.0[0] + y * b.0[1] + z * b.0[2]
    }

    /// The cross product, by the usual component formula.
    pub fn cross(self, b: Self) -> Self {
        let ([x, y, z], [u, v, w]) = (self.0, b.0);
        Self([y * w - z * v, z * u - x * w, x * v - y * u])
    }

    /// Component `k`.
    pub fn get(self, k: usize) -> DoubleDouble {
        self.0[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Dd = DoubleDouble;

    /// 2⁻ⁿ exactly.
    fn ulp(n: i32) -> f64 {
        2f64.powi(-n)
    }

    #[test]
    fn sums_and_products_of_two_doubles_are_exact() {
        // (1 + 2⁻⁵²)² = 1 + 2⁻⁵¹ + 2⁻¹⁰⁴: f64 drops the last term.
        let a = 1.0 + ulp(52);
        let p = Dd::product(a, a);
        assert_eq!((p.hi, p.lo), (1.0 + ulp(51), ulp(104)));
        // 1 + 2⁻⁸⁰ is not an f64, but a double-double.
        let s = Dd::sum(1.0, ulp(80));
        assert_eq!((s.hi, s.lo), (1.0, ulp(80)));
        assert_eq!((s - Dd::new(1.0)).to_f64(), ulp(80));
    }

    #[test]
    fn cancellation_keeps_the_low_bits_that_f64_loses() {
        // (1 + 2⁻³⁰)² − 1 = 2⁻²⁹ + 2⁻⁶⁰, which f64 rounds to 2⁻²⁹.
        let x = Dd::new(1.0 + ulp(30));
        let square = x * x - Dd::new(1.0);
        assert_eq!(square.to_f64(), ulp(29) + ulp(60));
        assert_eq!((1.0 + ulp(30)) * (1.0 + ulp(30)) - 1.0, ulp(29));
    }

    #[test]
    fn division_and_square_root_invert_multiplication_to_about_2_to_the_minus_100() {
        for (a, b) in [(1.0, 3.0), (2.0, 7.0), (1e10, 3e-7), (-5.5, 1.0 / 3.0), (123456.789, 0.001)] {
            let (a, b) = (Dd::new(a), Dd::new(b));
            let q = a / b;
            let back = q * b - a;
            assert!(back.abs().to_f64() <= ulp(100) * a.abs().to_f64(), "{a:?} / {b:?}");
            // The quotient is closer than f64's: 1/3 has lo ≠ 0.
            assert!(q.lo != 0.0);
        }
        for x in [2.0, 3.0, 1e-20, 12345.6789, 1e30] {
            let r = Dd::new(x).sqrt();
            let back = r * r - Dd::new(x);
            assert!(back.abs().to_f64() <= ulp(100) * x, "√{x}: {r:?}");
        }
        // √2 to 32 digits: 1.4142135623730950488016887242097.
        let r = Dd::new(2.0).sqrt();
        assert_eq!(r.hi, std::f64::consts::SQRT_2);
        assert!((r.lo - (-9.667293313452913e-17)).abs() < 1e-30, "{r:?}");
        assert_eq!(Dd::ZERO.sqrt(), Dd::ZERO);
    }

    #[test]
    fn order_and_extremes_follow_the_exact_values() {
        let a = Dd::sum(1.0, ulp(80));
        let b = Dd::new(1.0);
        assert!(a > b && a.max(b) == a && a.min(b) == b && b.partial_cmp(&a) == Some(Ordering::Less));
        assert!(-a < -b && (-a).abs() == a);
        assert!(a.is_finite() && !Dd::new(f64::INFINITY).is_finite());
    }

    #[test]
    fn vectors_take_exact_differences_and_the_usual_cross_product() {
        let d = DdVec3::difference(DVec3::new(1e8, 1.0, 0.0), DVec3::new(ulp(40), 0.0, 0.0));
        assert_eq!(d.get(0), Dd::sum(1e8, -ulp(40)));
        let x = DdVec3::new(DVec3::X);
        let y = DdVec3::new(DVec3::Y);
        assert_eq!(x.cross(y), DdVec3::new(DVec3::Z));
        assert_eq!(x.dot(y), Dd::ZERO);
        assert_eq!(y.get(1), Dd::new(1.0));
    }
}
