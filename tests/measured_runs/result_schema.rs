//! The JSON of `bikedyn fit --json` (one record per kick) is the
//! serialization of `bikedyn::fit::KickRecord`, and its shape is committed
//! in `tests/data/fit_schema.json` (`crate::common::schema`; rewrite it
//! with `BIKEDYN_BLESS=1 cargo test --release --test behaviour --
//! result_schema`, and review the diff as the schema's change).
//!
//! The inputs give every kind of record, so that the shape does not
//! depend on a borderline verdict: the example set's kicks (measured weave
//! eigenvalues with a clock offset and a prediction) and a copy of one of
//! its runs whose wheel sensor is silent (fitted, no speed, refused, no
//! prediction and the reason).

use crate::common::schema::{check_committed, shape, Paths};
use crate::common::*;

/// The kick record's paths whose keys are not schema.
const PATHS: Paths = Paths {
    maps: &[],
    // Verdicts (`accept::Rejected`, `accept::SpeedFormRejected`) flattened
    // with their sentence: the keys beside `test` are the variant's.
    variants: &["[].refused", "[].speed_varying_refused"],
};

/// Every value of the wheel sensor's record at zero volts: no pulse, so no
/// speed anywhere in the run.
fn silence_wheel_sensor(run: &std::path::Path) {
    let path = run.join("speed_switch.csv");
    let flat: String = std::fs::read_to_string(&path)
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 0 {
                format!("{l}\n")
            } else {
                format!("{},0.000\n", l.split(',').next().unwrap())
            }
        })
        .collect();
    std::fs::write(&path, flat).unwrap();
}

#[test]
fn fit_json_has_the_committed_result_schema() {
    let runs = ["calibration", "run01", "run02", "run03", "run04", "run05", "run06"];
    let set = example_runs("fit-schema", "set", &runs);
    let silent = example_runs("fit-schema", "silent", &["calibration", "run01"]);
    silence_wheel_sensor(&silent.join("run01"));
    let out = bikedyn(&[
        "fit",
        set.to_str().unwrap(),
        silent.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ]);
    // The silent run's kick is left out of the comparison with the model:
    // exit status 1, and every record on standard output.
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no usable speed record"), "{stderr}");
    let kicks = stdout_json(&out);
    let list = kicks.as_array().unwrap();
    let silent_run = silent.join("run01").display().to_string();
    let (no_speed, measured): (Vec<_>, Vec<_>) = list.iter().partition(|k| k["run"] == silent_run.as_str());
    assert_eq!(no_speed.len(), 1, "{kicks}");
    assert_eq!(measured.len(), 6, "one kick per run of the example set: {kicks}");
    let k = no_speed[0];
    assert!(
        k["mean_speed"].is_null() && k["predicted_weave"].is_null() && k["weave"].is_null(),
        "{k}"
    );
    assert!(
        k["no_prediction"].is_string() && k["refused"]["test"].is_string(),
        "{k}"
    );
    assert!(
        measured
            .iter()
            .any(|k| k["weave"].is_array() && k["predicted_weave"]["at_mean_speed"].is_array()),
        "no measured weave eigenvalue in the example set: {kicks}"
    );
    for k in list {
        // Thesis-style runs: a clock offset each; a verdict has its test
        // and sentence whatever its variant.
        assert!(k["clock_offset"]["from_data"].is_boolean(), "{k}");
        for v in ["refused", "speed_varying_refused"] {
            let r = &k[v];
            assert!(
                r.is_null() || (r["test"].is_string() && r["reason"].is_string()),
                "{v}: {r}"
            );
        }
        assert_eq!(k["no_prediction"].is_string(), k["mean_speed"].is_null(), "{k}");
    }
    check_committed("fit_schema.json", &[("kicks", &shape(&kicks, &PATHS))]);
}
