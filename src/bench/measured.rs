//! The measured-run pipeline of `bikedyn fit` timed on one thread: a
//! thesis-style run end to end (read, angles, speed, clock, kick, fits) and
//! a TU Delft log.

use super::{scratch, BenchError, BenchOptions};
use crate::runs::{read_run, read_tudelft};
use bikedyn_report::experiment::synth::write_run;
use bikedyn_runtime::experiment::angles::{median, Calibration};
use bikedyn_runtime::experiment::records::RunKind;
use bikedyn_runtime::experiment::synth::{rest_trajectory, ResponseSpec, SensorModel};
use bikedyn_runtime::experiment::{self, PipelineOptions};
use serde::Serialize;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Times of the measured-run pipeline, each the median of its repetitions.
#[derive(Clone, Debug, Serialize)]
pub struct MeasuredRunFigures {
    /// Repetitions of the calibration and the run (the log's: at most 10).
    pub repetitions: usize,
    /// The calibration run's misalignment estimate, its reading excluded (ms).
    pub calibration_ms: f64,
    /// The thesis-style run timed: dev run01 of `../shared` when present,
    /// else a synthetic run written to a temporary folder (removed after).
    pub run: PathBuf,
    /// That run end to end, reading included (ms).
    pub run_ms: f64,
    /// The TU Delft log (only with `../shared`), or `null`.
    pub log: Option<LogTiming>,
}

/// A TU Delft log end to end.
#[derive(Clone, Debug, Serialize)]
pub struct LogTiming {
    /// The log file.
    pub path: PathBuf,
    /// Kicks found in it.
    pub kicks: usize,
    /// Reading and processing it (ms).
    pub ms: f64,
}

/// Time the pipeline on one run and one log (see [`MeasuredRunFigures`]).
pub fn measured_runs(opts: &BenchOptions) -> Result<MeasuredRunFigures, BenchError> {
    let reps = if opts.quick { 5 } else { 30 };
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    let mut written = None;
    let (run_dir, cal_dir, log) = if root.join("data/dev/run01").is_dir() {
        (
            root.join("data/dev/run01"),
            root.join("data/dev/calibration"),
            Some(root.join("realdata/tudelft_sbw_kicks/logs/eigen_normal_sil6.5n2_16.2kph.log")),
        )
    } else {
        let d = scratch("bikedyn-bench")?;
        written = Some(d.clone());
        let spec = ResponseSpec::default();
        let s = SensorModel::default();
        write_run(
            &d.join("calibration"),
            "calibration",
            RunKind::Calibration,
            &rest_trajectory(10.0, spec.frame_pitch, 0.3),
            &s,
            1,
        )?;
        write_run(&d.join("run01"), "run01", RunKind::Run, &spec.trajectory(), &s, 2)?;
        (d.join("run01"), d.join("calibration"), None)
    };
    let figures = time_pipeline(reps, run_dir, &cal_dir, log);
    if let Some(d) = written {
        // A scratch folder of this process only: its loss is no error.
        let _ = std::fs::remove_dir_all(d);
    }
    figures
}

fn time_pipeline(
    reps: usize,
    run_dir: PathBuf,
    cal_dir: &Path,
    log: Option<PathBuf>,
) -> Result<MeasuredRunFigures, BenchError> {
    let opt = PipelineOptions::default();
    let cal_run = read_run(cal_dir)?;
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        black_box(Calibration::estimate(&cal_run, opt.frame_pitch));
        times.push(t.elapsed().as_secs_f64());
    }
    let calibration_ms = 1e3 * median(&times);
    let cal = Calibration::estimate(&cal_run, opt.frame_pitch);
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        let run = read_run(&run_dir)?;
        black_box(experiment::process_thesis_run(&run, &cal, &opt));
        times.push(t.elapsed().as_secs_f64());
    }
    let run_ms = 1e3 * median(&times);
    let log = match log.filter(|l| l.is_file()) {
        Some(path) => {
            let mut times = Vec::new();
            let mut kicks = 0;
            for _ in 0..reps.min(10) {
                let t = Instant::now();
                let l = read_tudelft(&path)?;
                kicks = experiment::process_tudelft(&l, &opt).kicks.len();
                times.push(t.elapsed().as_secs_f64());
            }
            Some(LogTiming {
                path,
                kicks,
                ms: 1e3 * median(&times),
            })
        }
        None => None,
    };
    Ok(MeasuredRunFigures {
        repetitions: reps,
        calibration_ms,
        run: run_dir,
        run_ms,
        log,
    })
}
