//! Where the viewer's scene comes from: a file (or the built-in scene), the
//! ways of opening another — a path typed and Enter, the Open button (a
//! file browser), a file dropped on the window, the recent files — Reload,
//! a watcher that reloads when an editor saves the scene or one of its mesh
//! files, and the error of the last load that failed.
//!
//! A failed load never replaces the scene: the last good one (and its image)
//! stays, and the error is shown until a load succeeds.
//!
//! A scene is loaded on a thread of its own, so the window never waits for
//! it: reading the files and building the BVH can take seconds, and the
//! BVH build runs beside the render still running, on rayon threads of its
//! own ([`load_apart`]). The
//! window keeps showing the current scene, says what is loading, and takes
//! the new scene on the first frame after it is ready ([`SceneSource::poll`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::{Duration, Instant};

use egui::Color32;
use rt_core::LoadedScene;

use super::file_browser::FileBrowser;
use super::remembered::RecentFiles;
use super::scene_watch::SceneWatcher;

/// The built-in default scene's text (`scenes/default.ron`).
pub const DEFAULT_SCENE: &str = include_str!("../../../../scenes/default.ron");
/// The name the built-in scene goes by in messages.
pub const DEFAULT_SCENE_NAME: &str = "<built-in default scene>";

/// Loads the scene (the built-in one for `None`).
pub fn load(path: Option<&Path>) -> Result<LoadedScene, rt_core::SceneError> {
    match path {
        Some(p) => crate::scene_cache::load_scene(p),
        None => rt_core::parse_scene(DEFAULT_SCENE, DEFAULT_SCENE_NAME, Path::new(".")),
    }
}

/// [`load`] on a rayon pool of its own, not the global one: a render keeps
/// every thread of the global pool busy until its last pass ends, and the
/// BVH build would wait for all of it. On its own pool the build shares the
/// cores with the render instead.
fn load_apart(path: Option<&Path>) -> Result<LoadedScene, rt_core::SceneError> {
    match rayon::ThreadPoolBuilder::new().thread_name(|i| format!("scene-load-{i}")).build() {
        Ok(pool) => pool.install(|| load(path)),
        Err(_) => load(path),
    }
}

/// A file event is acted on after this much quiet (editors write in bursts).
const RELOAD_DEBOUNCE: Duration = Duration::from_millis(100);

/// A new scene is in place: what it replaced, and whether it came from
/// another file (Open) rather than the same one again (Reload, a save).
#[derive(Clone, Debug)]
pub(super) struct SceneChange {
    /// The scene shown before.
    pub previous: Arc<LoadedScene>,
    /// Another file was opened: the view starts from its camera and settings.
    pub opened: bool,
}

/// The scene, where it came from, and its watcher.
pub(super) struct SceneSource {
    path: Option<PathBuf>,
    scene: Arc<LoadedScene>,
    watcher: Option<SceneWatcher>,
    reload_at: Option<Instant>,
    /// The text of the path field.
    open_path: String,
    browser: FileBrowser,
    recent: RecentFiles,
    /// Why the last load failed; cleared by the next one that succeeds.
    error: Option<String>,
    /// Why the files are not watched, if they are not.
    watch_problem: Option<String>,
    /// The load under way, if one is.
    loading: Option<Loading>,
}

/// A scene being loaded on a thread of its own.
struct Loading {
    /// The file (`None`: the built-in scene).
    path: Option<PathBuf>,
    /// Another file is being opened (not the same one reloaded).
    opened: bool,
    /// Where the loading thread sends its result.
    result: Receiver<Result<LoadedScene, rt_core::SceneError>>,
}

impl SceneSource {
    /// The source of `scene`, loaded from `path` (`None`: the built-in scene),
    /// watched from now on; `ctx` is repainted when a file changes.
    pub fn new(path: Option<PathBuf>, scene: LoadedScene, recent: RecentFiles, ctx: &egui::Context) -> Self {
        let start = path.as_ref().and_then(|p| p.parent()).map_or_else(|| PathBuf::from("."), Path::to_owned);
        let mut source = Self {
            open_path: path.as_ref().map(|p| p.display().to_string()).unwrap_or_default(),
            path,
            scene: Arc::new(scene),
            watcher: None,
            reload_at: None,
            browser: FileBrowser::new(start),
            recent,
            error: None,
            watch_problem: None,
            loading: None,
        };
        if let Some(p) = source.path.clone() {
            source.recent.add(&p);
        }
        source.watch(ctx);
        source
    }

    /// The scene shown.
    pub fn scene(&self) -> &Arc<LoadedScene> {
        &self.scene
    }

    /// The scene file (`None`: the built-in scene).
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// The scene files opened lately.
    pub fn recent(&self) -> &RecentFiles {
        &self.recent
    }

    /// Whether a scene is being loaded.
    pub fn is_loading(&self) -> bool {
        self.loading.is_some()
    }

    /// Why the last load failed, if it did.
    #[cfg(test)]
    pub fn error(&self) -> Option<&str> {
        self.error.as_deref()
    }

    /// The scene a finished load brought, if one did; then acts on file
    /// events: once the files have been quiet for [`RELOAD_DEBOUNCE`] after
    /// a change, starts reloading the scene (a later call brings it). This
    /// is the one place a new scene comes from.
    pub fn poll(&mut self, ctx: &egui::Context) -> Option<SceneChange> {
        if let Some(loading) = &self.loading {
            match loading.result.try_recv() {
                Ok(result) => return self.finish(result, ctx),
                Err(TryRecvError::Empty) => {}
                Err(TryRecvError::Disconnected) => {
                    self.loading = None;
                    self.error = Some("the scene could not be loaded: its loading thread stopped".to_owned());
                }
            }
        }
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
        self.reload(ctx);
        None
    }

    /// Starts loading the scene file again; on error the scene will stay
    /// and the error be kept. The new scene comes from [`SceneSource::poll`].
    pub fn reload(&mut self, ctx: &egui::Context) {
        self.start(self.path.clone(), false, ctx);
    }

    /// Starts opening the scene file at `path`, to be watched instead of
    /// the current one; on error nothing will change but the error shown.
    /// The new scene comes from [`SceneSource::poll`].
    pub fn open(&mut self, path: PathBuf, ctx: &egui::Context) {
        self.start(Some(path), true, ctx);
    }

    /// Loads `path` on a thread of its own (a load under way is forgotten:
    /// its thread finishes unheard); `ctx` is repainted when it is done.
    fn start(&mut self, path: Option<PathBuf>, opened: bool, ctx: &egui::Context) {
        let (send, result) = mpsc::channel();
        let (file, repaint) = (path.clone(), ctx.clone());
        let spawned = std::thread::Builder::new().name("scene-load".to_owned()).spawn(move || {
            // The receiver may be gone (another load started): nothing to tell.
            let _ = send.send(load_apart(file.as_deref()));
            repaint.request_repaint();
        });
        match spawned {
            Ok(_) => self.loading = Some(Loading { path, opened, result }),
            Err(e) => self.error = Some(format!("cannot start loading the scene: {e}")),
        }
    }

    /// Takes a finished load's result: the new scene in place (and watched),
    /// or its error shown.
    fn finish(
        &mut self,
        result: Result<LoadedScene, rt_core::SceneError>,
        ctx: &egui::Context,
    ) -> Option<SceneChange> {
        let Loading { path, opened, .. } = self.loading.take()?;
        match result {
            Ok(scene) => {
                if opened && let Some(p) = &path {
                    self.open_path = p.display().to_string();
                    self.recent.add(p);
                }
                self.path = path;
                let change = self.replace(scene, opened);
                self.watch(ctx); // The mesh files may have changed.
                Some(change)
            }
            Err(e) => {
                self.error = Some(e.to_string());
                None
            }
        }
    }

    /// Waits for the load under way and takes its result (tests).
    #[cfg(test)]
    pub fn wait_for_load(&mut self, ctx: &egui::Context) -> Option<SceneChange> {
        let result = self.loading.as_ref()?.result.recv().ok()?;
        self.finish(result, ctx)
    }

    fn replace(&mut self, scene: LoadedScene, opened: bool) -> SceneChange {
        self.error = None;
        let previous = std::mem::replace(&mut self.scene, Arc::new(scene));
        SceneChange { previous, opened }
    }

    /// Shows `scene`, an edit of the scene shown (the material panel's):
    /// the same file and geometry, so nothing is watched anew and no
    /// [`SceneChange`] follows; the file is not written.
    pub fn show_edited(&mut self, scene: Arc<LoadedScene>) {
        self.scene = scene;
    }

    /// Watches the scene file and its mesh files, if it has a file.
    fn watch(&mut self, ctx: &egui::Context) {
        self.watcher = None;
        self.watch_problem = None;
        if let Some(path) = &self.path {
            let mut files = vec![path.clone()];
            files.extend(self.scene.scene.source_files().iter().cloned());
            let repaint = ctx.clone();
            match SceneWatcher::new(&files, move || repaint.request_repaint()) {
                Ok(w) => self.watcher = Some(w),
                Err(e) => self.watch_problem = Some(format!("not watching {}: {e}", path.display())),
            }
        }
    }

    /// Shows the file browser (Ctrl+O).
    pub fn browse(&mut self) {
        let dir = self.path.as_ref().and_then(|p| p.parent()).map(Path::to_owned);
        self.browser.show(dir.as_deref());
    }

    /// Starts opening a `.ron` file dropped on the window, if one was.
    pub fn take_dropped(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> =
            ctx.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_owned()).collect());
        let Some(path) = dropped.into_iter().next() else { return };
        let is_scene = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron"));
        if !is_scene {
            self.error = Some(format!("{}: not a scene file (.ron)", path.display()));
            return;
        }
        self.open(path, ctx);
    }

    /// The file browser's window, if shown; a file chosen starts opening.
    pub fn browser_ui(&mut self, ctx: &egui::Context) {
        if let Some(path) = self.browser.ui(ctx) {
            self.open(path, ctx);
        }
    }

    /// The scene's path (resolved), the path field (Enter opens it), Open
    /// (the file browser), Recent, Reload, and the last load error.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        ui.heading("Scene");
        let shown = match &self.path {
            Some(p) => std::fs::canonicalize(p).unwrap_or_else(|_| p.clone()).display().to_string(),
            None => DEFAULT_SCENE_NAME.to_owned(),
        };
        ui.add(egui::Label::new(egui::RichText::new(shown).monospace()).wrap())
            .on_hover_text("The scene shown; it reloads when it or one of its mesh files is saved.");
        let field = ui.add(
            egui::TextEdit::singleline(&mut self.open_path)
                .hint_text("path/to/scene.ron, Enter opens")
                .desired_width(f32::INFINITY),
        );
        if field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter)) {
            self.open(PathBuf::from(self.open_path.trim()), &ctx);
        }
        ui.horizontal(|ui| {
            if ui.button("Open…").on_hover_text("Browse for a scene file (Ctrl+O)").clicked() {
                self.browse();
            }
            let recent = self.recent.files().to_vec();
            ui.add_enabled_ui(!recent.is_empty(), |ui| {
                ui.menu_button("Recent", |ui| {
                    for p in recent {
                        if ui.button(p.display().to_string()).clicked() {
                            self.open(p, &ctx);
                            ui.close();
                        }
                    }
                });
            });
            if ui.add_enabled(self.path.is_some(), egui::Button::new("Reload")).on_hover_text("F5").clicked()
            {
                self.reload(&ctx);
            }
        });
        if let Some(loading) = &self.loading {
            let name =
                loading.path.as_ref().map_or(DEFAULT_SCENE_NAME.to_owned(), |p| p.display().to_string());
            ui.label(format!("loading {name} …"));
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        for problem in [&self.error, &self.watch_problem].into_iter().flatten() {
            ui.colored_label(Color32::from_rgb(220, 60, 50), problem);
        }
        let warnings = self.scene.scene.warnings();
        if !warnings.is_empty() {
            let plural = if warnings.len() == 1 { "" } else { "s" };
            egui::CollapsingHeader::new(format!("{} warning{plural}", warnings.len()))
                .id_salt("scene warnings")
                .show(ui, |ui| {
                    for w in warnings {
                        ui.colored_label(Color32::from_rgb(200, 150, 40), w);
                    }
                });
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::atomic::{AtomicBool, Ordering};

    use super::*;

    #[test]
    fn a_scene_loads_while_a_render_keeps_every_rayon_thread_busy() {
        // A render holds each thread of rayon's global pool until its last
        // pass ends (render_job's broadcast). Before, the load's BVH build
        // queued behind it: the new scene came only once the render ended.
        let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let ctx = egui::Context::default();
        let mut source = SceneSource::new(None, load(None).unwrap(), RecentFiles::default(), &ctx);
        let busy = Arc::new(AtomicBool::new(true));
        let hog = {
            let busy = busy.clone();
            std::thread::spawn(move || {
                rayon::broadcast(|_| {
                    while busy.load(Ordering::Relaxed) {
                        std::thread::sleep(Duration::from_millis(1));
                    }
                })
            })
        };
        source.open(scenes.join("mesh.ron"), &ctx);
        let deadline = Instant::now() + Duration::from_secs(10);
        let change = loop {
            if let Some(change) = source.poll(&ctx) {
                break Some(change);
            }
            if Instant::now() > deadline || source.error.is_some() {
                break None;
            }
            std::thread::sleep(Duration::from_millis(5));
        };
        busy.store(false, Ordering::Relaxed);
        hog.join().unwrap();
        assert!(change.is_some(), "the scene did not load while the pool was busy: {:?}", source.error);
        assert!(source.path().is_some_and(|p| p.ends_with("mesh.ron")));
    }
}
