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
//! {"t":1.204,"job":7,"view":3,"kind":"preview","size":[320,180],
//!  "camera":{"position":[0,1,-5],"center_of_interest":[0,1,0],"up":[0,1,0],"fov_y":40}}
//! ```
//!
//! - `job`: its generation (the number its rows carry);
//! - `view`: what it shows, as a number that grows by one whenever the
//!   camera, the effect toggles or the scene itself (a reload too) differ
//!   from the previous job's — a preview and the full render after it are
//!   one view;
//! - `kind`: `preview` or `full`; `size`: its image in pixels;
//! - `camera`: its eye, centre of interest, up vector and vertical field of
//!   view (degrees), so that a measurement can render the same view.
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
//! - `samples`: the fewest and the most samples per pixel of the rows of
//!   the image on screen (`null` without one);
//! - `scene_view`: with the scene view open, how many flat renders of it
//!   have started so far (`null` while it is closed).
//! - `image`: with `RT_VIEW_TRACE_IMAGES=DIR` also set, the file the
//!   image on screen was written to in this frame, once every row of it has
//!   arrived at the same samples and whenever a row changed since: its linear colours as
//!   little-endian `f32` RGB triples, rows top to bottom, in
//!   `DIR/frame-N-WxH.f32` (`null` when nothing was written). It is
//!   written on the UI thread, so it is for measurements (bench/viewer_timing.py
//!   finds how long a camera move takes to a clean image), never on by
//!   default.

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

/// The environment variable naming the folder complete images on screen are
/// written to, with a trace.
pub const TRACE_IMAGES_VAR: &str = "RT_VIEW_TRACE_IMAGES";

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
    /// Where complete images go (`RT_VIEW_TRACE_IMAGES`), if anywhere.
    images: Option<PathBuf>,
    /// The canvas (generation, changes) written last.
    last_image: Option<(u64, u64)>,
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
                images: std::env::var_os(TRACE_IMAGES_VAR).map(PathBuf::from),
                last_image: None,
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
            "camera": {
                "position": spec.camera.position().to_array(),
                "center_of_interest": spec.camera.center_of_interest().to_array(),
                "up": spec.camera.up().to_array(),
                "fov_y": spec.camera.fov_y(),
            },
        });
        self.write(&line)
    }

    /// Writes the line of the frame that began at `began`, whose update
    /// took `update`, and shows `frame`.
    pub fn frame(&mut self, began: Instant, update: Duration, frame: Frame<'_>) -> std::io::Result<()> {
        let interval = self.previous_frame.map(|p| (began - p).as_secs_f64() * 1e3);
        self.previous_frame = Some(began);
        self.frames += 1;
        let samples = frame.canvas.map(|c| {
            let counts = (0..c.size()[1] as u32).map(|y| c.row_samples(y));
            counts.fold([u32::MAX, 0], |[lo, hi], n| [lo.min(n), hi.max(n)])
        });
        let image = match (frame.canvas, samples) {
            (Some(c), Some([lo, hi])) if lo == hi => self.write_image(c)?,
            _ => None,
        };
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
            "samples": samples,
            "image": image.map(|p| p.display().to_string()),
        });
        self.write(&line)
    }

    /// Writes `canvas`'s linear image into the images folder if there is
    /// one, every row has arrived, and it changed since the last written;
    /// returns the file written. (Called only when every row has the same
    /// samples: a pass half streamed in is not an image anyone measures.)
    fn write_image(&mut self, canvas: &Canvas) -> std::io::Result<Option<PathBuf>> {
        let Some(dir) = &self.images else { return Ok(None) };
        let key = (canvas.generation(), canvas.changes());
        if !canvas.is_complete() || self.last_image == Some(key) {
            return Ok(None);
        }
        self.last_image = Some(key);
        let [width, height] = canvas.size();
        let path = dir.join(format!("frame-{}-{width}x{height}.f32", self.frames));
        let bytes: Vec<u8> = canvas.linear().iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        std::fs::write(&path, bytes).map_err(|e| {
            std::io::Error::new(e.kind(), format!("{}: cannot write the image: {e}", path.display()))
        })?;
        Ok(Some(path))
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

    fn row(y: u32, samples: u32, value: f32) -> super::super::render_job::Row {
        let pixels = vec![egui::Color32::GRAY; 2];
        super::super::render_job::Row {
            generation: 1,
            y,
            samples,
            pixels,
            linear: vec![[value, 0.5, 2.0]; 2],
        }
    }

    #[test]
    fn a_frame_gives_the_samples_on_screen_and_writes_the_image_once_whole_at_one_count_and_changed() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("trace.jsonl");
        let mut trace = Trace {
            file: File::create(&path).unwrap(),
            path: path.clone(),
            start: Instant::now(),
            previous_frame: None,
            frames: 0,
            last_job: None,
            last_view: None,
            images: Some(dir.path().to_owned()),
            last_image: None,
        };
        let mut canvas = Canvas::new(1, 2, 2, 16);
        let frame = |trace: &mut Trace, canvas: &Canvas| {
            let frame =
                Frame { scene: None, loading: false, zoom: None, canvas: Some(canvas), scene_view: None };
            trace.frame(Instant::now(), Duration::ZERO, frame).unwrap();
        };
        assert!(canvas.apply(&row(0, 4, 0.25)));
        frame(&mut trace, &canvas); // half the rows: no image
        assert!(canvas.apply(&row(1, 4, 0.75)));
        frame(&mut trace, &canvas); // whole at 4: written
        frame(&mut trace, &canvas); // unchanged: not again
        assert!(canvas.apply(&row(0, 8, 0.5)));
        frame(&mut trace, &canvas); // rows at 8 and 4: not an image
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<serde_json::Value> = text.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        let samples: Vec<_> = lines.iter().map(|l| l["samples"].clone()).collect();
        assert_eq!(samples, [json!([0, 4]), json!([4, 4]), json!([4, 4]), json!([4, 8])]);
        let images: Vec<_> = lines.iter().map(|l| l["image"].as_str().map(str::to_owned)).collect();
        let written = dir.path().join("frame-2-2x2.f32");
        assert_eq!(images, [None, Some(written.display().to_string()), None, None]);
        let bytes = std::fs::read(&written).unwrap();
        let values: Vec<f32> =
            bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect();
        let expected: Vec<f32> = [0.25, 0.25, 0.75, 0.75].iter().flat_map(|&v| [v, 0.5, 2.0]).collect();
        assert_eq!(values, expected);
    }
}
