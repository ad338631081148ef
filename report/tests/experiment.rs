//! Measured runs (issue 8): the pipeline on synthetic runs with known truth,
//! on `shared/data/dev`, on the TU Delft kick logs, and on corrupt inputs.
//! Here rather than in the runtime because the synthetic runs are written
//! by the report layer's `write_run` and read back by the runtime.

use bikedyn_report::experiment::synth::write_run;
use bikedyn_runtime::experiment::angles::AngleMethod;
use bikedyn_runtime::experiment::{
    self,
    read::{self, ReadError, RunKind},
    synth::{rest_trajectory, ResponseSpec, SensorModel},
    PipelineOptions,
};
use nalgebra::Rotation3;
use std::path::{Path, PathBuf};

/// `../../shared/<sub>` relative to the crate, or `None` (with a skip
/// message) when the shared data is not checked out.
fn shared(sub: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared").join(sub);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: {} not found", p.display());
        None
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bikedyn-exp-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn noop() {}

/// Three synthetic runs (weave eigenvalues, speeds, clock offsets differ)
/// and a calibration run, written with the default (dev-like) sensors.
fn synthetic_set(dir: &Path) -> Vec<(ResponseSpec, experiment::synth::SynthTruth)> {
    let base = SensorModel::default();
    let pitch = ResponseSpec::default().frame_pitch;
    write_run(
        &dir.join("calibration"),
        "calibration",
        RunKind::Calibration,
        &rest_trajectory(10.0, pitch, 0.7),
        &base,
        1,
    )
    .unwrap();
    let cases = [
        ([-1.5, 6.0], 5.0, 1.42),
        ([-0.8, 4.5], 4.0, 1.15),
        ([-2.0, 9.0], 6.3, 1.55),
    ];
    cases
        .iter()
        .enumerate()
        .map(|(i, &(weave, v0, offset))| {
            let spec = ResponseSpec {
                weave,
                launch_speed: v0,
                ..ResponseSpec::default()
            };
            let sensors = SensorModel {
                clock_offset: offset,
                ..base.clone()
            };
            let mut truth = write_run(
                &dir.join(format!("run{:02}", i + 1)),
                &format!("run{:02}", i + 1),
                RunKind::Run,
                &spec.trajectory(),
                &sensors,
                10 + i as u64,
            )
            .unwrap();
            truth.kick_time = Some(spec.kick_time());
            truth.weave = Some(weave);
            (spec, truth)
        })
        .collect()
}

/// Issue 8: on synthetic runs with known truth the pipeline recovers the
/// mounting misalignments, the kick, the weave eigenvalue, the speed and
/// the magnet spacing, and its clock offset covers the true one.
///
/// Tolerances: misalignment 1.5 deg (the rotation about the vertical comes
/// from the steer axis seen in ~700 samples of steer up to 0.08 rad against
/// 0.003 rad noise per sensor; observed 0.8 deg); kick time 0.03 s (under
/// four IMU samples); eigenvalue 5 % of its modulus (the synthetic response
/// carries a slow capsize drift that eq. 94's constant does not model;
/// observed at most 1.5 %); speed at the kick 1 % (the profile averages two
/// wheel turns, and the synthetic deceleration is linear); magnet spacing
/// 0.1 % of the circumference, 2 mm (the spacing errors are 0.15 %;
/// observed at most 0.05 %); clock
/// offset within 2.5 reported standard errors.
#[test]
fn synthetic_runs_recover_misalignment_kick_eigenvalue_speed_and_clock() {
    let dir = tmp("synth");
    let truths = synthetic_set(&dir);
    let runs: Vec<PathBuf> = (1..=3).map(|i| dir.join(format!("run{i:02}"))).collect();
    let opt = PipelineOptions {
        frame_pitch: ResponseSpec::default().frame_pitch,
        ..PipelineOptions::default()
    };
    let (cal, reports) = experiment::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
    let e = |a: [f64; 3]| Rotation3::from_euler_angles(a[0], a[1], a[2]);
    let (tf, th) = (&truths[0].1.frame_misalignment, &truths[0].1.handlebar_misalignment);
    let err_f = cal.frame.angle_to(&e(*tf)).to_degrees();
    let err_h = cal.handlebar.angle_to(&e(*th)).to_degrees();
    println!("misalignment errors: frame {err_f:.3} deg, handlebar {err_h:.3} deg");
    assert!(cal.yaw_from_steer_axis);
    assert!(err_f < 1.5 && err_h < 1.5, "misalignment errors {err_f} {err_h} deg");
    for ((spec, truth), rep) in truths.iter().zip(&reports) {
        let rep = rep.as_ref().unwrap();
        assert_eq!(rep.kicks.len(), 1, "{}: one kick", truth.name);
        let k = &rep.kicks[0];
        let f = k.chosen_fit().expect("a fit");
        let off = rep.clock_offset.unwrap();
        let sp = rep.speed.as_ref().unwrap();
        let tk = truth.kick_time.unwrap();
        let (v, _) = sp.at(tk - truth.clock_offset).unwrap();
        let w = truth.weave.unwrap();
        println!(
            "{}: kick {:.3} (true {tk:.3}), weave {:.3}{:+.3}i +- {:.3},{:.3} (true {:.3}{:+.3}i), {}, r2 {:.4}, \
             window {:?}, offset {:.3} +- {:.3} from data: {} (true {:.3}), v {:.3} (true {:.3})",
            truth.name,
            k.kick_time,
            f.eigenvalue[0],
            f.eigenvalue[1],
            f.eigenvalue_stderr[0],
            f.eigenvalue_stderr[1],
            w[0],
            w[1],
            f.form.name(),
            f.r2,
            k.window,
            off.value,
            off.stderr,
            off.from_data,
            truth.clock_offset,
            v,
            spec.speed(tk)
        );
        assert!((k.kick_time - tk).abs() < 0.03);
        let modulus = w[0].hypot(w[1]);
        assert!(
            (f.eigenvalue[0] - w[0]).abs() < 0.05 * modulus,
            "{}: real part",
            truth.name
        );
        assert!(
            (f.eigenvalue[1] - w[1]).abs() < 0.05 * modulus,
            "{}: imaginary part",
            truth.name
        );
        assert!(f.r2 > 0.95);
        assert!((v - spec.speed(tk)).abs() < 0.01 * spec.speed(tk));
        assert!(k.mean_speed > k.speed_interval[0] && k.mean_speed < k.speed_interval[1]);
        assert!(
            (off.value - truth.clock_offset).abs() < 2.5 * off.stderr,
            "clock offset"
        );
        // Magnet spacing, up to which magnet came first.
        let c = 2.010;
        let pos = &truth.magnet_positions;
        let nm = pos.len();
        let true_spacing: Vec<f64> = (0..nm)
            .map(|i| ((pos[(i + 1) % nm] - pos[i]).rem_euclid(c)) / c)
            .collect();
        let (est, _) = rep.magnet_spacing.as_ref().unwrap();
        let best = (0..nm)
            .map(|shift| {
                (0..nm)
                    .map(|i| (est[i] - true_spacing[(i + shift) % nm]).abs())
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min);
        println!("  magnet spacing: largest error {:.5} of the circumference", best);
        assert!(best < 0.001);
    }
}

/// Issue 8, point 2: the two angle methods against the true roll and steer
/// of a synthetic run (dev-like sensors). The direct method is the default:
/// its steer error must be below the thesis method's, and its roll as good.
#[test]
fn angle_methods_compared_on_a_synthetic_run() {
    let dir = tmp("angles");
    let truths = synthetic_set(&dir);
    let opt = PipelineOptions {
        frame_pitch: ResponseSpec::default().frame_pitch,
        ..PipelineOptions::default()
    };
    let runs: Vec<PathBuf> = (1..=3).map(|i| dir.join(format!("run{i:02}"))).collect();
    let (cal, _) = experiment::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
    let mut rms = [[0.0; 2]; 2];
    let mut count = 0.0;
    for (i, (spec, _)) in truths.iter().enumerate() {
        let run = read::read_run(&runs[i]).unwrap();
        let traj = spec.trajectory();
        let d = experiment::angles::angles(&run, &cal, AngleMethod::Direct);
        let th = experiment::angles::angles(&run, &cal, AngleMethod::Thesis);
        for k in 0..d.t.len() {
            if d.t[k] < cal.settled_from {
                continue;
            }
            let j = ((d.t[k] * spec.rate_hz).round() as usize).min(traj.t.len() - 1);
            for (m, a) in [&d, &th].iter().enumerate() {
                rms[m][0] += (a.roll[k] - traj.roll[j]).powi(2);
                rms[m][1] += (a.steer[k] - traj.steer[j]).powi(2);
            }
            count += 1.0;
        }
    }
    let r = |x: f64| (x / count).sqrt().to_degrees();
    println!(
        "rms error (deg): direct roll {:.3} steer {:.3}; thesis roll {:.3} steer {:.3}",
        r(rms[0][0]),
        r(rms[0][1]),
        r(rms[1][0]),
        r(rms[1][1])
    );
    assert!(r(rms[0][1]) < r(rms[1][1]));
    assert!(r(rms[0][0]) < 1.2 * r(rms[1][0]) + 0.05);
}

/// Issue 8: runs made from the linearized benchmark bicycle (all modes in
/// the response, speed decaying slowly) give back its frozen-speed weave
/// eigenvalue at the window's mean speed within 5 % of its modulus (the
/// capsize mode's slow drift and the 0.1 m/s^2 deceleration are not in
/// eq. 94; observed below 3 %).
#[test]
fn linear_model_runs_give_the_models_weave_eigenvalue() {
    use bikedyn_runtime::closed_form::meijaard_canonical;
    use bikedyn_runtime::experiment::{compare::predicted_weave, synth::linear_model_trajectory};
    use bikedyn_runtime::parameters::BenchmarkParameters;
    let c = meijaard_canonical(&BenchmarkParameters::benchmark_bicycle());
    let lam = std::f64::consts::PI / 10.0;
    let dir = tmp("linear");
    let sensors = SensorModel::default();
    write_run(
        &dir.join("calibration"),
        "calibration",
        RunKind::Calibration,
        &rest_trajectory(10.0, -lam, 0.4),
        &sensors,
        21,
    )
    .unwrap();
    let speeds = [4.6, 5.2, 5.8];
    let mut runs = Vec::new();
    for (i, &v0) in speeds.iter().enumerate() {
        let spec = ResponseSpec {
            launch_speed: v0,
            deceleration: 0.1,
            frame_pitch: -lam,
            geometry: (1.02, 0.08, lam),
            roll_rate_jump: 0.5,
            ..ResponseSpec::default()
        };
        let traj = linear_model_trajectory(&c, &spec).unwrap();
        let d = dir.join(format!("run{:02}", i + 1));
        write_run(&d, "r", RunKind::Run, &traj, &sensors, 30 + i as u64).unwrap();
        runs.push(d);
    }
    let opt = PipelineOptions {
        frame_pitch: -lam,
        ..PipelineOptions::default()
    };
    let (_, reports) = experiment::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
    for rep in reports {
        let rep = rep.unwrap();
        let k = &rep.kicks[0];
        let f = k
            .chosen_fit()
            .unwrap_or_else(|| panic!("{:?} {:?} {:?} {:?}", k.kick_time, k.window, k.window_end, k.failed));
        let p = predicted_weave(&c, k.mean_speed).unwrap();
        let rel = (f.eigenvalue[0] - p[0]).hypot(f.eigenvalue[1] - p[1]) / p[0].hypot(p[1]);
        println!(
            "v {:.2} ({:.2}-{:.2}): measured {:.3}{:+.3}i +- {:.3},{:.3} ({}, r2 {:.4}), model {:.3}{:+.3}i, {:.1} %",
            k.mean_speed,
            k.speed_interval[0],
            k.speed_interval[1],
            f.eigenvalue[0],
            f.eigenvalue[1],
            f.eigenvalue_stderr[0],
            f.eigenvalue_stderr[1],
            f.form.name(),
            f.r2,
            p[0],
            p[1],
            100.0 * rel
        );
        assert!(rel < 0.05);
    }
}

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
    let err = |d: &Path| read::read_run(d).unwrap_err();
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
    let run = read::read_run(&d).unwrap();
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
    let run = read::read_run(&d).unwrap();
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
    let run = read::read_run(&d).unwrap();
    assert_eq!(run.frame.t.len(), read::read_run(&good).unwrap().frame.t.len());

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
    let inputs = experiment::classify(&set).unwrap();
    let experiment::Input::Set { runs, calibration } = &inputs[0] else {
        panic!("a set")
    };
    let (_, out) =
        experiment::process_set(runs, calibration.as_ref().unwrap(), &PipelineOptions::default(), &noop).unwrap();
    assert!(out[0].is_ok());
    let e = out[1].as_ref().unwrap_err().to_string();
    assert!(e.contains("run02") && e.contains("imu_handlebar.csv:50:"), "{e}");
}

/// Issue 8, point 8: every kick of the TU Delft logs is found without row
/// ranges, and each is fitted with its r^2. The kicks are lateral pushes
/// every few seconds; the detector must find them all and nothing in the
/// quiet stretches between.
#[test]
fn tudelft_logs_every_kick_found_and_fitted() {
    let Some(dir) = shared("realdata/tudelft_sbw_kicks/logs") else {
        return;
    };
    let mut logs: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    logs.sort();
    assert_eq!(logs.len(), 4);
    for path in logs {
        let log = read::read_tudelft(&path).unwrap();
        let rep = experiment::process_tudelft(&log, &PipelineOptions::default());
        let n = rep.kicks.len();
        let fitted: Vec<_> = rep
            .kicks
            .iter()
            .filter_map(|k| k.chosen_fit().map(|f| (k, f)))
            .collect();
        let good = fitted.iter().filter(|(_, f)| f.r2 > 0.9).count();
        println!(
            "{}: {n} kicks, {} fitted, {good} with r2 > 0.9",
            path.display(),
            fitted.len()
        );
        for (k, f) in &fitted {
            println!(
                "  t {:7.2} v {:.2}  {:7.3}{:+7.3}i  r2 {:.3} {}",
                k.kick_time,
                k.mean_speed,
                f.eigenvalue[0],
                f.eigenvalue[1],
                f.r2,
                f.form.name()
            );
        }
        assert!(n >= 15, "{}: only {n} kicks", path.display());
        for w in rep.kicks.windows(2) {
            assert!(w[0].window[1] <= w[1].kick_time, "window runs into the next kick");
        }
        assert!(fitted.len() * 10 >= n * 7, "{}: most kicks fitted", path.display());
        assert!(fitted.iter().all(|(_, f)| f.r2.is_finite() && f.eigenvalue[1] > 0.0));
    }
}

/// Counts, rates and file names read from `run.toml` are bounded and kept
/// inside the run folder; oversized inputs are refused before memory grows.
#[test]
fn run_metadata_is_bounded_and_kept_inside_the_run() {
    use bikedyn_runtime::experiment::read::{read_capped, read_meta};
    let good = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/data/hidden_steer_damping/run01/run.toml"),
    )
    .unwrap();
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

/// The curve `fit --plot` draws is the fitted curve: evaluated over the
/// window's samples it reproduces the fit's own r², for every form fitted
/// (whichever is reported). (It did not for the speed-varying forms, whose
/// curve was drawn with a speed integral other than the fitted one and lay
/// flat along the bottom of the plot.)
fn drawn_fit_reproduces_r2(reports: &[experiment::RunReport]) -> usize {
    let mut checked = 0;
    for rep in reports {
        for k in &rep.kicks {
            for f in &k.fits {
                let s = &k.samples;
                let on_rate = matches!(
                    f.form,
                    experiment::fit::FitForm::RollRate | experiment::fit::FitForm::SpeedVaryingRollRate
                );
                let y = if on_rate { &s.roll_rate } else { &s.roll };
                let inside: Vec<usize> = (0..s.t.len())
                    .filter(|&i| s.t[i] >= k.window[0] && s.t[i] <= k.window[1])
                    .collect();
                assert_eq!(inside.len(), f.n, "{}: window samples", rep.run.display());
                let t: Vec<f64> = inside.iter().map(|&i| s.t[i]).collect();
                let drawn = f.evaluate(&t);
                let ym = inside.iter().map(|&i| y[i]).sum::<f64>() / f.n as f64;
                let (ssr, sst) = inside.iter().zip(&drawn).fold((0.0, 0.0), |(a, b), (&i, d)| {
                    (a + (y[i] - d).powi(2), b + (y[i] - ym).powi(2))
                });
                let r2 = 1.0 - ssr / sst;
                assert!(
                    (r2 - f.r2).abs() < 1e-9,
                    "{} kick {:.2} s ({}): drawn curve r2 {r2} against the fit's {}",
                    rep.run.display(),
                    k.kick_time,
                    f.form.name(),
                    f.r2
                );
                checked += 1;
            }
        }
    }
    checked
}

#[test]
fn the_drawn_fit_is_the_fitted_curve() {
    // The committed synthetic set (speed decays during its responses).
    let set = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/data/hidden_steer_damping");
    let runs: Vec<PathBuf> = (1..=6).map(|i| set.join(format!("run{i:02}"))).collect();
    let (_, reports) =
        experiment::process_set(&runs, &set.join("calibration"), &PipelineOptions::default(), &noop).unwrap();
    let reports: Vec<_> = reports.into_iter().map(Result::unwrap).collect();
    assert!(drawn_fit_reproduces_r2(&reports) >= 6);
    // The dev runs whose plots were flat (run01, run05, run08 were fitted
    // with the speed-varying form).
    if let Some(dev) = shared("data/dev") {
        let runs: Vec<PathBuf> = ["run01", "run05", "run08"].iter().map(|r| dev.join(r)).collect();
        let (_, reports) =
            experiment::process_set(&runs, &dev.join("calibration"), &PipelineOptions::default(), &noop).unwrap();
        let reports: Vec<_> = reports.into_iter().map(Result::unwrap).collect();
        let varying = reports
            .iter()
            .flat_map(|r| &r.kicks)
            .filter(|k| k.fits.iter().any(|f| f.form.speed_varying()))
            .count();
        assert!(varying >= 2, "the dev runs fitted with the speed-varying form");
        assert!(drawn_fit_reproduces_r2(&reports) >= varying);
    }
}
