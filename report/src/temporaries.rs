//! bikedyn's own temporaries in an output folder, and their clean-up.
//!
//! An atomic write ([`crate::output`]) makes `.<name>.tmp-<pid>-<n>[.<ext>]`
//! files; a staged folder ([`crate::staged`]) makes `.<name>.partial-<pid>`
//! folders and moves an earlier output aside as `.<name>.old-<pid>`.
//! [`clean_stale`] removes those whose process no longer runs, checked
//! through `/proc/<pid>` on Linux; elsewhere they are left alone. An
//! earlier output moved aside by a run killed before its new output was in
//! place (`.old-<pid>`, no target) is moved back instead.
//!
//! Both writers use this module, and it uses neither.

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Best-effort fsync of the folder holding `path` (the rename itself).
pub(crate) fn sync_dir(path: &Path) {
    #[cfg(unix)]
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = fs::File::open(dir) {
            let _ = d.sync_all();
        }
    }
    // Elsewhere (Windows, WebAssembly) a folder cannot be opened to sync.
    #[cfg(not(unix))]
    let _ = path;
}

/// A temporary of bikedyn's naming: which kind and the process that made it.
#[derive(Debug, PartialEq, Eq)]
enum Temporary {
    /// `.<name>.tmp-<pid>-<n>[.<ext>]`: an atomic write's file.
    File(u32),
    /// `.<name>.partial-<pid>`: a staged folder.
    Partial(u32),
    /// `.<name>.old-<pid>`: an earlier output moved aside, and `<name>`.
    Old(u32, String),
}

fn digits(s: &str) -> Option<u32> {
    (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()))
        .then(|| s.parse().ok())
        .flatten()
}

/// Which of bikedyn's temporaries `name` is, if any.
fn temporary(name: &str) -> Option<Temporary> {
    let rest = name.strip_prefix('.')?;
    if let Some((stem, tail)) = rest.rsplit_once(".tmp-") {
        // `<pid>-<n>`, then at most one extension.
        let (ids, ext) = tail.split_once('.').unwrap_or((tail, ""));
        let (pid, n) = ids.split_once('-')?;
        if !stem.is_empty() && !ext.contains('.') && digits(n).is_some() {
            return digits(pid).map(Temporary::File);
        }
        return None;
    }
    if let Some((stem, pid)) = rest.rsplit_once(".partial-") {
        return (!stem.is_empty())
            .then(|| digits(pid).map(Temporary::Partial))
            .flatten();
    }
    let (stem, pid) = rest.rsplit_once(".old-")?;
    (!stem.is_empty())
        .then(|| digits(pid).map(|p| Temporary::Old(p, stem.to_string())))
        .flatten()
}

/// Whether process `pid` has ended: only known where `/proc` lists the
/// running processes (Linux); elsewhere every process counts as running.
fn ended(pid: u32) -> bool {
    if cfg!(target_os = "linux") && Path::new("/proc/self").exists() {
        pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists()
    } else {
        false
    }
}

/// Remove the temporaries of ended bikedyn runs in `dir` (see the module
/// docs); each folder once per process. Best effort: what cannot be
/// removed stays.
pub fn clean_stale(dir: &Path) {
    static CLEANED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());
    let key = fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
    if let Ok(mut done) = CLEANED.lock() {
        if done.contains(&key) {
            return;
        }
        done.push(key);
    }
    let Ok(entries) = fs::read_dir(dir) else { return };
    let mut found: Vec<(PathBuf, bool, Temporary)> = entries
        .filter_map(|e| e.ok())
        .filter_map(|e| {
            let t = temporary(e.file_name().to_str()?)?;
            let is_dir = e.file_type().ok()?.is_dir();
            Some((e.path(), is_dir, t))
        })
        .collect();
    // Earlier outputs are put back before the partial folders go, so a run
    // killed between its two renames leaves the old output.
    found.sort_by_key(|(_, _, t)| !matches!(t, Temporary::Old(..)));
    for (path, is_dir, t) in found {
        match t {
            Temporary::File(pid) if !is_dir && ended(pid) => {
                let _ = fs::remove_file(&path);
            }
            Temporary::Partial(pid) if is_dir && ended(pid) => {
                let _ = fs::remove_dir_all(&path);
            }
            Temporary::Old(pid, name) if is_dir && ended(pid) => {
                let target = dir.join(name);
                if fs::symlink_metadata(&target).is_err() {
                    let _ = fs::rename(&path, &target);
                } else {
                    let _ = fs::remove_dir_all(&path);
                }
            }
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_bikedyns_own_temporary_names_are_recognised() {
        assert_eq!(temporary(".big.tmp-123-0.csv"), Some(Temporary::File(123)));
        assert_eq!(temporary(".a.b.tmp-7-12"), Some(Temporary::File(7)));
        assert_eq!(temporary(".set.partial-99"), Some(Temporary::Partial(99)));
        assert_eq!(temporary(".set.old-99"), Some(Temporary::Old(99, "set".into())));
        for other in [
            "big.tmp-123-0.csv",
            ".big.tmp-123.csv",
            ".big.tmp-12a-0.csv",
            ".big.tmp-1-0.tar.gz",
            "..partial-1",
            ".set.partial-",
            ".set.partial-1x",
            ".notes.txt",
        ] {
            assert_eq!(temporary(other), None, "{other}");
        }
    }
}
