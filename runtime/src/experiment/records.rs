//! The records of a measured run, as the pipeline takes them: a
//! thesis-style run's two IMU orientation records and its reed switch's
//! voltages with its `run.toml` ([`ThesisRun`]), and a TU Delft
//! steer-by-wire kick log ([`TudelftLog`]).
//!
//! Reading them from files is the application's (`bikedyn::runs`: the
//! folder format of `shared/data/FORMAT.md`, its tolerances and its errors
//! naming file and line); the numerics start from these records, whatever
//! made them.

use nalgebra::UnitQuaternion;
use std::path::PathBuf;

/// Whether a folder is a run or the calibration.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum RunKind {
    /// Launch and kick.
    Run,
    /// Bicycle held upright at rest, handlebar straight.
    Calibration,
}

/// The parts of `run.toml` the pipeline uses.
#[derive(Clone, Debug)]
pub struct RunMeta {
    /// Run name.
    pub name: String,
    /// Run or calibration.
    pub kind: RunKind,
    /// Nominal `t_imu - t_daq` (s).
    pub nominal_offset_s: f64,
    /// IMU rate (Hz).
    pub imu_rate_hz: f64,
    /// IMU files (frame first, handlebar second).
    pub imu_files: [String; 2],
    /// DAQ rate (Hz).
    pub switch_rate_hz: f64,
    /// Reed-switch file.
    pub switch_file: String,
    /// Magnets on the wheel.
    pub magnets: usize,
    /// Circumference of the wheel carrying the magnets (m).
    pub wheel_circumference_m: f64,
    /// Supply (and closed-switch) voltage (V), if given.
    pub supply_v: Option<f64>,
}

/// A stretch where samples are missing: never interpolated across.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Gap {
    /// Last time stamp before the gap (s).
    pub start: f64,
    /// First time stamp after the gap (s).
    pub end: f64,
    /// Line of the first row after the gap.
    pub line: usize,
}

/// Orientation record of one IMU.
#[derive(Clone, Debug)]
pub struct ImuRecord {
    /// Source file.
    pub path: PathBuf,
    /// Time stamps on the IMU clock (s).
    pub t: Vec<f64>,
    /// Sensor orientation, `v_global = R(q) v_sensor`, global Z up.
    pub q: Vec<UnitQuaternion<f64>>,
    /// Rows whose quaternion the reader normalised (its norm off from 1 by
    /// more than the printed digits' rounding, yet close enough to be a
    /// rounding of the logger's and not a corrupt row).
    pub renormalised: usize,
    /// Missing stretches.
    pub gaps: Vec<Gap>,
    /// Line of each row.
    pub lines: Vec<usize>,
}

/// Voltage record of the reed switch.
#[derive(Clone, Debug)]
pub struct SwitchRecord {
    /// Source file.
    pub path: PathBuf,
    /// Time stamps on the DAQ clock (s).
    pub t: Vec<f64>,
    /// Switch output (V).
    pub volts: Vec<f64>,
    /// Missing stretches.
    pub gaps: Vec<Gap>,
}

/// A thesis-style run folder, read and checked.
#[derive(Clone, Debug)]
pub struct ThesisRun {
    /// The folder.
    pub dir: PathBuf,
    /// `run.toml`.
    pub meta: RunMeta,
    /// Frame (body 3) IMU.
    pub frame: ImuRecord,
    /// Handlebar (body 4) IMU.
    pub handlebar: ImuRecord,
    /// Reed switch.
    pub switch: SwitchRecord,
}

/// A TU Delft steer-by-wire kick log.
#[derive(Clone, Debug)]
pub struct TudelftLog {
    /// Source file.
    pub path: PathBuf,
    /// Data-row index times 0.01 s (first data row at 0).
    pub t: Vec<f64>,
    /// Forward speed (m/s).
    pub speed: Vec<f64>,
    /// Roll (lean) angle (rad).
    pub roll: Vec<f64>,
    /// Roll rate from the IMU gyro (rad/s).
    pub roll_rate: Vec<f64>,
    /// Handlebar angle (rad).
    pub steer: Vec<f64>,
    /// Fork angle (rad).
    pub fork: Vec<f64>,
    /// Line of each row.
    pub lines: Vec<usize>,
}
