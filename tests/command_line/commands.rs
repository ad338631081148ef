//! The `bikedyn` command line, end to end.

use crate::common::*;
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    scratch("commands").join(name)
}

#[test]
fn eig_json_has_the_documented_schema() {
    let v = ok_json(&["eig", "--bike", "benchmark", "--speeds", "0:10:0.5", "--format", "json"]);
    let pts = v.as_array().unwrap();
    assert_eq!(pts.len(), 21);
    for p in pts {
        assert!(p["v"].is_f64() || p["v"].is_u64());
        let ev = p["eigenvalues"].as_array().unwrap();
        let modes = p["modes"].as_array().unwrap();
        assert_eq!(ev.len(), 4);
        assert_eq!(modes.len(), 4);
        assert!(ev.iter().all(|e| e.as_array().unwrap().len() == 2));
    }
    let at5 = &pts[10];
    assert_eq!(at5["v"].as_f64().unwrap(), 5.0);
    let names: Vec<&str> = at5["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_str().unwrap())
        .collect();
    for m in ["weave", "capsize", "castering"] {
        assert!(names.contains(&m), "{names:?}");
    }
}

#[test]
fn eig_csv_and_plot_files() {
    let csv = tmp("eig.csv");
    let svg = tmp("eig.svg");
    let out = bikedyn(&[
        "eig",
        "--bike",
        "thesis",
        "--speeds",
        "0:10:0.1",
        "--format",
        "csv",
        "--output",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 1 + 101);
    assert!(text.lines().next().unwrap().starts_with("v,"));
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn eig_with_a_plot_prints_no_table_unless_one_is_asked_for() {
    let svg = tmp("eig_plot_only.svg");
    let args = [
        "eig",
        "--bike",
        "thesis",
        "--speeds",
        "0:10:0.01",
        "--plot",
        svg.to_str().unwrap(),
    ];
    let out = bikedyn(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(out.stdout.is_empty(), "{} bytes of table", out.stdout.len());
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
    // Asked for, the table comes as well.
    let out = bikedyn(&[&args[..], &["--format", "table"]].concat());
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 2 + 1001);
}

#[test]
fn eig_json_is_also_asked_for_with_json_as_stability_takes_it() {
    let a = ok_json(&["eig", "--bike", "benchmark", "--speeds", "0:10:1", "--json"]);
    let b = ok_json(&["eig", "--bike", "benchmark", "--speeds", "0:10:1", "--format", "json"]);
    assert_eq!(a, b);
    let both = bikedyn(&["eig", "--json", "--format", "csv"]);
    assert!(!both.status.success());
    assert!(String::from_utf8_lossy(&both.stderr).contains("--format"));
}

#[test]
fn thesis_bicycle_is_self_stable_where_the_thesis_says() {
    // Thesis section 4.4: self-stable from 3.4 to 6.1 m/s (read off a 0.5 m/s grid).
    let v = ok_json(&["stability", "--bike", "thesis", "--json"]);
    let iv = v["stable_intervals"].as_array().unwrap();
    assert_eq!(iv.len(), 1);
    let (lo, hi) = (iv[0][0].as_f64().unwrap(), iv[0][1].as_f64().unwrap());
    assert!((3.4..3.5).contains(&lo) && (6.1..6.2).contains(&hi), "{lo} {hi}");
    assert_eq!(v["weave_speed"].as_f64().unwrap(), lo);
    assert_eq!(v["capsize_speed"].as_f64().unwrap(), hi);
}

#[test]
fn params_convert_round_trips_through_files() {
    let thesis = tmp("bench_as_thesis.toml");
    let back = tmp("bench_back.toml");
    let out = bikedyn(&[
        "params",
        "convert",
        "--to",
        "thesis",
        "benchmark",
        "--output",
        thesis.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = bikedyn(&[
        "params",
        "convert",
        "--to",
        "benchmark",
        thesis.to_str().unwrap(),
        "--output",
        back.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    // The converted bicycle has the benchmark's weave speed.
    let v = ok_json(&["stability", "--bike", back.to_str().unwrap(), "--json"]);
    assert!((v["weave_speed"].as_f64().unwrap() - 4.29238253634111).abs() < 1e-9);
}

#[test]
fn sweep_over_trail_and_a_stability_map() {
    let v = ok_json(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.04:0.12:0.04",
        "--format",
        "json",
    ]);
    let s = v.to_string();
    assert!(s.contains("weave_speed"), "{s}");
    let png = tmp("map.png");
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.02:0.12:0.05",
        "--param2",
        "lam",
        "--values2",
        "0.2:0.4:0.1",
        "--format",
        "csv",
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 1 + 3 * 3);
    // The tables' headers carry the units, parameter columns included.
    let table = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.04:0.08:0.04",
        "--param2",
        "lam",
        "--values2",
        "0.3:0.31:0.01",
    ]);
    let header = String::from_utf8_lossy(&table.stdout)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    for column in ["c (m)", "lam (rad)", "v_w (m/s)", "v_c (m/s)"] {
        assert!(header.contains(column), "{header}");
    }
    // An effect parameter's column carries the unit of its declaration.
    let table = bikedyn(&["sweep", "--param", "c_steer", "--values", "0:0.2:0.1"]);
    assert!(table.status.success(), "{}", String::from_utf8_lossy(&table.stderr));
    let header = String::from_utf8_lossy(&table.stdout)
        .lines()
        .next()
        .unwrap_or_default()
        .to_string();
    assert!(header.contains("c_steer (N m s/rad)"), "{header}");
}

#[test]
fn bad_input_gives_clear_errors() {
    let out = bikedyn(&["stability", "--bike", "no_such_bike"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no_such_bike"));
    let bad = tmp("bad.txt");
    std::fs::write(&bad, "w = 1.02\nc = oops\n").unwrap();
    let out = bikedyn(&["stability", "--bike", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.txt") && err.contains('2'), "{err}");
    let out = bikedyn(&["eig", "--bike", "thesis", "--speeds", "10:0:1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--speeds"));
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "thesis",
        "--param",
        "wheelbase_typo",
        "--values",
        "0:1:0.5",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("wheelbase_typo"));
}

#[test]
fn every_real_parameter_set_gives_its_stability_interval() {
    let Some(dir) = shared("realdata/parameter_sets/HumanControl_Par") else {
        return;
    };
    let mut stable = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if !p.to_string_lossy().ends_with("Par.txt") {
            continue;
        }
        let v = ok_json(&["stability", "--bike", p.to_str().unwrap(), "--json"]);
        let n = v["stable_intervals"].as_array().unwrap().len();
        println!("{}: {}", p.display(), v["stable_intervals"]);
        // The measured bicycle + rigid rider sets of Moore (2012) are all
        // self-stable somewhere below 10 m/s.
        if p.file_name().unwrap().to_string_lossy().starts_with("Rigid") {
            assert!(n >= 1, "{} has no stable interval", p.display());
        }
        stable += (n > 0) as usize;
    }
    assert!(stable >= 20, "{stable}");
}

/// Every command that computes with a model names it (issue 20), on
/// standard output as part of its result or on standard error beside it.
#[test]
fn every_command_names_the_model_it_used() {
    let set = example_set();
    let run = set.join("run01");
    let synth = tmp("named-model-synth");
    let _ = std::fs::remove_dir_all(&synth);
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["canonical"], "model: thesis_whipple"),
        (vec!["stability", "--bike", "benchmark"], "model: whipple_offset"),
        (vec!["eig", "--speeds", "1:2:1"], "model: thesis_whipple"),
        (
            vec!["sweep", "--param", "c_steer", "--values", "0.1:0.2:0.1"],
            "model: extended",
        ),
        (
            vec!["simulate", "--speed", "4", "--duration", "0.2"],
            "model thesis_whipple",
        ),
        (
            vec!["verify", "--model", "thesis_whipple", "--states", "1"],
            "model thesis_whipple",
        ),
        (
            vec!["fit", run.to_str().unwrap(), "--bike", "thesis"],
            "model thesis_whipple",
        ),
        (
            vec!["synth", "--runs", "1", "--seed", "3", "--out", synth.to_str().unwrap()],
            "model: thesis_whipple",
        ),
    ];
    for (args, named) in cases {
        let out = bikedyn(&args);
        let all = text(&out.stdout) + &text(&out.stderr);
        assert!(out.status.success(), "{args:?}: {all}");
        assert!(all.contains(named), "{args:?} does not say `{named}`:\n{all}");
    }
}

/// The built-in thesis bicycle is the default of thesis-format runs only:
/// `fit` and `identify` on a TU Delft log, and `identify --eigenvalues` on
/// a table, without `--bike` are errors that name the flag (they used to
/// compare the logs' bicycle with the thesis bicycle and say nothing). The
/// committed thesis-format set still needs none.
#[test]
fn logs_and_tables_without_a_bicycle_are_errors_naming_bike() {
    let d = tmp("no-bike");
    std::fs::create_dir_all(&d).unwrap();
    let log = d.join("kicks.log");
    std::fs::write(&log, "not read: the bicycle is asked for first\n").unwrap();
    let table = d.join("table.csv");
    std::fs::write(&table, "v,re,im\n5,-1,7\n6,-1.5,8\n").unwrap();
    let (log, table) = (log.to_str().unwrap(), table.to_str().unwrap());
    for args in [
        &["fit", log][..],
        &["identify", log][..],
        &["identify", "--eigenvalues", table][..],
    ] {
        let out = bikedyn(args);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            err.contains("--bike") && err.contains("thesis-format"),
            "{args:?}: {err}"
        );
    }
    let set = example_set();
    let out = bikedyn(&["fit", set.to_str().unwrap(), "--json"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// The benchmark's structural zeros (Meijaard et al. 2007: `C1[0][0]`,
/// `K2[0][0]`, `K2[1][0]`) are written as 0 in JSON, not as the round-off
/// of the generated expressions (-4.4e-15 beside 33.9).
#[test]
fn canonical_json_writes_structural_zeros_as_zero() {
    let v = ok_json(&["canonical", "--bike", "benchmark", "--json"]);
    let at = |m: &str, i: usize, j: usize| v[m][i][j].as_f64().unwrap();
    assert_eq!(at("C1", 0, 0), 0.0);
    assert_eq!(at("K2", 0, 0), 0.0);
    assert_eq!(at("K2", 1, 0), 0.0);
    // Meijaard et al. (2007), the benchmark's C1[0][1] to 14 digits.
    assert!((at("C1", 0, 1) - 33.866_413_914_924_94).abs() < 1e-12);
}

/// `bikedyn bench --quick` is the library's `bench` printed section by
/// section: every section measures something (timings are the machine's,
/// so only their being positive and finite is checked), the counts follow
/// the quick options, and the printed sections are those of
/// docs/performance.md.
#[test]
fn bench_quick_measures_and_prints_every_section() {
    use bikedyn::bench::{bench, BenchOptions};
    let f = bench(&BenchOptions { quick: true }).unwrap();
    let positive = |x: f64| x.is_finite() && x > 0.0;
    assert!(f.codegen.derived != f.codegen.models.is_empty(), "{:?}", f.codegen);
    let g = &f.generated_functions;
    assert_eq!((g.model, g.calls, g.functions.len()), ("thesis_whipple", 20_000, 15));
    assert!(g.functions.iter().all(|t| positive(t.ns_per_call)));
    let mass = g.functions.iter().find(|t| t.name == "mass_matrix").unwrap();
    assert!(mass.flops > 0 && g.sum_flops >= mass.flops && g.all_quantities_flops > 0);
    let l = &f.linearization;
    assert!(l.reduced_equations_flops > 0);
    assert!([l.linearization_us, l.general_linearization_us, l.eigenvalues_ns]
        .into_iter()
        .all(positive));
    let s = &f.sweep;
    assert_eq!((s.designs, s.speeds), (100, 1000));
    // Stable only between the weave and capsize speeds: some points, not all.
    assert!(s.stable_points > 0 && s.stable_points < s.designs * s.speeds, "{s:?}");
    let m = &f.measured_runs;
    assert!(positive(m.calibration_ms) && positive(m.run_ms), "{m:?}");
    let sim = &f.simulation;
    assert_eq!((sim.outputs.len(), sim.variants.len()), (2, 3));
    assert!(sim
        .outputs
        .iter()
        .all(|o| o.rhs_evaluations > 0 && positive(o.real_time)));
    let out = bikedyn(&["bench", "--quick"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    for section in [
        "== code generation",
        "== generated functions of thesis_whipple (f64, one state per call, 20000 calls) ==",
        "== linearization and eigenvalues",
        "design x speed sweep: 100 designs x 1000 speeds",
        "== measured runs (bikedyn fit), median of 5, one thread ==",
        "== nonlinear simulation",
        "(extended_free)",
    ] {
        assert!(stdout.contains(section), "{section} missing in\n{stdout}");
    }
}
