//! Measured runs (issue 8): the pipeline on runs written here with known
//! truth, on `shared/data/dev` and on the TU Delft kick logs. The
//! synthetic runs are written by the report layer's `write_run` and read
//! back by the application's readers (`bikedyn::runs`).

use crate::common::*;
use bikedyn::report::experiment::synth::write_run;
use bikedyn::runs;
use bikedyn::runtime::experiment::angles::AngleMethod;
use bikedyn::runtime::experiment::{
    self,
    records::RunKind,
    synth::{rest_trajectory, ResponseSpec, SensorModel},
    PipelineOptions,
};
use nalgebra::Rotation3;
use std::path::{Path, PathBuf};

/// A fresh folder `name` of this group's scratch folder.
fn tmp(name: &str) -> PathBuf {
    let d = scratch("measured-pipeline").join(name);
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
    let (cal, reports) = runs::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
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
    let (cal, _) = runs::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
    let mut rms = [[0.0; 2]; 2];
    let mut count = 0.0;
    for (i, (spec, _)) in truths.iter().enumerate() {
        let run = runs::read_run(&runs[i]).unwrap();
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
    use bikedyn::runtime::closed_form::meijaard_canonical;
    use bikedyn::runtime::experiment::{compare::predicted_weave, synth::linear_model_trajectory};
    use bikedyn::runtime::parameters::BenchmarkParameters;
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
    let (_, reports) = runs::process_set(&runs, &dir.join("calibration"), &opt, &noop).unwrap();
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
        let log = runs::read_tudelft(&path).unwrap();
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
    let set = example_set();
    let runs: Vec<PathBuf> = (1..=6).map(|i| set.join(format!("run{i:02}"))).collect();
    let (_, reports) = runs::process_set(&runs, &set.join("calibration"), &PipelineOptions::default(), &noop).unwrap();
    let reports: Vec<_> = reports.into_iter().map(Result::unwrap).collect();
    assert!(drawn_fit_reproduces_r2(&reports) >= 6);
    // The dev runs whose plots were flat (run01, run05, run08 were fitted
    // with the speed-varying form).
    if let Some(dev) = shared("data/dev") {
        let runs: Vec<PathBuf> = ["run01", "run05", "run08"].iter().map(|r| dev.join(r)).collect();
        let (_, reports) =
            runs::process_set(&runs, &dev.join("calibration"), &PipelineOptions::default(), &noop).unwrap();
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
