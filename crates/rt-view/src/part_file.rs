//! Part files: one part of a render split over several machines
//! (`rt-view render --part K/N`), to be merged by `rt-view merge`.
//!
//! A part holds, for each pixel of its rows, the exact sums of its samples
//! ([`ExactColorSum`]), and says what it is ([`PartHeader`]): the scene's
//! content hash, the render settings, which of how many parts it is, its
//! rows and sample indices, the rt-view version.
//!
//! # Format (version 1)
//!
//! ```text
//! "RTVIEW-PART\n"                  12 bytes, the magic
//! version                          u32, little-endian (1)
//! header length L                  u64, little-endian (at most 1 MiB)
//! header                           L bytes of JSON (PartHeader)
//! sums                             48 bytes a pixel (three i128, little-endian),
//!                                  row-major over the part's rows, full width
//! checksum                         16 bytes: 128-bit FNV-1a of all the above
//! ```
//!
//! Not OpenEXR: the sums are 128-bit integers, which no EXR channel type
//! holds (a viewer could not show them anyway), and an EXR has no checksum,
//! so a flipped bit in its pixels would go into the merged image unnoticed.
//! Here every byte is checked, and a short, long or damaged file is an
//! error that says which ([`PartError`]). Parts are written atomically
//! ([`crate::image_out::PendingFile`]), so a task killed mid-write leaves
//! none.

use std::io::{Read, Write};
use std::ops::Range;
use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::content_hash::Fnv1a128;
use crate::exact_sum::ExactColorSum;

/// The first bytes of every part file.
pub const MAGIC: &[u8; 12] = b"RTVIEW-PART\n";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;
/// The longest header a part may have: far more than any has.
const MAX_HEADER: u64 = 1 << 20;
/// Bytes before the header: magic, version, header length.
const PREFIX: usize = 12 + 4 + 8;
/// Bytes of the checksum at the end.
const CHECKSUM: usize = 16;

/// How a render is split into parts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SplitKind {
    /// Every pixel, sample indices [K·S/N, (K+1)·S/N) of S.
    Samples,
    /// Rows [K·H/N, (K+1)·H/N) of H (bands across the whole width), every sample.
    Tiles,
}

impl SplitKind {
    /// The word for it in messages.
    pub fn name(self) -> &'static str {
        match self {
            Self::Samples => "sample ranges",
            Self::Tiles => "tiles",
        }
    }
}

/// Part `index` of `count` (0-based, as SLURM array indices are).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Split {
    /// By samples or by tiles.
    pub kind: SplitKind,
    /// K, in 0..N.
    pub index: u32,
    /// N.
    pub count: u32,
}

impl Split {
    /// K of N's share of `0..total`: [K·total/N, (K+1)·total/N).
    fn share(&self, total: u32) -> Range<u32> {
        let at = |k: u32| (k as u64 * total as u64 / self.count as u64) as u32;
        at(self.index)..at(self.index + 1)
    }

    /// The rows and sample indices of this part of an image `height` rows
    /// tall at `spp` samples per pixel.
    pub fn ranges(&self, height: u32, spp: u32) -> (Range<u32>, Range<u32>) {
        match self.kind {
            SplitKind::Samples => (0..height, self.share(spp)),
            SplitKind::Tiles => (self.share(height), 0..spp),
        }
    }
}

/// The settings a render was made with, besides the scene file's content:
/// parts merge only if these are equal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartSettings {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Samples per pixel of the whole render.
    pub spp: u32,
    /// The seed of the random numbers.
    pub seed: u64,
    /// How the merged PNG is encoded: "linear" or "srgb" (the scene's).
    pub color_space: String,
    /// The PNG's exposure, stops.
    pub exposure: f32,
    /// The PNG's view transform ("standard" or "agx").
    pub view_transform: String,
}

/// What a part file is.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PartHeader {
    /// The rt-view version that rendered it: parts of different versions
    /// may differ in their pixels, so do not merge.
    pub rt_view_version: String,
    /// The scene file as given on the command line (for messages only).
    pub scene: String,
    /// [`crate::content_hash::content_hash`] of the scene file and the files it loads.
    pub scene_hash: String,
    /// The render settings.
    pub settings: PartSettings,
    /// Which part.
    pub split: Split,
    /// The rows it holds (full width).
    pub rows: Range<u32>,
    /// The sample indices it holds, of each pixel of its rows.
    pub samples: Range<u32>,
    /// Seconds spent loading the scene (BVH build included) and hashing its files.
    pub load_seconds: f64,
    /// Seconds spent rendering.
    pub render_seconds: f64,
    /// Rays cast, all kinds.
    pub rays: u64,
}

impl PartHeader {
    /// Pixels of sums the part holds.
    pub fn pixels(&self) -> u64 {
        self.settings.width as u64 * (self.rows.end.saturating_sub(self.rows.start)) as u64
    }

    /// Samples per pixel it holds.
    pub fn samples_held(&self) -> u32 {
        self.samples.end.saturating_sub(self.samples.start)
    }

    /// Whether the rows and samples are what its split says they are, and
    /// fit the image (a header that passed the checksum but was written by
    /// something else is still refused).
    fn check(&self) -> Result<(), String> {
        let s = &self.settings;
        if self.split.count == 0 || self.split.index >= self.split.count {
            return Err(format!("part {}/{} does not exist", self.split.index, self.split.count));
        }
        if s.width == 0 || s.height == 0 || s.spp == 0 {
            return Err(format!("image {}x{} at {} spp is empty", s.width, s.height, s.spp));
        }
        // The largest image rt-view renders (docs/command-line.md's limits),
        // checked before a merge allocates the image's sums.
        if s.width > 32_768 || s.height > 32_768 || s.width as u64 * s.height as u64 > 1 << 27 {
            return Err(format!("image {}x{} is larger than any rt-view renders", s.width, s.height));
        }
        let (rows, samples) = self.split.ranges(s.height, s.spp);
        if (rows.clone(), samples.clone()) != (self.rows.clone(), self.samples.clone()) {
            return Err(format!(
                "rows {:?} and samples {:?} are not part {}/{}'s ({rows:?}, {samples:?})",
                self.rows, self.samples, self.split.index, self.split.count
            ));
        }
        Ok(())
    }
}

/// Why a part file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum PartError {
    /// The file cannot be opened or read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// Not a part file at all.
    #[error("not an rt-view part file (it does not start with the part file mark)")]
    NotAPart,
    /// A part file of another format version.
    #[error("part file format version {0}; this rt-view reads version {VERSION}")]
    Version(u32),
    /// Shorter than its header says: a write cut off, or a copy.
    #[error("truncated: {got} bytes where its header makes {want}")]
    Truncated {
        /// The file's length.
        got: u64,
        /// The length it should have.
        want: u64,
    },
    /// Longer than its header says.
    #[error("{got} bytes where its header makes {want}: something was appended")]
    TooLong {
        /// The file's length.
        got: u64,
        /// The length it should have.
        want: u64,
    },
    /// The header cannot be read.
    #[error("damaged header: {0}")]
    Header(String),
    /// The checksum does not match the contents.
    #[error("damaged: the checksum does not match its contents")]
    Checksum,
}

/// The bytes of a part file.
pub fn encode(header: &PartHeader, sums: &[ExactColorSum]) -> Vec<u8> {
    assert_eq!(sums.len() as u64, header.pixels(), "one sum per pixel of the part's rows");
    let json = serde_json::to_vec(header).expect("a header serialises");
    let mut out = Vec::with_capacity(PREFIX + json.len() + sums.len() * ExactColorSum::BYTES + CHECKSUM);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(json.len() as u64).to_le_bytes());
    out.extend_from_slice(&json);
    for s in sums {
        out.extend_from_slice(&s.to_le_bytes());
    }
    let mut hash = Fnv1a128::default();
    hash.write(&out);
    out.extend_from_slice(&hash.finish().to_le_bytes());
    out
}

/// Writes a part file's bytes to `out`.
pub fn write(out: &mut impl Write, header: &PartHeader, sums: &[ExactColorSum]) -> std::io::Result<()> {
    out.write_all(&encode(header, sums))
}

/// The header of the part at `path`, read without its sums (quick: to check
/// a set of parts before reading them), and the length the file must have.
pub fn read_header(path: &Path) -> Result<(PartHeader, u64), PartError> {
    let mut file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    let mut prefix = [0; PREFIX];
    read_exact_or_truncated(&mut file, &mut prefix, len, PREFIX as u64)?;
    let header_len = check_prefix(&prefix, len)?;
    let mut json = vec![0; header_len as usize];
    read_exact_or_truncated(&mut file, &mut json, len, PREFIX as u64 + header_len)?;
    let header = parse_header(&json)?;
    let want = file_length(header_len, &header);
    if len < want {
        return Err(PartError::Truncated { got: len, want });
    }
    if len > want {
        return Err(PartError::TooLong { got: len, want });
    }
    Ok((header, want))
}

/// Reads the part at `path`: its header and sums, every byte checked.
pub fn read(path: &Path) -> Result<(PartHeader, Vec<ExactColorSum>), PartError> {
    decode(&std::fs::read(path)?)
}

/// A part from its bytes, every byte checked.
pub fn decode(bytes: &[u8]) -> Result<(PartHeader, Vec<ExactColorSum>), PartError> {
    let len = bytes.len() as u64;
    let prefix = bytes.get(..PREFIX).ok_or(PartError::Truncated { got: len, want: PREFIX as u64 })?;
    let header_len = check_prefix(prefix.try_into().expect("PREFIX bytes"), len)?;
    let json_end = PREFIX + header_len as usize;
    let json = bytes.get(PREFIX..json_end).ok_or(PartError::Truncated { got: len, want: json_end as u64 })?;
    // The checksum first where the length is right: a damaged header is
    // then reported as damage, not as whatever its garbled JSON says.
    let header = parse_header(json);
    if let Ok(h) = &header {
        let want = file_length(header_len, h);
        if len < want {
            return Err(PartError::Truncated { got: len, want });
        }
        if len > want {
            return Err(PartError::TooLong { got: len, want });
        }
    }
    let body = &bytes[..bytes.len().saturating_sub(CHECKSUM)];
    let mut hash = Fnv1a128::default();
    hash.write(body);
    let stored = bytes.get(body.len()..).and_then(|c| <[u8; 16]>::try_from(c).ok()).map(u128::from_le_bytes);
    if stored != Some(hash.finish()) {
        return Err(PartError::Checksum);
    }
    let header = header?;
    let sums = bytes[json_end..body.len()]
        .chunks_exact(ExactColorSum::BYTES)
        .map(|c| ExactColorSum::from_le_bytes(c.try_into().expect("48 bytes")))
        .collect();
    Ok((header, sums))
}

/// The header's length from the prefix, after checking the magic and version.
fn check_prefix(prefix: &[u8; PREFIX], len: u64) -> Result<u64, PartError> {
    if &prefix[..12] != MAGIC {
        return Err(PartError::NotAPart);
    }
    let version = u32::from_le_bytes(prefix[12..16].try_into().expect("4 bytes"));
    if version != VERSION {
        return Err(PartError::Version(version));
    }
    let header_len = u64::from_le_bytes(prefix[16..24].try_into().expect("8 bytes"));
    if header_len > MAX_HEADER {
        return Err(PartError::Header(format!("{header_len} bytes of header (at most {MAX_HEADER})")));
    }
    if PREFIX as u64 + header_len > len {
        return Err(PartError::Truncated { got: len, want: PREFIX as u64 + header_len });
    }
    Ok(header_len)
}

/// The header from its JSON, checked for sense.
fn parse_header(json: &[u8]) -> Result<PartHeader, PartError> {
    let header: PartHeader = serde_json::from_slice(json).map_err(|e| PartError::Header(e.to_string()))?;
    header.check().map_err(PartError::Header)?;
    Ok(header)
}

/// The length a part file with this header must have.
fn file_length(header_len: u64, header: &PartHeader) -> u64 {
    PREFIX as u64 + header_len + header.pixels() * ExactColorSum::BYTES as u64 + CHECKSUM as u64
}

/// Fills `buf` from `file`, calling a short file truncated (`want` bytes
/// at least, of `len`).
fn read_exact_or_truncated(
    file: &mut impl Read,
    buf: &mut [u8],
    len: u64,
    want: u64,
) -> Result<(), PartError> {
    file.read_exact(buf).map_err(|e| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => PartError::Truncated { got: len, want },
        _ => PartError::Io(e),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(split: Split) -> PartHeader {
        let (rows, samples) = split.ranges(3, 10);
        PartHeader {
            rt_view_version: "0.1.0".into(),
            scene: "s.ron".into(),
            scene_hash: "00ff".into(),
            settings: PartSettings {
                width: 4,
                height: 3,
                spp: 10,
                seed: 1,
                color_space: "srgb".into(),
                exposure: 0.5,
                view_transform: "agx".into(),
            },
            split,
            rows,
            samples,
            load_seconds: 0.25,
            render_seconds: 1.5,
            rays: 1234,
        }
    }

    fn part() -> (PartHeader, Vec<ExactColorSum>) {
        let h = header(Split { kind: SplitKind::Samples, index: 1, count: 3 });
        let sums = (0..12).map(|i| ExactColorSum([i, -i << 70, i128::MAX - i])).collect();
        (h, sums)
    }

    #[test]
    fn shares_tile_the_whole_without_gaps_or_overlaps() {
        for (total, count) in [(10, 3), (7, 7), (256, 4), (5, 1), (1000, 64), (u32::MAX, 7)] {
            let mut next = 0;
            for index in 0..count {
                let split = Split { kind: SplitKind::Samples, index, count };
                let (rows, samples) = split.ranges(9, total);
                assert_eq!(rows, 0..9);
                assert_eq!(samples.start, next, "{index}/{count} of {total}");
                assert!(!samples.is_empty());
                next = samples.end;
                let tiles = Split { kind: SplitKind::Tiles, ..split }.ranges(total, 9);
                assert_eq!(tiles, (samples, 0..9));
            }
            assert_eq!(next, total);
        }
    }

    #[test]
    fn a_part_reads_back_as_written_from_bytes_and_from_a_file() {
        let (h, sums) = part();
        let bytes = encode(&h, &sums);
        assert_eq!(decode(&bytes).unwrap(), (h.clone(), sums.clone()));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.rtpart");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(read(&path).unwrap(), (h.clone(), sums));
        assert_eq!(read_header(&path).unwrap(), (h, bytes.len() as u64));
    }

    #[test]
    fn every_truncation_is_an_error_never_a_panic() {
        let (h, sums) = part();
        let bytes = encode(&h, &sums);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.rtpart");
        for len in 0..bytes.len() {
            let e = decode(&bytes[..len]).unwrap_err();
            assert!(
                matches!(e, PartError::Truncated { .. } | PartError::NotAPart | PartError::Header(_)),
                "{len}: {e}"
            );
            if len > PREFIX + 10 {
                assert!(matches!(e, PartError::Truncated { .. } | PartError::Header(_)), "{len}: {e}");
            }
            if len < 30 {
                std::fs::write(&path, &bytes[..len]).unwrap();
                assert!(read_header(&path).is_err());
            }
        }
        let mut long = bytes.clone();
        long.push(0);
        assert!(matches!(decode(&long).unwrap_err(), PartError::TooLong { .. }));
        // The header alone is read before a merge allocates anything: it
        // checks the length too.
        for len in [bytes.len() - 1, bytes.len() - 48] {
            std::fs::write(&path, &bytes[..len]).unwrap();
            assert!(matches!(read_header(&path).unwrap_err(), PartError::Truncated { .. }), "{len}");
        }
        std::fs::write(&path, &long).unwrap();
        assert!(matches!(read_header(&path).unwrap_err(), PartError::TooLong { .. }));
    }

    #[test]
    fn every_flipped_bit_is_an_error_never_a_panic() {
        let (h, sums) = part();
        let bytes = encode(&h, &sums);
        for at in 0..bytes.len() {
            for bit in [0, 3, 7] {
                let mut damaged = bytes.clone();
                damaged[at] ^= 1 << bit;
                assert!(decode(&damaged).is_err(), "byte {at}, bit {bit}");
            }
        }
    }

    #[test]
    fn other_files_and_versions_are_named_as_such() {
        assert!(matches!(
            decode(b"P6\n4 3\n255\nxxxxxxxxxxxxxxxxxxxxxxxx").unwrap_err(),
            PartError::NotAPart
        ));
        let (h, sums) = part();
        let mut bytes = encode(&h, &sums);
        bytes[12] = 9;
        assert_eq!(
            decode(&bytes).unwrap_err().to_string(),
            "part file format version 9; this rt-view reads version 1"
        );
    }

    #[test]
    fn a_header_of_an_image_larger_than_any_rendered_is_refused() {
        let (mut h, _) = part();
        h.settings.width = 1 << 20;
        let json = serde_json::to_vec(&h).unwrap();
        let e = parse_header(&json).unwrap_err();
        assert!(e.to_string().contains("larger than any rt-view renders"), "{e}");
    }

    #[test]
    fn a_header_whose_ranges_are_not_its_splits_is_refused() {
        let (mut h, _) = part();
        h.samples = 0..10;
        let sums = vec![ExactColorSum::default(); 12];
        let e = decode(&encode(&h, &sums)).unwrap_err();
        assert!(e.to_string().contains("not part 1/3's"), "{e}");
    }
}
