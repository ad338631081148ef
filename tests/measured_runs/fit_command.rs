//! `bikedyn fit` end to end.

use crate::common::*;

fn pair(v: &serde_json::Value) -> [f64; 2] {
    [v[0].as_f64().unwrap(), v[1].as_f64().unwrap()]
}

/// Every dev run is processed (one entry per run, the documented fields),
/// and every reliable fit (r^2 > 0.95) is within 20 % of the model's
/// frozen-speed weave eigenvalue over the window's speed interval. The dev runs
/// contain physics the rigid model lacks, so they are not expected to match
/// it exactly; 20 % is the bound asked of the fit.
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
    assert!(reliable >= 8, "only {reliable} reliable fits");
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

/// A TU Delft log: many kicks, times on the row-index clock, no clock offset.
#[test]
fn tudelft_log_json() {
    let Some(log) = shared("realdata/tudelft_sbw_kicks/logs/eigen_normal_sil6.5n2_16.2kph.log") else {
        return;
    };
    let out = bikedyn(&["fit", log.to_str().unwrap(), "--json"]);
    assert!(out.status.success());
    let v = stdout_json(&out);
    let list = v.as_array().unwrap();
    assert!(list.len() > 20);
    for e in list {
        assert!(e.get("clock_offset").is_none());
        assert!(e.get("predicted_weave").is_none());
        let t = e["kick_time"].as_f64().unwrap();
        // Row index times 0.01 s: a multiple of 0.01.
        assert!(((t * 100.0) - (t * 100.0).round()).abs() < 1e-6);
    }
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
