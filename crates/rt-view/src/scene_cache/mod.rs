//! The scene cache: a scene built once (`rt-view prepare SCENE -o
//! SCENE.rtc`) and stored as it is in memory — meshes with their
//! tangents, the BVH, the decoded textures with their mip-maps — so that
//! each task of a split render maps it and starts tracing instead of
//! reading models and building the tree again (docs/cluster.md).
//!
//! A cache records where it came from ([`Meta`]): the rt-view version that
//! wrote it, the scene's content hash (so parts rendered from it merge with
//! parts rendered from the scene file) and each source file with its own
//! hash. It is refused, with a [`CacheError`], when it is of another format
//! or rt-view version, when a source file still there has changed since
//! (stale), or when it is truncated or damaged (a checksum per section; every
//! index checked before use). Commands tell a cache from a scene file by its
//! first bytes ([`format::MAGIC`]), not by its name.

mod format;
mod read;
mod write;

use std::io::Read as _;
use std::path::{Path, PathBuf};

use thiserror::Error;

pub use read::read_cache;
pub use write::{cache_bytes, prepare};

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
pub(crate) fn modified_ns(metadata: &std::fs::Metadata) -> Option<u128> {
    metadata.modified().ok()?.duration_since(std::time::UNIX_EPOCH).ok().map(|d| d.as_nanos())
}

/// This build's version, as recorded in caches.
pub fn this_version() -> String {
    env!("CARGO_PKG_VERSION").to_owned()
}

/// Whether the file at `path` is a scene cache (by its first bytes).
pub fn is_cache(path: &Path) -> bool {
    let mut head = [0; format::MAGIC.len()];
    std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head)).is_ok() && format::has_magic(&head)
}

/// Loads a scene file or a scene cache (told apart by its first bytes),
/// as every command that takes a SCENE does. A cache's errors come back
/// as [`rt_core::SceneError::Read`] naming the file.
pub fn load_scene(path: &Path) -> Result<rt_core::LoadedScene, rt_core::SceneError> {
    if !is_cache(path) {
        return rt_core::load_scene(path);
    }
    read_cache(path).map(|(loaded, _)| loaded).map_err(|e| rt_core::SceneError::Read {
        file: path.display().to_string(),
        reason: std::io::Error::other(format!("scene cache {e}")),
    })
}

/// The content hash of the scene loaded from `path`: a cache's recorded
/// one, else the hash of the scene file and every file it loaded.
pub fn scene_hash(path: &Path, scene: &rt_core::Scene) -> anyhow::Result<String> {
    if is_cache(path) {
        let meta =
            read::read_meta(path).map_err(|e| anyhow::anyhow!("{}: scene cache {e}", path.display()))?;
        return Ok(meta.content_hash);
    }
    crate::content_hash::content_hash(&crate::content_hash::scene_files(path, scene))
}

#[cfg(test)]
mod tests;
