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
//! first bytes (`RTSCENE`), not by its name.

mod cache_error;
pub(crate) mod format;
mod meta;
mod read;
mod write;

use std::io::Read as _;
use std::path::Path;

use crate::image_out::PendingFile;
pub use cache_error::CacheError;
pub use meta::{Meta, Source, this_version};
pub use read::read_cache;
pub use write::cache_bytes;

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

/// `rt-view prepare`: loads and builds the scene at `scene_file` and writes
/// its cache to `out` atomically. Returns the cache's size in bytes.
pub fn prepare(scene_file: &Path, out: &Path) -> anyhow::Result<usize> {
    let pending = PendingFile::create(out)?;
    if is_cache(scene_file) {
        anyhow::bail!("{}: is a scene cache already; prepare takes a scene file", scene_file.display());
    }
    let loaded = rt_core::load_scene(scene_file)?;
    let bytes = cache_bytes(scene_file, &loaded)?;
    let len = bytes.len();
    pending.write_bytes(&bytes)?;
    Ok(len)
}

#[cfg(test)]
mod tests;
