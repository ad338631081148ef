//! Outputs of several files (a synthetic set, a report folder, the plots
//! of `fit`): written as a whole, recognised as bikedyn's own, and the
//! temporaries of killed runs cleaned up.
//!
//! # Staging
//! A [`StagedDir`] writes its files into a hidden folder beside the target
//! (`.<name>.partial-<pid>`), which takes the target's place on
//! [`StagedDir::commit`] by a rename. A kill at any moment leaves the old
//! output or the new one under the target's name, never a mix or a half.
//!
//! # The marker
//! A committed folder holds [`MARKER`]: its first line names the kind of
//! output ([`FolderKind`]), the other lines every file bikedyn wrote
//! (relative paths with `/`). A folder is replaced only when it holds the
//! marker of the same kind and no file the marker does not list, so
//! measured runs, a user's notes or an output of another kind are never
//! deleted (issue 35). A folder an earlier bikedyn wrote has no marker and
//! is refused: the user removes it.
//!
//! # Concurrency
//! The target's state is noted when the output starts and checked again
//! just before the rename: a folder that appeared or changed meanwhile
//! (another `synth --out` to the same place) fails this run, and the other
//! run's output stays. On Unix a folder is never renamed over a folder
//! with files in it, which closes the remaining window.
//!
//! # Stale temporaries
//! The temporaries of killed runs are removed by
//! [`clean_stale`], before any output is
//! written to a folder.

use std::collections::BTreeSet;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use crate::output::{write_string_atomic, OutputError};
use crate::temporaries::{clean_stale, sync_dir};

/// The file that marks a folder as bikedyn's own output.
pub const MARKER: &str = ".bikedyn-output";

/// What a staged folder holds (the first line of its [`MARKER`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FolderKind {
    /// A set of `bikedyn synth`.
    SyntheticSet,
    /// The report folder of `bikedyn identify --report`.
    IdentifyReport,
    /// The folder of `bikedyn report --out`.
    Report,
    /// The plots of `bikedyn fit --plot`.
    FitPlots,
}

impl FolderKind {
    /// The marker's first line.
    pub fn tag(self) -> &'static str {
        match self {
            FolderKind::SyntheticSet => "bikedyn synthetic set",
            FolderKind::IdentifyReport => "bikedyn identify report",
            FolderKind::Report => "bikedyn report",
            FolderKind::FitPlots => "bikedyn fit plots",
        }
    }
}

/// The state of a target folder that allows writing it.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Writable {
    /// No such path.
    Absent,
    /// An empty folder.
    Empty,
    /// bikedyn's own output of the same kind (the marker's text).
    Own(String),
}

/// Every file under `dir`, as paths relative to it with `/` separators
/// (a symbolic link counts as a file and is not followed).
fn files_under(dir: &Path) -> io::Result<Vec<String>> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, prefix)) = stack.pop() {
        for e in fs::read_dir(&d)? {
            let e = e?;
            let name = format!("{prefix}{}", e.file_name().to_string_lossy());
            if e.file_type()?.is_dir() {
                stack.push((e.path(), format!("{name}/")));
            } else {
                out.push(name);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Whether `target` may be written as an output of `kind`, and its state.
fn writable(target: &Path, kind: FolderKind) -> Result<Writable, OutputError> {
    let io_err = |op: &'static str| {
        let path = target.to_path_buf();
        move |source| OutputError::Io { path, op, source }
    };
    match fs::symlink_metadata(target) {
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Writable::Absent),
        Err(e) => return Err(io_err("read the folder")(e)),
        // A link is not followed: the rename would replace the link, not
        // the folder it leads to.
        Ok(m) if m.file_type().is_symlink() => {
            return Err(io_err("write the folder")(io::Error::other(
                "it is a symbolic link; name the folder itself, or choose another name",
            )))
        }
        Ok(m) if !m.is_dir() => {
            return Err(io_err("create the folder")(io::Error::new(
                io::ErrorKind::AlreadyExists,
                "a file of that name exists; choose another name",
            )))
        }
        Ok(_) => {}
    }
    if fs::read_dir(target)
        .map_err(io_err("read the folder"))?
        .next()
        .is_none()
    {
        return Ok(Writable::Empty);
    }
    let marker = match fs::read_to_string(target.join(MARKER)) {
        Ok(text) => text,
        Err(_) => {
            return Err(OutputError::ForeignFolder {
                path: target.to_path_buf(),
                marker: MARKER,
            })
        }
    };
    let found = marker.lines().next().unwrap_or_default().trim();
    if found != kind.tag() {
        return Err(OutputError::OtherKind {
            path: target.to_path_buf(),
            found: found.to_string(),
            expected: kind.tag(),
        });
    }
    let listed: BTreeSet<&str> = marker.lines().skip(1).filter(|l| !l.starts_with('#')).collect();
    for f in files_under(target).map_err(io_err("read the folder"))? {
        if f != MARKER && !listed.contains(f.as_str()) {
            return Err(OutputError::ForeignFile {
                path: target.to_path_buf(),
                file: target.join(f),
            });
        }
    }
    Ok(Writable::Own(marker))
}

/// An output folder written as a whole (see the module docs): its files go
/// into [`StagedDir::path`]; dropped without a commit (an error on the
/// way), the staging folder is removed and the target is left as it was.
pub struct StagedDir {
    staging: PathBuf,
    target: PathBuf,
    kind: FolderKind,
    found: Writable,
    committed: bool,
}

impl StagedDir {
    /// Check that `target` can be written (before any work): its parent
    /// folder exists, and `target` is new, empty or an earlier output of
    /// `kind` holding only the files bikedyn wrote.
    pub fn check(target: &Path, kind: FolderKind) -> Result<(), OutputError> {
        parent_of(target)?;
        writable(target, kind).map(drop)
    }

    /// Start writing `target` (see [`StagedDir::check`]); stale
    /// temporaries beside it are cleaned first.
    pub fn new(target: &Path, kind: FolderKind) -> Result<StagedDir, OutputError> {
        let (parent, name) = parent_of(target)?;
        clean_stale(&parent);
        let found = writable(target, kind)?;
        let staging = parent.join(format!(".{name}.partial-{}", std::process::id()));
        // Only this process writes its own staging name (an earlier
        // staged output of this process was committed or dropped).
        let _ = fs::remove_dir_all(&staging);
        fs::create_dir(&staging).map_err(|source| OutputError::Io {
            path: target.to_path_buf(),
            op: "create a folder beside it",
            source,
        })?;
        Ok(StagedDir {
            staging,
            target: target.to_path_buf(),
            kind,
            found,
            committed: false,
        })
    }

    /// The folder to write the files into.
    pub fn path(&self) -> &Path {
        &self.staging
    }

    /// Write the marker, then put the staged folder in the target's place.
    /// An earlier output is moved aside first and removed once the new one
    /// is in place; a target that appeared or changed since [`StagedDir::new`]
    /// fails the commit and is left as it is.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let io = |op: &'static str| {
            let path = self.target.clone();
            move |source| OutputError::Io { path, op, source }
        };
        let files = files_under(&self.staging).map_err(io("list the files written"))?;
        let mut marker = format!(
            "{}\n# Written by bikedyn {}: a later run may replace this folder while it holds only these files.\n",
            self.kind.tag(),
            env!("CARGO_PKG_VERSION")
        );
        for f in files.iter().filter(|f| *f != MARKER) {
            marker.push_str(f);
            marker.push('\n');
        }
        write_string_atomic(self.staging.join(MARKER), &marker)?;
        let now = writable(&self.target, self.kind)?;
        let unchanged = match (&self.found, &now) {
            // A new empty folder in the target's place loses nothing.
            (Writable::Absent | Writable::Empty, Writable::Absent | Writable::Empty) => true,
            (a, b) => a == b,
        };
        if !unchanged {
            return Err(OutputError::Changed {
                path: self.target.clone(),
            });
        }
        let old = match now {
            Writable::Own(_) => {
                let (parent, name) = parent_of(&self.target)?;
                let old = parent.join(format!(".{name}.old-{}", std::process::id()));
                let _ = fs::remove_dir_all(&old);
                fs::rename(&self.target, &old).map_err(io("move the earlier output aside"))?;
                Some(old)
            }
            // Only an empty folder goes (remove_dir refuses any other).
            Writable::Empty => {
                fs::remove_dir(&self.target).map_err(io("replace the empty folder"))?;
                None
            }
            Writable::Absent => None,
        };
        if let Err(e) = fs::rename(&self.staging, &self.target) {
            if let Some(old) = &old {
                let _ = fs::rename(old, &self.target);
            }
            return Err(if self.target.exists() {
                OutputError::Changed {
                    path: self.target.clone(),
                }
            } else {
                io("move the new output into place")(e)
            });
        }
        self.committed = true;
        if let Some(old) = old {
            let _ = fs::remove_dir_all(old);
        }
        sync_dir(&self.target);
        Ok(())
    }
}

impl Drop for StagedDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

/// The existing parent folder of `target` and the target's file name.
fn parent_of(target: &Path) -> Result<(PathBuf, String), OutputError> {
    let name = target
        .file_name()
        .filter(|n| *n != "." && *n != "..")
        .ok_or_else(|| OutputError::InvalidPath {
            path: target.to_path_buf(),
        })?;
    let parent = target
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !parent.is_dir() {
        return Err(OutputError::NoSuchDirectory {
            path: target.to_path_buf(),
            dir: parent.to_path_buf(),
        });
    }
    Ok((parent.to_path_buf(), name.to_string_lossy().into_owned()))
}
