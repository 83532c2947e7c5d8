//! What `rt-view render` writes besides the plain image: feature passes
//! as EXR layers (`--passes`, `--aovs`) and the image denoised by OIDN
//! (`--denoise`).
//!
//! EXR channels: the colour `R`, `G`, `B` (the denoised colour under
//! `--denoise`, the noisy one then in `noisy.R`, `noisy.G`, `noisy.B`);
//! `albedo.R/G/B` and `N.X/Y/Z` (first non-specular hit, means over the
//! samples), `Z` (distance from the camera to the first hit, infinite
//! where none) and `id` (index of the first object hit in the scene
//! file's list, −1 where none): see [`rt_core::render::passes`]. Without
//! passes or denoising the EXR is the plain RGB file, unchanged.

use std::time::{Duration, Instant};

use clap::ValueEnum;
use rt_core::Color;
use rt_core::Frame;
use rt_core::render::passes::FeatureFrame;

use crate::denoise::{self, AuxImages};

/// A feature pass `--passes` can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, ValueEnum)]
pub enum Pass {
    /// `albedo.R/G/B`: the albedo of the first non-specular hit.
    Albedo,
    /// `N.X/Y/Z`: its shading normal, world space.
    Normal,
    /// `Z`: distance from the camera to the first hit.
    Depth,
    /// `id`: the first object hit.
    Id,
}

impl Pass {
    /// Every pass (`--aovs`).
    pub const ALL: [Pass; 4] = [Pass::Albedo, Pass::Normal, Pass::Depth, Pass::Id];
}

/// `colors`' channels named `prefix` + R, G, B (or the names given).
fn rgb_channels(colors: &[Color], names: [&str; 3]) -> Vec<(String, Vec<f32>)> {
    (0..3).map(|i| (names[i].to_owned(), colors.iter().map(|c| c[i]).collect())).collect()
}

/// The EXR channels of `frame` (its colour as `R`, `G`, `B`), the noisy
/// colour where `noisy` is given, and `passes` of `features`.
pub fn exr_channels(
    frame: &Frame,
    noisy: Option<&[Color]>,
    features: Option<&FeatureFrame>,
    passes: &[Pass],
) -> Vec<(String, Vec<f32>)> {
    let mut out = rgb_channels(&frame.pixels, ["R", "G", "B"]);
    if let Some(noisy) = noisy {
        out.extend(rgb_channels(noisy, ["noisy.R", "noisy.G", "noisy.B"]));
    }
    let Some(f) = features else { return out };
    for pass in passes {
        match pass {
            Pass::Albedo => out.extend(rgb_channels(&f.albedo(), ["albedo.R", "albedo.G", "albedo.B"])),
            Pass::Normal => out.extend(rgb_channels(&f.normal(), ["N.X", "N.Y", "N.Z"])),
            Pass::Depth => out.push(("Z".into(), f.depth())),
            Pass::Id => out.push(("id".into(), f.object_ids())),
        }
    }
    out
}

/// What denoising did: the time OIDN took, or why it did not run.
pub enum Denoised {
    /// The frame's pixels were replaced by OIDN's output in this time; the
    /// noisy pixels are kept.
    Done { took: Duration, noisy: Vec<Color> },
    /// OIDN is absent or failed: the frame is as rendered.
    Skipped(String),
}

/// Denoises `frame` in place with OIDN fed the albedo and normal of
/// `features` ([`crate::denoise`]); where OIDN is absent or fails the frame
/// stays as it is and the reason comes back (the caller warns and goes on).
pub fn denoise_frame(frame: &mut Frame, features: &FeatureFrame) -> Denoised {
    let oidn = match denoise::find_and_load() {
        Ok(oidn) => oidn,
        Err(e) => return Denoised::Skipped(e.to_string()),
    };
    let (albedo, normal) = (features.albedo(), features.normal());
    let start = Instant::now();
    let aux = AuxImages { albedo: Some(&albedo), normal: Some(&normal) };
    match oidn.denoise(frame.width, frame.height, &frame.pixels, aux) {
        Ok(clean) => {
            let noisy = std::mem::replace(&mut frame.pixels, clean);
            Denoised::Done { took: start.elapsed(), noisy }
        }
        Err(e) => Denoised::Skipped(e.to_string()),
    }
}
