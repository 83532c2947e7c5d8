//! `rt-view --screenshot OUT.png SCENE`: once the full-resolution frame is
//! complete and on screen, save the window's pixels and close it.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::Context as _;

use crate::image_out::PendingImage;

/// Screenshot mode gives up after this long.
const SCREENSHOT_TIMEOUT: Duration = Duration::from_secs(120);

/// How the window's run ended, for [`super::run`] to report: `None` while
/// running, or when closed by the user.
pub(super) type Outcome = Arc<Mutex<Option<Result<(), String>>>>;

/// Screenshot mode's progress.
pub(super) enum Screenshot {
    /// Waiting for a complete full-resolution frame; counts frames drawn since.
    Waiting { path: PathBuf, frames_since_complete: u32, started: Instant },
    /// Asked egui for the pixels; the callback finishes the job.
    Requested,
}

impl Screenshot {
    /// Waiting to save the window to `path`.
    pub fn new(path: PathBuf) -> Self {
        Self::Waiting { path, frames_since_complete: 0, started: Instant::now() }
    }

    /// One frame of screenshot mode: once the frame is `complete` and has
    /// been drawn twice more, asks for the window's pixels, saves them and
    /// closes the window, recording the result in `outcome`.
    pub fn step(&mut self, ctx: &egui::Context, complete: bool, outcome: &Outcome) {
        let Self::Waiting { path, frames_since_complete, started } = self else { return };
        if started.elapsed() > SCREENSHOT_TIMEOUT {
            *outcome.lock().unwrap() = Some(Err("screenshot: the frame did not complete in time".into()));
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            return;
        }
        if !complete {
            ctx.request_repaint_after(Duration::from_millis(20));
            return;
        }
        *frames_since_complete += 1;
        if *frames_since_complete < 3 {
            ctx.request_repaint();
            return;
        }
        let path = path.clone();
        let outcome = outcome.clone();
        let close = ctx.clone();
        ctx.request_screenshot(move |image| {
            let result = save_screenshot(&path, &image).map_err(|e| format!("{e:#}"));
            *outcome.lock().unwrap() = Some(result);
            close.send_viewport_cmd(egui::ViewportCommand::Close);
            close.request_repaint();
        });
        *self = Self::Requested;
    }
}

/// Writes a window screenshot as an RGB PNG, atomically.
fn save_screenshot(path: &Path, image: &egui::ColorImage) -> anyhow::Result<()> {
    let [width, height] = image.size;
    let pixels: Vec<_> = image.pixels.iter().map(|c| [c.r(), c.g(), c.b()]).collect();
    PendingImage::png(path)?.write_rgb8(width as u32, height as u32, &pixels).context("screenshot")
}
