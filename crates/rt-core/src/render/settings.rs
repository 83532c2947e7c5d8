//! How to render a scene: everything a render needs besides the world
//! ([`crate::scene::Scene`]) and the camera. A scene file gives the first
//! settings ([`crate::files::scene_file::LoadedScene`]); the command line and the
//! viewer override them, each value checked once, by the constructor of its
//! type, with one error type ([`SettingsError`]).

use thiserror::Error;

use crate::camera::view_plane::{MAX_IMAGE_SIDE, MAX_PIXELS, check_image_size};
use crate::math::color::ColorSpace;
use crate::render::view_transform::Display;
use crate::sampling::sampler::{MAX_SAMPLES_PER_PIXEL, SamplerKind};
use crate::scene::effects::{EffectToggles, Effects};

/// Why a render setting is out of range.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SettingsError {
    /// Width or height is zero or above [`MAX_IMAGE_SIDE`], or W·H is above [`MAX_PIXELS`].
    #[error(
        "image size {width}x{height} is out of range: each side must be 1 to {MAX_IMAGE_SIDE} \
         and the image at most {MAX_PIXELS} pixels"
    )]
    ImageSize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// Samples per pixel out of range.
    #[error("samples per pixel must be 1 to {MAX_SAMPLES_PER_PIXEL}, got {0}")]
    SamplesPerPixel(u32),
    /// A noise threshold that is not a finite number above 0.
    #[error("the noise threshold must be a finite number above 0, got {0}")]
    NoiseThreshold(f32),
    /// A minimum sample count out of range.
    #[error("the minimum samples per pixel must be 1 to {MAX_SAMPLES_PER_PIXEL}, got {0}")]
    MinSamples(u32),
    /// A minimum sample count given with no noise threshold to apply it to.
    #[error("a minimum sample count needs a noise threshold (adaptive sampling is off)")]
    MinSamplesWithoutThreshold,
}

/// Adaptive sampling: each pixel stops taking samples once its noise
/// estimate falls below `threshold` ([`crate::render::adaptive`]), after at
/// least `min_samples`. Valid by construction.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AdaptiveSampling {
    threshold: f32,
    min_samples: u32,
}

impl AdaptiveSampling {
    /// The minimum sample count when none is given.
    pub const DEFAULT_MIN_SAMPLES: u32 = 16;

    /// Adaptive sampling to the noise `threshold` (finite, above 0) after at
    /// least `min_samples` (1 to [`MAX_SAMPLES_PER_PIXEL`]), or why not.
    pub fn new(threshold: f32, min_samples: u32) -> Result<Self, SettingsError> {
        if !(threshold.is_finite() && threshold > 0.0) {
            return Err(SettingsError::NoiseThreshold(threshold));
        }
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&min_samples) {
            return Err(SettingsError::MinSamples(min_samples));
        }
        Ok(Self { threshold, min_samples })
    }

    /// The noise threshold: a pixel whose relative error estimate is below
    /// it has converged.
    pub fn threshold(self) -> f32 {
        self.threshold
    }

    /// The samples every pixel takes before its noise is first estimated.
    pub fn min_samples(self) -> u32 {
        self.min_samples
    }
}

/// An image size in pixels: each side 1 to [`MAX_IMAGE_SIDE`], at most
/// [`MAX_PIXELS`] in all. Valid by construction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ImageSize {
    width: u32,
    height: u32,
}

impl ImageSize {
    /// `width`×`height`, or why not.
    pub fn new(width: u32, height: u32) -> Result<Self, SettingsError> {
        check_image_size(width, height).map_err(|_| SettingsError::ImageSize { width, height })?;
        Ok(Self { width, height })
    }

    /// Width in pixels.
    pub fn width(self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(self) -> u32 {
        self.height
    }
}

impl Default for ImageSize {
    /// 640×480.
    fn default() -> Self {
        Self { width: 640, height: 480 }
    }
}

/// Samples per pixel, 1 to [`MAX_SAMPLES_PER_PIXEL`]; 1 means one ray
/// through each pixel centre. Valid by construction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub struct SamplesPerPixel(u32);

impl SamplesPerPixel {
    /// One sample, through the pixel's centre.
    pub const ONE: Self = Self(1);

    /// `n` samples, or why not.
    pub fn new(n: u32) -> Result<Self, SettingsError> {
        if (1..=MAX_SAMPLES_PER_PIXEL).contains(&n) {
            Ok(Self(n))
        } else {
            Err(SettingsError::SamplesPerPixel(n))
        }
    }

    /// The count.
    pub fn get(self) -> u32 {
        self.0
    }
}

impl Default for SamplesPerPixel {
    fn default() -> Self {
        Self::ONE
    }
}

/// Everything about a render that is not the world or the camera.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RenderSettings {
    /// The image size.
    pub image: ImageSize,
    /// Samples per pixel.
    pub samples: SamplesPerPixel,
    /// Seed of the random numbers: renders with different seeds are
    /// independent estimates of the same image ([`crate::sampling::sampler::SampleRng::seeded`]); 0 by default.
    pub seed: u64,
    /// Which points the samples take: stratified jitter with independent
    /// random numbers, or Owen-scrambled Sobol points
    /// ([`crate::sampling::sampler::Sampler`]).
    pub sampler: SamplerKind,
    /// Adaptive sampling, if any: pixels stop taking samples once their
    /// noise estimate is below a threshold, `samples` being the most.
    pub adaptive: Option<AdaptiveSampling>,
    /// How rendered colours are encoded into 8-bit pixels.
    pub color_space: ColorSpace,
    /// The light transport asked for: recursion depth, ambient occlusion,
    /// global illumination (which chooses the path tracer).
    pub effects: Effects,
    /// Effects switched off by the user (the viewer's toggles); a render
    /// never simulates what neither the scene nor `effects` asks for.
    pub toggles: EffectToggles,
    /// The exposure and view transform of 8-bit output (not of EXR).
    pub display: Display,
}

impl RenderSettings {
    /// These settings at another image size.
    pub fn with_image(self, image: ImageSize) -> Self {
        Self { image, ..self }
    }

    /// These settings with another sample count.
    pub fn with_samples(self, samples: SamplesPerPixel) -> Self {
        Self { samples, ..self }
    }

    /// These settings with the image width, height and sample count
    /// replaced where given (a command line's `--width`, `--height`,
    /// `--spp`), each checked as its type's constructor checks it.
    pub fn overridden(
        self,
        width: Option<u32>,
        height: Option<u32>,
        samples: Option<u32>,
    ) -> Result<Self, SettingsError> {
        let image = ImageSize::new(width.unwrap_or(self.image.width), height.unwrap_or(self.image.height))?;
        let samples = samples.map_or(Ok(self.samples), SamplesPerPixel::new)?;
        Ok(Self { image, samples, ..self })
    }

    /// These settings with another seed.
    pub fn with_seed(self, seed: u64) -> Self {
        Self { seed, ..self }
    }

    /// These settings with adaptive sampling as the command line's
    /// `--noise-threshold` and `--min-samples` say, where given: a threshold
    /// of 0 switches it off, a minimum alone changes that of the settings'
    /// own adaptive sampling (and is refused without one).
    pub fn with_adaptive(
        self,
        threshold: Option<f32>,
        min_samples: Option<u32>,
    ) -> Result<Self, SettingsError> {
        let min = min_samples
            .or(self.adaptive.map(AdaptiveSampling::min_samples))
            .unwrap_or(AdaptiveSampling::DEFAULT_MIN_SAMPLES);
        let adaptive = match (threshold, self.adaptive) {
            (Some(0.0), _) => None,
            (Some(t), _) => Some(AdaptiveSampling::new(t, min)?),
            (None, Some(a)) => Some(AdaptiveSampling::new(a.threshold, min)?),
            (None, None) if min_samples.is_some() => return Err(SettingsError::MinSamplesWithoutThreshold),
            (None, None) => None,
        };
        Ok(Self { adaptive, ..self })
    }

    /// These settings with another sampler.
    pub fn with_sampler(self, sampler: SamplerKind) -> Self {
        Self { sampler, ..self }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_sample_counts_out_of_range_are_refused_with_the_value() {
        assert_eq!(ImageSize::new(0, 240), Err(SettingsError::ImageSize { width: 0, height: 240 }));
        assert_eq!(
            ImageSize::new(MAX_IMAGE_SIDE + 1, 1).map(|_| ()),
            Err(SettingsError::ImageSize { width: MAX_IMAGE_SIDE + 1, height: 1 })
        );
        assert_eq!(ImageSize::new(320, 240).map(|s| (s.width(), s.height())), Ok((320, 240)));
        assert_eq!(SamplesPerPixel::new(0), Err(SettingsError::SamplesPerPixel(0)));
        assert_eq!(
            SamplesPerPixel::new(MAX_SAMPLES_PER_PIXEL + 1),
            Err(SettingsError::SamplesPerPixel(MAX_SAMPLES_PER_PIXEL + 1))
        );
        assert_eq!(
            SamplesPerPixel::new(MAX_SAMPLES_PER_PIXEL).map(SamplesPerPixel::get),
            Ok(MAX_SAMPLES_PER_PIXEL)
        );
        let file = RenderSettings::default();
        let wider = file.overridden(Some(1000), None, Some(9)).unwrap();
        assert_eq!((wider.image.width(), wider.image.height(), wider.samples.get()), (1000, 480, 9));
        assert_eq!(
            file.overridden(None, Some(0), None),
            Err(SettingsError::ImageSize { width: 640, height: 0 })
        );
        assert_eq!(file.overridden(None, None, Some(0)), Err(SettingsError::SamplesPerPixel(0)));
        let e = SamplesPerPixel::new(0).unwrap_err().to_string();
        assert!(e.starts_with("samples per pixel must be 1 to"), "{e}");
    }

    #[test]
    fn adaptive_sampling_takes_a_positive_threshold_and_a_minimum_and_zero_switches_it_off() {
        assert_eq!(AdaptiveSampling::new(0.0, 16), Err(SettingsError::NoiseThreshold(0.0)));
        assert!(matches!(AdaptiveSampling::new(f32::NAN, 16), Err(SettingsError::NoiseThreshold(_))));
        assert_eq!(AdaptiveSampling::new(0.01, 0), Err(SettingsError::MinSamples(0)));
        let file = RenderSettings::default();
        let on = file.with_adaptive(Some(0.02), None).unwrap().adaptive.unwrap();
        assert_eq!((on.threshold(), on.min_samples()), (0.02, AdaptiveSampling::DEFAULT_MIN_SAMPLES));
        let scene = RenderSettings { adaptive: Some(AdaptiveSampling::new(0.05, 8).unwrap()), ..file };
        assert_eq!(scene.with_adaptive(None, None).unwrap(), scene);
        assert_eq!(scene.with_adaptive(Some(0.0), None).unwrap().adaptive, None);
        let more = scene.with_adaptive(None, Some(32)).unwrap().adaptive.unwrap();
        assert_eq!((more.threshold(), more.min_samples()), (0.05, 32));
        assert_eq!(file.with_adaptive(None, Some(32)), Err(SettingsError::MinSamplesWithoutThreshold));
        assert_eq!(file.with_adaptive(Some(-1.0), None), Err(SettingsError::NoiseThreshold(-1.0)));
        let e = SamplesPerPixel::new(0).unwrap_err().to_string();
        assert!(e.starts_with("samples per pixel must be 1 to"), "{e}");
    }
}
