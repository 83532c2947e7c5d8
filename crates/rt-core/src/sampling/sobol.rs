//! Owen-scrambled Sobol points, padded to any number of dimensions and
//! decorrelated between pixels: the values of [`super::sampler::Sampler`]'s
//! Sobol method ([`super::sampler::SamplerKind::Sobol`]).
//!
//! The points are those of the `sobol_burley` crate: the Sobol sequence
//! (direction numbers of Joe and Kuo), its index shuffled and its values
//! Owen-scrambled by hashing (Burley, "Practical Hash-based Owen
//! Scrambling", JCGT 9(4), 2020, §§3–5). Owen scrambling keeps the
//! sequence's nets: within the first two dimensions, every aligned block of
//! 2^m points (in particular every prefix of 2^m samples) puts exactly one
//! point in each elementary interval of area 2^−m, whatever the scramble.
//! Shuffling the index (a nested uniform scramble of its reversed bits,
//! Burley §4) maps each aligned block onto another, so this holds for the
//! shuffled order too.
//!
//! **Padding** (Burley §5): a path asks for far more dimensions than a
//! Sobol table holds, and high Sobol dimensions have poor 2D projections.
//! So every value a path asks for, a 1D value or a 2D pair, comes from its
//! own *slot*: the first one or two dimensions of a Sobol sequence whose
//! shuffle and scramble are seeded by a hash of (pixel, image seed, slot).
//! Within a slot, a pixel's samples are the stratified 2D sequence above;
//! between slots, and between pixels, they are independent (only randomly
//! associated), which is what makes the error noise rather than pattern.
//! Cycles' Sobol-Burley sampler and pbrt-v4's `ZSobolSampler` pad the same
//! way. Sample indices run up to 2¹⁶ per sequence (the crate's table); past
//! that, each further block of 2¹⁶ samples is another independently
//! seeded sequence (still unbiased, no longer one net).

use crate::math::real::Real;

/// Sample indices one Sobol sequence covers (the `sobol_burley` table).
pub const SEQUENCE_LENGTH: u32 = 1 << 16;

/// The seed of pixel (`x`, `y`)'s sequences in the image of seed `seed`
/// (a SplitMix64 hash, [`super::sampler`]'s): every pixel's points are
/// shuffled and scrambled differently.
#[inline]
pub fn pixel_seed(x: u32, y: u32, seed: u64) -> u64 {
    pixel_seed_in(x, y, image_bits(seed))
}

/// What the image seed `seed` adds to every pixel's seed
/// ([`pixel_seed_in`]): a hash of it, the same for every pixel, so a
/// sampler makes it once per image.
#[inline]
pub fn image_bits(seed: u64) -> u64 {
    mix(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15).wrapping_add(1))
}

/// [`pixel_seed`] of pixel (`x`, `y`) from its image's [`image_bits`].
#[inline]
pub fn pixel_seed_in(x: u32, y: u32, image: u64) -> u64 {
    let z = (x as u64) ^ ((y as u64) << 32) ^ PIXEL_SALT;
    mix(mix(z) ^ image)
}

/// Slot `slot`'s 1D value for sample `k` of the pixel of seed `pixel`, in [0, 1).
#[inline]
pub fn value_1d(pixel: u64, slot: u32, k: u32) -> Real {
    Sequence::new(pixel, slot, k / SEQUENCE_LENGTH).value_1d(k % SEQUENCE_LENGTH)
}

/// Slot `slot`'s 2D value for sample `k` of the pixel of seed `pixel`, in
/// [0, 1)²: the first two dimensions of one shuffled, scrambled sequence,
/// so a pixel's samples are stratified in the pair (the module's nets).
#[inline]
pub fn value_2d(pixel: u64, slot: u32, k: u32) -> (Real, Real) {
    Sequence::new(pixel, slot, k / SEQUENCE_LENGTH).value_2d(k % SEQUENCE_LENGTH)
}

/// One slot's sequence for one pixel and one block of [`SEQUENCE_LENGTH`]
/// samples: the hashes of its seed that shuffle its index and scramble its
/// two dimensions (`sobol_burley::sample`'s, Burley §§3–4). They do not
/// depend on the sample index, so a sampler that takes many samples of one
/// pixel makes them once per slot ([`super::sampler::Sampler`]'s cache);
/// each value then costs two or three Owen scrambles and two table
/// look-ups instead of also two 64-bit and two or three 32-bit hashes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[repr(C)]
pub struct Sequence {
    /// `hash(seed ^ 0x79c68e4a)`: the index shuffle's scramble.
    shuffle: u32,
    /// Dimension d's Owen scramble, `hash(seed · 0x9c8f2d3b ^ salt_d)`.
    scramble: [u32; 2],
}

impl Sequence {
    /// Slot `slot`'s sequence for the pixel of seed `pixel`, for the
    /// samples of block `block` (sample indices `block · SEQUENCE_LENGTH`
    /// on): its 32-bit seed is a SplitMix64 hash of the three.
    #[inline]
    pub fn new(pixel: u64, slot: u32, block: u32) -> Self {
        Self::of_seed(mix(pixel ^ mix((slot as u64) | ((block as u64) << 32))) as u32)
    }

    /// The sequence of 32-bit seed `seed` (`sobol_burley`'s `seed`).
    #[inline]
    fn of_seed(seed: u32) -> Self {
        use sobol_burley::parts::hash;
        // The crate's constants for dimension set 0.
        const DIMENSION_SALT: [u32; 2] = [0x912f_69ba, 0x174f_18ab];
        let scramble = seed.wrapping_mul(0x9c8f_2d3b);
        Self {
            shuffle: hash(seed ^ 0x79c6_8e4a),
            scramble: [hash(scramble ^ DIMENSION_SALT[0]), hash(scramble ^ DIMENSION_SALT[1])],
        }
    }

    /// Dimension 0 of sample `index` (< [`SEQUENCE_LENGTH`]), in [0, 1).
    #[inline]
    pub fn value_1d(&self, index: u32) -> Real {
        self.value_1d_rev(index.reverse_bits())
    }

    /// Dimensions 0 and 1 of sample `index` (< [`SEQUENCE_LENGTH`]), in [0, 1)².
    #[inline]
    pub fn value_2d(&self, index: u32) -> (Real, Real) {
        self.value_2d_rev(index.reverse_bits())
    }

    /// [`Sequence::value_1d`] of the sample whose index, bits reversed, is
    /// `index_rev`: a sampler reverses a sample's index once for all its
    /// slots (x86 has no instruction for it: some twenty).
    #[inline]
    pub fn value_1d_rev(&self, index_rev: u32) -> Real {
        use sobol_burley::parts::owen_scramble_rev;
        let [u, _] = sobol_rev_pair(self.shuffled_rev(index_rev));
        to_unit(owen_scramble_rev(u, self.scramble[0]).reverse_bits())
    }

    /// [`Sequence::value_2d`] of the sample whose index, bits reversed, is
    /// `index_rev`. The two scrambled values' bits are put back in order
    /// by one 64-bit reversal (of v·2³² + u, which is rev(u)·2³² + rev(v)).
    #[inline]
    pub fn value_2d_rev(&self, index_rev: u32) -> (Real, Real) {
        use sobol_burley::parts::owen_scramble_rev;
        let [u, v] = sobol_rev_pair(self.shuffled_rev(index_rev));
        let (u, v) = (owen_scramble_rev(u, self.scramble[0]), owen_scramble_rev(v, self.scramble[1]));
        let both = ((v as u64) << 32 | u as u64).reverse_bits();
        (to_unit((both >> 32) as u32), to_unit(both as u32))
    }

    /// The sample whose reversed index is `index_rev` shuffled (Burley §4:
    /// a nested uniform scramble of the index's reversed bits), still
    /// reversed: `sobol_burley::sample`'s first step. Its dimensions' values
    /// are then Owen-scrambled (Burley §3), their bits put back in order
    /// and made floats ([`to_unit`]): the crate's last steps.
    #[inline]
    fn shuffled_rev(&self, index_rev: u32) -> u32 {
        sobol_burley::parts::owen_scramble_rev(index_rev, self.shuffle)
    }
}

/// Sequences kept field by field (a struct of arrays): sequence `i`'s
/// shuffle is `shuffle[i]`, its scrambles `scramble[0][i]` and
/// `scramble[1][i]`, so that eight neighbouring sequences' fields are three
/// eight-lane loads for [`SequenceColumns::values_8x2`] (as an array of
/// [`Sequence`]s they were three gathers).
#[derive(Clone, Copy, Debug)]
pub struct SequenceColumns<const N: usize> {
    shuffle: [u32; N],
    scramble: [[u32; N]; 2],
}

impl<const N: usize> SequenceColumns<N> {
    /// `N` default sequences.
    pub const EMPTY: Self = Self { shuffle: [0; N], scramble: [[0; N]; 2] };

    /// Sequence `i`.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Sequence {
        Sequence { shuffle: self.shuffle[i], scramble: [self.scramble[0][i], self.scramble[1][i]] }
    }

    /// Sets sequence `i` to `sequence`.
    #[inline(always)]
    pub fn set(&mut self, i: usize, sequence: Sequence) {
        self.shuffle[i] = sequence.shuffle;
        self.scramble[0][i] = sequence.scramble[0];
        self.scramble[1][i] = sequence.scramble[1];
    }

    /// Eight sequences' values at once: for sequences `first..first + 8`
    /// and the sample whose reversed index is `index_rev`, dimension 0 and
    /// dimension 1 of each, the values [`Sequence::value_2d_rev`] gives,
    /// bit for bit (the same integer operations lane by lane, and the same
    /// float conversion). With AVX2; `None` without it.
    ///
    /// # Panics
    /// If `first + 8` is past `N`.
    #[inline]
    pub fn values_8x2(&self, first: usize, index_rev: u32) -> Option<[[f32; 8]; 2]> {
        fn eight<const N: usize>(column: &[u32; N], first: usize) -> &[u32; 8] {
            column[first..first + 8].try_into().expect("eight sequences")
        }
        let columns =
            [eight(&self.shuffle, first), eight(&self.scramble[0], first), eight(&self.scramble[1], first)];
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: AVX2 is available, checked just above.
            return Some(unsafe { values_8x2_avx2(columns, index_rev) });
        }
        let _ = (columns, index_rev);
        None
    }
}

/// [`SequenceColumns::values_8x2`] with AVX2, for the eight sequences'
/// `[shuffle, scramble 0, scramble 1]` columns: the index shuffle and both
/// Owen scrambles on eight lanes (`vpmulld`), [`sobol_rev_pair`]'s shifts
/// and XORs, the bits reversed by byte shuffles (bytes swapped, then each
/// byte's nibbles looked up reversed).
///
/// # Safety
/// The processor must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn values_8x2_avx2(columns: [&[u32; 8]; 3], index_rev: u32) -> [[f32; 8]; 2] {
    use std::arch::x86_64::*;
    // SAFETY: each column is eight u32s, loaded whole; AVX2 as the caller
    // promises.
    unsafe {
        let load = |c: &[u32; 8]| _mm256_loadu_si256(c.as_ptr().cast());
        let (shuffle, scramble0, scramble1) = (load(columns[0]), load(columns[1]), load(columns[2]));
        let owen = |n: __m256i, scramble: __m256i| {
            let n = _mm256_xor_si256(n, _mm256_mullo_epi32(n, _mm256_set1_epi32(0x3d20adea)));
            let n = _mm256_add_epi32(n, scramble);
            let odd = _mm256_or_si256(_mm256_srli_epi32::<16>(scramble), _mm256_set1_epi32(1));
            let n = _mm256_mullo_epi32(n, odd);
            let n = _mm256_xor_si256(n, _mm256_mullo_epi32(n, _mm256_set1_epi32(0x05526c56)));
            _mm256_xor_si256(n, _mm256_mullo_epi32(n, _mm256_set1_epi32(0x53a22864)))
        };
        let reverse = |x: __m256i| {
            let swap = _mm256_setr_epi8(
                3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12, 3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8,
                15, 14, 13, 12,
            );
            let x = _mm256_shuffle_epi8(x, swap);
            let nibble = _mm256_set1_epi8(0x0f);
            // Each nibble's bits reversed, as the low and as the high nibble.
            let rev_low = _mm256_setr_epi8(
                0x0, 0x8, 0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf, 0x0, 0x8,
                0x4, 0xc, 0x2, 0xa, 0x6, 0xe, 0x1, 0x9, 0x5, 0xd, 0x3, 0xb, 0x7, 0xf,
            );
            let rev_high = _mm256_slli_epi16::<4>(rev_low);
            let low = _mm256_and_si256(x, nibble);
            let high = _mm256_and_si256(_mm256_srli_epi16::<4>(x), nibble);
            _mm256_or_si256(_mm256_shuffle_epi8(rev_high, low), _mm256_shuffle_epi8(rev_low, high))
        };
        let rev = owen(_mm256_set1_epi32(index_rev as i32), shuffle);
        // `sobol_rev_pair` on eight lanes.
        let u = reverse(_mm256_and_si256(rev, _mm256_set1_epi32(0xffff_0000_u32 as i32)));
        // SUPERSET_STEPS, the shifts written out (they must be constants).
        let step = |v: __m256i, down: __m256i, mask: u32| {
            _mm256_xor_si256(v, _mm256_and_si256(down, _mm256_set1_epi32(mask as i32)))
        };
        let v = step(u, _mm256_srli_epi32::<1>(u), SUPERSET_STEPS[0].1);
        let v = step(v, _mm256_srli_epi32::<2>(v), SUPERSET_STEPS[1].1);
        let v = step(v, _mm256_srli_epi32::<4>(v), SUPERSET_STEPS[2].1);
        let v = step(v, _mm256_srli_epi32::<8>(v), SUPERSET_STEPS[3].1);
        let to_unit = |x: __m256i| {
            let bits = _mm256_or_si256(_mm256_srli_epi32::<9>(x), _mm256_set1_epi32(0x3f80_0000));
            _mm256_sub_ps(_mm256_castsi256_ps(bits), _mm256_set1_ps(1.0))
        };
        let mut out = [[0.0f32; 8]; 2];
        _mm256_storeu_ps(out[0].as_mut_ptr(), to_unit(reverse(owen(u, scramble0))));
        _mm256_storeu_ps(out[1].as_mut_ptr(), to_unit(reverse(owen(v, scramble1))));
        out
    }
}

/// A float in [0, 1) from the top 23 bits of `bits`
/// (`sobol_burley::parts::u32_to_f32_norm`).
#[inline]
fn to_unit(bits: u32) -> Real {
    sobol_burley::parts::u32_to_f32_norm(bits) as Real
}

/// The first two dimensions' reversed Sobol values of the (reversed,
/// shuffled) index `rev`, whose top 16 bits are the index: what
/// `sobol_burley::parts::sobol_rev` gives (a Sobol value is the XOR of the
/// direction vectors of the index's set bits), worked out instead of
/// looked up. In the crate's reversed form, index bit `31 − i` brings in
/// direction vector `i`, which for dimension 0 (the identity matrix, van
/// der Corput) is bit `i` alone, and for dimension 1 (Pascal's triangle
/// mod 2, Joe and Kuo's second dimension) is every bit `j ⊆ i` (Lucas's
/// theorem: C(i, j) is odd exactly then). So with `y` the index's top 16
/// bits reversed, dimension 0's value is `y`, and dimension 1's gives each
/// bit `j` the XOR of `y`'s bits over the supersets of `j`: the subset-sum
/// transform over GF(2), four shift-and-XOR steps ([`SUPERSET_STEPS`]).
/// Tested against the crate for all 2¹⁶ indices.
#[inline]
fn sobol_rev_pair(rev: u32) -> [u32; 2] {
    let y = (rev & 0xffff_0000).reverse_bits();
    let v = SUPERSET_STEPS.iter().fold(y, |v, &(shift, mask)| v ^ ((v >> shift) & mask));
    [y, v]
}

/// The steps of [`sobol_rev_pair`]'s superset XOR: bit `j` takes bit
/// `j + s` where `j` lacks the bit `s` (the mask), for `s` = 1, 2, 4, 8.
const SUPERSET_STEPS: [(u32, u32); 4] = [(1, 0x5555), (2, 0x3333), (4, 0x0f0f), (8, 0x00ff)];

/// What sets pixel seeds apart from the stratified sampler's hashes (any
/// odd constant; these are the first digits of √3).
const PIXEL_SALT: u64 = 0xBB67_AE85_84CA_A73B;

/// SplitMix64's output function (Steele, Lea, Flood 2014).
#[inline]
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The cell of `(u, v)` in the elementary intervals of 2^−a by 2^−b.
    fn cell((u, v): (Real, Real), a: u32, b: u32) -> usize {
        let (i, j) = ((u * (1u32 << a) as Real) as usize, (v * (1u32 << b) as Real) as usize);
        (j << a) | i
    }

    #[test]
    fn every_power_of_two_prefix_of_a_pixels_pairs_is_a_net() {
        // For m = 0..=10 and every split a + b = m, the first 2^m samples of
        // a slot put exactly one point in each 2^−a × 2^−b interval: the
        // (0, m, 2)-net property, for several pixels, slots and seeds.
        for (x, y, seed, slot) in [(0, 0, 0, 0), (17, 3, 0, 5), (17, 3, 9, 5), (640, 479, 1, 1000)] {
            let pixel = pixel_seed(x, y, seed);
            for m in 0..=10u32 {
                let points: Vec<_> = (0..1u32 << m).map(|k| value_2d(pixel, slot, k)).collect();
                for a in 0..=m {
                    let mut seen = vec![0u8; 1 << m];
                    for &p in &points {
                        seen[cell(p, a, m - a)] += 1;
                    }
                    assert!(
                        seen.iter().all(|&n| n == 1),
                        "pixel ({x}, {y}), seed {seed}, slot {slot}: 2^{m} split {a}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_second_block_of_samples_is_a_net_too() {
        // Samples 256..512 (an aligned block, what a render adding samples
        // in doubling passes takes next) are also one per interval.
        let pixel = pixel_seed(4, 5, 6);
        let mut seen = vec![0u8; 256];
        for k in 256..512 {
            seen[cell(value_2d(pixel, 3, k), 4, 4)] += 1;
        }
        assert!(seen.iter().all(|&n| n == 1));
    }

    #[test]
    fn values_stay_in_the_half_open_unit_interval_and_past_the_table_go_on() {
        let pixel = pixel_seed(1, 2, 3);
        for k in [0, 1, SEQUENCE_LENGTH - 1, SEQUENCE_LENGTH, 3 * SEQUENCE_LENGTH + 7, u32::MAX] {
            let (u, v) = value_2d(pixel, 9, k);
            let w = value_1d(pixel, 9, k);
            assert!([u, v, w].iter().all(|t| (0.0..1.0).contains(t)), "{k}");
        }
        // A sample index past the table is another sequence, not sample k mod 2^16 again.
        assert_ne!(value_2d(pixel, 9, 5), value_2d(pixel, 9, SEQUENCE_LENGTH + 5));
    }

    #[test]
    fn a_pair_is_the_first_two_dimensions_of_its_sequence() {
        // Slot 4's sequence in the first block: seed mix(pixel ^ mix(4)).
        let pixel = pixel_seed(8, 9, 10);
        let seed = mix(pixel ^ mix(4)) as u32;
        for k in [0, 1, 77, 4095] {
            let pair = (sobol_burley::sample(k, 0, seed) as Real, sobol_burley::sample(k, 1, seed) as Real);
            assert_eq!(value_2d(pixel, 4, k), pair);
            assert_eq!(value_1d(pixel, 4, k), pair.0);
        }
    }

    #[test]
    fn table_lookups_give_the_crates_values_bit_for_bit_at_every_index() {
        // Every index of the table, for seeds that set and clear each bit
        // the scrambles use: the pair is `sample_4d`'s first two dimensions,
        // the 1D value `sample`'s dimension 0.
        for seed in [0, 1, 0x8000_0000, 0xdead_beef, u32::MAX, 0x79c6_8e4a] {
            for index in 0..SEQUENCE_LENGTH {
                let sequence = Sequence::of_seed(seed);
                let [u, v, _, _] = sobol_burley::sample_4d(index, 0, seed);
                let got = sequence.value_2d(index);
                assert_eq!(got, (u as Real, v as Real), "index {index}, seed {seed:#x}");
                assert_eq!(got.0, sobol_burley::sample(index, 0, seed) as Real);
                assert_eq!(sequence.value_1d(index), got.0);
            }
        }
    }

    #[test]
    fn the_first_two_dimensions_are_the_crates_for_every_index() {
        for index in 0..SEQUENCE_LENGTH {
            // Low bits set too: only the top 16 count.
            let rev = index.reverse_bits() | 0x5a5a;
            let expected = [0, 1].map(|d| sobol_burley::parts::sobol_rev(rev, d));
            assert_eq!(sobol_rev_pair(rev), expected, "index {index}");
        }
    }

    #[test]
    fn eight_slots_at_once_are_each_slots_values_bit_for_bit() {
        let pixel = pixel_seed(5, 6, 7);
        for first in [0, 10, 1000] {
            let sequences: [Sequence; 8] = std::array::from_fn(|i| Sequence::new(pixel, first + i as u32, 0));
            // Kept from column 3 on, as a sampler keeps a bounce's slots.
            let mut columns = SequenceColumns::<12>::EMPTY;
            for (i, &sequence) in sequences.iter().enumerate() {
                columns.set(3 + i, sequence);
                assert_eq!(columns.get(3 + i), sequence);
            }
            for index in (0..SEQUENCE_LENGTH).step_by(7).chain([SEQUENCE_LENGTH - 1]) {
                let Some(values) = columns.values_8x2(3, index.reverse_bits()) else { return };
                for (i, sequence) in sequences.iter().enumerate() {
                    let (u, v) = sequence.value_2d(index);
                    assert_eq!(
                        (values[0][i] as Real, values[1][i] as Real),
                        (u, v),
                        "slot {}, {index}",
                        first + i as u32
                    );
                }
            }
        }
    }

    #[test]
    fn pixels_slots_and_seeds_get_different_sequences() {
        let a = pixel_seed(3, 4, 0);
        assert_ne!(a, pixel_seed(4, 3, 0));
        assert_ne!(a, pixel_seed(3, 4, 1));
        assert_ne!(value_2d(a, 0, 0), value_2d(a, 1, 0));
        assert_ne!(value_2d(a, 0, 0), value_2d(pixel_seed(3, 5, 0), 0, 0));
        assert_ne!(value_1d(a, 2, 1), value_1d(pixel_seed(3, 4, 7), 2, 1));
    }
}
