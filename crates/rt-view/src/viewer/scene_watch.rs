//! Watching the open scene file, so that saving it in an editor reloads it.
//!
//! The scene's directory is watched rather than the file itself: editors
//! often save by writing a new file and renaming it over the old one, which
//! ends a watch on the old file. Events are filtered by file name.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver};

use notify::{RecursiveMode, Watcher};

/// A watch on one scene file.
pub struct SceneWatcher {
    file_name: std::ffi::OsString,
    events: Receiver<notify::Result<notify::Event>>,
    // Kept alive: dropping it ends the watch.
    _watcher: notify::RecommendedWatcher,
}

impl SceneWatcher {
    /// Watches `path`; `on_event` is called from the watcher's thread after
    /// each file-system event (the viewer passes `request_repaint`).
    pub fn new(path: &Path, on_event: impl Fn() + Send + 'static) -> notify::Result<Self> {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
        let dir: PathBuf = path.parent().map_or_else(|| PathBuf::from("."), Path::to_owned);
        let file_name = path.file_name().unwrap_or_default().to_owned();
        let (tx, events) = mpsc::channel();
        let mut watcher = notify::recommended_watcher(move |event| {
            let _ = tx.send(event);
            on_event();
        })?;
        watcher.watch(&dir, RecursiveMode::NonRecursive)?;
        Ok(Self { file_name, events, _watcher: watcher })
    }

    /// Whether the scene file was created, modified or renamed into place
    /// since the last call.
    pub fn changed(&self) -> bool {
        let mut changed = false;
        for event in self.events.try_iter().flatten() {
            let relevant = matches!(
                event.kind,
                notify::EventKind::Create(_) | notify::EventKind::Modify(_) | notify::EventKind::Any
            );
            if relevant && event.paths.iter().any(|p| p.file_name() == Some(&self.file_name)) {
                changed = true;
            }
        }
        changed
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    fn wait_for(watcher: &SceneWatcher) -> bool {
        let deadline = Instant::now() + Duration::from_secs(5);
        while Instant::now() < deadline {
            if watcher.changed() {
                return true;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        false
    }

    #[test]
    fn writing_or_renaming_over_the_file_is_seen_and_other_files_are_not() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene.ron");
        std::fs::write(&scene, "a").unwrap();
        let watcher = SceneWatcher::new(&scene, || {}).unwrap();

        std::fs::write(dir.path().join("other.ron"), "b").unwrap();
        std::thread::sleep(Duration::from_millis(200));
        assert!(!watcher.changed(), "another file's change was reported");

        std::fs::write(&scene, "c").unwrap();
        assert!(wait_for(&watcher), "a write was missed");

        // Save by rename, as many editors do.
        let temp = dir.path().join(".scene.ron.swp");
        std::fs::write(&temp, "d").unwrap();
        std::fs::rename(&temp, &scene).unwrap();
        assert!(wait_for(&watcher), "a rename over the file was missed");
    }
}
