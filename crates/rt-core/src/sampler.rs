//! Where in a pixel each sample goes: SPEC.md's sub-pixel offset (sx, sy) ∈ [0,1)².
//!
//! One sample per pixel is the pixel centre (0.5, 0.5). For n > 1 samples the
//! pixel is split into a grid of `cols × rows` cells (`cols = ⌈√n⌉`,
//! `rows = ⌈n / cols⌉`), sample k goes to cell (k mod cols, k div cols), and
//! is jittered inside its cell by a hash of (pixel, sample): stratified
//! jitter that is the same for a pixel whatever thread or row order renders it.

use crate::real::Real;

/// The sub-pixel offset of sample `sample` of `spp` at pixel (`x`, `y`).
pub fn subpixel_offset(x: u32, y: u32, sample: u32, spp: u32) -> (Real, Real) {
    if spp <= 1 {
        return (0.5, 0.5);
    }
    let cols = (spp as f64).sqrt().ceil() as u32;
    let rows = spp.div_ceil(cols);
    let (cx, cy) = (sample % cols, sample / cols);
    let h = hash(x, y, sample);
    let (jx, jy) = (unit_float(h as u32), unit_float((h >> 32) as u32));
    // `(c + j) / n < 1` for j < 1 in exact arithmetic; `min` keeps it so after rounding.
    let below_one = 1.0 - Real::EPSILON / 2.0;
    (((cx as Real + jx) / cols as Real).min(below_one), ((cy as Real + jy) / rows as Real).min(below_one))
}

/// A float in [0, 1) from the top 24 bits of `bits`.
fn unit_float(bits: u32) -> Real {
    (bits >> 8) as Real * (1.0 / (1u32 << 24) as Real)
}

/// SplitMix64 finaliser of the packed (x, y, sample): a well-mixed 64-bit hash
/// (Steele, Lea, Flood, "Fast Splittable Pseudorandom Number Generators", 2014).
fn hash(x: u32, y: u32, sample: u32) -> u64 {
    let mut z = (x as u64) ^ ((y as u64) << 21) ^ ((sample as u64) << 42);
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_is_the_pixel_centre() {
        assert_eq!(subpixel_offset(7, 3, 0, 1), (0.5, 0.5));
    }

    #[test]
    fn four_samples_fall_one_in_each_quadrant() {
        let mut quadrants: Vec<(bool, bool)> =
            (0..4).map(|k| subpixel_offset(5, 9, k, 4)).map(|(x, y)| (x >= 0.5, y >= 0.5)).collect();
        quadrants.sort();
        assert_eq!(quadrants, vec![(false, false), (false, true), (true, false), (true, true)]);
    }

    #[test]
    fn offsets_stay_in_the_half_open_unit_square_and_are_reproducible() {
        for spp in [2, 3, 5, 16, 17] {
            for k in 0..spp {
                let (sx, sy) = subpixel_offset(1234, 567, k, spp);
                assert!((0.0..1.0).contains(&sx) && (0.0..1.0).contains(&sy));
                assert_eq!((sx, sy), subpixel_offset(1234, 567, k, spp));
            }
        }
    }

    #[test]
    fn neighbouring_pixels_get_different_jitter() {
        assert_ne!(subpixel_offset(0, 0, 0, 4), subpixel_offset(1, 0, 0, 4));
        assert_ne!(subpixel_offset(0, 0, 0, 4), subpixel_offset(0, 1, 0, 4));
    }
}
