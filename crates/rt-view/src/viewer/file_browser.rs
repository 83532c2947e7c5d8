//! A file browser inside the window, for opening scene files where no
//! desktop file dialog is available (no portal, a bare X server): folders
//! and `.ron` files of one folder, a click to go into a folder or open a
//! scene, and ".." to go up.

use std::path::{Path, PathBuf};

/// The browser's state: shown or not, and the folder it lists.
pub(super) struct FileBrowser {
    open: bool,
    dir: PathBuf,
    entries: Vec<Entry>,
    error: Option<String>,
}

/// One line of the listing.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Entry {
    is_dir: bool,
    name: String,
}

impl FileBrowser {
    /// A closed browser that will start in `dir`.
    pub fn new(dir: PathBuf) -> Self {
        Self { open: false, dir, entries: Vec::new(), error: None }
    }

    /// Shows the browser, listing `dir` (its current folder if `None`).
    pub fn show(&mut self, dir: Option<&Path>) {
        if let Some(d) = dir {
            self.dir = d.to_owned();
        }
        self.open = true;
        self.refresh();
    }

    /// The folder listed.
    #[cfg(test)]
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The listing: folders, then `.ron` files, each by name.
    #[cfg(test)]
    pub fn entries(&self) -> Vec<(bool, &str)> {
        self.entries.iter().map(|e| (e.is_dir, e.name.as_str())).collect()
    }

    /// Goes into `name` (a folder of the listing, or ".." for the parent).
    pub fn enter(&mut self, name: &str) {
        self.dir = if name == ".." {
            let absolute = std::path::absolute(&self.dir).unwrap_or_else(|_| self.dir.clone());
            absolute.parent().map_or(absolute.clone(), Path::to_owned)
        } else {
            self.dir.join(name)
        };
        self.refresh();
    }

    fn refresh(&mut self) {
        self.error = None;
        self.entries = match list(&self.dir) {
            Ok(entries) => entries,
            Err(e) => {
                self.error = Some(format!("{}: {e}", self.dir.display()));
                Vec::new()
            }
        };
    }

    /// The browser's window; returns the scene file picked, if one was.
    pub fn ui(&mut self, ctx: &egui::Context) -> Option<PathBuf> {
        if !self.open {
            return None;
        }
        let mut picked = None;
        let mut enter = None;
        let mut open = self.open;
        egui::Window::new("Open scene").open(&mut open).default_size([360.0, 420.0]).show(ctx, |ui| {
            let shown = std::path::absolute(&self.dir).unwrap_or_else(|_| self.dir.clone());
            ui.label(shown.display().to_string());
            if let Some(e) = &self.error {
                ui.colored_label(egui::Color32::from_rgb(220, 60, 50), e);
            }
            ui.separator();
            egui::ScrollArea::vertical().show(ui, |ui| {
                if ui.selectable_label(false, "../").clicked() {
                    enter = Some("..".to_owned());
                }
                for e in &self.entries {
                    let label = if e.is_dir { format!("{}/", e.name) } else { e.name.clone() };
                    if ui.selectable_label(false, label).clicked() {
                        if e.is_dir {
                            enter = Some(e.name.clone());
                        } else {
                            picked = Some(self.dir.join(&e.name));
                        }
                    }
                }
            });
        });
        if let Some(name) = enter {
            self.enter(&name);
        }
        self.open = open && picked.is_none();
        picked
    }
}

/// The folders and `.ron` files of `dir`, folders first, each by name;
/// hidden entries (starting with a dot) are left out.
fn list(dir: &Path) -> std::io::Result<Vec<Entry>> {
    let mut entries = Vec::new();
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with('.') {
            continue;
        }
        let is_dir = entry.file_type().is_ok_and(|t| t.is_dir());
        let is_scene = Path::new(&name).extension().is_some_and(|e| e.eq_ignore_ascii_case("ron"));
        if is_dir || is_scene {
            entries.push(Entry { is_dir, name });
        }
    }
    // Folders first, then by name.
    entries.sort_by(|a, b| b.is_dir.cmp(&a.is_dir).then_with(|| a.name.cmp(&b.name)));
    Ok(entries)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_listing_shows_folders_then_scene_files_and_goes_in_and_out() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("meshes")).unwrap();
        for f in ["b.ron", "a.ron", "notes.txt", ".hidden.ron"] {
            std::fs::write(dir.path().join(f), "").unwrap();
        }
        let mut b = FileBrowser::new(dir.path().to_owned());
        b.show(None);
        assert_eq!(b.entries(), vec![(true, "meshes"), (false, "a.ron"), (false, "b.ron")]);
        b.enter("meshes");
        assert!(b.entries().is_empty());
        b.enter("..");
        assert_eq!(std::fs::canonicalize(b.dir()).unwrap(), std::fs::canonicalize(dir.path()).unwrap());
        b.enter("nope");
        assert!(b.error.as_deref().is_some_and(|e| e.contains("nope")), "{:?}", b.error);
    }
}
