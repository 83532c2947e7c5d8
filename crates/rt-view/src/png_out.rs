//! Writing images atomically: a temporary file in the target's directory,
//! renamed over the target only once it is complete and flushed to disk.

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use image::ImageEncoder;
use image::codecs::png::PngEncoder;
use rt_core::Frame;

/// A PNG output that has been checked for writability but not yet written.
/// Dropping it without [`PendingPng::write`] leaves nothing behind.
pub struct PendingPng {
    target: PathBuf,
    temp: tempfile::NamedTempFile,
}

impl PendingPng {
    /// Checks that `target` ends in `.png` and that its directory accepts a
    /// new file, by creating the temporary file there now, before any work.
    pub fn create(target: &Path) -> anyhow::Result<Self> {
        let is_png = target.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !is_png {
            bail!("{}: output must be a .png file", target.display());
        }
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(".rt-view-").suffix(".png.tmp");
        // Temporary files are private (0600) by default; the image should get
        // the mode of any new file (0666 less the umask), as `cp` would give it.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        let temp = builder
            .tempfile_in(dir)
            .with_context(|| format!("{}: cannot write to directory {}", target.display(), dir.display()))?;
        Ok(Self { target: target.to_owned(), temp })
    }

    /// Encodes `frame` into the temporary file, syncs it and renames it over the target.
    pub fn write(self, frame: &Frame) -> anyhow::Result<()> {
        let target = self.target.display().to_string();
        let mut out = BufWriter::new(self.temp.as_file());
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
        self.temp.as_file().sync_all().with_context(|| format!("{target}: cannot write"))?;
        self.temp
            .persist(&self.target)
            .map_err(|e| e.error)
            .with_context(|| format!("{target}: cannot replace"))?;
        Ok(())
    }
}
