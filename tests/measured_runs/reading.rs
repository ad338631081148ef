//! Reading measured runs: each kind of corrupt input is an error naming
//! the file and the line, tolerable variants are read, a corrupt run of a
//! set leaves the others processed, and `run.toml` and the file sizes are
//! bounded (`bikedyn::runs`, `bikedyn::capped`).

use crate::common::*;
use bikedyn::report::experiment::synth::write_run;
use bikedyn::runs::{self, ReadError};
use bikedyn::runtime::experiment::{
    records::RunKind,
    synth::{rest_trajectory, ResponseSpec, SensorModel},
    PipelineOptions,
};
use std::path::{Path, PathBuf};

/// A fresh folder `name` of this group's scratch folder.
fn tmp(name: &str) -> PathBuf {
    let d = scratch("measured-reading").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn noop() {}

fn write_good_run(dir: &Path, seed: u64) {
    let spec = ResponseSpec {
        after_kick: 2.0,
        ..ResponseSpec::default()
    };
    write_run(
        dir,
        "r",
        RunKind::Run,
        &spec.trajectory(),
        &SensorModel::default(),
        seed,
    )
    .unwrap();
}

fn replace_line(path: &Path, line: usize, text: &str) {
    let s = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = s.lines().map(str::to_string).collect();
    lines[line - 1] = text.to_string();
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
}

/// Issue 8, point 1: each kind of corrupt input gives an error naming the
/// file and the line; tolerable variants are read.
#[test]
fn corrupt_inputs_are_reported_with_file_and_line() {
    let base = tmp("corrupt");
    let good = base.join("good");
    write_good_run(&good, 3);
    let copy = |name: &str| -> PathBuf {
        let d = base.join(name);
        std::fs::create_dir_all(&d).unwrap();
        for f in ["imu_frame.csv", "imu_handlebar.csv", "speed_switch.csv", "run.toml"] {
            std::fs::copy(good.join(f), d.join(f)).unwrap();
        }
        d
    };
    let frame = |d: &Path| d.join("imu_frame.csv");
    let row = |d: &Path, line: usize| -> String {
        std::fs::read_to_string(frame(d))
            .unwrap()
            .lines()
            .nth(line - 1)
            .unwrap()
            .to_string()
    };
    let err = |d: &Path| runs::read_run(d).unwrap_err();
    let msg_has = |e: &ReadError, file: &str, line: usize| {
        let m = e.to_string();
        assert!(m.contains(file) && m.contains(&format!(":{line}:")), "message `{m}`");
    };

    // Malformed row.
    let d = copy("malformed");
    replace_line(&frame(&d), 10, "0.0750,0.5,0.5");
    let e = err(&d);
    assert!(matches!(e, ReadError::FieldCount { line: 10, .. }), "{e}");
    msg_has(&e, "imu_frame.csv", 10);
    let d = copy("notnumber");
    replace_line(&frame(&d), 11, "0.0833,abc,0.1,0.1,0.1");
    assert!(matches!(err(&d), ReadError::NotANumber { line: 11, .. }));
    // NaN.
    let d = copy("nan");
    replace_line(&frame(&d), 12, "0.0917,NaN,0.1,0.1,0.1");
    let e = err(&d);
    assert!(matches!(e, ReadError::NotFinite { line: 12, .. }), "{e}");
    msg_has(&e, "imu_frame.csv", 12);
    // Non-monotonic and duplicated time stamps.
    let d = copy("backwards");
    let r = row(&d, 20);
    replace_line(&frame(&d), 21, &r.replacen(r.split(',').next().unwrap(), "0.0100", 1));
    assert!(matches!(err(&d), ReadError::NonMonotonicTime { line: 21, .. }));
    let d = copy("duplicate");
    let r = row(&d, 30);
    replace_line(&frame(&d), 31, &r);
    let e = err(&d);
    assert!(
        matches!(
            e,
            ReadError::DuplicateTime {
                line: 31,
                previous_line: 30,
                ..
            }
        ),
        "{e}"
    );
    // Quaternion far from unit norm; near it, normalised and counted.
    let d = copy("quatnorm");
    let t = row(&d, 40).split(',').next().unwrap().to_string();
    replace_line(&frame(&d), 40, &format!("{t},0.9,0.9,0.1,0.1"));
    let e = err(&d);
    assert!(matches!(e, ReadError::QuaternionNorm { line: 40, .. }), "{e}");
    let d = copy("quatnear");
    let f: Vec<f64> = row(&d, 41).split(',').map(|x| x.parse().unwrap()).collect();
    replace_line(
        &frame(&d),
        41,
        &format!(
            "{},{},{},{},{}",
            f[0],
            f[1] * 1.01,
            f[2] * 1.01,
            f[3] * 1.01,
            f[4] * 1.01
        ),
    );
    let run = runs::read_run(&d).unwrap();
    assert_eq!(run.frame.renormalised, 1);
    assert!((run.frame.q[39].norm() - 1.0).abs() < 1e-12);
    // Gaps: reported, not an error; the windows never span them.
    let d = copy("gap");
    let s = std::fs::read_to_string(frame(&d)).unwrap();
    let kept: Vec<&str> = s
        .lines()
        .enumerate()
        .filter(|(i, _)| !(100..110).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(frame(&d), kept.join("\n") + "\n").unwrap();
    let s = std::fs::read_to_string(d.join("imu_handlebar.csv")).unwrap();
    let kept: Vec<&str> = s
        .lines()
        .enumerate()
        .filter(|(i, _)| !(100..110).contains(i))
        .map(|(_, l)| l)
        .collect();
    std::fs::write(d.join("imu_handlebar.csv"), kept.join("\n") + "\n").unwrap();
    let run = runs::read_run(&d).unwrap();
    assert_eq!(run.frame.gaps.len(), 1);
    assert_eq!(run.frame.gaps[0].line, 101);
    // Truncated file (cut in the middle of the last row, no line end).
    let d = copy("truncated");
    let s = std::fs::read_to_string(frame(&d)).unwrap();
    std::fs::write(frame(&d), &s[..s.len() - 20]).unwrap();
    let e = err(&d);
    assert!(matches!(e, ReadError::Truncated { .. }), "{e}");
    assert!(e.to_string().contains("imu_frame.csv"));
    // Tolerated: CRLF, comments, blank lines, header variant, BOM.
    let d = copy("variants");
    let s = std::fs::read_to_string(frame(&d)).unwrap();
    let body: String = s.lines().skip(1).map(|l| format!("{l}\r\n")).collect();
    std::fs::write(
        frame(&d),
        format!("\u{feff}# exported by the logger\r\nTime, qw, qx, qy, qz\r\n\r\n{body}"),
    )
    .unwrap();
    let run = runs::read_run(&d).unwrap();
    assert_eq!(run.frame.t.len(), runs::read_run(&good).unwrap().frame.t.len());

    // A corrupt run in a set is reported; the others are processed.
    let set = tmp("set");
    write_run(
        &set.join("calibration"),
        "calibration",
        RunKind::Calibration,
        &rest_trajectory(8.0, ResponseSpec::default().frame_pitch, 0.2),
        &SensorModel::default(),
        5,
    )
    .unwrap();
    write_good_run(&set.join("run01"), 6);
    write_good_run(&set.join("run02"), 7);
    replace_line(&set.join("run02/imu_handlebar.csv"), 50, "nan,nan");
    let inputs = runs::classify(&set).unwrap();
    let runs::Input::Set { runs, calibration } = &inputs[0] else {
        panic!("a set")
    };
    let (_, out) = runs::process_set(runs, calibration.as_ref().unwrap(), &PipelineOptions::default(), &noop).unwrap();
    assert!(out[0].is_ok());
    let e = out[1].as_ref().unwrap_err().to_string();
    assert!(e.contains("run02") && e.contains("imu_handlebar.csv:50:"), "{e}");
}

/// Counts, rates and file names read from `run.toml` are bounded and kept
/// inside the run folder; oversized inputs are refused before memory grows.
#[test]
fn run_metadata_is_bounded_and_kept_inside_the_run() {
    use bikedyn::capped::read_capped;
    use bikedyn::runs::read_meta;
    let good = std::fs::read_to_string(example_set().join("run01/run.toml")).unwrap();
    let dir = tmp("bounded_meta");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("run.toml");
    std::fs::write(&path, &good).unwrap();
    assert!(read_meta(&path).is_ok());
    for (from, to, says) in [
        ("magnets = 9", "magnets = 1e9", "from 1 to 1000"),
        ("magnets = 9", "magnets = 2.5", "whole number"),
        ("rate_hz = 120", "rate_hz = 1e300", "sample rate"),
        (
            "files = [\"imu_frame.csv\", \"imu_handlebar.csv\"]",
            "files = [\"/etc/passwd\", \"imu_handlebar.csv\"]",
            "inside the run folder",
        ),
        (
            "file = \"speed_switch.csv\"",
            "file = \"../run02/speed_switch.csv\"",
            "inside the run folder",
        ),
        (
            "wheel_circumference_m = 2.0",
            "wheel_circumference_m = 2000.0",
            "circumference",
        ),
    ] {
        assert!(good.contains(from), "{from}");
        std::fs::write(&path, good.replacen(from, to, 1)).unwrap();
        let err = read_meta(&path).unwrap_err().to_string();
        assert!(err.contains("run.toml") && err.contains(says), "{to}: {err}");
    }
    // An endless device is refused as no file, not read whole; a file above
    // the cap is refused from its size (sparse: no data in it).
    if cfg!(unix) {
        let err = read_capped(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(err.to_string().contains("device"), "{err}");
    }
    let big = dir.join("big.csv");
    std::fs::File::create(&big).unwrap().set_len(3 << 20).unwrap();
    let err = read_capped(&big, 1 << 20).unwrap_err();
    assert!(err.to_string().contains("more than the 1 MiB"), "{err}");
}
