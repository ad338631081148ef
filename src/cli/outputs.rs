//! No output replaces an input, and no two outputs share a file (issue
//! 35): every command lists its inputs and outputs with their flags, and
//! paths that lead to the same file (after links, `.` and `..`; or one
//! file under two hard links) are refused before any work.

use anyhow::{bail, Result};
use std::fs;
use std::path::{Path, PathBuf};

/// One path of a command line, with the flag that gave it.
pub struct Named<'a> {
    /// The flag (`--bike`, `--output`) or `INPUT` for a positional path.
    pub flag: &'static str,
    pub path: &'a Path,
}

/// A command's paths: what it reads, the files it writes and the folders
/// it writes as a whole (replaced on completion, so an input anywhere under
/// one would be lost).
#[derive(Default)]
pub struct Paths<'a> {
    inputs: Vec<Named<'a>>,
    files: Vec<Named<'a>>,
    folders: Vec<Named<'a>>,
}

impl<'a> Paths<'a> {
    pub fn new() -> Self {
        Self::default()
    }

    /// An input path (a file or a folder; `None` is skipped).
    pub fn input(mut self, flag: &'static str, path: Option<&'a Path>) -> Self {
        self.inputs.extend(path.map(|path| Named { flag, path }));
        self
    }

    /// A bicycle given as a built-in name or a parameter file: an input
    /// only when it names a file.
    pub fn bike(self, flag: &'static str, spec: Option<&'a str>) -> Self {
        let file = spec.map(Path::new).filter(|p| p.is_file());
        self.input(flag, file)
    }

    /// An output file.
    pub fn file(mut self, flag: &'static str, path: Option<&'a Path>) -> Self {
        self.files.extend(path.map(|path| Named { flag, path }));
        self
    }

    /// An output folder written as a whole.
    pub fn folder(mut self, flag: &'static str, path: Option<&'a Path>) -> Self {
        self.folders.extend(path.map(|path| Named { flag, path }));
        self
    }

    /// Refuse an output that is an input or another output.
    pub fn check(&self) -> Result<()> {
        // FIFOs and devices (`/dev/null`, `/dev/stdout`) are written
        // through, never replaced: two of them may be the same node.
        let files: Vec<&Named> = self.files.iter().filter(|o| !is_special(o.path)).collect();
        for (k, o) in files.iter().enumerate() {
            for i in self.inputs.iter().filter(|i| !is_special(i.path)) {
                if same(o.path, i.path) {
                    bail!(
                        "{} {} is the file given as {}: bikedyn never writes over an input; choose another output file",
                        o.flag,
                        o.path.display(),
                        i.flag
                    );
                }
            }
            for other in &files[k + 1..] {
                if same(o.path, other.path) {
                    bail!(
                        "{} {} and {} {} are the same file: give each output its own file",
                        o.flag,
                        o.path.display(),
                        other.flag,
                        other.path.display()
                    );
                }
            }
        }
        for o in &self.folders {
            let folder = identity(o.path);
            for i in &self.inputs {
                let input = identity(i.path);
                if input == folder {
                    bail!(
                        "{} {} is the input given as {}: bikedyn never writes over an input; choose another folder",
                        o.flag,
                        o.path.display(),
                        i.flag
                    );
                }
                if input.starts_with(&folder) {
                    bail!(
                        "{} {} holds {} {}: the folder is replaced whole when written, so it cannot hold an input; choose another folder",
                        o.flag,
                        o.path.display(),
                        i.flag,
                        i.path.display()
                    );
                }
            }
        }
        Ok(())
    }
}

/// An existing path that is neither a regular file nor a folder.
fn is_special(p: &Path) -> bool {
    fs::metadata(p).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// The canonical form of `p`; for a path not yet written, that of its
/// folder joined with its name.
fn identity(p: &Path) -> PathBuf {
    if let Ok(c) = fs::canonicalize(p) {
        return c;
    }
    match (p.parent(), p.file_name()) {
        (Some(d), Some(name)) => {
            let d = if d.as_os_str().is_empty() { Path::new(".") } else { d };
            fs::canonicalize(d).map_or_else(|_| p.to_path_buf(), |d| d.join(name))
        }
        _ => p.to_path_buf(),
    }
}

/// Whether `a` and `b` are one file: the same canonical path, or (on Unix)
/// the same device and inode (hard links).
fn same(a: &Path, b: &Path) -> bool {
    if identity(a) == identity(b) {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(ma), Ok(mb)) = (fs::metadata(a), fs::metadata(b)) {
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
    }
    false
}
