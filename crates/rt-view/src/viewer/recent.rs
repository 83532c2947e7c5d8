//! The scene files opened lately, newest first, kept between runs in
//! `recent-scenes` (one absolute path a line) in the viewer's configuration
//! folder: `$RT_VIEW_CONFIG_DIR`, else `$XDG_CONFIG_HOME/rt-view`, else
//! `~/.config/rt-view`. Writing it is best effort: a read-only home only
//! means the list is not remembered.

use std::path::{Path, PathBuf};

/// How many files the list keeps.
pub const MAX_RECENT: usize = 10;

/// The recent scene files and where they are stored.
pub(super) struct RecentFiles {
    store: Option<PathBuf>,
    files: Vec<PathBuf>,
}

impl RecentFiles {
    /// The list stored in the configuration folder (empty if there is none).
    pub fn load() -> Self {
        Self::load_from(config_dir().map(|d| d.join("recent-scenes")))
    }

    /// The list stored in `store` (`None`: not stored).
    pub fn load_from(store: Option<PathBuf>) -> Self {
        let files = store
            .as_ref()
            .and_then(|p| std::fs::read_to_string(p).ok())
            .map(|text| text.lines().filter(|l| !l.is_empty()).map(PathBuf::from).take(MAX_RECENT).collect())
            .unwrap_or_default();
        Self { store, files }
    }

    /// The files, newest first.
    pub fn files(&self) -> &[PathBuf] {
        &self.files
    }

    /// Puts `path` (made absolute) first, and stores the list.
    pub fn add(&mut self, path: &Path) {
        let path = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
        self.files.retain(|p| *p != path);
        self.files.insert(0, path);
        self.files.truncate(MAX_RECENT);
        self.save();
    }

    fn save(&self) {
        let Some(store) = &self.store else { return };
        let text: String = self.files.iter().map(|p| format!("{}\n", p.display())).collect();
        if let Some(dir) = store.parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        // Best effort, and never half-written: a temporary file renamed over it.
        let temp = store.with_extension("tmp");
        if std::fs::write(&temp, text).is_ok() {
            let _ = std::fs::rename(&temp, store);
        }
    }
}

/// The viewer's configuration folder, if one can be named.
fn config_dir() -> Option<PathBuf> {
    let var = |name| std::env::var_os(name).filter(|v| !v.is_empty()).map(PathBuf::from);
    var("RT_VIEW_CONFIG_DIR")
        .or_else(|| var("XDG_CONFIG_HOME").map(|d| d.join("rt-view")))
        .or_else(|| var("HOME").map(|d| d.join(".config/rt-view")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn files_are_kept_newest_first_without_repeats_and_survive_a_restart() {
        let dir = tempfile::tempdir().unwrap();
        let store = dir.path().join("conf/recent-scenes");
        let mut recent = RecentFiles::load_from(Some(store.clone()));
        assert!(recent.files().is_empty());
        let a = dir.path().join("a.ron");
        let b = dir.path().join("b.ron");
        std::fs::write(&a, "").unwrap();
        std::fs::write(&b, "").unwrap();
        recent.add(&a);
        recent.add(&b);
        recent.add(&a);
        let canonical = |p: &Path| std::fs::canonicalize(p).unwrap();
        assert_eq!(recent.files(), &[canonical(&a), canonical(&b)]);
        let again = RecentFiles::load_from(Some(store));
        assert_eq!(again.files(), recent.files());
        for i in 0..20 {
            recent.add(&dir.path().join(format!("{i}.ron")));
        }
        assert_eq!(recent.files().len(), MAX_RECENT);
    }
}
