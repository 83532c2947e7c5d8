//! Broken copies of real material files: MTL files with the PBR extension's
//! fields (`scenes/material_params/ball.mtl`) and the classic ones
//! (`scenes/models/vase.mtl`), and scene files whose materials use textures
//! with their options (`scenes/material_params/*.ron`, `scenes/materials.ron`,
//! `scenes/models.ron`). Each mutant has one to four changes — a flipped
//! byte, a cut-off end, two tokens swapped, a number or file name replaced
//! by a hostile one (NaN, infinities, negatives, huge values, a missing, a
//! non-image or a radiance file), a line dropped or repeated, and for
//! scene files a texture option added (wrap, filter, mip-maps, texture
//! coordinate set, transform). Every mutant must load or be refused with a
//! message naming the file (and, for an MTL value, the material), never
//! panic; what loads must hold consistent values, and a few samples of its
//! image are rendered through the new material paths.
//!
//! More mutants by hand: `RT_MATERIAL_MUTANTS=20000 cargo test -p rt-view --test material_file_mutations`.

mod common;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use common::scenes_dir;
use rt_core::{Color, LoadedScene, Material, RayCounts, Renderer, load_scene};

/// SplitMix64 (Steele, Lea & Flood 2014): the mutants' choices, the same
/// for the same seed.
struct Choices(u64);

impl Choices {
    fn below(&mut self, n: usize) -> usize {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) % n.max(1) as u64) as usize
    }

    fn pick<'a>(&mut self, from: &[&'a str]) -> &'a str {
        from[self.below(from.len())]
    }
}

/// How many mutants each test tries (`RT_MATERIAL_MUTANTS`, else `default`).
fn runs(default: u64) -> u64 {
    std::env::var("RT_MATERIAL_MUTANTS").ok().and_then(|n| n.parse().ok()).unwrap_or(default)
}

/// Numbers a mutant may put where a number was.
const NUMBERS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0",
    "1",
    "2",
    "1e39",
    "3.4e38",
    "-3.4e38",
    "1e-45",
    "0.5",
    "99999999999",
    "4294967295",
    "-2147483648",
    "1.5e",
    "--1",
    "0x10",
    "",
];

/// File names a mutant may put where a file name was: missing, not an
/// image, a radiance image, a folder, outside, empty.
const FILES: &[&str] = &[
    "missing.png",
    "ball.mtl",
    "../studio.hdr",
    "studio.hdr",
    ".",
    "..",
    "/",
    "../../../../../../etc/passwd",
    "checker.png",
    "bumps_normal.png",
    "stripes_alpha.png",
    "",
];

/// The file's tokens: runs of letters, digits and `._-+/` (numbers,
/// names, file names), quoted strings, and single other characters, as
/// byte ranges.
fn tokens(text: &str) -> Vec<(usize, usize)> {
    let b = text.as_bytes();
    let word = |c: u8| c.is_ascii_alphanumeric() || b"._-+/".contains(&c);
    let (mut out, mut i) = (Vec::new(), 0);
    while i < b.len() {
        let start = i;
        if b[i] == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += 1;
            }
            i = (i + 1).min(b.len());
        } else if word(b[i]) {
            while i < b.len() && word(b[i]) {
                i += 1;
            }
        } else if b[i].is_ascii_whitespace() {
            i += 1;
            continue;
        } else {
            i += 1;
            while !text.is_char_boundary(i) {
                i += 1;
            }
        }
        out.push((start, i));
    }
    out
}

/// `text` with `range` replaced by `with`.
fn splice(text: &str, (a, b): (usize, usize), with: &str) -> String {
    format!("{}{}{}", &text[..a], with, &text[b..])
}

/// Texture options a scene-file mutant may add after a texture's `file`.
const TEXTURE_OPTIONS: &[&str] = &[
    ", wrap: ClampToEdge",
    ", wrap: MirroredRepeat",
    ", wrap: Bounce",
    ", filter: Nearest",
    ", filter: Cubic",
    ", mipmaps: false",
    ", mipmaps: 0",
    ", tex_coord: 1",
    ", tex_coord: 2",
    ", tex_coord: 4294967295",
    ", scale: (1e30, 1e30)",
    ", scale: (0, 0)",
    ", scale: (NaN, 1)",
    ", scale: (-1, 1e-30)",
    ", offset: (inf, 0)",
    ", offset: (1e20, -1e20)",
    ", rotation: 1e30",
    ", rotation: NaN",
    ", scale: 2",
    ", file: \"checker.png\"",
];

/// One change to `text`; `ron` adds the scene-file-only changes.
fn mutate_once(text: &str, ron: bool, c: &mut Choices) -> String {
    let toks = tokens(text);
    if toks.is_empty() {
        return text.to_owned();
    }
    let t = toks[c.below(toks.len())];
    match c.below(if ron { 8 } else { 7 }) {
        // A byte flipped (kept as text where the flip breaks UTF-8: the
        // lossy form of what a reader would see).
        0 => {
            let mut bytes = text.as_bytes().to_vec();
            let at = c.below(bytes.len());
            bytes[at] ^= 1 << c.below(8);
            String::from_utf8_lossy(&bytes).into_owned()
        }
        // The end cut off.
        1 => {
            let mut at = c.below(text.len());
            while !text.is_char_boundary(at) {
                at -= 1;
            }
            text[..at].to_owned()
        }
        // Two tokens swapped.
        2 => {
            let u = toks[c.below(toks.len())];
            let (first, second) = if t.0 <= u.0 { (t, u) } else { (u, t) };
            if first.1 > second.0 {
                return text.to_owned();
            }
            format!(
                "{}{}{}{}{}",
                &text[..first.0],
                &text[second.0..second.1],
                &text[first.1..second.0],
                &text[first.0..first.1],
                &text[second.1..]
            )
        }
        // A number made hostile.
        3 | 4 => {
            let numbers: Vec<_> =
                toks.iter().filter(|&&(a, b)| text[a..b].parse::<f64>().is_ok()).copied().collect();
            match numbers.len() {
                0 => text.to_owned(),
                n => splice(text, numbers[c.below(n)], c.pick(NUMBERS)),
            }
        }
        // A file name replaced.
        5 => {
            let files: Vec<_> = toks
                .iter()
                .filter(|&&(a, b)| {
                    let s = text[a..b].trim_matches('"');
                    s.ends_with(".png") || s.ends_with(".obj") || s.ends_with(".hdr") || s.ends_with(".glb")
                })
                .copied()
                .collect();
            match files.len() {
                0 => text.to_owned(),
                n => {
                    let at = files[c.below(n)];
                    let file = c.pick(FILES);
                    let quoted = text[at.0..at.1].starts_with('"');
                    splice(text, at, &if quoted { format!("\"{file}\"") } else { file.to_owned() })
                }
            }
        }
        // A line dropped or repeated.
        6 => {
            let lines: Vec<&str> = text.lines().collect();
            let k = c.below(lines.len());
            let mut out: Vec<&str> = lines[..k].to_vec();
            if c.below(2) == 0 {
                out.push(lines[k]);
                out.push(lines[k]);
            }
            out.extend_from_slice(&lines[k + 1..]);
            out.join("\n") + "\n"
        }
        // A texture option added after a texture's file.
        _ => {
            let files: Vec<usize> = text.match_indices("(file: \"").map(|(i, _)| i).collect();
            if files.is_empty() {
                // A plain `slot: "name.png"` becomes a table with an option.
                let png: Vec<_> =
                    toks.iter().filter(|&&(a, b)| text[a..b].ends_with(".png\"")).copied().collect();
                return match png.len() {
                    0 => text.to_owned(),
                    n => {
                        let at = png[c.below(n)];
                        let with = format!("(file: {}{})", &text[at.0..at.1], c.pick(TEXTURE_OPTIONS));
                        splice(text, at, &with)
                    }
                };
            }
            let start = files[c.below(files.len())] + "(file: \"".len();
            let end = start + text[start..].find('"').unwrap_or(0) + 1;
            splice(text, (end, end), c.pick(TEXTURE_OPTIONS))
        }
    }
}

/// `text` with one to four changes.
fn mutant(text: &str, ron: bool, c: &mut Choices) -> String {
    let mut out = text.to_owned();
    for _ in 0..1 + c.below(4) {
        out = mutate_once(&out, ron, c);
    }
    out
}

/// What a loaded material must hold whatever its file said: finite,
/// in-range values and texture slots that point at textures.
fn check_material(m: &Material, textures: usize, what: &str) {
    let colour = |c: Color, name: &str| {
        assert!(c.is_finite() && c.min_element() >= 0.0, "{what}: {name} {c:?}");
    };
    colour(m.color, "color");
    colour(m.emission, "emission");
    colour(m.specular_color, "specular_color");
    for (name, x) in [
        ("diffuse", m.diffuse),
        ("specular", m.specular),
        ("reflectivity", m.reflectivity),
        ("transparency", m.transparency),
        ("alpha", m.alpha),
    ] {
        assert!((0.0..=1.0).contains(&x), "{what}: {name} {x}");
    }
    assert!(m.ior > 0.0 && m.ior <= 100.0, "{what}: ior {}", m.ior);
    assert!(m.shininess.is_finite() && m.shininess >= 0.0, "{what}: shininess {}", m.shininess);
    if let Some(p) = &m.physical {
        for (name, x) in [
            ("metallic", p.metallic),
            ("roughness", p.roughness),
            ("transmission", p.transmission),
            ("clearcoat", p.clearcoat),
            ("clearcoat_roughness", p.clearcoat_roughness),
            ("specular", p.specular),
        ] {
            assert!((0.0..=1.0).contains(&x), "{what}: {name} {x}");
        }
        colour(p.attenuation_color, "attenuation_color");
        colour(p.specular_color, "specular_color_factor");
        assert!(!p.attenuation_distance.is_nan(), "{what}: attenuation_distance");
    }
    for (name, slot) in [
        ("base_color_texture", m.base_color_texture),
        ("metallic_roughness_texture", m.metallic_roughness_texture),
        ("emissive_texture", m.emissive_texture),
        ("occlusion_texture", m.occlusion_texture),
        ("normal_texture", m.normal_texture),
    ] {
        if let Some(slot) = slot {
            assert!((slot.texture as usize) < textures, "{what}: {name} texture {}", slot.texture);
            assert!(slot.scale.is_finite(), "{what}: {name} scale {}", slot.scale);
        }
    }
}

/// Checks a loaded mutant and renders a few samples of it (one path each,
/// at a 4 × 3 grid of pixels): the new material paths — texture reads with
/// the mutant's options, normal maps, alpha, the PBR lobes — run on what
/// the file said. Returns how many samples were not finite.
fn check_and_sample(loaded: &LoadedScene, what: &str) -> usize {
    let scene = &loaded.scene;
    let textures = scene.texture_stats().0;
    for (m, name) in scene.materials().iter().zip(scene.material_names()) {
        check_material(m, textures, &format!("{what}: material {name}"));
    }
    let renderer = Renderer::new(scene, loaded.camera, &loaded.settings).expect("the loaded scene renders");
    let (w, h) = (loaded.settings.image.width(), loaded.settings.image.height());
    let mut counts = RayCounts::default();
    let mut bad = 0;
    for j in 0..3 {
        for i in 0..4 {
            let c = renderer.sample((2 * i + 1) * w / 8, (2 * j + 1) * h / 6, 0, &mut counts);
            bad += usize::from(!c.is_finite());
        }
    }
    bad
}

/// Loads `scene` (which reads the mutated file), with no panic allowed:
/// `Ok(bad samples)` or the error's message.
fn load_and_sample(scene: &Path, what: &str, text: &str) -> Result<usize, String> {
    let result = catch_unwind(AssertUnwindSafe(|| match load_scene(scene) {
        Ok(loaded) => Ok(check_and_sample(&loaded, what)),
        Err(e) => Err(e.to_string()),
    }));
    match result {
        Ok(r) => r,
        Err(_) => panic!("{what} panicked; the mutated file:\n{text}"),
    }
}

/// Copies every file of `scenes/material_params/` (the ball, its MTL, its
/// textures) and `scenes/studio.hdr` into a new folder laid out the same way.
fn material_params_copy() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let params = dir.path().join("material_params");
    std::fs::create_dir(&params).unwrap();
    for entry in std::fs::read_dir(scenes_dir().join("material_params")).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, params.join(path.file_name().unwrap())).unwrap();
    }
    std::fs::copy(scenes_dir().join("studio.hdr"), dir.path().join("studio.hdr")).unwrap();
    dir
}

/// A small scene in `dir` that shows the model `model` (relative to
/// `dir`) with its own materials, under a light and a sky colour.
fn scene_showing(dir: &Path, model: &str, scale: f32) -> std::path::PathBuf {
    let path = dir.join("show.ron");
    std::fs::write(
        &path,
        format!(
            "Scene(camera: (position: (0, 0.5, -3), center_of_interest: (0, 0.3, 0), up: (0, 1, 0), fov_y: 40, near: 1),
             image: (width: 64, height: 48), background: (0.5, 0.6, 0.7),
             materials: {{}},
             objects: [Mesh(file: \"{model}\", scale: {scale})],
             lights: [Point(position: (-2, 4, -4), intensity: 60)],
             effects: (global_illumination: (max_bounces: 6)))"
        ),
    )
    .unwrap();
    path
}

#[test]
fn the_real_material_files_load_and_render_before_any_mutation() {
    // The baseline the mutants are made from: every file loads as shipped,
    // the ball's MTL as a physically based material with all its maps.
    let dir = material_params_copy();
    let show = scene_showing(&dir.path().join("material_params"), "ball.obj", 1.0);
    let loaded = load_scene(&show).unwrap();
    let (names, materials) = (loaded.scene.material_names(), loaded.scene.materials());
    let tiles = names.iter().position(|n| n.ends_with(":tiles")).expect("the ball's material");
    let m = &materials[tiles];
    assert!(m.physical.is_some() && m.base_color_texture.is_some() && m.metallic_roughness_texture.is_some());
    assert!(m.normal_texture.is_some() && m.emissive_texture.is_some(), "{m:?}");
    assert_eq!(check_and_sample(&loaded, "ball.mtl"), 0);
    for scene in ["materials.ron", "models.ron"] {
        let loaded = load_scene(&scenes_dir().join(scene)).unwrap();
        assert_eq!(check_and_sample(&loaded, scene), 0, "{scene}");
    }
    for entry in std::fs::read_dir(scenes_dir().join("material_params")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "ron") {
            let loaded = load_scene(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(check_and_sample(&loaded, &path.display().to_string()), 0, "{}", path.display());
        }
    }
}

/// Mutants of the MTL file `mtl` (in `dir`, read by `obj`): each loads or
/// is refused naming the OBJ file and a material. Returns (loaded, refused).
fn mtl_mutants(dir: &Path, obj: &str, mtl: &str, seeds: std::ops::Range<u64>) -> (u64, u64) {
    let original = std::fs::read_to_string(dir.join(mtl)).unwrap();
    let show = scene_showing(dir, obj, 1.0);
    let (mut loaded, mut refused, mut bad_samples) = (0, 0, 0);
    for seed in seeds {
        let text = mutant(&original, false, &mut Choices(seed));
        std::fs::write(dir.join(mtl), &text).unwrap();
        match load_and_sample(&show, &format!("{mtl} mutant {seed}"), &text) {
            Ok(bad) => {
                loaded += 1;
                bad_samples += bad;
            }
            Err(e) => {
                refused += 1;
                assert!(
                    e.contains(obj) && e.contains("material \""),
                    "{mtl} mutant {seed}: the error names neither file nor material: {e}\n{text}"
                );
                if std::env::var("RT_MATERIAL_SHOW").is_ok() {
                    eprintln!("{seed}: {e}");
                }
            }
        }
    }
    std::fs::write(dir.join(mtl), original).unwrap();
    assert_eq!(bad_samples, 0, "{mtl}: samples that are not finite");
    (loaded, refused)
}

#[test]
fn mutated_pbr_mtl_files_load_or_are_refused_naming_file_material_and_field() {
    let dir = material_params_copy();
    let params = dir.path().join("material_params");
    let n = runs(600);
    let (loaded, refused) = mtl_mutants(&params, "ball.obj", "ball.mtl", 0..n);
    // Most damage is local: a bad value is refused, most other mutants load
    // (unknown statements become warnings, unreadable maps fall back).
    assert!(loaded > n / 4 && refused > n / 20, "{loaded} loaded, {refused} refused");
}

#[test]
fn mutated_classic_mtl_files_load_or_are_refused_naming_file_material_and_field() {
    let dir = tempfile::tempdir().unwrap();
    for file in ["vase.obj", "vase.mtl", "tiles.png"] {
        std::fs::copy(scenes_dir().join("models").join(file), dir.path().join(file)).unwrap();
    }
    let n = runs(600) / 2;
    let (loaded, refused) = mtl_mutants(dir.path(), "vase.obj", "vase.mtl", 0..n);
    assert!(loaded > n / 4 && refused > n / 20, "{loaded} loaded, {refused} refused");
}

#[test]
fn mutated_scene_files_with_texture_options_load_or_are_refused_naming_the_file() {
    let dir = material_params_copy();
    let models = dir.path().join("models");
    std::fs::create_dir(&models).unwrap();
    for entry in std::fs::read_dir(scenes_dir().join("models")).unwrap() {
        let path = entry.unwrap().path();
        std::fs::copy(&path, models.join(path.file_name().unwrap())).unwrap();
    }
    // Each scene sits where it sits in scenes/, so its relative paths hold.
    let scenes = [
        ("material_params/texture_scale.ron", scenes_dir().join("material_params/texture_scale.ron")),
        ("material_params/normal_scale.ron", scenes_dir().join("material_params/normal_scale.ron")),
        ("material_params/alpha_cutoff.ron", scenes_dir().join("material_params/alpha_cutoff.ron")),
        ("materials.ron", scenes_dir().join("materials.ron")),
        ("models.ron", scenes_dir().join("models.ron")),
    ];
    let (mut loaded, mut refused) = (0u64, 0u64);
    let mut bad_samples = Vec::new();
    let n = runs(600);
    for seed in 0..n {
        let (name, original) = &scenes[seed as usize % scenes.len()];
        let original = std::fs::read_to_string(original).unwrap();
        let path = dir.path().join(name);
        let text = mutant(&original, true, &mut Choices(seed));
        std::fs::write(&path, &text).unwrap();
        match load_and_sample(&path, &format!("{name} mutant {seed}"), &text) {
            Ok(0) => loaded += 1,
            Ok(_) => bad_samples.push(seed),
            Err(e) => {
                refused += 1;
                let file = path.display().to_string();
                assert!(
                    e.starts_with(&file),
                    "{name} mutant {seed}: the error does not name the file: {e}\n{text}"
                );
                if std::env::var("RT_MATERIAL_SHOW").is_ok() {
                    eprintln!("{seed}: {e}");
                }
            }
        }
        std::fs::write(&path, original).unwrap();
    }
    assert!(bad_samples.is_empty(), "mutants with samples that are not finite: {bad_samples:?}");
    // RON is strict: most damage is a syntax error; what survives loads.
    assert!(loaded > n / 20 && refused > n / 2, "{loaded} loaded, {refused} refused");
}
