//! Regressions of the reliability audit (issue 20, point 5): each test is
//! one defect the audit found, driven through the command line as a user
//! would meet it.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let d = scratch("reliability").join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// A closed pipe or a full device on standard output used to panic (exit
/// 101) in most commands. A full device is an error (exit 2) that says the
/// output is incomplete; a pipe closed by its reader (`| head -1`) stops
/// the command quietly with exit 0, as Unix tools do (issue 35, reproducer
/// 28: the JSON path printed "Broken pipe (os error 32)"). Outputs larger
/// than a pipe's buffer (64 KiB), so the write surely fails: streamed CSV
/// and JSON, and two aligned tables.
#[test]
fn a_closed_pipe_stops_quietly_and_a_full_device_is_an_error() {
    for args in [
        &[
            "eig",
            "--bike",
            "benchmark",
            "--speeds",
            "0:100:0.001",
            "--format",
            "csv",
        ][..],
        &[
            "eig",
            "--bike",
            "benchmark",
            "--speeds",
            "0:100:0.001",
            "--format",
            "json",
        ][..],
        &["eig", "--bike", "benchmark", "--speeds", "0:20:0.001"][..],
        &[
            "sweep",
            "--bike",
            "benchmark",
            "--param",
            "c",
            "--values",
            "0:0.2:0.0001",
        ][..],
    ] {
        let (code, stderr) = with_closed_stdout(args);
        assert_eq!(code, Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("panicked") && !stderr.contains("error") && !stderr.to_lowercase().contains("broken pipe"),
            "{args:?}: {stderr}"
        );
    }
    if Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new().write(true).open("/dev/full").unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
            .args(["models"])
            .stdout(full)
            .output()
            .unwrap();
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains("writing to standard output") && !stderr.contains("panicked"),
            "{stderr}"
        );
    }
}

/// `synth --out` into a folder with files in it used to overwrite its
/// calibration and first runs and keep the rest: now it is refused and the
/// folder left as it was; `--force` replaces a set synth wrote whole (no
/// run of the old set survives beside the new ones), and only such a set
/// (see `user_files`). A set is written beside the folder and renamed into
/// place, so a refused or failed run leaves no partial folder.
#[test]
fn synth_refuses_a_folder_with_files_and_replaces_its_own_set_whole_when_forced() {
    let dir = tmp("synth-existing");
    std::fs::create_dir_all(dir.join("run09")).unwrap();
    std::fs::write(dir.join("run09/run.toml"), "measured data\n").unwrap();
    let out_arg = dir.to_str().unwrap();
    let out = bikedyn(&["synth", "--runs", "1", "--out", out_arg]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("is not empty") && stderr.contains("--force"),
        "{stderr}"
    );
    assert_eq!(entries(&dir), vec!["run09"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("run09/run.toml")).unwrap(),
        "measured data\n"
    );

    // A set of synth's own with more runs is replaced whole.
    std::fs::remove_dir_all(&dir).unwrap();
    let out = bikedyn(&["synth", "--runs", "2", "--out", out_arg]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = bikedyn(&["synth", "--runs", "1", "--out", out_arg, "--force"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(entries(&dir), vec![".bikedyn-output", "calibration", "run01", "truth"]);
    // Only this set's own temporaries: other tests share the parent folder.
    let own = format!(".{}.", dir.file_name().unwrap().to_string_lossy());
    let parent = entries(dir.parent().unwrap());
    assert!(
        !parent.iter().any(|n| n.starts_with(&own) && n.contains(".partial-")),
        "{parent:?}"
    );
}

/// `synth | head -1` used to leave a half-written set: the set is now
/// complete before the first line is printed, so a closed pipe costs only
/// the console lines (and stops quietly).
#[test]
fn synth_into_a_closed_pipe_still_writes_the_whole_set() {
    let dir = tmp("synth-closed-pipe");
    let (code, stderr) = with_closed_stdout(&["synth", "--runs", "2", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(
        entries(&dir),
        vec![".bikedyn-output", "calibration", "run01", "run02", "truth"]
    );
    assert!(!entries(&dir.join("truth")).is_empty());
}

/// A synthetic set of `runs` runs of the thesis bicycle in a fresh folder.
fn synth_set(name: &str, runs: usize) -> PathBuf {
    let dir = tmp(name);
    let out = bikedyn(&[
        "synth",
        "--runs",
        &runs.to_string(),
        "--seed",
        "5",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "synth: {}", text(&out.stderr));
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// `identify R R R` used to report three kicks from one run and
/// cross-validate on copies of the training run; a copy of a run (even one
/// marked as a calibration) was counted as data. Both are refused, naming
/// the two paths.
#[test]
fn the_same_run_given_twice_is_refused() {
    let set = synth_set("duplicates", 2);
    let run = set.join("run01");
    let r = run.to_str().unwrap();
    for cmd in ["fit", "identify"] {
        let out = bikedyn(&[cmd, r, r, r]);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{cmd}: {stderr}");
        assert!(
            stderr.contains("are the same run") && stderr.contains("run01"),
            "{cmd}: {stderr}"
        );
    }
    // A copy inside the set, under another name: the same data files.
    copy_dir(&run, &set.join("run03"));
    let out = bikedyn(&["fit", set.to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("a copy") && stderr.contains("run03"), "{stderr}");
    // The copy marked as a calibration, given as the calibration.
    let cal = set.join("run03");
    let toml = std::fs::read_to_string(cal.join("run.toml")).unwrap();
    std::fs::write(
        cal.join("run.toml"),
        toml.replace("kind = \"run\"", "kind = \"calibration\""),
    )
    .unwrap();
    let out = bikedyn(&["fit", r, "--calibration", cal.to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("calibration is a copy of a run"), "{stderr}");
}

/// A calibration run given alone used to vanish from the counts: it is
/// listed as skipped with the reason, and the exit status says so.
#[test]
fn a_calibration_given_as_data_is_listed_as_skipped() {
    let set = synth_set("calibration-as-data", 1);
    let out = bikedyn(&[
        "fit",
        set.join("calibration").to_str().unwrap(),
        set.join("run01").to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    // Given with the run it calibrates: used, nothing skipped.
    assert!(out.status.success(), "{stderr}");
    let other = synth_set("calibration-alone", 1);
    let out = bikedyn(&[
        "fit",
        other.join("calibration").to_str().unwrap(),
        set.join("run01").to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("skipped: ") && stderr.contains("a calibration run"),
        "{stderr}"
    );
}

/// A run whose speed sensor recorded nothing used to be a success with a
/// mean speed of -0.0: now the kick is fitted, its prediction is skipped
/// with the reason, and the exit status is 1.
#[test]
fn a_run_without_a_speed_record_says_so() {
    let set = synth_set("no-speed", 1);
    let speed = set.join("run01/speed_switch.csv");
    let flat: String = std::fs::read_to_string(&speed)
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
    std::fs::write(&speed, flat).unwrap();
    let out = bikedyn(&["fit", set.to_str().unwrap(), "--bike", "thesis", "--json"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("no usable speed record"), "{stderr}");
    let kicks = stdout_json(&out);
    for k in kicks.as_array().unwrap() {
        assert!(k["mean_speed"].is_null() && k["predicted_weave"].is_null(), "{k}");
        assert!(
            k["no_prediction"].as_str().unwrap().contains("no usable speed record"),
            "{k}"
        );
    }
}

/// `params convert` used to drop the effect parameters (a fitted.toml lost
/// `CdA` and `c_steer`): they follow the converted table, and the converted
/// file loads back with the same values.
#[test]
fn params_convert_keeps_effect_parameters() {
    let dir = tmp("convert");
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("damped.toml");
    let benchmark = include_str!("../../runtime/data/benchmark_bicycle.toml");
    std::fs::write(&src, format!("{benchmark}\nc_steer = 0.25\nCdA = 0.4\n")).unwrap();
    for form in ["thesis", "benchmark"] {
        let converted = dir.join(format!("to-{form}.toml"));
        let out = bikedyn(&[
            "params",
            "convert",
            "--to",
            form,
            src.to_str().unwrap(),
            "--output",
            converted.to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let text_out = std::fs::read_to_string(&converted).unwrap();
        assert!(
            text_out.contains("c_steer = 2.5e-1") && text_out.contains("CdA = 4e-1"),
            "{text_out}"
        );
        let out = bikedyn(&["params", "show", converted.to_str().unwrap()]);
        let shown = text(&out.stdout);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert!(shown.contains("c_steer") && shown.contains("CdA"), "{shown}");
    }
}

/// `--effects` with an unknown symbol used to list 52 geometry symbols and
/// not `c_steer`; a repeated symbol silently took its last value.
#[test]
fn effect_symbols_are_listed_suggested_and_given_once() {
    let dir = tmp("effects-args");
    let out = bikedyn(&[
        "synth",
        "--runs",
        "1",
        "--effects",
        "c_stear=0.1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("did you mean `c_steer`?"), "{stderr}");
    assert!(
        stderr.contains("effect parameters are ") && stderr.contains("CdA"),
        "{stderr}"
    );
    let out = bikedyn(&[
        "synth",
        "--runs",
        "1",
        "--effects",
        "c_steer=0.1,c_steer=0.3",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`c_steer` is given twice (0.1 and 0.3)"), "{stderr}");
    assert!(!dir.exists());
}

/// `verify --states 0` used to report "verification passed" having checked
/// nothing, and `--states` and `--folds` took any count (folds silently
/// clamped): the counts are bounded with the range in the message.
#[test]
fn counts_on_the_command_line_are_bounded() {
    for args in [
        &["verify", "--states", "0"][..],
        &["verify", "--states", "100001"][..],
        &["identify", "x", "--folds", "1"][..],
        &["identify", "x", "--folds", "0"][..],
    ] {
        let out = bikedyn(args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("not in 1..=100000") || stderr.contains("not in 2..=1000"),
            "{args:?}: {stderr}"
        );
    }
}

/// A raw bicycleparameters measurement file (`<Name>Measured.txt`) is
/// recognised and the message says what it is and what to do with it.
#[test]
fn a_raw_measurement_file_is_recognised() {
    let dir = tmp("measured");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("CrescendoMeasured.txt");
    std::fs::write(
        &p,
        "lF = 0.301+/-0.001\nlP = 1.05+/-0.001\nnF = 13\nTcB1 = 1.16+/-0.01\n",
    )
    .unwrap();
    let out = bikedyn(&["canonical", "--bike", p.to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("CrescendoMeasured.txt:1")
            && stderr.contains("raw measurement")
            && stderr.contains("Benchmark.txt"),
        "{stderr}"
    );
}

/// Uncertainties (`+/-`) of a parameter file are kept and shown by
/// `params show`, not dropped silently.
#[test]
fn params_show_shows_the_uncertainties() {
    let out = bikedyn(&["params", "show", &fixture_arg("Balanceassistv1Benchmark.txt")]);
    let shown = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(shown.contains("standard deviations the file gives"), "{shown}");
    assert!(
        shown.lines().any(|l| l.starts_with("#   w ") && l.contains("+/- ")),
        "{shown}"
    );
}

/// Negative numbers after a flag are values (`--speed -5`), ranges may
/// start below zero, and a kick in the wrong format shows the right one.
#[test]
fn negative_values_and_kick_formats() {
    let out = bikedyn(&["eig", "--bike", "benchmark", "--speeds", "-1:1:1", "--format", "csv"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        text(&out.stdout).lines().filter(|l| l.starts_with("-1")).count(),
        1,
        "{}",
        text(&out.stdout)
    );
    let out = bikedyn(&["simulate", "--speed", "-5", "--duration", "0.1"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let out = bikedyn(&["simulate", "--speed", "5", "--duration", "1", "--kick", "1,3"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("TIME:IMPULSE") && stderr.contains("1.0:3"), "{stderr}");
}

/// `identify --report` into a folder that cannot take a report fails before
/// any computation; an earlier report is replaced whole (a failed run
/// would leave it as it was: the new one is written beside it and moved
/// into place), so no old file stays beside the new ones. (A file that no
/// report wrote is never deleted: see `user_files`.)
#[test]
fn an_identify_report_is_checked_first_and_replaced_whole() {
    let set = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/hidden_steer_damping");
    let foreign = tmp("report-foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("thesis.tex"), "a user's file\n").unwrap();
    let out = bikedyn(&["identify", set.to_str().unwrap(), "--report", foreign.to_str().unwrap()]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no .bikedyn-output file") && !stderr.contains("progress:"),
        "{stderr}"
    );
    assert_eq!(entries(&foreign), vec!["thesis.tex"]);
    let under_file = foreign.join("thesis.tex").join("report");
    let out = bikedyn(&[
        "identify",
        set.to_str().unwrap(),
        "--report",
        under_file.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(!text(&out.stderr).contains("progress:"), "{}", text(&out.stderr));

    // The file handling is under test, not the search: one candidate.
    let quick = ["--effects", "steer_damping", "--corrections", "0", "--no-discover"];
    // Its own parent folder: the check below that nothing is left beside
    // the report must not see another test's partial file in `tmp`'s
    // shared folder (CI once failed on `.synth-closed-pipe.partial-*`).
    let earlier = tmp("report-earlier").join("report");
    std::fs::create_dir_all(earlier.parent().unwrap()).unwrap();
    let out = bikedyn(
        &[
            &["identify", set.to_str().unwrap(), "--report", earlier.to_str().unwrap()],
            &quick[..],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    // An earlier report with a plot this one does not draw (listed among
    // the files bikedyn wrote, as a report of another version would be).
    std::fs::write(earlier.join("stale_plot.svg"), "<svg/>\n").unwrap();
    let marker = earlier.join(".bikedyn-output");
    let listed = std::fs::read_to_string(&marker).unwrap() + "stale_plot.svg\n";
    std::fs::write(&marker, listed).unwrap();
    let out = bikedyn(
        &[
            &["identify", set.to_str().unwrap(), "--report", earlier.to_str().unwrap()],
            &quick[..],
        ]
        .concat(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let files = entries(&earlier);
    assert!(
        files.contains(&"report.md".to_string()) && !files.contains(&"stale_plot.svg".to_string()),
        "{files:?}"
    );
    let parent = entries(earlier.parent().unwrap());
    assert!(
        !parent.iter().any(|n| n.contains(".partial-") || n.ends_with(".old")),
        "{parent:?}"
    );
}

/// A two-parameter `sweep` streams its CSV a row at a time (a 1001 x 401
/// grid used to print nothing for 40 s): the streamed table is the one
/// the whole map gives (computed whole when a plot is asked for too).
#[test]
fn a_stability_map_streams_the_same_csv() {
    let args = [
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0:0.12:0.02",
        "--param2",
        "lam",
        "--values2",
        "0.2:0.5:0.1",
        "--format",
        "csv",
    ];
    let streamed = bikedyn(&args);
    assert!(streamed.status.success(), "{}", text(&streamed.stderr));
    let plot = tmp("map-plot").with_extension("svg");
    let mut whole_args = args.to_vec();
    whole_args.extend(["--plot", plot.to_str().unwrap()]);
    let whole = bikedyn(&whole_args);
    assert!(whole.status.success(), "{}", text(&whole.stderr));
    let s = text(&streamed.stdout);
    assert_eq!(s, text(&whole.stdout));
    assert_eq!(s.lines().count(), 1 + 7 * 4, "{s}");
    assert!(s.lines().last().unwrap().starts_with("0.12,0.5,6,3,"), "{s}");
}

/// A wrong nominal IMU rate in run.toml made every sample a gap, one line
/// each (1,213 lines): a few are shown per file, then one line with the
/// count and the likely cause.
#[test]
fn a_wrong_imu_rate_gives_a_few_gap_lines_and_the_cause() {
    let set = synth_set("wrong-rate", 1);
    let toml_path = set.join("run01/run.toml");
    let toml = std::fs::read_to_string(&toml_path).unwrap();
    assert!(toml.contains("rate_hz = 120"), "{toml}");
    std::fs::write(&toml_path, toml.replacen("rate_hz = 120", "rate_hz = 400", 1)).unwrap();
    let out = bikedyn(&["fit", set.join("run01").to_str().unwrap()]);
    let stderr = text(&out.stderr);
    let gap_lines = stderr.lines().filter(|l| l.contains(": gap ")).count();
    assert!(gap_lines <= 6, "{gap_lines} gap lines: {stderr}");
    assert!(stderr.contains("more gaps") && stderr.contains("rate_hz"), "{stderr}");
}

/// A plot or output path under a file (not a directory) says so, before
/// any computation, instead of the system's "File exists" or "does not
/// exist".
#[test]
fn an_output_under_a_file_says_the_folder_is_a_file() {
    let file = tmp("plain-file");
    std::fs::write(&file, "not a folder").unwrap();
    let plot = file.join("eig.svg");
    let out = bikedyn(&[
        "eig",
        "--bike",
        "benchmark",
        "--speeds",
        "0:1:0.5",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("is a file, not a directory") && err.contains("plain-file"),
        "{err}"
    );
    assert!(text(&out.stdout).is_empty(), "computed before checking the output");
}

/// `[speed_switch] magnets = 1e9` in one run.toml drove the process to
/// 23 GB and the whole batch was killed: every count read from a file is
/// bounded, and the run is refused with its file and field while the other
/// runs of the set are still fitted.
#[test]
fn a_huge_count_in_a_run_file_is_refused_not_allocated() {
    let set = tmp("magnets");
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/hidden_steer_damping");
    for run in ["calibration", "run01", "run02"] {
        copy_dir(&examples.join(run), &set.join(run));
    }
    let toml = set.join("run02/run.toml");
    let meta = std::fs::read_to_string(&toml).unwrap();
    assert!(meta.contains("magnets = 9"));
    std::fs::write(&toml, meta.replace("magnets = 9", "magnets = 1e9")).unwrap();
    let out = bikedyn(&["fit", set.to_str().unwrap(), "--json"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "a run failed: exit 1; {err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("skipped:") && l.contains("run02/run.toml") && l.contains("magnets = 1000000000")),
        "{err}"
    );
    let kicks: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(!kicks.as_array().unwrap().is_empty(), "run01 still fitted");
}

/// `--bike /dev/zero` grew to 2 GB: every input file is read through a
/// size cap, and a device is refused as no file, naming it, at once.
#[cfg(unix)]
#[test]
fn an_endless_input_file_is_refused_at_its_cap() {
    let out = bikedyn(&["params", "show", "--bike", "/dev/zero"]);
    let err = text(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("/dev/zero") && err.contains("is a device"), "{err}");
    // A run's data file likewise (a sensor log cannot be endless).
    let set = tmp("endless");
    let examples = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/hidden_steer_damping");
    for run in ["calibration", "run01"] {
        copy_dir(&examples.join(run), &set.join(run));
    }
    let csv = set.join("run01/speed_switch.csv");
    std::fs::remove_file(&csv).unwrap();
    std::os::unix::fs::symlink("/dev/zero", &csv).unwrap();
    let out = bikedyn(&["fit", set.join("run01").to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("speed_switch.csv") && err.contains("is a device"), "{err}");
}

/// A log of one 2 MiB line (no table at all) was refused with the whole
/// line echoed as the header it lacked: megabytes on the terminal. The
/// message names the file, the line and the missing column, and echoes the
/// line's start with the count of what it leaves out.
#[test]
fn a_file_of_one_long_line_is_refused_with_its_start_echoed() {
    let dir = tmp("one-long-line");
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("log.csv");
    std::fs::write(&log, "x".repeat(2 << 20)).unwrap();
    let bike = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tudelft_sbw_bicycle.toml");
    let out = bikedyn(&["fit", log.to_str().unwrap(), "--bike", bike.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("log.csv:1: header has no column `speed`"),
        "{}",
        &err[..err.len().min(500)]
    );
    assert!(err.contains("more characters)"), "{}", &err[..err.len().min(500)]);
    assert!(err.len() < 2000, "{} bytes of messages", err.len());
}
