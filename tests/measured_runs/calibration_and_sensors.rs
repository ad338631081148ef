//! A set's calibration and its runs' two sensor records are checked before
//! anything is fitted with them: a calibration record cut short or rotated,
//! and one sensor's record given for both, are refused with the reason
//! (they gave weave eigenvalues from a wrong mounting, with exit 0).

use crate::common::*;
use std::path::{Path, PathBuf};

/// The example set's calibration and run03 in a fresh set folder.
fn mini(name: &str) -> PathBuf {
    let d = scratch("calibration-and-sensors").join(name);
    let _ = std::fs::remove_dir_all(&d);
    for r in ["calibration", "run03"] {
        std::fs::create_dir_all(d.join(r)).unwrap();
        for f in std::fs::read_dir(example_set().join(r)).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, d.join(r).join(f.file_name().unwrap())).unwrap();
        }
    }
    d
}

/// Rewrite every data row of both IMU files of `run` with `f(row, line)`
/// (rows from 0; `None` drops the row).
fn rewrite_imu(run: &Path, f: impl Fn(usize, &str) -> Option<String>) {
    for sensor in ["imu_frame.csv", "imu_handlebar.csv"] {
        let p = run.join(sensor);
        let s = std::fs::read_to_string(&p).unwrap();
        let mut lines = s.lines();
        let mut out = format!("{}\n", lines.next().unwrap());
        for l in lines.enumerate().filter_map(|(i, l)| f(i, l)) {
            out += &l;
            out += "\n";
        }
        std::fs::write(&p, out).unwrap();
    }
}

/// `fit` fails (exit 1) with every message in `expected`, fitting nothing.
fn refused(set: &Path, expected: &[&str]) {
    let out = bikedyn(&["fit", set.to_str().unwrap(), "--json"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for e in expected {
        assert!(err.contains(e), "{e}: {err}");
    }
    assert_eq!(stdout_json(&out).as_array().unwrap().len(), 0, "{err}");
}

/// A calibration record cut to its first 1 or 10 rows (none of them
/// settled) used to give a misalignment from noise and pass: a record
/// settled for less than 2 s is refused, saying how long it is.
#[test]
fn a_calibration_record_cut_short_is_refused() {
    for rows in [1usize, 10] {
        let d = mini(&format!("cut-{rows}"));
        rewrite_imu(&d.join("calibration"), |i, l| (i < rows).then(|| l.to_string()));
        refused(&d, &["calibration record is settled for", &format!("({rows} samples)")]);
    }
}

/// A calibration whose sensors are turned half a turn about their z axes
/// (q -> q * Rz(180 deg)) gave a frame misalignment of -155 deg about z,
/// used without a word: a misalignment beyond 30 deg is refused, with its
/// angles and what to check.
#[test]
fn a_calibration_rotated_half_a_turn_is_refused() {
    let d = mini("rotated");
    rewrite_imu(&d.join("calibration"), |_, l| {
        let v: Vec<f64> = l.split(',').map(|x| x.trim().parse().unwrap()).collect();
        // (w, x, y, z) * (0, 0, 0, 1) = (-z, y, -x, w).
        Some(format!("{:.4},{:.7},{:.7},{:.7},{:.7}", v[0], -v[4], v[3], -v[2], v[1]))
    });
    refused(&d, &["mounting misalignment comes out at", "calibration"]);
    // The set as committed passes: its sensors are a few degrees off.
    let ok = bikedyn(&["fit", mini("as-committed").to_str().unwrap()]);
    assert!(ok.status.success(), "{}", text(&ok.stderr));
}

/// One sensor's record given for both, by naming one file twice in
/// run.toml or by a copy under the other's name, read as a run with its
/// handlebar held straight: both are refused, naming the files.
#[test]
fn one_sensor_record_given_for_both_is_refused() {
    let d = mini("named-twice");
    let toml = d.join("run03").join("run.toml");
    let s = std::fs::read_to_string(&toml).unwrap();
    let s = s.replace(
        "files = [\"imu_frame.csv\", \"imu_handlebar.csv\"]",
        "files = [\"imu_frame.csv\", \"imu_frame.csv\"]",
    );
    std::fs::write(&toml, s).unwrap();
    refused(&d, &["run.toml", "names \"imu_frame.csv\" twice"]);

    let d = mini("copied");
    let run = d.join("run03");
    std::fs::copy(run.join("imu_frame.csv"), run.join("imu_handlebar.csv")).unwrap();
    refused(&d, &["imu_handlebar.csv: the same orientations as", "imu_frame.csv"]);
}
