//! Long measured eigenvalue tables: the held-out error of a table beyond
//! ten rows comes from ten folds, so the time grows with the rows and not
//! with their square (leaving each of 100 rows out took 29 s, of 300 rows
//! more than 300 s).

use crate::common::*;

/// A table of the thesis bicycle's weave with 0.3 N m s/rad of steer
/// damping at `speeds` (`START:STOP:STEP`), perturbed by 0.05 1/s in turn.
fn damped_table(name: &str, speeds: &str) -> std::path::PathBuf {
    let dir = scratch("identify-long-tables");
    let bike = dir.join("damped.toml");
    let thesis = text(&bikedyn(&["params", "show", "--bike", "thesis"]).stdout);
    std::fs::write(&bike, format!("{thesis}\nc_steer = 0.3\n")).unwrap();
    let points = ok_json(&[
        "eig",
        "--bike",
        bike.to_str().unwrap(),
        "--speeds",
        speeds,
        "--format",
        "json",
    ]);
    let mut csv = String::from("v,re,im,sd_re,sd_im\n");
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
        csv += &format!("{},{:.4},{:.4},0.05,0.05\n", p["v"], w[0] + d, w[1] - d);
    }
    let path = dir.join(name);
    std::fs::write(&path, csv).unwrap();
    path
}

/// A table of 100 speeds is identified as its nine-row sample is (steer
/// damping, c_steer within 1 %), with a held-out error of the same size as
/// the fitted one, and in well under the 29 s leaving each row out took
/// (3.6 s on an idle 2-core machine; the bound leaves room for a busy one).
#[test]
fn a_long_eigenvalue_table_is_identified_in_time_growing_with_its_rows() {
    let table = damped_table("hundred.csv", "2.5:7.45:0.05");
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
    assert_eq!(v["selected"], serde_json::json!(["steer_damping"]), "{v}");
    let c = v["parameters"]["c_steer"][0].as_f64().unwrap();
    assert!((c - 0.3).abs() < 0.003, "c_steer {c}");
    let (after, held) = (
        v["eigen_rms_after"].as_f64().unwrap(),
        v["eigen_rms_held_out"].as_f64().unwrap(),
    );
    assert!(held < 1.5 * after && held < 0.1, "held out {held}, after {after}");
    assert!(took < 20.0, "{took:.1} s");
}
