//! A set of run folders as the runtime's set pipeline takes it: a
//! [`RunSource`] that reads the calibration folder and each run folder when
//! the pipeline asks for it, so that the runtime decides how many runs are
//! in memory at once (one).

use super::read::{read_run, read_run_orientations};
use super::InputError;
use bikedyn_runtime::experiment::angles::Calibration;
use bikedyn_runtime::experiment::records::{ImuRecord, ThesisRun};
use bikedyn_runtime::experiment::{self, PipelineOptions, RunReport, RunSource};
use std::path::{Path, PathBuf};

/// The run folders of a set and its calibration folder.
#[derive(Clone, Copy, Debug)]
pub struct RunFolders<'a> {
    /// Run folders, in the order their results are given.
    pub runs: &'a [PathBuf],
    /// Calibration folder.
    pub calibration: &'a Path,
}

impl RunSource for RunFolders<'_> {
    type Error = InputError;

    fn run_count(&self) -> usize {
        self.runs.len()
    }

    fn calibration_path(&self) -> &Path {
        self.calibration
    }

    fn run_path(&self, i: usize) -> &Path {
        &self.runs[i]
    }

    fn calibration(&self) -> Result<ThesisRun, InputError> {
        Ok(read_run(self.calibration)?)
    }

    fn orientations(&self, i: usize) -> Result<(ImuRecord, ImuRecord), InputError> {
        let (_, frame, handlebar) = read_run_orientations(&self.runs[i])?;
        Ok((frame, handlebar))
    }

    fn run(&self, i: usize) -> Result<ThesisRun, InputError> {
        Ok(read_run(&self.runs[i])?)
    }
}

/// Process the set of run folders `runs` with the calibration folder
/// `calibration` (the runtime's `process_set` on [`RunFolders`]): the
/// calibration and its steer axis, then each run's report, or why it was
/// skipped (a reading problem naming file and line, or a failed check).
/// `progress` is called after each run.
pub fn process_set(
    runs: &[PathBuf],
    calibration: &Path,
    opt: &PipelineOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<(Calibration, Vec<Result<RunReport, InputError>>), InputError> {
    experiment::process_set(&RunFolders { runs, calibration }, opt, progress)
}
