//! What a user sees at the command line: bad parameter files refused with
//! file, line and field, numbers printed with fixed digits, outputs checked
//! before computing and written through links and devices, streamed and
//! bounded outputs, stability crossings and stability maps.

use crate::common::*;
use std::path::PathBuf;
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    scratch("inputs-and-outputs").join(name)
}

/// The embedded benchmark TOML with one line replaced.
fn benchmark_with(replace: &str, with: &str, name: &str) -> PathBuf {
    let src = include_str!("../../runtime/data/benchmark_bicycle.toml");
    assert!(src.contains(replace), "{replace}");
    let p = tmp(name);
    std::fs::write(&p, src.replacen(replace, with, 1)).unwrap();
    p
}

/// `lam = 18.0` (degrees typed for radians) is refused
/// with the range and the value in radians, naming file and line; `lam =
/// pi/2` is refused too (it used to give a degenerate bicycle).
#[test]
fn head_angle_in_degrees_is_refused() {
    let p = benchmark_with("lam = 0.3141592653589793 ", "lam = 18.0 ", "lam18.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("(-pi/2, pi/2)") && err.contains("0.314159 rad"), "{err}");
    assert!(err.contains("lam18.toml, line 16"), "{err}");
    let p = benchmark_with("lam = 0.3141592653589793 ", "lam = 1.5707963267948966 ", "lam90.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("`lam`"), "{}", text(&out.stderr));
}

/// A wheelbase of 1020 (millimetres) is refused, naming the file and the
/// field, unless `--allow-units` (then a warning); a frame mass centre
/// below the ground gives a warning that names the field.
#[test]
fn millimetres_are_refused_and_mass_centre_below_ground_warns() {
    let p = benchmark_with("w = 1.02 ", "w = 1020 ", "w1020.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(out.stdout.is_empty());
    assert!(
        err.contains("w1020.toml")
            && err.contains("`w` = 1020.0 m")
            && err.contains("millimetres")
            && err.contains("--allow-units"),
        "{err}"
    );
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap(), "--allow-units"]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("warning") && err.contains("`w` = 1020.0 m"), "{err}");
    let p = benchmark_with("zB = -0.9 ", "zB = 0.2 ", "zb.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    assert!(out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("rear frame mass centre is 0.200000 m below the ground"),
        "{err}"
    );
    // The benchmark bicycle itself gets no such warning.
    let out = bikedyn(&["canonical", "--bike", "benchmark"]);
    assert!(text(&out.stderr).is_empty(), "{}", text(&out.stderr));
}

/// The built-in thesis bicycle's inertias violate the triangle inequality
/// as published: that is known, so it is shown only with `--verbose`; a
/// file with the same values gets one note with what it means, once.
#[test]
fn warnings_nobody_can_act_on_are_quiet() {
    let out = bikedyn(&["eig", "--bike", "thesis", "--speeds", "5"]);
    assert!(out.status.success());
    let err = text(&out.stderr);
    assert!(!err.contains("triangle"), "{err}");
    let out = bikedyn(&["eig", "--bike", "thesis", "--speeds", "5", "--verbose"]);
    let err = text(&out.stderr);
    assert_eq!(err.matches("violate the triangle inequality").count(), 2, "{err}");
    let thesis = tmp("thesis-file.toml");
    let out = bikedyn(&[
        "params",
        "convert",
        "--to",
        "thesis",
        "thesis",
        "--output",
        thesis.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = bikedyn(&["eig", "--bike", thesis.to_str().unwrap(), "--speeds", "5"]);
    let err = text(&out.stderr);
    assert_eq!(err.matches("triangle inequality").count(), 1, "{err}");
    assert!(
        err.contains("handlebar and the front wheel") && err.contains("uses them as given"),
        "{err}"
    );
}

/// `stability` lists every crossing with its mode; for the
/// Bluenose the first is the capsize root at 3.1413834189 m/s.
#[test]
fn stability_lists_crossings_with_modes() {
    let out = bikedyn(&["stability", "--bike", &fixture_arg("BluenosePar.txt")]);
    assert!(out.status.success());
    let s = text(&out.stdout);
    assert!(s.contains("capsize speed v_c: 3.1413834189 m/s"), "{s}");
    assert!(
        s.contains("3.1413834189 m/s  capsize            becomes unstable (real root through zero)"),
        "{s}"
    );
    assert!(s.contains("weave-capsize"), "{s}");
    assert!(s.ends_with('\n'), "{s:?}");
}

/// Matrices print with a fixed number of significant
/// digits and no negative zero (they used to print `80.81721999999998`,
/// `-80.94999999999999` and `-0.00000000000000`); JSON keeps full precision.
#[test]
fn matrices_print_fixed_significant_digits_without_negative_zero() {
    let out = bikedyn(&["canonical", "--bike", "benchmark"]);
    let s = text(&out.stdout);
    assert!(s.contains("[[80.8172200000,  2.3194133221]"), "{s}");
    assert!(s.contains("[[-80.9500000000,"), "{s}");
    assert!(!s.contains("-0.000") && !s.contains("9999999"), "{s}");
    let out = bikedyn(&["canonical", "--bike", "benchmark", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // Every bit of the computed entry, not the ten printed digits.
    let m0 = bikedyn::bicycle::Bicycle::resolve("benchmark")
        .unwrap()
        .canonical()
        .unwrap()
        .m0;
    assert_eq!(v["M0"][0][0].as_f64().unwrap(), m0[(0, 0)]);
    assert!((m0[(0, 0)] - 80.81722).abs() < 1e-12);
    // Eigenvalue tables: no "-0.00000" (the Bluenose has a purely imaginary pair at rest).
    let out = bikedyn(&[
        "eig",
        "--bike",
        &fixture_arg("BluenosePar.txt"),
        "--speeds",
        "0:0.1:0.1",
    ]);
    let s = text(&out.stdout);
    assert!(s.contains("+0.00000 + 0.83122i") && !s.contains("-0.00000"), "{s}");
}

/// Each cause is printed once (the UTF-8 error used to
/// read "...UTF-8: stream did not contain valid UTF-8" twice over).
#[test]
fn a_read_error_states_its_cause_once() {
    let p = tmp("latin1.txt");
    std::fs::write(&p, b"w = 1.02\n\xff\xfe\n").unwrap();
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert_eq!(err.matches("valid UTF-8").count(), 1, "{err}");
}

/// A 10 MB junk line is not echoed whole.
#[test]
fn junk_line_is_cut() {
    let p = tmp("junk.txt");
    std::fs::write(&p, format!("w = {}\n", "x".repeat(10_000_000))).unwrap();
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.len() < 2_000, "{} bytes of error", err.len());
    assert!(err.contains("junk.txt:1") && err.contains("more characters"), "{err}");
}

/// `mB = 1e300` names the file, line and field (it used to
/// end in "singular mass matrix M0 (det = NaN)"); `1e-300` is printed as
/// such, not with 300 digits.
#[test]
fn huge_and_tiny_values_name_file_and_field() {
    let p = benchmark_with("mB = 85.0 ", "mB = 1e300 ", "mb_huge.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(
        err.contains("`mB` = 1e300") && err.contains("mb_huge.toml, line 28"),
        "{err}"
    );
    let p = benchmark_with("mB = 85.0 ", "mB = -1e-300 ", "mb_tiny.toml");
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(err.contains("found -1e-300") && err.len() < 300, "{err}");
}

/// Huge times and speeds on the command line come back in messages in
/// scientific notation, not with 301 digits.
#[test]
fn huge_numbers_in_messages_are_short() {
    let out = bikedyn(&[
        "simulate",
        "--bike",
        "benchmark",
        "--speed",
        "5",
        "--duration",
        "1",
        "--kick",
        "1e300:1",
    ]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("1.000000000e300") && err.len() < 300, "{err}");
    let out = bikedyn(&["eig", "--bike", "benchmark", "--speeds", "0:1e300:1e299"]);
    let err = text(&out.stderr);
    assert!(err.len() < 400 && !err.contains("0000000000000000000000"), "{err}");
}

/// A file missing several fields reports all of them.
#[test]
fn all_missing_fields_at_once() {
    let p = tmp("two_fields.txt");
    std::fs::write(&p, "w = 1.02\nc = 0.08\n").unwrap();
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(
        err.contains("missing 24 parameters") && err.contains("`lam`") && err.contains("`IFyy`"),
        "{err}"
    );
}

/// A range of 1e300 points states the count and the
/// limit (it used to say "0 points is too many").
#[test]
fn too_many_points_says_how_many() {
    let out = bikedyn(&["eig", "--speeds", "0:1:1e-300"]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("1.000e300 points") && err.contains("limit of"), "{err}");
}

/// `--output` through a symbolic link writes the link's
/// target and keeps the link; a character device (`/dev/null`) and a FIFO
/// are written through, not replaced by a regular file; a directory is
/// refused.
#[cfg(unix)]
#[test]
fn output_keeps_links_devices_and_fifos() {
    use std::os::unix::fs::FileTypeExt;
    let target = tmp("real.csv");
    let link = tmp("link.csv");
    let _ = std::fs::remove_file(&link);
    let _ = std::fs::remove_file(&target);
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let out = bikedyn(&[
        "eig",
        "--speeds",
        "0:1:0.5",
        "--format",
        "csv",
        "--output",
        link.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(&target).unwrap().starts_with("v,re_1"));

    let out = bikedyn(&["eig", "--speeds", "0:1:0.5", "--format", "csv", "--output", "/dev/null"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::metadata("/dev/null").unwrap().file_type().is_char_device());

    let fifo = tmp("pipe.csv");
    let _ = std::fs::remove_file(&fifo);
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
    {
        let f2 = fifo.clone();
        let reader = std::thread::spawn(move || std::fs::read_to_string(f2).unwrap());
        let out = bikedyn(&[
            "eig",
            "--speeds",
            "0:1:0.5",
            "--format",
            "json",
            "--output",
            fifo.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let got = reader.join().unwrap();
        assert!(got.contains("mode_shapes"), "{got}");
        assert!(std::fs::metadata(&fifo).unwrap().file_type().is_fifo());
    } else {
        eprintln!("SKIP: mkfifo not available");
    }

    let out = bikedyn(&[
        "eig",
        "--format",
        "csv",
        "--output",
        std::env::temp_dir().to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("is a directory"), "{}", text(&out.stderr));
}

/// An unsupported plot format is reported before any
/// output (it used to print the whole table and then fail).
#[test]
fn outputs_are_validated_before_computing() {
    let out = bikedyn(&["eig", "--speeds", "0:1:0.1", "--plot", tmp("x.gif").to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(out.stdout.is_empty(), "{}", text(&out.stdout));
    assert!(text(&out.stderr).contains("unsupported file extension"));
    let out = bikedyn(&["eig", "--format", "csv", "--output", "/nonexistent-dir/e.csv"]);
    assert!(!out.status.success() && out.stdout.is_empty());
}

/// `eig` streams CSV and JSON (several blocks
/// here) with the same labels as one in-memory sweep, and both carry the
/// mode shapes.
#[test]
fn streamed_eig_output_with_mode_shapes() {
    let out = bikedyn(&[
        "eig",
        "--bike",
        "benchmark",
        "--speeds",
        "0:10:0.001",
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let pts = v.as_array().unwrap();
    assert_eq!(pts.len(), 10_001);
    // v = 5 m/s, computed in the second block, matches a one-point request.
    let one = bikedyn(&["eig", "--bike", "benchmark", "--speeds", "5", "--format", "json"]);
    let one: serde_json::Value = serde_json::from_slice(&one.stdout).unwrap();
    assert_eq!(pts[5000], one[0]);
    let shapes = pts[5000]["mode_shapes"].as_array().unwrap();
    assert_eq!(shapes.len(), 4);
    assert_eq!(shapes[0]["roll_amplitude"].as_f64().unwrap(), 1.0);
    let out = bikedyn(&[
        "eig",
        "--bike",
        "benchmark",
        "--speeds",
        "0:10:0.001",
        "--format",
        "csv",
    ]);
    let s = text(&out.stdout);
    assert_eq!(s.lines().count(), 10_002);
    assert!(s.starts_with("v,re_1,im_1,mode_1,roll_amp_1,roll_phase_1,steer_amp_1,steer_phase_1,re_2"));
}

/// `params show` prints the derived geometry of a bicycle
/// in either form, as comments (the output still loads).
#[test]
fn params_show_prints_derived_geometry() {
    for bike in ["thesis", "benchmark"] {
        let out = bikedyn(&["params", "show", "--bike", bike]);
        let s = text(&out.stdout);
        for key in ["# w ", "# c ", "# lam ", "# mT ", "# xT ", "# hT ", "# IAll "] {
            assert!(s.contains(key), "{bike}: {key} missing in\n{s}");
        }
        let p = tmp(&format!("{bike}_shown.toml"));
        std::fs::write(&p, &s).unwrap();
        let again = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
        assert!(again.status.success(), "{}", text(&again.stderr));
    }
    let s = text(&bikedyn(&["params", "show", "--bike", "benchmark"]).stdout);
    assert!(s.contains("# mT       =      94.000000 kg"), "{s}");
}

/// `sweep --param2` maps a chosen quantity; `--map
/// least-stable --at-speed 5` records the real part of the least stable
/// eigenvalue at 5 m/s (-0.322866429004 for the benchmark bicycle, as `eig`
/// gives), and cells whose stable range is cut by `--speed-max` are marked
/// in the plot.
#[test]
fn sweep_maps_a_chosen_quantity() {
    let svg = tmp("least.svg");
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.06:0.1:0.02",
        "--param2",
        "lam",
        "--values2",
        "0.3141592653589793",
        "--map",
        "least-stable",
        "--at-speed",
        "5",
        "--speed-max",
        "5",
        "--plot",
        svg.to_str().unwrap(),
        "--format",
        "json",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cell = &v["cells"][1];
    assert_eq!(cell["x"].as_f64().unwrap(), 0.08);
    assert!((cell["least_stable_real_part"].as_f64().unwrap() + 0.32286642900408524).abs() < 1e-12);
    assert_eq!(cell["open_ended"].as_bool(), Some(true));
    let drawn = std::fs::read_to_string(&svg).unwrap();
    // Issue 20: the map says the speed it was made at.
    assert!(drawn.contains("largest real part at v = 5 m/s (1/s)"), "{drawn}");
    assert!(drawn.contains("range cut there"));
    // The weave-speed map is another quantity on the same grid.
    let svg2 = tmp("weave.svg");
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.06:0.1:0.02",
        "--param2",
        "lam",
        "--values2",
        "0.3141592653589793",
        "--map",
        "weave",
        "--plot",
        svg2.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(std::fs::read_to_string(&svg2).unwrap().contains("weave speed (m/s)"));
    let out = bikedyn(&[
        "sweep",
        "--param",
        "c",
        "--values",
        "0:0.1:0.1",
        "--map",
        "least-stable",
    ]);
    assert!(!out.status.success() && text(&out.stderr).contains("--at-speed"));
}

/// The in-memory outputs state their limits: a table of
/// more than 100,000 rows points to the streamed formats, and a stability
/// map of more than 10^7 cells says how many it would have.
#[test]
fn in_memory_limits_are_stated() {
    let out = bikedyn(&["eig", "--speeds", "0:10:1e-5"]);
    let err = text(&out.stderr);
    assert!(
        err.contains("1000001 points") && err.contains("--format csv or json streams"),
        "{err}"
    );
    let out = bikedyn(&[
        "sweep",
        "--param",
        "c",
        "--values",
        "0:1:1e-4",
        "--param2",
        "lam",
        "--values2",
        "0:1:1e-4",
    ]);
    let err = text(&out.stderr);
    assert!(
        err.contains("10001 x 10001") && err.contains("limit of 10000000"),
        "{err}"
    );
}
