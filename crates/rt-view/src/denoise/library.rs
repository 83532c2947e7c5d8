//! Where OIDN's library is looked for, and loading it once per process.
//!
//! In order: the folder or file `RT_VIEW_OIDN` names (and only there when it
//! is set, so a test or a person can point at one copy for sure); else
//! `~/.cache/rt-view/oidn` (`$XDG_CACHE_HOME/rt-view/oidn` where that is
//! set), where `scripts/get_oidn.sh` puts it; else the system's library
//! search path (`libOpenImageDenoise.so.2`). In a folder, `lib/` is tried
//! first (the script's layout), then the folder itself.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::denoise::oidn::Oidn;

/// The library's file name (OIDN 2.x's soname).
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";

/// The environment variable naming OIDN's folder (or library file).
pub const ENV_VAR: &str = "RT_VIEW_OIDN";

/// OIDN could not be loaded: where it was looked for, and why each place failed.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
#[error("OIDN not found (looked in {}); run scripts/get_oidn.sh", .tried.join("; "))]
pub struct NotFound {
    /// Each place tried, with the loader's reason.
    pub tried: Vec<String>,
}

/// The places to look in, in order, for these values of `RT_VIEW_OIDN`,
/// `XDG_CACHE_HOME` and `HOME`: paths, and last the bare name for the
/// system's search path.
pub fn candidates(env: Option<&str>, xdg_cache: Option<&str>, home: Option<&str>) -> Vec<PathBuf> {
    let in_folder = |dir: &Path| vec![dir.join("lib").join(LIBRARY_NAME), dir.join(LIBRARY_NAME)];
    if let Some(env) = env.filter(|e| !e.is_empty()) {
        let path = Path::new(env);
        return if path.is_file() { vec![path.to_owned()] } else { in_folder(path) };
    }
    let cache = match (xdg_cache.filter(|c| !c.is_empty()), home) {
        (Some(c), _) => Some(PathBuf::from(c)),
        (None, Some(h)) => Some(Path::new(h).join(".cache")),
        (None, None) => None,
    };
    let mut out = cache.map(|c| in_folder(&c.join("rt-view").join("oidn"))).unwrap_or_default();
    out.push(PathBuf::from(LIBRARY_NAME));
    out
}

/// Loads OIDN from the first of `places` that loads.
pub fn load_from(places: &[PathBuf]) -> Result<Oidn, NotFound> {
    let mut tried = Vec::new();
    for place in places {
        let shown = if place.components().count() == 1 {
            format!("the system's library path ({})", place.display())
        } else {
            place.display().to_string()
        };
        if place.components().count() > 1 && !place.exists() {
            tried.push(format!("{shown}: no such file"));
            continue;
        }
        match Oidn::load(place) {
            Ok(oidn) => return Ok(oidn),
            Err(e) => tried.push(format!("{shown}: {e}")),
        }
    }
    Err(NotFound { tried })
}

/// OIDN, found and loaded the first time it is asked for in this process
/// (from this process's environment), or why not: later calls give the
/// same answer without looking again.
pub fn find_and_load() -> Result<&'static Oidn, NotFound> {
    static LOADED: OnceLock<Result<Oidn, NotFound>> = OnceLock::new();
    LOADED
        .get_or_init(|| {
            let var = |name| std::env::var(name).ok();
            load_from(&candidates(
                var(ENV_VAR).as_deref(),
                var("XDG_CACHE_HOME").as_deref(),
                var("HOME").as_deref(),
            ))
        })
        .as_ref()
        .map_err(Clone::clone)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_variable_alone_is_looked_in_when_set() {
        let c = candidates(Some("/opt/oidn"), Some("/x"), Some("/home/me"));
        assert_eq!(
            c,
            [
                PathBuf::from("/opt/oidn/lib").join(LIBRARY_NAME),
                PathBuf::from("/opt/oidn").join(LIBRARY_NAME)
            ]
        );
    }

    #[test]
    fn without_the_variable_the_cache_then_the_system_path_are_tried() {
        let c = candidates(None, None, Some("/home/me"));
        let cache = PathBuf::from("/home/me/.cache/rt-view/oidn");
        assert_eq!(
            c,
            [cache.join("lib").join(LIBRARY_NAME), cache.join(LIBRARY_NAME), PathBuf::from(LIBRARY_NAME)]
        );
        assert_eq!(
            candidates(Some(""), Some("/c"), None)[0],
            PathBuf::from("/c/rt-view/oidn/lib").join(LIBRARY_NAME)
        );
    }

    #[test]
    fn a_missing_library_says_where_it_was_looked_for_and_what_to_run() {
        let dir = tempfile::tempdir().unwrap();
        let bogus = dir.path().join(LIBRARY_NAME);
        std::fs::write(&bogus, b"not a library").unwrap();
        let err = load_from(&candidates(Some(dir.path().to_str().unwrap()), None, None)).unwrap_err();
        let text = err.to_string();
        assert!(text.starts_with("OIDN not found (looked in "), "{text}");
        assert!(text.ends_with("run scripts/get_oidn.sh"), "{text}");
        assert!(
            text.contains(&format!("{}: no such file", dir.path().join("lib").join(LIBRARY_NAME).display())),
            "{text}"
        );
        // A file that is there but no library: the loader's reason.
        assert!(
            text.contains(&bogus.display().to_string()) && text.contains("file too short")
                || text.contains("invalid ELF"),
            "{text}"
        );
    }
}
