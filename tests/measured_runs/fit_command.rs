//! `bikedyn fit` end to end.

use crate::common::*;

fn pair(v: &serde_json::Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

/// Every dev run is processed (one entry per run, the documented fields),
/// and every reliable fit (r^2 > 0.95) is within 20 % of the model's
/// frozen-speed weave eigenvalue over the window's speed interval. The dev runs
/// contain physics the rigid model lacks, so they are not expected to match
/// it exactly; 20 % is the bound asked of the fit. Below 3 m/s, where the
/// weave merges with the slow modes, run05 and run09 converge only in the
/// speed-varying form, with slopes of 11 and 15 (1/s)/(m/s) against the
/// model's 1.9 and 2.2: not the weave changing with speed, so they are
/// refused (they counted as reliable before).
#[test]
fn dev_set_fits_every_run_near_the_model() {
    let Some(dev) = shared("data/dev") else { return };
    let out = bikedyn(&["fit", dev.to_str().unwrap(), "--bike", "thesis", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v = stdout_json(&out);
    let list = v.as_array().unwrap();
    assert_eq!(list.len(), 12, "one kick per run");
    let mut reliable = 0;
    for e in list {
        for key in [
            "run",
            "kick_time",
            "window",
            "speed_interval",
            "mean_speed",
            "clock_offset",
            "form",
            "r2",
        ] {
            assert!(e.get(key).is_some(), "{key} missing in {e}");
        }
        assert!(e["clock_offset"]["value"].is_f64() && e["clock_offset"]["stderr"].is_f64());
        let w = pair(&e["window"]);
        assert!(w[0] >= e["kick_time"].as_f64().unwrap() && w[1] > w[0]);
        let run = e["run"].as_str().unwrap();
        if run.ends_with("run05") || run.ends_with("run09") {
            let r = &e["refused"];
            assert_eq!(r["test"], "only_speed_form", "{e}");
            assert_eq!(r["why"]["test"], "implausible", "{e}");
        }
        if e["weave"].is_null() {
            continue;
        }
        let m = pair(&e["weave"]);
        let se = pair(&e["weave_stderr"]);
        assert!(m[1] > 0.0 && se[0] > 0.0 && se[1] > 0.0);
        // The model's eigenvalue over the window's speed interval (the
        // speed falls during a response; below the weave speed the real
        // part changes by ~1.6 1/s per m/s): distance from the measured
        // eigenvalue to that range, relative to the eigenvalue at the mean
        // speed.
        let p = pair(&e["predicted_weave"]["at_mean_speed"]);
        let (re, im) = (
            pair(&e["predicted_weave"]["real_range"]),
            pair(&e["predicted_weave"]["imag_range"]),
        );
        let gap = |x: f64, r: [f64; 2]| (r[0] - x).max(x - r[1]).max(0.0);
        let rel = gap(m[0], re).hypot(gap(m[1], im)) / p[0].hypot(p[1]);
        let r2 = e["r2"].as_f64().unwrap();
        eprintln!("{}: measured {m:?} predicted {p:?} rel {rel:.3} r2 {r2:.3}", e["run"]);
        if r2 > 0.95 {
            reliable += 1;
            assert!(rel < 0.2, "{}: {rel}", e["run"]);
        }
    }
    assert!(reliable >= 7, "only {reliable} reliable fits");
}

/// `--plot` writes one response plot per kick and the continuation diagram
/// with the measured eigenvalues.
#[test]
fn plots_are_written() {
    let Some(run) = shared("data/dev/run03") else { return };
    let d = scratch("fit").join("plots");
    let _ = std::fs::remove_dir_all(&d);
    let out = bikedyn(&[
        "fit",
        run.to_str().unwrap(),
        "--bike",
        "thesis",
        "--plot",
        d.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for f in ["run03_kick01.svg", "continuation_measured.svg"] {
        let svg = std::fs::read_to_string(d.join(f)).unwrap();
        assert!(svg.contains("<svg") && svg.contains("polyline"), "{f}");
    }
}

/// A TU Delft log with its bicycle: many kicks, times on the row-index
/// clock, no clock offset. Every kick has a verdict: a measured weave
/// eigenvalue, or refused with the test it failed. The kick at 140.21 s
/// (its window noise, fitted at 314.16 rad/s, the log's Nyquist limit, with
/// r² 0.003) is refused as above a quarter of the Nyquist frequency, and
/// the speed-varying form, chosen for most kicks before (slopes of hundreds
/// of (1/s)/(m/s) over speed changes of hundredths of a m/s), is chosen for
/// none of this log's kicks.
#[test]
fn tudelft_log_json() {
    let Some(log) = shared("realdata/tudelft_sbw_kicks/logs/eigen_normal_sil6.5n2_16.2kph.log") else {
        return;
    };
    let bike = fixture_arg("tudelft_sbw_bicycle.toml");
    let out = bikedyn(&["fit", log.to_str().unwrap(), "--bike", &bike, "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v = stdout_json(&out);
    let list = v.as_array().unwrap();
    assert!(list.len() > 20);
    let mut accepted = 0;
    for e in list {
        assert!(e.get("clock_offset").is_none());
        let t = e["kick_time"].as_f64().unwrap();
        // Row index times 0.01 s: a multiple of 0.01.
        assert!(((t * 100.0) - (t * 100.0).round()).abs() < 1e-6);
        // Measured, or refused with a reason; never both.
        assert_ne!(e["weave"].is_null(), e["refused"].is_null(), "{e}");
        if e["refused"].is_object() {
            assert!(!e["refused"]["reason"].as_str().unwrap().is_empty());
        } else {
            accepted += 1;
        }
        assert!(
            !e["form"].as_str().is_some_and(|f| f.starts_with("speed_varying")),
            "{e}"
        );
    }
    assert!(accepted >= 20, "{accepted} accepted");
    let k = list
        .iter()
        .find(|e| (e["kick_time"].as_f64().unwrap() - 140.21).abs() < 1e-6)
        .expect("the kick at 140.21 s");
    let r = &k["refused"];
    assert_eq!(r["test"], "above_nyquist", "{k}");
    assert!((r["omega"].as_f64().unwrap() - 314.159).abs() < 0.01, "{r}");
    assert!((r["limit"].as_f64().unwrap() - 78.54).abs() < 0.01, "{r}");
    assert!(r["reason"].as_str().unwrap().contains("Nyquist"), "{r}");
    assert!(k["weave"].is_null() && r["fit"]["r2"].as_f64().unwrap() < 0.01, "{k}");
    // The console lists it with the reason.
    let out = bikedyn(&["fit", log.to_str().unwrap(), "--bike", &bike]);
    let console = text(&out.stdout);
    assert!(
        console
            .lines()
            .any(|l| l.starts_with("refused: ") && l.contains("kick at 140.21 s") && l.contains("Nyquist")),
        "{console}"
    );
}

/// A missing calibration and a corrupt file are reported on stderr, the
/// exit status is 1, and the other runs are still output.
#[test]
fn corrupt_and_missing_inputs_are_reported() {
    let Some(dev) = shared("data/dev") else { return };
    let d = scratch("fit").join("inputs");
    let _ = std::fs::remove_dir_all(&d);
    for r in ["calibration", "run02", "run03"] {
        std::fs::create_dir_all(d.join(r)).unwrap();
        for f in ["imu_frame.csv", "imu_handlebar.csv", "speed_switch.csv", "run.toml"] {
            std::fs::copy(dev.join(r).join(f), d.join(r).join(f)).unwrap();
        }
    }
    let f = d.join("run03/speed_switch.csv");
    let s = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<&str> = s.lines().collect();
    lines[99] = "0.098,0.1,0.2";
    std::fs::write(&f, lines.join("\n") + "\n").unwrap();
    let out = bikedyn(&["fit", d.to_str().unwrap(), "--json"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("speed_switch.csv:100:"), "{err}");
    assert_eq!(stdout_json(&out).as_array().unwrap().len(), 1);
    std::fs::remove_dir_all(d.join("calibration")).unwrap();
    let out = bikedyn(&["fit", d.join("run02").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no calibration run"));
}

/// The fitted curve a plot draws is the fit: evaluated at the window's
/// samples it gives back the fit's own r² for every kick and every form
/// (the speed-varying forms drew a flat line at zero when the curve was
/// evaluated without the speed line they were fitted with, on dev run01,
/// run05 and run08 although their r² was 0.86-0.998).
#[test]
fn the_drawn_curve_of_every_fit_reproduces_its_r2() {
    use bikedyn::fit::{run_fit, FitOptions};
    use bikedyn::runtime::experiment::fit::FitForm;
    let out = run_fit(
        &FitOptions {
            inputs: vec![example_set()],
            ..FitOptions::default()
        },
        &bikedyn::progress::ignore,
    )
    .unwrap();
    let mut checked = 0;
    for k in out.reports.iter().flat_map(|r| &r.kicks) {
        for f in &k.fits {
            let on_rate = matches!(f.form, FitForm::RollRate | FitForm::SpeedVaryingRollRate);
            let y = if on_rate { &k.samples.roll_rate } else { &k.samples.roll };
            let drawn = f.evaluate(&k.samples.t);
            let mean = y.iter().sum::<f64>() / y.len() as f64;
            let ssr: f64 = y.iter().zip(&drawn).map(|(a, b)| (a - b).powi(2)).sum();
            let sst: f64 = y.iter().map(|a| (a - mean).powi(2)).sum();
            let r2 = 1.0 - ssr / sst;
            assert!(
                (r2 - f.r2).abs() < 1e-6,
                "{} {:?}: drawn r2 {r2}, fit r2 {}",
                k.run.display(),
                f.form,
                f.r2
            );
            checked += 1;
        }
    }
    assert!(checked >= 12, "{checked} fits");
}

/// `fit --plot` draws that curve: read back from the SVG, the fitted line
/// spans the measured points' height and follows them.
#[test]
fn the_plotted_fit_follows_the_measured_points() {
    let d = scratch("fit").join("plots-readback");
    let _ = std::fs::remove_dir_all(&d);
    let out = bikedyn(&["fit", example_set().to_str().unwrap(), "--plot", d.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut plots = 0;
    for e in std::fs::read_dir(&d).unwrap() {
        let path = e.unwrap().path();
        if !path.to_string_lossy().contains("_kick") || path.extension().is_none_or(|x| x != "svg") {
            continue;
        }
        let svg = std::fs::read_to_string(&path).unwrap();
        // The measured points are circles; the fit is the first long
        // polyline (grid lines have two points; the speed trace comes after).
        let attr = |tag: &str, name: &str| -> f64 {
            let start = tag.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
            tag[start..].split('"').next().unwrap().parse().unwrap()
        };
        let points: Vec<(f64, f64)> = svg
            .split("<circle")
            .skip(1)
            // Data points are filled in the data colour (their white rims
            // and the legend's marker aside).
            .filter(|c| c.contains("fill=\"#282828\""))
            .map(|c| (attr(c, "cx"), attr(c, "cy")))
            .collect();
        let line: Vec<(f64, f64)> = svg
            .split("<polyline")
            .skip(1)
            .map(|p| {
                let start = p.find("points=\"").unwrap() + 8;
                p[start..]
                    .split('"')
                    .next()
                    .unwrap()
                    .split_whitespace()
                    .map(|xy| {
                        let (x, y) = xy.split_once(',').unwrap();
                        (x.parse().unwrap(), y.parse().unwrap())
                    })
                    .collect::<Vec<(f64, f64)>>()
            })
            .find(|l| l.len() > 20)
            .unwrap();
        let span = |v: &[f64]| v.iter().cloned().fold(f64::MIN, f64::max) - v.iter().cloned().fold(f64::MAX, f64::min);
        let py: Vec<f64> = points.iter().map(|p| p.1).collect();
        let ly: Vec<f64> = line.iter().map(|p| p.1).collect();
        assert!(
            span(&ly) > 0.5 * span(&py),
            "{}: fit spans {} px, data {} px",
            path.display(),
            span(&ly),
            span(&py)
        );
        // The line at each point's x, against the point: correlated.
        let at = |x: f64| {
            let k = line.partition_point(|p| p.0 < x).clamp(1, line.len() - 1);
            let (a, b) = (line[k - 1], line[k]);
            if b.0 == a.0 {
                a.1
            } else {
                a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0)
            }
        };
        let pairs: Vec<(f64, f64)> = points.iter().map(|p| (p.1, at(p.0))).collect();
        let n = pairs.len() as f64;
        let (ma, mb) = (
            pairs.iter().map(|p| p.0).sum::<f64>() / n,
            pairs.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let cov: f64 = pairs.iter().map(|p| (p.0 - ma) * (p.1 - mb)).sum();
        let va: f64 = pairs.iter().map(|p| (p.0 - ma).powi(2)).sum();
        let vb: f64 = pairs.iter().map(|p| (p.1 - mb).powi(2)).sum();
        let corr = cov / (va * vb).sqrt();
        assert!(corr > 0.9, "{}: drawn fit and points correlate {corr}", path.display());
        // Issue 20: a PNG beside each SVG, the measured points and the fit
        // in the legend.
        assert!(path.with_extension("png").is_file(), "{}: no PNG", path.display());
        assert!(
            svg.contains(">measured<") && svg.contains(">fit<"),
            "{}: legend",
            path.display()
        );
        plots += 1;
    }
    assert!(plots >= 6, "{plots} kick plots");
    assert!(d.join("continuation_measured.png").is_file() || !d.join("continuation_measured.svg").is_file());
}

/// A calibration run whose handlebar is turned back and forth (6 deg at
/// 0.3 Hz about the handlebar sensor's own z axis, nominally the steer
/// axis) while the frame stays still is refused: the handlebar sensor
/// tilts against gravity by the steer times the sine of the axis's tilt.
#[test]
fn a_calibration_run_with_the_handlebar_turning_is_refused() {
    let d = example_runs("fit", "steering-calibration", &["calibration", "run01"]);
    rotate_orientations(&d.join("calibration").join("imu_handlebar.csv"), |t, q, _| {
        let a = 6f64.to_radians() * (2.0 * std::f64::consts::PI * 0.3 * t).sin();
        // A rotation about the sensor's own z axis (applied on the right).
        q * nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), a)
    });
    let bad = bikedyn(&["fit", d.to_str().unwrap(), "--json"]);
    assert_eq!(bad.status.code(), Some(1));
    let err = text(&bad.stderr);
    assert!(
        err.contains("not at rest") && err.contains("handlebar sensor by"),
        "{err}"
    );
    assert_eq!(stdout_json(&bad).as_array().unwrap().len(), 0, "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Real units drift in heading (the oracle simulator's by up to 2.5 deg
/// relative to each other over a ten-second calibration), which reads as
/// a steer that moves while the bicycle stands still. A calibration check
/// on the steer angle refused two of five oracle control sets made with
/// random seeds. The check is on each sensor's tilt against gravity, which
/// the calibration measures and heading drift leaves alone: the committed
/// calibration with 4 deg of heading drift in its handlebar sensor (and 3
/// deg the other way in its frame sensor) is accepted, and the run's fit is
/// what it was to a tenth of its standard error. (Not bit for bit: the
/// calibration takes steer zero from the sensors' mean relative heading,
/// which the drift moves by 3.5 deg; the fit, whose steer has its own
/// offset, moves by 0.07 standard errors.)
#[test]
fn a_calibration_run_whose_sensors_drift_in_heading_is_accepted() {
    let d = example_runs("fit", "drifting-calibration", &["calibration", "run01"]);
    let fit = |d: &std::path::Path| {
        let out = bikedyn(&["fit", d.to_str().unwrap(), "--json"]);
        assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
        stdout_json(&out)[0].clone()
    };
    let before = fit(&d);
    for (sensor, drift_deg) in [("imu_frame.csv", -3.0), ("imu_handlebar.csv", 4.0)] {
        rotate_orientations(&d.join("calibration").join(sensor), |t, q, t_end| {
            // A heading turn about the global Z axis, growing over the record.
            let a = f64::to_radians(drift_deg) * t / t_end;
            nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::z_axis(), a) * q
        });
    }
    let after = fit(&d);
    let (a, b, se) = (&before["weave"], &after["weave"], &before["weave_stderr"]);
    for k in 0..2 {
        let (x, y, s) = (a[k].as_f64().unwrap(), b[k].as_f64().unwrap(), se[k].as_f64().unwrap());
        assert!((x - y).abs() < 0.1 * s, "weave {a} at rest, {b} with heading drift");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A calibration run whose bicycle sways (the whole bicycle rolling 3 deg
/// back and forth at 0.3 Hz, applied to both sensors' orientations) is
/// refused with the reason and how much it moved; the runs it calibrates
/// are skipped (exit status 1), not fitted with a biased mounting. The
/// committed set's own calibration (sensor noise and wander only) passes.
#[test]
fn a_calibration_run_that_is_not_at_rest_is_refused() {
    let d = example_runs("fit", "swaying-calibration", &["calibration", "run01"]);
    let ok = bikedyn(&["fit", d.to_str().unwrap(), "--json"]);
    assert_eq!(ok.status.code(), Some(0), "{}", text(&ok.stderr));
    for sensor in ["imu_frame.csv", "imu_handlebar.csv"] {
        rotate_orientations(&d.join("calibration").join(sensor), |t, q, _| {
            // A rotation about the global X axis (v_global = R(q) v_sensor).
            let a = 3f64.to_radians() * (2.0 * std::f64::consts::PI * 0.3 * t).sin();
            nalgebra::UnitQuaternion::from_axis_angle(&nalgebra::Vector3::x_axis(), a) * q
        });
    }
    let bad = bikedyn(&["fit", d.to_str().unwrap(), "--json"]);
    assert_eq!(bad.status.code(), Some(1));
    let err = text(&bad.stderr);
    assert!(err.contains("not at rest") && err.contains("calibration"), "{err}");
    assert!(err.contains("frame sensor tilts by"), "{err}");
    assert_eq!(stdout_json(&bad).as_array().unwrap().len(), 0, "{err}");
    let _ = std::fs::remove_dir_all(&d);
}
