//! Issue 8, point 8: the measured-run pipeline on runs that `bikedyn synth`
//! made (the committed set `examples/data/hidden_steer_damping`: six runs of
//! the nonlinear free-speed thesis bicycle with steer damping 0.25 N m s/rad,
//! hand launch, release, saddle kick; dev-like sensors with mounting
//! misalignments, noise, heading drift, settling, a clock offset drawn
//! within +-0.3 s of the nominal one, reed-switch bounce and magnet spacing
//! errors). Its `truth/` folder holds what the pipeline must recover.

use crate::common::*;
use bikedyn::bicycle::Bicycle;
use bikedyn::runs;
use bikedyn::runtime::experiment::PipelineOptions;
use nalgebra::Rotation3;
use std::collections::BTreeMap;
use std::path::PathBuf;

fn set() -> PathBuf {
    example_set()
}

fn truth(run: &str) -> serde_json::Value {
    let p = set().join("truth").join(format!("{run}_truth.json"));
    serde_json::from_str(&std::fs::read_to_string(&p).unwrap()).unwrap()
}

fn triple(v: &serde_json::Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [a[0].as_f64().unwrap(), a[1].as_f64().unwrap(), a[2].as_f64().unwrap()]
}

/// Tolerances, each with its reason:
/// * misalignment 1.5 deg as a rotation: the calibration run gives two axes
///   from gravity to ~0.01 deg, the rotation about the vertical comes from
///   the steer axis seen in the runs' steer motion (a few hundred samples of
///   steer up to ~0.1 rad against ~0.5 deg noise);
/// * kick time 0.03 s (under four IMU samples; the kick is a roll-rate jump
///   smoothed over 0.05 s);
/// * clock offset: within 2.5 of its reported standard errors (a 99 %
///   interval for a Gaussian error; the stated uncertainty must be honest,
///   whether the data determined the offset or the nominal bound is kept);
/// * weave eigenvalue: within 10 % of its modulus from the generating
///   model's frozen-speed eigenvalue over the window's speed interval, for
///   fits with r^2 > 0.95. The synthetic response is nonlinear, its speed
///   falls, the kick's forcing and the capsize drift overlap the window and
///   the roll carries ~0.2 deg noise: the study of these effects in docs/validation.md
///   puts the fitted real part within 0.1-0.3 1/s (3-5 %) of the frozen-speed
///   value; 10 % leaves room for the window choice.
#[test]
fn synth_runs_recover_misalignments_kicks_clock_offsets_and_eigenvalues() {
    let dir = set();
    let runs: Vec<PathBuf> = (1..=6).map(|i| dir.join(format!("run{i:02}"))).collect();
    let bike = Bicycle::resolve("thesis").unwrap();
    let opt = PipelineOptions {
        frame_pitch: bike.thesis().unwrap().frame_pitch().unwrap(),
        ..PipelineOptions::default()
    };
    let (cal, reports) = runs::process_set(&runs, &dir.join("calibration"), &opt, &|| {}).unwrap();

    let t1 = truth("run01");
    let e = |a: [f64; 3]| Rotation3::from_euler_angles(a[0], a[1], a[2]);
    let err_f = cal
        .frame
        .angle_to(&e(triple(&t1["sensors"]["frame_misalignment"])))
        .to_degrees();
    let err_h = cal
        .handlebar
        .angle_to(&e(triple(&t1["sensors"]["handlebar_misalignment"])))
        .to_degrees();
    println!("misalignment errors: frame {err_f:.3} deg, handlebar {err_h:.3} deg");
    assert!(err_f < 1.5 && err_h < 1.5, "misalignment errors {err_f} {err_h} deg");

    let driven = bike.model(Some("extended")).unwrap();
    let mut effects = BTreeMap::new();
    effects.insert("c_steer".to_string(), t1["parameters"]["c_steer"].as_f64().unwrap());
    let (mut reliable, mut from_data) = (0, 0);
    for (run, rep) in runs.iter().zip(&reports) {
        let name = run.file_name().unwrap().to_str().unwrap();
        let t = truth(name);
        let rep = rep.as_ref().unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(rep.kicks.len(), 1, "{name}: one kick");
        let k = &rep.kicks[0];
        let tk = t["kick_time_on_imu_clock"].as_f64().unwrap();
        let off = rep.clock_offset.unwrap();
        let true_off = t["sensors"]["clock_offset"].as_f64().unwrap();
        from_data += off.from_data as usize;
        println!(
            "{name}: kick {:.3} (true {tk:.3}); clock offset {:.3} +- {:.3}{} (true {true_off:.3}, error {:+.3} s)",
            k.kick_time,
            off.value,
            off.stderr,
            if off.from_data { " from the data" } else { " nominal" },
            off.value - true_off
        );
        assert!((k.kick_time - tk).abs() < 0.03, "{name}: kick time");
        assert!(
            (off.value - true_off).abs() < 2.5 * off.stderr,
            "{name}: clock offset {} +- {} against {true_off}",
            off.value,
            off.stderr
        );
        let Some(f) = k.chosen_fit() else {
            println!("{name}: no fit ({:?})", k.failed);
            continue;
        };
        let [lo, hi] = k.speed_interval;
        let speeds: Vec<f64> = (0..=10).map(|i| lo + (hi - lo) * i as f64 / 10.0).collect();
        let curve = bikedyn::identify::predict::predict(driven, &bike, &effects, &speeds).unwrap();
        let curve: Vec<[f64; 2]> = curve.into_iter().flatten().collect();
        assert_eq!(curve.len(), speeds.len(), "{name}: model weave over {lo}-{hi} m/s");
        let range = |i: usize| {
            curve.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), w| {
                (a.min(w[i]), b.max(w[i]))
            })
        };
        let gap = |x: f64, (a, b): (f64, f64)| (a - x).max(x - b).max(0.0);
        let m = f.eigenvalue;
        let mid = curve[5];
        let rel = gap(m[0], range(0)).hypot(gap(m[1], range(1))) / mid[0].hypot(mid[1]);
        println!(
            "  weave {:.3}{:+.3}i +- {:.3},{:.3} ({}, r2 {:.4}) over {lo:.2}-{hi:.2} m/s; model {:.3}{:+.3}i at the middle; \
             distance to the model's range {:.1} %",
            m[0],
            m[1],
            f.eigenvalue_stderr[0],
            f.eigenvalue_stderr[1],
            f.form.name(),
            f.r2,
            mid[0],
            mid[1],
            100.0 * rel
        );
        if f.r2 > 0.95 {
            reliable += 1;
            assert!(rel < 0.10, "{name}: weave {m:?} is {rel} from the model's range");
        }
    }
    println!("clock offsets determined by the data: {from_data} of {}", runs.len());
    // The launches of these runs steer (the hand's steer wander), so the
    // heading relation determines most offsets; keeping the nominal value
    // everywhere would pass the coverage check above without refining any.
    assert!(from_data >= 3, "only {from_data} of 6 clock offsets from the data");
    assert!(reliable >= 4, "only {reliable} reliable fits of 6");
}
