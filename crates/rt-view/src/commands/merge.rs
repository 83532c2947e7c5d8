//! `rt-view merge PARTS... -o OUT.exr|OUT.png [--partial]`: the image of a
//! render split into parts (`rt-view render --part K/N`), from its part
//! files.
//!
//! The parts must be of one render: the same scene content, settings,
//! rt-view version and split (by sample ranges or by tiles, into N), each
//! part once. Then the merged image is the one `rt-view render` makes on
//! one machine, bit for bit: the parts hold exact per-pixel sums
//! ([`crate::exact_sum`]), which add up to the whole render's sums in any
//! order. Missing parts are named; `--partial` merges what is there.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use rt_core::render::view_transform::{Display, ViewTransform};

use crate::commands::render::display_of;
use crate::commands::render_part::color_space_named;
use crate::exact_sum::ExactColorSum;
use crate::image_out::PendingImage;
use crate::part_file::{self, PartHeader, SplitKind};

/// `rt-view merge`.
#[derive(Debug, Args)]
pub struct MergeArgs {
    /// The part files (.rtpart) of one render, in any order.
    #[arg(required = true, value_name = "PARTS")]
    pub parts: Vec<PathBuf>,
    /// Output file: .exr for linear HDR, or .png.
    #[arg(short, long, value_name = "OUT.exr")]
    pub output: PathBuf,
    /// Merge the parts that are there when some are missing: with sample
    /// ranges, an image of fewer samples per pixel; with tiles, the missing
    /// rows black. Says what is missing.
    #[arg(long)]
    pub partial: bool,
    /// Exposure of the PNG in stops (default: the one the parts were rendered with).
    #[arg(long, value_name = "STOPS", allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// View transform of the PNG (default: the one the parts were rendered with).
    #[arg(long, value_name = "standard|agx")]
    pub view_transform: Option<ViewTransform>,
}

/// What the merged parts hold: which parts, and which are missing.
#[derive(Debug, PartialEq)]
pub struct Coverage {
    /// The parts given, by index.
    pub present: Vec<u32>,
    /// The indices of the split that no file holds.
    pub missing: Vec<u32>,
}

/// Checks that the parts `headers` (each with its file) are of one render
/// and none is given twice, and says which indices are missing.
pub fn check_parts(headers: &[(PathBuf, PartHeader)]) -> anyhow::Result<Coverage> {
    let Some((first_path, first)) = headers.first() else { bail!("no parts to merge") };
    let a = first_path.display();
    for (path, h) in &headers[1..] {
        let b = path.display();
        if h.rt_view_version != first.rt_view_version {
            bail!(
                "{b}: rendered by rt-view {}, but {a} by rt-view {}: parts of different versions may differ, so do not merge",
                h.rt_view_version,
                first.rt_view_version
            );
        }
        if h.scene_hash != first.scene_hash {
            bail!(
                "{b}: a part of another scene than {a} ({} against {}: the scene file or a file it loads differs; \
                 content hash {} against {})",
                h.scene,
                first.scene,
                h.scene_hash,
                first.scene_hash
            );
        }
        if h.settings != first.settings {
            bail!(
                "{b}: rendered with other settings than {a}: {}",
                settings_difference(&h.settings, &first.settings)
            );
        }
        if (h.split.kind, h.split.count) != (first.split.kind, first.split.count) {
            bail!(
                "{b}: part of a split into {} {}, but {a} of a split into {} {}",
                h.split.count,
                h.split.kind.name(),
                first.split.count,
                first.split.kind.name()
            );
        }
    }
    let mut by_index: BTreeMap<u32, &Path> = BTreeMap::new();
    for (path, h) in headers {
        if let Some(other) = by_index.insert(h.split.index, path) {
            bail!(
                "part {}/{} given twice: {} and {} (parts must not overlap)",
                h.split.index,
                h.split.count,
                other.display(),
                path.display()
            );
        }
    }
    let missing = (0..first.split.count).filter(|k| !by_index.contains_key(k)).collect();
    Ok(Coverage { present: by_index.into_keys().collect(), missing })
}

/// The settings that differ, in words: "spp 16 against 32, seed 1 against 0".
fn settings_difference(b: &part_file::PartSettings, a: &part_file::PartSettings) -> String {
    let mut out = Vec::new();
    let mut differ = |name: &str, x: String, y: String| {
        if x != y {
            out.push(format!("{name} {x} against {y}"));
        }
    };
    differ("size", format!("{}x{}", b.width, b.height), format!("{}x{}", a.width, a.height));
    differ("spp", b.spp.to_string(), a.spp.to_string());
    differ("seed", b.seed.to_string(), a.seed.to_string());
    differ("colour space", b.color_space.clone(), a.color_space.clone());
    differ("exposure", b.exposure.to_string(), a.exposure.to_string());
    differ("view transform", b.view_transform.clone(), a.view_transform.clone());
    out.join(", ")
}

/// `1, 3` for `[1, 3]`.
fn list(indices: &[u32]) -> String {
    indices.iter().map(u32::to_string).collect::<Vec<_>>().join(",")
}

/// Reads the parts' headers, checks them ([`check_parts`]), reads and adds
/// their sums one part at a time (every byte checked) and writes the image
/// atomically. Nothing is written on any error.
pub fn run(args: &MergeArgs) -> anyhow::Result<()> {
    let output = PendingImage::create(&args.output)?;
    let mut headers = Vec::new();
    for path in &args.parts {
        let (header, _) = part_file::read_header(path).with_context(|| path.display().to_string())?;
        headers.push((path.clone(), header));
    }
    let coverage = check_parts(&headers)?;
    let first = headers[0].1.clone();
    let (split, s) = (first.split, &first.settings);
    if !coverage.missing.is_empty() && !args.partial {
        bail!(
            "missing part{} {} of {} ({}): render {} (a SLURM array: resubmit with --array={}), \
             or merge what is there with --partial",
            if coverage.missing.len() > 1 { "s" } else { "" },
            list(&coverage.missing),
            split.count,
            split.kind.name(),
            if coverage.missing.len() > 1 { "them" } else { "it" },
            list(&coverage.missing),
        );
    }

    let (width, height) = (s.width as usize, s.height);
    let mut sums = vec![ExactColorSum::default(); width * height as usize];
    // Samples held per row: all rows alike for sample ranges; per tile for tiles.
    let mut held = vec![0u32; height as usize];
    for (path, header) in &headers {
        let (read, part) = part_file::read(path).with_context(|| path.display().to_string())?;
        if &read != header {
            bail!("{}: changed while being merged", path.display());
        }
        let at = read.rows.start as usize * width;
        for (sum, p) in sums[at..at + part.len()].iter_mut().zip(&part) {
            sum.merge(p);
        }
        for row in read.rows.clone() {
            held[row as usize] += read.samples_held();
        }
    }
    let pixels = sums
        .chunks_exact(width)
        .zip(&held)
        .flat_map(|(row, &count)| row.iter().map(move |sum| sum.mean(count)))
        .collect();
    let color_space = color_space_named(&s.color_space)
        .with_context(|| format!("{}: unknown colour space {}", headers[0].0.display(), s.color_space))?;
    let view_transform: ViewTransform =
        s.view_transform.parse().map_err(|e: String| anyhow::anyhow!("{}: {e}", headers[0].0.display()))?;
    let display =
        display_of(Display { exposure: s.exposure, view_transform }, args.exposure, args.view_transform)?;
    let frame = rt_core::Frame { width: s.width, height, pixels, color_space, rays: Default::default() };
    output.write_frame(&frame, &display)?;

    let what = if coverage.missing.is_empty() {
        format!("{} spp", s.spp)
    } else {
        match split.kind {
            SplitKind::Samples => format!(
                "PARTIAL: {} of {} spp (missing parts {})",
                held.first().copied().unwrap_or(0),
                s.spp,
                list(&coverage.missing)
            ),
            SplitKind::Tiles => format!(
                "PARTIAL: rows of missing parts {} black ({} of {} rows rendered)",
                list(&coverage.missing),
                held.iter().filter(|&&c| c > 0).count(),
                height
            ),
        }
    };
    eprintln!(
        "merged {} of {} parts ({}) of {} into {} ({}x{height}, {what})",
        coverage.present.len(),
        split.count,
        split.kind.name(),
        first.scene,
        args.output.display(),
        s.width
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::part_file::{PartSettings, Split};

    fn header(kind: SplitKind, index: u32, count: u32) -> PartHeader {
        let split = Split { kind, index, count };
        let (rows, samples) = split.ranges(4, 8);
        PartHeader {
            rt_view_version: "1".into(),
            scene: "s.ron".into(),
            scene_hash: "aa".into(),
            settings: PartSettings {
                width: 2,
                height: 4,
                spp: 8,
                seed: 0,
                color_space: "srgb".into(),
                exposure: 0.0,
                view_transform: "standard".into(),
            },
            split,
            rows,
            samples,
            load_seconds: 0.0,
            render_seconds: 0.0,
            rays: 0,
        }
    }

    fn named(headers: Vec<PartHeader>) -> Vec<(PathBuf, PartHeader)> {
        headers.into_iter().enumerate().map(|(i, h)| (PathBuf::from(format!("p{i}.rtpart")), h)).collect()
    }

    #[test]
    fn missing_parts_are_named_and_present_ones_listed() {
        let parts = named(vec![header(SplitKind::Samples, 3, 4), header(SplitKind::Samples, 0, 4)]);
        assert_eq!(check_parts(&parts).unwrap(), Coverage { present: vec![0, 3], missing: vec![1, 2] });
    }

    #[test]
    fn a_part_given_twice_is_an_overlap() {
        let parts = named(vec![header(SplitKind::Tiles, 1, 2), header(SplitKind::Tiles, 1, 2)]);
        let e = check_parts(&parts).unwrap_err().to_string();
        assert!(e.contains("part 1/2 given twice: p0.rtpart and p1.rtpart"), "{e}");
    }

    #[test]
    fn parts_of_other_scenes_settings_versions_or_splits_are_refused_saying_which() {
        let base = header(SplitKind::Samples, 0, 2);
        type Change = Box<dyn Fn(&mut PartHeader)>;
        let cases: Vec<(Change, &str)> = vec![
            (Box::new(|h| h.scene_hash = "bb".into()), "another scene"),
            (Box::new(|h| h.settings.spp = 16), "spp 16 against 8"),
            (Box::new(|h| h.settings.seed = 3), "seed 3 against 0"),
            (Box::new(|h| h.settings.width = 3), "size 3x4 against 2x4"),
            (Box::new(|h| h.rt_view_version = "2".into()), "rt-view 2"),
            (Box::new(|h| h.split.kind = SplitKind::Tiles), "split into 2 tiles"),
            (Box::new(|h| h.split.count = 3), "split into 3 sample ranges"),
        ];
        for (change, message) in cases {
            let mut other = header(SplitKind::Samples, 1, 2);
            change(&mut other);
            let e = check_parts(&named(vec![base.clone(), other])).unwrap_err().to_string();
            assert!(e.starts_with("p1.rtpart: "), "{e}");
            assert!(e.contains(message), "{message}: {e}");
        }
    }
}
