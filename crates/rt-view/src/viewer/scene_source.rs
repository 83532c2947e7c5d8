//! Where the viewer's scene comes from: a file (or the built-in scene), Open
//! and Reload, a watcher that reloads the file when an editor saves it, and
//! the error of the last load that failed.
//!
//! A failed load never replaces the scene: the last good one (and its image)
//! stays, and the error is shown until a load succeeds.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use egui::Color32;
use rt_core::Scene;

use super::scene_watch::SceneWatcher;

/// The built-in default scene's text (`scenes/default.ron`).
pub const DEFAULT_SCENE: &str = include_str!("../../../../scenes/default.ron");
/// The name the built-in scene goes by in messages.
pub const DEFAULT_SCENE_NAME: &str = "<built-in default scene>";

/// Loads the scene (the built-in one for `None`).
pub fn load(path: Option<&Path>) -> Result<Scene, rt_core::SceneError> {
    match path {
        Some(p) => rt_core::load_scene(p),
        None => rt_core::parse_scene(DEFAULT_SCENE, DEFAULT_SCENE_NAME, Path::new(".")),
    }
}

/// A file event is acted on after this much quiet (editors write in bursts).
const RELOAD_DEBOUNCE: Duration = Duration::from_millis(100);

/// A new scene is in place: what it replaced, and whether it came from
/// another file (Open) rather than the same one again (Reload, a save).
#[derive(Clone, Debug)]
pub(super) struct SceneChange {
    /// The scene shown before.
    pub previous: Arc<Scene>,
    /// Another file was opened: the view starts from its camera and settings.
    pub opened: bool,
}

/// The scene, where it came from, and its watcher.
pub(super) struct SceneSource {
    path: Option<PathBuf>,
    scene: Arc<Scene>,
    watcher: Option<SceneWatcher>,
    reload_at: Option<Instant>,
    /// The text of the Open field.
    open_path: String,
    /// Why the last load failed; cleared by the next one that succeeds.
    error: Option<String>,
    /// Why the file is not watched, if it is not.
    watch_problem: Option<String>,
}

impl SceneSource {
    /// The source of `scene`, loaded from `path` (`None`: the built-in scene),
    /// watched from now on; `ctx` is repainted when the file changes.
    pub fn new(path: Option<PathBuf>, scene: Scene, ctx: &egui::Context) -> Self {
        let mut source = Self {
            open_path: path.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
            path,
            scene: Arc::new(scene),
            watcher: None,
            reload_at: None,
            error: None,
            watch_problem: None,
        };
        source.watch(ctx);
        source
    }

    /// The scene shown.
    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// Why the last load failed, if it did.
    #[cfg(test)]
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// Acts on file events: once the file has been quiet for
    /// [`RELOAD_DEBOUNCE`] after a change, reloads it.
    pub fn poll(&mut self, ctx: &egui::Context) -> Option<SceneChange> {
        if self.watcher.as_ref().is_some_and(SceneWatcher::changed) {
            self.reload_at = Some(Instant::now() + RELOAD_DEBOUNCE);
        }
        let at = self.reload_at?;
        let now = Instant::now();
        if now < at {
            ctx.request_repaint_after(at - now);
            return None;
        }
        self.reload_at = None;
        self.reload()
    }

    /// Loads the scene file again; on error the scene stays and the error is kept.
    pub fn reload(&mut self) -> Option<SceneChange> {
        match load(self.path.as_deref()) {
            Ok(scene) => Some(self.replace(scene, false)),
            Err(e) => {
                self.error = Some(e.to_string());
                None
            }
        }
    }

    /// Opens the scene file at `path` and watches it instead of the current one;
    /// on error nothing changes but the error shown.
    pub fn open(&mut self, path: PathBuf, ctx: &egui::Context) -> Option<SceneChange> {
        match load(Some(&path)) {
            Ok(scene) => {
                self.path = Some(path);
                let change = self.replace(scene, true);
                self.watch(ctx);
                Some(change)
            }
            Err(e) => {
                self.error = Some(e.to_string());
                None
            }
        }
    }

    fn replace(&mut self, scene: Scene, opened: bool) -> SceneChange {
        self.error = None;
        let previous = std::mem::replace(&mut self.scene, Arc::new(scene));
        SceneChange { previous, opened }
    }

    /// Starts watching the scene file, if there is one.
    fn watch(&mut self, ctx: &egui::Context) {
        self.watcher = None;
        self.watch_problem = None;
        if let Some(path) = &self.path {
            let repaint = ctx.clone();
            match SceneWatcher::new(path, move || repaint.request_repaint()) {
                Ok(w) => self.watcher = Some(w),
                Err(e) => self.watch_problem = Some(format!("not watching {}: {e}", path.display())),
            }
        }
    }

    /// The scene's name, the Open field and button, Reload, and the last
    /// load error.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> Option<SceneChange> {
        let mut change = None;
        ui.heading("Scene");
        let name = self.path.as_ref().map_or(DEFAULT_SCENE_NAME.to_owned(), |p| p.display().to_string());
        ui.label(name).on_hover_text("The scene file shown; it reloads when saved on disk.");
        ui.horizontal(|ui| {
            ui.add(
                egui::TextEdit::singleline(&mut self.open_path)
                    .hint_text("path/to/scene.ron")
                    .desired_width(150.0),
            );
            if ui.button("Open").clicked() {
                change = self.open(PathBuf::from(self.open_path.trim()), ui.ctx());
            }
        });
        if self.path.is_some() && ui.button("Reload").clicked() {
            change = self.reload();
        }
        for problem in [&self.error, &self.watch_problem].into_iter().flatten() {
            ui.colored_label(Color32::from_rgb(220, 60, 50), problem);
        }
        change
    }
}
