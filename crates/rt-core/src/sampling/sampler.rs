//! Where samples go: in the pixel, on area lights, over the hemisphere.
//!
//! Every random number comes from a stream seeded by (pixel, sample) alone
//! ([`SampleRng`]), never by thread or row, so an image is the same bit for
//! bit whatever the thread count or the order rows finish in.
//!
//! The sub-pixel offset (sx, sy) ∈ [0,1)² of the view plane's pixel formula
//! (`docs/conventions.md`): one sample per pixel is the
//! pixel centre (0.5, 0.5). For n > 1 samples the pixel is split into a grid
//! of n cells of equal area (an m × m grid when n = m²), sample k goes to
//! one cell of its own, and is jittered inside its cell: stratified jitter
//! ([`stratified`]). Area-light and ambient-occlusion samples are
//! stratified the same way.
//!
//! The cells are visited in an order that spreads every prefix of the
//! samples over the whole pixel ([`Strata`]), not row by row: the viewer
//! shows a fixed-count render after its first 1, 4, 16, … samples, and a
//! partial merge of a split render holds some sample ranges only; in
//! row-major order both would see the top of each pixel only (after 64 of
//! 256 samples, its top quarter), and edges would be wrong until the end.
//!
//! That layout needs the count n before the first sample, so an open-ended
//! render (the viewer's "no limit") uses [`Sampler::open_ended`] instead:
//! its samples come in blocks ([`open_ended_block`]: `0..1`, `1..4`,
//! `4..16`, … then blocks of [`OPEN_ENDED_BLOCK`]), each block stratified
//! over the whole pixel on its own, so after any number of whole blocks
//! the pixel's samples are an unbiased, stratified estimate.

use std::ops::Range;

use serde::Deserialize;

use crate::math::real::{Real, Vec3};
use crate::sampling::sobol;

/// Largest accepted samples-per-pixel count, 2¹⁶.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 1 << 16;

/// The sub-pixel offset of sample `sample` of `spp` at pixel (`x`, `y`), in
/// the image of seed `seed` ([`SampleRng::seeded`]).
#[inline]
pub fn subpixel_offset(x: u32, y: u32, sample: u32, spp: u32, seed: u64) -> (Real, Real) {
    Strata::new(spp).subpixel_offset(x, y, sample, seed)
}

/// The length of an open-ended render's blocks of samples once they stop
/// growing (a power of two: a 32 × 32 grid of strata).
pub const OPEN_ENDED_BLOCK: u32 = 1024;

/// The most samples an open-ended render takes per pixel, 2²²: a pixel's
/// sample streams are distinct for indices below it ([`SampleRng`] hashes
/// 22 bits of the index).
pub const MAX_OPEN_ENDED_SAMPLES: u32 = 1 << 22;

/// The block of an open-ended render's samples that sample `k` belongs to:
/// `0..1`, then blocks four times longer than all before them together
/// (`1..4`, `4..16`, … `256..1024`), then blocks of [`OPEN_ENDED_BLOCK`]
/// (`1024..2048`, …). Each block is stratified over the pixel on its own
/// ([`Sampler::open_ended`]).
pub fn open_ended_block(k: u32) -> Range<u32> {
    if k == 0 {
        return 0..1;
    }
    if k >= OPEN_ENDED_BLOCK {
        let start = k / OPEN_ENDED_BLOCK * OPEN_ENDED_BLOCK;
        return start..start.saturating_add(OPEN_ENDED_BLOCK);
    }
    // Powers of four: the block is 4^i..4^(i+1) for 4^i ≤ k.
    let i = (31 - k.leading_zeros()) / 2;
    1 << (2 * i)..1 << (2 * i + 2)
}

/// Point `k` of `n` stratified over [0,1)²: the square is cut into `n`
/// cells of equal area, one per point, and the point is placed at `jitter`
/// ∈ [0,1)² inside its cell ([`Strata`]).
#[inline]
pub fn stratified(k: u32, n: u32, jitter: (Real, Real)) -> (Real, Real) {
    Strata::new(n).point(k, jitter)
}

/// The cells of `n` stratified points over [0,1)²: cut into `n` cells of
/// equal area, one per point.
///
/// The cells lie in `rows = ⌊√n⌋` rows; the first `n mod rows` rows hold
/// `⌊n/rows⌋ + 1` cells, the others `⌊n/rows⌋`, and each row's height is its
/// number of cells over n, so every cell has area exactly 1/n and a uniform
/// `jitter` gives a uniform point (a grid with empty cells would not). For
/// n = m² this is the m × m grid. Made once per sample count (a renderer
/// keeps its pixels'), so the square root and divisions that lay out the
/// rows are not paid per sample.
///
/// Point k goes to cell `order(k)`, a permutation of 0..n:
/// where the grid is 2ᶜ × 2ᶜ or 2ᶜ⁺¹ × 2ᶜ (n = 2, 4, 8, 16, 64, 256, 1024,
/// …) the bit-reversed Morton order, so that the first 4ʲ points fall one
/// in each cell of the 2ʲ × 2ʲ grid (the first 4 one per quadrant, as the
/// (0, 2)-sequences of Kollig and Keller's "Efficient Multidimensional
/// Sampling", 2002, are stratified in every prefix of 4ʲ); for other n a
/// stride through the cells by the integer nearest n/φ that is prime to n,
/// whose prefixes spread over the rows as the golden-ratio sequence does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strata {
    n: u32,
    /// Cells per row in the first `extra` rows is `base + 1`, then `base`.
    base: u32,
    extra: u32,
    /// Cells in the first `extra` rows: `extra · (base + 1)`.
    wide: u32,
    /// Where every row has `base` cells and both `base` and `n` are powers
    /// of two (n = 1, 2, 4, 8, 16, 64, 256, …): log₂ `base`, and `1/base`
    /// and `1/n`, which are exact, so multiplying by them gives the
    /// quotients' very bits without a division.
    powers_of_two: Option<(u32, Real, Real)>,
    /// The order the cells are visited in.
    order: CellOrder,
}

/// The order in which [`Strata`] hands out its cells: a permutation of
/// 0..n, so that every cell still holds exactly one of the n points.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CellOrder {
    /// Bit-reversed Morton order on a 2ᶜ-row grid with 2ᶜ (`wide` false)
    /// or 2ᶜ⁺¹ (`wide` true) columns: bit i of the point's index becomes,
    /// from the most significant down, alternately a bit of the column and
    /// of the row, the column's first; the wide grid's last column bit is
    /// the index's top bit. `bits` is log₂ n.
    Morton { bits: u32, wide: bool },
    /// Cell `(k · stride) mod n`, the stride prime to n.
    Stride(u32),
}

impl CellOrder {
    /// The order for `n` cells in rows of `base` (`extra` rows of one more).
    fn new(n: u32, base: u32, extra: u32) -> Self {
        let rows = n / base;
        if extra == 0 && n.is_power_of_two() && base.is_power_of_two() && (base == rows || base == 2 * rows) {
            return Self::Morton { bits: n.trailing_zeros(), wide: base == 2 * rows };
        }
        // The integer nearest n/φ that shares no factor with n (1 always does not).
        let golden = (n as f64 * 0.618_033_988_749_895).round() as u32;
        let gcd = |mut a: u32, mut b: u32| {
            while b != 0 {
                (a, b) = (b, a % b);
            }
            a
        };
        let stride = (0..n)
            .flat_map(|d| [golden.saturating_sub(d), golden + d])
            .find(|&s| s >= 1 && gcd(s, n) == 1)
            .unwrap_or(1);
        Self::Stride(stride)
    }

    /// The row-major index of point `k`'s cell (`k` < n) in a grid of rows
    /// of `base` cells (`shift` = log₂ `base`, Morton order only).
    #[inline]
    fn cell(self, k: u32, n: u32, shift: u32) -> u32 {
        match self {
            Self::Morton { bits: 0, .. } => 0,
            Self::Morton { bits, wide } if bits <= MORTON_TABLE_BITS => {
                MORTON_CELLS[wide as usize][bits as usize][k as usize] as u32
            }
            Self::Morton { bits, wide } => morton_cell(k, bits, wide, shift),
            Self::Stride(stride) => ((k as u64 * stride as u64) % n as u64) as u32,
        }
    }
}

/// [`CellOrder::cell`] of the Morton order of `2^bits` cells (`bits` ≥ 1)
/// in rows of `2^shift`.
const fn morton_cell(k: u32, bits: u32, wide: bool, shift: u32) -> u32 {
    // The index's bits reversed: its lowest bit is now the top one.
    let mut r = k.reverse_bits() >> (32 - bits);
    let last_column_bit = if wide { r & 1 } else { 0 };
    if wide {
        r >>= 1;
    }
    // Even bits of r are the row's, odd bits the column's.
    let (row, column) = (compact_even_bits(r), compact_even_bits(r >> 1));
    let column = if wide { column << 1 | last_column_bit } else { column };
    row << shift | column
}

/// Up to `2^MORTON_TABLE_BITS` cells, the Morton order's cells are looked
/// up in [`MORTON_CELLS`] rather than made by reversing and compacting
/// the index's bits at every sample (60 instructions of a flat sample).
const MORTON_TABLE_BITS: u32 = 8;

/// [`morton_cell`] of every point of `2^bits` cells, `bits` ≤
/// [`MORTON_TABLE_BITS`], made at compile time: `[wide][bits][k]`, each
/// row `2^(bits/2)` cells long, twice that for the wide grid (as
/// [`Strata::new`] lays out a power of two: odd `bits` give the wide grid).
static MORTON_CELLS: [[[u8; 1 << MORTON_TABLE_BITS]; MORTON_TABLE_BITS as usize + 1]; 2] = {
    let mut table = [[[0; 1 << MORTON_TABLE_BITS]; MORTON_TABLE_BITS as usize + 1]; 2];
    let mut wide = 0;
    while wide < 2 {
        let mut bits = 1;
        while bits <= MORTON_TABLE_BITS {
            let shift = if wide == 1 { bits.div_ceil(2) } else { bits / 2 };
            let mut k = 0;
            while k < 1 << bits {
                table[wide][bits as usize][k as usize] = morton_cell(k, bits, wide == 1, shift) as u8;
                k += 1;
            }
            bits += 1;
        }
        wide += 1;
    }
    table
};

/// The even-numbered bits of `x` (bits 0, 2, 4, …) packed together: the
/// inverse of spreading a number's bits for a Morton code.
#[inline]
const fn compact_even_bits(mut x: u32) -> u32 {
    x &= 0x5555_5555;
    x = (x | x >> 1) & 0x3333_3333;
    x = (x | x >> 2) & 0x0f0f_0f0f;
    x = (x | x >> 4) & 0x00ff_00ff;
    (x | x >> 8) & 0x0000_ffff
}

impl Strata {
    /// The one cell of a single point, laid out by hand and what
    /// [`Strata::new`]`(1)` returns: a light sampled once per point (a
    /// path's next-event estimate) pays for no square root or division to
    /// lay out its strata.
    pub const ONE: Strata = Strata {
        n: 1,
        base: 1,
        extra: 0,
        wide: 0,
        powers_of_two: Some((0, 1.0, 1.0)),
        order: CellOrder::Morton { bits: 0, wide: false },
    };

    /// The cells of `n` points (`n` = 0 counts as 1).
    pub fn new(n: u32) -> Self {
        if n <= 1 { Self::ONE } else { Self::laid_out(n) }
    }

    /// How many points the strata hold.
    pub fn count(&self) -> u32 {
        self.n
    }

    /// The cells of `n` points laid out by the general rule (`n` = 0
    /// counts as 1).
    fn laid_out(n: u32) -> Self {
        let n = n.max(1);
        let rows = (n as f64).sqrt().floor().max(1.0) as u32;
        let (base, extra) = (n / rows, n % rows);
        let powers_of_two = (extra == 0 && base.is_power_of_two() && n.is_power_of_two())
            .then(|| (base.trailing_zeros(), 1.0 / base as Real, 1.0 / n as Real));
        let order = CellOrder::new(n, base, extra);
        Self { n, base, extra, wide: extra * (base + 1), powers_of_two, order }
    }

    /// Point `k` placed at `jitter` ∈ [0,1)² inside its cell.
    #[inline]
    pub fn point(&self, k: u32, jitter: (Real, Real)) -> (Real, Real) {
        let Strata { n, base, extra, wide, powers_of_two, order } = *self;
        let k = order.cell(k.min(n - 1), n, base.trailing_zeros());
        // `(c + j) / n < 1` for j < 1 in exact arithmetic; `min` keeps it so after rounding.
        let below_one = 1.0 - Real::EPSILON / 2.0;
        if let Some((shift, inv_base, inv_n)) = powers_of_two {
            // The general case's arithmetic below with shifts for the
            // integer divisions and exact reciprocals for the float ones.
            let (row, col) = (k >> shift, k & (base - 1));
            return (
                ((col as Real + jitter.0) * inv_base).min(below_one),
                (((row * base) as Real + jitter.1 * base as Real) * inv_n).min(below_one),
            );
        }
        // Cells before row `row`, the row, the cell in it and the row's width.
        let (row, col, count) = if k < wide {
            (k / (base + 1), k % (base + 1), base + 1)
        } else {
            (extra + (k - wide) / base, (k - wide) % base, base)
        };
        let before = if row < extra { row * (base + 1) } else { wide + (row - extra) * base };
        (
            ((col as Real + jitter.0) / count as Real).min(below_one),
            ((before as Real + jitter.1 * count as Real) / n as Real).min(below_one),
        )
    }

    /// The sub-pixel offset of sample `sample` of these cells at pixel
    /// (`x`, `y`), in the image of seed `seed`: the pixel centre for one
    /// sample, else the sample's cell jittered by the pixel's random stream.
    #[inline]
    pub fn subpixel_offset(&self, x: u32, y: u32, sample: u32, seed: u64) -> (Real, Real) {
        self.subpixel_offset_of(sample, hash(x, y, sample) ^ seed_bits(seed))
    }

    /// [`Strata::subpixel_offset`] of the sample whose hash is `bits`
    /// (`hash(x, y, sample) ^ seed_bits(seed)`, which a sampler keeps).
    #[inline]
    fn subpixel_offset_of(&self, sample: u32, bits: u64) -> (Real, Real) {
        if self.n <= 1 {
            return (0.5, 0.5);
        }
        self.point(sample, jitter_of(bits))
    }
}

/// The jitter inside its stratum, in [0,1)², of the pixel sample whose
/// hash is `h` (`hash(x, y, sample) ^ seed_bits(seed)`).
#[inline(always)]
fn jitter_of(h: u64) -> (Real, Real) {
    (unit_float(h as u32), unit_float((h >> 32) as u32))
}

/// Shirley and Chiu's concentric map ("A Low Distortion Map Between Disk and
/// Square", 1997) from [0,1)² to the unit disk: strata stay compact, so
/// stratified square samples are stratified on the disk.
#[inline]
pub fn concentric_disk((u, v): (Real, Real)) -> (Real, Real) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let quarter = std::f64::consts::FRAC_PI_4 as Real;
    let (r, phi) =
        if a.abs() > b.abs() { (a, quarter * (b / a)) } else { (b, 2.0 * quarter - quarter * (a / b)) };
    (r * phi.cos(), r * phi.sin())
}

/// A direction about the unit normal `n` with density cos θ / π (Malley's
/// method: a concentric disk point lifted onto the hemisphere).
#[inline]
pub fn cosine_hemisphere(n: Vec3, square: (Real, Real)) -> Vec3 {
    cosine_hemisphere_in(n, n.any_orthonormal_pair(), square)
}

/// [`cosine_hemisphere`] about `n` for a caller that has its tangents
/// already: `tangents` must be `n.any_orthonormal_pair()`, so the
/// direction has the very bits [`cosine_hemisphere`] gives. A BSDF keeps
/// them for its local frame, and ambient occlusion casts many rays about
/// one normal: neither pays for the frame (a division) again per direction.
#[inline]
pub fn cosine_hemisphere_in(n: Vec3, (u, v): (Vec3, Vec3), square: (Real, Real)) -> Vec3 {
    let (x, y) = concentric_disk(square);
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    (x * u + y * v + z * n).normalize_or(n)
}

/// A direction uniform over the unit sphere for (u, v) ∈ [0,1)²: z = 1 − 2u,
/// φ = 2πv (pbrt-v4 §A.5.2, `SampleUniformSphere`).
pub fn uniform_sphere((u, v): (Real, Real)) -> Vec3 {
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI as Real * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// The density of [`uniform_sphere`] over solid angle, `1/(4π)`.
pub fn uniform_sphere_pdf() -> Real {
    1.0 / (4.0 * std::f64::consts::PI as Real)
}

/// Which points a [`Sampler`] hands out: the scene file's `sampler` and the
/// command line's `--sampler`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, serde::Serialize)]
pub enum SamplerKind {
    /// Stratified jitter for the film position, independent random numbers
    /// ([`SampleRng`]) for the path: what images always were.
    #[default]
    Stratified,
    /// Owen-scrambled Sobol points for the film position, the lens and
    /// every dimension of the path, each bounce its own
    /// ([`crate::sampling::sobol`]).
    Sobol,
}

impl SamplerKind {
    /// Its name as the command line writes it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Stratified => "stratified",
            Self::Sobol => "sobol",
        }
    }
}

impl std::str::FromStr for SamplerKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "stratified" => Ok(Self::Stratified),
            "sobol" => Ok(Self::Sobol),
            _ => Err(format!("unknown sampler \"{s}\": stratified or sobol")),
        }
    }
}

/// The Sobol slot of the film position ([`crate::sampling::sobol`]).
const FILM_SLOT: u32 = 0;
/// The Sobol slot of the lens position.
const LENS_SLOT: u32 = 1;
/// The first Sobol slot of a path's values: those of bounce b start at
/// `PATH_SLOTS + b·BOUNCE_SLOTS` ([`Sampler::start_bounce`]).
const PATH_SLOTS: u32 = 2;
/// Slots per bounce of a path: next-event estimation takes two (light
/// choice, point on the light), BSDF sampling two (lobe, direction),
/// Russian roulette one; the rest are spare.
pub const BOUNCE_SLOTS: u32 = 8;
/// Slots below this ([`FILM_SLOT`], [`LENS_SLOT`] and those of bounces 1
/// to 15) keep their sequences for the pixel a [`Sampler`] is in
/// ([`PixelSequences`]); the random walks' are made per value.
const CACHED_SLOTS: usize = 128;
/// The first slot of the random walks' values: the walk of bounce b starts
/// at `WALK_SLOTS + b·2²⁰` ([`Sampler::start_walk`]), far from any bounce's.
const WALK_SLOTS: u32 = 1 << 31;

/// Where a render's samples come from: for sample k of pixel (x, y) of the
/// image of seed `seed`, a film position in the pixel and, in the order a
/// path asks for them, its 1D and 2D values, one dimension after another
/// (pbrt-v4's `Sampler`: `StartPixelSample`, `GetPixel2D`, `Get1D`, `Get2D`).
/// Values depend only on (pixel, sample, seed, dimension), never on the
/// thread or the order pixels are rendered in.
///
/// Two methods ([`SamplerKind`]):
///
/// - **Stratified** (the default): stratified jitter for the film position
///   ([`Strata::subpixel_offset`]; the pixel centre at one sample per pixel)
///   and, for the path, the [`SampleRng`] stream of the sample, which draws
///   values in pairs: a 1D value is the first of a pair whose second is not
///   used. That keeps the images of earlier versions bit for bit.
/// - **Sobol**: every value, film and lens position included, from its own
///   slot of padded, Owen-scrambled Sobol points seeded per pixel
///   ([`crate::sampling::sobol`]), so each dimension's values over a
///   pixel's samples are stratified. Each bounce of a path takes its values
///   from slots of its own ([`Sampler::start_bounce`]), so a value that one
///   sample draws and another does not (Russian roulette) does not shift
///   the later bounces' dimensions. At one sample per pixel the film
///   position is the pixel centre, as for the stratified method.
///
/// A Sobol sampler keeps the hashes of each slot's sequence for the pixel
/// it is in: they do not depend on the sample index, and a render takes a
/// pixel's samples one after another, so they are made once per pixel and
/// slot rather than once per value; with AVX2 it also makes a bounce's
/// eight slots' values at once when the bounce starts
/// ([`Sampler::start_bounce`]). The values are the same bit for bit; a
/// render keeps one sampler per run of pixels rather than copying it per
/// sample (about 2 KiB).
#[derive(Clone, Copy, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    strata: Strata,
    spp: u32,
    /// Film positions stratified per [`open_ended_block`], not over `spp`.
    open_ended: bool,
    seed: u64,
    /// [`seed_bits`] of `seed`, made once.
    seed_bits: u64,
    /// The stratified method's hash of the current sample, `hash(x, y,
    /// sample) ^ seed_bits`: its film jitter, and with salts its stream and
    /// lens position, so that a sample hashes its pixel once.
    pixel_bits: u64,
    stream: SampleRng,
    /// The current sample: its pixel and index.
    x: u32,
    y: u32,
    sample: u32,
    /// Sobol: the next slot.
    slot: u32,
    /// Sobol: the current pixel's sequences.
    sobol: PixelSequences,
}

/// A Sobol [`Sampler`]'s sequences for the pixel it is in: each slot's
/// [`sobol::Sequence`] below [`CACHED_SLOTS`], made when the slot is first
/// used in the pixel and kept for its later samples.
#[derive(Clone, Copy, Debug)]
struct PixelSequences {
    /// [`sobol::image_bits`] of the image's seed.
    image: u64,
    /// The pixel and block of [`sobol::SEQUENCE_LENGTH`] samples the
    /// sequences are for (none before the first sample).
    key: (u32, u32, u32),
    /// The pixel's seed ([`sobol::pixel_seed`]).
    pixel: u64,
    /// The current sample's index in its block, its bits reversed.
    index_rev: u32,
    /// Which pixel and block, counted from 1, the sequences are for: slot
    /// i's sequence is made for this one if `tags[i]` says so (0: none yet).
    generation: u32,
    tags: [u32; CACHED_SLOTS],
    sequences: sobol::SequenceColumns<CACHED_SLOTS>,
    /// Whether eight slots' values can be made at once
    /// ([`sobol::values_8x2`]), asked once.
    wide: bool,
    /// The current sample's values of slots `batch_slot..batch_slot + 8`
    /// (a bounce's), dimension 0 and 1, made at once, if `batched`.
    batch: [[f32; 8]; 2],
    batch_slot: u32,
    batched: bool,
}

impl PixelSequences {
    /// None made yet, for the image of seed `seed`.
    fn new(seed: u64) -> Self {
        Self {
            image: sobol::image_bits(seed),
            key: (u32::MAX, u32::MAX, u32::MAX),
            pixel: 0,
            index_rev: 0,
            generation: 0,
            tags: [0; CACHED_SLOTS],
            sequences: sobol::SequenceColumns::EMPTY,
            wide: sobol::SequenceColumns::<8>::EMPTY.values_8x2(0, 0).is_some(),
            batch: [[0.0; 8]; 2],
            batch_slot: 0,
            batched: false,
        }
    }

    /// Starts sample `k` of pixel (`x`, `y`): the sequences made so far
    /// stay if the pixel and block are those of the last sample.
    #[inline]
    fn start(&mut self, x: u32, y: u32, k: u32) {
        let key = (x, y, k / sobol::SEQUENCE_LENGTH);
        if key != self.key || self.generation == 0 {
            (self.key, self.pixel) = (key, sobol::pixel_seed_in(x, y, self.image));
            self.generation = self.generation.wrapping_add(1);
            if self.generation == 0 {
                // Tags of 2³² pixels ago could match again: forget them.
                self.tags = [0; CACHED_SLOTS];
                self.generation = 1;
            }
        }
        self.index_rev = (k % sobol::SEQUENCE_LENGTH).reverse_bits();
        self.batched = false;
    }

    /// Makes the current sample's values of the eight slots from `first`
    /// at once, if they are cached slots and the processor can
    /// ([`sobol::values_8x2`]).
    #[inline(never)]
    fn make_batch(&mut self, first: u32) {
        let range = first as usize..first as usize + 8;
        self.batched = false;
        if !self.wide || range.end > CACHED_SLOTS {
            return;
        }
        for slot in first..first + 8 {
            if self.tags[slot as usize] != self.generation {
                self.make(slot);
            }
        }
        if let Some(values) = self.sequences.values_8x2(range.start, self.index_rev) {
            (self.batch, self.batch_slot, self.batched) = (values, first, true);
        }
    }

    /// Slot `slot`'s sequence for the current pixel and block.
    #[inline(always)]
    fn sequence(&mut self, slot: u32) -> sobol::Sequence {
        match self.tags.get(slot as usize) {
            Some(&tag) if tag == self.generation => self.sequences.get(slot as usize),
            _ => self.make(slot),
        }
    }

    /// [`PixelSequences::sequence`] made, and kept if the slot is cached:
    /// once per pixel and slot (out of line, so the loops that ask for
    /// values keep the look-up only).
    #[inline(never)]
    fn make(&mut self, slot: u32) -> sobol::Sequence {
        let sequence = sobol::Sequence::new(self.pixel, slot, self.key.2);
        if let Some(tag) = self.tags.get_mut(slot as usize) {
            *tag = self.generation;
            self.sequences.set(slot as usize, sequence);
        }
        sequence
    }

    /// Slot `slot`'s 1D value for the current sample.
    #[inline]
    fn value_1d(&mut self, slot: u32) -> Real {
        let i = slot.wrapping_sub(self.batch_slot) as usize;
        if self.batched && i < 8 {
            return self.batch[0][i] as Real;
        }
        self.sequence(slot).value_1d_rev(self.index_rev)
    }

    /// Slot `slot`'s 2D value for the current sample.
    #[inline]
    fn value_2d(&mut self, slot: u32) -> (Real, Real) {
        let i = slot.wrapping_sub(self.batch_slot) as usize;
        if self.batched && i < 8 {
            return (self.batch[0][i] as Real, self.batch[1][i] as Real);
        }
        self.sequence(slot).value_2d_rev(self.index_rev)
    }
}

impl Sampler {
    /// A stratified sampler for `spp` samples per pixel (≥ 1) in the image of seed `seed`.
    pub fn new(spp: u32, seed: u64) -> Self {
        Self {
            kind: SamplerKind::Stratified,
            strata: Strata::new(spp),
            spp,
            open_ended: false,
            seed,
            seed_bits: seed_bits(seed),
            pixel_bits: hash(0, 0, 0) ^ seed_bits(seed),
            stream: SampleRng::seeded(0, 0, 0, seed),
            x: 0,
            y: 0,
            sample: 0,
            slot: PATH_SLOTS,
            sobol: PixelSequences::new(seed),
        }
    }

    /// This sampler with the method `kind`.
    pub fn with_kind(self, kind: SamplerKind) -> Self {
        Self { kind, ..self }
    }

    /// A stratified sampler for a render with no sample count fixed in
    /// advance, in the image of seed `seed`: sample k's film position is
    /// stratified within its block ([`open_ended_block`]) instead of over
    /// all the pixel's samples, and is never the bare pixel centre (a
    /// one-sample block is a uniform point in the pixel). The path's values
    /// are those of [`Sampler::new`]. Samples must stay below
    /// [`MAX_OPEN_ENDED_SAMPLES`].
    pub fn open_ended(seed: u64) -> Self {
        Self { open_ended: true, ..Self::new(1, seed) }
    }

    /// This sampler's method for a render with no sample count fixed in
    /// advance ([`Sampler::open_ended`]). Sobol points need no blocks: any
    /// prefix of 2^m samples is stratified; only the film position is never
    /// the bare pixel centre.
    pub fn to_open_ended(self) -> Self {
        Self::open_ended(self.seed).with_kind(self.kind)
    }

    /// The seed of the image this sampler samples.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The method of this sampler.
    pub fn kind(&self) -> SamplerKind {
        self.kind
    }

    /// Starts sample `k` of pixel (`x`, `y`): the values handed out next are that sample's.
    #[inline]
    pub fn start_pixel_sample(&mut self, x: u32, y: u32, k: u32) {
        let bits = match self.kind {
            SamplerKind::Stratified => self.sample_bits(x, y, k),
            SamplerKind::Sobol => 0,
        };
        self.resume_pixel_sample(PixelSample { x, y, sample: k, bits });
    }

    /// The stratified method's hash of sample `k` of pixel (`x`, `y`) in
    /// this sampler's image (what [`Sampler::pixel_sample`] carries).
    #[inline(always)]
    fn sample_bits(&self, x: u32, y: u32, k: u32) -> u64 {
        hash(x, y, k) ^ self.seed_bits
    }

    /// The current sample ([`Sampler::start_pixel_sample`]), for another
    /// copy of this sampler to go on with ([`Sampler::resume_pixel_sample`]).
    #[inline]
    pub fn pixel_sample(&self) -> PixelSample {
        PixelSample { x: self.x, y: self.y, sample: self.sample, bits: self.pixel_bits }
    }

    /// Starts the sample `start` that a copy of this sampler started
    /// ([`Sampler::pixel_sample`]): the same values as
    /// [`Sampler::start_pixel_sample`] with its pixel and sample, without
    /// hashing them again (the packet loop starts each sample twice, for
    /// its camera ray and for its path).
    #[inline]
    pub fn resume_pixel_sample(&mut self, start: PixelSample) {
        let PixelSample { x, y, sample, bits } = start;
        (self.x, self.y, self.sample) = (x, y, sample);
        match self.kind {
            SamplerKind::Stratified => {
                self.pixel_bits = bits;
                self.stream = SampleRng(bits ^ STREAM_SALT);
            }
            SamplerKind::Sobol => {
                self.sobol.start(x, y, sample);
                self.slot = PATH_SLOTS;
            }
        }
    }

    /// The values handed out next are bounce `bounce`'s (counting the first
    /// surface a camera ray meets as bounce 1): Sobol slots
    /// `PATH_SLOTS + bounce·`[`BOUNCE_SLOTS`] on, whose values a Sobol
    /// sampler makes here, eight at once, where it can. The stratified
    /// method's stream just goes on.
    #[inline]
    pub fn start_bounce(&mut self, bounce: u32) {
        if self.kind == SamplerKind::Sobol {
            self.slot = PATH_SLOTS.wrapping_add(bounce.wrapping_mul(BOUNCE_SLOTS));
            self.sobol.make_batch(self.slot);
        }
    }

    /// The values handed out next are those of the random walk that
    /// bounce `bounce` starts, step after step: slots of their own, apart
    /// from every bounce's (2²⁰ values per walk before they would reach the
    /// next walk's). The stratified method's stream just goes on.
    #[inline]
    pub fn start_walk(&mut self, bounce: u32) {
        if self.kind == SamplerKind::Sobol {
            self.slot = WALK_SLOTS.wrapping_add(bounce.wrapping_mul(1 << 20));
        }
    }

    /// The film position of sample `k` of pixel (`x`, `y`) inside the
    /// pixel, in [0,1)² (`(0.5, 0.5)`, the centre, at one sample per pixel).
    /// It uses up no dimension of the path, so primary rays can be made
    /// before their samples' paths start (packets of camera rays).
    #[inline(always)]
    pub fn film_position(&self, x: u32, y: u32, k: u32) -> (Real, Real) {
        if self.kind == SamplerKind::Sobol {
            if self.spp == 1 && !self.open_ended {
                return (0.5, 0.5);
            }
            return sobol::value_2d(sobol::pixel_seed_in(x, y, self.sobol.image), FILM_SLOT, k);
        }
        self.stratified_film_position(k, self.sample_bits(x, y, k))
    }

    /// [`Sampler::film_position`] of the current sample
    /// ([`Sampler::start_pixel_sample`]), the same bit for bit: for many
    /// samples of one pixel, a Sobol sampler makes its film slot's
    /// sequence once.
    #[inline(always)]
    pub fn film(&mut self) -> (Real, Real) {
        if self.kind == SamplerKind::Sobol {
            if self.spp == 1 && !self.open_ended {
                return (0.5, 0.5);
            }
            return self.sobol.value_2d(FILM_SLOT);
        }
        self.stratified_film_position(self.sample, self.pixel_bits)
    }

    /// The stratified method's [`Sampler::film_position`] of sample `k`
    /// whose hash is `bits` (`hash(x, y, k) ^ seed_bits`): the cell's point
    /// jittered by those bits ([`Strata::subpixel_offset`]'s jitter).
    #[inline(always)]
    fn stratified_film_position(&self, k: u32, bits: u64) -> (Real, Real) {
        if self.open_ended {
            let block = open_ended_block(k);
            let strata = Strata::new(block.end - block.start);
            strata.point(k - block.start, jitter_of(bits))
        } else if self.spp == 1 {
            (0.5, 0.5)
        } else {
            // spp ≥ 2 here, so never the one cell `subpixel_offset` centres.
            self.strata.point(k, jitter_of(bits))
        }
    }

    /// The lens position of sample `k` of pixel (`x`, `y`), in [0,1)²,
    /// for a camera with a lens
    /// ([`crate::camera::view_plane::ViewPlane::has_lens`]; a pinhole
    /// ignores it and the renderer does not ask). Stratified method:
    /// uniform and independent of the film position (a hash of the sample
    /// other than the film jitter's), not stratified, since pairing film
    /// cell k with lens cell k would tie the two together. Sobol: its own
    /// slot, stratified over the pixel's samples and independent of the
    /// film's. Like the film position it uses up no dimension of the path.
    #[inline(always)]
    pub fn lens_position(&self, x: u32, y: u32, k: u32) -> (Real, Real) {
        if self.kind == SamplerKind::Sobol {
            return sobol::value_2d(sobol::pixel_seed_in(x, y, self.sobol.image), LENS_SLOT, k);
        }
        stratified_lens_position(self.sample_bits(x, y, k))
    }

    /// [`Sampler::lens_position`] of the current sample
    /// ([`Sampler::start_pixel_sample`]), the same bit for bit (as
    /// [`Sampler::film`] is the film position).
    #[inline(always)]
    pub fn lens(&mut self) -> (Real, Real) {
        if self.kind == SamplerKind::Sobol {
            return self.sobol.value_2d(LENS_SLOT);
        }
        stratified_lens_position(self.pixel_bits)
    }

    /// The next dimension's value in [0, 1).
    // Inlined with both methods: as a call it cost the stratified method
    // more than its few instructions, and the Sobol method no less.
    #[inline(always)]
    pub fn get_1d(&mut self) -> Real {
        match self.kind {
            SamplerKind::Stratified => self.stream.next_pair().0,
            SamplerKind::Sobol => self.sobol_1d(),
        }
    }

    /// The next dimension's pair of values in [0, 1)².
    #[inline(always)]
    pub fn get_2d(&mut self) -> (Real, Real) {
        match self.kind {
            SamplerKind::Stratified => self.stream.next_pair(),
            SamplerKind::Sobol => self.sobol_2d(),
        }
    }

    /// The Sobol method's [`Sampler::get_1d`].
    #[inline(always)]
    fn sobol_1d(&mut self) -> Real {
        self.slot = self.slot.wrapping_add(1);
        self.sobol.value_1d(self.slot.wrapping_sub(1))
    }

    /// The Sobol method's [`Sampler::get_2d`].
    #[inline(always)]
    fn sobol_2d(&mut self) -> (Real, Real) {
        self.slot = self.slot.wrapping_add(1);
        self.sobol.value_2d(self.slot.wrapping_sub(1))
    }
}

/// One sample of one pixel as a [`Sampler`] started it
/// ([`Sampler::pixel_sample`]), to be taken up by a copy of the same sampler
/// ([`Sampler::resume_pixel_sample`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSample {
    /// The pixel's column.
    pub x: u32,
    /// The pixel's row.
    pub y: u32,
    /// The sample's index in the pixel.
    pub sample: u32,
    /// The stratified method's hash of the sample (0 for Sobol points).
    bits: u64,
}

/// The random numbers of one sample of one pixel: a SplitMix64 stream seeded
/// by (x, y, sample). Draw order within a sample is fixed by the tracer.
#[derive(Clone, Copy, Debug)]
pub struct SampleRng(u64);

impl SampleRng {
    /// The stream of sample `sample` of pixel (`x`, `y`).
    pub fn new(x: u32, y: u32, sample: u32) -> Self {
        Self::seeded(x, y, sample, 0)
    }

    /// The stream of sample `sample` of pixel (`x`, `y`) in the image of seed
    /// `seed`: images with different seeds are independent estimates (their
    /// noise can be measured by comparing them); seed 0 is the default image.
    pub fn seeded(x: u32, y: u32, sample: u32, seed: u64) -> Self {
        Self::with_seed_bits(x, y, sample, seed_bits(seed))
    }

    /// [`SampleRng::seeded`] from the seed's [`seed_bits`], made once.
    #[inline]
    fn with_seed_bits(x: u32, y: u32, sample: u32, bits: u64) -> Self {
        Self(hash(x, y, sample) ^ STREAM_SALT ^ bits)
    }

    /// The next pair of numbers in [0, 1).
    #[inline]
    pub fn next_pair(&mut self) -> (Real, Real) {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let h = mix(self.0);
        (unit_float(h as u32), unit_float((h >> 32) as u32))
    }
}

/// What sets a sample's stream apart from its film jitter's hash.
const STREAM_SALT: u64 = 0x5851_F42D_4C95_7F2D;

/// The stratified method's lens position of the sample whose hash is
/// `bits` (`hash(x, y, k) ^ seed_bits`).
#[inline(always)]
fn stratified_lens_position(bits: u64) -> (Real, Real) {
    let h = mix(bits ^ LENS_SALT);
    (unit_float(h as u32), unit_float((h >> 32) as u32))
}

/// What sets the lens position's hash apart from the film jitter's and the
/// path's streams (any odd constant; these are the first digits of √2).
const LENS_SALT: u64 = 0x6A09_E667_F3BC_C909;

/// A float in [0, 1) from the top 24 bits of `bits`.
fn unit_float(bits: u32) -> Real {
    (bits >> 8) as Real * (1.0 / (1u32 << 24) as Real)
}

/// SplitMix64 finaliser of the packed (x, y, sample): a well-mixed 64-bit hash
/// (Steele, Lea, Flood, "Fast Splittable Pseudorandom Number Generators", 2014).
fn hash(x: u32, y: u32, sample: u32) -> u64 {
    let z = (x as u64) ^ ((y as u64) << 21) ^ ((sample as u64) << 42);
    mix(z.wrapping_add(0x9E37_79B9_7F4A_7C15))
}

/// What a seed changes in every hash: 0 for seed 0 (SplitMix64's output
/// function maps 0 to 0), well mixed bits otherwise.
fn seed_bits(seed: u64) -> u64 {
    mix(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// SplitMix64's output function.
pub(crate) fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::real::{to_f64, widen};
    use crate::testing::chi_square::{self, Draw, Interval, Rectangle, SphereGrid};

    #[test]
    fn a_samples_values_depend_on_its_pixel_index_and_seed_alone() {
        // Started twice, a sample hands out the same dimensions; another
        // pixel, index or seed gives others. A 1D value is the first of the
        // stream's pair; the film position is the pixel centre at one
        // sample per pixel and the stratified offset otherwise, and uses up
        // no dimension.
        let draw = |sampler: &mut Sampler, x, y, k| {
            sampler.start_pixel_sample(x, y, k);
            (sampler.get_1d(), sampler.get_2d(), sampler.get_1d())
        };
        let mut a = Sampler::new(4, 3);
        let first = draw(&mut a, 5, 6, 2);
        let _ = draw(&mut a, 9, 9, 0);
        assert_eq!(draw(&mut a, 5, 6, 2), first);
        let mut stream = SampleRng::seeded(5, 6, 2, 3);
        assert_eq!(first, (stream.next_pair().0, stream.next_pair(), stream.next_pair().0));
        for other in [draw(&mut a, 5, 6, 3), draw(&mut a, 6, 5, 2), draw(&mut Sampler::new(4, 4), 5, 6, 2)] {
            assert_ne!(other, first);
        }
        assert_eq!(Sampler::new(1, 3).film_position(5, 6, 0), (0.5, 0.5));
        assert_eq!(a.film_position(5, 6, 2), subpixel_offset(5, 6, 2, 4, 3));
        a.start_pixel_sample(5, 6, 2);
        let _ = a.film_position(5, 6, 2);
        assert_eq!(a.get_1d(), first.0);
    }

    #[test]
    fn a_copy_that_resumes_a_started_sample_hands_out_the_values_of_starting_it_afresh() {
        // The packet loop makes a sample's camera ray with one sampler and
        // its path with another, which takes the sample up from the first
        // rather than hashing its pixel again: film, lens and every path
        // value must be those of `start_pixel_sample`, for every method,
        // open-ended or not.
        let kinds = [SamplerKind::Stratified, SamplerKind::Sobol];
        for base in kinds.map(|k| Sampler::new(16, 7).with_kind(k)) {
            for sampler in [base, base.to_open_ended()] {
                for (x, y, k) in [(0, 0, 0), (5, 6, 2), (1023, 77, 15)] {
                    let values = |s: &mut Sampler| (s.film(), s.lens(), s.get_1d(), s.get_2d(), s.get_1d());
                    let mut fresh = sampler;
                    fresh.start_pixel_sample(x, y, k);
                    let start = fresh.pixel_sample();
                    assert_eq!((start.x, start.y, start.sample), (x, y, k));
                    let expected = values(&mut fresh);
                    assert_eq!(expected.0, sampler.film_position(x, y, k));
                    assert_eq!(expected.1, sampler.lens_position(x, y, k));
                    let mut other = sampler;
                    other.start_pixel_sample(x + 1, y, k);
                    let _ = values(&mut other);
                    other.resume_pixel_sample(start);
                    assert_eq!(values(&mut other), expected, "{:?} ({x}, {y}, {k})", sampler.kind());
                }
            }
        }
    }

    #[test]
    fn the_morton_table_holds_the_cells_the_bit_formula_gives_for_every_power_of_two_it_covers() {
        // Powers of two whose rows are not a power of two (32, 128) take
        // the stride order instead.
        let mut checked = Vec::new();
        for bits in 1..=MORTON_TABLE_BITS {
            let n = 1u32 << bits;
            let strata = Strata::new(n);
            let CellOrder::Morton { bits: b, wide } = strata.order else { continue };
            checked.push(n);
            assert_eq!((b, wide), (bits, bits % 2 == 1), "{n}");
            let shift = strata.base.trailing_zeros();
            let cells: Vec<u32> = (0..n).map(|k| strata.order.cell(k, n, shift)).collect();
            let formula: Vec<u32> = (0..n).map(|k| morton_cell(k, bits, wide, shift)).collect();
            assert_eq!(cells, formula, "{n} cells");
            let mut sorted = cells;
            sorted.sort_unstable();
            assert!(sorted.iter().copied().eq(0..n), "{n}: every cell once");
        }
        assert_eq!(checked, [2, 4, 8, 16, 64, 256]);
    }

    /// Sobol sampler `spp` samples per pixel, seed `seed`.
    fn sobol(spp: u32, seed: u64) -> Sampler {
        Sampler::new(spp, seed).with_kind(SamplerKind::Sobol)
    }

    #[test]
    fn a_sobol_samples_values_depend_on_its_pixel_index_seed_and_bounce_alone() {
        // Started twice, a sample hands out the same values; another pixel,
        // index or seed gives others. A bounce's values do not depend on
        // how many values earlier bounces drew (Russian roulette draws one
        // or none), and a walk's are not any bounce's.
        let draw = |sampler: &mut Sampler, x, y, k| {
            sampler.start_pixel_sample(x, y, k);
            (sampler.get_1d(), sampler.get_2d(), sampler.get_1d())
        };
        let mut a = sobol(16, 3);
        let first = draw(&mut a, 5, 6, 2);
        let _ = draw(&mut a, 9, 9, 0);
        assert_eq!(draw(&mut a, 5, 6, 2), first);
        for other in [draw(&mut a, 5, 6, 3), draw(&mut a, 6, 5, 2), draw(&mut sobol(16, 4), 5, 6, 2)] {
            assert_ne!(other, first);
        }
        let bounce = |before: usize| {
            let mut s = sobol(16, 3);
            s.start_pixel_sample(5, 6, 2);
            s.start_bounce(1);
            for _ in 0..before {
                s.get_1d();
            }
            s.start_bounce(2);
            (s.get_1d(), s.get_2d())
        };
        assert_eq!(bounce(4), bounce(5));
        let mut s = sobol(16, 3);
        s.start_pixel_sample(5, 6, 2);
        s.start_walk(2);
        assert_ne!((s.get_1d(), s.get_2d()), bounce(4));
        // The stratified method ignores bounces: its stream goes on.
        let mut t = Sampler::new(16, 3);
        t.start_pixel_sample(5, 6, 2);
        t.start_bounce(7);
        t.start_walk(7);
        assert_eq!(t.get_1d(), SampleRng::seeded(5, 6, 2, 3).next_pair().0);
        // One sample per pixel sees the pixel centre, as with strata; the
        // open-ended render never does.
        assert_eq!(sobol(1, 3).film_position(5, 6, 0), (0.5, 0.5));
        assert_ne!(sobol(1, 3).to_open_ended().film_position(5, 6, 0), (0.5, 0.5));
        assert_eq!(sobol(1, 3).to_open_ended().kind(), SamplerKind::Sobol);
    }

    #[test]
    fn a_pixels_sobol_film_and_lens_positions_fill_every_elementary_interval_of_each_power_of_two_prefix() {
        // The first 2^m samples of a pixel put one film position (and one
        // lens position) in each 2^−a × 2^−(m−a) interval, for every split:
        // what makes Sobol converge faster than jittered strata, whose
        // prefixes are not stratified at all unless the count is fixed.
        for (x, y) in [(0, 0), (13, 7)] {
            let s = sobol(1024, 5).to_open_ended();
            for m in 0..=10u32 {
                for a in 0..=m {
                    for position in [Sampler::film_position, Sampler::lens_position] {
                        let mut seen = vec![0u8; 1 << m];
                        for k in 0..1u32 << m {
                            let (u, v) = position(&s, x, y, k);
                            let (i, j) = (
                                (u * (1u32 << a) as Real) as usize,
                                (v * (1u32 << (m - a)) as Real) as usize,
                            );
                            seen[(j << a) | i] += 1;
                        }
                        assert!(seen.iter().all(|&n| n == 1), "pixel ({x}, {y}), 2^{m} split {a}");
                    }
                }
            }
        }
        assert_eq!(
            parse_kind(&["sobol", "Stratified", "halton"]),
            vec![
                Ok(SamplerKind::Sobol),
                Ok(SamplerKind::Stratified),
                Err("unknown sampler \"halton\": stratified or sobol".into())
            ]
        );
    }

    fn parse_kind(names: &[&str]) -> Vec<Result<SamplerKind, String>> {
        names.iter().map(|n| n.parse()).collect()
    }

    #[test]
    fn sobol_values_of_every_kind_of_dimension_are_uniform_and_independent_of_each_other() {
        // χ² (16 × 16 cells, α ≈ 10⁻⁴) over 100 pixels × 2048 samples of:
        // the film position; two 1D values of one bounce (light choice and
        // lobe choice: each uniform, and together uniform on the square,
        // so independent); a bounce's direction pair; and a walk step's
        // value against a later bounce's. Stratification only makes the
        // counts less variable than independent draws, so the bound holds.
        type Pick = fn(&mut Sampler, u32, u32, u32) -> (Real, Real);
        let picks: [(&str, Pick); 4] = [
            ("Sobol film", |s, x, y, k| s.film_position(x, y, k)),
            ("Sobol light and lobe choice", |s, _, _, _| {
                s.start_bounce(2);
                let light = s.get_1d();
                let _ = s.get_2d();
                (light, s.get_1d())
            }),
            ("Sobol direction", |s, _, _, _| {
                s.start_bounce(3);
                let _ = (s.get_1d(), s.get_2d(), s.get_1d());
                s.get_2d()
            }),
            ("Sobol walk step and bounce", |s, _, _, _| {
                s.start_walk(1);
                let step = (0..7).map(|_| s.get_1d()).last().unwrap();
                s.start_bounce(2);
                (step, s.get_1d())
            }),
        ];
        for (name, pick) in picks {
            let mut sampler = sobol(2048, 11);
            let mut i = 0u32;
            let draw = |_: &mut SampleRng| {
                let (x, y, k) = ((i / 2048) % 10, i / 20480, i % 2048);
                i += 1;
                sampler.start_pixel_sample(x, y, k);
                let (u, v) = pick(&mut sampler, x, y, k);
                Draw::At((to_f64(u), to_f64(v)))
            };
            let side = Interval { lo: 0.0, hi: 1.0, n: 16 };
            chi_square::plane(name, Rectangle { s: side, t: side }, 204_800, draw, &|_, _| 1.0);
        }
    }

    #[test]
    fn power_of_two_counts_place_points_with_the_general_arithmetic_bits() {
        let mut rng = SampleRng::seeded(3, 0, 0, 0);
        for n in [1, 2, 4, 8, 16, 64, 256, 1024] {
            let fast = Strata::new(n);
            assert!(fast.powers_of_two.is_some(), "{n}");
            let general = Strata { powers_of_two: None, ..fast };
            for k in 0..n {
                let jitters = [(0.0, 0.0), (1.0 - Real::EPSILON / 2.0, 1.0 - Real::EPSILON / 2.0)];
                let random = (0..8).map(|_| rng.next_pair());
                for jitter in jitters.into_iter().chain(random) {
                    let (a, b) = (fast.point(k, jitter), general.point(k, jitter));
                    assert_eq!((a.0.to_bits(), a.1.to_bits()), (b.0.to_bits(), b.1.to_bits()), "{n} {k}");
                }
            }
        }
        assert!(Strata::new(32).powers_of_two.is_none() && Strata::new(9).powers_of_two.is_none());
    }

    #[test]
    fn every_prefix_of_four_to_the_j_samples_falls_one_in_each_cell_of_the_coarser_grid() {
        // The viewer shows a 256-sample render after 1, 4, 16 and 64 samples:
        // each must cover the whole pixel (row-major order put the first 64
        // in its top quarter).
        for n in [4, 16, 64, 256, 1024] {
            let mut j = 0;
            while 1 << (2 * j) <= n {
                let (prefix, side) = (1u32 << (2 * j), 1u32 << j);
                let mut seen = vec![false; prefix as usize];
                for k in 0..prefix {
                    let (x, y) = stratified(k, n, (0.5, 0.5));
                    let cell = (y * side as Real) as usize * side as usize + (x * side as Real) as usize;
                    assert!(!seen[cell], "n = {n}: sample {k} shares a cell of the {side}×{side} grid");
                    seen[cell] = true;
                }
                j += 1;
            }
        }
        // 8 samples (a 4 × 2 grid): the first two in the left and right halves.
        let (a, b) = (stratified(0, 8, (0.5, 0.5)), stratified(1, 8, (0.5, 0.5)));
        assert!((a.0 < 0.5) != (b.0 < 0.5), "{a:?} {b:?}");
    }

    #[test]
    fn other_counts_visit_every_cell_once_and_spread_their_first_quarter_and_half_over_the_rows() {
        // Row-major order put the first quarter of the points in the top
        // quarter of the pixel: none below the middle.
        for n in (2..1100).filter(|n| !matches!(Strata::new(*n).order, CellOrder::Morton { .. })) {
            let strata = Strata::new(n);
            let mut cells: Vec<u32> = (0..n).map(|k| strata.order.cell(k, n, 0)).collect();
            for prefix in [n / 4, n / 2].into_iter().filter(|&m| m >= 2) {
                let below = (0..prefix).filter(|&k| strata.point(k, (0.5, 0.5)).1 >= 0.5).count();
                let half = prefix as f64 / 2.0;
                assert!(
                    (below as f64 - half).abs() <= 1.0 + half * 0.3,
                    "n = {n}: {below} of {prefix} below"
                );
            }
            cells.sort_unstable();
            assert_eq!(cells, (0..n).collect::<Vec<_>>(), "n = {n}");
        }
    }

    #[test]
    fn one_sample_is_the_pixel_centre() {
        assert_eq!(subpixel_offset(7, 3, 0, 1, 0), (0.5, 0.5));
    }

    #[test]
    fn the_one_cell_constant_is_the_layout_of_one_point() {
        assert_eq!(Strata::ONE, Strata::laid_out(1));
        let mut rng = SampleRng::new(2, 9, 4);
        for _ in 0..64 {
            let u = rng.next_pair();
            let (a, b) = (Strata::ONE.point(0, u), Strata::laid_out(1).point(0, u));
            assert_eq!((a.0.to_bits(), a.1.to_bits()), (b.0.to_bits(), b.1.to_bits()));
        }
    }

    #[test]
    fn cosine_directions_in_a_given_frame_have_the_bits_of_the_frame_made_per_direction() {
        let mut rng = SampleRng::new(5, 1, 8);
        for n in [Vec3::new(0.0, 0.6, 0.8), Vec3::new(0.0, 0.0, -1.0), Vec3::new(-0.48, 0.6, -0.64)] {
            let frame = n.any_orthonormal_pair();
            for _ in 0..256 {
                let u = rng.next_pair();
                let (a, b) = (cosine_hemisphere_in(n, frame, u), cosine_hemisphere(n, u));
                assert_eq!(a.to_array().map(Real::to_bits), b.to_array().map(Real::to_bits), "{n} {u:?}");
            }
        }
    }

    #[test]
    fn four_samples_fall_one_in_each_quadrant() {
        let mut quadrants: Vec<(bool, bool)> =
            (0..4).map(|k| subpixel_offset(5, 9, k, 4, 0)).map(|(x, y)| (x >= 0.5, y >= 0.5)).collect();
        quadrants.sort();
        assert_eq!(quadrants, vec![(false, false), (false, true), (true, false), (true, true)]);
    }

    #[test]
    fn every_stratum_has_the_same_area_for_any_count() {
        // Uniform jitter must give a uniform point: the strata of n points
        // tile the square with cells of area 1/n, for square and other n.
        for n in [1, 2, 3, 5, 8, 9, 12, 16, 17, 32, 1000] {
            let mut area = 0.0;
            let mut cells = Vec::new();
            for k in 0..n {
                let lo = stratified(k, n, (0.0, 0.0));
                let hi = stratified(k, n, (1.0, 1.0));
                let cell = (hi.0 - lo.0) * (hi.1 - lo.1);
                assert!((cell - 1.0 / n as Real).abs() < 1e-5, "n = {n}, cell {k}: {cell}");
                area += cell;
                cells.push((lo, hi));
            }
            assert!((area - 1.0).abs() < 1e-4, "n = {n}: {area}");
            // No two cells overlap, even in part (a shifted row would overlap
            // its neighbour and leave a gap elsewhere, with every cell's area
            // still 1/n).
            let slack = 1e-5;
            for (i, (lo, hi)) in cells.iter().enumerate() {
                for (j, (l, h)) in cells.iter().enumerate().skip(i + 1) {
                    let apart = hi.0 <= l.0 + slack
                        || h.0 <= lo.0 + slack
                        || hi.1 <= l.1 + slack
                        || h.1 <= lo.1 + slack;
                    assert!(apart, "n = {n}: cells {i} {:?} and {j} {:?} overlap", (lo, hi), (l, h));
                }
            }
            // A point in one is in no other.
            for (i, (lo, hi)) in cells.iter().enumerate() {
                let mid = ((lo.0 + hi.0) / 2.0, (lo.1 + hi.1) / 2.0);
                let inside = |(l, h): &((Real, Real), (Real, Real))| {
                    mid.0 >= l.0 && mid.0 < h.0 && mid.1 >= l.1 && mid.1 < h.1
                };
                assert_eq!(cells.iter().filter(|c| inside(c)).count(), 1, "n = {n}, cell {i}");
            }
        }
    }

    #[test]
    fn the_streams_of_pixels_and_samples_use_every_bit_of_their_state() {
        // Over 4096 streams, each of the 64 state bits is set in some and
        // clear in others (a hash losing bits would leave some fixed).
        let (mut any, mut all) = (0u64, u64::MAX);
        for k in 0..4096u32 {
            let state = SampleRng::seeded(k % 64, k / 64, k % 7, 0).0;
            (any, all) = (any | state, all & state);
        }
        assert_eq!((any, all), (u64::MAX, 0));
    }

    #[test]
    fn the_largest_jitter_stays_below_one_and_an_index_past_the_count_stays_in_the_last_point_s_cell() {
        // Jitter just below 1 in the last cell (whichever point has it) gives
        // the largest number below 1 (not 1, not less); k ≥ n is point n − 1.
        let top = 1.0 - Real::EPSILON / 2.0;
        for n in [1, 5, 16, 17] {
            let strata = Strata::new(n);
            assert!((0..n).any(|k| strata.point(k, (top, top)) == (top, top)), "n = {n}");
            assert_eq!(strata.point(n + 3, (0.25, 0.75)), strata.point(n - 1, (0.25, 0.75)), "n = {n}");
        }
    }

    #[test]
    fn offsets_stay_in_the_half_open_unit_square_and_are_reproducible() {
        for spp in [2, 3, 5, 16, 17] {
            for k in 0..spp {
                let (sx, sy) = subpixel_offset(1234, 567, k, spp, 7);
                assert!((0.0..1.0).contains(&sx) && (0.0..1.0).contains(&sy));
                assert_eq!((sx, sy), subpixel_offset(1234, 567, k, spp, 7));
            }
        }
    }

    #[test]
    fn the_concentric_map_stays_in_the_disk_and_keeps_quadrants() {
        for (u, v) in [(0.0, 0.0), (0.99, 0.5), (0.5, 0.5), (0.25, 0.9), (0.999, 0.999)] {
            let (x, y) = concentric_disk((u, v));
            assert!(x * x + y * y <= 1.0 + 1e-6, "({u}, {v})");
            assert!((x >= 0.0) == (u >= 0.5) || x.abs() < 1e-6, "({u}, {v}) → ({x}, {y})");
        }
    }

    #[test]
    fn cosine_directions_stay_above_the_surface() {
        let n = Vec3::new(0.0, 0.6, 0.8);
        let mut rng = SampleRng::new(3, 4, 5);
        for k in 0..64 {
            let d = cosine_hemisphere(n, stratified(k, 64, rng.next_pair()));
            assert!(d.dot(n) >= 0.0 && (d.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn neighbouring_pixels_get_different_jitter() {
        assert_ne!(subpixel_offset(0, 0, 0, 4, 0), subpixel_offset(1, 0, 0, 4, 0));
        assert_ne!(subpixel_offset(0, 0, 0, 4, 0), subpixel_offset(0, 1, 0, 4, 0));
    }

    #[test]
    fn seed_zero_is_the_default_stream_and_other_seeds_differ() {
        assert_eq!(SampleRng::seeded(3, 4, 5, 0).next_pair(), SampleRng::new(3, 4, 5).next_pair());
        assert_ne!(SampleRng::seeded(3, 4, 5, 1).next_pair(), SampleRng::new(3, 4, 5).next_pair());
        assert_ne!(subpixel_offset(3, 4, 5, 16, 1), subpixel_offset(3, 4, 5, 16, 0));
    }

    #[test]
    fn cosine_directions_follow_the_density_cos_over_pi() {
        // χ² of 2·10⁵ directions about a tilted normal on a 20 × 40
        // equal-area grid of the sphere about it, against cos θ/π above and
        // 0 below (α ≈ 10⁻⁴, see `chi_square`).
        let n = Vec3::new(0.3, -0.5, 0.8).normalize();
        let draw = |rng: &mut SampleRng| Draw::At(widen(cosine_hemisphere(n, rng.next_pair())));
        let axis = widen(n);
        let grid = SphereGrid::sphere(axis, 20, 40);
        chi_square::directions("cosine hemisphere", &grid, 200_000, draw, &|d| {
            d.dot(axis).max(0.0) * std::f64::consts::FRAC_1_PI
        });
    }

    #[test]
    fn uniform_sphere_directions_follow_the_density_one_over_four_pi() {
        // χ² of 2·10⁵ directions on a 16 × 32 equal-area grid of the sphere
        // about a tilted axis, against `uniform_sphere_pdf` everywhere (the
        // density of a constant environment's samples and of a walk's first
        // step out of a boundary).
        let axis = widen(Vec3::new(0.3, -0.5, 0.8).normalize());
        let draw = |rng: &mut SampleRng| Draw::At(widen(uniform_sphere(rng.next_pair())));
        let grid = SphereGrid::sphere(axis, 16, 32);
        let density = to_f64(uniform_sphere_pdf());
        chi_square::directions("uniform sphere", &grid, 200_000, draw, &|_| density);
    }

    #[test]
    fn the_concentric_map_is_uniform_on_the_disk() {
        // χ² of 2·10⁵ points on a 20 × 20 grid of [−1, 1]², against 1/π
        // inside the unit disk and 0 outside (α ≈ 10⁻⁴).
        let draw = |rng: &mut SampleRng| {
            let (x, y) = concentric_disk(rng.next_pair());
            Draw::At((to_f64(x), to_f64(y)))
        };
        let side = Interval { lo: -1.0, hi: 1.0, n: 20 };
        let grid = Rectangle { s: side, t: side };
        chi_square::plane("concentric disk", grid, 200_000, draw, &|x, y| {
            if x * x + y * y < 1.0 { std::f64::consts::FRAC_1_PI } else { 0.0 }
        });
    }

    #[test]
    fn open_ended_blocks_grow_fourfold_then_stay_at_the_block_length_and_tile_the_indices() {
        let blocks: Vec<Range<u32>> =
            [0, 1, 3, 4, 15, 16, 64, 256, 1023, 1024, 2047, 5000].into_iter().map(open_ended_block).collect();
        let expected = [
            0..1,
            1..4,
            1..4,
            4..16,
            4..16,
            16..64,
            64..256,
            256..1024,
            256..1024,
            1024..2048,
            1024..2048,
            4096..5120,
        ];
        assert_eq!(blocks, expected);
        // Every index lies in its block, and blocks follow one another up to the cap.
        let mut end = 0;
        let mut k = 0;
        while k < MAX_OPEN_ENDED_SAMPLES {
            let block = open_ended_block(k);
            assert_eq!(block.start, end, "a gap or overlap before {k}");
            assert!(block.contains(&k) && open_ended_block(block.end - 1) == block);
            end = block.end;
            k = block.end;
        }
        assert_eq!(end, MAX_OPEN_ENDED_SAMPLES);
    }

    #[test]
    fn open_ended_film_positions_are_stratified_per_block_and_uniform_over_the_pixel() {
        // Each block's positions fall one per stratum of the block's length
        // (the one-sample block anywhere, not at the centre), so the union
        // of whole blocks is uniform: χ² of the first 2048 samples of 100
        // pixels on a 16 × 16 grid against the density 1.
        let s = Sampler::open_ended(0);
        assert_ne!(s.film_position(3, 4, 0), (0.5, 0.5));
        for block in [1..4, 4..16, 16..64] {
            let n = block.len() as u32;
            let strata = Strata::new(n);
            let corner = 1.0 - Real::EPSILON;
            let cell_of = |(x, y): (Real, Real)| {
                (0..n).filter(move |&c| {
                    let ((x0, y0), (x1, y1)) =
                        (strata.point(c, (0.0, 0.0)), strata.point(c, (corner, corner)));
                    (x0..=x1).contains(&x) && (y0..=y1).contains(&y)
                })
            };
            let mut cells: Vec<u32> = block.clone().flat_map(|k| cell_of(s.film_position(3, 4, k))).collect();
            cells.sort();
            assert_eq!(cells, (0..n).collect::<Vec<_>>(), "block {block:?}");
        }
        let mut k = 0;
        let mut pixel = 0;
        let draw = |_: &mut SampleRng| {
            let (x, y) = s.film_position(pixel % 10, pixel / 10, k);
            k += 1;
            if k == 2048 {
                (k, pixel) = (0, pixel + 1);
            }
            Draw::At((to_f64(x), to_f64(y)))
        };
        let side = Interval { lo: 0.0, hi: 1.0, n: 16 };
        chi_square::plane("open-ended", Rectangle { s: side, t: side }, 204_800, draw, &|_, _| 1.0);
    }

    #[test]
    fn a_sobol_sampler_kept_over_many_pixels_hands_out_each_slots_values_bit_for_bit() {
        // One sampler visits pixels in runs, back and forth, across the
        // block boundary of the Sobol table, past its cached slots (deep
        // bounces, walks) and through its tags' wrap-around: every value is
        // the one sobol::value_1d/value_2d make from scratch, and the film
        // and lens positions those of `film_position`/`lens_position`.
        let seed = 9;
        let mut sampler = sobol(64, seed);
        let end = sobol::SEQUENCE_LENGTH;
        let visits = [(3, 4, 0), (3, 4, 1), (3, 4, 2), (4, 3, 0), (3, 4, 3), (3, 4, end - 1), (3, 4, end)]
            .into_iter()
            .chain([(3, 4, end + 1), (3, 4, 5), (0, 0, 0), (0, 0, 0)]);
        let wrap = [(3, 4, 0), (4, 3, 0)];
        for (round, (x, y, k)) in visits.clone().chain(visits).chain(wrap).enumerate() {
            if round == 23 {
                // The tags wrap here: those made for the first pixel (tag 1
                // after the last wrap) are not the second's.
                let mut fresh = sobol(64, seed);
                fresh.start_pixel_sample(3, 4, 0);
                (0..16).for_each(|b| {
                    fresh.start_bounce(b);
                    fresh.get_2d();
                });
                sampler = fresh;
                sampler.sobol.generation = u32::MAX;
            }
            let pixel = sobol::pixel_seed(x, y, seed);
            sampler.start_pixel_sample(x, y, k);
            assert_eq!(sampler.film(), sampler.film_position(x, y, k), "({x}, {y}) {k}");
            assert_eq!(sampler.film(), sobol::value_2d(pixel, FILM_SLOT, k));
            assert_eq!(sampler.lens(), sampler.lens_position(x, y, k));
            for bounce in [1, 2, 7, 15, 16, 40] {
                sampler.start_bounce(bounce);
                let slot = PATH_SLOTS + bounce * BOUNCE_SLOTS;
                assert_eq!(sampler.get_1d(), sobol::value_1d(pixel, slot, k), "bounce {bounce}, {k}");
                assert_eq!(sampler.get_2d(), sobol::value_2d(pixel, slot + 1, k));
            }
            sampler.start_walk(3);
            assert_eq!(sampler.get_2d(), sobol::value_2d(pixel, WALK_SLOTS + 3 * (1 << 20), k));
        }
    }

    #[test]
    fn the_current_samples_film_and_lens_positions_are_those_of_its_pixel_and_index() {
        for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
            for spp in [1, 4, 70] {
                for mut sampler in
                    [Sampler::new(spp, 2).with_kind(kind), Sampler::open_ended(2).with_kind(kind)]
                {
                    for (x, y, k) in [(0, 0, 0), (5, 1, 3), (5, 1, 2), (6, 1, 2), (6, 1, 1000)] {
                        sampler.start_pixel_sample(x, y, k);
                        assert_eq!(sampler.film(), sampler.film_position(x, y, k), "{kind:?} {spp} {k}");
                        assert_eq!(sampler.lens(), sampler.lens_position(x, y, k));
                    }
                }
            }
        }
    }

    #[test]
    fn an_open_ended_sampler_hands_out_the_paths_values_of_a_fixed_one() {
        let (mut open, mut fixed) = (Sampler::open_ended(5), Sampler::new(64, 5));
        open.start_pixel_sample(7, 8, 9);
        fixed.start_pixel_sample(7, 8, 9);
        assert_eq!((open.get_1d(), open.get_2d()), (fixed.get_1d(), fixed.get_2d()));
    }

    #[test]
    fn stratified_points_are_uniform_on_the_square_for_any_count() {
        // Point k of n, for k running through 0..n over and over with a
        // uniform jitter: χ² of 2·10⁵ points on a 16 × 16 grid against the
        // density 1 (α ≈ 10⁻⁴). Stratification only makes the counts less
        // variable than independent draws, so the bound stays valid.
        for n in [5, 16, 17, 1000] {
            let strata = Strata::new(n);
            let mut k = 0;
            let draw = |rng: &mut SampleRng| {
                k = (k + 1) % n;
                let (x, y) = strata.point(k, rng.next_pair());
                Draw::At((to_f64(x), to_f64(y)))
            };
            let side = Interval { lo: 0.0, hi: 1.0, n: 16 };
            chi_square::plane(
                &format!("{n} strata"),
                Rectangle { s: side, t: side },
                200_000,
                draw,
                &|_, _| 1.0,
            );
        }
    }
}
