//! Why a scene cache cannot be used: each refusal, typed.

use thiserror::Error;

/// Why a scene cache cannot be used.
#[derive(Debug, Error)]
pub enum CacheError {
    /// The file does not start with the cache's magic bytes.
    #[error("not a scene cache")]
    NotACache,
    /// The file cannot be read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// Written in another layout.
    #[error("scene cache format {found}, this rt-view reads format {expected}: prepare it again")]
    FormatVersion {
        /// The file's.
        found: u32,
        /// This build's.
        expected: u32,
    },
    /// Written by a build with another number type (f32 or f64 geometry).
    #[error(
        "written with {found}-byte geometry numbers, this build uses {expected}-byte ones: prepare it again"
    )]
    NumberSize {
        /// The file's.
        found: u32,
        /// This build's.
        expected: u32,
    },
    /// Written by another rt-view version, whose scenes may render otherwise.
    #[error("written by rt-view {found}, this is rt-view {expected}: prepare it again")]
    Version {
        /// The file's.
        found: String,
        /// This build's.
        expected: String,
    },
    /// A source file still there has changed since the cache was written.
    #[error("stale: changed since it was prepared: {}; prepare it again", .0.join(", "))]
    Stale(Vec<String>),
    /// Truncated or damaged: a checksum, offset, length or index is wrong.
    #[error("damaged or truncated: {0}")]
    Corrupt(String),
}
