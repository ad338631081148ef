//! Arguments that make no sense are refused, naming the flag (issue 35,
//! point 1): a map over one parameter twice, an empty or unbounded speed
//! range, a temporary folder that does not exist.

use crate::common::*;

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
        let out = bikedyn(&["simulate", "--speed", "5", "--duration", "0.1", flag, v]);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{flag} {v}: {stderr}");
        assert!(stderr.contains(flag), "{stderr}");
    }
    // 0 still disables the stop.
    let out = bikedyn(&["simulate", "--speed", "5", "--duration", "0.1", "--roll-limit", "0"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}
