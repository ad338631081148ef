//! The folder walk: what a path given on the command line stands for (a
//! set of runs with its calibration, a single run, a TU Delft log or a
//! folder of logs), told from the files in it.

use super::read::read_meta;
use super::InputError;
use bikedyn_runtime::experiment::records::RunKind;
use std::path::{Path, PathBuf};

/// What a path on the command line stands for.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// A thesis-style set: runs and the calibration folder.
    Set {
        /// Run folders.
        runs: Vec<PathBuf>,
        /// Calibration folder, if present.
        calibration: Option<PathBuf>,
    },
    /// A TU Delft log file.
    Log(PathBuf),
}

fn is_run_dir(p: &Path) -> bool {
    p.join("run.toml").is_file()
}

fn kind_of(p: &Path) -> Option<RunKind> {
    read_meta(&p.join("run.toml")).ok().map(|m| m.kind)
}

/// Classify a command-line path: a set folder (all its runs; calibration =
/// `calibration/` or the folder whose run.toml says so), a run folder (the
/// calibration beside it), a log file, or a folder of log files.
pub fn classify(path: &Path) -> Result<Vec<Input>, InputError> {
    classify_reporting(path).map(|(inputs, _)| inputs)
}

/// [`classify`], with the folders of a set left out because they look like
/// runs (they hold IMU or speed-switch CSV files, or a `run.toml` that is
/// no file) but have no
/// `run.toml` to read ([`InputError::NoRunToml`]): a run is never dropped
/// without a word. Other folders (notes, plots) are not runs and pass
/// unremarked.
pub fn classify_reporting(path: &Path) -> Result<(Vec<Input>, Vec<InputError>), InputError> {
    if path.is_file() {
        return Ok((vec![Input::Log(path.to_path_buf())], vec![]));
    }
    if is_run_dir(path) {
        let cal = path.parent().map(|p| p.join("calibration")).filter(|c| is_run_dir(c));
        if kind_of(path) == Some(RunKind::Calibration) {
            return Ok((
                vec![Input::Set {
                    runs: vec![],
                    calibration: Some(path.to_path_buf()),
                }],
                vec![],
            ));
        }
        return Ok((
            vec![Input::Set {
                runs: vec![path.to_path_buf()],
                calibration: cal,
            }],
            vec![],
        ));
    }
    let rd = std::fs::read_dir(path).map_err(|source| match source.kind() {
        // A file that is not a regular one (a device) or a folder whose
        // run.toml is no file: no run, not an I/O fault.
        std::io::ErrorKind::NotADirectory => InputError::NotARun {
            path: path.to_path_buf(),
        },
        _ => InputError::Unreadable {
            path: path.to_path_buf(),
            source,
        },
    })?;
    let mut entries: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    entries.sort();
    let mut runs = Vec::new();
    let mut calibration = None;
    let mut logs = Vec::new();
    let mut left_out = Vec::new();
    for e in entries {
        if is_run_dir(&e) {
            let named = e.file_name().is_some_and(|n| n == "calibration");
            if named || (calibration.is_none() && kind_of(&e) == Some(RunKind::Calibration)) {
                calibration = Some(e);
            } else {
                runs.push(e);
            }
        } else if e.is_file() && e.extension().is_some_and(|x| x == "log") {
            logs.push(Input::Log(e));
        } else if let Some(why) = looks_like_a_run(&e) {
            left_out.push(InputError::NoRunToml { path: e, why });
        }
    }
    if runs.is_empty() && logs.is_empty() && calibration.is_none() {
        return Err(left_out.into_iter().next().unwrap_or(InputError::NotARun {
            path: path.to_path_buf(),
        }));
    }
    let mut out = Vec::new();
    if !runs.is_empty() || calibration.is_some() {
        // A calibration alone is listed (and skipped with its reason by
        // `fit`), not "not a run folder".
        out.push(Input::Set { runs, calibration });
    }
    out.extend(logs);
    Ok((out, left_out))
}

/// Why a folder of a set without a readable `run.toml` looks like a run
/// that was meant: its `run.toml` is something other than a file, or it
/// holds IMU or speed-switch records. Hidden folders (bikedyn's own temporaries) are not.
fn looks_like_a_run(p: &Path) -> Option<&'static str> {
    let hidden = p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'));
    if hidden || !p.is_dir() {
        return None;
    }
    let toml = p.join("run.toml");
    if toml.exists() {
        return Some("its run.toml is not a file");
    }
    // A run's records by their usual names (FORMAT.md); other CSV files
    // (a synthetic set's `truth/` trajectories) are no run.
    let has_records = std::fs::read_dir(p).ok()?.filter_map(|e| e.ok()).any(|e| {
        let name = e.file_name().to_string_lossy().to_ascii_lowercase();
        name.ends_with(".csv") && (name.starts_with("imu") || name.starts_with("speed_switch"))
    });
    has_records.then_some("it holds a run's records (IMU or speed-switch CSV) but no run.toml")
}
