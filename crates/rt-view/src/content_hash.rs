//! What identifies a scene's content: a 128-bit FNV-1a hash of the scene
//! file and of every file it loads (meshes, MTL files, textures, glTF
//! buffers and images, the environment map), and the same hash as the
//! checksum of part files.
//!
//! FNV-1a (Fowler, Noll, Vo; the 128-bit parameters of
//! <http://www.isthe.com/chongo/tech/comp/fnv/>) is not a cryptographic
//! hash: it tells an edited or other scene from the one a render started
//! with, and a damaged file from the one written, which is all a split
//! render needs (nobody forges a part). It is fixed forever, unlike the
//! standard library's hasher, so hashes agree between builds and machines.

use std::path::{Path, PathBuf};

use anyhow::Context;

/// FNV-1a's 128-bit offset basis.
const OFFSET: u128 = 0x6c62272e07bb014262b821756295c58d;
/// FNV-1a's 128-bit prime, 2⁸⁸ + 2⁸ + 0x3b.
const PRIME: u128 = 0x0000000001000000000000000000013b;

/// A running 128-bit FNV-1a hash.
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a128(u128);

impl Default for Fnv1a128 {
    fn default() -> Self {
        Self(OFFSET)
    }
}

impl Fnv1a128 {
    /// Hashes `bytes` in.
    pub fn write(&mut self, bytes: &[u8]) {
        let mut h = self.0;
        for &b in bytes {
            h ^= b as u128;
            h = h.wrapping_mul(PRIME);
        }
        self.0 = h;
    }

    /// The hash so far.
    pub fn finish(&self) -> u128 {
        self.0
    }

    /// The hash so far as 32 lowercase hex digits.
    pub fn hex(&self) -> String {
        format!("{:032x}", self.0)
    }
}

/// The files a loaded scene was read from: the scene file, then each file
/// it loaded ([`rt_core::Scene::source_files`]) once, in the order loaded.
pub fn scene_files(scene_file: &Path, scene: &rt_core::Scene) -> Vec<PathBuf> {
    let mut files = vec![scene_file.to_owned()];
    for f in scene.source_files() {
        if !files.contains(f) {
            files.push(f.clone());
        }
    }
    files
}

/// The content hash of `files`: each file's length (8 bytes, little-endian)
/// and bytes, one after the other, so that moving bytes from one file to the
/// next changes it. Names and places do not count: the same scene copied
/// elsewhere has the same hash.
pub fn content_hash(files: &[PathBuf]) -> anyhow::Result<String> {
    let mut hash = Fnv1a128::default();
    for file in files {
        let bytes =
            std::fs::read(file).with_context(|| format!("{}: cannot read to hash it", file.display()))?;
        hash.write(&(bytes.len() as u64).to_le_bytes());
        hash.write(&bytes);
    }
    Ok(hash.hex())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_128_gives_the_published_values() {
        // From the FNV reference implementation's test vectors.
        let hash = |s: &str| {
            let mut h = Fnv1a128::default();
            h.write(s.as_bytes());
            h.hex()
        };
        assert_eq!(hash(""), "6c62272e07bb014262b821756295c58d");
        assert_eq!(hash("a"), "d228cb696f1a8caf78912b704e4a8964");
    }

    #[test]
    fn the_hash_follows_every_byte_of_every_file_but_not_their_names() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b, c) = (dir.path().join("a.ron"), dir.path().join("b.obj"), dir.path().join("c.obj"));
        std::fs::write(&a, "scene").unwrap();
        std::fs::write(&b, "mesh").unwrap();
        std::fs::write(&c, "mesh").unwrap();
        let h = content_hash(&[a.clone(), b.clone()]).unwrap();
        assert_eq!(content_hash(&[a.clone(), c.clone()]).unwrap(), h);
        std::fs::write(&c, "mesH").unwrap();
        assert_ne!(content_hash(&[a.clone(), c.clone()]).unwrap(), h);
        // Bytes moved from one file to the next.
        std::fs::write(&a, "scenem").unwrap();
        std::fs::write(&c, "esh").unwrap();
        assert_ne!(content_hash(&[a.clone(), c]).unwrap(), h);
        let missing = content_hash(&[dir.path().join("gone.obj")]).unwrap_err();
        assert!(format!("{missing:#}").contains("gone.obj"), "{missing:#}");
    }
}
