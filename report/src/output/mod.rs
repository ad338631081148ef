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

mod atomic;
mod eigen;
mod sweep;
mod table;

pub use atomic::*;
pub use eigen::*;
pub use sweep::*;
pub use table::*;

// The number formatters live in the runtime (its error messages use them);
// tables and callers reach them here.
pub use bikedyn_runtime::number_text::{format_fixed, format_significant};
