//! `rt-view render SCENE --part K/N [--tiles] -o PART.rtpart`: one part of
//! a render split over many machines (a SLURM job array's tasks), written
//! as a part file ([`crate::part_file`]) for `rt-view merge`.

use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::bail;
use indicatif::{ProgressBar, ProgressStyle};
use rt_core::render::settings::RenderSettings;
use rt_core::render::view_transform::Display;
use rt_core::{Renderer, math::color::ColorSpace};

use crate::image_out::PendingFile;
use crate::part_file::{self, PartHeader, PartSettings, Split, SplitKind};
use crate::sum_render::render_sums;

/// The extension part files must have.
pub const PART_EXTENSION: &str = "rtpart";

/// `--part K/N`: part K (0-based) of N.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PartOf {
    /// K, in 0..N.
    pub index: u32,
    /// N, at least 1.
    pub count: u32,
}

impl PartOf {
    /// Parses `K/N` with 0 ≤ K < N.
    pub fn parse(text: &str) -> Result<Self, String> {
        let wrong = || format!("\"{text}\" is not K/N with 0 <= K < N (e.g. 0/4 .. 3/4)");
        let (k, n) = text.split_once('/').ok_or_else(wrong)?;
        let (index, count) = (k.trim().parse().map_err(|_| wrong())?, n.trim().parse().map_err(|_| wrong())?);
        if index >= count {
            return Err(wrong());
        }
        Ok(Self { index, count })
    }

    /// This part of a split by tiles (`tiles`) or by sample ranges.
    pub fn split(self, tiles: bool) -> Split {
        let kind = if tiles { SplitKind::Tiles } else { SplitKind::Samples };
        Split { kind, index: self.index, count: self.count }
    }
}

/// A part file output whose name and directory have been checked, not yet written.
pub struct PendingPart {
    file: PendingFile,
    target: std::path::PathBuf,
    split: Split,
}

impl PendingPart {
    /// Checks that `target` is named `.rtpart` and its directory accepts a new file.
    pub fn create(target: &Path, split: Split) -> anyhow::Result<Self> {
        if !target.extension().is_some_and(|e| e.eq_ignore_ascii_case(PART_EXTENSION)) {
            bail!("{}: a part (--part) is written to a .{PART_EXTENSION} file", target.display());
        }
        Ok(Self { file: PendingFile::create(target)?, target: target.to_owned(), split })
    }

    /// Renders this part of the render `renderer` makes of `scene` (read
    /// from `scene_file`; its loading began at `load_start`) with `settings`
    /// and writes it atomically: nothing on an error or on Ctrl-C, which
    /// returns `false`.
    pub fn render(
        self,
        scene_file: &Path,
        scene: &rt_core::Scene,
        renderer: &Renderer,
        settings: &RenderSettings,
        display: Display,
        load_start: Instant,
    ) -> anyhow::Result<bool> {
        let (width, height, spp) = (settings.image.width(), settings.image.height(), settings.samples.get());
        let split = self.split;
        let (limit, what) = match split.kind {
            SplitKind::Samples => (spp, "samples per pixel"),
            SplitKind::Tiles => (height, "rows"),
        };
        if split.count > limit {
            bail!(
                "--part {}/{}: {} parts of {limit} {what} would leave some empty; use at most {limit} parts{}",
                split.index,
                split.count,
                split.count,
                if split.kind == SplitKind::Samples { " (or --tiles)" } else { "" }
            );
        }
        let scene_hash = crate::scene_cache::scene_hash(scene_file, scene)?;
        let load_seconds = load_start.elapsed().as_secs_f64();
        let (rows, samples) = split.ranges(height, spp);

        let stop = Arc::new(AtomicBool::new(false));
        let handler_stop = stop.clone();
        let _ = ctrlc::set_handler(move || handler_stop.store(true, Ordering::Relaxed));
        let bar = ProgressBar::new(rows.len() as u64).with_style(
            ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} rows, {elapsed} (ETA {eta})")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_message(format!(
            "part {}/{}: rows {}..{}, samples {}..{} of {spp}",
            split.index, split.count, rows.start, rows.end, samples.start, samples.end
        ));
        let start = Instant::now();
        let result = render_sums(renderer, rows.clone(), samples.clone(), |_| bar.inc(1), &stop);
        let render_seconds = start.elapsed().as_secs_f64();
        bar.finish_and_clear();
        let Some((sums, rays)) = result else { return Ok(false) };

        let header = PartHeader {
            rt_view_version: env!("CARGO_PKG_VERSION").to_owned(),
            scene: scene_file.display().to_string(),
            scene_hash,
            settings: PartSettings {
                width,
                height,
                spp,
                seed: settings.seed,
                color_space: color_space_name(settings.color_space).to_owned(),
                exposure: display.exposure,
                view_transform: display.view_transform.name().to_owned(),
            },
            split,
            rows: rows.clone(),
            samples: samples.clone(),
            load_seconds,
            render_seconds,
            rays: rays.total(),
        };
        let write_start = Instant::now();
        self.file.write_with(|out| part_file::write(out, &header, &sums).map_err(Into::into))?;
        eprintln!(
            "wrote {} (part {}/{} by {}: rows {}..{}, samples {}..{} of {spp}; {width}x{height}) \
             load {load_seconds:.3} s, render {render_seconds:.3} s, write {:.3} s",
            self.target.display(),
            split.index,
            split.count,
            split.kind.name(),
            rows.start,
            rows.end,
            samples.start,
            samples.end,
            write_start.elapsed().as_secs_f64()
        );
        Ok(true)
    }
}

/// The colour space's name in part files.
pub fn color_space_name(c: ColorSpace) -> &'static str {
    match c {
        ColorSpace::Linear => "linear",
        ColorSpace::Srgb => "srgb",
    }
}

/// The colour space a part file names.
pub fn color_space_named(name: &str) -> Option<ColorSpace> {
    match name {
        "linear" => Some(ColorSpace::Linear),
        "srgb" => Some(ColorSpace::Srgb),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn part_numbers_are_k_of_n_counted_from_zero() {
        assert_eq!(PartOf::parse("0/4"), Ok(PartOf { index: 0, count: 4 }));
        assert_eq!(PartOf::parse("3/4"), Ok(PartOf { index: 3, count: 4 }));
        for bad in ["4/4", "1/0", "0/0", "-1/4", "1", "a/b", "1/4/5", ""] {
            assert!(PartOf::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn colour_space_names_round_trip() {
        for c in [ColorSpace::Linear, ColorSpace::Srgb] {
            assert_eq!(color_space_named(color_space_name(c)), Some(c));
        }
    }
}
