//! `bikedyn sensitivity` and `bikedyn bode`: their outputs (table, CSV,
//! JSON, plots) and their errors for bad input, which name the flag or the
//! file and never panic.

use crate::common::*;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    scratch("sensitivity_and_bode").join(name)
}

/// Runs a command that must fail cleanly: exit status 2, one error line
/// naming the problem, no panic. Returns standard error.
fn fails(args: &[&str]) -> String {
    let out = bikedyn(args);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    err
}

#[test]
fn sensitivity_json_ranks_every_parameter_of_both_speeds() {
    let v = ok_json(&["sensitivity", "--bike", "benchmark", "--speed", "5", "--format", "json"]);
    assert_eq!(v["parameter_form"], "benchmark");
    for which in ["weave_speed", "capsize_speed"] {
        let d = v[which]["derivatives"].as_array().unwrap();
        assert_eq!(d.len(), 26, "{which}");
        let e: Vec<f64> = d.iter().map(|x| x["elasticity"].as_f64().unwrap().abs()).collect();
        assert!(e.windows(2).all(|w| w[0] >= w[1]), "{which} not ranked: {e:?}");
        let g = d.iter().find(|x| x["parameter"] == "g").unwrap();
        assert!((g["elasticity"].as_f64().unwrap() - 0.5).abs() < 1e-12);
    }
    assert!((v["weave_speed"]["speed"].as_f64().unwrap() - 4.2923825363).abs() < 1e-9);
    let modes: Vec<&str> = v["eigenvalues"]["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["mode"].as_str().unwrap())
        .collect();
    assert_eq!(modes, ["weave", "capsize", "castering"]);
    // The thesis bicycle in its own symbols, or in the benchmark's.
    let v = ok_json(&["sensitivity", "--bike", "thesis", "--format", "json"]);
    assert_eq!(v["parameter_form"], "thesis");
    assert!(v["capsize_speed"]["derivatives"]
        .as_array()
        .unwrap()
        .iter()
        .any(|d| d["parameter"] == "x4"));
    let v = ok_json(&[
        "sensitivity",
        "--bike",
        "thesis",
        "--form",
        "benchmark",
        "--format",
        "json",
    ]);
    assert_eq!(v["parameter_form"], "benchmark");
}

#[test]
fn sensitivity_table_csv_and_bar_chart() {
    let out = bikedyn(&["sensitivity", "--bike", "thesis"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t = text(&out.stdout);
    assert!(
        t.contains("elasticity") && t.contains("dv_w/dp") && t.contains("e_c"),
        "{t}"
    );
    let csv = tmp("s.csv");
    let svg = tmp("s.svg");
    let out = bikedyn(&[
        "sensitivity",
        "--bike",
        "benchmark",
        "--speed",
        "4",
        "--format",
        "csv",
        "--output",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let c = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(
        c.lines().next().unwrap(),
        "quantity,rank,parameter,value,derivative,elasticity,scaled"
    );
    // Two speeds and three eigenvalues' real and imaginary parts, 26 each.
    assert_eq!(c.lines().count(), 1 + 26 * (2 + 2 * 3));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn bode_csv_json_and_plot() {
    let csv = tmp("b.csv");
    let png = tmp("b.png");
    let out = bikedyn(&[
        "bode",
        "--bike",
        "benchmark",
        "--speed",
        "5",
        "--omega",
        "0.1:100",
        "--points",
        "50",
        "--format",
        "csv",
        "--output",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let c = std::fs::read_to_string(&csv).unwrap();
    assert!(c.starts_with("omega,frequency_hz,input,output,re,im,magnitude,magnitude_db,phase_deg\n"));
    assert_eq!(c.lines().count(), 1 + 4 * 50);
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    let v = ok_json(&[
        "bode", "--bike", "thesis", "--speed", "4", "--points", "20", "--format", "json",
    ]);
    assert_eq!(v["omega"].as_array().unwrap().len(), 20);
    assert_eq!(v["responses"].as_array().unwrap().len(), 4);
    assert_eq!(v["stable"], true);
    let t = text(&bikedyn(&["bode", "--bike", "benchmark", "--speed", "5"]).stdout);
    assert!(t.contains("steer_torque") && t.contains("G(0)"), "{t}");
}

#[test]
fn bad_input_to_sensitivity_and_bode_names_the_flag_or_file() {
    let missing = tmp("no-such-bike.toml");
    let m = missing.to_str().unwrap();
    for cmd in [
        vec!["sensitivity", "--bike", m],
        vec!["bode", "--bike", m, "--speed", "5"],
    ] {
        let e = fails(&cmd);
        assert!(e.contains("no-such-bike.toml"), "{e}");
    }
    for speed in ["nan", "inf", "-inf"] {
        let e = fails(&["sensitivity", "--bike", "benchmark", "--speed", speed]);
        assert!(e.contains("--speed"), "{e}");
        let e = fails(&["bode", "--bike", "benchmark", "--speed", speed]);
        assert!(e.contains("--speed"), "{e}");
    }
    // No crossing below 1 m/s.
    let e = fails(&["sensitivity", "--bike", "benchmark", "--speed-max", "1"]);
    assert!(
        e.contains("--speed-max") && e.contains("no weave or capsize crossing"),
        "{e}"
    );
    let e = fails(&["sensitivity", "--bike", "benchmark", "--speed-max", "nan"]);
    assert!(e.contains("--speed-max"), "{e}");
    // A bicycle with an effect has no exact parameter derivatives.
    let damped = tmp("damped.toml");
    let bench = text(&bikedyn(&["params", "show", "benchmark"]).stdout);
    std::fs::write(&damped, format!("{bench}\nc_steer = 0.3\n")).unwrap();
    let e = fails(&["sensitivity", "--bike", damped.to_str().unwrap()]);
    assert!(e.contains("canonical form") && e.contains("c_steer"), "{e}");
    for omega in ["0:10", "10:1", "1", "a:b", "-1:10"] {
        let e = fails(&["bode", "--bike", "benchmark", "--speed", "5", "--omega", omega]);
        assert!(e.contains("--omega"), "{omega}: {e}");
    }
    let e = fails(&["bode", "--bike", "benchmark", "--speed", "5", "--points", "1"]);
    assert!(e.contains("--points"), "{e}");
    let e = fails(&[
        "bode",
        "--bike",
        "benchmark",
        "--speed",
        "5",
        "--plot",
        &tmp("x.pdf").to_string_lossy(),
    ]);
    assert!(e.contains("x.pdf"), "{e}");
}

#[test]
fn stability_gives_the_speeds_standard_deviations_from_the_files_uncertainties() {
    let file = fixture_arg("Balanceassistv1Benchmark.txt");
    let v = ok_json(&["stability", "--bike", &file, "--json"]);
    let sd_w = v["weave_speed_sd"].as_f64().unwrap();
    let sd_c = v["capsize_speed_sd"].as_f64().unwrap();
    assert!(sd_w > 0.0 && sd_c > 0.0, "{v}");
    assert_eq!(v["uncertainty"]["weave_speed"]["shares"][0]["parameter"], "lam");
    let out = bikedyn(&["stability", "--bike", &file]);
    let t = text(&out.stdout);
    assert!(
        t.contains("v_w = 3.44213 +/- ") && t.contains("from the file's +/- values"),
        "{t}"
    );
    // The built-in bicycles carry no standard deviations: no such fields.
    let v = ok_json(&["stability", "--bike", "benchmark", "--json"]);
    assert!(v.get("weave_speed_sd").is_none(), "{v}");
}

/// The first-order standard deviations of v_w and v_c against bicycles
/// drawn with a real bicycle's measured `+/-` values, there scaled down
/// tenfold so that the speeds are near linear over them (where first order
/// holds): the two agree within three standard errors of the drawn
/// standard deviation, the drawn mean is the nominal speed, and the same
/// seed draws the same bicycles. At the file's own spread the weave
/// speed's curvature shows: the draws' standard deviation is larger, and
/// the text says first order does not hold there.
#[test]
fn stability_monte_carlo_agrees_with_the_first_order_standard_deviations() {
    let original = std::fs::read_to_string(fixture("Balanceassistv1Benchmark.txt")).unwrap();
    let tenth: String = original
        .lines()
        .map(|l| match l.split_once("+/-") {
            Some((head, sd)) => format!("{head}+/-{:e}\n", sd.trim().parse::<f64>().unwrap() / 10.0),
            None => format!("{l}\n"),
        })
        .collect();
    let file = tmp("balance_assist_tenth_sd.txt");
    std::fs::write(&file, tenth).unwrap();
    let file = file.to_string_lossy().into_owned();
    let args = [
        "stability",
        "--bike",
        &file,
        "--json",
        "--monte-carlo",
        "4000",
        "--seed",
        "3",
    ];
    let v = ok_json(&args);
    for key in ["weave_speed", "capsize_speed"] {
        let first = v["uncertainty"][key]["standard_deviation"].as_f64().unwrap();
        let m = &v["monte_carlo"][key];
        let sd = m["standard_deviation"].as_f64().unwrap();
        let se = m["standard_error_of_sd"].as_f64().unwrap();
        assert_eq!(m["draws"].as_u64(), Some(4000), "{key}: {m}");
        assert!(
            (sd - first).abs() < 3.0 * se,
            "{key}: first order {first}, drawn {sd} +/- {se}"
        );
        let mean = m["mean"].as_f64().unwrap();
        let nominal = v[key].as_f64().unwrap();
        assert!(
            (mean - nominal).abs() < 0.1 * first,
            "{key}: mean {mean}, nominal {nominal}"
        );
    }
    assert_eq!(ok_json(&args)["monte_carlo"], v["monte_carlo"], "same seed, same draws");
    let at_full_spread = bikedyn(&[
        "stability",
        "--bike",
        &fixture_arg("Balanceassistv1Benchmark.txt"),
        "--monte-carlo",
        "4000",
    ]);
    let t = text(&at_full_spread.stdout);
    assert!(t.contains("v_w: first order does not hold"), "{t}");
    // Without +/- values there is nothing to draw: an error that says so.
    let out = bikedyn(&["stability", "--bike", "benchmark", "--monte-carlo", "10"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("+/-"), "{}", text(&out.stderr));
}

/// The first-order standard deviations of the figures `figures` computes
/// from a parameter file's text, by central differences: for each line
/// `symbol = value+/-sd` of `original`, the figures at `value +/- h`, and
/// `sqrt(sum ((f(+h) - f(-h)) / 2h sd)^2)` per figure.
fn spread_by_differences(original: &str, figures: &dyn Fn(&str, &str) -> Vec<f64>) -> Vec<f64> {
    let mut variance: Vec<f64> = Vec::new();
    for line in original.lines() {
        let Some((head, sd)) = line.split_once("+/-") else {
            continue;
        };
        let (symbol, value) = head.split_once('=').unwrap();
        let (value, sd): (f64, f64) = (value.trim().parse().unwrap(), sd.trim().parse().unwrap());
        let h = 1e-5 * value.abs().max(1e-2);
        let with = |x: f64| original.replace(line, &format!("{} = {x:e}+/-{sd}", symbol.trim()));
        let (up, down) = (figures(&with(value + h), "up"), figures(&with(value - h), "down"));
        variance.resize(up.len(), 0.0);
        for ((var, a), b) in variance.iter_mut().zip(&up).zip(&down) {
            *var += ((a - b) / (2.0 * h) * sd).powi(2);
        }
    }
    variance.iter().map(|v| v.sqrt()).collect()
}

/// Exact and by-differences standard deviations agree to 1e-5 relative.
fn assert_spreads_agree(exact: &[f64], by_differences: &[f64], what: &str) {
    assert_eq!(exact.len(), by_differences.len(), "{what}");
    for (k, (e, d)) in exact.iter().zip(by_differences).enumerate() {
        assert!(
            (e - d).abs() <= 1e-5 * (1e-3 + d),
            "{what} {k}: {e} exact, {d} by differences"
        );
    }
}

/// `eig` on a file with `+/-` values gives each eigenvalue's standard
/// deviation (first order, exact derivatives): the same as summing the
/// squares of central differences over each parameter times its standard
/// deviation.
#[test]
fn eig_gives_each_eigenvalues_standard_deviation_from_the_files_uncertainties() {
    let original = std::fs::read_to_string(fixture("Balanceassistv1Benchmark.txt")).unwrap();
    let eig = |text: &str, name: &str| -> serde_json::Value {
        let file = tmp(&format!("eig_sd_{name}.txt"));
        std::fs::write(&file, text).unwrap();
        let v = ok_json(&[
            "eig",
            "--bike",
            &file.to_string_lossy(),
            "--speeds",
            "4.5:4.5:1",
            "--json",
        ]);
        v[0].clone()
    };
    // Real and imaginary parts of the four eigenvalues, in order.
    let flat = |v: &serde_json::Value| -> Vec<f64> {
        (0..4)
            .flat_map(|k| (0..2).map(move |c| v[k][c].as_f64().unwrap()))
            .collect()
    };
    let nominal = eig(&original, "nominal");
    let by_differences = spread_by_differences(&original, &|text, name| flat(&eig(text, name)["eigenvalues"]));
    assert_spreads_agree(
        &flat(&nominal["standard_deviations"]),
        &by_differences,
        "eigenvalue part",
    );
    // The built-in bicycles carry no standard deviations: no such field.
    let v = ok_json(&["eig", "--bike", "benchmark", "--speeds", "4.5:4.5:1", "--json"]);
    assert!(v[0].get("standard_deviations").is_none(), "{v}");
}

/// `canonical` on a file with `+/-` values gives each entry's standard
/// deviation: the same as summing the squares of central differences over
/// each parameter times its standard deviation.
#[test]
fn canonical_gives_each_entrys_standard_deviation_from_the_files_uncertainties() {
    let original = std::fs::read_to_string(fixture("Balanceassistv1Benchmark.txt")).unwrap();
    let canonical = |text: &str, name: &str| -> serde_json::Value {
        let file = tmp(&format!("canonical_sd_{name}.txt"));
        std::fs::write(&file, text).unwrap();
        ok_json(&["canonical", "--bike", &file.to_string_lossy(), "--json"])
    };
    // The entries of M0, C1, K0, K2, row by row.
    let flat = |v: &serde_json::Value| -> Vec<f64> {
        ["M0", "C1", "K0", "K2"]
            .iter()
            .flat_map(|m| (0..4).map(move |e| v[m][e / 2][e % 2].as_f64().unwrap()))
            .collect()
    };
    let nominal = canonical(&original, "nominal");
    let by_differences = spread_by_differences(&original, &|text, name| flat(&canonical(text, name)));
    assert_spreads_agree(&flat(&nominal["standard_deviations"]), &by_differences, "matrix entry");
    assert!(ok_json(&["canonical", "--bike", "benchmark", "--json"])
        .get("standard_deviations")
        .is_none());
}

/// `sweep` over one parameter of a file with `+/-` values gives the
/// critical speeds' standard deviations at each value: those of the file
/// with that value set and its own `+/-` left out (the swept parameter is
/// set, not measured).
#[test]
fn sweep_gives_the_critical_speeds_standard_deviations_at_each_value() {
    let original = std::fs::read_to_string(fixture("Balanceassistv1Benchmark.txt")).unwrap();
    let file = fixture_arg("Balanceassistv1Benchmark.txt");
    // `sweep` of trail over `values` on `bike`, then the output flags.
    let sweep = |bike: &str, values: &str, output: &[&str]| -> Vec<String> {
        ["sweep", "--bike", bike, "--param", "c", "--values", values]
            .iter()
            .chain(output)
            .map(|a| a.to_string())
            .collect()
    };
    let call = |args: Vec<String>| bikedyn(&args.iter().map(String::as_str).collect::<Vec<_>>());
    let out = call(sweep(&file, "0.03:0.05:0.02", &["--json"]));
    assert!(out.status.success(), "{}", text(&out.stderr));
    let swept = stdout_json(&out);
    for point in swept["points"].as_array().unwrap() {
        let c = point["value"].as_f64().unwrap();
        let line = original.lines().find(|l| l.starts_with("c =")).unwrap();
        let set = tmp(&format!("sweep_sd_c_{c}.txt"));
        std::fs::write(&set, original.replace(line, &format!("c = {c}"))).unwrap();
        let st = ok_json(&["stability", "--bike", &set.to_string_lossy(), "--json"]);
        for key in ["weave_speed_sd", "capsize_speed_sd"] {
            let (a, b) = (point[key].as_f64().unwrap(), st[key].as_f64().unwrap());
            assert!((a - b).abs() <= 1e-9 * b, "c = {c}, {key}: sweep {a}, stability {b}");
        }
    }
    let csv = call(sweep(&file, "0.03:0.05:0.02", &["--format", "csv"]));
    let header = text(&csv.stdout).lines().next().unwrap().to_string();
    assert!(header.ends_with("weave_speed_sd,capsize_speed_sd"), "{header}");
    // The built-in bicycles carry no standard deviations: no such field.
    let v = stdout_json(&call(sweep("benchmark", "0.08:0.08:1", &["--json"])));
    assert!(v["points"][0].get("weave_speed_sd").is_none(), "{v}");
}
