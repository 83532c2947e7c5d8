//! What the viewer remembers between runs: one value, [`Remembered`], saved
//! through eframe's storage under [`eframe::APP_KEY`] when the window closes
//! (and every 30 s), as egui's demo app keeps its state. The window's size
//! and place are eframe's own entry in the same file (`persist_window`).
//!
//! The file is `app.ron` in `$RT_VIEW_CONFIG_DIR` if that is set (tests set
//! it), else in eframe's folder for the app `rt-view`
//! ([`eframe::storage_dir`]: `$XDG_DATA_HOME/rt-view` or
//! `~/.local/share/rt-view` on Linux).
//!
//! Reading it never fails and never blocks the start: a field a state lacks
//! (one written by an older viewer) takes its default, and a state that
//! cannot be read is replaced by the defaults, with one warning on stderr.
//! With no state at all, the recent files an older viewer kept in a file of
//! their own (`recent-scenes`, one path a line, in `$RT_VIEW_CONFIG_DIR`,
//! else `$XDG_CONFIG_HOME/rt-view`, else `~/.config/rt-view`) are read once;
//! from then on the saved state is the only list.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::camera_controls::CameraSettings;
use super::image_settings::RESOLUTION_SCALE;

/// How many recent files are remembered.
pub const MAX_RECENT: usize = 10;

/// Everything the viewer remembers between runs (besides the window).
///
/// The parts of the window own this state while it runs; the viewer gathers
/// it into this value to save it, and hands it back out at the next start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub(super) struct Remembered {
    /// The scene files opened lately.
    pub recent: RecentFiles,
    /// Whether the side panel is shown (it has a fixed width).
    pub show_panel: bool,
    /// The image size as a multiple of the scene's: how many pixels this
    /// machine and screen want, whatever the scene.
    pub resolution_scale: f32,
    /// The scene file shown when the viewer closed (`None`: the built-in scene).
    pub last_scene: Option<LastScene>,
}

impl Default for Remembered {
    fn default() -> Self {
        Self { recent: RecentFiles::default(), show_panel: true, resolution_scale: 1.0, last_scene: None }
    }
}

/// The scene file shown when the viewer closed, and how it was seen.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(super) struct LastScene {
    /// The scene file, absolute.
    pub path: PathBuf,
    /// The viewer's camera.
    pub camera: CameraSettings,
    /// The camera the scene file gave. The viewer's comes back only while
    /// the file's is unchanged, as a reload keeps edits only then.
    pub file_camera: CameraSettings,
}

impl LastScene {
    /// The camera to start `path`, whose file gives `file_camera`, with: the
    /// remembered one if this is the same file and its camera is unchanged.
    pub fn camera_for(&self, path: &Path, file_camera: &CameraSettings) -> Option<CameraSettings> {
        (absolute(path) == self.path && self.file_camera == *file_camera).then_some(self.camera)
    }
}

/// The scene files opened lately: newest first, absolute, each once, at most
/// [`MAX_RECENT`]. A file that has gone stays listed; opening it says why it
/// cannot be read.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(from = "Vec<PathBuf>", into = "Vec<PathBuf>")]
pub(super) struct RecentFiles(Vec<PathBuf>);

impl RecentFiles {
    /// The files, newest first.
    pub fn files(&self) -> &[PathBuf] {
        &self.0
    }

    /// Puts `path` (made absolute) first.
    pub fn add(&mut self, path: &Path) {
        let path = absolute(path);
        self.0.retain(|p| *p != path);
        self.0.insert(0, path);
        self.0.truncate(MAX_RECENT);
    }
}

/// A list as stored, kept to the rules: empty paths and repeats dropped
/// (the first, newest, kept), at most [`MAX_RECENT`].
impl From<Vec<PathBuf>> for RecentFiles {
    fn from(paths: Vec<PathBuf>) -> Self {
        let mut files: Vec<PathBuf> = Vec::new();
        for p in paths {
            if !p.as_os_str().is_empty() && !files.contains(&p) && files.len() < MAX_RECENT {
                files.push(p);
            }
        }
        Self(files)
    }
}

impl From<RecentFiles> for Vec<PathBuf> {
    fn from(recent: RecentFiles) -> Self {
        recent.0
    }
}

/// `path` resolved (links followed), or made absolute if it does not exist.
pub(super) fn absolute(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).or_else(|_| std::path::absolute(path)).unwrap_or_else(|_| path.to_owned())
}

impl Remembered {
    /// The state saved in `storage` (eframe's, `None` if it has none), read
    /// as the module header says.
    pub fn load(storage: Option<&dyn eframe::Storage>) -> Self {
        Self::load_from(storage, storage_file().as_deref(), legacy_recent_file().as_deref())
    }

    /// [`Remembered::load`] with the storage's file (for the warning when it
    /// cannot be read at all) and the old recent-files list given.
    pub fn load_from(
        storage: Option<&dyn eframe::Storage>,
        file: Option<&Path>,
        legacy: Option<&Path>,
    ) -> Self {
        let shown = file.map_or_else(|| "eframe's storage".to_owned(), |f| f.display().to_string());
        match storage.and_then(|s| s.get_string(eframe::APP_KEY)) {
            Some(text) => Self::from_ron(&text).unwrap_or_else(|e| {
                eprintln!(
                    "warning: {shown}: forgot the viewer's remembered state, which cannot be read: {e}"
                );
                Self::default()
            }),
            None => {
                // eframe reads the file quietly and starts empty when it cannot.
                if let Some(e) = file.and_then(unreadable) {
                    eprintln!(
                        "warning: {shown}: forgot the viewer's remembered state, which cannot be read: {e}"
                    );
                }
                Self::from_legacy(legacy)
            }
        }
    }

    /// The state in `text` (RON, as eframe stores it), its values kept in range.
    pub fn from_ron(text: &str) -> Result<Self, ron::error::SpannedError> {
        let mut state: Self = ron::from_str(text)?;
        state.resolution_scale = if state.resolution_scale.is_finite() {
            state.resolution_scale.clamp(*RESOLUTION_SCALE.start(), *RESOLUTION_SCALE.end())
        } else {
            1.0
        };
        Ok(state)
    }

    /// The defaults, with the recent files of an older viewer's list at `legacy`.
    fn from_legacy(legacy: Option<&Path>) -> Self {
        let text = legacy.and_then(|p| std::fs::read_to_string(p).ok()).unwrap_or_default();
        let recent = text.lines().map(PathBuf::from).collect::<Vec<_>>().into();
        Self { recent, ..Self::default() }
    }

    /// Writes the state into eframe's `storage`.
    pub fn save(&self, storage: &mut dyn eframe::Storage) {
        eframe::set_value(storage, eframe::APP_KEY, self);
    }
}

/// Why eframe's file at `path` cannot be read, if it exists and cannot.
fn unreadable(path: &Path) -> Option<String> {
    let text = std::fs::read_to_string(path).ok()?;
    ron::from_str::<std::collections::HashMap<String, String>>(&text).err().map(|e| e.to_string())
}

/// A variable's value, if set and not empty.
fn var(name: &str) -> Option<PathBuf> {
    std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from)
}

/// The storage file eframe is told to use instead of its own place:
/// `$RT_VIEW_CONFIG_DIR/app.ron`, if that is set.
pub fn storage_override() -> Option<PathBuf> {
    var("RT_VIEW_CONFIG_DIR").map(|d| d.join("app.ron"))
}

/// The storage file eframe uses for the app `rt-view`.
fn storage_file() -> Option<PathBuf> {
    storage_override().or_else(|| eframe::storage_dir("rt-view").map(|d| d.join("app.ron")))
}

/// Where an older viewer kept its recent files.
fn legacy_recent_file() -> Option<PathBuf> {
    var("RT_VIEW_CONFIG_DIR")
        .or_else(|| var("XDG_CONFIG_HOME").map(|d| d.join("rt-view")))
        .or_else(|| var("HOME").map(|d| d.join(".config/rt-view")))
        .map(|d| d.join("recent-scenes"))
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use eframe::Storage as _;
    use rt_core::{Projection, Vec3};

    use super::*;

    /// eframe's storage, in memory.
    #[derive(Default)]
    struct Storage(HashMap<String, String>);

    impl eframe::Storage for Storage {
        fn get_string(&self, key: &str) -> Option<String> {
            self.0.get(key).cloned()
        }
        fn set_string(&mut self, key: &str, value: String) {
            self.0.insert(key.to_owned(), value);
        }
        fn remove_string(&mut self, key: &str) {
            self.0.remove(key);
        }
        fn flush(&mut self) {}
    }

    fn camera(x: f32) -> CameraSettings {
        CameraSettings {
            position: Vec3::new(x as _, 1.3, -5.7),
            center_of_interest: Vec3::new(0.1, 0.2, 0.3),
            up: Vec3::Y,
            fov_y: 41.37,
            near: 0.7,
            projection: Projection::Orthographic,
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }

    fn state() -> Remembered {
        let mut recent = RecentFiles::default();
        recent.add(Path::new("/scenes/a.ron"));
        recent.add(Path::new("/scenes/b.ron"));
        Remembered {
            recent,
            show_panel: false,
            resolution_scale: 0.37,
            last_scene: Some(LastScene {
                path: "/scenes/b.ron".into(),
                camera: camera(0.123_456_79),
                file_camera: camera(2.0),
            }),
        }
    }

    #[test]
    fn the_state_comes_back_exactly_from_eframes_storage() {
        let mut storage = Storage::default();
        state().save(&mut storage);
        let text = storage.get_string(eframe::APP_KEY).unwrap();
        assert!(text.contains("show_panel:false") && text.contains("/scenes/b.ron"), "{text}");
        assert_eq!(Remembered::load_from(Some(&storage), None, None), state());
    }

    #[test]
    fn a_partial_or_empty_state_takes_the_defaults_for_what_it_lacks() {
        assert_eq!(Remembered::from_ron("()").unwrap(), Remembered::default());
        let old = Remembered::from_ron(r#"(recent: ["/x.ron"], show_panel: false)"#).unwrap();
        assert_eq!(old.recent.files(), [PathBuf::from("/x.ron")]);
        assert!(!old.show_panel);
        assert_eq!((old.resolution_scale, old.last_scene), (1.0, None));
        // A field this viewer does not know (written by a newer one) is skipped.
        assert!(!Remembered::from_ron("(show_panel: false, zoom: 3)").unwrap().show_panel);
    }

    #[test]
    fn a_state_that_cannot_be_read_gives_the_defaults() {
        for text in
            ["", "(recent: 3)", "(show_panel: maybe", "\u{0}garbage", "(last_scene: Some((path: \"/a\")))"]
        {
            let mut storage = Storage::default();
            storage.set_string(eframe::APP_KEY, text.to_owned());
            assert_eq!(Remembered::load_from(Some(&storage), None, None), Remembered::default(), "{text:?}");
        }
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("app.ron");
        std::fs::write(&file, "{ not ron").unwrap();
        assert!(unreadable(&file).is_some());
        assert_eq!(Remembered::load_from(None, Some(&file), None), Remembered::default());
        std::fs::write(&file, r#"{"window": "()"}"#).unwrap();
        assert_eq!(unreadable(&file), None);
    }

    #[test]
    fn a_resolution_scale_out_of_range_is_brought_into_it() {
        let scale = |text: &str| Remembered::from_ron(text).unwrap().resolution_scale;
        assert_eq!(scale("(resolution_scale: 9.0)"), 2.0);
        assert_eq!(scale("(resolution_scale: 0.0)"), 0.25);
        assert_eq!(scale("(resolution_scale: NaN)"), 1.0);
        assert_eq!(scale("(resolution_scale: 0.5)"), 0.5);
    }

    #[test]
    fn recent_files_are_newest_first_absolute_without_repeats_and_at_most_ten() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.ron"), dir.path().join("b.ron"));
        std::fs::write(&a, "").unwrap();
        std::fs::write(&b, "").unwrap();
        let mut recent = RecentFiles::default();
        recent.add(&a);
        recent.add(&b);
        recent.add(&a);
        let canonical = |p: &Path| std::fs::canonicalize(p).unwrap();
        assert_eq!(recent.files(), [canonical(&a), canonical(&b)]);
        // A relative path of a file that does not exist is made absolute.
        recent.add(Path::new("gone.ron"));
        assert_eq!(recent.files()[0], std::env::current_dir().unwrap().join("gone.ron"));
        for i in 0..20 {
            recent.add(&dir.path().join(format!("{i}.ron")));
        }
        assert_eq!(recent.files().len(), MAX_RECENT);
        assert_eq!(recent.files()[0], dir.path().join("19.ron"));
        // A stored list is brought to the same rules.
        let stored: Vec<PathBuf> =
            ["/a", "", "/b", "/a"].into_iter().chain(["/c"; 20]).map(PathBuf::from).collect();
        assert_eq!(RecentFiles::from(stored).files(), ["/a", "/b", "/c"].map(PathBuf::from));
        let many: Vec<PathBuf> = (0..20).map(|i| PathBuf::from(format!("/{i}"))).collect();
        assert_eq!(RecentFiles::from(many.clone()).files(), &many[..MAX_RECENT]);
    }

    #[test]
    fn an_older_viewers_recent_files_are_read_once_when_nothing_is_saved() {
        let dir = tempfile::tempdir().unwrap();
        let legacy = dir.path().join("recent-scenes");
        std::fs::write(&legacy, "/s/new.ron\n\n/s/old.ron\n").unwrap();
        let migrated = Remembered::load_from(None, None, Some(&legacy));
        assert_eq!(migrated.recent.files(), ["/s/new.ron", "/s/old.ron"].map(PathBuf::from));
        assert_eq!(Remembered { recent: RecentFiles::default(), ..migrated }, Remembered::default());
        // Once a state is saved, the old list is not read again.
        let mut storage = Storage::default();
        Remembered::default().save(&mut storage);
        assert_eq!(Remembered::load_from(Some(&storage), None, Some(&legacy)), Remembered::default());
        assert_eq!(Remembered::load_from(None, None, Some(&dir.path().join("none"))), Remembered::default());
    }

    #[test]
    fn the_camera_comes_back_only_for_the_same_file_with_its_camera_unchanged() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.ron");
        std::fs::write(&path, "").unwrap();
        let last = LastScene { path: absolute(&path), camera: camera(0.5), file_camera: camera(2.0) };
        assert_eq!(last.camera_for(&path, &camera(2.0)), Some(camera(0.5)));
        // The same file by another name.
        let dotted = dir.path().join(".").join("s.ron");
        assert_eq!(last.camera_for(&dotted, &camera(2.0)), Some(camera(0.5)));
        assert_eq!(last.camera_for(&dir.path().join("t.ron"), &camera(2.0)), None);
        assert_eq!(last.camera_for(&path, &camera(2.5)), None, "the file's camera changed");
    }
}
