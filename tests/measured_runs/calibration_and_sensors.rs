//! A set's calibration and its runs' two sensor records are checked before
//! anything is fitted with them: a calibration record cut short or rotated,
//! and one sensor's record given for both, are refused with the reason
//! (they gave weave eigenvalues from a wrong mounting, with exit 0).

use crate::common::*;
use std::path::{Path, PathBuf};

/// The example set's calibration and run03 in a fresh set folder.
fn mini(name: &str) -> PathBuf {
    example_runs("calibration-and-sensors", name, &["calibration", "run03"])
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

/// The example set copied whole into a fresh folder, without the runs in
/// `leave_out`.
pub(super) fn whole_set(name: &str, leave_out: &[&str]) -> PathBuf {
    let d = scratch("calibration-and-sensors").join(name);
    let _ = std::fs::remove_dir_all(&d);
    for entry in std::fs::read_dir(example_set()).unwrap() {
        let src = entry.unwrap().path();
        let run = src.file_name().unwrap().to_str().unwrap().to_string();
        if !src.is_dir() || leave_out.contains(&run.as_str()) {
            continue;
        }
        std::fs::create_dir_all(d.join(&run)).unwrap();
        for f in std::fs::read_dir(&src).unwrap() {
            let f = f.unwrap().path();
            if f.is_file() {
                std::fs::copy(&f, d.join(&run).join(f.file_name().unwrap())).unwrap();
            }
        }
    }
    d
}

/// `fit --json` of a set: exit status, stderr and the fits by run name.
pub(super) fn fits_by_run(
    set: &Path,
) -> (
    Option<i32>,
    String,
    std::collections::BTreeMap<String, serde_json::Value>,
) {
    let out = bikedyn(&["fit", set.to_str().unwrap(), "--json"]);
    let fits = stdout_json(&out)
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let run = Path::new(f["run"].as_str().unwrap())
                .file_name()
                .unwrap()
                .to_str()
                .unwrap()
                .to_string();
            let mut f = f.clone();
            f["run"] = serde_json::Value::Null;
            (run, f)
        })
        .collect();
    (out.status.code(), text(&out.stderr), fits)
}

/// A run whose two IMU files hold noise alone (random orientations) used
/// to turn the set's steer-axis estimate: three good runs lost their kicks
/// and the misalignment came out at -60 deg. The steer axis now comes from
/// the runs that show one and agree on it, so every other run's fits are
/// bit for bit those of the set without the noise run, which is reported
/// as skipped with its reason (exit 1).
#[test]
fn a_run_of_noise_leaves_the_other_runs_fits_unchanged() {
    let d = whole_set("with-noise-run", &[]);
    let noise = d.join("run07");
    std::fs::create_dir_all(&noise).unwrap();
    for f in std::fs::read_dir(d.join("run03")).unwrap() {
        let f = f.unwrap().path();
        std::fs::copy(&f, noise.join(f.file_name().unwrap())).unwrap();
    }
    let toml = noise.join("run.toml");
    let s = std::fs::read_to_string(&toml)
        .unwrap()
        .replace("name = \"run03\"", "name = \"run07\"");
    std::fs::write(&toml, s).unwrap();
    // Random unit quaternions from a fixed linear congruential sequence.
    let state = std::cell::Cell::new(0x2545_f491_4f6c_dd1du64);
    let uniform = || {
        state.set(
            state
                .get()
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        );
        (state.get() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    rewrite_imu(&noise, |_, l| {
        let t = l.split(',').next().unwrap();
        let q: Vec<f64> = (0..4).map(|_| uniform()).collect();
        let n = q.iter().map(|x| x * x).sum::<f64>().sqrt();
        Some(format!(
            "{t},{:.7},{:.7},{:.7},{:.7}",
            q[0] / n,
            q[1] / n,
            q[2] / n,
            q[3] / n
        ))
    });
    let (status, err, with_noise) = fits_by_run(&d);
    let (clean_status, clean_err, clean) = fits_by_run(&whole_set("clean", &[]));
    assert_eq!(clean_status, Some(0), "{clean_err}");
    assert_eq!(status, Some(1), "{err}");
    assert!(err.contains("run07: no kick found"), "{err}");
    assert_eq!(clean.len(), 6, "{clean_err}");
    assert_eq!(with_noise, clean, "{err}");
}

/// A run whose frame and handlebar files are swapped turns its handlebar
/// "sensor" about an axis several degrees from the steer axis of the other
/// runs (by the two mountings' difference), and each of its files tilts
/// against gravity as the calibration's other sensor does. It used to be
/// accepted silently and to shift the other runs' weaves through the
/// pooled steer axis. It is now set aside with both findings and what to
/// do, and the other runs' fits are bit for bit those of the set without
/// it (exit 1: a run was skipped).
#[test]
fn a_run_with_its_sensor_files_swapped_is_set_aside() {
    let d = whole_set("swapped", &[]);
    let run = d.join("run03");
    std::fs::rename(run.join("imu_frame.csv"), run.join("swap.csv")).unwrap();
    std::fs::rename(run.join("imu_handlebar.csv"), run.join("imu_frame.csv")).unwrap();
    std::fs::rename(run.join("swap.csv"), run.join("imu_handlebar.csv")).unwrap();
    let (status, err, swapped) = fits_by_run(&d);
    assert_eq!(status, Some(1), "{err}");
    let line = err
        .lines()
        .find(|l| l.contains("run03"))
        .unwrap_or_else(|| panic!("run03 not named:\n{err}"));
    assert!(line.starts_with("skipped:") && line.contains("set aside"), "{line}");
    assert!(
        line.contains("look swapped") && line.contains("swap them back"),
        "{line}"
    );
    assert!(!err.contains("steer axis apart"), "no run is merely flagged:\n{err}");
    let (status, without_err, without) = fits_by_run(&whole_set("without-run03", &["run03"]));
    assert_eq!(status, Some(0), "{without_err}");
    assert_eq!(without.len(), 5);
    assert_eq!(swapped, without, "{err}");
}

/// A run whose own steer axis lies apart from the set's while its files
/// tilt as their names say (a sensor knocked on its mount, or a good run's
/// axis estimate far out: one oracle control run lay 8.5 deg out) is left
/// out of the set's axis and fitted, with a warning that names it and what
/// to check. Here the example set's run03 has its handlebar sensor turned
/// 8 deg about its own x axis for the whole run: the other runs' fits are
/// bit for bit those of the set without run03, and run03 is fitted.
#[test]
fn a_run_whose_steer_axis_lies_apart_is_fitted_with_a_warning() {
    let d = whole_set("knocked", &[]);
    let run = d.join("run03");
    rotate_orientations(&run.join("imu_handlebar.csv"), |_, q, _| {
        q * nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), 8f64.to_radians())
    });
    let (_, err, mut knocked) = fits_by_run(&d);
    let warning = err
        .lines()
        .find(|l| l.contains("run03") && l.contains("steer axis apart"))
        .unwrap_or_else(|| panic!("no steer-axis warning for run03:\n{err}"));
    assert!(warning.starts_with("warning:"), "{warning}");
    assert!(warning.contains("sat on their mounts"), "{warning}");
    assert!(!err.contains("look swapped"), "{err}");
    assert!(knocked.remove("run03").is_some(), "run03 is fitted:\n{err}");
    let (status, without_err, without) = fits_by_run(&whole_set("without-run03-knocked", &["run03"]));
    assert_eq!(status, Some(0), "{without_err}");
    assert_eq!(knocked, without, "{err}");
}

/// A logger that keeps recording after the wheel stops writes the reed
/// switch's level for as long as it runs, and a converter at rest repeats
/// one value exactly. Such seconds after run04 broke its speed:
/// - at the open level, the record's robust spread became zero, so noise a
///   step above the open level was taken for the closed one; the pulses
///   came from noise and the kick was lost ("no kick found");
/// - with a magnet stopped at the switch (the closed level repeated), the
///   record's median, taken as the open level, was the closed one; the
///   speed came out at 18-27 m/s.
/// The noise is now at least a 10-bit converter's step over the record's
/// span (between its tenth lowest and tenth highest samples, so a rest of
/// any length leaves it), a record that sits mostly closed finds its open
/// level below the span's middle, and the run's fit is what it was, after
/// twenty seconds at rest or a thousand.
#[test]
fn a_switch_record_that_goes_on_at_rest_keeps_the_run_as_it_was() {
    let others = ["run01", "run02", "run03", "run05", "run06"];
    let fit_run04 = |set: &Path| {
        let (status, err, fits) = fits_by_run(set);
        assert_eq!(status, Some(0), "{err}");
        fits["run04"].clone()
    };
    let reference = fit_run04(&whole_set("run04-as-recorded", &others));
    for (name, level, rest_s) in [
        ("open", "last", 20),
        ("closed", "highest", 20),
        ("open-long", "last", 1000),
    ] {
        let d = whole_set(&format!("run04-at-rest-{name}"), &others);
        let switch = d.join("run04").join("speed_switch.csv");
        let text = std::fs::read_to_string(&switch).unwrap();
        let rows: Vec<(f64, &str)> = text
            .lines()
            .skip(1)
            .map(|l| {
                let (t, v) = l.split_once(',').unwrap();
                (t.parse().unwrap(), v)
            })
            .collect();
        let t_end = rows.last().unwrap().0;
        let volts = if level == "last" {
            rows.last().unwrap().1
        } else {
            rows.iter()
                .max_by(|a, b| a.1.parse::<f64>().unwrap().total_cmp(&b.1.parse().unwrap()))
                .unwrap()
                .1
        };
        // At 1 kHz; a thousand seconds are 99 % of the record.
        let mut more = text.clone();
        for k in 1..=rest_s * 1000 {
            more += &format!("{:.3},{volts}\n", t_end + 0.001 * k as f64);
        }
        std::fs::write(&switch, more).unwrap();
        let extended = fit_run04(&d);
        let (a, b) = (
            reference["weave"].as_array().unwrap(),
            extended["weave"].as_array().unwrap(),
        );
        let se = reference["weave_stderr"].as_array().unwrap();
        for k in 0..2 {
            let (x, y, s) = (a[k].as_f64().unwrap(), b[k].as_f64().unwrap(), se[k].as_f64().unwrap());
            assert!(
                (x - y).abs() < 0.01 * s,
                "at rest {name}: weave {a:?} as recorded, {b:?} with the rest after"
            );
        }
        assert_eq!(
            reference["speed_interval"], extended["speed_interval"],
            "at rest {name}"
        );
    }
}
