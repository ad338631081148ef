//! Measured runs read from their files: a path given to `fit` or
//! `identify` walked into sets of run folders and logs ([`classify`]),
//! each run folder and log read and checked into the runtime's records
//! ([`read`]), and a set's runs handed to the runtime's set pipeline one at
//! a time ([`process_set`]). What the numerics make of the records (the
//! calibration and its checks, angles, speed, kicks, fits) is the
//! runtime's (`bikedyn_runtime::experiment`); the files are the
//! application's, as the parameter files are (`crate::bicycle::files`).
//!
//! From a run folder to measured eigenvalues: [`classify_reporting`] ->
//! [`process_set`] ([`RunFolders`], a `RunSource`) -> the runtime's
//! `process_set` and `process_thesis_run`; a log: [`read_tudelft`] -> the
//! runtime's `process_tudelft`. `crate::fit` runs both on its inputs.

mod classify;
pub mod read;
mod set;

pub use classify::{classify, classify_reporting, Input};
pub use read::{
    read_imu, read_meta, read_run, read_run_orientations, read_switch, read_tudelft, ReadError, MAX_SPEED_M_S,
};
pub use set::{process_set, RunFolders};

use bikedyn_runtime::experiment::RunError;
use std::path::PathBuf;

/// Why an input (a path given, a set's calibration, a run or a log) could
/// not be used: a reading problem, a failed check of the runtime's set
/// pipeline, or a path that is no run.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// A reading problem (file and line named).
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The set's calibration or the run fails the pipeline's checks (the
    /// run named).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A thesis-style run without a calibration run.
    #[error("{}: no calibration run (expected {} or --calibration)", run.display(), expected.display())]
    NoCalibration {
        /// The run.
        run: PathBuf,
        /// Where it was looked for.
        expected: PathBuf,
    },
    /// The named path is neither a run, a set nor a log.
    #[error("{}: not a run folder (run.toml), a set of runs, or a log file", path.display())]
    NotARun {
        /// The path.
        path: PathBuf,
    },
    /// The named folder could not be listed (missing, or no permission).
    #[error("{}: cannot be read: {source}", path.display())]
    Unreadable {
        /// The path.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// A folder of a set that holds a run's files but no readable
    /// `run.toml`: it is left out, and said so.
    #[error("{}: left out of the set: {why} (a run folder needs its run.toml beside the data files)", path.display())]
    NoRunToml {
        /// The folder.
        path: PathBuf,
        /// `run.toml` missing, or not a file.
        why: &'static str,
    },
}
