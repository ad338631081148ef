//! Finding what no library names, from a measured eigenvalue table: tables
//! of the thesis bicycle's weave with a force that no library effect
//! expresses are made here, by their own equations (the benchmark form of
//! the bicycle from `bikedyn canonical`, the force written into the state
//! matrix by hand: not the dictionary's code), with seeded measurement
//! scatter. The discovery must name the right kind of term, recover its
//! values within 25 %, and at least halve the held-out error; a table with
//! no such force must get no term.

use crate::common::*;
use nalgebra::{Complex, DMatrix, Matrix2};
use serde_json::Value;

/// The thesis bicycle's canonical matrices `(M0, C1, K0, K2, g)`.
fn thesis_canonical() -> (Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, f64) {
    let v = ok_json(&["canonical", "--bike", "thesis", "--json"]);
    let m = |k: &str| Matrix2::from_fn(|i, j| v[k][i][j].as_f64().unwrap());
    (m("M0"), m("C1"), m("K0"), m("K2"), v["g"].as_f64().unwrap())
}

/// What the table's bicycle has beyond the thesis bicycle's equations
/// (benchmark signs: roll and steer positive to the right).
#[derive(Clone, Copy)]
enum Hidden {
    Nothing,
    /// A steer inertia added to the front assembly (kg m^2).
    SteerInertia(f64),
    /// A steer torque `k` times the roll rate (N m s/rad) reaching the
    /// fork through a first-order lag of `tau` seconds (a controller with
    /// its own dynamics).
    LaggedRollRateToSteer {
        k: f64,
        tau: f64,
    },
}

/// The weave eigenvalue at speed `v` (the complex pair of highest
/// frequency, followed from the bicycle's own when a lag adds a state).
fn weave(hidden: Hidden, v: f64) -> Complex<f64> {
    let (m0, c1, k0, k2, g) = thesis_canonical_cached();
    let mut m = m0;
    let (c, k) = (c1 * v, k0 * g + k2 * v * v);
    let mut extra = None;
    match hidden {
        Hidden::Nothing => {}
        Hidden::SteerInertia(i) => m[(1, 1)] += i,
        Hidden::LaggedRollRateToSteer { k, tau } => extra = Some((k, tau)),
    }
    let mi = m.try_inverse().unwrap();
    let n = if extra.is_some() { 5 } else { 4 };
    let mut a = DMatrix::zeros(n, n);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    let (mk, mc) = (-mi * k, -mi * c);
    for i in 0..2 {
        for j in 0..2 {
            a[(2 + i, j)] = mk[(i, j)];
            a[(2 + i, 2 + j)] = mc[(i, j)];
        }
    }
    if let Some((gain, tau)) = extra {
        // tau z' = -z + gain roll_rate; the steer equation's torque is z.
        a[(4, 4)] = -1.0 / tau;
        a[(4, 2)] = gain / tau;
        a[(2, 4)] = mi[(0, 1)];
        a[(3, 4)] = mi[(1, 1)];
    }
    let ev = a.complex_eigenvalues();
    let mut pairs: Vec<Complex<f64>> = ev.iter().copied().filter(|z| z.im > 1e-9).collect();
    pairs.sort_by(|x, y| y.im.total_cmp(&x.im));
    pairs[0]
}

fn thesis_canonical_cached() -> (Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, f64) {
    static CANONICAL: std::sync::OnceLock<(Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, Matrix2<f64>, f64)> =
        std::sync::OnceLock::new();
    *CANONICAL.get_or_init(thesis_canonical)
}

/// A table at 3-7 m/s in steps of 0.5 m/s with uniform scatter of
/// standard deviation `sd` (1/s) on both parts (seeded), which its
/// standard-error columns state.
fn table(name: &str, hidden: Hidden, sd: f64, seed: u64) -> std::path::PathBuf {
    let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut uniform = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    // A uniform variable on (-0.5, 0.5) has standard deviation 1/sqrt(12).
    let scale = sd * 12f64.sqrt();
    let mut csv = "speed,re,im,sd_re,sd_im\n".to_string();
    for i in 0..9 {
        let v = 3.0 + 0.5 * f64::from(i);
        let w = weave(hidden, v);
        csv += &format!(
            "{v},{:.5},{:.5},{sd},{sd}\n",
            w.re + scale * uniform(),
            w.im + scale * uniform()
        );
    }
    let path = scratch("identify-discovery").join(format!("{name}.csv"));
    std::fs::write(&path, csv).unwrap();
    path
}

fn identify(table: &std::path::Path) -> Value {
    ok_json(&[
        "identify",
        "--eigenvalues",
        table.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ])
}

fn found_terms(v: &Value) -> Vec<Value> {
    assert_eq!(v["discovery"]["status"], "ran", "{:#}", v["discovery"]);
    v["discovery"]["terms"].as_array().unwrap().clone()
}

fn held_out_halved(v: &Value) {
    let (before, held) = (
        v["error_before"]["eigen_rms"].as_f64().unwrap(),
        v["discovery"]["rms_held_out"].as_f64().unwrap(),
    );
    assert!(held <= 0.5 * before, "held out {held} against {before} before");
}

#[test]
fn a_lagged_steer_torque_from_the_roll_rate_is_discovered_with_its_gain_and_lag() {
    let (k, tau) = (6.0, 0.15);
    for seed in [11, 12] {
        let v = identify(&table(
            &format!("lagged-{seed}"),
            Hidden::LaggedRollRateToSteer { k, tau },
            0.03,
            seed,
        ));
        let terms = found_terms(&v);
        let t = terms
            .iter()
            .find(|t| t["term"]["signal"]["kind"] == "rate" && t["term"]["equation"] == "steer")
            .unwrap_or_else(|| panic!("no steer torque from a rate: {:#}", v["discovery"]));
        assert_eq!(t["term"]["signal"]["of"], "roll", "{t:#}");
        assert_eq!(t["term"]["speed_power"], 0, "{t:#}");
        assert_eq!(t["term"]["lagged"], true, "{t:#}");
        let gain = t["coefficient"][0].as_f64().unwrap();
        let lag = t["time_constant"][0].as_f64().unwrap();
        assert!((gain - k).abs() < 0.25 * k, "gain {gain} against {k}");
        assert!((lag - tau).abs() < 0.25 * tau, "lag {lag} against {tau}");
        held_out_halved(&v);
    }
}

#[test]
fn an_added_steer_inertia_is_discovered_where_no_correction_expresses_it() {
    let (m0, ..) = thesis_canonical_cached();
    let added = 0.3 * m0[(1, 1)];
    let v = ok_json(&[
        "identify",
        "--eigenvalues",
        table("inertia", Hidden::SteerInertia(added), 0.03, 21)
            .to_str()
            .unwrap(),
        "--bike",
        "thesis",
        "--corrections",
        "0",
        "--json",
    ]);
    let terms = found_terms(&v);
    let t = &terms[0];
    assert_eq!(t["term"]["signal"]["kind"], "acceleration", "{:#}", v["discovery"]);
    assert_eq!(t["term"]["signal"]["of"], "steer", "{t:#}");
    assert_eq!(t["term"]["equation"], "steer", "{t:#}");
    // The term is `theta delta''` on the right: an added inertia is -theta.
    let found = -t["coefficient"][0].as_f64().unwrap();
    assert!((found - added).abs() < 0.25 * added, "{found} against {added}");
    held_out_halved(&v);
}

#[test]
fn a_table_of_the_bicycle_as_modelled_gets_no_discovered_term() {
    for seed in [31, 32, 33] {
        let v = identify(&table(&format!("control-{seed}"), Hidden::Nothing, 0.03, seed));
        // Nothing structured is left, so nothing is searched for.
        assert_eq!(v["remaining"]["structured"], false, "seed {seed}: {:#}", v["remaining"]);
        assert_eq!(v["discovery"]["status"], "not_run", "seed {seed}: {:#}", v["discovery"]);
        assert!(v["discovery"].get("terms").is_none());
    }
}

#[test]
fn the_summary_says_what_was_discovered_and_the_errors_of_the_three_stages() {
    let path = table("summary", Hidden::LaggedRollRateToSteer { k: 6.0, tau: 0.15 }, 0.03, 41);
    let out = bikedyn(&["identify", "--eigenvalues", path.to_str().unwrap(), "--bike", "thesis"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = text(&out.stdout);
    assert!(
        s.contains("discovered beyond the library: a steer torque from the roll rate"),
        "{s}"
    );
    assert!(s.contains("through a first-order lag of"), "{s}");
    assert!(
        s.contains("weave eigenvalue RMS: base model") && s.contains("with the discovered terms"),
        "{s}"
    );
    let skipped = bikedyn(&[
        "identify",
        "--eigenvalues",
        path.to_str().unwrap(),
        "--bike",
        "thesis",
        "--no-discover",
    ]);
    assert!(
        !text(&skipped.stdout).contains("discovered"),
        "{}",
        text(&skipped.stdout)
    );
}

/// On runs: the committed example set (0.25 N m s/rad of steer damping
/// hidden) identified with a library that lacks steer damping (aero drag
/// only, no corrections). The time series' residual follows the simulated
/// states, and the discovery on the kicks' weave eigenvalues names a steer
/// damper within 25 % of the hidden value and at least halves the kicks'
/// held-out weave error. With the whole library the damping is selected,
/// the residual does not follow the states, and nothing is searched (on
/// the eigenvalues nor in the time series).
#[test]
#[ignore = "about 2 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn on_runs_a_steer_damper_the_library_lacks_is_discovered_on_the_kicks() {
    let set = example_set();
    let v = ok_json(&[
        "identify",
        set.to_str().unwrap(),
        "--effects",
        "aero_drag",
        "--corrections",
        "0",
        "--json",
    ]);
    let follows = |v: &Value| {
        v["state_correlation"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["significant"].as_bool().unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(follows(&v), [true, true], "{:#}", v["state_correlation"]);
    let terms = found_terms(&v);
    let damper = terms
        .iter()
        .find(|t| {
            t["term"]["equation"] == "steer"
                && t["term"]["signal"]["kind"] == "rate"
                && t["term"]["signal"]["of"] == "steer"
                && t["term"]["speed_power"] == 0
                && t["term"]["lagged"] == false
        })
        .unwrap_or_else(|| panic!("no steer damper: {:#}", v["discovery"]));
    // The term is `theta delta'` on the right: a damper is -theta.
    let c = -damper["coefficient"][0].as_f64().unwrap();
    assert!((c - 0.25).abs() <= 0.25 * 0.25, "c = {c}");
    let d = &v["discovery"];
    assert!(
        d["rms_held_out"].as_f64().unwrap() <= 0.5 * d["rms_library_held_out"].as_f64().unwrap(),
        "{d:#}"
    );

    let v = ok_json(&["identify", set.to_str().unwrap(), "--json"]);
    assert_eq!(follows(&v), [false, false], "{:#}", v["state_correlation"]);
    assert_eq!(v["discovery"]["status"], "not_run", "{:#}", v["discovery"]);
    assert_eq!(
        v["time_series_discovery"]["status"], "not_run",
        "{:#}",
        v["time_series_discovery"]
    );
}

/// The found time-series terms of an identify JSON, each with its runtime
/// term and `(value, one standard error)` in the benchmark's signs.
fn time_series_terms(v: &Value) -> Vec<Value> {
    let d = &v["time_series_discovery"];
    assert_eq!(d["status"], "ran", "{d:#}");
    d["terms"].as_array().unwrap().clone()
}

/// The roll RMS of a stage (`base`, `library`, `with_terms`) held out.
fn held_out_roll(v: &Value, stage: &str) -> f64 {
    v["time_series_discovery"][stage]["roll_rms_held_out"].as_f64().unwrap()
}

/// In the time series: on the example set identified with a library that
/// lacks steer damping, the dictionary's steer damper is fitted through the
/// nonlinear simulation of every kick (0.25 N m s/rad hidden: within 25 %),
/// and the held-out roll error with it is at most half the library's.
#[test]
fn in_the_time_series_a_steer_damper_the_library_lacks_is_found_and_halves_the_roll_error() {
    let set = example_set();
    let v = ok_json(&[
        "identify",
        set.to_str().unwrap(),
        "--effects",
        "aero_drag",
        "--corrections",
        "0",
        "--json",
    ]);
    let terms = time_series_terms(&v);
    let damper = terms
        .iter()
        .find(|t| {
            t["term"]["equation"] == "steer"
                && t["term"]["signal"]["kind"] == "rate"
                && t["term"]["signal"]["of"] == "steer"
        })
        .unwrap_or_else(|| panic!("no steer damper: {:#}", v["time_series_discovery"]["terms"]));
    assert_eq!(damper["term"]["speed_power"], 0, "{damper:#}");
    let c = -damper["coefficient"][0].as_f64().unwrap();
    assert!((c - 0.25).abs() <= 0.25 * 0.25, "c = {c}");
    assert!(
        held_out_roll(&v, "with_terms") <= 0.5 * held_out_roll(&v, "library"),
        "{:#}",
        v["time_series_discovery"]
    );
}

// A steer torque from the roll angle hidden in runs (no library effect
// expresses it), found in the time series, written as an effect file,
// derived and refitted: `examples/discovered_force/tests/runs.rs`.

/// The same force (3 N m/rad of steer torque per roll angle, through the
/// identification model's dictionary parameter, eight runs at 5.5-7 m/s,
/// sensor errors included) with every declared correction a candidate of
/// the library. The library takes corrections beyond their priors for want
/// of the force, so the search in the time series starts twice: from the
/// library's whole selection, and from it without the corrections beyond
/// their plausible range. Whichever start is kept, the search must end with
/// the force alone, within 25 %, and halve the library's held-out roll
/// error. Which start gets there depends on the criterion: with the
/// criterion of a variance per kick and channel, the first start added a
/// steer stiffness growing with v^2 and saw no gain left for the force
/// (roll error 0.43 deg), and only the second found it; with the criterion
/// on the fits' own weighted sum (on its branch, stop 72) the first start
/// already ended at the force and the second, equal to it, was not kept (the second start is kept only
/// when it predicts the held-out runs better by more than one standard
/// error). (Seed 11, the example's in `examples/discovered_force`, takes a
/// third path: the force enters beside the stand-ins, and the backward
/// check removes them.)
#[test]
#[ignore = "about 15 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn in_runs_the_search_ends_at_the_force_that_implausible_corrections_stood_in_for_from_either_start() {
    let dir = scratch("identify").join("steer_torque_roll_runs");
    let _ = std::fs::remove_dir_all(&dir);
    let out = bikedyn(&[
        "synth",
        "--bike",
        "thesis",
        "--effects",
        "Q_steer_torque_roll=-3",
        "--speeds",
        "5.5:7",
        "--runs",
        "8",
        "--seed",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "synth: {}", text(&out.stderr));
    let v = ok_json(&["identify", dir.to_str().unwrap(), "--bike", "thesis", "--json"]);
    // The library's stand-ins were beyond their priors: a second start ran.
    let second = &v["time_series_discovery"]["second_start"];
    assert!(
        second["left_out"].as_array().is_some_and(|l| !l.is_empty()),
        "no second start: {:#}",
        v["time_series_discovery"]
    );
    // One not kept was no better on held-out runs by one standard error.
    if second["kept_second"] == Value::from(false) {
        let number = |k: &str| second[k].as_f64().unwrap_or(f64::NAN);
        assert!(
            !(number("cv_first") - number("cv_second") > number("standard_error")),
            "{second:#}"
        );
    }
    let terms = time_series_terms(&v);
    assert_eq!(terms.len(), 1, "{:#}", v["time_series_discovery"]);
    let t = &terms[0]["term"];
    assert_eq!(
        (
            &t["equation"],
            &t["signal"]["kind"],
            &t["signal"]["of"],
            &t["speed_power"]
        ),
        (
            &Value::from("steer"),
            &Value::from("angle"),
            &Value::from("roll"),
            &Value::from(0)
        ),
        "{:#}",
        terms[0]
    );
    let k = terms[0]["coefficient"][0].as_f64().unwrap();
    assert!((k - 3.0).abs() <= 0.25 * 3.0, "k = {k} N m/rad");
    // The final model is the force alone: every correction the library
    // took has left it.
    let symbols: Vec<&str> = v["time_series_discovery"]["after"]["parameters"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["symbol"].as_str().unwrap())
        .collect();
    assert_eq!(
        symbols,
        ["Q_steer_torque_roll"],
        "{:#}",
        v["time_series_discovery"]["final_check"]
    );
    assert!(
        held_out_roll(&v, "with_terms") <= 0.5 * held_out_roll(&v, "library"),
        "{:#}",
        v["time_series_discovery"]
    );
}

/// Every term of the runtime's time-series dictionary is a parameter of
/// both identification models (the modeler's `generalized_forces` effect
/// and the runtime's term names are written apart), absent at its default,
/// and its model sign converts the benchmark's signs as the steer's sign
/// demands.
#[test]
fn every_term_of_the_time_series_dictionary_is_a_parameter_of_the_identification_models() {
    use bikedyn::registry::ModelRegistry;
    use bikedyn_runtime::identify::discovery::{Coordinate, Signal, Term};
    let models = bikedyn::registry::BuiltIn::models();
    let terms = Term::time_series_dictionary();
    assert_eq!(terms.len(), 28);
    for name in ["extended", "extended_free"] {
        let info = models.iter().find(|m| m.name == name).unwrap();
        assert!(
            info.effects.contains(&"generalized_forces"),
            "{name}: {:?}",
            info.effects
        );
        for t in &terms {
            let p = info
                .parameter(&t.model_symbol())
                .unwrap_or_else(|| panic!("{name} lacks {}", t.model_symbol()));
            assert_eq!(p.default, Some(0.0), "{}", t.model_symbol());
        }
        // The candidates the application builds are exactly these.
        assert_eq!(bikedyn::identify::time_series::terms(info).len(), terms.len());
    }
    let t = |equation, signal| Term {
        equation,
        signal,
        speed_power: 0,
        lagged: false,
    };
    assert_eq!(t(Coordinate::Steer, Signal::Angle(Coordinate::Roll)).model_sign(), -1.0);
    assert_eq!(t(Coordinate::Steer, Signal::Rate(Coordinate::Steer)).model_sign(), 1.0);
    assert_eq!(t(Coordinate::Steer, Signal::Constant).model_sign(), -1.0);
    assert_eq!(t(Coordinate::Roll, Signal::Constant).model_sign(), 1.0);
    assert_eq!(
        t(Coordinate::Steer, Signal::Coulomb(Coordinate::Steer)).model_sign(),
        1.0
    );
}
