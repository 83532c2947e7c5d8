//! What a scene cache records of where it came from: the version that
//! wrote it, the scene's content hash and its source files.

use std::path::PathBuf;

/// Where a cache came from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Meta {
    /// The rt-view version that wrote it.
    pub rt_view_version: String,
    /// The scene's content hash ([`crate::content_hash`]): the same as
    /// parts rendered from the scene file record.
    pub content_hash: String,
    /// The scene file as given to `prepare`.
    pub scene_file: PathBuf,
    /// The scene file and each file it loaded (absolute where the path
    /// could be made so), with the length and FNV-1a hash of each.
    pub sources: Vec<Source>,
}

/// A file a cached scene was read from.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Source {
    /// Its path.
    pub path: PathBuf,
    /// Its length in bytes.
    pub len: u64,
    /// Its 128-bit FNV-1a hash, hex.
    pub hash: String,
    /// Its modification time (nanoseconds since the Unix epoch) when the
    /// cache was written, if the file system tells: a file of the same
    /// length and time is taken as unchanged without reading it (as `make`
    /// and `rsync` do), which spares a task hashing a large mesh.
    pub modified: Option<u128>,
}

/// The modification time of `metadata` in nanoseconds since the Unix epoch.
pub fn modified_ns(metadata: &std::fs::Metadata) -> Option<u128> {
    metadata.modified().ok()?.duration_since(std::time::UNIX_EPOCH).ok().map(|d| d.as_nanos())
}

/// This build's version, as recorded in caches.
pub fn this_version() -> String {
    env!("CARGO_PKG_VERSION").to_owned()
}
