//! Writing images atomically: a temporary file in the target's directory,
//! renamed over the target only once it is complete and flushed to disk.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use image::ImageEncoder;
use image::codecs::png::PngEncoder;
use rt_core::Frame;

/// A PNG output whose directory has been checked but which is not written yet.
/// Nothing exists on disk until [`PendingPng::write`], so a render that is
/// killed part-way leaves no trace.
pub struct PendingPng {
    target: PathBuf,
    dir: PathBuf,
}

impl PendingPng {
    /// Checks that `target` ends in `.png` and that its directory accepts a
    /// new file (by creating and removing a probe file), before any work.
    pub fn create(target: &Path) -> anyhow::Result<Self> {
        let is_png = target.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !is_png {
            bail!("{}: output must be a .png file", target.display());
        }
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
            _ => PathBuf::from("."),
        };
        let pending = Self { target: target.to_owned(), dir };
        drop(pending.temp_file()?); // Removed again on drop.
        Ok(pending)
    }

    /// A new temporary file beside the target. Temporary files are private
    /// (0600) by default; the image should get the mode of any new file (0666
    /// less the umask), as `cp` would give it.
    fn temp_file(&self) -> anyhow::Result<tempfile::NamedTempFile> {
        let mut builder = tempfile::Builder::new();
        builder.prefix(".rt-view-").suffix(".png.tmp");
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        builder.tempfile_in(&self.dir).with_context(|| {
            format!("{}: cannot write to directory {}", self.target.display(), self.dir.display())
        })
    }

    /// Encodes `frame` into a temporary file, syncs it and renames it over
    /// the target. On any error the temporary file is removed and an existing
    /// target is left as it was.
    pub fn write(self, frame: &Frame) -> anyhow::Result<()> {
        let target = self.target.display().to_string();
        let temp = self.temp_file()?;
        let mut out = BufWriter::new(temp.as_file());
        PngEncoder::new(&mut out)
            .write_image(
                frame.pixels.as_flattened(),
                frame.width,
                frame.height,
                image::ExtendedColorType::Rgb8,
            )
            .with_context(|| format!("{target}: cannot encode PNG"))?;
        out.flush().with_context(|| format!("{target}: cannot write"))?;
        drop(out);
        temp.as_file().sync_all().with_context(|| format!("{target}: cannot write"))?;
        temp.persist(&self.target)
            .map_err(|e| e.error)
            .with_context(|| format!("{target}: cannot replace"))?;
        Ok(())
    }
}
