//! A trace of what the real window does, for the tests that drive it under
//! Xvfb (`tests/viewer_window.rs`) and for looking into a slow frame.
//!
//! With `RT_VIEW_TRACE=FILE` set, the viewer appends JSON lines to FILE: one
//! per render job that streamed into the window, and one per frame. Unset,
//! there is no trace: nothing is measured or written.
//!
//! A job line, written at the end of the first frame the job is current in
//! (a job cancelled within the frame it started in never shows a row, and
//! has no line):
//!
//! ```json
//! {"t":1.204,"job":7,"view":3,"kind":"preview","size":[320,180]}
//! ```
//!
//! - `job`: its generation (the number its rows carry);
//! - `view`: what it shows, as a number that grows by one whenever the
//!   camera, the effect toggles or the scene itself (a reload too) differ
//!   from the previous job's — a preview and the full render after it are
//!   one view;
//! - `kind`: `preview` or `full`; `size`: its image in pixels.
//!
//! A frame line:
//!
//! ```json
//! {"t":1.220,"frame":42,"update_ms":1.9,"interval_ms":16.5,"scene":"/abs/a.ron",
//!  "loading":false,"zoom":87.5,"canvas":7,"texture":[[7,180],[5,540]],"scene_view":null}
//! ```
//!
//! - `t`: seconds since the viewer started, at the frame's start;
//!   `update_ms`: how long the viewer's own update took; `interval_ms`:
//!   since the previous frame's start (`null` for the first);
//! - `scene`: the scene file shown (`null`: the built-in scene);
//!   `loading`: whether another scene is being loaded;
//! - `zoom`: the image's size on screen in percent (screen pixels per image
//!   pixel × 100), measured on the image as drawn this frame (`null` if
//!   none was);
//! - `canvas`: the generation of the image on screen; `texture`: which
//!   job's pixels each row of its texture shows after this frame's uploads,
//!   top to bottom, as runs `[generation, rows]` — the canvas's own
//!   generation, an older one's carried over from the image it replaced, or
//!   0 for rows no job has drawn (black). Every row applied in a frame is
//!   uploaded in that frame, so this is the texture the frame shows;
//! - `scene_view`: with the scene view open, how many flat renders of it
//!   have started so far (`null` while it is closed).

use std::fs::{File, OpenOptions};
use std::hash::{DefaultHasher, Hash, Hasher};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::{LayerId, TextureId};
use serde_json::json;

use super::canvas::Canvas;
use super::render_job::RenderJob;

/// The environment variable naming the trace file.
pub const TRACE_VAR: &str = "RT_VIEW_TRACE";

/// The trace file and what the next lines are measured against.
pub(super) struct Trace {
    file: File,
    path: PathBuf,
    start: Instant,
    previous_frame: Option<Instant>,
    frames: u64,
    /// The generation of the last job written.
    last_job: Option<u64>,
    /// What the last job written showed ([`view_key`]), and its view number.
    last_view: Option<(u64, u64)>,
}

/// What a frame shows, for its trace line.
pub(super) struct Frame<'a> {
    /// The scene file shown (`None`: the built-in scene).
    pub scene: Option<&'a Path>,
    /// Whether a scene is being loaded.
    pub loading: bool,
    /// The image's size on screen in percent ([`drawn_zoom`]).
    pub zoom: Option<f32>,
    /// The image on screen.
    pub canvas: Option<&'a Canvas>,
    /// With the scene view open, how many flat renders it has started
    /// (`None`: closed).
    pub scene_view: Option<u64>,
}

impl Trace {
    /// The trace `RT_VIEW_TRACE` names, if set; a file that cannot be opened
    /// is a warning, and no trace.
    pub fn from_env() -> Option<Self> {
        let path = PathBuf::from(std::env::var_os(TRACE_VAR)?);
        match OpenOptions::new().create(true).append(true).open(&path) {
            Ok(file) => Some(Self {
                file,
                path,
                start: Instant::now(),
                previous_frame: None,
                frames: 0,
                last_job: None,
                last_view: None,
            }),
            Err(e) => {
                eprintln!("warning: {}: cannot write the trace: {e}", path.display());
                None
            }
        }
    }

    /// Writes `job`'s line if it is not the job written last.
    pub fn job(&mut self, job: &RenderJob, preview: bool) -> std::io::Result<()> {
        if self.last_job == Some(job.generation()) {
            return Ok(());
        }
        self.last_job = Some(job.generation());
        let spec = job.spec();
        let key = view_key(job);
        let view = match self.last_view {
            Some((k, view)) if k == key => view,
            Some((_, view)) => view + 1,
            None => 1,
        };
        self.last_view = Some((key, view));
        let line = json!({
            "t": self.start.elapsed().as_secs_f64(),
            "job": job.generation(),
            "view": view,
            "kind": if preview { "preview" } else { "full" },
            "size": [spec.width, spec.height],
        });
        self.write(&line)
    }

    /// Writes the line of the frame that began at `began`, whose update
    /// took `update`, and shows `frame`.
    pub fn frame(&mut self, began: Instant, update: Duration, frame: Frame<'_>) -> std::io::Result<()> {
        let interval = self.previous_frame.map(|p| (began - p).as_secs_f64() * 1e3);
        self.previous_frame = Some(began);
        self.frames += 1;
        let line = json!({
            "t": (began - self.start).as_secs_f64(),
            "frame": self.frames,
            "update_ms": update.as_secs_f64() * 1e3,
            "interval_ms": interval,
            "scene": frame.scene.map(|p| p.display().to_string()),
            "loading": frame.loading,
            "zoom": frame.zoom,
            "canvas": frame.canvas.map(Canvas::generation),
            "texture": frame.canvas.map(|c| runs(c.display_sources())),
            "scene_view": frame.scene_view,
        });
        self.write(&line)
    }

    /// Appends `line`, in one write so a reader never sees half of it.
    fn write(&mut self, line: &serde_json::Value) -> std::io::Result<()> {
        let text = format!("{line}\n");
        self.file.write_all(text.as_bytes()).map_err(|e| std::io::Error::new(e.kind(), self.describe(e)))
    }

    fn describe(&self, e: std::io::Error) -> String {
        format!("{}: cannot write the trace: {e}", self.path.display())
    }
}

/// What `job` shows, as a number: its camera, effect toggles and scene (the
/// scene by identity, so a reload is another view).
fn view_key(job: &RenderJob) -> u64 {
    let spec = job.spec();
    let mut hasher = DefaultHasher::new();
    format!("{:?} {:?}", spec.camera, spec.toggles).hash(&mut hasher);
    Arc::as_ptr(&spec.scene).hash(&mut hasher);
    hasher.finish()
}

/// `sources` as runs of equal values: `[value, count]`, in order.
fn runs(sources: &[u64]) -> Vec<[u64; 2]> {
    let mut runs: Vec<[u64; 2]> = Vec::new();
    for &s in sources {
        match runs.last_mut() {
            Some([value, count]) if *value == s => *count += 1,
            _ => runs.push([s, 1]),
        }
    }
    runs
}

/// The zoom of the image drawn with `texture` on `layer` this frame, in
/// percent: its width on screen in physical pixels per pixel of the
/// `image_width` image, × 100 (`None` if it was not drawn).
pub(super) fn drawn_zoom(
    ctx: &egui::Context,
    layer: LayerId,
    texture: TextureId,
    image_width: u32,
) -> Option<f32> {
    let width = ctx.graphics(|g| {
        g.get(layer)?
            .all_entries()
            .find(|s| s.shape.texture_id() == texture)
            .map(|s| s.shape.visual_bounding_rect().width())
    })?;
    Some(width * ctx.pixels_per_point() / image_width.max(1) as f32 * 100.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_rows_are_written_as_runs_of_one_generation() {
        assert_eq!(runs(&[]), Vec::<[u64; 2]>::new());
        assert_eq!(runs(&[3, 3, 2, 2, 2, 0, 3]), [[3, 2], [2, 3], [0, 1], [3, 1]]);
    }
}
