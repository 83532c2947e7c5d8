//! The examples in the README and the docs are true: their scene files load,
//! and the `cast` session they show prints what they say.

mod common;

use std::path::{Path, PathBuf};

use common::{rt_view, scenes_dir, stderr, stdout};

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The fenced blocks of `language` in the Markdown file `page`.
fn blocks(page: &str, language: &str) -> Vec<String> {
    let text = std::fs::read_to_string(root().join(page)).unwrap();
    let mut out = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match &mut current {
            None if line.trim_start() == format!("```{language}") => current = Some(String::new()),
            Some(block) if line.trim_start() == "```" => {
                out.push(std::mem::take(block));
                current = None;
            }
            Some(block) => {
                block.push_str(line);
                block.push('\n');
            }
            None => {}
        }
    }
    out
}

#[test]
fn every_whole_scene_example_in_the_docs_loads() {
    let mut checked = 0;
    for page in ["README.md", "docs/scene-format.md"] {
        for block in blocks(page, "ron") {
            // Fragments (with "…" for what is left out) are not whole scenes.
            if block.contains('…') {
                continue;
            }
            // Mesh paths in the examples are relative to scenes/.
            let scene = rt_core::parse_scene(&block, page, &scenes_dir());
            assert!(scene.is_ok(), "{page}: {}\n{block}", scene.unwrap_err());
            checked += 1;
        }
    }
    assert!(checked >= 2, "only {checked} examples found");
}

#[test]
fn the_cast_session_in_the_docs_is_what_cast_prints() {
    let block =
        blocks("docs/command-line.md", "sh").into_iter().find(|b| b.contains("rt-view cast")).unwrap();
    let mut lines = block.lines();
    let command = lines.next().unwrap();
    let expected: String = lines.map(|l| format!("{l}\n")).collect();
    // `$ printf 'RAYS' | rt-view cast scenes/NAME.ron`
    let rays = command.split('\'').nth(1).unwrap().replace("\\n", "\n");
    let scene = command.rsplit(' ').next().unwrap();
    let o = rt_view(&["cast", root().join(scene).to_str().unwrap()], &rays);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o), expected);
}

#[test]
fn the_model_objects_in_the_models_page_load() {
    let block = blocks("docs/models.md", "ron").into_iter().next().expect("a ron block");
    let mut checked = 0;
    for line in block.lines().filter(|l| l.trim_start().starts_with("Mesh(")) {
        let object = line.split("//").next().unwrap().trim().trim_end_matches(',');
        let scene = format!(
            "Scene(camera: (position: (0, 1, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1), \
             image: (width: 8, height: 6), materials: {{ \"clay\": (color: (0.7, 0.5, 0.4)) }}, objects: [ {object} ])"
        );
        let loaded = rt_core::parse_scene(&scene, "docs/models.md", &scenes_dir());
        assert!(loaded.is_ok(), "{object}: {}", loaded.unwrap_err());
        checked += 1;
    }
    assert_eq!(checked, 3);
}
