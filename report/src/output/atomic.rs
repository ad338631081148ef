//! Atomic writing of output files (see the module above: a symbolic link
//! is followed, a FIFO written through, a regular file replaced by rename).

use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Boxed error of a writer callback.
pub type BoxError = Box<dyn std::error::Error + Send + Sync + 'static>;

/// Why `dir` cannot hold a new file: it is a file, or it does not exist.
fn missing_directory(dir: &Path) -> String {
    if dir.exists() {
        format!("{} is a file, not a directory", dir.display())
    } else {
        format!("directory {} does not exist", dir.display())
    }
}

/// Error writing an output file; always names the target path.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The directory of the target does not exist (it is not created), or
    /// is a file.
    #[error("cannot write {}: {}", .path.display(), missing_directory(.dir))]
    NoSuchDirectory {
        /// Target file.
        path: PathBuf,
        /// Its (missing) directory.
        dir: PathBuf,
    },
    /// The path is a directory.
    #[error("cannot write {}: it is a directory", .path.display())]
    IsDirectory {
        /// Offending path.
        path: PathBuf,
    },
    /// The path is a symbolic link that leads nowhere.
    #[error("cannot write {}: it is a symbolic link to a missing file ({})", .path.display(), .target.display())]
    DanglingSymlink {
        /// Offending path.
        path: PathBuf,
        /// Where the link points.
        target: PathBuf,
    },
    /// The path has no file name (e.g. ends in `..` or is a root).
    #[error("cannot write {}: not a file path", .path.display())]
    InvalidPath {
        /// Offending path.
        path: PathBuf,
    },
    /// An I/O step failed.
    #[error("cannot write {}: {op}: {source}", .path.display())]
    Io {
        /// Target file.
        path: PathBuf,
        /// Step that failed (e.g. "create temporary file", "rename").
        op: &'static str,
        /// Underlying error.
        source: io::Error,
    },
    /// An output folder holds files but no marker of bikedyn's (so
    /// replacing it could destroy someone's files; see `crate::staged`).
    #[error("cannot write {}: the folder holds files and no {marker} file says bikedyn wrote it (measured data, someone's files, or an output of a bikedyn older than this one); choose a new or empty folder, or remove this one yourself if nothing in it is needed", .path.display())]
    ForeignFolder {
        /// The folder.
        path: PathBuf,
        /// The marker file an output of bikedyn holds.
        marker: &'static str,
    },
    /// An output folder of bikedyn's holds a file bikedyn did not write.
    #[error("cannot replace {}: {} was not written by bikedyn (the folder's list of its files does not name it); move it out of the folder, or choose a new folder", .path.display(), .file.display())]
    ForeignFile {
        /// The folder.
        path: PathBuf,
        /// The first file bikedyn did not write.
        file: PathBuf,
    },
    /// An output folder holds another kind of bikedyn output.
    #[error("cannot write {}: it holds a {found}, not a {expected}; choose another folder", .path.display())]
    OtherKind {
        /// The folder.
        path: PathBuf,
        /// What the folder's marker says it holds.
        found: String,
        /// What this run writes.
        expected: &'static str,
    },
    /// The output folder appeared or changed while this run was writing
    /// (another run writing the same place): nothing was replaced.
    #[error("cannot write {}: it appeared or changed while this run was writing it (another run writing the same folder?); it was left as it is: run again, or choose another folder", .path.display())]
    Changed {
        /// The folder.
        path: PathBuf,
    },
    /// Producing the content failed (encoding or rendering).
    #[error("cannot write {}: {source}", .path.display())]
    Content {
        /// Target file.
        path: PathBuf,
        /// Underlying error.
        source: BoxError,
    },
}

impl OutputError {
    /// The target path of the failed write.
    pub fn path(&self) -> &Path {
        match self {
            OutputError::NoSuchDirectory { path, .. }
            | OutputError::IsDirectory { path }
            | OutputError::DanglingSymlink { path, .. }
            | OutputError::InvalidPath { path }
            | OutputError::Io { path, .. }
            | OutputError::ForeignFolder { path, .. }
            | OutputError::ForeignFile { path, .. }
            | OutputError::OtherKind { path, .. }
            | OutputError::Changed { path }
            | OutputError::Content { path, .. } => path,
        }
    }
}

static TEMP_COUNTER: AtomicU64 = AtomicU64::new(0);

/// The directory a file `path` goes in (`.` for a bare name), which must
/// exist.
fn existing_dir_of(path: &Path) -> Result<PathBuf, OutputError> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(OutputError::NoSuchDirectory {
            path: path.to_path_buf(),
            dir,
        });
    }
    Ok(dir)
}

/// Reserve a fresh temporary file next to `path`; returns (file, temp path).
fn create_temp(path: &Path) -> Result<(File, PathBuf), OutputError> {
    let name = match path.file_name() {
        Some(n) => n.to_string_lossy().into_owned(),
        None => {
            return Err(OutputError::InvalidPath {
                path: path.to_path_buf(),
            })
        }
    };
    let dir = existing_dir_of(path)?;
    // Temporaries of killed runs in the same folder go now (issue 35).
    crate::temporaries::clean_stale(&dir);
    // Keep the extension last: some encoders choose the format from it.
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or(name);
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let mut last_err = None;
    for _ in 0..16 {
        let n = TEMP_COUNTER.fetch_add(1, Ordering::Relaxed);
        let tmp = dir.join(format!(".{stem}.tmp-{}-{n}{ext}", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&tmp) {
            Ok(f) => return Ok((f, tmp)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last_err = Some(e),
            Err(e) => {
                return Err(OutputError::Io {
                    path: path.to_path_buf(),
                    op: "create temporary file",
                    source: e,
                })
            }
        }
    }
    Err(OutputError::Io {
        path: path.to_path_buf(),
        op: "create temporary file",
        source: last_err.unwrap_or_else(|| io::Error::other("no free temporary name")),
    })
}

/// fsync the complete temporary file, rename it over `path`, fsync the directory.
fn commit(tmp: &Path, path: &Path) -> Result<(), OutputError> {
    let io_err = |op, source| OutputError::Io {
        path: path.to_path_buf(),
        op,
        source,
    };
    let f = OpenOptions::new()
        .read(true)
        .write(true)
        .open(tmp)
        .map_err(|e| io_err("reopen temporary file", e))?;
    f.sync_all().map_err(|e| io_err("fsync", e))?;
    drop(f);
    if let Ok(meta) = fs::metadata(path) {
        // Keep the permissions of the file being replaced (best effort).
        let _ = fs::set_permissions(tmp, meta.permissions());
    }
    fs::rename(tmp, path).map_err(|e| io_err("rename temporary file", e))?;
    // Best effort: some file systems do not support fsync on directories.
    crate::temporaries::sync_dir(path);
    Ok(())
}

/// How an output path is written.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum OutputTarget {
    /// A regular file or a new path: written to a temporary file in the same
    /// directory and renamed over it.
    Atomic(PathBuf),
    /// Anything else that can be opened for writing (a FIFO, a character
    /// device such as `/dev/null`, a terminal): written through, so the node
    /// itself is never replaced.
    WriteThrough(PathBuf),
}

/// Decide how `path` is written, following symbolic links (the link stays, its
/// target is written). Errors: a directory, a dangling link, a path without a
/// file name, or a missing parent directory. Call it before computing, so a
/// bad output is reported before any work (issue 10, point 4).
pub fn output_target(path: impl AsRef<Path>) -> Result<OutputTarget, OutputError> {
    let path = path.as_ref();
    match fs::symlink_metadata(path) {
        Err(_) => {
            // A new file: its directory must exist and it must have a name.
            if path.file_name().is_none() {
                return Err(OutputError::InvalidPath {
                    path: path.to_path_buf(),
                });
            }
            existing_dir_of(path)?;
            Ok(OutputTarget::Atomic(path.to_path_buf()))
        }
        Ok(m) if m.file_type().is_symlink() => match fs::canonicalize(path) {
            Ok(real) => output_target(real),
            Err(_) => {
                // A link to a file not yet written: write that file, if its
                // directory exists (the link then points at it).
                let target = fs::read_link(path).unwrap_or_default();
                let resolved = match path.parent() {
                    Some(d) if target.is_relative() => d.join(&target),
                    _ => target.clone(),
                };
                match resolved.parent() {
                    Some(d)
                        if d.is_dir() && resolved.file_name().is_some() && fs::symlink_metadata(&resolved).is_err() =>
                    {
                        Ok(OutputTarget::Atomic(resolved))
                    }
                    _ => Err(OutputError::DanglingSymlink {
                        path: path.to_path_buf(),
                        target,
                    }),
                }
            }
        },
        Ok(m) if m.is_dir() => Err(OutputError::IsDirectory {
            path: path.to_path_buf(),
        }),
        Ok(m) if m.is_file() => Ok(OutputTarget::Atomic(path.to_path_buf())),
        Ok(_) => Ok(OutputTarget::WriteThrough(path.to_path_buf())),
    }
}

/// Open a non-regular file for writing through (no create, no truncate).
fn open_through(path: &Path) -> Result<File, OutputError> {
    OpenOptions::new().write(true).open(path).map_err(|e| OutputError::Io {
        path: path.to_path_buf(),
        op: "open for writing",
        source: e,
    })
}

/// Write `path` with what `write` writes: atomically for a regular file or a
/// new path (see the module docs), through the node for a FIFO or a device
/// (see [`output_target`]); a symbolic link is followed and kept.
///
/// The writer is buffered; `write` need not flush. If `write` fails, nothing
/// at a regular `path` changes and the temporary file is removed.
pub fn write_atomic<F, E>(path: impl AsRef<Path>, write: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut dyn Write) -> Result<(), E>,
    E: Into<BoxError>,
{
    let given = path.as_ref();
    let path = match output_target(given)? {
        OutputTarget::Atomic(p) => p,
        OutputTarget::WriteThrough(p) => {
            let mut w = BufWriter::new(open_through(&p)?);
            write(&mut w).map_err(|e| OutputError::Content {
                path: given.to_path_buf(),
                source: e.into(),
            })?;
            return w.flush().map_err(|e| OutputError::Io {
                path: given.to_path_buf(),
                op: "write",
                source: e,
            });
        }
    };
    let path = path.as_path();
    let (file, tmp) = create_temp(path)?;
    let result = (|| {
        let mut w = BufWriter::new(file);
        write(&mut w).map_err(|e| OutputError::Content {
            path: given.to_path_buf(),
            source: e.into(),
        })?;
        w.flush().map_err(|e| OutputError::Io {
            path: given.to_path_buf(),
            op: "write",
            source: e,
        })?;
        drop(w);
        commit(&tmp, path)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp);
    }
    result
}

/// Write `path` with a file that `produce` writes at the given temporary path
/// (same directory and extension as `path`; the file exists and is empty
/// when `produce` is called and may be overwritten). A regular file or new
/// path is replaced atomically; for a FIFO or a device the finished file is
/// copied through the node (see [`output_target`]).
pub fn write_atomic_via_path<F, E>(path: impl AsRef<Path>, produce: F) -> Result<(), OutputError>
where
    F: FnOnce(&Path) -> Result<(), E>,
    E: Into<BoxError>,
{
    let given = path.as_ref();
    let target = output_target(given)?;
    let path = match &target {
        OutputTarget::Atomic(p) => p.clone(),
        OutputTarget::WriteThrough(_) => {
            // Render into a temporary file of the same extension elsewhere.
            let ext = given
                .extension()
                .map(|e| e.to_string_lossy().into_owned())
                .unwrap_or_default();
            std::env::temp_dir().join(format!("bikedyn-output.{ext}"))
        }
    };
    let (file, tmp) = create_temp(&path)?;
    drop(file);
    let result = produce(&tmp)
        .map_err(|e| OutputError::Content {
            path: given.to_path_buf(),
            source: e.into(),
        })
        .and_then(|()| match &target {
            OutputTarget::Atomic(p) => commit(&tmp, p),
            OutputTarget::WriteThrough(p) => {
                let mut out = open_through(p)?;
                let mut src = File::open(&tmp).map_err(|e| OutputError::Io {
                    path: given.to_path_buf(),
                    op: "read rendered file",
                    source: e,
                })?;
                io::copy(&mut src, &mut out).map(|_| ()).map_err(|e| OutputError::Io {
                    path: given.to_path_buf(),
                    op: "write",
                    source: e,
                })
            }
        });
    let _ = fs::remove_file(&tmp);
    result
}

/// Atomically write `contents` to `path`.
pub fn write_string_atomic(path: impl AsRef<Path>, contents: &str) -> Result<(), OutputError> {
    write_atomic(path, |w| w.write_all(contents.as_bytes()))
}

/// Atomically save a JSON value (pretty-printed, trailing newline).
pub fn save_json<T: serde::Serialize + ?Sized>(path: impl AsRef<Path>, value: &T) -> Result<(), OutputError> {
    write_atomic(path, |w| -> Result<(), BoxError> {
        serde_json::to_writer_pretty(&mut *w, value)?;
        w.write_all(b"\n")?;
        Ok(())
    })
}
