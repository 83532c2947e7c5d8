//! Scenes rendered by the CLI, compared with committed references: small
//! golden images of the showcase (flat colours) and of the every-effect
//! scene, and the docs' pictures at their scenes' own sizes.
//!
//! Tolerance: a pixel "differs" when any channel is off by more than 2/255; at
//! most 0.5% of the pixels may differ. With flat colours every difference is
//! an edge pixel that changed object; with effects, also a shadow, AO or
//! reflection ray whose hit flipped. That is what a change in floating-point
//! rounding (another compiler, CPU or libm) can do, and nothing more.
//!
//! Regenerate the references after an intended change in the pictures:
//!
//! ```text
//! RT_BLESS=1 cargo test -p rt-view --test golden
//! ```

mod common;

use std::path::Path;

use common::{read_png, rt_view, scenes_dir, stderr};

const CHANNEL_TOLERANCE: i32 = 2;
const MAX_DIFFERING_FRACTION: f64 = 0.005;

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

/// Renders scenes/`name`.ron with `extra` arguments and compares the result
/// with `reference`, or overwrites `reference` when `RT_BLESS` is set.
fn compare_render(name: &str, reference: &Path, extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join(format!("{name}.png"));
    let scene = scenes_dir().join(format!("{name}.ron"));
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let o = rt_view(&args, "");
    assert!(o.status.success(), "{}", stderr(&o));
    if std::env::var_os("RT_BLESS").is_some() {
        std::fs::copy(&out, reference).unwrap();
        eprintln!("wrote {}", reference.display());
        return;
    }
    let (got, want) = (read_png(&out), read_png(reference));
    assert_eq!(got.dimensions(), want.dimensions());
    let differing = got
        .pixels()
        .zip(want.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0).any(|(&x, y)| (x as i32 - y as i32).abs() > CHANNEL_TOLERANCE))
        .count();
    let fraction = differing as f64 / got.pixels().len() as f64;
    assert!(
        fraction <= MAX_DIFFERING_FRACTION,
        "{differing} pixels ({:.2}%) differ from {}; if the change is intended, \
         regenerate with RT_BLESS=1 cargo test -p rt-view --test golden",
        100.0 * fraction,
        reference.display()
    );
}
