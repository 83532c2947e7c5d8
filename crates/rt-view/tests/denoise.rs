//! `rt-view render --denoise` and `--passes`: the denoised image is closer
//! to a converged one than the noisy image, or, where OIDN is absent, the
//! render says so and writes the image as rendered; passes go into EXR
//! layers and leave the colour as it was.

mod common;

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use common::{rt_view, scenes_dir, stderr};

/// Runs `rt-view` with `args`, with `RT_VIEW_OIDN` set to `oidn` (or left
/// as the environment has it).
fn rt_view_with_oidn(args: &[&str], oidn: Option<&Path>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_rt-view"));
    command.args(args).stdin(Stdio::null());
    if let Some(oidn) = oidn {
        command.env("RT_VIEW_OIDN", oidn);
    }
    command.output().unwrap()
}

/// Every channel of an EXR file, by name.
fn exr_channels(path: &Path) -> BTreeMap<String, Vec<f32>> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    image
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

/// Root-mean-square difference of the `R`, `G`, `B` channels (or those with
/// `prefix`) of `a` from those of `reference`, each value clamped to [0, 1]
/// first (as a display shows it: the light's radiance of 17 would
/// otherwise outweigh the whole room).
fn rmse(a: &BTreeMap<String, Vec<f32>>, prefix: &str, reference: &BTreeMap<String, Vec<f32>>) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for c in ["R", "G", "B"] {
        for (x, y) in a[&format!("{prefix}{c}")].iter().zip(&reference[c]) {
            sum += ((x.clamp(0.0, 1.0) - y.clamp(0.0, 1.0)) as f64).powi(2);
            n += 1;
        }
    }
    (sum / n as f64).sqrt()
}

fn render_args<'a>(scene: &'a str, out: &'a str, spp: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec!["render", scene, "-o", out, "--width", "64", "--height", "64", "--spp", spp];
    args.extend_from_slice(extra);
    args
}

#[test]
fn denoising_brings_a_noisy_render_closer_to_the_converged_one_or_says_oidn_is_absent() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("cornell_box.ron");
    let scene = scene.to_str().unwrap();
    let out = dir.path().join("denoised.exr");
    let out = out.to_str().unwrap();

    // Absent for sure: a warning naming where it looked and what to run,
    // exit 0, and the image as rendered (no noisy layer).
    let nowhere = dir.path().join("no-oidn-here");
    let o = rt_view_with_oidn(&render_args(scene, out, "4", &["--denoise"]), Some(&nowhere));
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(err.contains("warning: not denoised: OIDN not found (looked in "), "{err}");
    assert!(err.contains(&nowhere.display().to_string()) && err.contains("run scripts/get_oidn.sh"), "{err}");
    let plain = dir.path().join("plain.exr");
    let o = rt_view(&render_args(scene, plain.to_str().unwrap(), "4", &[]), "");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(out).unwrap(), std::fs::read(&plain).unwrap(), "the image as rendered");

    // As this machine has it: present or not, the run says which.
    let o = rt_view_with_oidn(&render_args(scene, out, "4", &["--denoise"]), None);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    if err.contains("OIDN not found") {
        eprintln!("OIDN is not installed here; checked the message: {err}");
        return;
    }
    assert!(err.contains("denoised with OIDN in "), "{err}");
    let reference = dir.path().join("reference.exr");
    let o = rt_view(&render_args(scene, reference.to_str().unwrap(), "256", &[]), "");
    assert!(o.status.success(), "{}", stderr(&o));
    let (image, reference) = (exr_channels(Path::new(out)), exr_channels(&reference));
    let (noisy, denoised) = (rmse(&image, "noisy.", &reference), rmse(&image, "", &reference));
    eprintln!("RMSE against 256 spp: noisy {noisy:.4}, denoised {denoised:.4}");
    assert!(denoised < noisy * 0.7, "noisy {noisy}, denoised {denoised}");
    // The noisy layer is the plain render, bit for bit.
    assert_eq!(image["noisy.R"], exr_channels(&plain)["R"]);
    assert_eq!(rmse(&image, "noisy.", &exr_channels(&plain)), 0.0);
}

#[test]
fn passes_are_layers_of_the_exr_beside_the_unchanged_colour() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scenes_dir().join("cornell_box.ron");
    let scene = scene.to_str().unwrap();
    let (plain, layered) = (dir.path().join("plain.exr"), dir.path().join("layered.exr"));
    let o = rt_view(&render_args(scene, plain.to_str().unwrap(), "2", &[]), "");
    assert!(o.status.success(), "{}", stderr(&o));
    let o = rt_view(
        &render_args(scene, layered.to_str().unwrap(), "2", &["--passes", "depth,albedo,id,normal"]),
        "",
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let (plain, layered) = (exr_channels(&plain), exr_channels(&layered));
    let names: Vec<&str> = layered.keys().map(String::as_str).collect();
    assert_eq!(names, ["B", "G", "N.X", "N.Y", "N.Z", "R", "Z", "albedo.B", "albedo.G", "albedo.R", "id"]);
    for c in ["R", "G", "B"] {
        assert_eq!(layered[c], plain[c], "channel {c}");
    }
    // Depths from the camera at z = −8 to the back wall, ids among the
    // scene's 8 objects, where a pixel sees the box at all (the edges look
    // past its open front: infinite depth, id −1).
    for (&z, &id) in layered["Z"].iter().zip(&layered["id"]) {
        assert!((7.0..17.0).contains(&z) || z == f32::INFINITY, "depth {z}");
        let seen =
            if z == f32::INFINITY { id == -1.0 } else { (0.0..8.0).contains(&id) && id.fract() == 0.0 };
        assert!(seen, "id {id} at depth {z}");
    }
    let red_wall = layered["id"].iter().filter(|&&i| i == 3.0).count();
    assert!(red_wall > 40, "{red_wall} pixels see the red wall");
    let centre = 32 * 64 + 32;
    assert!((layered["albedo.R"][centre] - 0.73).abs() < 1e-6, "{}", layered["albedo.R"][centre]);
    let n = |i: usize| [layered["N.X"][i], layered["N.Y"][i], layered["N.Z"][i]];
    assert!(n(centre)[2] < -0.99, "the back wall faces the camera: {:?}", n(centre));

    // --aovs is every pass; a PNG output refuses passes before rendering.
    let all = dir.path().join("all.exr");
    let o = rt_view(&render_args(scene, all.to_str().unwrap(), "2", &["--aovs"]), "");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(exr_channels(&all), layered);
    let png = dir.path().join("x.png");
    let o = rt_view(&render_args(scene, png.to_str().unwrap(), "2", &["--aovs"]), "");
    assert!(!o.status.success() && stderr(&o).contains("written to an .exr output only"), "{}", stderr(&o));
    assert!(!png.exists());
}
