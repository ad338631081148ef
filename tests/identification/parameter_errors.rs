//! Errors in measured parameters: a correction found beside an effect, one
//! beyond its prior rather than a proxy for it, and a mass centre corrected
//! as a whole.

use super::*;

/// A cause no effect file declares: the frame's roll inertia 25 % high (a
/// parameter error, as from a mis-measured pendulum swing) plus weak steer
/// damping. Both the correction of `I3x` (within its 10 % prior, which the
/// data overrule) and the damping are selected, each within 20 % of the
/// truth, and the roll and steer errors at least halved, on held-out runs
/// too.
#[test]
#[ignore = "about 4 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn a_frame_inertia_error_is_corrected_beside_steer_damping() {
    let i3x = 0.3295 * 1.25;
    let dir = synth_twelve("inertia", &format!("I3x={i3x},c_steer=0.1"), 31);
    // Corrections are candidates by default (issue 17, point 1).
    let out = bikedyn(&["identify", dir.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "identify: {}", text(&out.stderr));
    let j = stdout_json(&out);
    let mut sel = selected_effects(&j);
    sel.sort();
    assert_eq!(sel, vec!["correct I3x", "steer_damping"], "{j:#}");
    // Steer damping alone explains most of the slower, more damped weave;
    // the frame's roll inertia alone would have to move 6 prior standard
    // deviations to do the same, so it is no rival explanation of the first
    // step (a rival is offered only when plausible under its prior), and it
    // joins as a correction beside the damping, within its prior.
    for c in j["confounded"].as_array().unwrap() {
        let rival = c["rival"].as_str().unwrap();
        let step = c["step"].as_u64().unwrap();
        let fit = j["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .find(|t| t["name"] == rival && t["step"] == step)
            .unwrap();
        assert!(
            !fit["verdict"].as_str().unwrap().contains("prior standard deviations"),
            "an implausible rival offered: {c:#}"
        );
    }
    let i3x_sds = f(&j["parameters"]["I3x"]["prior_sds"]);
    assert!(
        i3x_sds.abs() <= 3.0,
        "correct I3x {i3x_sds} prior sd from the measured value"
    );
    for (symbol, truth) in [("I3x", i3x), ("c_steer", 0.1)] {
        let v = f(&j["parameters"][symbol]["value"]);
        assert!(((v - truth) / truth).abs() < 0.2, "{symbol} = {v}, hidden {truth}");
    }
    for key in ["roll_rms", "steer_rms"] {
        let (before, after) = (f(&j["error_before"][key]), f(&j["error_after"][key]));
        assert!(after <= 0.5 * before, "{key} {before} -> {after}");
        let (hb, ha) = (
            f(&j["error_before"]["held_out"][key]),
            f(&j["error_after"]["held_out"][key]),
        );
        assert!(ha <= 0.5 * hb, "held-out {key} {hb} -> {ha}");
    }
    // Issue 17, point 6: the weave eigenvalue error, weighted by each
    // fit's standard error, at least halves on fitted and held-out runs.
    // The plain RMS is held to a floor instead: the fitted eigenvalues
    // scatter about the truth's (the frozen-speed weave of the simulated
    // model, in synth's truth files) by about 0.35 1/s over the 11 kicks
    // `fit` accepts (0.38 over all 12, when it could not halve).
    for part in [&j["error_before"], &j["error_after"]] {
        assert!(part["eigen_weighted_rms"].is_number() && part["held_out"]["eigen_weighted_rms"].is_number());
    }
    let (wb, wa) = (
        f(&j["error_before"]["eigen_weighted_rms"]),
        f(&j["error_after"]["eigen_weighted_rms"]),
    );
    assert!(wa <= 0.5 * wb, "weighted weave RMS {wb} -> {wa}");
    let (hb, ha) = (
        f(&j["error_before"]["held_out"]["eigen_weighted_rms"]),
        f(&j["error_after"]["held_out"]["eigen_weighted_rms"]),
    );
    assert!(ha <= 0.5 * hb, "held-out weighted weave RMS {hb} -> {ha}");
    let kicks = ok_json(&["fit", dir.to_str().unwrap(), "--json"]);
    let mut ss = Vec::new();
    for k in kicks.as_array().unwrap() {
        // The kicks whose fit is a measured weave eigenvalue, as in the
        // eigenvalue figures (run05's standard errors are a seventh of its
        // eigenvalue: refused).
        if k["weave"].is_null() {
            continue;
        }
        let run = std::path::Path::new(k["run"].as_str().unwrap())
            .file_name()
            .unwrap()
            .to_string_lossy()
            .into_owned();
        let (_, weave) = truth_weave(&dir.join(format!("truth/{run}_truth.json")));
        let m = [f(&k["weave"][0]), f(&k["weave"][1])];
        ss.push((m[0] - weave[0]).powi(2) + (m[1] - weave[1]).powi(2));
    }
    let floor = (ss.iter().sum::<f64>() / ss.len() as f64).sqrt();
    let (before, after) = (f(&j["error_before"]["eigen_rms"]), f(&j["error_after"]["eigen_rms"]));
    assert!(
        after <= 1.15 * floor && after < before,
        "weave RMS {before} -> {after}, the truth's own {floor}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A front assembly whose steer inertia is half again what the file says
/// (a lamp or a bag on the handlebar: 5 prior standard deviations, beyond
/// what the measurement makes plausible). A plausible effect that absorbs
/// part of it (a steer controller, a damper) may pass first; fitted
/// together with the correction it must be explained away (the
/// encompassing test) or removed by the final check, so the correction is
/// what remains, near the hidden value, with its distance from the prior
/// reported.
#[test]
#[ignore = "about 14 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn a_steer_inertia_beyond_its_prior_is_not_left_to_a_proxy() {
    let i4z = 0.0385 * 1.5;
    let dir = synth_twelve("steer_inertia", &format!("I4z={i4z}"), 41);
    // Exit 1 says that some runs were set aside (a kick whose window the
    // bicycle's fall cut short); the identification is on the others.
    let out = bikedyn(&["identify", dir.to_str().unwrap(), "--json"]);
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "identify: {}",
        text(&out.stderr)
    );
    let j = stdout_json(&out);
    let sel = selected_effects(&j);
    assert!(sel.iter().any(|s| s.starts_with("correct I4z")), "{sel:?}");
    for s in &sel {
        assert!(
            s.starts_with("correct") || s.contains("speed decay"),
            "a proxy effect kept beside the correction: {sel:?}"
        );
    }
    let v = f(&j["parameters"]["I4z"]["value"]);
    assert!(((v - i4z) / (i4z - 0.0385)).abs() < 0.25, "I4z = {v}, hidden {i4z}");
    assert!(
        f(&j["parameters"]["I4z"]["prior_sds"]) > 3.0,
        "{:#}",
        j["parameters"]["I4z"]
    );
    // Every check of the final model is in the JSON with its verdict.
    for c in j["final_check"].as_array().unwrap() {
        assert!(c["outcome"]["kind"].is_string() && c["removed"].is_boolean(), "{c:#}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 17, point 6(b): the front assembly (handlebar and fork) has its
/// mass centre 3 cm higher than the bicycle file says. The model holds that
/// point in the steer-axis point, the wheel centre from it and the offset
/// from the axis, so no single parameter's correction is it; the file's own
/// quantity `zH` is corrected as a whole (the steer axis kept) and found
/// within 20 % of the hidden shift. Its effect on the weave is a few
/// hundredths of 1/s, below the scatter of the fitted eigenvalues about the
/// truth's, so the eigenvalue check is against the truth itself: the
/// corrected bicycle's weave is at least twice as close to the simulated
/// model's as the file's. The held-out errors fall.
#[test]
#[ignore = "about 8 minutes: .ci/run runs it last when its time allows; `cargo test --release -- --ignored` runs it"]
fn a_higher_front_mass_centre_is_corrected_as_a_whole() {
    let rep = scratch("identify").join("front_mass_centre_report");
    let _ = std::fs::remove_dir_all(&rep);
    let benchmark = bikedyn(&["params", "convert", "--to", "benchmark", "thesis"]);
    assert!(benchmark.status.success(), "{}", text(&benchmark.stderr));
    let zh = |toml: &str| -> f64 {
        toml.lines()
            .find_map(|l| l.strip_prefix("zH = "))
            .and_then(|v| v.split_whitespace().next()?.parse().ok())
            .unwrap_or_else(|| panic!("no zH in\n{toml}"))
    };
    let zh0 = zh(&text(&benchmark.stdout));
    let shift = -0.03; // z points down: 3 cm higher
    let dir = synth_twelve("front_mass_centre", &format!("zH={}", zh0 + shift), 41);
    let out = bikedyn(&[
        "identify",
        dir.to_str().unwrap(),
        "--json",
        "--report",
        rep.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "identify: {}", text(&out.stderr));
    let j = stdout_json(&out);
    let selected = selected_effects(&j);
    let confounded = j["confounded"]
        .as_array()
        .unwrap()
        .iter()
        .any(|c| c["confounded"] == true && (c["chosen"] == "correct zH" || c["rival"] == "correct zH"));
    assert!(selected.contains(&"correct zH") || confounded, "{j:#}");
    if selected.contains(&"correct zH") {
        let fitted = f(&j["parameters"]["zH"]["value"]) - zh0;
        assert!(
            ((fitted - shift) / shift).abs() < 0.2,
            "zH moved {fitted} m, hidden {shift} m"
        );
    }
    for key in ["roll_rms", "steer_rms"] {
        let (hb, ha) = (
            f(&j["error_before"]["held_out"][key]),
            f(&j["error_after"]["held_out"][key]),
        );
        assert!(ha < hb, "held-out {key} {hb} -> {ha}");
    }
    // The weave of the file's bicycle and of the corrected one (the
    // report's fitted.toml) against the simulated model's, at each run's
    // speed (synth's truth files).
    let fitted_bike = rep.join("fitted.toml");
    let weave = |bike: &str, v: f64| -> [f64; 2] {
        let speeds = format!("{v}:{v}:1");
        let e = ok_json(&["eig", "--bike", bike, "--speeds", &speeds, "--format", "json"]);
        let p = &e[0];
        let k = p["modes"]
            .as_array()
            .unwrap()
            .iter()
            .zip(p["eigenvalues"].as_array().unwrap())
            .filter(|(m, z)| m.as_str().unwrap().starts_with("weave") && f(&z[1]) > 0.0)
            .map(|(_, z)| [f(&z[0]), f(&z[1])])
            .next();
        k.unwrap_or_else(|| panic!("no weave at {v} m/s for {bike}: {e:#}"))
    };
    let (mut before, mut after) = (0.0, 0.0);
    for entry in std::fs::read_dir(dir.join("truth")).unwrap() {
        let path = entry.unwrap().path();
        if !path.to_string_lossy().ends_with("_truth.json") {
            continue;
        }
        let (v, truth) = truth_weave(&path);
        let d2 = |w: [f64; 2]| (w[0] - truth[0]).powi(2) + (w[1] - truth[1]).powi(2);
        before += d2(weave("thesis", v));
        after += d2(weave(fitted_bike.to_str().unwrap(), v));
    }
    assert!(
        after.sqrt() <= 0.5 * before.sqrt(),
        "weave distance to the truth {} -> {}",
        before.sqrt(),
        after.sqrt()
    );
    for d in [&dir, &rep] {
        let _ = std::fs::remove_dir_all(d);
    }
}
