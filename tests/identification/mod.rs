//! Closing the loop: for every effect identification
//! supports, a set made by `bikedyn synth` with that effect hidden; the
//! effect must be selected, its parameter recovered within 20 %, and the
//! error it drives must fall by at least half. A control set with no hidden
//! mechanical effect must get none. Each set has 6 runs of the thesis
//! bicycle at 4-6.5 m/s (its self-stable range, like the thesis's tests),
//! with the default sensor effects (misalignment, noise, drift, clock
//! offset, magnet spacing errors, switch bounce).

use crate::common::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

mod discovery;
mod eigenvalue_tables;
mod kick_fits;
mod parameter_errors;
mod result_schema;

fn synth(name: &str, effects: &str, seed: u64) -> PathBuf {
    synth_with(name, None, effects, seed)
}

fn synth_with(name: &str, model: Option<&str>, effects: &str, seed: u64) -> PathBuf {
    let dir = scratch("identify").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    let seed = seed.to_string();
    let mut args = vec![
        "synth", "--bike", "thesis", "--speeds", "4:6.5", "--runs", "6", "--seed", &seed,
    ];
    if !effects.is_empty() {
        args.extend(["--effects", effects]);
    }
    if let Some(m) = model {
        args.extend(["--model", m]);
    }
    args.extend(["--out", dir.to_str().unwrap()]);
    let out = bikedyn(&args);
    assert!(out.status.success(), "synth: {}", String::from_utf8_lossy(&out.stderr));
    dir
}

/// A 12-run set of the thesis bicycle at synth's default speeds (3-7 m/s),
/// with `effects` hidden.
fn synth_twelve(name: &str, effects: &str, seed: u64) -> PathBuf {
    let dir = scratch("identify").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    let seed = seed.to_string();
    let out = bikedyn(&[
        "synth",
        "--bike",
        "thesis",
        "--runs",
        "12",
        "--seed",
        &seed,
        "--effects",
        effects,
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "synth: {}", text(&out.stderr));
    dir
}

/// The effects (and corrections) an identify report selected, in order.
fn selected_effects(j: &Value) -> Vec<&str> {
    j["selected_effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect()
}

fn identify(dir: &Path, report: Option<&Path>) -> Value {
    identify_with(dir, report, &[])
}

fn identify_with(dir: &Path, report: Option<&Path>, extra: &[&str]) -> Value {
    let mut args = vec!["identify", dir.to_str().unwrap(), "--json"];
    args.extend(extra);
    if let Some(r) = report {
        args.extend(["--report", r.to_str().unwrap()]);
    }
    let out = bikedyn(&args);
    assert!(
        out.status.success(),
        "identify: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Not a terminal: one progress line per step with its count and, in a
    // counted stage past its first step, the estimate of the time left
    // (issue 17, point 5; issue 20, point 2).
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("progress: runs processed (1 of ")
            && err.contains("progress: fitted base model (1 of 1, ")
            && err.contains("progress: score test of "),
        "{err}"
    );
    let runs = err
        .lines()
        .filter(|l| l.starts_with("progress: runs processed"))
        .count();
    if runs >= 3 {
        assert!(
            err.lines()
                .any(|l| l.starts_with("progress: runs processed (2 of ") && l.contains("left in this stage)")),
            "{err}"
        );
    }
    for l in err
        .lines()
        .filter(|l| l.starts_with("progress: fitted ") || l.starts_with("progress: cross-validated "))
    {
        assert!(l.contains(" of "), "a counted stage without its count: {l}");
    }
    let j: Value = serde_json::from_slice(&out.stdout).expect("JSON output");
    every_unseparated_pair_says_why(&j);
    j
}

/// A pair is reported not separated only for a stated reason: estimates
/// that correlate at or above 0.9, or a rival that passed cross-validation
/// too and whose paired held-out gain over the added candidate is within
/// two standard errors either way.
fn every_unseparated_pair_says_why(j: &Value) {
    // And the remaining-residual verdict agrees with its own test.
    if let Some(r) = j["remaining"].as_object() {
        let p = f(&r["p_value"]);
        assert_eq!(r["structured"], p < 0.01, "{r:#?}");
        assert!(f(&r["floor_rms"]) >= 0.0 && r["kicks"].as_u64().unwrap() >= 4, "{r:#?}");
    }
    for c in j["confounded"].as_array().expect("confounded list") {
        let gain = c["held_out_gain"].as_f64();
        let se = c["held_out_gain_stderr"].as_f64();
        let alike = matches!((gain, se), (Some(g), Some(s)) if g.abs() <= 2.0 * s);
        assert_eq!(c["predicts_alike"], alike, "{c:#}");
        let correlated = f(&c["correlation"]) >= 0.9;
        assert_eq!(c["confounded"], correlated || alike, "{c:#}");
        if gain.is_some() {
            let rival = j["candidates"]
                .as_array()
                .unwrap()
                .iter()
                .find(|t| t["name"] == c["rival"] && t["step"] == c["step"])
                .expect("the rival's trial");
            assert!(
                rival["verdict"].as_str().unwrap().starts_with("passed"),
                "a held-out gain for a rival that did not pass: {rival:#}"
            );
        }
    }
}

/// A synthetic run's truth (synth's `truth/<run>_truth.json`): the mean
/// speed after the release (m/s) and the weave eigenvalue `[re, im]` (1/s)
/// of the simulated model's linear equations at that speed.
fn truth_weave(path: &std::path::Path) -> (f64, [f64; 2]) {
    let t: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let weave = t["frozen_speed_eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|z| [f(&z[0]), f(&z[1])])
        .max_by(|a, b| a[1].total_cmp(&b[1]))
        .unwrap();
    (f(&t["mean_speed_after_release"]), weave)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or(f64::NAN)
}

/// The hidden effect is selected alone, its parameter within 20 %, and the
/// error it drives (`error_key`) at least halved.
fn recovers(name: &str, effects: &str, seed: u64, selected: &str, symbol: &str, truth: f64, error_key: &str) {
    recovers_with_args(name, None, &[], effects, seed, selected, symbol, truth, error_key)
}

/// [`recovers`] on runs of `model`, with more arguments to `identify`.
#[allow(clippy::too_many_arguments)]
fn recovers_with_args(
    name: &str,
    model: Option<&str>,
    args: &[&str],
    effects: &str,
    seed: u64,
    selected: &str,
    symbol: &str,
    truth: f64,
    error_key: &str,
) {
    let dir = synth_with(name, model, effects, seed);
    let j = identify_with(&dir, None, args);
    let sel = selected_effects(&j);
    assert_eq!(sel, vec![selected], "{name}: selected {sel:?}\n{j:#}");
    let v = f(&j["parameters"][symbol]["value"]);
    assert!(
        ((v - truth) / truth).abs() < 0.2,
        "{name}: {symbol} = {v}, hidden {truth}"
    );
    let (lo, hi) = (f(&j["parameters"][symbol]["low"]), f(&j["parameters"][symbol]["high"]));
    assert!(lo < v && v < hi, "{name}: interval [{lo}, {hi}] around {v}");
    let (before, after) = (f(&j["error_before"][error_key]), f(&j["error_after"][error_key]));
    assert!(after <= 0.5 * before, "{name}: {error_key} {before} -> {after}");
    // Held out too: the effect generalises to runs it was not fitted on.
    let (hb, ha) = (
        f(&j["error_before"]["held_out"][error_key]),
        f(&j["error_after"]["held_out"][error_key]),
    );
    assert!(ha <= 0.5 * hb, "{name}: held-out {error_key} {hb} -> {ha}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hidden_steer_damping_is_found() {
    recovers(
        "damping",
        "c_steer=0.25",
        22,
        "steer_damping",
        "c_steer",
        0.25,
        "eigen_rms",
    );
}

#[test]
fn hidden_steer_friction_is_found() {
    recovers(
        "friction",
        "T_steer=0.1",
        23,
        "steer_friction",
        "T_steer",
        0.1,
        "roll_rms",
    );
}

/// The friction's smoothing rate is fitted with its torque: runs made with
/// a law sharper than the model's default (0.03 against 0.1 rad/s) give
/// back both. Held at the default, the rate was wrong and the torque took
/// up the difference.
#[test]
#[ignore = "about 3 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn hidden_steer_friction_gives_back_its_smoothing_rate() {
    let dir = synth_with("friction_sharp", None, "T_steer=0.1,w_steer=0.03", 31);
    let j = identify_with(&dir, None, &[]);
    assert_eq!(selected_effects(&j), vec!["steer_friction"], "{j:#}");
    for (symbol, truth) in [("T_steer", 0.1), ("w_steer", 0.03)] {
        let v = f(&j["parameters"][symbol]["value"]);
        assert!(((v - truth) / truth).abs() < 0.2, "{symbol} = {v}, hidden {truth}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn hidden_lateral_mass_offset_is_found() {
    recovers("offset", "y3=0.02", 24, "lateral_mass_offset", "y3", 0.02, "roll_rms");
}

#[test]
fn hidden_steer_controller_is_found() {
    recovers(
        "controller",
        "Kc_roll_rate=0.6",
        25,
        "steer_controller",
        "Kc_roll_rate",
        0.6,
        "eigen_rms",
    );
}

#[test]
fn hidden_rolling_resistance_is_found() {
    recovers(
        "rolling",
        "Crr_rear=0.01,Crr_front=0.01",
        26,
        "rolling_resistance (speed decay)",
        "Crr_rear",
        0.01,
        "speed_rms",
    );
}

#[test]
fn hidden_aero_drag_is_found() {
    recovers(
        "drag",
        "CdA=0.5,rho_air=1.2",
        27,
        "aero_drag (speed decay)",
        "CdA",
        0.5,
        "speed_rms",
    );
}

#[test]
fn hidden_tyre_relaxation_is_found() {
    // The runs come from the tyre model (lateral slip with relaxation,
    // cornering stiffness 14 per unit load); identification starts from the
    // no-slip model and fits the relaxation length, with each kick's tyre
    // forces and their rates at the window start as nuisances (the window
    // starts a few hundredths of a second after the kick, within one
    // relaxation time). Every correction is a candidate too, and none
    // joins: before the forces' rates were nuisances, corrections of I3z
    // and I4xz absorbed the lag of the forces behind the slip.
    recovers_with_args(
        "tyre",
        Some("tyre_free"),
        &[],
        "sigma_rear=0.4,sigma_front=0.4",
        28,
        "tyre_relaxation",
        "sigma_rear",
        0.4,
        "roll_rms",
    );
}

#[test]
fn control_set_gets_no_effect() {
    let dir = synth("control", "", 21);
    let report = dir.join("report");
    let j = identify(&dir, Some(&report));
    assert_eq!(j["selected_effects"].as_array().unwrap().len(), 0, "{j:#}");
    assert_eq!(j["parameters"].as_object().unwrap().len(), 0);
    let md = std::fs::read_to_string(report.join("report.md")).unwrap();
    assert!(md.contains("No effect warranted"), "{md}");
    // The base model is the right one: what it leaves is the kicks'
    // scatter, and the report says so.
    assert_eq!(j["remaining"]["structured"], false, "{:#}", j["remaining"]);
    assert!(md.contains("no structured residual remains in the weave"), "{md}");
    // So no force beyond the library is searched for.
    assert_eq!(j["discovery"]["status"], "not_run", "{:#}", j["discovery"]);
    // Every candidate was tried and got a score.
    let n = j["candidates"].as_array().unwrap().len();
    assert!(n >= 7, "{n} candidates");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn example_set_report_folder() {
    let dir = scratch("identify").join("report");
    let _ = std::fs::remove_dir_all(&dir);
    let set = example_set();
    let j = identify(&set, Some(&dir));
    assert_eq!(j["selected_effects"][0], "steer_damping");
    // Issue 33, item 1: with no compute budget (the default) the search
    // ends only when every candidate predicted to gain has been fitted
    // and failed; none is left unfitted for want of budget.
    let unfitted: Vec<&Value> = j["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["outcome"]["kind"] == "beyond_budget")
        .collect();
    assert!(unfitted.is_empty(), "{unfitted:#?}");
    // Each trial is fitted once a step and listed once: the speed loss's
    // pair, fitted as one trial, is not fitted again by the search over
    // pairs when no single candidate passes.
    let mut trials: Vec<(i64, &str)> = j["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| (c["step"].as_i64().unwrap(), c["name"].as_str().unwrap()))
        .collect();
    let listed = trials.len();
    trials.sort();
    trials.dedup();
    assert_eq!(trials.len(), listed, "a trial listed twice in a step");
    // Issue 33, item 4: an added candidate's claim says how consistent its
    // held-out gain was (the bar it passed: two standard errors), in the
    // JSON and in the report's words.
    let added: Vec<&Value> = j["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["outcome"]["kind"] == "added")
        .collect();
    assert!(!added.is_empty());
    for c in &added {
        let g = &c["outcome"]["held_out_gain"];
        let (gain, stderr) = (g["gain"].as_f64().unwrap(), g["stderr"].as_f64().unwrap());
        assert!(gain > 2.0 * stderr, "{c:#}");
        assert!(c["verdict"].as_str().unwrap().contains("(1 SE, "), "{c:#}");
    }
    for f in [
        "report.md",
        "report.json",
        "fitted.toml",
        "continuation.svg",
        "run_residuals.svg",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    // Issue 20: the continuation before and after tells real (solid) and
    // imaginary (dashed) parts apart, shows the measured points with a
    // legend entry, and its title names bicycle and model.
    let svg = std::fs::read_to_string(dir.join("continuation.svg")).unwrap();
    assert!(svg.matches("stroke-dasharray").count() >= 2, "dashed imaginary parts");
    assert!(
        svg.contains(">measured real part (bar: 1 s.e.)<"),
        "measured in the legend"
    );
    assert!(svg.contains("bicycle thesis, model"), "title");
    // The fitted parameter file loads, carries the effect, and refits to
    // nothing more.
    let toml = std::fs::read_to_string(dir.join("fitted.toml")).unwrap();
    assert!(toml.contains("c_steer"), "{toml}");
    let fitted = dir.join("fitted.toml");
    let out = bikedyn(&["params", "show", "--bike", fitted.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_inputs_are_clear_errors() {
    let out = bikedyn(&["identify", "/nonexistent/set"]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("/nonexistent/set"), "{e}");
    let set = example_set();
    let out = bikedyn(&["identify", set.to_str().unwrap(), "--effects", "flux_capacitor"]);
    assert!(!out.status.success());
    let e = String::from_utf8_lossy(&out.stderr);
    assert!(e.contains("flux_capacitor") && e.contains("steer_damping"), "{e}");
    // A compute budget of no fit, or one on a table (whose search fits
    // every candidate), is refused by name before any work.
    for (bad, named) in [
        (vec!["--max-fits-per-step", "0"], "--max-fits-per-step"),
        (
            vec!["--max-fits-per-step", "4", "--eigenvalues", "t.csv", "--bike", "thesis"],
            "--eigenvalues",
        ),
    ] {
        let mut args = vec!["identify", set.to_str().unwrap()];
        args.extend(bad.iter().copied());
        let out = bikedyn(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(named), "{args:?}: {e}");
    }
    // The family-wise bar is the library search's; a table's search has its
    // own bars, so the flag there is refused by name.
    for flag in ["--family-wise-bar"] {
        let out = bikedyn(&["identify", flag, "--eigenvalues", "t.csv", "--bike", "thesis"]);
        assert_eq!(out.status.code(), Some(2));
        let e = String::from_utf8_lossy(&out.stderr);
        assert!(e.contains(flag) && e.contains("--eigenvalues"), "{e}");
    }
}

/// `identify --eigenvalues`: effects fitted to a table of measured weave
/// eigenvalues (no time series), with a header row in the authors' own
/// words and semicolons. A table of the thesis bicycle with steer damping
/// 0.3 N m s/rad (the model's weave at nine speeds, perturbed by 0.05 1/s)
/// gives `steer_damping` within 5 %; the same table without damping gives
/// nothing; a row with four fields is an error naming the file and line.
#[test]
fn measured_eigenvalue_tables_are_identified() {
    let dir = scratch("identify-eigen-table");
    // Headers in whatever words the table's authors chose.
    let header = "Geschwindigkeit [m/s]; Realteil; Imaginaerteil; sigma Re; sigma Im";
    let table = |name: &str, c_steer: Option<f64>| eigenvalue_tables::weave_table(name, c_steer, "3:7:0.5", header);
    let damped = table("damped", Some(0.3));
    let v = ok_json(&[
        "identify",
        "--eigenvalues",
        damped.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ]);
    assert_eq!(v["selected_effects"], serde_json::json!(["steer_damping"]), "{v}");
    let c = v["parameters"]["c_steer"]["value"].as_f64().unwrap();
    assert!((c - 0.3).abs() < 0.015, "c_steer {c}");
    let before = v["error_before"]["eigen_rms"].as_f64().unwrap();
    assert!(v["error_after"]["eigen_rms"].as_f64().unwrap() < 0.5 * before);
    assert!(v["error_after"]["held_out"]["eigen_rms"].as_f64().unwrap() < 0.5 * before);
    // With the damping found, what remains is the rows' scatter.
    assert_eq!(v["remaining"]["structured"], false, "{:#}", v["remaining"]);
    // A library without damping cannot explain it: a lateral mass offset
    // takes up most of the shift, and what it leaves is a pattern over
    // speed beyond the rows' scatter, which the summary says in words.
    let args = [
        "identify",
        "--eigenvalues",
        damped.to_str().unwrap(),
        "--bike",
        "thesis",
        "--effects",
        "lateral_mass_offset",
    ];
    let v = ok_json(&[&args[..], &["--json"]].concat());
    let r = &v["remaining"];
    assert_eq!(r["structured"], true, "{r:#}");
    assert!(f(&r["p_value"]) < 0.01 && f(&r["explained"]) < 1.0, "{r:#}");
    assert!(f(&r["after_rms"]) > 1.5 * f(&r["floor_rms"]), "{r:#}");
    let summary = text(&bikedyn(&args).stdout);
    assert!(
        summary.contains("a structured residual remains: the library explains"),
        "{summary}"
    );

    let plain = table("plain", None);
    let v = ok_json(&[
        "identify",
        "--eigenvalues",
        plain.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ]);
    assert_eq!(v["selected_effects"], serde_json::json!([]), "{v}");

    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "v,re,im\n4,-1,5\n5,-1.2,6\n6,-1.3,7,0.1\n").unwrap();
    let out = bikedyn(&["identify", "--eigenvalues", bad.to_str().unwrap(), "--bike", "thesis"]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("bad.csv:4") && err.contains("4 fields"), "{err}");
}

/// A kick window starts while the tyre forces are still building up. With
/// a tyre model, those forces and their rates (which set the slip) at the
/// window start are nuisances of each kick like its roll and steer: a
/// response simulated from lateral forces of 40 N (rear) and -25 N (front)
/// changing at 300 and -150 N/s is fitted to rounding, and the forces and
/// rates are recovered, from a start at rest.
#[test]
fn tyre_forces_at_the_window_start_are_fitted_per_kick() {
    use bikedyn::generated::TyreFree;
    use bikedyn::runtime::identify::{fit_candidate, IdentifyOptions, Segment, Setup, Weights, INITIAL_MOTION};
    use bikedyn::runtime::linearize::parameter_vector;
    use bikedyn::runtime::model::CoordinateRole as R;
    use bikedyn::runtime::parameters::ThesisParameters;
    use bikedyn::runtime::simulate::{simulate, Inputs};
    use bikedyn::runtime::MultibodyModel;
    type M = TyreFree;

    let thesis = ThesisParameters::thesis_bicycle();
    let mut param = parameter_vector::<M>(|s| thesis.get(s), 5.0).unwrap();
    for s in ["sigma_rear", "sigma_front"] {
        param[M::parameter_index(s).unwrap()] = 0.4;
    }
    let forces = [40.0, -25.0];
    let rates = [300.0, -150.0];
    assert_eq!(M::STATES, ["Fy_rear", "Fy_front"]);
    // The parameter vector's tail holds the extra states' initial values.
    let np = M::PARAMETERS.len();
    assert_eq!(param.len(), np + 2);
    let mut with_forces = param.clone();
    with_forces[np..].copy_from_slice(&forces);
    let (mut ic, opts) = kick_and_tight_options();
    ic.state_rates = rates;
    let sim = simulate::<M>(&with_forces, &ic, &Inputs::default(), 3.0, &opts).unwrap();
    let roll = sim.require_coordinate(R::Roll, "test").unwrap();
    let steer = sim.require_coordinate(R::Steer, "test").unwrap();
    let speed_t: Vec<f64> = sim.t.iter().step_by(25).copied().collect();
    let speed: Vec<f64> = sim.speed.iter().step_by(25).copied().collect();
    let seg = Segment::new(
        "synthetic".into(),
        0.0,
        sim.t.clone(),
        roll,
        steer,
        speed_t,
        speed,
        None,
    )
    .unwrap();
    assert!(
        seg.initial[INITIAL_MOTION..].iter().all(|x| *x == 0.0),
        "the fit starts from forces at rest"
    );
    let weights = [Weights {
        roll: 0.005,
        steer: 0.01,
        speed: 0.05,
    }];
    let segments = [seg];
    let setup = Setup::new::<M>(&param, &segments, &weights, &[]).unwrap();
    let x0 = [segments[0].initial];
    let fit = fit_candidate(&setup, vec![], &[], &x0, &[], &IdentifyOptions::default(), None).unwrap();
    let fitted = &fit.nuisance[0];
    println!("fitted window-start state {fitted:?}, chi2 {:.3e}", fit.chi2);
    // Layout: the initial motion, then the states, then their rates.
    for (i, (f, r)) in forces.iter().zip(&rates).enumerate() {
        let (ff, fr) = (fitted[INITIAL_MOTION + i], fitted[INITIAL_MOTION + 2 + i]);
        assert!((ff - f).abs() < 0.5, "force {i}: fitted {ff} N, simulated from {f} N");
        assert!(
            (fr - r).abs() < 5.0,
            "force rate {i}: fitted {fr} N/s, simulated from {r} N/s"
        );
    }
    assert!(
        (fitted[0] - ic.roll).abs() < 1e-5 && (fitted[3] - ic.steer_rate).abs() < 1e-4,
        "{fitted:?}"
    );
    assert!(fit.chi2 < 1e-6, "chi2 {}", fit.chi2);
}

/// Coulomb friction's law is not smooth at zero torque: the score test
/// cannot judge it from its slope there, so it is fitted in every step;
/// viscous damping and the speed-loss effects are smooth and are screened.
#[test]
fn a_candidate_with_a_describing_function_is_fitted_not_screened() {
    use bikedyn::bicycle::Bicycle;
    use bikedyn::identify::candidates::{candidates, identification_models};
    let bike = Bicycle::resolve("thesis").expect("built-in bicycle");
    let (model, _, alt) = identification_models(&bike, false).expect("models");
    let all = candidates(model, alt, &bike, &[], false).expect("candidates");
    let flag = |name: &str| all.iter().find(|c| c.name == name).map(|c| c.nonsmooth);
    assert_eq!(flag("steer_friction"), Some(true));
    assert_eq!(flag("steer_damping"), Some(false));
    assert_eq!(flag("rolling_resistance"), Some(false));
}

/// A friction's smoothing rate is the shape of its law, not its size: it
/// is fitted between its floor and its ceiling from the bicycle's value,
/// and a file that sets it (and no torque) still leaves friction a
/// candidate, while a file that sets the torque declares it.
#[test]
fn the_friction_smoothing_rate_is_a_shape_fitted_from_the_files_value() {
    use bikedyn::bicycle::Bicycle;
    use bikedyn::identify::candidates::{candidates, identification_models};
    let mut bike = Bicycle::resolve("thesis").expect("built-in bicycle");
    bike.effects.insert("w_steer".into(), 0.04);
    let (model, _, alt) = identification_models(&bike, false).expect("models");
    let all = candidates(model, alt, &bike, &[], false).expect("candidates");
    let friction = all
        .iter()
        .find(|c| c.name == "steer_friction")
        .expect("friction is a candidate");
    let w = friction
        .parameters
        .iter()
        .find(|p| p.symbol == "w_steer")
        .expect("the smoothing rate is fitted");
    assert!(w.shape && !w.dissipative, "{w:?}");
    assert_eq!(w.initial, Some(0.04));
    assert!(
        w.lower.is_some_and(|lo| lo > 0.0) && w.upper.is_some_and(|hi| hi > 0.04),
        "{w:?}"
    );
    assert!(friction.fixed.iter().all(|(s, _)| s != "w_steer"));
    bike.effects.insert("T_steer".into(), 0.05);
    let all = candidates(model, alt, &bike, &[], false).expect("candidates");
    assert!(all.iter().all(|c| c.name != "steer_friction"));
}
