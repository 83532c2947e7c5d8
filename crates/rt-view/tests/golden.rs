//! Scenes rendered by the CLI, compared with committed references: small
//! golden images of the showcase (flat colours) and of the every-effect
//! scene, and the docs' pictures at their scenes' own sizes.
//!
//! Two rules, both must hold:
//!
//! - Per pixel: a pixel "differs" when any channel is off by more than 2/255;
//!   at most 0.5% of the pixels may differ. With flat colours every
//!   difference is an edge pixel that changed object; with effects, also a
//!   shadow, AO or reflection ray whose hit flipped, or a path that took
//!   another turn. That is what a change in floating-point rounding (another
//!   compiler, CPU or libm) can do, and nothing more.
//! - Per block ([`biased_blocks`]): the mean of each 16×16 block, per channel
//!   in linear light, must not shift. 2/255 per pixel is 10 % of a dark
//!   pixel's value (sRGB level 40 and below), so a bias in the dark regions
//!   would pass the first rule; a block mean sees it.
//!
//! Regenerate the references after an intended change in the pictures:
//!
//! ```text
//! RT_BLESS=1 cargo test -p rt-view --test golden
//! ```
//!
//! Only `RT_BLESS=1` blesses: any other value (`0`, `true`, empty) is an
//! error, so that no setting meant to switch blessing off overwrites them.

mod common;

use std::path::{Path, PathBuf};

use common::{read_png, rt_view, scenes_dir, stderr};
use image::RgbImage;
use rt_core::math::color::ColorSpace;

const CHANNEL_TOLERANCE: i32 = 2;
const MAX_DIFFERING_FRACTION: f64 = 0.005;

/// Side of the blocks whose means [`biased_blocks`] compares, pixels.
const BLOCK: u32 = 16;
/// A block's mean shift must reach this many standard errors to count
/// ([`biased_blocks`]).
const BLOCK_SIGMAS: f64 = 5.0;
/// … and this fraction of the reference block's mean …
const BLOCK_RELATIVE: f64 = 0.02;
/// … plus this much linear light: a third of the smallest sRGB step (1/255
/// of 12.92⁻¹ ≈ 3·10⁻⁴), below which a shift is not visible in 8 bits.
const BLOCK_ABSOLUTE: f64 = 1e-4;

#[test]
fn showcase_matches_the_reference_image() {
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/showcase_240x135.png");
    compare_render("showcase", &reference, &["--width", "240", "--height", "135"]);
}

#[test]
fn every_effect_scene_matches_the_reference_image() {
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/effects_160x90.png");
    compare_render("effects", &reference, &["--width", "160", "--height", "90"]);
}

/// The README's picture is what the README's command renders (the scene's own
/// size, 800×450), so the README stays true when the scene or renderer changes.
#[test]
fn readme_picture_is_the_current_showcase_render() {
    let picture = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/showcase.png");
    compare_render("showcase", &picture, &[]);
}

/// Likewise for the effect pictures of docs/effects.md, docs/effects/SCENE.png,
/// each rendered by `rt-view render scenes/SCENE.ron` at the scene's own
/// settings (and the 1-spp anti-aliasing comparison with `--spp 1`).
#[test]
fn docs_effect_pictures_are_current_renders() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/effects");
    for scene in ["shadows", "soft_shadows", "mirrors", "glass", "ao", "antialiasing", "effects"] {
        compare_render(scene, &docs.join(format!("{scene}.png")), &[]);
    }
    compare_render("antialiasing", &docs.join("antialiasing_1spp.png"), &["--spp", "1"]);
}

/// And for the global-illumination pictures of docs/effects.md,
/// docs/gi/SCENE.png: many samples each, so this is the slowest test (about
/// 30 s on two cores), but the sampling is deterministic, so the picture is
/// checked like the others, not merely in the mean.
#[test]
fn docs_global_illumination_pictures_are_current_renders() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/gi");
    for scene in ["cornell_box", "caustic", "interreflection", "sky"] {
        compare_render(scene, &docs.join(format!("{scene}.png")), &[]);
    }
}

/// And for the subsurface-scattering pictures of docs/effects.md (and the
/// README), docs/sss/SCENE.png.
#[test]
fn docs_subsurface_pictures_are_current_renders() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/sss");
    for scene in ["subsurface", "translucent_slab", "skin_mesh"] {
        compare_render(scene, &docs.join(format!("{scene}.png")), &[]);
    }
}

/// And for the models of docs/models.md (and the README): an OBJ with its
/// MTL materials and texture, and a glTF file, docs/models/models.png.
#[test]
fn docs_model_pictures_are_current_renders() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/models");
    compare_render("models", &docs.join("models.png"), &[]);
}

/// And for the environment, sky and lens pictures of docs/scene-format.md,
/// docs/environment/SCENE.png (AgX, as the scenes ask), with the studio
/// once more through the standard transform.
#[test]
fn docs_environment_pictures_are_current_renders() {
    let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/environment");
    for scene in ["studio", "outdoor", "depth_of_field"] {
        compare_render(scene, &docs.join(format!("{scene}.png")), &[]);
    }
    compare_render("studio", &docs.join("studio_standard.png"), &["--view-transform", "standard"]);
}

/// Whether the references are to be overwritten, from `RT_BLESS`: unset
/// compares, `1` blesses, any other value is an error (see the module's
/// documentation).
fn bless_requested(value: Option<&std::ffi::OsStr>) -> Result<bool, String> {
    match value {
        None => Ok(false),
        Some(v) if v == "1" => Ok(true),
        Some(v) => Err(format!(
            "RT_BLESS={v:?}: only RT_BLESS=1 overwrites the reference images; unset RT_BLESS to compare with them"
        )),
    }
}

/// Renders scenes/`name`.ron with `extra` arguments and compares the result
/// with `reference` (both rules of the module's documentation), or
/// overwrites `reference` when `RT_BLESS=1`.
fn compare_render(name: &str, reference: &Path, extra: &[&str]) {
    let bless = bless_requested(std::env::var_os("RT_BLESS").as_deref()).unwrap_or_else(|e| panic!("{e}"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(format!("{name}.png"));
    let scene = scenes_dir().join(format!("{name}.ron"));
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = rt_view(&args, "");
    assert!(o.status.success(), "{}", stderr(&o));
    if bless {
        std::fs::copy(&out, reference).unwrap();
        eprintln!("wrote {}", reference.display());
        return;
    }
    let (got, want) = (read_png(&out), read_png(reference));
    assert_eq!(got.dimensions(), want.dimensions());
    let fraction = differing_fraction(&got, &want);
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{:.2}% of the pixels differ from {}; if the change is intended, \
         regenerate with RT_BLESS=1 cargo test -p rt-view --test golden",
        100.0 * fraction,
        reference.display()
    );
    let color_space = rt_core::load_scene(&scene).unwrap().settings.color_space;
    let biased = biased_blocks(&got, &want, color_space);
    assert!(
        biased.is_empty(),
        "{} blocks of {} are brighter or darker than the reference's (first: {}); if the change is \
         intended, regenerate with RT_BLESS=1 cargo test -p rt-view --test golden",
        biased.len(),
        reference.display(),
        biased[0]
    );
}

/// The fraction of pixels with a channel more than [`CHANNEL_TOLERANCE`] off.
fn differing_fraction(got: &RgbImage, want: &RgbImage) -> f64 {
    let differing = got
        .pixels()
        .zip(want.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(&x, y)| (x as i32 - y as i32).abs() > CHANNEL_TOLERANCE))
        .count();
    differing as f64 / got.pixels().len() as f64
}

/// An 8-bit value decoded to linear light: the inverse of
/// [`ColorSpace::encode`] (IEC 61966-2-1 for sRGB).
fn decode(v: u8, color_space: ColorSpace) -> f64 {
    let e = v as f64 / 255.0;
    match color_space {
        ColorSpace::Linear => e,
        ColorSpace::Srgb if e <= 0.04045 => e / 12.92,
        ColorSpace::Srgb => ((e + 0.055) / 1.055).powf(2.4),
    }
}

/// The blocks ([`BLOCK`]² pixels, smaller at the right and bottom edges)
/// whose mean in linear light shifted, per channel, from `want` to `got`;
/// each as "block (x, y), channel c: mean m → m′ (…σ)".
///
/// Estimator: per channel, the pixel differences dᵢ = gotᵢ − wantᵢ of the n
/// pixels of a block; the shift is their mean Δ = Σdᵢ/n, with standard error
/// σ = √(Σdᵢ²)/n. That σ is the spread of the differences themselves, the
/// noise of the comparison: the render and its reference share their
/// samples (the sampling is deterministic), so differing pixels are those
/// whose rays a rounding change sent elsewhere, fresh samples of the same
/// pixel whose differences average to zero, with that standard error. (The
/// spread of the reference's own pixels is not the noise here: it counts the
/// image's edges and textures, and would hide a bias in any textured block.)
///
/// A block is biased when |Δ| > [`BLOCK_SIGMAS`]·σ (a shift of fresh samples
/// passes that with probability ≈ 6·10⁻⁷ per block and channel; and since
/// |Σdᵢ| ≤ √k·√(Σdᵢ²) for k differing pixels (Cauchy–Schwarz), fewer than
/// 25 differing pixels can never reach 5σ) and |Δ| > [`BLOCK_RELATIVE`] of
/// the reference block's mean plus [`BLOCK_ABSOLUTE`] (a shift too small to
/// matter, or to see in 8 bits). A bias moves every pixel of a block the
/// same way: a 10 % darkening of a block whose mean is m gives Δ = −0.1·m
/// and, all dᵢ alike, Δ/σ = √n = 16 for a full block, whatever the noise.
fn biased_blocks(got: &RgbImage, want: &RgbImage, color_space: ColorSpace) -> Vec<String> {
    assert_eq!(got.dimensions(), want.dimensions());
    let (width, height) = got.dimensions();
    let mut biased = Vec::new();
    for by in (0..height).step_by(BLOCK as usize) {
        for bx in (0..width).step_by(BLOCK as usize) {
            for c in 0..3 {
                let (mut sum_want, mut sum_d, mut sum_d2, mut n) = (0.0, 0.0, 0.0, 0.0);
                for y in by..(by + BLOCK).min(height) {
                    for x in bx..(bx + BLOCK).min(width) {
                        let w = decode(want.get_pixel(x, y).0[c], color_space);
                        let d = decode(got.get_pixel(x, y).0[c], color_space) - w;
                        sum_want += w;
                        sum_d += d;
                        sum_d2 += d * d;
                        n += 1.0;
                    }
                }
                let (mean, shift, sigma) = (sum_want / n, sum_d / n, sum_d2.sqrt() / n);
                if shift.abs() > BLOCK_SIGMAS * sigma && shift.abs() > BLOCK_RELATIVE * mean + BLOCK_ABSOLUTE
                {
                    biased.push(format!(
                        "block ({bx}, {by}), channel {c}: mean {mean:.5} → {:.5} ({:.1}σ)",
                        mean + shift,
                        shift.abs() / sigma
                    ));
                }
            }
        }
    }
    biased
}

/// `image` with every pixel whose channels are all below `level` (linear),
/// and one at least above `level`/5, made `factor` times as bright, in
/// linear light, and encoded again; and how many pixels that is.
fn scaled_dark_pixels(
    image: &RgbImage,
    color_space: ColorSpace,
    level: f64,
    factor: f64,
) -> (RgbImage, usize) {
    let mut out = image.clone();
    let mut count = 0;
    for p in out.pixels_mut() {
        let linear = p.0.map(|v| decode(v, color_space));
        if linear.iter().all(|&v| v < level) && linear.iter().any(|&v| v >= level / 5.0) {
            let scaled = rt_core::Color::new(
                (linear[0] * factor) as f32,
                (linear[1] * factor) as f32,
                (linear[2] * factor) as f32,
            );
            p.0 = color_space.encode(scaled);
            count += 1;
        }
    }
    (out, count)
}

/// Committed references (path, scene) and their colour spaces.
fn references(files: &[(&str, &str)]) -> Vec<(PathBuf, ColorSpace)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    files
        .iter()
        .map(|(file, scene)| {
            let color_space =
                rt_core::load_scene(&scenes_dir().join(format!("{scene}.ron"))).unwrap().settings.color_space;
            (root.join(file), color_space)
        })
        .collect()
}

/// The references with dark regions: path-traced and subsurface pictures.
const DARK: [(&str, &str); 3] = [
    ("../../docs/gi/cornell_box.png", "cornell_box"),
    ("../../docs/gi/caustic.png", "caustic"),
    ("../../docs/sss/skin_mesh.png", "skin_mesh"),
];

/// Those and others: flat colours, every classic effect, more path tracing.
const OTHERS: [(&str, &str); 4] = [
    ("tests/golden/showcase_240x135.png", "showcase"),
    ("tests/golden/effects_160x90.png", "effects"),
    ("../../docs/gi/interreflection.png", "interreflection"),
    ("../../docs/sss/subsurface.png", "subsurface"),
];

#[test]
fn a_ten_percent_darkening_of_the_dark_regions_passes_the_pixel_rule_but_not_the_block_rule() {
    for (path, color_space) in references(&DARK) {
        let reference = read_png(&path);
        // Every pixel darker than the level below which 10 % of it is at most
        // 2/255 once encoded: linear 0.02 (level 39) in sRGB, 0.075 (level 19)
        // in linear; and not black (a fifth of that level at least), where
        // 10 % is less than one step of 8 bits and nothing can see it.
        let level = match color_space {
            ColorSpace::Srgb => 0.02,
            ColorSpace::Linear => 0.075,
        };
        let (darker, count) = scaled_dark_pixels(&reference, color_space, level, 0.9);
        assert!(count >= (BLOCK * BLOCK) as usize, "{}: only {count} dark pixels", path.display());
        assert!(differing_fraction(&darker, &reference) <= MAX_DIFFERING_FRACTION, "{}", path.display());
        let biased = biased_blocks(&darker, &reference, color_space);
        assert!(!biased.is_empty(), "{}: a 10 % darkening of {count} dark pixels passes", path.display());
        // Nor does a 10 % brightening pass.
        let (brighter, _) = scaled_dark_pixels(&reference, color_space, level, 1.1);
        assert!(!biased_blocks(&brighter, &reference, color_space).is_empty(), "{}", path.display());
        // The reference against itself: nothing.
        assert!(biased_blocks(&reference, &reference, color_space).is_empty());
    }
}

#[test]
fn pixels_that_change_at_random_do_not_make_a_block_biased() {
    // What a rounding change does to a path-traced image: some pixels become
    // other samples of themselves. Model: 1 pixel in 10 (twenty times the
    // 0.5 % the pixel rule allows, about 25 in every block, enough to reach
    // 5σ if they all moved one way) replaced by one of its four neighbours,
    // chosen by a fixed xorshift sequence (in flat images, only edge pixels
    // change).
    for (path, color_space) in references(&[&DARK[..], &OTHERS[..]].concat()) {
        let reference = read_png(&path);
        let mut changed = reference.clone();
        let (w, h) = reference.dimensions();
        let mut state = 0x9E37_79B9_7F4A_7C15_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                if next() % 10 == 0 {
                    let (nx, ny) = [(x - 1, y), (x + 1, y), (x, y - 1), (x, y + 1)][(next() % 4) as usize];
                    changed.put_pixel(x, y, *reference.get_pixel(nx, ny));
                }
            }
        }
        let biased = biased_blocks(&changed, &reference, color_space);
        assert!(biased.is_empty(), "{}: {biased:?}", path.display());
    }
}

#[test]
fn only_rt_bless_1_blesses() {
    use std::ffi::OsStr;
    assert_eq!(bless_requested(None), Ok(false));
    assert_eq!(bless_requested(Some(OsStr::new("1"))), Ok(true));
    for other in ["0", "", "true", "yes", " 1", "2"] {
        let err = bless_requested(Some(OsStr::new(other))).unwrap_err();
        assert!(err.contains("only RT_BLESS=1"), "{other:?}: {err}");
    }
}
