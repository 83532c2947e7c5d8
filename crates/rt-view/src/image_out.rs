//! Writing files atomically: a temporary file in the target's directory,
//! renamed over the target only once it is complete and flushed to disk.
//!
//! PNG holds 8-bit pixels encoded in the scene's colour space, after the
//! exposure and view transform ([`rt_core::render::view_transform`]);
//! OpenEXR holds the linear colours themselves as 32-bit floats (HDR:
//! nothing is clamped, exposed or transformed). An EXR may also hold more
//! channels than the colour ([`PendingImage::write_channels`]: feature
//! passes, the noisy image beside a denoised one), named as compositors
//! expect (`albedo.R`, `N.X`, `Z`, `id`, …).
//!
//! # Temporary files
//!
//! The temporary file is `.NAME.rt-view-PID-XXXXXX.tmp` beside the target
//! `NAME` (its first 100 characters; PID: the writer's process id, XXXXXX:
//! random), so a leftover says
//! what it was for and who wrote it. An error or a panic removes it (and
//! `render` handles Ctrl-C by stopping before the write, never during it);
//! only a process killed during the write (SIGKILL, a power cut, a signal the
//! command does not handle) leaves it behind. The next write to the same directory then removes every
//! such stale file ([`remove_stale_temp_files`]): one whose writer is gone —
//! on Linux, no `/proc/PID`; elsewhere (or without `/proc`), one untouched
//! for [`STALE_AGE`]. A live writer's file is never removed. The pid is
//! checked on this machine (in this pid namespace): a directory shared with
//! another machine or container could lose a temporary file of a writer
//! running there, whose rename then fails with an error (never a corrupt
//! target).

use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, bail};
use image::ImageEncoder;
use image::codecs::png::PngEncoder;
use rt_core::Frame;
use rt_core::render::Rgb8;
use rt_core::render::view_transform::Display;

/// The file formats images can be written in, by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.png`: 8-bit RGB.
    Png,
    /// `.exr`: linear 32-bit float RGB.
    Exr,
}

/// A file output whose directory has been checked but which is not written
/// yet. Nothing exists on disk until it is written, so a command killed
/// before the write leaves no trace, and one killed during it a temporary
/// file that the next write to the directory removes (see the module's
/// documentation).
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

    /// A new temporary file beside the target, `.NAME.rt-view-PID-XXXXXX.tmp`
    /// (see the module's documentation). Temporary files are private (0600)
    /// by default; the output should get the mode of any new file (0666 less
    /// the umask), as `cp` would give it.
    fn temp_file(&self) -> anyhow::Result<tempfile::NamedTempFile> {
        let name = self.target.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        // At most 100 characters of it, so that the temporary name stays
        // within the 255 bytes a file name may have whatever the target's.
        let name: String = name.chars().take(100).collect();
        let prefix = format!(".{name}{TEMP_MARK}{}-", std::process::id());
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(TEMP_SUFFIX);
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
        remove_stale_temp_files(&self.dir);
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

/// What marks a temporary file's name: `.NAME` + this + `PID-XXXXXX.tmp`.
const TEMP_MARK: &str = ".rt-view-";
/// The end of a temporary file's name.
const TEMP_SUFFIX: &str = ".tmp";

/// Where there is no `/proc` to ask whether a writer is alive, how long its
/// temporary file must have been left untouched to count as stale: far
/// longer than any write takes (a live write keeps touching its file).
pub const STALE_AGE: Duration = Duration::from_secs(24 * 60 * 60);

/// The pid of the writer of a temporary file named `name`
/// (`.NAME.rt-view-PID-XXXXXX.tmp`); `None` for any other name.
pub fn temp_file_writer(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?.strip_suffix(TEMP_SUFFIX)?;
    let (_, tail) = rest.rsplit_once(TEMP_MARK)?;
    let (pid, random) = tail.split_once('-')?;
    let valid = !pid.is_empty()
        && pid.bytes().all(|b| b.is_ascii_digit())
        && !random.is_empty()
        && random.bytes().all(|b| b.is_ascii_alphanumeric());
    if valid { pid.parse().ok() } else { None }
}

/// Whether the writer `pid` of a temporary file last modified `age` ago may
/// still be writing it: its process exists (Linux, by `/proc/PID`), or,
/// without `/proc`, the file was touched less than [`STALE_AGE`] ago.
fn writer_may_be_alive(pid: u32, age: Option<Duration>) -> bool {
    if pid == std::process::id() {
        return true;
    }
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        return Path::new("/proc").join(pid.to_string()).exists();
    }
    age.is_none_or(|a| a < STALE_AGE)
}

/// Removes the temporary files in `dir` that writers killed mid-write left
/// behind: names [`temp_file_writer`] recognises, of writers that are gone
/// (`writer_may_be_alive`). Best effort: an unreadable directory or a file
/// that cannot be removed is left as it is (the write itself reports real
/// trouble). Returns the files removed.
pub fn remove_stale_temp_files(dir: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let Some(pid) = entry.file_name().to_str().and_then(temp_file_writer) else { continue };
        let Ok(meta) = entry.metadata() else { continue };
        let age = meta.modified().ok().and_then(|m| m.elapsed().ok());
        if meta.is_file() && !writer_may_be_alive(pid, age) && std::fs::remove_file(entry.path()).is_ok() {
            removed.push(entry.path());
        }
    }
    removed
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

    /// Writes a rendered frame: for PNG exposed, through the view
    /// transform and encoded to 8 bits in its colour space (`display`;
    /// the default is the plain encoding), for EXR the linear floats as
    /// they are (scene-referred: no exposure, no view transform).
    pub fn write_frame(self, frame: &Frame, display: &Display) -> anyhow::Result<()> {
        match self.format {
            Format::Png => {
                let pixels: Vec<Rgb8> =
                    frame.pixels.iter().map(|&c| display.encode(c, frame.color_space)).collect();
                self.write_rgb8(frame.width, frame.height, &pixels)
            }
            Format::Exr => {
                let pixels: Vec<[f32; 3]> = frame.pixels.iter().map(|c| c.to_array()).collect();
                self.write_linear(frame.width, frame.height, &pixels)
            }
        }
    }

    /// Writes linear colours (row-major, top row first) as OpenEXR, 32-bit
    /// floats as they are (scene-referred: nothing clamped or encoded).
    pub fn write_linear(self, width: u32, height: u32, pixels: &[[f32; 3]]) -> anyhow::Result<()> {
        if self.format != Format::Exr {
            bail!("{}: linear images are written as .exr only", self.file.target.display());
        }
        if pixels.len() != width as usize * height as usize {
            bail!("image size does not match its pixels");
        }
        let channel = |c: usize| pixels.iter().map(|p| p[c]).collect();
        let channels = vec![("R".into(), channel(0)), ("G".into(), channel(1)), ("B".into(), channel(2))];
        self.write_channels(width, height, channels)
    }

    /// Writes named channels of 32-bit floats, each `width × height`
    /// values (row-major, top row first), as one OpenEXR layer (ZIP
    /// compressed; the channels sorted by name, as the format wants). The
    /// colour is the channels `R`, `G`, `B`; a layer's channels are
    /// `layer.X` (OpenEXR's naming convention for multi-part images in one
    /// part, which Blender and Nuke read as layers). Blocks are compressed
    /// one after the other, so the same pixels give the same bytes (in
    /// parallel, the blocks go into the file in the order they finish).
    pub fn write_channels(
        self,
        width: u32,
        height: u32,
        channels: Vec<(String, Vec<f32>)>,
    ) -> anyhow::Result<()> {
        use exr::prelude::{
            AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer, LayerAttributes, WritableImage,
        };
        if self.format != Format::Exr {
            bail!("{}: image layers are written as .exr only", self.file.target.display());
        }
        let pixels = width as usize * height as usize;
        if let Some((name, _)) = channels.iter().find(|(_, v)| v.len() != pixels) {
            bail!("channel {name} does not have {width}×{height} values");
        }
        let list: Vec<AnyChannel<FlatSamples>> = channels
            .into_iter()
            .map(|(name, values)| AnyChannel::new(name.as_str(), FlatSamples::F32(values)))
            .collect();
        let layer = Layer::new(
            (width as usize, height as usize),
            LayerAttributes::default(),
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(list.into()),
        );
        let image = Image::from_layer(layer);
        self.file
            .write_with(|out| image.write().non_parallel().to_buffered(out).context("cannot encode image"))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A process that has run and been waited for, so is gone (its pid could
    /// be reused only after some 32 768, or 4 million, others started).
    fn gone_process() -> std::process::Child {
        let mut child = std::process::Command::new(std::env::current_exe().unwrap())
            .args(["--list", "--exact", "no such test"])
            .stdout(std::process::Stdio::null())
            .spawn()
            .unwrap();
        child.wait().unwrap();
        child
    }

    #[test]
    fn the_same_pixels_make_the_same_exr_bytes() {
        // Enough rows for many compressed blocks (16 rows each): written in
        // parallel, they went into the file in the order they finished.
        let dir = tempfile::tempdir().unwrap();
        let (w, h) = (300u32, 400u32);
        let pixels: Vec<[f32; 3]> =
            (0..w * h).map(|i| [(i % 977) as f32 * 0.37, (i % 13) as f32, (i as f32).sqrt()]).collect();
        let bytes: Vec<Vec<u8>> = (0..4)
            .map(|k| {
                let target = dir.path().join(format!("{k}.exr"));
                PendingImage::create(&target).unwrap().write_linear(w, h, &pixels).unwrap();
                std::fs::read(&target).unwrap()
            })
            .collect();
        assert!(bytes.iter().all(|b| *b == bytes[0]));
    }

    #[test]
    fn linear_images_read_back_from_exr_as_the_same_floats() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("linear.exr");
        let pixels = [[0.0, 0.5, 1.0], [3.75, 1e-4, 250.0], [0.1, 0.2, 0.3], [-0.0, 7.0, 0.015625]];
        PendingImage::create(&target).unwrap().write_linear(2, 2, &pixels).unwrap();
        let back = image::open(&target).unwrap().to_rgb32f();
        assert_eq!((back.width(), back.height()), (2, 2));
        let back: Vec<[f32; 3]> = back.pixels().map(|p| p.0).collect();
        assert_eq!(back, pixels);
        // Linear images are not PNGs, nor 8-bit ones EXRs.
        let png = PendingImage::create(&dir.path().join("x.png")).unwrap();
        assert!(png.write_linear(2, 2, &pixels).unwrap_err().to_string().contains(".exr only"));
    }

    #[test]
    fn named_channels_read_back_from_exr_by_name() {
        use exr::prelude::{ReadChannels, ReadLayers};
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("layers.exr");
        let channels = vec![
            ("R".to_owned(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0]),
            ("albedo.R".to_owned(), vec![0.5; 6]),
            ("Z".to_owned(), vec![1.0, f32::INFINITY, 2.5, 3.0, 4.0, 5.0]),
            ("id".to_owned(), vec![-1.0, 0.0, 1.0, 2.0, 3.0, 7.0]),
        ];
        PendingImage::create(&target).unwrap().write_channels(3, 2, channels.clone()).unwrap();
        let image = exr::prelude::read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(&target)
            .unwrap();
        assert_eq!(image.layer_data.size, exr::prelude::Vec2(3, 2));
        let mut back: Vec<(String, Vec<f32>)> = image
            .layer_data
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
            .collect();
        back.sort_by(|a, b| a.0.cmp(&b.0));
        let mut want = channels;
        want.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(back, want);
        // The wrong number of values, or a PNG, is refused.
        let short = vec![("R".to_owned(), vec![1.0])];
        assert!(PendingImage::create(&target).unwrap().write_channels(3, 2, short).is_err());
        let png = PendingImage::create(&dir.path().join("x.png")).unwrap();
        assert!(png.write_channels(1, 1, vec![]).unwrap_err().to_string().contains(".exr only"));
    }

    #[test]
    fn temporary_files_are_named_after_their_target_and_their_writer() {
        let dir = tempfile::tempdir().unwrap();
        let pending = PendingFile::create(&dir.path().join("out.png")).unwrap();
        let temp = pending.temp_file().unwrap();
        let name = temp.path().file_name().unwrap().to_str().unwrap().to_owned();
        assert!(name.starts_with(&format!(".out.png.rt-view-{}-", std::process::id())), "{name}");
        assert_eq!(temp_file_writer(&name), Some(std::process::id()), "{name}");
    }

    #[test]
    fn a_target_with_the_longest_name_a_file_may_have_can_be_written() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join(format!("{}.png", "é".repeat(125)));
        assert_eq!(target.file_name().unwrap().len(), 254);
        PendingFile::create(&target).unwrap().write_bytes(b"done").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"done");
    }

    #[test]
    fn only_names_of_the_temporary_file_pattern_have_a_writer() {
        assert_eq!(temp_file_writer(".out.png.rt-view-1234-aB3xYz.tmp"), Some(1234));
        // A target whose own name holds the mark: the last one counts.
        assert_eq!(temp_file_writer(".a.rt-view-9-x.png.rt-view-77-q1.tmp"), Some(77));
        for other in [
            "out.png",
            "out.png.rt-view-1234-aB3xYz.tmp",
            ".out.png.rt-view-1234-aB3xYz",
            ".out.png.rt-view--aB3xYz.tmp",
            ".out.png.rt-view-12a4-aB3xYz.tmp",
            ".out.png.rt-view-1234-.tmp",
            ".out.png.rt-view-1234-a.b.tmp",
            ".out.png.rt-view-1234.tmp",
            ".out.png.rt-view-99999999999-abc.tmp",
            ".rt-view-abcdef.tmp",
        ] {
            assert_eq!(temp_file_writer(other), None, "{other}");
        }
    }

    #[test]
    fn a_live_writer_is_never_stale_and_a_gone_one_is() {
        assert!(writer_may_be_alive(std::process::id(), Some(STALE_AGE * 2)));
        if cfg!(target_os = "linux") {
            let pid = gone_process().id();
            assert!(!writer_may_be_alive(pid, Some(Duration::ZERO)));
            assert!(writer_may_be_alive(1, Some(STALE_AGE * 2)), "init is alive");
        }
    }

    #[test]
    fn stale_temporary_files_go_and_everything_else_stays() {
        let dir = tempfile::tempdir().unwrap();
        let gone = gone_process().id();
        let me = std::process::id();
        let stale = format!(".out.png.rt-view-{gone}-abc123.tmp");
        let keep = [
            format!(".out.png.rt-view-{me}-abc123.tmp"),
            format!("out.png.rt-view-{gone}-abc123.tmp"),
            format!(".notes.rt-view-{gone}.tmp"),
            "out.png".to_owned(),
        ];
        for name in keep.iter().chain([&stale]) {
            std::fs::write(dir.path().join(name), b"x").unwrap();
        }
        std::fs::create_dir(dir.path().join(format!(".d.rt-view-{gone}-abc.tmp"))).unwrap();
        let removed = remove_stale_temp_files(dir.path());
        if cfg!(target_os = "linux") {
            assert_eq!(removed, [dir.path().join(&stale)]);
        }
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        let mut want: Vec<String> = keep.to_vec();
        want.push(format!(".d.rt-view-{gone}-abc.tmp"));
        if !cfg!(target_os = "linux") {
            want.push(stale);
        }
        want.sort();
        assert_eq!(left, want);
    }

    #[test]
    fn a_write_removes_the_stale_temporary_files_of_its_directory() {
        let dir = tempfile::tempdir().unwrap();
        let gone = gone_process().id();
        let stale = dir.path().join(format!(".other.exr.rt-view-{gone}-Zz9.tmp"));
        std::fs::write(&stale, b"half an image").unwrap();
        let target = dir.path().join("out.txt");
        PendingFile::create(&target).unwrap().write_bytes(b"done").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"done");
        assert_eq!(stale.exists(), !cfg!(target_os = "linux"));
    }
}
