//! The linear-analysis jobs as library calls (`canonical`, `stability`,
//! `eig`, `sweep`): the typed results the command line prints and Python
//! converts.

use crate::common::{bikedyn, fixture, fixture_arg, ok_json, stdout_json, text};
use bikedyn::bicycle::Bicycle;
use bikedyn::canonical::{canonical, state_space, CanonicalOptions, CanonicalReport};
use bikedyn::eigen::{eigen_sweep, eigenvalues, EigenJob, EigenOptions, EigenSweepError, Speeds};
use bikedyn::runtime::eigen::LinearBicycle;
use bikedyn::runtime::sweep::no_progress;
use bikedyn::stability::{stability, StabilityError, StabilityOptions};
use bikedyn::sweep::{sweep, sweep_at_speeds, sweep_model, SweepError, SweepOptions, SweepReport, SweptParameter};

/// The benchmark bicycle has the canonical form; its structural zero
/// `C1[0][0]` is written as 0, and the file-free built-in has no standard
/// deviations.
#[test]
fn the_canonical_job_gives_the_benchmark_matrices_with_structural_zeros_as_zero() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let CanonicalReport::Canonical(c) = canonical(&b, &CanonicalOptions::default()).unwrap() else {
        panic!("the benchmark bicycle has a canonical form");
    };
    assert_eq!(c.matrices.c1[0][0], 0.0);
    assert_eq!(c.matrices.m0[0][0], c.exact.m0[(0, 0)]);
    assert!(c.standard_deviations.is_none());
    let json = serde_json::to_value(CanonicalReport::Canonical(c)).unwrap();
    for key in ["M0", "C1", "K0", "K2", "g", "model"] {
        assert!(json.get(key).is_some(), "{key} in {json}");
    }
}

/// A bicycle with a feedback controller has no canonical form: the job says
/// why and gives A(v) and B(v) = [0; M(v)^-1], which reproduce the linear
/// equations at each speed (A's lower rows are -M^-1 [K, C]).
#[test]
fn without_a_canonical_form_the_job_gives_state_space_matrices_that_reproduce_the_equations() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/balance_assist_gain_8.toml");
    let b = Bicycle::resolve(file).unwrap();
    let speeds = vec![0.5, 3.0, 6.0];
    let report = canonical(
        &b,
        &CanonicalOptions {
            model: None,
            speeds: speeds.clone(),
        },
    )
    .unwrap();
    let CanonicalReport::StateSpace(n) = &report else {
        panic!("a controller removes the canonical form");
    };
    assert!(n.why.contains("controller"), "{}", n.why);
    let ss = &n.state_space;
    assert_eq!(ss.states, ["roll", "steer", "roll_rate", "steer_rate"]);
    assert_eq!(ss.inputs, ["roll_torque", "steer_torque"]);
    let lin = b.linear_with(None).unwrap();
    for (at, &v) in ss.at.iter().zip(&speeds) {
        assert_eq!(at.speed, v);
        let m = lin.at_speed(v).unwrap();
        let minv = m.mass.try_inverse().unwrap();
        let bm = at.b.as_ref().unwrap();
        for i in 0..2 {
            assert_eq!(bm[i], [0.0, 0.0]);
            for j in 0..2 {
                assert_eq!(bm[i + 2][j], minv[(i, j)]);
                // Position rows: the rates.
                assert_eq!(at.a[i][j + 2], if i == j { 1.0 } else { 0.0 });
            }
        }
        // Acceleration rows: A[2.., ..2] M = -K and A[2.., 2..] M = -C.
        let a = nalgebra::Matrix4::from_fn(|i, j| at.a[i][j]);
        let k = -m.mass * a.fixed_view::<2, 2>(2, 0);
        let c = -m.mass * a.fixed_view::<2, 2>(2, 2);
        assert!((k - m.stiffness).amax() <= 1e-12 * m.stiffness.amax(), "K at {v} m/s");
        assert!(
            (c - m.damping).amax() <= 1e-12 * m.damping.amax().max(1.0),
            "C at {v} m/s"
        );
    }
    // The same matrices from the state-space call alone.
    let direct = state_space(&b, None, &speeds).unwrap();
    assert_eq!(direct.at.len(), 3);
    assert_eq!(direct.at[1].a, ss.at[1].a);
}

/// A model with extra first-order states (tyre forces) gives its own
/// lateral states, no inputs, and says which states are extra.
#[test]
fn a_model_with_extra_states_gives_its_own_lateral_states() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let ss = state_space(&b, Some("tyre_free"), &[4.0]).unwrap();
    assert!(ss.model_coordinates);
    assert!(ss.inputs.is_empty());
    assert_eq!(ss.extra_states, ["Fy_rear", "Fy_front"]);
    let n = ss.states.len();
    assert_eq!(ss.at[0].a.len(), n);
    assert!(ss.at[0].b.is_none());
    assert!(state_space(&b, None, &[f64::NAN]).is_err());
}

/// The benchmark bicycle's weave and capsize speeds from the stability job
/// are Meijaard et al. (2007)'s (v_w = 4.2923825363 m/s, v_c = 6.0242620154 m/s), its
/// self-stable interval lies between them, and a built-in bicycle without
/// `+/-` values has no standard deviations and refuses a Monte Carlo check.
#[test]
fn the_stability_job_gives_the_benchmark_speeds_and_refuses_draws_without_spreads() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let r = stability(&b, &StabilityOptions::default()).unwrap();
    assert!(
        (r.weave_speed.unwrap() - 4.292_382_536_341_11).abs() < 1e-10,
        "{:?}",
        r.weave_speed
    );
    assert!(
        (r.capsize_speed.unwrap() - 6.024_262_015_388_37).abs() < 1e-10,
        "{:?}",
        r.capsize_speed
    );
    assert_eq!(r.stable_intervals.len(), 1);
    assert!(r
        .crossings
        .iter()
        .any(|c| c.mode == "weave" && c.direction == "stabilizing" && c.kind == "complex_pair"));
    assert!(r.uncertainty.is_none() && r.weave_speed_sd.is_none());
    let json = serde_json::to_value(&r).unwrap();
    assert!(json.get("weave_speed_sd").is_none(), "{json}");
    assert_eq!(
        json["weave_real_pair_merge_speed"],
        serde_json::json!(r.weave_real_pair_merge)
    );
    let draws = StabilityOptions {
        monte_carlo: Some((20, 1)),
        ..StabilityOptions::default()
    };
    assert!(matches!(stability(&b, &draws), Err(StabilityError::NoUncertainties(_))));
    let backwards = StabilityOptions {
        speed_min: 5.0,
        speed_max: 2.0,
        ..StabilityOptions::default()
    };
    assert!(matches!(stability(&b, &backwards), Err(StabilityError::SpeedRange(..))));
}

/// `value` as JSON text read back: the command line's output is read by
/// the same parser, whose last digit can differ from the number's
/// (serde_json reads floats fast, not exactly), so text equal to the
/// command line's compares equal.
fn as_printed(value: &impl serde::Serialize) -> serde_json::Value {
    serde_json::from_str(&serde_json::to_string(value).unwrap()).unwrap()
}

/// The keys `keys` appear in `json` (an object's text) in this order
/// (each key's last occurrence: an object's own after its nested ones).
fn assert_in_order(json: &str, keys: &[&str]) {
    let at: Vec<usize> = keys
        .iter()
        .map(|k| {
            json.rfind(&format!("\"{k}\":"))
                .unwrap_or_else(|| panic!("{k} in {json}"))
        })
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{keys:?} out of order in {json}");
}

/// What `bikedyn eig --format json` prints is the serialization of the
/// `eig` job's typed result, field for field and number for number: for a
/// file with `+/-` values (standard deviations in every entry) over a
/// range, and for a model with extra states (extra eigenvalues).
#[test]
fn the_eig_job_result_is_what_bikedyn_eig_prints_in_json() {
    let file = fixture_arg("Balanceassistv1Benchmark.txt");
    let b = Bicycle::resolve(&file).unwrap();
    let printed = ok_json(&["eig", "--bike", &file, "--speeds", "0:9:0.75", "--format", "json"]);
    let report = eigen_sweep(
        &b,
        &EigenOptions {
            speeds: Speeds::Range {
                start: 0.0,
                step: 0.75,
                count: 13,
            },
            ..EigenOptions::default()
        },
    )
    .unwrap();
    assert!(report.points.iter().all(|p| p.standard_deviations.is_some()));
    assert_eq!(as_printed(&report), printed);

    let b = Bicycle::resolve("benchmark").unwrap();
    let printed = ok_json(&[
        "eig",
        "--bike",
        "benchmark",
        "--model",
        "tyre_free",
        "--speeds",
        "2:6:2",
        "--format",
        "json",
    ]);
    let report = eigen_sweep(
        &b,
        &EigenOptions {
            model: Some("tyre_free".into()),
            speeds: Speeds::List(vec![2.0, 4.0, 6.0]),
            ..EigenOptions::default()
        },
    )
    .unwrap();
    assert_eq!(report.model, "tyre_free");
    assert!(!report.points[0].extra_eigenvalues.is_empty());
    assert_eq!(as_printed(&report), printed);
}

/// The defaults are those documented (and `bikedyn eig`'s): 0 to 10 m/s in
/// steps of 0.5 m/s through the bicycle's own model, standard deviations
/// when the file has `+/-` values, no critical speeds; the benchmark's
/// weave pair at 0 m/s is the first entry.
#[test]
fn the_eig_job_defaults_are_21_speeds_from_rest_to_10_m_per_s() {
    let o = EigenOptions::default();
    assert!(o.model.is_none() && o.standard_deviations && !o.critical_speeds);
    let b = Bicycle::resolve("benchmark").unwrap();
    let r = eigen_sweep(&b, &o).unwrap();
    let v: Vec<f64> = r.points.iter().map(|p| p.v).collect();
    assert_eq!(v, (0..=20).map(|k| 0.5 * k as f64).collect::<Vec<_>>());
    assert_eq!(r.model, b.model(None).unwrap().name);
    assert!(r.critical.is_none());
    // A built-in bicycle has no `+/-` values: nothing to give.
    assert!(r.points.iter().all(|p| p.standard_deviations.is_none()));
    assert_eq!(
        as_printed(&r),
        ok_json(&["eig", "--bike", "benchmark", "--format", "json"])
    );
    // Byte for byte: one speed's object per line, fields in their order.
    let out = bikedyn(&["eig", "--bike", "benchmark", "--format", "json"]);
    let lines: Vec<String> = r.points.iter().map(|p| serde_json::to_string(p).unwrap()).collect();
    assert_eq!(text(&out.stdout), format!("[\n  {}\n]\n", lines.join(",\n  ")));
    // The fields in the order the command has always written them.
    assert_in_order(&lines[0], &["eigenvalues", "mode_shapes", "modes", "v"]);
    // With critical speeds asked, the benchmark's v_w and v_c.
    let crit = eigen_sweep(
        &b,
        &EigenOptions {
            critical_speeds: true,
            ..EigenOptions::default()
        },
    )
    .unwrap()
    .critical
    .unwrap();
    assert!((crit.weave_speed.unwrap() - 4.292_382_536_341_11).abs() < 1e-8);
    assert!((crit.capsize_speed.unwrap() - 6.024_262_015_388_37).abs() < 1e-8);
}

/// Speeds given a block at a time (the command line's streaming) give the
/// same points as one call, and the fast eigenvalue path gives the same
/// spectrum by descending real part.
#[test]
fn the_eig_job_streamed_equals_the_job_at_once_and_the_fast_path() {
    let b = Bicycle::resolve(&fixture("TmsBenchmark.txt").to_string_lossy()).unwrap();
    let speeds = Speeds::Range {
        start: 0.0,
        step: 0.001,
        count: 5001,
    };
    let opts = EigenOptions {
        speeds: speeds.clone(),
        ..EigenOptions::default()
    };
    let job = EigenJob::new(&b, &opts).unwrap();
    let streamed: Vec<_> = job.points().map(Result::unwrap).collect();
    let at_once = eigen_sweep(&b, &opts).unwrap();
    assert_eq!(streamed, at_once.points);
    let list: Vec<f64> = (0..speeds.len()).map(|k| speeds.at(k)).collect();
    let fast = eigenvalues(&b, None, &list).unwrap();
    assert_eq!(fast.per_speed, 4);
    for (p, z) in streamed.iter().zip(fast.values.chunks(4)) {
        let mut e = p.eigenvalues;
        e.sort_by(|a, b| b[0].total_cmp(&a[0]).then(b[1].total_cmp(&a[1])));
        assert_eq!(e.as_slice(), z, "at {} m/s", p.v);
    }
}

/// One more speed asked of a prepared job (the explorer's slider beside its
/// diagram) is the point a job of that speed alone gives, standard
/// deviations included (a file with uncertainties), through another model
/// than the bicycle's, and with a rider's lean as extra states; a bad speed
/// is the same typed error.
#[test]
fn a_point_asked_of_a_prepared_job_is_that_of_a_job_of_its_speed_alone() {
    let with_uncertainties = fixture("BrowserBenchmark.txt").to_string_lossy().to_string();
    let rider_lean = fixture("MooreRiderLean2012BrowserJason.txt")
        .to_string_lossy()
        .to_string();
    for (file, model) in [
        (with_uncertainties.as_str(), None),
        ("benchmark", Some("extended")),
        (rider_lean.as_str(), None),
    ] {
        let b = Bicycle::resolve(file).unwrap();
        let opts = EigenOptions {
            model: model.map(str::to_string),
            speeds: Speeds::Range {
                start: 0.5,
                step: 0.5,
                count: 20,
            },
            standard_deviations: true,
            ..EigenOptions::default()
        };
        let job = EigenJob::new(&b, &opts).unwrap();
        for v in [0.0, 2.3, 4.9, 7.25, 12.0] {
            let alone = EigenOptions {
                speeds: Speeds::List(vec![v]),
                ..opts.clone()
            };
            let expected = eigen_sweep(&b, &alone).unwrap().points.remove(0);
            assert_eq!(job.point_at(v).unwrap(), expected, "{file} {model:?} at {v} m/s");
        }
        assert!(matches!(
            job.point_at(f64::NAN),
            Err(EigenSweepError::Speed { index: 0, .. })
        ));
    }
}

/// Bad speeds are typed errors naming what is wrong, never a panic.
#[test]
fn the_eig_job_refuses_bad_speeds_with_a_typed_error() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let with = |speeds| EigenOptions {
        speeds,
        ..EigenOptions::default()
    };
    let e = eigen_sweep(&b, &with(Speeds::List(vec![1.0, f64::NAN]))).unwrap_err();
    assert!(matches!(e, EigenSweepError::Speed { index: 1, .. }), "{e}");
    assert!(e.to_string().starts_with("speeds[1]"), "{e}");
    assert!(matches!(
        eigen_sweep(&b, &with(Speeds::List(Vec::new()))),
        Err(EigenSweepError::NoSpeeds)
    ));
    let backwards = Speeds::Range {
        start: 0.0,
        step: -1.0,
        count: 3,
    };
    let e = eigen_sweep(&b, &with(backwards)).unwrap_err();
    assert!(
        matches!(e, EigenSweepError::Step(_)) && e.to_string().contains("step"),
        "{e}"
    );
    let e = eigenvalues(&b, None, &[f64::INFINITY]).unwrap_err();
    assert!(matches!(e, EigenSweepError::Speed { index: 0, .. }), "{e}");
    let bad_model = EigenOptions {
        model: Some("nosuch".into()),
        ..EigenOptions::default()
    };
    assert!(matches!(eigen_sweep(&b, &bad_model), Err(EigenSweepError::Bicycle(_))));
}

/// What `bikedyn sweep --format json` prints is the serialization of the
/// `sweep` job's typed result: over one parameter of a file with `+/-`
/// values (the critical speeds' standard deviations in every point), and
/// over two with the least stable real part at a speed.
#[test]
fn the_sweep_job_result_is_what_bikedyn_sweep_prints_in_json() {
    let file = fixture_arg("Balanceassistv1Benchmark.txt");
    let b = Bicycle::resolve(&file).unwrap();
    let printed = ok_json(&[
        "sweep",
        "--bike",
        &file,
        "--param",
        "c",
        "--values",
        "0.05:0.1:0.025",
        "--format",
        "json",
    ]);
    // The values as the command line counts them (0.05 + 0.025 is not 0.075).
    let values: Vec<f64> = (0..3).map(|k| 0.05 + k as f64 * 0.025).collect();
    let report = sweep(&b, &SweepOptions::new("c", values), &no_progress).unwrap();
    let SweepReport::Parameter(p) = &report else {
        panic!("one parameter: no map");
    };
    assert!(p.points.iter().all(|p| p.weave_speed_sd.is_some()));
    assert_eq!(as_printed(&report), printed);

    let b = Bicycle::resolve("benchmark").unwrap();
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0:0.1:0.05",
        "--param2",
        "lam",
        "--values2",
        "0.2:0.4:0.2",
        "--at-speed",
        "5",
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let printed = stdout_json(&out);
    let report = sweep(
        &b,
        &SweepOptions {
            second: Some(SweptParameter::new("lam", vec![0.2, 0.4])),
            at_speed: Some(5.0),
            ..SweepOptions::new("c", vec![0.0, 0.05, 0.1])
        },
        &no_progress,
    )
    .unwrap();
    let SweepReport::Map(m) = &report else {
        panic!("two parameters: a map");
    };
    assert_eq!(m.cells.len(), 6);
    assert!(m.cells.iter().all(|c| c.least_stable_real_part.is_some()));
    assert_eq!(as_printed(&report), printed);
    // Byte for byte: the pretty-printed serialization, fields in their
    // order.
    assert_eq!(text(&out.stdout), serde_json::to_string_pretty(&report).unwrap() + "\n");
    // The fields in the order the command has always written them.
    let first_cell = serde_json::to_string(&m.cells[0]).unwrap();
    assert_in_order(
        &first_cell,
        &[
            "capsize_speed",
            "error",
            "i",
            "j",
            "least_stable_real_part",
            "open_ended",
            "stable_intervals",
            "stable_width",
            "weave_real_pair_merge",
            "weave_speed",
            "x",
            "y",
        ],
    );
    assert_in_order(
        &serde_json::to_string(&report).unwrap(),
        &["cells", "layout", "speed_range", "x", "y"],
    );
}

/// The defaults are those documented: the model chosen at the first
/// non-zero values (a steer-damping sweep from 0 goes through the model
/// with steer damping), speeds searched from 0 to 10 m/s, standard
/// deviations asked; and the sweep at given speeds finds the benchmark's
/// weave speed at its own trail.
#[test]
fn the_sweep_job_defaults_and_its_model_choice() {
    let o = SweepOptions::new("c_steer", vec![0.0, 1.0]);
    assert!(o.model.is_none() && o.second.is_none() && o.at_speed.is_none() && o.standard_deviations);
    assert_eq!(o.speed_max, 10.0);
    let b = Bicycle::resolve("benchmark").unwrap();
    let damped = b.with_parameter("c_steer", 1.0).unwrap().model(None).unwrap().name;
    assert_ne!(damped, b.model(None).unwrap().name);
    assert_eq!(sweep_model(&b, &o).unwrap(), damped);
    let SweepReport::Parameter(p) = sweep(&b, &o, &no_progress).unwrap() else {
        panic!("one parameter: no map");
    };
    assert_eq!(p.model, damped);
    assert_eq!(p.speed_range, [0.0, 10.0]);
    // A built-in bicycle has no `+/-` values.
    assert!(p.standard_deviations.is_none() && !p.standard_deviations_missing);
    let named = SweepOptions {
        model: Some("extended".into()),
        ..SweepOptions::new("c", vec![0.08])
    };
    assert_eq!(sweep_model(&b, &named).unwrap(), "extended");

    let speeds: Vec<f64> = (0..=20).map(|k| 0.5 * k as f64).collect();
    let s = sweep_at_speeds(&b, &SweepOptions::new("c", vec![0.08, 0.1]), &speeds).unwrap();
    assert_eq!((s.designs, s.least_stable_real_part.len()), (2, 42));
    assert!(
        (s.weave_speed[0] - 4.292_382_536_341_11).abs() < 1e-8,
        "{:?}",
        s.weave_speed
    );
    assert!(
        (s.capsize_speed[0] - 6.024_262_015_388_37).abs() < 1e-8,
        "{:?}",
        s.capsize_speed
    );
    // Unstable at rest, stable at 5 m/s.
    assert!(s.least_stable_real_part[0] > 0.0 && s.least_stable_real_part[10] < 0.0);
}

/// Bad options are typed errors naming the field, and failed designs an
/// error listing them, never a panic or a table with messages in it.
#[test]
fn the_sweep_job_refuses_bad_options_with_a_typed_error() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let run = |o: &SweepOptions| sweep(&b, o, &no_progress);
    let same = SweepOptions {
        second: Some(SweptParameter::new("c", vec![0.1])),
        ..SweepOptions::new("c", vec![0.1])
    };
    assert!(matches!(run(&same), Err(SweepError::SameParameter(p)) if p == "c"));
    assert!(matches!(
        run(&SweepOptions::new("c", Vec::new())),
        Err(SweepError::NoValues("parameter"))
    ));
    let speed_max = SweepOptions {
        speed_max: -1.0,
        ..SweepOptions::new("c", vec![0.1])
    };
    let e = run(&speed_max).unwrap_err();
    assert!(
        matches!(e, SweepError::SpeedMax(_)) && e.to_string().starts_with("speed_max"),
        "{e}"
    );
    let at_speed = SweepOptions {
        at_speed: Some(f64::NAN),
        ..SweepOptions::new("c", vec![0.1])
    };
    let e = run(&at_speed).unwrap_err();
    assert!(
        matches!(e, SweepError::AtSpeed(_)) && e.to_string().starts_with("at_speed"),
        "{e}"
    );
    assert!(matches!(
        run(&SweepOptions::new("nosuch", vec![1.0])),
        Err(SweepError::Bicycle(_))
    ));
    // Steer-axis tilts of 1.6 and 2 rad are no bicycle: both listed.
    let e = run(&SweepOptions::new("lam", vec![0.3, 1.6, 2.0])).unwrap_err();
    let SweepError::FailedDesigns(failed) = &e else {
        panic!("{e}");
    };
    assert_eq!(failed.len(), 2);
    assert_eq!(failed[0].at, [("lam".to_string(), 1.6)]);
    assert!(e.to_string().starts_with("2 of the sweep's designs failed"), "{e}");
    assert!(sweep_at_speeds(&b, &SweepOptions::new("c", vec![0.1]), &[f64::NAN]).is_err());
}

/// The main job (`bikedyn report`) is one library call: every built-in
/// model passes its verification, each built-in bicycle has its figures
/// and files (the benchmark's weave speed to 1e-10), the files are in the
/// target folder once the job returns, and a folder bikedyn did not write
/// is refused before anything is computed, left as it was.
#[test]
fn the_main_job_verifies_the_models_and_writes_each_bicycles_figures() {
    use bikedyn::main_report::{main_report, MainReportError, MainReportOptions};
    let dir = crate::common::scratch("main-job");
    let out = dir.join("report");
    let _ = std::fs::remove_dir_all(&out);
    let options = MainReportOptions {
        identify: false,
        ..MainReportOptions::new(&out)
    };
    let r = main_report(&options, &bikedyn::progress::ignore).unwrap();
    assert!(r.verified(), "{:?}", r.verified);
    assert_eq!(r.verified.len(), bikedyn::models::model_names().len());
    assert_eq!(r.bicycles.len(), bikedyn::bicycle::BUILT_IN.len());
    let benchmark = r.bicycles.iter().find(|b| b.name == "benchmark").unwrap();
    assert!((benchmark.critical.weave_speed.unwrap() - 4.292_382_536_341_11).abs() < 1e-10);
    for b in &r.bicycles {
        assert_eq!(b.files.len(), 5, "{:?}", b.files);
        for f in &b.files {
            assert!(f.starts_with(&out) && f.is_file(), "{}", f.display());
        }
    }
    assert!(r.identification.is_none());

    let foreign = dir.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let refused = main_report(
        &MainReportOptions {
            identify: false,
            ..MainReportOptions::new(&foreign)
        },
        &bikedyn::progress::ignore,
    );
    assert!(
        matches!(refused, Err(MainReportError::Output(_))),
        "{:?}",
        refused.err()
    );
    assert_eq!(std::fs::read_to_string(foreign.join("notes.txt")).unwrap(), "mine");
    let _ = std::fs::remove_dir_all(&dir);
}
