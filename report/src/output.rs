//! Output files: atomic writing, CSV/JSON writers and terminal tables.
//!
//! # Atomic writes
//! Every `save_*` function (and the plots of the `plot` module) writes through
//! [`write_atomic`] / [`write_atomic_via_path`]. A symbolic link is followed
//! (and kept); a FIFO or a device is written through, never replaced
//! ([`output_target`]). For a regular file or a new path the content goes to a fresh
//! temporary file in the target's directory (`.<name>.tmp-<pid>-<n>.<ext>`),
//! is flushed and fsynced, and is then renamed over the target (followed by a
//! best-effort fsync of the directory). On any error the temporary file is
//! removed and an existing target is left untouched; a missing directory is
//! reported as [`OutputError::NoSuchDirectory`] (directories are never created).
//!
//! # Eigenvalue order
//! Within each speed the four eigenvalues are written in the order of
//! [`ordered_eigenvalues`]: by mode (weave, capsize, castering, the merged
//! pairs weave-capsize, weave-castering, capsize-castering, other), then by
//! descending imaginary part, then by descending real part. For a conventional
//! bicycle slots 1-2 are the weave pair (`+i` first; two real roots below
//! `v_d`), slot 3 capsize and slot 4 castering; the mode of each slot is
//! written alongside it, so unusual labelings are never misread.
//!
//! # Eigen sweep formats
//! * JSON ([`eigen_sweep_json`]): a list of
//!   `{"v": speed, "eigenvalues": [[re, im], x4], "modes": ["weave", x4],
//!   "mode_shapes": [{"roll_amplitude", "roll_phase", "steer_amplitude",
//!   "steer_phase"}, x4]}` ([`ModeShape`]: roll normalised to 1).
//! * CSV ([`write_eigen_sweep_csv`]): header `v`, then for `k = 1..4`
//!   `re_k,im_k,mode_k,roll_amp_k,roll_phase_k,steer_amp_k,steer_phase_k`,
//!   one row per speed, in sweep order. Units: `v` m/s, eigenvalues 1/s,
//!   phases rad.
//! * [`stream_eigen_sweep`] writes either format block by block, so memory
//!   stays flat in the number of speeds.
//!
//! # Parameter sweep / stability map formats
//! CSV columns (after the parameter column(s), for a grid also `i,j`):
//! `weave_speed,capsize_speed,weave_real_pair_merge,stable_width,stable_lo,stable_hi,
//! n_stable_intervals,stable_intervals,open_ended,error`.
//! Absent values are empty cells. `stable_lo`/`stable_hi` bound the first
//! (lowest-speed) stable interval, `stable_intervals` lists all as
//! `lo:hi` separated by `;`, `error` is empty for successful cells. A grid is
//! written in long (tidy) format, row-major (`x` outer, `y` inner). JSON holds
//! the same fields per cell (`null` when absent) plus the axes and speed range.
//!
//! Floating-point numbers are written with Rust's shortest round-trip
//! representation (`{:?}`, e.g. `4.29238253634111`, `1e-20`).

use std::fmt::Write as _;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use nalgebra::Complex;
use serde_json::{json, Value};

use bikedyn_runtime::eigen::{EigenPoint, EigenSweep, Mode};
use bikedyn_runtime::sweep::{CellResult, ParameterSweep, StabilityMap};

// The number formatters live in the runtime (its error messages use them);
// tables and callers reach them here.
pub use bikedyn_runtime::number_text::{format_fixed, format_significant};

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
    crate::staged::clean_stale(&dir);
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
    crate::staged::sync_dir(path);
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

// ---------------------------------------------------------------------------
// Eigen sweeps

fn mode_rank(m: Mode) -> u32 {
    m.rank() as u32
}

/// Indices of a point's eigenvalues in the stable output order: by mode
/// (weave, capsize, castering, merged pairs, other), then descending imaginary
/// part, then descending real part.
pub fn ordered_indices(p: &EigenPoint) -> [usize; 4] {
    let mut idx = [0usize, 1, 2, 3];
    idx.sort_by(|&a, &b| {
        mode_rank(p.modes[a])
            .cmp(&mode_rank(p.modes[b]))
            .then(p.eigenvalues[b].im.total_cmp(&p.eigenvalues[a].im))
            .then(p.eigenvalues[b].re.total_cmp(&p.eigenvalues[a].re))
    });
    idx
}

/// The eigenvalues of a point with their modes, in the stable output order
/// ([`ordered_indices`]).
pub fn ordered_eigenvalues(p: &EigenPoint) -> [(Complex<f64>, Mode); 4] {
    ordered_indices(p).map(|k| (p.eigenvalues[k], p.modes[k]))
}

/// Roll and steer components of an eigenvector (a mode shape), normalised so
/// that the roll component is 1 (amplitude 1, phase 0), as the eigenvector
/// components of the benchmark are presented (Meijaard et al. 2007, Fig. 4:
/// components relative to the roll angle); a mode without roll (roll
/// amplitude below `1e-12` of steer) is normalised on the steer component
/// instead. Phases in rad, in `(-pi, pi]`; for a real eigenvalue the phase is
/// 0 or pi (steer in or against the roll direction). Benchmark sign
/// convention (roll right, steer right positive).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ModeShape {
    /// Roll amplitude (1 unless the mode has no roll).
    pub roll_amplitude: f64,
    /// Roll phase (rad).
    pub roll_phase: f64,
    /// Steer amplitude relative to roll (rad per rad).
    pub steer_amplitude: f64,
    /// Steer phase relative to roll (rad).
    pub steer_phase: f64,
}

/// The [`ModeShape`] of an eigenvector `x = [phi, delta, phi', delta']`.
pub fn mode_shape(x: &[Complex<f64>; 4]) -> ModeShape {
    let (roll, steer) = (x[0], x[1]);
    let reference = if roll.norm() > 1e-12 * steer.norm() {
        roll
    } else {
        steer
    };
    if !(reference.norm() > 0.0) {
        return ModeShape {
            roll_amplitude: 0.0,
            roll_phase: 0.0,
            steer_amplitude: 0.0,
            steer_phase: 0.0,
        };
    }
    let phase = |z: Complex<f64>| if z.norm() == 0.0 { 0.0 } else { z.im.atan2(z.re) + 0.0 };
    let (r, d) = (roll / reference, steer / reference);
    ModeShape {
        roll_amplitude: r.norm(),
        roll_phase: phase(r),
        steer_amplitude: d.norm(),
        steer_phase: phase(d),
    }
}

/// JSON object of one speed point: `{"v", "eigenvalues", "modes",
/// "mode_shapes"}` (see [`eigen_sweep_json`]).
pub fn eigen_point_json(p: &EigenPoint) -> Value {
    let idx = ordered_indices(p);
    let mut v = json!({
        "v": p.v,
        "eigenvalues": idx.iter().map(|&k| [p.eigenvalues[k].re, p.eigenvalues[k].im]).collect::<Vec<_>>(),
        "modes": idx.iter().map(|&k| p.modes[k].name()).collect::<Vec<_>>(),
        "mode_shapes": idx.iter().map(|&k| mode_shape(&p.eigenvectors[k])).collect::<Vec<_>>(),
    });
    // A model with extra states (tyre forces) adds its other modes.
    if !p.extra_eigenvalues.is_empty() {
        v["extra_eigenvalues"] = json!(p.extra_eigenvalues.iter().map(|z| [z.re, z.im]).collect::<Vec<_>>());
    }
    v
}

/// JSON value of an eigen sweep: `[{"v": .., "eigenvalues": [[re, im], ..],
/// "modes": ["weave", ..], "mode_shapes": [{"roll_amplitude", "roll_phase",
/// "steer_amplitude", "steer_phase"}, ..]}, ..]` (see [`ModeShape`]), and
/// `"extra_eigenvalues": [[re, im], ..]` for a model with extra states.
pub fn eigen_sweep_json(sweep: &EigenSweep) -> Value {
    Value::Array(sweep.points.iter().map(eigen_point_json).collect())
}

/// Header of the eigen-sweep CSV: `v`, then per eigenvalue `k`: `re_k, im_k,
/// mode_k, roll_amp_k, roll_phase_k, steer_amp_k, steer_phase_k`.
pub fn eigen_sweep_csv_header() -> Vec<String> {
    eigen_sweep_csv_header_with(0)
}

/// [`eigen_sweep_csv_header`] with `extra` more eigenvalues (a model with
/// extra states): `re_extra_k, im_extra_k` each.
pub fn eigen_sweep_csv_header_with(extra: usize) -> Vec<String> {
    let mut h = vec!["v".to_string()];
    for k in 1..=4 {
        for c in ["re", "im", "mode", "roll_amp", "roll_phase", "steer_amp", "steer_phase"] {
            h.push(format!("{c}_{k}"));
        }
    }
    for k in 1..=extra {
        h.push(format!("re_extra_{k}"));
        h.push(format!("im_extra_{k}"));
    }
    h
}

/// One CSV row of a speed point (columns of [`eigen_sweep_csv_header`]).
pub fn eigen_point_csv_row(p: &EigenPoint) -> Vec<String> {
    let mut row = vec![num(p.v)];
    for k in ordered_indices(p) {
        let (s, m, shape) = (p.eigenvalues[k], p.modes[k], mode_shape(&p.eigenvectors[k]));
        row.push(num(s.re));
        row.push(num(s.im));
        row.push(m.name().to_string());
        row.push(num(shape.roll_amplitude));
        row.push(num(shape.roll_phase));
        row.push(num(shape.steer_amplitude));
        row.push(num(shape.steer_phase));
    }
    for z in &p.extra_eigenvalues {
        row.push(num(z.re));
        row.push(num(z.im));
    }
    row
}

/// Write an eigen sweep as CSV (see the module docs for the columns).
pub fn write_eigen_sweep_csv<W: Write>(w: W, sweep: &EigenSweep) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    let extra = sweep.points.first().map_or(0, |p| p.extra_eigenvalues.len());
    wr.write_record(eigen_sweep_csv_header_with(extra))?;
    for p in &sweep.points {
        wr.write_record(eigen_point_csv_row(p))?;
    }
    wr.flush()?;
    Ok(())
}

/// Machine-readable formats of [`stream_eigen_sweep`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamFormat {
    /// CSV, as [`write_eigen_sweep_csv`].
    Csv,
    /// JSON, as [`eigen_sweep_json`] (one point object per line).
    Json,
}

/// Speeds per block of [`stream_eigen_sweep`].
pub const STREAM_BLOCK: usize = 4096;

/// Compute and write the eigen sweep of `c` at the `n` speeds `speed(0)`,
/// ..., `speed(n - 1)` block by block ([`STREAM_BLOCK`] speeds at a time), so
/// memory stays flat in `n` (issue 10, point 5). Labels are the same as those
/// of one [`bikedyn_runtime::eigen::eigen_sweep`] over all speeds, because every speed
/// is labelled by continuation from the bicycle's anchor speed, independent
/// of the other requested speeds.
pub fn stream_eigen_sweep(
    c: &dyn bikedyn_runtime::eigen::LinearBicycle,
    n: usize,
    speed: impl Fn(usize) -> f64,
    format: StreamFormat,
    w: &mut dyn Write,
) -> Result<(), BoxError> {
    stream_eigen_sweep_with(c, n, speed, format, w, None)
}

/// The standard deviations `[re, im]` (1/s) of a point's eigenvalues given
/// at its speed in the order given ([`ordered_indices`]).
pub type EigenSpread<'a> = &'a dyn Fn(f64, &[[f64; 2]]) -> Vec<[f64; 2]>;

/// [`stream_eigen_sweep`] with each eigenvalue's standard deviation from
/// `spread`: CSV columns `re_sd_k, im_sd_k` after the others, JSON
/// `"standard_deviations": [[re, im], ..]` in the order of `eigenvalues`.
pub fn stream_eigen_sweep_with(
    c: &dyn bikedyn_runtime::eigen::LinearBicycle,
    n: usize,
    speed: impl Fn(usize) -> f64,
    format: StreamFormat,
    w: &mut dyn Write,
    spread: Option<EigenSpread<'_>>,
) -> Result<(), BoxError> {
    let sd_of = |p: &EigenPoint| -> Option<Vec<[f64; 2]>> {
        let f = spread?;
        let z: Vec<[f64; 2]> = ordered_indices(p)
            .iter()
            .map(|&k| [p.eigenvalues[k].re, p.eigenvalues[k].im])
            .collect();
        Some(f(p.v, &z))
    };
    // Fail before writing anything if the bicycle has no eigen analysis;
    // the first point also says how many extra eigenvalues each row has.
    let extra = if n > 0 {
        bikedyn_runtime::eigen::eigen_sweep_of(c, &[speed(0)])?.points[0]
            .extra_eigenvalues
            .len()
    } else {
        0
    };
    let for_each_point = |f: &mut dyn FnMut(usize, &EigenPoint) -> Result<(), BoxError>| -> Result<(), BoxError> {
        let mut speeds = Vec::with_capacity(STREAM_BLOCK.min(n));
        let mut start = 0;
        while start < n {
            let end = (start + STREAM_BLOCK).min(n);
            speeds.clear();
            speeds.extend((start..end).map(&speed));
            let sweep = bikedyn_runtime::eigen::eigen_sweep_of(c, &speeds)?;
            for (i, p) in sweep.points.iter().enumerate() {
                f(start + i, p)?;
            }
            start = end;
        }
        Ok(())
    };
    match format {
        StreamFormat::Csv => {
            let mut wr = csv::Writer::from_writer(w);
            let mut header = eigen_sweep_csv_header_with(extra);
            if spread.is_some() {
                for k in 1..=4 {
                    header.push(format!("re_sd_{k}"));
                    header.push(format!("im_sd_{k}"));
                }
            }
            wr.write_record(header)?;
            for_each_point(&mut |_, p| {
                let mut row = eigen_point_csv_row(p);
                for sd in sd_of(p).unwrap_or_default() {
                    row.push(num(sd[0]));
                    row.push(num(sd[1]));
                }
                Ok(wr.write_record(row)?)
            })?;
            wr.flush()?;
        }
        StreamFormat::Json => {
            w.write_all(b"[")?;
            for_each_point(&mut |i, p| {
                w.write_all(if i == 0 { b"\n  " } else { b",\n  " })?;
                let mut v = eigen_point_json(p);
                if let Some(sd) = sd_of(p) {
                    let sd: Vec<[Option<f64>; 2]> = sd.iter().map(|s| s.map(|x| x.is_finite().then_some(x))).collect();
                    v["standard_deviations"] = json!(sd);
                }
                serde_json::to_writer(&mut *w, &v)?;
                Ok(())
            })?;
            w.write_all(b"\n]\n")?;
        }
    }
    Ok(())
}

/// Atomically save an eigen sweep as CSV.
pub fn save_eigen_sweep_csv(path: impl AsRef<Path>, sweep: &EigenSweep) -> Result<(), OutputError> {
    write_atomic(path, |w| write_eigen_sweep_csv(w, sweep))
}

/// Atomically save an eigen sweep as pretty-printed JSON.
pub fn save_eigen_sweep_json(path: impl AsRef<Path>, sweep: &EigenSweep) -> Result<(), OutputError> {
    save_json(path, &eigen_sweep_json(sweep))
}

/// Atomically save a JSON value (pretty-printed, trailing newline).
pub fn save_json(path: impl AsRef<Path>, value: &Value) -> Result<(), OutputError> {
    write_atomic(path, |w| -> Result<(), BoxError> {
        serde_json::to_writer_pretty(&mut *w, value)?;
        w.write_all(b"\n")?;
        Ok(())
    })
}

/// Aligned plain-text table of an eigen sweep for terminals. Columns are
/// titled by mode when every row has the same mode sequence, else `lambda_k`
/// with the mode in each cell.
pub fn format_eigen_table(sweep: &EigenSweep) -> String {
    let rows: Vec<[(Complex<f64>, Mode); 4]> = sweep.points.iter().map(ordered_eigenvalues).collect();
    let uniform = rows.windows(2).all(|w| w[0].iter().zip(&w[1]).all(|(a, b)| a.1 == b.1));
    let mut header = vec!["v (m/s)".to_string()];
    for k in 0..4 {
        header.push(match rows.first() {
            Some(r) if uniform => r[k].1.name().to_string(),
            _ => format!("lambda_{} (1/s)", k + 1),
        });
    }
    // A model with extra states: its other modes after the bicycle's.
    let extra = sweep
        .points
        .iter()
        .map(|p| p.extra_eigenvalues.len())
        .max()
        .unwrap_or(0);
    header.extend((1..=extra).map(|k| format!("extra {k}")));
    let complex = |s: &Complex<f64>| {
        format!(
            "{} {} {}i",
            format_fixed(s.re, 5, true),
            if s.im < 0.0 { '-' } else { '+' },
            format_fixed(s.im.abs(), 5, false)
        )
    };
    let body = sweep
        .points
        .iter()
        .zip(&rows)
        .map(|(p, r)| {
            let mut row = vec![format!("{:.3}", p.v)];
            for (s, m) in r {
                let z = complex(s);
                row.push(if uniform { z } else { format!("{z} {}", m.name()) });
            }
            row.extend(p.extra_eigenvalues.iter().map(complex));
            row
        })
        .collect::<Vec<_>>();
    format_table(&header, &body)
}

/// Aligned plain-text table: a header, a rule, then the rows; every column is
/// right-aligned to its widest entry, two spaces between columns.
pub fn format_table(header: &[String], rows: &[Vec<String>]) -> String {
    let ncol = header.len().max(rows.iter().map(Vec::len).max().unwrap_or(0));
    let mut width = vec![0usize; ncol];
    for r in std::iter::once(header).chain(rows.iter().map(Vec::as_slice)) {
        for (k, s) in r.iter().enumerate() {
            width[k] = width[k].max(s.chars().count());
        }
    }
    let mut out = String::new();
    let line = |r: &[String], out: &mut String| {
        let cells: Vec<String> = (0..ncol)
            .map(|k| {
                let s = r.get(k).map(String::as_str).unwrap_or("");
                format!("{s:>w$}", w = width[k])
            })
            .collect();
        let _ = writeln!(out, "{}", cells.join("  ").trim_end());
    };
    line(header, &mut out);
    let rule: Vec<String> = width.iter().map(|w| "-".repeat(*w)).collect();
    line(&rule, &mut out);
    for r in rows {
        line(r, &mut out);
    }
    out
}

// ---------------------------------------------------------------------------
// Parameter sweeps and stability maps

const CELL_COLUMNS: [&str; 10] = [
    "weave_speed",
    "capsize_speed",
    "weave_real_pair_merge",
    "stable_width",
    "stable_lo",
    "stable_hi",
    "n_stable_intervals",
    "stable_intervals",
    "open_ended",
    "error",
];

fn num(x: f64) -> String {
    format!("{x:?}")
}

fn opt(x: Option<f64>) -> String {
    x.map(num).unwrap_or_default()
}

fn cell_fields(c: &CellResult) -> Vec<String> {
    match c {
        Ok(s) => {
            let first = s.first_stable_interval();
            vec![
                opt(s.weave_speed),
                opt(s.capsize_speed),
                opt(s.weave_real_pair_merge),
                num(s.stable_width),
                opt(first.map(|i| i[0])),
                opt(first.map(|i| i[1])),
                s.stable_intervals.len().to_string(),
                s.stable_intervals
                    .iter()
                    .map(|[a, b]| format!("{}:{}", num(*a), num(*b)))
                    .collect::<Vec<_>>()
                    .join(";"),
                s.open_ended.to_string(),
                String::new(),
            ]
        }
        Err(e) => {
            let mut v = vec![String::new(); CELL_COLUMNS.len()];
            v[CELL_COLUMNS.len() - 1] = e.to_string();
            v
        }
    }
}

fn cell_json(c: &CellResult) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    match c {
        Ok(s) => {
            m.insert("weave_speed".into(), json!(s.weave_speed));
            m.insert("capsize_speed".into(), json!(s.capsize_speed));
            m.insert("weave_real_pair_merge".into(), json!(s.weave_real_pair_merge));
            m.insert("stable_intervals".into(), json!(s.stable_intervals));
            m.insert("stable_width".into(), json!(s.stable_width));
            m.insert("open_ended".into(), json!(s.open_ended));
            if s.least_stable_real_part.is_some() {
                m.insert("least_stable_real_part".into(), json!(s.least_stable_real_part));
            }
            m.insert("error".into(), Value::Null);
        }
        Err(e) => {
            for k in [
                "weave_speed",
                "capsize_speed",
                "weave_real_pair_merge",
                "stable_intervals",
                "stable_width",
                "open_ended",
            ] {
                m.insert(k.into(), Value::Null);
            }
            m.insert("error".into(), json!({"stage": e.stage, "message": e.message}));
        }
    }
    m
}

/// Header of the parameter-sweep CSV: the parameter's name, then the cell columns.
pub fn parameter_sweep_csv_header(s: &ParameterSweep) -> Vec<String> {
    std::iter::once(s.param.name.clone())
        .chain(CELL_COLUMNS.iter().map(|c| c.to_string()))
        .collect()
}

/// Write a parameter sweep as CSV, one row per parameter value.
pub fn write_parameter_sweep_csv<W: Write>(w: W, s: &ParameterSweep) -> Result<(), csv::Error> {
    write_parameter_sweep_csv_with(w, s, &[])
}

/// More columns of a sweep, one value per point (empty in CSV and `null`
/// in JSON where `None`): e.g. the critical speeds' standard deviations.
pub type SweepColumns<'a> = &'a [(&'a str, Vec<Option<f64>>)];

/// [`write_parameter_sweep_csv`] with `extra` columns after the others.
pub fn write_parameter_sweep_csv_with<W: Write>(
    w: W,
    s: &ParameterSweep,
    extra: SweepColumns<'_>,
) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    let mut header = parameter_sweep_csv_header(s);
    header.extend(extra.iter().map(|(name, _)| name.to_string()));
    wr.write_record(header)?;
    for (i, (p, c)) in s.param.values.iter().zip(&s.points).enumerate() {
        let mut row = vec![num(*p)];
        row.extend(cell_fields(c));
        row.extend(
            extra
                .iter()
                .map(|(_, v)| v.get(i).copied().flatten().map_or(String::new(), num)),
        );
        wr.write_record(&row)?;
    }
    wr.flush()?;
    Ok(())
}

/// JSON value of a parameter sweep:
/// `{"parameter": name, "speed_range": [lo, hi], "points": [{"value": p, ...cell fields}]}`.
pub fn parameter_sweep_json(s: &ParameterSweep) -> Value {
    parameter_sweep_json_with(s, &[])
}

/// [`parameter_sweep_json`] with `extra` fields in each point.
pub fn parameter_sweep_json_with(s: &ParameterSweep, extra: SweepColumns<'_>) -> Value {
    let points: Vec<Value> = s
        .param
        .values
        .iter()
        .zip(&s.points)
        .enumerate()
        .map(|(i, (p, c))| {
            let mut m = serde_json::Map::new();
            m.insert("value".into(), json!(p));
            m.extend(cell_json(c));
            for (name, v) in extra {
                m.insert(name.to_string(), json!(v.get(i).copied().flatten()));
            }
            Value::Object(m)
        })
        .collect();
    json!({"parameter": s.param.name, "speed_range": s.speed_range, "points": points})
}

/// Header of the stability-map CSV: x name, y name, `i`, `j`, then the cell columns.
pub fn stability_map_csv_header(m: &StabilityMap) -> Vec<String> {
    [m.x.name.clone(), m.y.name.clone(), "i".into(), "j".into()]
        .into_iter()
        .chain(CELL_COLUMNS.iter().map(|c| c.to_string()))
        .collect()
}

/// Write a stability map as long-format CSV, one row per cell, row-major.
pub fn write_stability_map_csv<W: Write>(w: W, m: &StabilityMap) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(stability_map_csv_header(m))?;
    write_stability_map_csv_rows(&mut wr, m, 0)?;
    wr.flush()?;
    Ok(())
}

/// The rows of `m` (no header), its first-parameter index counted from
/// `i0`: a map computed a row (one value of the first parameter) at a time
/// is streamed as one CSV, the same as [`write_stability_map_csv`] gives
/// for the whole map.
pub fn write_stability_map_csv_rows<W: Write>(
    wr: &mut csv::Writer<W>,
    m: &StabilityMap,
    i0: usize,
) -> Result<(), csv::Error> {
    let (nx, ny) = m.shape();
    for i in 0..nx {
        for j in 0..ny {
            let Some(c) = m.cell(i, j) else { continue };
            let mut row = vec![
                num(m.x.values[i]),
                num(m.y.values[j]),
                (i0 + i).to_string(),
                j.to_string(),
            ];
            row.extend(cell_fields(c));
            wr.write_record(&row)?;
        }
    }
    Ok(())
}

/// JSON value of a stability map:
/// `{"x": {"name", "values"}, "y": {..}, "speed_range": [lo, hi], "layout": "row-major",
///   "cells": [{"i", "j", "x", "y", ...cell fields}]}`.
pub fn stability_map_json(m: &StabilityMap) -> Value {
    let (nx, ny) = m.shape();
    let mut cells = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            let Some(c) = m.cell(i, j) else { continue };
            let mut o = serde_json::Map::new();
            o.insert("i".into(), json!(i));
            o.insert("j".into(), json!(j));
            o.insert("x".into(), json!(m.x.values[i]));
            o.insert("y".into(), json!(m.y.values[j]));
            o.extend(cell_json(c));
            cells.push(Value::Object(o));
        }
    }
    json!({
        "x": m.x,
        "y": m.y,
        "speed_range": m.speed_range,
        "layout": "row-major: cells[i * len(y.values) + j] is (x.values[i], y.values[j])",
        "cells": cells,
    })
}

/// Atomically save a parameter sweep as CSV.
pub fn save_parameter_sweep_csv(path: impl AsRef<Path>, s: &ParameterSweep) -> Result<(), OutputError> {
    write_atomic(path, |w| write_parameter_sweep_csv(w, s))
}

/// Atomically save a parameter sweep as JSON.
pub fn save_parameter_sweep_json(path: impl AsRef<Path>, s: &ParameterSweep) -> Result<(), OutputError> {
    save_json(path, &parameter_sweep_json(s))
}

/// Atomically save a stability map as CSV.
pub fn save_stability_map_csv(path: impl AsRef<Path>, m: &StabilityMap) -> Result<(), OutputError> {
    write_atomic(path, |w| write_stability_map_csv(w, m))
}

/// Atomically save a stability map as JSON.
pub fn save_stability_map_json(path: impl AsRef<Path>, m: &StabilityMap) -> Result<(), OutputError> {
    save_json(path, &stability_map_json(m))
}

fn short(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into())
}

fn summary_row(c: &CellResult) -> Vec<String> {
    match c {
        Ok(s) => vec![
            short(s.weave_speed),
            short(s.capsize_speed),
            format!("{:.4}{}", s.stable_width, if s.open_ended { "+" } else { "" }),
            if s.stable_intervals.is_empty() {
                "-".into()
            } else {
                s.stable_intervals
                    .iter()
                    .map(|[a, b]| format!("[{a:.3}, {b:.3}]"))
                    .collect::<Vec<_>>()
                    .join(" ")
            },
        ],
        Err(e) => vec!["-".into(), "-".into(), "-".into(), format!("error: {e}")],
    }
}

/// A parameter column's header with its unit, `c (m)`, from the symbol's
/// description (`describe`: the model's parameter docs, which end in the
/// unit, as `"steer-axis viscous damping coefficient (N m s/rad)"`, or the
/// thesis and benchmark descriptions); a name with no description as it is.
fn parameter_header(symbol: &str, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let doc = describe(symbol);
    match doc.as_deref().and_then(bikedyn_runtime::model::unit_of) {
        Some(u) => format!("{symbol} ({u})"),
        None => symbol.to_string(),
    }
}

/// The description of a parameter symbol: the thesis and benchmark sets'
/// descriptions, else the doc of the parameter in `model` (effect
/// parameters such as `c_steer`). Each ends in its unit in parentheses.
pub fn describe_parameter(symbol: &str, model: Option<&bikedyn_runtime::registry::ModelInfo>) -> Option<String> {
    use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
    BenchmarkParameters::describe(symbol)
        .or_else(|| ThesisParameters::describe(symbol))
        .or_else(|| model?.parameter(symbol).map(|p| p.doc))
        .map(str::to_string)
}

const SUMMARY_HEADER: [&str; 4] = ["v_w (m/s)", "v_c (m/s)", "stable width (m/s)", "stable intervals (m/s)"];

/// Aligned plain-text table of a parameter sweep (`+` marks a width cut off
/// at `speed_max`). `describe` gives a parameter's description ending in its
/// unit in parentheses, for the header (see [`describe_parameter`]).
pub fn format_parameter_table(s: &ParameterSweep, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let header: Vec<String> = std::iter::once(parameter_header(&s.param.name, describe))
        .chain(SUMMARY_HEADER.iter().map(|h| h.to_string()))
        .collect();
    let rows: Vec<Vec<String>> = s
        .param
        .values
        .iter()
        .zip(&s.points)
        .map(|(p, c)| {
            std::iter::once(format_fixed(*p, 6, false))
                .chain(summary_row(c))
                .collect()
        })
        .collect();
    format_table(&header, &rows)
}

/// Aligned plain-text table of a stability map, one line per cell
/// (row-major); `describe` as in [`format_parameter_table`].
pub fn format_stability_map_table(m: &StabilityMap, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let header: Vec<String> = [
        parameter_header(&m.x.name, describe),
        parameter_header(&m.y.name, describe),
    ]
    .into_iter()
    .chain(SUMMARY_HEADER.iter().map(|h| h.to_string()))
    .collect();
    let (nx, ny) = m.shape();
    let mut rows = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            if let Some(c) = m.cell(i, j) {
                let mut r = vec![
                    format_fixed(m.x.values[i], 6, false),
                    format_fixed(m.y.values[j], 6, false),
                ];
                r.extend(summary_row(c));
                rows.push(r);
            }
        }
    }
    format_table(&header, &rows)
}

// ---------------------------------------------------------------------------
// Printed numbers (issue 10, point 8). JSON and CSV keep full precision
// (shortest round-trip representation); text for people has a fixed number
// of significant digits and never a negative zero.

/// The entries of a matrix with `digits` significant digits relative to its
/// largest entry (all entries get the same number of decimals, so columns
/// align and an entry that is zero to that precision prints as zero without
/// a sign); scientific notation when the largest entry is below `1e-4` or at
/// least `1e12`.
pub fn format_matrix_entries(entries: &[f64], digits: usize) -> Vec<String> {
    let max = entries.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if max == 0.0 || !max.is_finite() {
        return entries.iter().map(|&x| format_significant(x, digits)).collect();
    }
    let e = max.log10().floor() as i32;
    if !(-4..12).contains(&e) {
        return entries.iter().map(|&x| format_significant(x, digits)).collect();
    }
    let decimals = (digits as i32 - 1 - e).max(0) as usize;
    entries.iter().map(|&x| format_fixed(x, decimals, false)).collect()
}

/// The stability of a bicycle as JSON (`bikedyn stability --json`, the
/// Python package's `Bicycle.stability()`): weave, capsize and real-pair
/// merge speeds (m/s), the self-stable intervals and every crossing of a
/// mode's real part through zero, with its frequency (rad/s).
pub fn stability_json(name: &str, c: &bikedyn_runtime::eigen::CriticalSpeeds) -> serde_json::Value {
    serde_json::json!({
        "bike": name,
        "weave_speed": c.weave_speed,
        "capsize_speed": c.capsize_speed,
        "weave_real_pair_merge_speed": c.weave_real_pair_merge,
        "stable_intervals": c.stable_intervals,
        "crossings": c.crossings.iter().map(|x| serde_json::json!({
            "speed": x.speed, "mode": x.mode.name(), "direction": format!("{:?}", x.direction).to_lowercase(),
            "kind": match x.kind { bikedyn_runtime::eigen::CrossingKind::RealRoot => "real_root", bikedyn_runtime::eigen::CrossingKind::ComplexPair => "complex_pair" },
            "frequency": x.frequency
        })).collect::<Vec<_>>(),
    })
}
