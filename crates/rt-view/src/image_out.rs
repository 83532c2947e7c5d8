//! Writing files atomically: a temporary file in the target's directory,
//! renamed over the target only once it is complete and flushed to disk.
//!
//! PNG holds 8-bit pixels encoded in the scene's colour space; OpenEXR holds
//! the linear colours themselves as 32-bit floats (HDR: nothing is clamped).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use image::ImageEncoder;
use image::codecs::openexr::OpenExrEncoder;
use image::codecs::png::PngEncoder;
use rt_core::Frame;
use rt_core::render::Rgb8;

/// The file formats images can be written in, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.png`: 8-bit RGB.
    Png,
    /// `.exr`: linear 32-bit float RGB.
    Exr,
}

/// A file output whose directory has been checked but which is not written
/// yet. Nothing exists on disk until it is written, so a command that is
/// killed part-way leaves no trace.
pub struct PendingFile {
    target: PathBuf,
    dir: PathBuf,
}

impl PendingFile {
    /// An output at `target`: checks that its directory accepts a new file
    /// (by creating and removing a probe file), before any work.
    pub fn create(target: &Path) -> anyhow::Result<Self> {
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_owned(),
            _ => PathBuf::from("."),
        };
        let pending = Self { target: target.to_owned(), dir };
        drop(pending.temp_file()?); // Removed again on drop.
        Ok(pending)
    }

    /// A new temporary file beside the target. Temporary files are private
    /// (0600) by default; the output should get the mode of any new file
    /// (0666 less the umask), as `cp` would give it.
    fn temp_file(&self) -> anyhow::Result<tempfile::NamedTempFile> {
        let mut builder = tempfile::Builder::new();
        builder.prefix(".rt-view-").suffix(".tmp");
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        builder.tempfile_in(&self.dir).with_context(|| {
            format!("{}: cannot write to directory {}", self.target.display(), self.dir.display())
        })
    }

    /// Writes `bytes` as the whole file.
    pub fn write_bytes(self, bytes: &[u8]) -> anyhow::Result<()> {
        self.write_with(|out| out.write_all(bytes).context("cannot write"))
    }

    /// Writes the file with `write` into a temporary file, syncs it and
    /// renames it over the target. On any error the temporary file is
    /// removed and an existing target is left as it was.
    pub fn write_with(
        self,
        write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> anyhow::Result<()>,
    ) -> anyhow::Result<()> {
        let target = self.target.display().to_string();
        let temp = self.temp_file()?;
        let mut out = BufWriter::new(temp.as_file());
        write(&mut out).with_context(|| format!("{target}: cannot write"))?;
        out.flush().with_context(|| format!("{target}: cannot write"))?;
        drop(out);
        temp.as_file().sync_all().with_context(|| format!("{target}: cannot write"))?;
        temp.persist(&self.target)
            .map_err(|e| e.error)
            .with_context(|| format!("{target}: cannot replace"))?;
        Ok(())
    }
}

/// An image output whose directory has been checked but which is not
/// written yet ([`PendingFile`]), in the format its extension names.
pub struct PendingImage {
    file: PendingFile,
    format: Format,
}

impl PendingImage {
    /// A `.png` or `.exr` output: checks the extension and that the
    /// directory accepts a new file, before any work.
    pub fn create(target: &Path) -> anyhow::Result<Self> {
        let extension = target.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        let format = match extension.as_deref() {
            Some("png") => Format::Png,
            Some("exr") => Format::Exr,
            _ => bail!("{}: output must be a .png or .exr file", target.display()),
        };
        Ok(Self { file: PendingFile::create(target)?, format })
    }

    /// A `.png` output only (for 8-bit images such as the viewer's).
    pub fn png(target: &Path) -> anyhow::Result<Self> {
        let is_png = target.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !is_png {
            bail!("{}: output must be a .png file", target.display());
        }
        Ok(Self { file: PendingFile::create(target)?, format: Format::Png })
    }

    /// The format the file will have.
    pub fn format(&self) -> Format {
        self.format
    }

    /// Writes a rendered frame: encoded to 8 bits in its colour space for
    /// PNG, linear floats for EXR.
    pub fn write_frame(self, frame: &Frame) -> anyhow::Result<()> {
        match self.format {
            Format::Png => self.write_rgb8(frame.width, frame.height, &frame.to_rgb8()),
            Format::Exr => {
                let floats: Vec<f32> = frame.pixels.iter().flat_map(|c| c.to_array()).collect();
                let image = image::Rgb32FImage::from_raw(frame.width, frame.height, floats)
                    .context("frame size does not match its pixels")?;
                self.write_bytes(|out| image.write_with_encoder(OpenExrEncoder::new(out)))
            }
        }
    }

    /// Writes 8-bit pixels (row-major, top row first) as PNG.
    pub fn write_rgb8(self, width: u32, height: u32, pixels: &[Rgb8]) -> anyhow::Result<()> {
        if self.format != Format::Png {
            bail!("{}: 8-bit images are written as .png only", self.file.target.display());
        }
        self.write_bytes(|out| {
            PngEncoder::new(out).write_image(
                pixels.as_flattened(),
                width,
                height,
                image::ExtendedColorType::Rgb8,
            )
        })
    }

    /// Encodes the image into the file.
    fn write_bytes(
        self,
        encode: impl FnOnce(&mut BufWriter<&std::fs::File>) -> image::ImageResult<()>,
    ) -> anyhow::Result<()> {
        self.file.write_with(|out| encode(out).context("cannot encode image"))
    }
}
