//! The reference image the render is compared with.
//!
//! A reference is a linear image: an OpenEXR file as it is (scene-referred
//! floats), a PNG decoded from sRGB to linear (the sRGB curve of IEC
//! 61966-2-1 inverted), or the render on screen. It loads on a thread of
//! its own ([`Loading`]), so a large file never holds up the window; a
//! file that cannot be read, or one of another size than the render, is a
//! message, never a panic. The metrics are in `error_metrics`.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{Receiver, TryRecvError};

/// A linear image to compare the render with.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    width: usize,
    height: usize,
    /// Row-major linear colours, top row first.
    pixels: Vec<[f32; 3]>,
    /// Where it came from, as the panel names it.
    name: String,
}

impl Reference {
    /// A reference of `width`×`height` linear `pixels` (row-major), called
    /// `name`; `None` if the pixels do not fill the size.
    pub fn new(width: usize, height: usize, pixels: Vec<[f32; 3]>, name: String) -> Option<Self> {
        (pixels.len() == width * height && width > 0 && height > 0).then_some(Self {
            width,
            height,
            pixels,
            name,
        })
    }

    /// Reads `path`: `.exr` as linear floats, `.png` decoded from sRGB.
    pub fn load(path: &Path) -> Result<Self, String> {
        let shown = path.display();
        let extension = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        let srgb = match extension.as_deref() {
            Some("exr") => false,
            Some("png") => true,
            _ => return Err(format!("{shown}: a reference must be a .exr or .png file")),
        };
        let image = image::open(path).map_err(|e| format!("{shown}: cannot read the image: {e}"))?;
        let image = image.to_rgb32f();
        let (width, height) = (image.width() as usize, image.height() as usize);
        let decode = |v: f32| if srgb { srgb_decode(v) } else { v };
        let pixels = image.pixels().map(|p| p.0.map(decode)).collect();
        let name = path.file_name().map_or_else(|| shown.to_string(), |n| n.to_string_lossy().into_owned());
        Self::new(width, height, pixels, name).ok_or_else(|| format!("{shown}: the image is empty"))
    }

    /// `[width, height]` in pixels.
    pub fn size(&self) -> [usize; 2] {
        [self.width, self.height]
    }

    /// Row `y`'s linear colours.
    pub fn row(&self, y: usize) -> &[[f32; 3]] {
        &self.pixels[y * self.width..(y + 1) * self.width]
    }

    /// Row-major linear colours.
    pub fn pixels(&self) -> &[[f32; 3]] {
        &self.pixels
    }

    /// What it is called in the panel: the file's name, or "the render …".
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Why it cannot be compared with a render of `size`, if it cannot.
    pub fn mismatch(&self, [w, h]: [usize; 2]) -> Option<String> {
        (self.size() != [w, h]).then(|| {
            format!(
                "the reference is {} × {} pixels, the render {w} × {h}: no comparison",
                self.width, self.height
            )
        })
    }
}

/// The sRGB decoding (IEC 61966-2-1) of an encoded value in [0, 1]:
/// `v / 12.92` up to 0.04045, else `((v + 0.055) / 1.055)^2.4`.
pub fn srgb_decode(v: f32) -> f32 {
    if v <= 0.040_45 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// A reference being read on a thread of its own.
pub struct Loading {
    path: PathBuf,
    result: Receiver<Result<Reference, String>>,
}

impl Loading {
    /// Starts reading `path`; `done` runs when it is read (the viewer
    /// passes `request_repaint`).
    pub fn start(path: PathBuf, done: impl FnOnce() + Send + 'static) -> Self {
        let (tx, result) = std::sync::mpsc::channel();
        let reading = path.clone();
        std::thread::spawn(move || {
            let _ = tx.send(Reference::load(&reading));
            done();
        });
        Self { path, result }
    }

    /// The file being read.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The reference or why not, once read; `None` while reading.
    pub fn poll(&self) -> Option<Result<Reference, String>> {
        match self.result.try_recv() {
            Ok(result) => Some(result),
            Err(TryRecvError::Empty) => None,
            Err(TryRecvError::Disconnected) => Some(Err(format!("{}: reading failed", self.path.display()))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_exr_reads_back_as_the_same_floats_and_a_png_is_decoded_from_srgb() {
        let dir = tempfile::tempdir().unwrap();
        let floats = [0.0f32, 0.25, 3.5, 1e-3, 100.0, 0.5];
        let exr = dir.path().join("ref.exr");
        image::Rgb32FImage::from_raw(2, 1, floats.to_vec()).unwrap().save(&exr).unwrap();
        let r = Reference::load(&exr).unwrap();
        assert_eq!(r.size(), [2, 1]);
        assert_eq!(r.pixels(), &[[0.0, 0.25, 3.5], [1e-3, 100.0, 0.5]]);
        assert_eq!(r.name(), "ref.exr");

        let png = dir.path().join("ref.png");
        image::RgbImage::from_raw(2, 1, vec![0, 255, 188, 10, 128, 60]).unwrap().save(&png).unwrap();
        let r = Reference::load(&png).unwrap();
        let want = [0u8, 255, 188, 10, 128, 60].map(|v| srgb_decode(v as f32 / 255.0));
        assert_eq!(r.pixels(), &[[want[0], want[1], want[2]], [want[3], want[4], want[5]]]);
        // sRGB 188 is about linear 0.5, 128 about 0.216.
        assert!((r.pixels()[0][2] - 0.5).abs() < 0.005 && (r.pixels()[1][1] - 0.216).abs() < 0.005);
    }

    #[test]
    fn unreadable_references_are_messages_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("missing.exr");
        let e = Reference::load(&missing).unwrap_err();
        assert!(e.starts_with(&format!("{}: cannot read the image: ", missing.display())), "{e}");
        let broken = dir.path().join("broken.png");
        std::fs::write(&broken, b"not a png").unwrap();
        assert!(Reference::load(&broken).unwrap_err().contains("broken.png: cannot read the image"));
        let text = dir.path().join("notes.txt");
        assert!(Reference::load(&text).unwrap_err().ends_with("a reference must be a .exr or .png file"));
    }

    #[test]
    fn loading_happens_on_its_own_thread_and_reports_once_read() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("gone.png");
        let loading = Loading::start(missing.clone(), || {});
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        let result = loop {
            if let Some(r) = loading.poll() {
                break r;
            }
            assert!(std::time::Instant::now() < deadline);
            std::thread::sleep(std::time::Duration::from_millis(1));
        };
        assert!(result.unwrap_err().contains("gone.png"));
        assert_eq!(loading.path(), missing);
    }
}
