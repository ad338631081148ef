//! Arguments that make no sense are refused, naming the flag (issue 35,
//! point 1): a map over one parameter twice, an empty or unbounded speed
//! range, a temporary folder that does not exist.

use crate::common::*;

/// `bikedyn simulate` of a tenth of a second at 5 m/s with `extra`
/// arguments: the short run every flag check below needs.
fn short_simulation(extra: &[&str]) -> std::process::Output {
    bikedyn(&[&["simulate", "--speed", "5", "--duration", "0.1"][..], extra].concat())
}

/// `sweep --param c --param2 c` labelled its rows wrongly (every cell was
/// the second value's): refused, naming both flags.
#[test]
fn sweep_refuses_the_same_parameter_twice() {
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0:0.2:0.1",
        "--param2",
        "c",
        "--values2",
        "0:0.2:0.1",
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--param and --param2") && stderr.contains("`c`"),
        "{stderr}"
    );
    assert!(out.stdout.is_empty());
}

/// `stability --speed-max 0` printed "self-stable: never", and -5, NaN and
/// inf gave messages that did not name the flag: each is refused, naming
/// `--speed-max`, in `stability` and `sweep`.
#[test]
fn a_speed_max_that_is_not_a_positive_speed_is_refused() {
    for v in ["0", "-5", "nan", "inf"] {
        for args in [
            vec!["stability", "--bike", "benchmark", "--speed-max", v],
            vec![
                "sweep",
                "--bike",
                "benchmark",
                "--param",
                "c",
                "--values",
                "0:0.1:0.1",
                "--speed-max",
                v,
            ],
        ] {
            let out = bikedyn(&args);
            let stderr = text(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(
                stderr.contains("--speed-max") && stderr.contains("positive finite speed"),
                "{args:?}: {stderr}"
            );
        }
    }
}

/// `TMPDIR=/missing/dir bench --identify` created the missing folders and
/// left them: it fails at once, naming the folder and what to do.
#[test]
fn bench_refuses_a_temporary_folder_that_does_not_exist() {
    let missing = scratch("arguments").join("missing-tmp").join("dir");
    let _ = std::fs::remove_dir_all(missing.parent().unwrap());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args(["bench", "--identify"])
        .env("TMPDIR", &missing)
        .output()
        .unwrap();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(missing.to_str().unwrap()) && stderr.contains("TMPDIR"),
        "{stderr}"
    );
    assert!(!missing.parent().unwrap().exists());
}

/// A value set by `sweep --param` is checked as a parameter file's would be:
/// a wheelbase of 1000-1020 is millimetres, refused with the value named
/// (Python's `with_parameters` goes through the same check).
#[test]
fn a_swept_length_in_millimetres_is_refused() {
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "w",
        "--values",
        "1000:1020:10",
    ]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("w = 1000") && stderr.contains("millimetres"),
        "{stderr}"
    );
}

/// `simulate --roll-limit nan` (or -5) silently disabled the stop: a stop
/// angle that is no angle is refused, naming the flag.
#[test]
fn a_stop_angle_that_is_not_an_angle_is_refused() {
    for (flag, v) in [
        ("--roll-limit", "nan"),
        ("--roll-limit", "-5"),
        ("--steer-limit", "inf"),
    ] {
        let out = short_simulation(&[flag, v]);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{flag} {v}: {stderr}");
        assert!(stderr.contains(flag), "{stderr}");
    }
    // 0 still disables the stop.
    let out = short_simulation(&["--roll-limit", "0"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// `simulate --kick T:J:AHEAD:-1` kicked the bicycle a metre below the
/// ground without a word: a height below the ground is refused, naming the
/// flag.
#[test]
fn a_kick_below_the_ground_is_refused() {
    let out = short_simulation(&["--kick", "0.05:3:0.25:-1"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--kick") && stderr.contains("below the ground"),
        "{stderr}"
    );
    let out = short_simulation(&["--kick", "0.05:3:0.25:0.95"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// `simulate --rtol 1e-300` was clamped silently to what the integrator
/// can meet: a tolerance below ten units of rounding (and a non-positive
/// absolute one) is refused, naming the flag and the floor.
#[test]
fn a_tolerance_below_rounding_is_refused_not_clamped() {
    for (flag, v) in [
        ("--rtol", "1e-300"),
        ("--rtol", "0"),
        ("--atol", "-1"),
        ("--atol", "inf"),
    ] {
        let out = short_simulation(&[flag, v]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {v}: {stderr}");
        assert!(stderr.contains(flag), "{flag} {v}: {stderr}");
    }
    let out = short_simulation(&["--rtol", "1e-300"]);
    assert!(text(&out.stderr).contains("2.2e-15"), "{}", text(&out.stderr));
    let out = short_simulation(&["--rtol", "1e-14"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// `--free-speed` with `--model thesis_whipple` ran another model than the
/// one named, saying so only in the first line of the output: a note on
/// standard error names both.
#[test]
fn free_speed_says_which_model_it_runs_for_the_one_named() {
    let out = short_simulation(&["--free-speed", "--model", "thesis_whipple"]);
    let stderr = text(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("--free-speed runs thesis_whipple_free") && stderr.contains("--model thesis_whipple"),
        "{stderr}"
    );
}

/// `synth --speeds 100:200` made a set at speeds no bicycle is measured at
/// (and `fit` refuses): release speeds above 30 m/s are refused.
#[test]
fn synth_refuses_release_speeds_no_bicycle_rides_at() {
    let out_dir = scratch("arguments").join("synth-fast");
    let _ = std::fs::remove_dir_all(&out_dir);
    let out = bikedyn(&[
        "synth",
        "--runs",
        "1",
        "--speeds",
        "100:200",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--speeds") && stderr.contains("30"), "{stderr}");
    assert!(!out_dir.exists());
}

/// `canonical --speeds foo` was ignored for a bicycle with a canonical form
/// (the speeds are used only without one): it is refused, naming the flag.
#[test]
fn canonical_checks_its_speeds_even_when_they_are_not_used() {
    let out = bikedyn(&["canonical", "--bike", "benchmark", "--speeds", "foo"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--speeds"), "{stderr}");
    assert!(out.stdout.is_empty());
}

/// A `BIKEDYN_FONT` that names no font file (missing, a folder, a device)
/// was passed over for a system font without a word: the figure is
/// refused, naming the variable and the path.
#[test]
fn a_font_named_by_bikedyn_font_is_used_or_refused() {
    let dir = scratch("arguments").join("font");
    std::fs::create_dir_all(&dir).unwrap();
    let plot = dir.join("eig.svg");
    for font in ["/nonexistent/font.ttf", dir.to_str().unwrap(), "/dev/zero"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_bikedyn"))
            .args([
                "eig",
                "--bike",
                "benchmark",
                "--speeds",
                "0:10:1",
                "--plot",
                plot.to_str().unwrap(),
            ])
            .env("BIKEDYN_FONT", font)
            .output()
            .unwrap();
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{font}: {stderr}");
        assert!(
            stderr.contains("BIKEDYN_FONT") && stderr.contains(font),
            "{font}: {stderr}"
        );
    }
}
