//! The progressive viewer: `rt-view [SCENE]`.
//!
//! The window is composed of parts that each own their state and draw their
//! own piece of the UI, in the spirit of egui's demo app (`app::Viewer`
//! composes them):
//!
//! - `scene_source`: the scene file (or the built-in scene), opening another
//!   (path field, `file_browser`, drop, recent files), Reload, watching
//!   its files ([`scene_watch`]) and load errors;
//! - `camera_panel`: the camera controls, on top of the pure camera
//!   functions of [`camera_controls`]; fly navigation (`fly`), undo and
//!   redo (`camera_history`), the camera saved into its scene file or
//!   copied as RON (`camera_in_file`);
//! - `image_settings`: resolution scale, samples per pixel, effect toggles;
//! - `scheduler`: which render job runs (preview while dragging, full
//!   resolution once still), and the image it streams into: each job
//!   ([`render_job`]) renders rows in the background and sends them to a
//!   [`canvas`], from where they reach an egui texture;
//! - `display_panel`: exposure, the channel and false colour views
//!   ([`display`]), the [`histogram`], and the [`reference`](mod@reference) image with
//!   the comparison views and their metrics (`error_metrics`);
//! - `image_view`: the image on screen (fit, 1:1, zoom), orbit, pan and
//!   zoom with the mouse, and pixel inspection;
//! - `scene_view`: beside the image, the scene seen by an `observer`
//!   camera (rt-core's flat render, `observer_render`, on a thread of its
//!   own), the render camera, view plane, frustum and lights drawn over it
//!   (`camera_overlay`) through the observer's `projection`, and the
//!   pinned pixel's path (`path_overlay`) from the record of one of its
//!   samples (`record_job`); [`scene_view_image`] makes the
//!   same picture without a window, painted on the CPU (`soft_paint`);
//! - `screenshot`: `--screenshot`, saving the window once the frame is done;
//! - `trace`: with `RT_VIEW_TRACE=FILE`, a line per frame and per job of
//!   what the window did and shows, for the tests that drive it;
//! - `remembered`: what the viewer remembers between runs (recent files,
//!   the panel, the resolution scale, the last scene and its camera), one
//!   value saved through eframe's storage beside the window's size and place.
//!
//! Rows flow one way: scene → job spec → render job (worker threads) →
//! rows over a channel → canvas (UI thread) → texture. The UI thread never
//! waits for a worker.

mod app;
pub mod camera_controls;
mod camera_history;
mod camera_in_file;
mod camera_overlay;
mod camera_panel;
pub mod canvas;
pub mod display;
mod display_panel;
mod error_metrics;
pub mod eta;
mod file_browser;
mod fly;
pub mod histogram;
mod image_settings;
mod image_view;
mod interaction;
mod material_panel;
mod observer;
mod observer_render;
mod path_overlay;
mod projection;
mod record_job;
pub mod reference;
pub mod region;
mod remembered;
pub mod render_job;
mod scene_source;
mod scene_view;
pub mod scene_view_image;
pub mod scene_watch;
mod scheduler;
mod screenshot;
mod soft_paint;
mod trace;

use std::sync::{Arc, Mutex};

use anyhow::anyhow;

use app::Opening;
pub use app::{SHORTCUTS, ViewerOptions};
use remembered::Remembered;
pub use scene_source::{DEFAULT_SCENE, DEFAULT_SCENE_NAME, load};

use crate::image_out::PendingImage;

/// Opens the window and runs until it is closed.
pub fn run(options: ViewerOptions) -> anyhow::Result<()> {
    // A scene named on the command line that cannot be read is an error
    // there; later reloads show their errors in the window instead.
    let named = match &options.scene {
        Some(path) => Some((path.clone(), load(Some(path))?)),
        None => None,
    };
    if let Some(out) = &options.screenshot {
        // Check the output path now, not after the window has run.
        drop(PendingImage::png(out)?);
    }
    let outcome = Arc::new(Mutex::new(None));
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1180.0, 720.0])
            .with_min_inner_size([640.0, 400.0])
            .with_title("rt-view"),
        // The window comes back where it was, as large as it was: eframe's
        // own entry in the file that holds `remembered::Remembered`.
        persist_window: true,
        // The RON file itself (eframe 0.37 opens this path as its file).
        persistence_path: remembered::storage_override(),
        ..Default::default()
    };
    let app_outcome = outcome.clone();
    eframe::run_native(
        "rt-view",
        native,
        Box::new(move |cc| {
            let remembered = Remembered::load(cc.storage);
            let opening = Opening::choose(named, remembered.last_scene.as_ref())?;
            let screenshot = options.screenshot;
            Ok(Box::new(app::Viewer::new(&cc.egui_ctx, opening, screenshot, remembered, app_outcome)))
        }),
    )
    .map_err(|e| anyhow!("cannot open the viewer window: {}", without_source_location(&e.to_string())))?;
    let result = outcome.lock().unwrap().take();
    result.unwrap_or(Ok(())).map_err(|e: String| anyhow!(e))
}

/// `message` without the source locations windowing errors carry (winit
/// prints "os error at /…/winit-…/src/….rs:765: reason"): " at PATH.rs:LINE"
/// is dropped, the reason kept.
fn without_source_location(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    while let Some(i) = rest.find(" at ") {
        let after = &rest[i + 4..];
        let location = after.find(".rs:").and_then(|end| {
            let tail = &after[end + 4..];
            let digits = tail.chars().take_while(char::is_ascii_digit).count();
            (digits > 0 && !after[..end].contains(' ')).then_some(&tail[digits..])
        });
        match location {
            Some(tail) => {
                out.push_str(&rest[..i]);
                rest = tail;
            }
            None => {
                out.push_str(&rest[..i + 4]);
                rest = after;
            }
        }
    }
    out + rest
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn windowing_errors_lose_their_source_location_and_keep_their_reason() {
        let winit = "winit EventLoopError: os error at /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/\
                     winit-0.30.13/src/platform_impl/linux/mod.rs:765: neither WAYLAND_DISPLAY nor DISPLAY is set.";
        assert_eq!(
            without_source_location(winit),
            "winit EventLoopError: os error: neither WAYLAND_DISPLAY nor DISPLAY is set."
        );
        assert_eq!(without_source_location("look at this: fine"), "look at this: fine");
    }
}
