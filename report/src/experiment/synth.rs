//! The files of a synthetic measured run (`shared/data/FORMAT.md`):
//! `imu_frame.csv`, `imu_handlebar.csv`, `speed_switch.csv` and `run.toml`,
//! from the sensor readings of `bikedyn_runtime::experiment::synth`.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use bikedyn_runtime::experiment::synth::{
    record_run, ImuSample, RunKind, SensorModel, SwitchSample, SynthError, SynthTruth,
};
use bikedyn_runtime::simulate::trajectory::Trajectory;

/// Why writing a run failed.
#[derive(Debug, thiserror::Error)]
pub enum WriteRunError {
    /// A file or the run's directory could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// Path.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// The readings could not be made (an unusable trajectory).
    #[error(transparent)]
    Record(#[from] SynthError),
}

fn write(path: &Path, text: &str) -> Result<(), WriteRunError> {
    std::fs::write(path, text).map_err(|source| WriteRunError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// An IMU file: time with 4 decimals, quaternion components with 7.
fn imu_csv(readings: &[ImuSample]) -> String {
    let mut csv = String::from("time_s,q0,q1,q2,q3\n");
    for r in readings {
        let q = &r.orientation;
        let _ = writeln!(csv, "{:.4},{:.7},{:.7},{:.7},{:.7}", r.time, q.w, q.i, q.j, q.k);
    }
    csv
}

/// The reed-switch file: time and volts with 3 decimals.
fn switch_csv(readings: &[SwitchSample]) -> String {
    let mut csv = String::from("time_s,volts\n");
    for r in readings {
        let _ = writeln!(csv, "{:.3},{:.3}", r.time, r.volts);
    }
    csv
}

/// Write `imu_frame.csv`, `imu_handlebar.csv`, `speed_switch.csv` and
/// `run.toml` of one run into `dir` (created), following FORMAT.md, from the
/// angles of `traj` (the reed switch follows its wheel rotation; its speed
/// series is not read). Returns what the pipeline should recover.
pub fn write_run(
    dir: &Path,
    name: &str,
    kind: RunKind,
    traj: &Trajectory,
    sensors: &SensorModel,
    seed: u64,
) -> Result<SynthTruth, WriteRunError> {
    let recording = record_run(name, kind, traj, sensors, seed)?;
    std::fs::create_dir_all(dir).map_err(|source| WriteRunError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    write(&dir.join("imu_frame.csv"), &imu_csv(&recording.frame))?;
    write(&dir.join("imu_handlebar.csv"), &imu_csv(&recording.handlebar))?;
    write(&dir.join("speed_switch.csv"), &switch_csv(&recording.speed_switch))?;
    let nm = sensors.magnets.max(1);
    let kind_s = match kind {
        RunKind::Run => "run",
        RunKind::Calibration => "calibration",
    };
    let toml = format!(
        "# synthetic run written by bikedyn (see shared/data/FORMAT.md)\n\
         name = \"{name}\"\nkind = \"{kind_s}\"\n\
         bicycle = \"synthetic\"\nparameters = \"synthetic\"\n\n\
         [clocks]\nnominal_offset_s = {:.2}\n\n\
         [imu]\nrate_hz = {}\nfiles = [\"imu_frame.csv\", \"imu_handlebar.csv\"]\n\n\
         [speed_switch]\nrate_hz = {}\nfile = \"speed_switch.csv\"\nmagnets = {nm}\nwheel = \"rear\"\n\
         wheel_circumference_m = {}\nsupply_v = {}\nclosing_distance_mm = {}\nsensor_set = \"synthetic\"\n",
        sensors.nominal_offset,
        sensors.imu_rate_hz,
        sensors.daq_rate_hz,
        sensors.wheel_circumference,
        sensors.supply_v,
        sensors.closing_distance * 1000.0
    );
    write(&dir.join("run.toml"), &toml)?;
    Ok(recording.truth)
}
