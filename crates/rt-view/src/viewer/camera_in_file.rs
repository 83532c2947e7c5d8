//! The camera written back into its scene file, and as RON text.
//!
//! Saving edits only the values inside the file's `camera: ( … )` block:
//! a value whose number is unchanged keeps its text (`4` stays `4`, not
//! `4.0`), and every comment, blank and line of the rest of the file stays
//! byte for byte. The block is found by a small RON scanner that knows
//! comments (`//`, nested `/* */`), strings and nested brackets, so a `)`
//! in a comment or a string never ends the block. Numbers are written with
//! Rust's shortest round-trip formatting, so the file loads back to exactly
//! the same camera. The file is replaced atomically (temporary file, then
//! rename); an edit that does not read back to the camera is refused and
//! the file left as it was.

use std::fmt;
use std::ops::Range;
use std::path::Path;

use rt_core::{Projection, Real, Vec3};

use super::camera_controls::CameraSettings;
use crate::image_out::PendingFile;

/// Why the camera could not be read from or written into a scene file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraFileError(String);

impl fmt::Display for CameraFileError {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(&self.0)
    }
}

fn error(message: impl Into<String>) -> CameraFileError {
    CameraFileError(message.into())
}

/// The camera's fields in the order they are written.
const FIELDS: [&str; 8] =
    ["position", "center_of_interest", "up", "fov_y", "near", "projection", "aperture", "focus_distance"];

/// The fields of a camera taken from a glTF file, `(gltf: FILE, index: N,
/// scale: S, translate: T)`, which a saved camera replaces.
const GLTF_FIELDS: [&str; 4] = ["gltf", "index", "scale", "translate"];

/// `camera` as the scene file's `camera: ( … )` entry, on one line.
pub fn camera_ron(camera: &CameraSettings) -> String {
    format!("camera: ({}),", field_list(camera))
}

/// `camera`'s fields as RON, `position: …, …`, those that can be left out
/// ([`implied`]) only when they differ from what leaving them out means.
fn field_list(camera: &CameraSettings) -> String {
    let fields: Vec<String> = FIELDS
        .iter()
        .filter(|&&name| !implied(camera, name))
        .map(|&name| format!("{name}: {}", value_text(camera, name)))
        .collect();
    fields.join(", ")
}

/// Writes `camera` into the scene file at `path` (see the module's
/// documentation). Returns whether the file changed: a camera equal to the
/// file's is not written at all.
pub fn save_camera(path: &Path, camera: &CameraSettings) -> Result<bool, CameraFileError> {
    let shown = path.display();
    if crate::scene_cache::is_cache(path) {
        return Err(error(format!(
            "{shown} is a scene cache (made by `rt-view prepare`), which holds no camera text to edit: save the \
             camera in the scene file the cache was made from, then run `rt-view prepare` on it again"
        )));
    }
    let text = std::fs::read_to_string(path).map_err(|e| error(format!("{shown}: cannot read: {e}")))?;
    let edited = with_camera(&text, camera).map_err(|e| error(format!("{shown}: {e}")))?;
    if edited == text {
        return Ok(false);
    }
    PendingFile::create(path)
        .and_then(|file| file.write_bytes(edited.as_bytes()))
        .map_err(|e| error(format!("{e:#}")))?;
    Ok(true)
}

/// `text` (a scene file) with its camera block's values set to `camera`;
/// `text` itself if the camera is the same.
pub fn with_camera(text: &str, camera: &CameraSettings) -> Result<String, CameraFileError> {
    let block = CameraBlock::find(text)?;
    let mut edits: Vec<(Range<usize>, String)> = Vec::new();
    // A camera taken from a glTF file is saved as the camera it now is:
    // its fields give way to the camera's own, all of them.
    let from_gltf = block.fields.iter().any(|f| GLTF_FIELDS.contains(&f.name.as_str()));
    if from_gltf && let (Some(first), Some(last)) = (block.fields.first(), block.fields.last()) {
        edits.push((first.start..last.value.end, field_list(camera)));
    }
    for name in FIELDS.iter().copied().filter(|_| !from_gltf) {
        let wanted = value_text(camera, name);
        match block.fields.iter().find(|f| f.name == name) {
            Some(field) => {
                if !same_value(&text[field.value.clone()], &wanted) {
                    edits.push((field.value.clone(), wanted));
                }
            }
            None if implied(camera, name) => {}
            None => edits.push(block.insertion(text, name, &wanted)),
        }
    }
    let mut edited = text.to_owned();
    edits.sort_by_key(|(range, _)| std::cmp::Reverse(range.start));
    for (range, replacement) in edits {
        edited.replace_range(range, &replacement);
    }
    match read_camera(&edited) {
        Ok(read) if read == *camera => Ok(edited),
        Ok(_) => Err(error("the edited camera block does not read back to the camera; file left as it was")),
        Err(e) => {
            Err(error(format!("the edited camera block does not read back ({e}); file left as it was")))
        }
    }
}

/// The camera written in `text`'s camera block (the fields the scene file
/// requires, `projection` perspective when absent). It is not checked for
/// degeneracy: the scene loader does that.
pub fn read_camera(text: &str) -> Result<CameraSettings, CameraFileError> {
    let block = CameraBlock::find(text)?;
    let value = |name: &str| {
        block
            .fields
            .iter()
            .find(|f| f.name == name)
            .map(|f| &text[f.value.clone()])
            .ok_or_else(|| error(format!("the camera block has no `{name}`")))
    };
    let vector = |name: &str| {
        let v = value(name)?;
        parse_vector(v).ok_or_else(|| error(format!("camera `{name}` is not a vector of three numbers: {v}")))
    };
    let number = |name: &str| {
        let v = value(name)?;
        parse_number(v).ok_or_else(|| error(format!("camera `{name}` is not a number: {v}")))
    };
    let projection = match value("projection") {
        Err(_) => Projection::Perspective,
        Ok(v) => parse_projection(v).ok_or_else(|| error(format!("camera `projection` is unknown: {v}")))?,
    };
    let optional = |name: &str| if value(name).is_ok() { number(name).map(Some) } else { Ok(None) };
    let mut camera = CameraSettings {
        position: vector("position")?,
        center_of_interest: vector("center_of_interest")?,
        up: vector("up")?,
        fov_y: number("fov_y")?,
        near: number("near")?,
        projection,
        aperture: optional("aperture")?.unwrap_or(0.0),
        focus_distance: 0.0,
    };
    camera.focus_distance = optional("focus_distance")?.unwrap_or_else(|| implied_focus_distance(&camera));
    Ok(camera)
}

/// The focus distance a camera block without `focus_distance` has, as the
/// scene loader reads it: the distance to the centre of interest with a
/// lens, 1 for the pinhole.
fn implied_focus_distance(camera: &CameraSettings) -> Real {
    if camera.aperture > 0.0 { (camera.center_of_interest - camera.position).length() } else { 1.0 }
}

/// Whether field `name` of `camera` is what a block without it means, so
/// that it need not be written: a perspective projection, no aperture, the
/// implied focus distance.
fn implied(camera: &CameraSettings, name: &str) -> bool {
    match name {
        "projection" => camera.projection == Projection::Perspective,
        "aperture" => camera.aperture == 0.0,
        "focus_distance" => camera.focus_distance == implied_focus_distance(camera),
        _ => false,
    }
}

/// The text a field of `camera` is written as.
fn value_text(camera: &CameraSettings, name: &str) -> String {
    match name {
        "position" => vector_text(camera.position),
        "center_of_interest" => vector_text(camera.center_of_interest),
        "up" => vector_text(camera.up),
        "fov_y" => number_text(camera.fov_y),
        "near" => number_text(camera.near),
        "aperture" => number_text(camera.aperture),
        "focus_distance" => number_text(camera.focus_distance),
        _ => format!("{:?}", camera.projection),
    }
}

/// The shortest text that reads back as `x`; `0` for ±0.
fn number_text(x: Real) -> String {
    if x == 0.0 { "0".to_owned() } else { format!("{x}") }
}

fn vector_text(v: Vec3) -> String {
    format!("({}, {}, {})", number_text(v.x), number_text(v.y), number_text(v.z))
}

/// Whether the written value `old` means the same as `new` (both as a
/// number, a vector or a name), so that its text can stay.
fn same_value(old: &str, new: &str) -> bool {
    if let (Some(a), Some(b)) = (parse_number(old), parse_number(new)) {
        return a == b;
    }
    if let (Some(a), Some(b)) = (parse_vector(old), parse_vector(new)) {
        return a == b;
    }
    old.trim() == new.trim()
}

fn parse_number(text: &str) -> Option<Real> {
    let t = text.trim();
    let t = t.strip_prefix('+').unwrap_or(t);
    t.replace('_', "").parse::<Real>().ok().filter(|x| x.is_finite())
}

/// `(x, y, z)`, comments and a trailing comma allowed.
fn parse_vector(text: &str) -> Option<Vec3> {
    let tokens = tokens(text).ok()?;
    let words: Vec<&Token> = tokens.iter().filter(|t| t.kind == Kind::Word).collect();
    let shape_ok = tokens.first()?.kind == Kind::Open(b'(')
        && tokens.last()?.kind == Kind::Close(b')')
        && tokens.iter().filter(|t| matches!(t.kind, Kind::Open(_) | Kind::Close(_))).count() == 2
        && words.len() == 3;
    if !shape_ok {
        return None;
    }
    let n = |i: usize| parse_number(&text[words[i].span.clone()]);
    Some(Vec3::new(n(0)?, n(1)?, n(2)?))
}

fn parse_projection(text: &str) -> Option<Projection> {
    match text.trim() {
        "Perspective" => Some(Projection::Perspective),
        "Orthographic" => Some(Projection::Orthographic),
        _ => None,
    }
}

/// What the scanner sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Open(u8),
    Close(u8),
    Colon,
    Comma,
    /// A name, a number or another bare value.
    Word,
    /// A string or character literal.
    Str,
}

#[derive(Clone, Debug)]
struct Token {
    kind: Kind,
    span: Range<usize>,
}

/// The tokens of RON `text`, comments and whitespace skipped.
fn tokens(text: &str) -> Result<Vec<Token>, CameraFileError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let line_of = |at: usize| text[..at].matches('\n').count() + 1;
    while i < b.len() {
        let start = i;
        let kind = match b[i] {
            c if c.is_ascii_whitespace() => {
                i += 1;
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                i = text[i..].find('\n').map_or(b.len(), |n| i + n + 1);
                continue;
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                let mut depth = 0;
                loop {
                    if i + 1 >= b.len() {
                        return Err(error(format!("line {}: a /* comment is never closed", line_of(start))));
                    }
                    match (b[i], b[i + 1]) {
                        (b'/', b'*') => (depth, i) = (depth + 1, i + 2),
                        (b'*', b'/') => (depth, i) = (depth - 1, i + 2),
                        _ => i += 1,
                    }
                    if depth == 0 {
                        break;
                    }
                }
                continue;
            }
            c @ (b'(' | b'[' | b'{') => {
                i += 1;
                Kind::Open(c)
            }
            c @ (b')' | b']' | b'}') => {
                i += 1;
                Kind::Close(c)
            }
            b':' => {
                i += 1;
                Kind::Colon
            }
            b',' => {
                i += 1;
                Kind::Comma
            }
            q @ (b'"' | b'\'') => {
                i += 1;
                while i < b.len() && b[i] != q {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                if i >= b.len() {
                    return Err(error(format!("line {}: a string is never closed", line_of(start))));
                }
                i += 1;
                Kind::Str
            }
            b'r' if matches!(b.get(i + 1), Some(b'"' | b'#')) => {
                // A raw string: r"…", r#"…"#, …
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                if b.get(i + 1 + hashes) != Some(&b'"') {
                    return Err(error(format!("line {}: cannot read this raw string", line_of(start))));
                }
                let close = format!("\"{}", "#".repeat(hashes));
                let body = i + 2 + hashes;
                let end = text[body..]
                    .find(&close)
                    .ok_or_else(|| error(format!("line {}: a raw string is never closed", line_of(start))))?;
                i = body + end + close.len();
                Kind::Str
            }
            _ => {
                // The first byte is a word's (every other kind was matched above).
                i += 1;
                while !word_ends(b, i) {
                    i += 1;
                }
                Kind::Word
            }
        };
        out.push(Token { kind, span: start..i });
    }
    Ok(out)
}

/// Whether a bare word (a name or a number) ends before byte `i`: at the
/// end, whitespace, punctuation, a string or a comment.
fn word_ends(b: &[u8], i: usize) -> bool {
    let Some(&c) = b.get(i) else { return true };
    c.is_ascii_whitespace()
        || matches!(c, b'(' | b')' | b'[' | b']' | b'{' | b'}' | b':' | b',' | b'"')
        || (c == b'/' && matches!(b.get(i + 1), Some(b'/' | b'*')))
}

/// One `name: value` of the camera block.
#[derive(Debug)]
struct Field {
    name: String,
    /// Where the name starts.
    start: usize,
    /// The value's text, from its first token to its last.
    value: Range<usize>,
    /// The end of the comma after the value, if there is one.
    comma_end: Option<usize>,
}

/// The `camera: ( … )` block of a scene file.
#[derive(Debug)]
struct CameraBlock {
    /// Just after its `(`.
    inner_start: usize,
    fields: Vec<Field>,
}

impl CameraBlock {
    /// The camera block at the top level of the scene in `text`.
    fn find(text: &str) -> Result<Self, CameraFileError> {
        let tokens = tokens(text)?;
        let mut depth = 0usize;
        let mut open = None;
        for (i, t) in tokens.iter().enumerate() {
            match t.kind {
                Kind::Open(_) => depth += 1,
                Kind::Close(_) => depth = depth.saturating_sub(1),
                Kind::Word if depth == 1 && &text[t.span.clone()] == "camera" => {
                    if let (Some(colon), Some(paren)) = (tokens.get(i + 1), tokens.get(i + 2))
                        && colon.kind == Kind::Colon
                        && paren.kind == Kind::Open(b'(')
                    {
                        if open.is_some() {
                            return Err(error("the scene has two `camera` blocks"));
                        }
                        open = Some(i + 2);
                    }
                }
                _ => {}
            }
        }
        let open = open.ok_or_else(|| error("the scene file has no `camera: ( … )` block"))?;
        // The fields, up to the matching `)`.
        let mut fields = Vec::new();
        let mut i = open + 1;
        loop {
            let t = tokens.get(i).ok_or_else(|| error("the camera block is never closed"))?;
            if t.kind == Kind::Close(b')') {
                break;
            }
            let (Some(colon), Kind::Word) = (tokens.get(i + 1), t.kind) else {
                return Err(error(format!("cannot read the camera block at `{}`", &text[t.span.clone()])));
            };
            if colon.kind != Kind::Colon {
                return Err(error(format!("cannot read the camera block at `{}`", &text[t.span.clone()])));
            }
            let name = text[t.span.clone()].to_owned();
            if fields.iter().any(|f: &Field| f.name == name) {
                return Err(error(format!("the camera block has `{name}` twice")));
            }
            // The value: tokens up to a `,` or `)` outside brackets.
            let first = i + 2;
            let mut j = first;
            let mut nested = 0usize;
            loop {
                let t = tokens.get(j).ok_or_else(|| error("the camera block is never closed"))?;
                match t.kind {
                    Kind::Open(_) => nested += 1,
                    Kind::Close(_) if nested == 0 => break,
                    Kind::Close(_) => nested -= 1,
                    Kind::Comma if nested == 0 => break,
                    _ => {}
                }
                j += 1;
            }
            if j == first {
                return Err(error(format!("the camera's `{name}` has no value")));
            }
            let value = tokens[first].span.start..tokens[j - 1].span.end;
            let comma_end = (tokens[j].kind == Kind::Comma).then(|| tokens[j].span.end);
            fields.push(Field { name, start: t.span.start, value, comma_end });
            i = if comma_end.is_some() { j + 1 } else { j };
        }
        Ok(Self { inner_start: tokens[open].span.end, fields })
    }

    /// Where and how to add the field `name: value` that the block lacks:
    /// after its last field, on a line of its own if the fields have lines
    /// of their own.
    fn insertion(&self, text: &str, name: &str, value: &str) -> (Range<usize>, String) {
        let Some(last) = self.fields.last() else {
            return (self.inner_start..self.inner_start, format!("{name}: {value}"));
        };
        let line_start = text[..last.start].rfind('\n').map_or(0, |n| n + 1);
        let before = &text[line_start..last.start];
        let own_line = before.trim().is_empty();
        let separator = if own_line { format!("\n{before}") } else { " ".to_owned() };
        match last.comma_end {
            Some(at) => (at..at, format!("{separator}{name}: {value},")),
            None => (last.value.end..last.value.end, format!(",{separator}{name}: {value}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;

    use super::*;

    fn scenes() -> Vec<PathBuf> {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "ron"))
            .collect();
        files.sort();
        assert!(files.len() > 10, "{files:?}");
        files
    }

    /// The scenes whose camera block gives the camera's numbers (not a
    /// glTF file's camera, which saving replaces by numbers on purpose).
    fn scenes_with_own_camera() -> Vec<PathBuf> {
        let own = |p: &PathBuf| {
            let text = std::fs::read_to_string(p).unwrap();
            let block = CameraBlock::find(&text).unwrap();
            !block.fields.iter().any(|f| GLTF_FIELDS.contains(&f.name.as_str()))
        };
        let files: Vec<PathBuf> = scenes().into_iter().filter(own).collect();
        assert!(files.len() > 10, "{files:?}");
        files
    }

    fn file_camera(path: &Path) -> CameraSettings {
        CameraSettings::from_camera(&rt_core::load_scene(path).unwrap().camera)
    }

    #[test]
    fn every_scene_saved_with_its_own_camera_is_unchanged_to_the_byte() {
        for path in scenes_with_own_camera() {
            let text = std::fs::read_to_string(&path).unwrap();
            let camera = file_camera(&path);
            assert_eq!(read_camera(&text).unwrap(), camera, "{}", path.display());
            assert_eq!(with_camera(&text, &camera).unwrap(), text, "{}", path.display());
        }
    }

    #[test]
    fn every_scene_saved_with_another_camera_loads_to_that_camera_and_keeps_the_rest() {
        for path in scenes() {
            let text = std::fs::read_to_string(&path).unwrap();
            let original = file_camera(&path);
            let moved = original
                .orbit(0.37, 0.11)
                .zoom(0.813)
                .with_projection(Projection::Orthographic)
                .pan(0.1, -0.3);
            let edited = with_camera(&text, &moved).unwrap();
            let dir = path.parent().unwrap();
            let loaded = rt_core::parse_scene(&edited, &path.display().to_string(), dir)
                .unwrap_or_else(|e| panic!("{}: {e}\n{edited}", path.display()));
            assert_eq!(CameraSettings::from_camera(&loaded.camera), moved, "{}", path.display());
            // Outside the camera block, not a byte changed.
            let (a, b) = (CameraBlock::find(&text).unwrap(), CameraBlock::find(&edited).unwrap());
            assert_eq!(text[..a.inner_start], edited[..b.inner_start], "{}", path.display());
            let tail = |t: &str| t[matching_close(t, t.find("camera:").unwrap())..].to_owned();
            assert_eq!(tail(&text), tail(&edited), "{}", path.display());
            // And back again: the file's own camera.
            let back = with_camera(&edited, &original).unwrap();
            assert_eq!(read_camera(&back).unwrap(), original);
        }
    }

    /// The index of the `)` closing the block that starts after `from`.
    fn matching_close(text: &str, from: usize) -> usize {
        let tokens = tokens(&text[from..]).unwrap();
        let mut depth = 0;
        for t in tokens {
            match t.kind {
                Kind::Open(_) => depth += 1,
                Kind::Close(_) => {
                    depth -= 1;
                    if depth == 0 {
                        return from + t.span.start;
                    }
                }
                _ => {}
            }
        }
        panic!("unclosed")
    }

    fn settings(projection: Projection) -> CameraSettings {
        CameraSettings {
            position: Vec3::new(1.5, -2.0, -7.25),
            center_of_interest: Vec3::new(0.0, 0.5, 0.0),
            up: Vec3::Y,
            fov_y: 33.5,
            near: 0.5,
            projection,
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }

    #[test]
    fn comments_strings_and_brackets_inside_and_around_the_block_are_kept() {
        let text = r#"// a ) in a comment
Scene(
    name: "camera: (not this)",
    /* camera: ( nor /* nested */ this ) */
    camera: (
        position: (0, 0, -5), // eye ) here
        center_of_interest: (0, /* ( */ 0, 0),
        up: (0, 1, 0),
        fov_y: 40, /* , */
        near: 1
    ),
    objects: [],
)
"#;
        let camera = settings(Projection::Orthographic);
        let edited = with_camera(text, &camera).unwrap();
        assert_eq!(
            edited,
            r#"// a ) in a comment
Scene(
    name: "camera: (not this)",
    /* camera: ( nor /* nested */ this ) */
    camera: (
        position: (1.5, -2, -7.25), // eye ) here
        center_of_interest: (0, 0.5, 0),
        up: (0, 1, 0),
        fov_y: 33.5, /* , */
        near: 0.5,
        projection: Orthographic
    ),
    objects: [],
)
"#
        );
        assert_eq!(read_camera(&edited).unwrap(), camera);
    }

    #[test]
    fn a_lens_set_in_the_viewer_is_written_and_one_as_the_file_means_is_left_out() {
        let text = "Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1), image: (width: 8, height: 6), materials: {}, objects: [])";
        let pinhole = read_camera(text).unwrap();
        assert_eq!((pinhole.aperture, pinhole.focus_distance), (0.0, 1.0), "no lens fields: the pinhole");
        // A lens focused at the centre of interest is what `aperture` alone means.
        let at_coi = CameraSettings { aperture: 0.25, focus_distance: 5.0, ..pinhole };
        let edited = with_camera(text, &at_coi).unwrap();
        assert!(edited.contains("near: 1, aperture: 0.25), image"), "{edited}");
        let focused = CameraSettings { focus_distance: 3.5, ..at_coi };
        let edited = with_camera(&edited, &focused).unwrap();
        assert!(edited.contains("aperture: 0.25, focus_distance: 3.5)"), "{edited}");
        let loaded = rt_core::parse_scene(&edited, "t.ron", Path::new(".")).unwrap().camera;
        assert_eq!(CameraSettings::from_camera(&loaded), focused);
        assert_eq!(with_camera(&edited, &focused).unwrap(), edited, "unchanged: not a byte moves");
    }

    #[test]
    fn a_one_line_block_gets_a_missing_field_on_the_same_line() {
        let text = "Scene(camera: (position: (0, 0, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 40, near: 1), objects: [])";
        let edited = with_camera(text, &settings(Projection::Orthographic)).unwrap();
        assert!(edited.contains("near: 0.5, projection: Orthographic), objects: [])"), "{edited}");
    }

    #[test]
    fn a_camera_taken_from_a_gltf_file_is_saved_as_the_camera_it_now_is() {
        let text =
            "(\n    camera: (gltf: \"m.glb\", index: 1, scale: 2),\n    image: (width: 8, height: 6),\n)";
        let camera = CameraSettings {
            position: Vec3::new(0.0, 1.0, -5.0),
            center_of_interest: Vec3::ZERO,
            up: Vec3::Y,
            fov_y: 30.0,
            near: 0.5,
            projection: Projection::Perspective,
            aperture: 0.0,
            focus_distance: 1.0,
        };
        let edited = with_camera(text, &camera).unwrap();
        assert_eq!(
            edited,
            "(\n    camera: (position: (0, 1, -5), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 30, near: 0.5),\n    image: (width: 8, height: 6),\n)"
        );
    }

    #[test]
    fn a_file_without_a_camera_block_or_that_cannot_be_read_is_refused() {
        let camera = settings(Projection::Perspective);
        for (text, why) in [
            ("Scene(objects: [])", "no `camera"),
            ("Scene(camera: (position: (0, 0, -5), up: (0, 1, 0)", "never closed"),
            ("Scene(camera: (position: (0, 0, -5), position: (1, 0, 0)))", "twice"),
            ("Scene(camera: (position: \"x), objects: [])", "never closed"),
            ("Scene(camera: (position: (0, 0, -5)), /* open", "never closed"),
        ] {
            let e = with_camera(text, &camera).unwrap_err().to_string();
            assert!(e.contains(why), "{text}: {e}");
        }
    }

    #[test]
    fn saving_writes_the_file_atomically_and_only_when_the_camera_changed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.ron");
        let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/sphere.ron");
        let text = std::fs::read_to_string(&source).unwrap();
        std::fs::write(&path, &text).unwrap();
        let camera = file_camera(&path);
        assert_eq!(save_camera(&path, &camera), Ok(false));
        let moved = camera.orbit(0.5, 0.2);
        assert_eq!(save_camera(&path, &moved), Ok(true));
        assert_eq!(file_camera(&path), moved);
        let saved = std::fs::read_to_string(&path).unwrap();
        assert!(saved.contains("// C, world units (left-handed: +z into the screen)"), "{saved}");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(names, ["scene.ron"], "no temporary file is left");
        let missing = dir.path().join("nope.ron");
        assert!(save_camera(&missing, &moved).unwrap_err().to_string().contains("nope.ron"));
    }

    #[test]
    fn saving_into_a_scene_cache_is_refused_naming_what_to_do_and_leaves_it_alone() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("scene.rtc");
        let mut bytes = crate::scene_cache::format::MAGIC.to_vec();
        bytes.extend([0xff, 0xfe, 0, 1, 2, 3]);
        std::fs::write(&path, &bytes).unwrap();
        let e = save_camera(&path, &settings(Projection::Perspective)).unwrap_err().to_string();
        assert!(e.contains("scene.rtc is a scene cache") && e.contains("rt-view prepare"), "{e}");
        assert_eq!(std::fs::read(&path).unwrap(), bytes, "the cache is untouched");
    }

    #[test]
    fn copied_ron_reads_as_a_camera_block() {
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let camera = settings(projection);
            let text = format!("Scene({})", camera_ron(&camera));
            assert_eq!(read_camera(&text).unwrap(), camera, "{text}");
        }
        assert_eq!(
            camera_ron(&settings(Projection::Perspective)),
            "camera: (position: (1.5, -2, -7.25), center_of_interest: (0, 0.5, 0), up: (0, 1, 0), fov_y: 33.5, near: 0.5),"
        );
    }
}
