//! The container of a scene cache: a fixed prefix, a section table, and
//! sections of plain little-endian numbers, each aligned to 64 bytes and
//! with its own CRC-32.
//!
//! ```text
//! prefix (64 bytes): magic "RTSCENE\0" | format version u32 | bytes per Real u32
//!                    | table offset u64 | sections u64 | table CRC-32 u32 | 0…
//! table:             one entry a section: kind u32 | CRC-32 u32 | offset u64 | length u64
//! sections:          at their offsets, each a multiple of 64
//! ```
//!
//! Reading checks the magic, the format version and the number size
//! before anything else, then the table's checksum, then each section's
//! offset, length and checksum before its bytes are used: a truncated
//! or damaged file is an error, never a panic. Numbers are read with
//! `bytemuck` casts of the mapped bytes (one copy into the scene's own
//! arrays), which need the 64-byte alignment the writer gives and the
//! reader checks.

use super::cache_error::CacheError;

/// The first bytes of every scene cache.
pub const MAGIC: [u8; 8] = *b"RTSCENE\0";
/// The layout's version: changed whenever what is stored changes.
pub const FORMAT_VERSION: u32 = 1;
/// Bytes of the fixed prefix.
const PREFIX: usize = 64;
/// Bytes of a table entry.
const ENTRY: usize = 24;
/// Every section starts at a multiple of this.
const ALIGN: usize = 64;

/// What a section holds (checked on reading, so that sections cannot be
/// swapped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum Kind {
    /// RON text: where the cache came from ([`super::Meta`]).
    Meta = 1,
    /// CBOR: the scene's small parts.
    Small = 2,
    /// Plain numbers (Real, f32 or u32, as the reader expects).
    Array = 3,
}

/// Builds a cache file in memory.
#[derive(Default)]
pub struct Writer {
    sections: Vec<(Kind, Vec<u8>)>,
}

impl Writer {
    /// Adds a section of bytes.
    pub fn bytes(&mut self, kind: Kind, bytes: Vec<u8>) {
        self.sections.push((kind, bytes));
    }

    /// Adds a section of numbers, little-endian.
    pub fn array<T: bytemuck::Pod>(&mut self, values: &[T]) {
        self.bytes(Kind::Array, bytemuck::cast_slice(values).to_vec());
    }

    /// Adds `other`'s sections after these.
    pub fn append(&mut self, other: Writer) {
        self.sections.extend(other.sections);
    }

    /// The whole file.
    pub fn finish(self) -> Vec<u8> {
        let table_at = PREFIX;
        let mut at = (table_at + ENTRY * self.sections.len()).next_multiple_of(ALIGN);
        let mut table = Vec::with_capacity(ENTRY * self.sections.len());
        for (kind, bytes) in &self.sections {
            table.extend((*kind as u32).to_le_bytes());
            table.extend(crc32fast::hash(bytes).to_le_bytes());
            table.extend((at as u64).to_le_bytes());
            table.extend((bytes.len() as u64).to_le_bytes());
            at = (at + bytes.len()).next_multiple_of(ALIGN);
        }
        let mut out = Vec::with_capacity(at);
        out.extend(MAGIC);
        out.extend(FORMAT_VERSION.to_le_bytes());
        out.extend((size_of::<rt_core::Real>() as u32).to_le_bytes());
        out.extend((table_at as u64).to_le_bytes());
        out.extend((self.sections.len() as u64).to_le_bytes());
        out.extend(crc32fast::hash(&table).to_le_bytes());
        out.resize(PREFIX, 0);
        out.extend(table);
        for (_, bytes) in &self.sections {
            out.resize(out.len().next_multiple_of(ALIGN), 0);
            out.extend(bytes);
        }
        out.resize(out.len().next_multiple_of(ALIGN), 0);
        out
    }
}

/// Whether `bytes` (a file's first bytes) start like a scene cache.
pub fn has_magic(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// Reads a cache's sections one after the other, each checked.
pub struct Reader<'a> {
    file: &'a [u8],
    table: Vec<(u32, u32, u64, u64)>,
    next: usize,
}

impl<'a> Reader<'a> {
    /// The reader of `file` (the whole cache), its prefix and table checked.
    pub fn new(file: &'a [u8]) -> Result<Self, CacheError> {
        if !has_magic(file) {
            return Err(CacheError::NotACache);
        }
        let corrupt = |what: &str| CacheError::Corrupt(what.to_owned());
        if file.len() < PREFIX {
            return Err(corrupt("shorter than its header"));
        }
        let u32_at = |at: usize| u32::from_le_bytes(file[at..at + 4].try_into().expect("4 bytes"));
        let u64_at = |at: usize| u64::from_le_bytes(file[at..at + 8].try_into().expect("8 bytes"));
        let version = u32_at(8);
        if version != FORMAT_VERSION {
            return Err(CacheError::FormatVersion { found: version, expected: FORMAT_VERSION });
        }
        let real = u32_at(12);
        if real as usize != size_of::<rt_core::Real>() {
            return Err(CacheError::NumberSize { found: real, expected: size_of::<rt_core::Real>() as u32 });
        }
        let (table_at, count) = (u64_at(16), u64_at(24));
        let table_len =
            count.checked_mul(ENTRY as u64).ok_or_else(|| corrupt("section count out of range"))?;
        let table_end = table_at.checked_add(table_len).filter(|&e| e <= file.len() as u64);
        let Some(table_end) = table_end else {
            return Err(corrupt("section table beyond the end of the file"));
        };
        let table_bytes = &file[table_at as usize..table_end as usize];
        if crc32fast::hash(table_bytes) != u32_at(32) {
            return Err(corrupt("section table checksum mismatch"));
        }
        let table = table_bytes
            .chunks_exact(ENTRY)
            .map(|e| {
                let u32_of = |at: usize| u32::from_le_bytes(e[at..at + 4].try_into().expect("4 bytes"));
                let u64_of = |at: usize| u64::from_le_bytes(e[at..at + 8].try_into().expect("8 bytes"));
                (u32_of(0), u32_of(4), u64_of(8), u64_of(16))
            })
            .collect();
        Ok(Self { file, table, next: 0 })
    }

    /// The next section's bytes, which must be of `kind`, checked.
    pub fn bytes(&mut self, kind: Kind) -> Result<&'a [u8], CacheError> {
        let index = self.next;
        let corrupt = |what: String| CacheError::Corrupt(format!("section {index}: {what}"));
        let &(found, crc, at, len) =
            self.table.get(index).ok_or_else(|| corrupt("missing (the table ends before)".into()))?;
        self.next += 1;
        if found != kind as u32 {
            return Err(corrupt(format!("of kind {found}, expected {}", kind as u32)));
        }
        let end = at.checked_add(len).filter(|&e| e <= self.file.len() as u64);
        let Some(end) = end else {
            return Err(corrupt(format!(
                "bytes {at}..{} beyond the end of the file ({} bytes): truncated?",
                at.saturating_add(len),
                self.file.len()
            )));
        };
        if !(at as usize).is_multiple_of(ALIGN) {
            return Err(corrupt(format!("at {at}, not aligned")));
        }
        let bytes = &self.file[at as usize..end as usize];
        if crc32fast::hash(bytes) != crc {
            return Err(corrupt("checksum mismatch".into()));
        }
        Ok(bytes)
    }

    /// The next section as RON text of a `T`.
    pub fn ron<T: serde::de::DeserializeOwned>(&mut self, kind: Kind) -> Result<T, CacheError> {
        let index = self.next;
        let bytes = self.bytes(kind)?;
        let text = std::str::from_utf8(bytes)
            .map_err(|_| CacheError::Corrupt(format!("section {index}: not UTF-8 text")))?;
        ron::from_str(text).map_err(|e| CacheError::Corrupt(format!("section {index}: {e}")))
    }

    /// The next section as CBOR of a `T`.
    pub fn cbor<T: serde::de::DeserializeOwned>(&mut self, kind: Kind) -> Result<T, CacheError> {
        let index = self.next;
        let bytes = self.bytes(kind)?;
        ciborium::from_reader(bytes).map_err(|e| CacheError::Corrupt(format!("section {index}: {e}")))
    }

    /// The next section as numbers, `count` of them (`None`: any number).
    pub fn array<T: bytemuck::Pod>(&mut self, count: Option<usize>) -> Result<&'a [T], CacheError> {
        let index = self.next;
        let bytes = self.bytes(Kind::Array)?;
        let values: &[T] = bytemuck::try_cast_slice(bytes)
            .map_err(|e| CacheError::Corrupt(format!("section {index}: {e:?}")))?;
        match count {
            Some(n) if n != values.len() => {
                Err(CacheError::Corrupt(format!("section {index}: {} values, expected {n}", values.len())))
            }
            _ => Ok(values),
        }
    }

    /// Whether every section has been read.
    pub fn at_end(&self) -> bool {
        self.next == self.table.len()
    }
}
