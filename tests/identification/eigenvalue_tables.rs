//! Long measured eigenvalue tables: the held-out error of a table beyond
//! ten rows comes from ten folds, so the time grows with the rows and not
//! with their square (leaving each of 100 rows out took 29 s, of 300 rows
//! more than 300 s).

use crate::common::*;

/// A table of the thesis bicycle's weave, with `c_steer` N m s/rad of
/// steer damping when given, at `speeds` (`START:STOP:STEP`), perturbed by
/// a fixed, sign-alternating 0.05 1/s (measurement noise), under the header
/// line `header` (a table's authors choose its words).
pub(super) fn weave_table(name: &str, c_steer: Option<f64>, speeds: &str, header: &str) -> std::path::PathBuf {
    let dir = scratch("identify-eigen-tables");
    let mut bike = text(&bikedyn(&["params", "show", "--bike", "thesis"]).stdout);
    if let Some(c) = c_steer {
        bike += &format!("\nc_steer = {c}\n");
    }
    let bike_path = dir.join(format!("{name}.toml"));
    std::fs::write(&bike_path, bike).unwrap();
    let points = ok_json(&[
        "eig",
        "--bike",
        bike_path.to_str().unwrap(),
        "--speeds",
        speeds,
        "--format",
        "json",
    ]);
    let sep = if header.contains(';') { "; " } else { "," };
    let mut csv = format!("{header}\n");
    for (k, p) in points.as_array().unwrap().iter().enumerate() {
        let w = p["eigenvalues"]
            .as_array()
            .unwrap()
            .iter()
            .zip(p["modes"].as_array().unwrap())
            .find(|(e, m)| *m == "weave" && e[1].as_f64().unwrap() > 0.0)
            .map(|(e, _)| [e[0].as_f64().unwrap(), e[1].as_f64().unwrap()])
            .unwrap();
        let d = if k % 2 == 0 { 0.05 } else { -0.05 };
        csv += &[
            p["v"].to_string(),
            format!("{:.4}", w[0] + d),
            format!("{:.4}", w[1] - d),
            "0.05".into(),
            "0.05".into(),
        ]
        .join(sep);
        csv += "\n";
    }
    let path = dir.join(format!("{name}.csv"));
    std::fs::write(&path, csv).unwrap();
    path
}

/// A table of 100 speeds is identified as its nine-row sample is (steer
/// damping, c_steer within 1 %), with a held-out error of the same size as
/// the fitted one. Its time is printed, not asserted (3.6 s on an idle
/// 2-core machine, against 29 s when each row was left out in turn).
#[test]
fn a_long_eigenvalue_table_is_identified_in_time_growing_with_its_rows() {
    let table = weave_table("hundred", Some(0.3), "2.5:7.45:0.05", "v,re,im,sd_re,sd_im");
    let start = std::time::Instant::now();
    let v = ok_json(&[
        "identify",
        "--eigenvalues",
        table.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ]);
    let took = start.elapsed().as_secs_f64();
    assert_eq!(v["points"].as_array().unwrap().len(), 100, "{v}");
    assert_eq!(v["source"], "eigenvalue_table");
    assert_eq!(v["selected_effects"], serde_json::json!(["steer_damping"]), "{v}");
    let c = v["parameters"]["c_steer"]["value"].as_f64().unwrap();
    assert!((c - 0.3).abs() < 0.003, "c_steer {c}");
    let (after, held) = (
        v["error_after"]["eigen_rms"].as_f64().unwrap(),
        v["error_after"]["held_out"]["eigen_rms"].as_f64().unwrap(),
    );
    assert!(held < 1.5 * after && held < 0.1, "held out {held}, after {after}");
    eprintln!("a table of 100 speeds identified in {took:.1} s");
}

/// The screen of corrections orders them and vetoes none: on a table the
/// bicycle fits as modelled, where no correction explains anything of the
/// base model's weave, every parameter the model declares uncertain is
/// still a candidate of the first step, and each stops on its own verdict
/// (here: no gain in the criterion), not because of what the screen saw
/// on the base model. A gate there (a misfit reduction of at least one
/// unit) once kept the right correction of an oracle set (the rear frame's
/// roll inertia 25 % high, 0.7 units on the base model) from ever being
/// tried.
#[test]
fn a_correction_that_explains_nothing_on_the_base_model_is_still_tried() {
    let table = weave_table("as_modelled", None, "3:7:0.5", "v,re,im,sd_re,sd_im");
    let v = ok_json(&[
        "identify",
        "--eigenvalues",
        table.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ]);
    assert_eq!(v["selected_effects"], serde_json::json!([]), "{v}");
    let candidates = v["candidates"].as_array().unwrap();
    let corrections: Vec<&serde_json::Value> = candidates
        .iter()
        .filter(|c| c["name"].as_str().unwrap().starts_with("correct "))
        .collect();
    for symbol in ["I3x", "I3z", "I4z", "m3", "z3", "x3", "Rt"] {
        let c = corrections
            .iter()
            .find(|c| c["name"] == format!("correct {symbol}"))
            .unwrap_or_else(|| panic!("correct {symbol} was not tried: {candidates:#?}"));
        assert_eq!(c["step"], 1, "{c}");
        assert_eq!(c["selected"], false, "{c}");
        assert!(c["outcome"]["kind"].is_string(), "{c}");
    }
    assert!(corrections.len() >= 20, "{} corrections tried", corrections.len());
}
