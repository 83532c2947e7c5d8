//! Reading an environment map's image: Radiance `.hdr` (RGBE) or OpenEXR,
//! with the `image` crate's decoders, into linear RGB texels.
//!
//! The header's size is checked against [`MAX_MAP_SIDE`] and
//! [`MAX_MAP_TEXELS`] before anything is decoded, and the decoder is held
//! to the same budget, so a file that claims an absurd size is refused
//! without allocating it. Texels that are NaN become 0, infinite ones 0 and
//! negative ones 0 (an environment sends no negative light), each kind
//! counted in a warning that names the file; a map with nothing left above
//! 0 is refused (it would light nothing, without a word).

use std::path::Path;

use image::{ImageFormat, ImageReader};
use thiserror::Error;

use crate::lights::environment_map::{MAX_MAP_SIDE, MAX_MAP_TEXELS};
use crate::math::color::Color;

/// Why an environment map's image cannot be used. The scene file's loader
/// puts the file's path in front.
#[derive(Debug, Error)]
pub enum EnvironmentImageError {
    /// The file cannot be opened or read.
    #[error("cannot read the environment map: {0}")]
    Read(std::io::Error),
    /// Not a Radiance HDR or OpenEXR file.
    #[error("an environment map must be a Radiance HDR (.hdr) or OpenEXR (.exr) file; this is {0}")]
    Format(String),
    /// Its header gives a size outside the limits.
    #[error(
        "the environment map is {width}x{height} texels: each side must be 1 to {MAX_MAP_SIDE} \
         and the map at most {MAX_MAP_TEXELS} texels"
    )]
    Size {
        /// Width in texels.
        width: u32,
        /// Height in texels.
        height: u32,
    },
    /// The decoder failed (a corrupt or truncated file).
    #[error("the environment map cannot be decoded: {0}")]
    Decode(image::ImageError),
    /// Every texel is 0 (after NaN, infinite and negative ones became 0).
    #[error("the environment map is black everywhere: it would light nothing")]
    Black,
}

/// A decoded map: `width × height` linear texels, row by row from the top,
/// and what was changed on the way, one line each.
#[derive(Clone, Debug)]
pub struct EnvironmentImage {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Linear RGB, finite and ≥ 0.
    pub texels: Vec<Color>,
    /// What was changed (NaN, infinite or negative texels set to 0).
    pub warnings: Vec<String>,
}

/// Reads the `.hdr` or `.exr` file at `path` (see the module's documentation).
pub fn read_environment_image(path: &Path) -> Result<EnvironmentImage, EnvironmentImageError> {
    let reader = || -> Result<ImageReader<_>, EnvironmentImageError> {
        let r = ImageReader::open(path).map_err(EnvironmentImageError::Read)?;
        let r = r.with_guessed_format().map_err(EnvironmentImageError::Read)?;
        match r.format() {
            Some(ImageFormat::Hdr | ImageFormat::OpenExr) => Ok(r),
            Some(other) => Err(EnvironmentImageError::Format(format!("{other:?}"))),
            None => {
                Err(EnvironmentImageError::Format(String::from("not an image format that can be recognised")))
            }
        }
    };
    let (width, height) = reader()?.into_dimensions().map_err(EnvironmentImageError::Decode)?;
    let texels = width as u64 * height as u64;
    if width == 0 || height == 0 || width > MAX_MAP_SIDE || height > MAX_MAP_SIDE || texels > MAX_MAP_TEXELS {
        return Err(EnvironmentImageError::Size { width, height });
    }
    let mut r = reader()?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_MAP_SIDE);
    limits.max_image_height = Some(MAX_MAP_SIDE);
    // The decoded image as f32 RGBA, plus as much again for the decoder's own buffers.
    limits.max_alloc = Some(2 * 16 * MAX_MAP_TEXELS);
    r.limits(limits);
    let image = r.decode().map_err(EnvironmentImageError::Decode)?.into_rgb32f();
    let (mut nan, mut infinite, mut negative) = (0usize, 0usize, 0usize);
    let texels: Vec<Color> = image
        .pixels()
        .map(|p| {
            Color::from_array(p.0.map(|v| {
                if v.is_nan() {
                    nan += 1;
                    0.0
                } else if v.is_infinite() {
                    infinite += 1;
                    0.0
                } else if v < 0.0 {
                    negative += 1;
                    0.0
                } else {
                    v
                }
            }))
        })
        .collect();
    let mut warnings = Vec::new();
    for (count, what) in [(nan, "NaN"), (infinite, "infinite"), (negative, "negative")] {
        if count > 0 {
            warnings.push(format!("{count} {what} texel channel(s) set to 0"));
        }
    }
    if texels.iter().all(|t| t.max_element() <= 0.0) {
        return Err(EnvironmentImageError::Black);
    }
    Ok(EnvironmentImage { width: width as usize, height: height as usize, texels, warnings })
}

/// Writes `texels` (`width × height`, row by row from the top) to `out` as
/// a Radiance `.hdr` image.
pub fn encode_hdr(
    out: impl std::io::Write,
    width: usize,
    height: usize,
    texels: &[Color],
) -> std::io::Result<()> {
    let pixels: Vec<image::Rgb<f32>> = texels.iter().map(|c| image::Rgb(c.to_array())).collect();
    image::codecs::hdr::HdrEncoder::new(out).encode(&pixels, width, height).map_err(std::io::Error::other)
}

/// [`encode_hdr`] into a new file at `path`: for tests and the scripts that
/// make maps (the `export` command writes atomically instead).
pub fn write_hdr(path: &Path, width: usize, height: usize, texels: &[Color]) -> std::io::Result<()> {
    encode_hdr(std::io::BufWriter::new(std::fs::File::create(path)?), width, height, texels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("rt-env-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join(name)
    }

    #[test]
    fn a_written_map_reads_back_within_the_rgbe_precision() {
        let texels: Vec<Color> =
            (0..12).map(|k| Color::new(k as f32 * 0.5, 100.0, 0.01 + k as f32)).collect();
        let path = temp("round.hdr");
        write_hdr(&path, 4, 3, &texels).unwrap();
        let image = read_environment_image(&path).unwrap();
        assert_eq!((image.width, image.height), (4, 3));
        for (a, b) in image.texels.iter().zip(&texels) {
            // RGBE keeps 8 bits of mantissa under a shared exponent.
            assert!((*a - *b).abs().max_element() <= b.max_element() / 128.0, "{a} against {b}");
        }
        assert!(image.warnings.is_empty());
    }

    #[test]
    fn missing_corrupt_and_non_hdr_files_are_clear_errors() {
        let e = read_environment_image(&temp("missing.hdr")).unwrap_err();
        assert!(matches!(e, EnvironmentImageError::Read(_)), "{e}");
        let path = temp("corrupt.hdr");
        std::fs::write(&path, b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 4\n\x02\x02").unwrap();
        let e = read_environment_image(&path).unwrap_err();
        assert!(matches!(e, EnvironmentImageError::Decode(_)), "{e}");
        let path = temp("text.hdr");
        std::fs::write(&path, b"hello").unwrap();
        let e = read_environment_image(&path).unwrap_err();
        assert!(matches!(e, EnvironmentImageError::Decode(_)), "{e}");
        // An 8-bit image is display-referred, not radiance: refused by kind.
        let path = temp("eight-bit.png");
        image::save_buffer(&path, &[10, 20, 30], 1, 1, image::ExtendedColorType::Rgb8).unwrap();
        let e = read_environment_image(&path).unwrap_err().to_string();
        assert!(e.contains("Radiance HDR") && e.contains("Png"), "{e}");
    }

    #[test]
    fn an_absurd_size_is_refused_from_the_header_alone() {
        // A header that claims 100000 × 100000 texels, and no data.
        let path = temp("huge.hdr");
        std::fs::write(&path, b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n").unwrap();
        let e = read_environment_image(&path).unwrap_err();
        assert!(matches!(e, EnvironmentImageError::Size { width: 100000, height: 100000 }), "{e}");
    }

    #[test]
    fn nan_and_negative_texels_become_zero_with_a_warning_and_a_black_map_is_refused() {
        let exr = temp("bad.exr");
        let pixels = [f32::NAN, 1.0, -2.0, 0.5, 0.5, 0.5];
        let bytes: Vec<u8> = pixels.iter().flat_map(|v| v.to_ne_bytes()).collect();
        image::save_buffer(&exr, &bytes, 2, 1, image::ExtendedColorType::Rgb32F).unwrap();
        let image = read_environment_image(&exr).unwrap();
        assert_eq!(image.texels, [Color::new(0.0, 1.0, 0.0), Color::splat(0.5)]);
        assert_eq!(
            image.warnings,
            ["1 NaN texel channel(s) set to 0", "1 negative texel channel(s) set to 0"]
        );
        let black = temp("black.hdr");
        write_hdr(&black, 2, 1, &[Color::ZERO; 2]).unwrap();
        assert!(matches!(read_environment_image(&black), Err(EnvironmentImageError::Black)));
    }
}
