//! Watching the open scene file and the mesh files it reads, so that saving
//! any of them in an editor reloads the scene.
//!
//! Each file's directory is watched rather than the file itself: editors
//! often save by writing a new file and renaming it over the old one, which
//! ends a watch on the old file. Events are filtered by path.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver};

use notify::{RecursiveMode, Watcher};

/// A watch on a scene's files.
pub struct SceneWatcher {
    files: BTreeSet<PathBuf>,
    events: Receiver<notify::Result<notify::Event>>,
    // Kept alive: dropping it ends the watch.
    _watcher: notify::RecommendedWatcher,
}

impl SceneWatcher {
    /// Watches `files`; `on_event` is called from the watcher's thread after
    /// each file-system event (the viewer passes `request_repaint`).
    pub fn new(files: &[PathBuf], on_event: impl Fn() + Send + 'static) -> notify::Result<Self> {
        let files: BTreeSet<PathBuf> =
            files.iter().map(|p| std::path::absolute(p).unwrap_or_else(|_| p.clone())).collect();
        let dirs: BTreeSet<PathBuf> =
            files.iter().map(|p| p.parent().map_or_else(|| PathBuf::from("."), Path::to_owned)).collect();
        let (tx, events) = mpsc::channel();
        let mut watcher = notify::recommended_watcher(move |event| {
            let _ = tx.send(event);
            on_event();
        })?;
        for dir in &dirs {
            watcher.watch(dir, RecursiveMode::NonRecursive)?;
        }
        Ok(Self { files, events, _watcher: watcher })
    }

    /// Whether a watched file was created, modified or renamed into place
    /// since the last call.
    pub fn changed(&self) -> bool {
        let mut changed = false;
        for event in self.events.try_iter().flatten() {
            let relevant = matches!(
                event.kind,
                notify::EventKind::Create(_) | notify::EventKind::Modify(_) | notify::EventKind::Any
            );
            if relevant && event.paths.iter().any(|p| self.files.contains(p)) {
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
        let watcher = SceneWatcher::new(std::slice::from_ref(&scene), || {}).unwrap();

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

    #[test]
    fn a_mesh_file_in_another_directory_is_watched_too() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene.ron");
        std::fs::create_dir(dir.path().join("meshes")).unwrap();
        let mesh = dir.path().join("meshes/m.obj");
        std::fs::write(&scene, "a").unwrap();
        std::fs::write(&mesh, "v 0 0 0").unwrap();
        let watcher = SceneWatcher::new(&[scene, mesh.clone()], || {}).unwrap();
        std::fs::write(dir.path().join("meshes/other.obj"), "b").unwrap();
        std::thread::sleep(Duration::from_millis(200));
        assert!(!watcher.changed(), "another mesh's change was reported");
        std::fs::write(&mesh, "v 1 1 1").unwrap();
        assert!(wait_for(&watcher), "the mesh's change was missed");
    }
}
