//! Bad input files give a clear error naming the file, the line or the
//! field and what to do, or a correct result (issue 35, reproducers 3, 5,
//! 7, 9, 11, 13, 14, 21, 24, 25, 27 and 30): size caps checked before
//! reading, eigenvalue tables and TU Delft logs checked row by row, one
//! geometry check for every command, no kick found is a failure, formats
//! found from the content, and the real cause stated.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn tmp(name: &str) -> PathBuf {
    let d = scratch("bad-inputs").join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn arg(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs `bikedyn args`, asserts it failed with exit 1 or 2 and nothing
/// on standard output, and returns standard error.
fn fails(args: &[&str]) -> String {
    let out = bikedyn(args);
    let err = text(&out.stderr);
    assert!(
        matches!(out.status.code(), Some(1 | 2)),
        "{args:?}: {:?} {err}",
        out.status
    );
    err
}

/// A file of `bytes` bytes holding no data (sparse): a size check refuses
/// it at once, a reader would first take the whole of it.
fn sparse(dir: &Path, name: &str, bytes: u64) -> PathBuf {
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().set_len(bytes).unwrap();
    p
}

/// Files far above their cap (an eigenvalue table, a parameter file, a TU
/// Delft log and a run's IMU record of 1 GiB) are refused from their size,
/// at once and naming the size, before a byte is read (a 1 GB log used to
/// be refused only after 1.03 GB were resident); devices such as
/// `/dev/zero` are refused as not files (`identify --eigenvalues /dev/zero`
/// grew to 8.4 GB).
#[test]
fn files_above_their_cap_are_refused_from_their_size_at_once() {
    let d = tmp("caps");
    let gib = 1u64 << 30;
    let table = sparse(&d, "table.csv", gib);
    let bike = sparse(&d, "bike.toml", gib);
    let log = sparse(&d, "kicks.log", gib);
    let set = d.join("set");
    copy_dir(&example_set().join("calibration"), &set.join("calibration"));
    copy_dir(&example_set().join("run01"), &set.join("run01"));
    std::fs::File::options()
        .write(true)
        .open(set.join("run01/imu_frame.csv"))
        .unwrap()
        .set_len(gib)
        .unwrap();
    let tudelft = fixture_arg("tudelft_sbw_bicycle.toml");
    for (args, file) in [
        (
            vec!["identify", "--eigenvalues", arg(&table), "--bike", "thesis"],
            "table.csv",
        ),
        (vec!["stability", "--bike", arg(&bike)], "bike.toml"),
        (vec!["fit", arg(&log), "--bike", &tudelft], "kicks.log"),
        (vec!["fit", arg(&set)], "imu_frame.csv"),
    ] {
        let start = Instant::now();
        let err = fails(&args);
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "{args:?} took {:?}",
            start.elapsed()
        );
        assert!(err.contains(file) && err.contains(&gib.to_string()), "{args:?}: {err}");
        assert!(err.contains("MiB"), "{args:?}: the cap is named: {err}");
    }
    if cfg!(unix) {
        for dev in ["/dev/zero", "/dev/urandom"] {
            let err = fails(&["identify", "--eigenvalues", dev, "--bike", "thesis"]);
            assert!(err.contains(dev) && err.contains("device"), "{err}");
        }
    }
}

/// `identify --eigenvalues` on a table with a row out of a bicycle's speed
/// range (1e6 m/s used to select m3 = -2.82 kg), a repeated row (it counted
/// twice), rows of 3 and 5 fields mixed, or a field that is not finite is
/// refused, naming the line; a clean table still identifies.
#[test]
fn eigenvalue_tables_with_bad_rows_are_refused_naming_the_line() {
    let d = tmp("tables");
    let header = "speed,re,im\n";
    let rows = ["3,-0.5,3.8", "4,-1.2,5.4", "5,-1.8,6.6", "6,-2.4,7.6"];
    let write = |name: &str, rows: &[&str]| {
        let p = d.join(name);
        std::fs::write(&p, format!("{header}{}\n", rows.join("\n"))).unwrap();
        p
    };
    let good = write("good.csv", &rows);
    ok_json(&["identify", "--eigenvalues", arg(&good), "--bike", "thesis", "--json"]);
    // Every speed outside (0, 30] m/s, in the third row (line 4).
    for speed in ["1e6", "30.5", "0", "-4", "inf", "nan"] {
        let bad = format!("{speed},-1.8,6.6");
        let p = write("speed.csv", &[rows[0], rows[1], &bad, rows[3]]);
        let err = fails(&["identify", "--eigenvalues", arg(&p), "--bike", "thesis"]);
        assert!(err.contains("speed.csv:4"), "{speed}: {err}");
    }
    let p = write("repeated.csv", &[rows[0], rows[1], rows[1], rows[3]]);
    let err = fails(&["identify", "--eigenvalues", arg(&p), "--bike", "thesis"]);
    assert!(
        err.contains("repeated.csv:4") && err.contains("repeats line 3"),
        "{err}"
    );
    let p = write("mixed.csv", &[rows[0], "4,-1.2,5.4,0.1,0.1", rows[2], rows[3]]);
    let err = fails(&["identify", "--eigenvalues", arg(&p), "--bike", "thesis"]);
    assert!(err.contains("mixed.csv:3") && err.contains("line 2 has 3"), "{err}");
}

/// `identify --eigenvalues --effects steer_friction` used to exit 0 having
/// tried nothing (friction needs the response's amplitude, which a table
/// lacks): it is refused, listing the effects a table can try.
#[test]
fn an_effect_a_table_cannot_try_is_refused_with_those_it_can() {
    let d = tmp("effects");
    let p = d.join("t.csv");
    std::fs::write(&p, "speed,re,im\n3,-0.5,3.8\n4,-1.2,5.4\n5,-1.8,6.6\n6,-2.4,7.6\n").unwrap();
    let err = fails(&[
        "identify",
        "--eigenvalues",
        arg(&p),
        "--bike",
        "thesis",
        "--effects",
        "steer_friction",
    ]);
    assert!(
        err.contains("steer_friction") && err.contains("amplitude") && err.contains("steer_damping"),
        "{err}"
    );
}

/// A thesis parameter file whose geometry is no upright bicycle (x4 = -1:
/// a steer-axis tilt of 2.83 rad; a front wheel that cannot touch the
/// ground) used to pass `stability`, `eig`, `canonical` and `simulate`, and
/// `params` refused it without naming the file or the field. Every
/// command now refuses it through one check, naming the file, the line and
/// the field.
#[test]
fn impossible_thesis_geometry_is_refused_by_every_command_naming_the_field() {
    let d = tmp("geometry");
    let thesis = text(&bikedyn(&["params", "show", "thesis"]).stdout);
    let line_of = |sym: &str| {
        thesis
            .lines()
            .position(|l| l.starts_with(&format!("{sym} ")))
            .unwrap_or_else(|| panic!("{sym} in {thesis}"))
            + 1
    };
    // A steer axis tilted back beyond 90 degrees (x4 < 0), and a front
    // wheel too large to reach the ground (Rd = 2 m).
    for (sym, value) in [("x4", "-1"), ("x4", "-0.2"), ("Rd", "2")] {
        let edited: Vec<String> = thesis
            .lines()
            .map(|l| {
                if l.starts_with(&format!("{sym} ")) {
                    format!("{sym} = {value}")
                } else {
                    l.to_string()
                }
            })
            .collect();
        let p = d.join("tilted.toml");
        std::fs::write(&p, edited.join("\n") + "\n").unwrap();
        let b = arg(&p);
        let located = format!("(in {b}, line {})", line_of(sym));
        for args in [
            vec!["stability", "--bike", b],
            vec!["eig", "--bike", b],
            vec!["canonical", "--bike", b],
            vec!["simulate", "--bike", b, "--speed", "5", "--duration", "1"],
            vec!["sweep", "--bike", b, "--param", "m3", "--values", "5:7:1"],
            vec!["params", "show", b],
            vec!["params", "convert", "--to", "benchmark", b],
        ] {
            let err = fails(&args);
            assert!(
                err.contains(&format!("`{sym}` = ")) && err.contains(&located),
                "{sym} = {value}, {args:?}: {err}"
            );
        }
    }
}

/// The header of the TU Delft logs (13 columns; no time column).
const LOG_HEADER: &str = "sil_command,speed,lean_angle,lean_rate,hand_angle,fork_angle,fork_rate,lean_torque,hand_torque,x_acceleration,y_acceleration,command_fork,command_hand";

/// A TU Delft log of `n` rows at `speed` m/s whose other columns are
/// noise (uniform, seeded): distinct rows with no kick in them.
fn log_rows(n: usize, speed: f64) -> Vec<String> {
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut noise = |scale: f64| {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        scale * ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
    };
    (0..n)
        .map(|_| {
            format!(
                "0.0,{speed:.5},{:.5},{:.5},{:.5},{:.5},0.0,0.0,0.0,{:.5},{:.5},0.0,0.0",
                noise(0.01),
                noise(0.01),
                noise(0.02),
                noise(0.02),
                noise(1.0),
                noise(1.0)
            )
        })
        .collect()
}

fn write_log(dir: &Path, name: &str, rows: &[String]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, format!("{LOG_HEADER}\n{}\n", rows.join("\n"))).unwrap();
    p
}

/// A TU Delft log with a speed no bicycle rides at (-2.5 or 1e6 m/s, or
/// other units) used to be accepted with an empty prediction and no reason;
/// it is refused, naming the line and the column.
#[test]
fn a_log_with_an_implausible_speed_is_refused_naming_the_line() {
    let d = tmp("log-speed");
    let bike = fixture_arg("tudelft_sbw_bicycle.toml");
    for bad in [-2.5, 1e6, 31.0] {
        let mut rows = log_rows(400, 3.0);
        rows[100] = rows[100].replacen(",3.00000,", &format!(",{bad},"), 1);
        let p = write_log(&d, "speed.log", &rows);
        let err = fails(&["fit", arg(&p), "--bike", &bike]);
        // Line 102: the header is line 1, row 0 line 2.
        assert!(err.contains("speed.log:102") && err.contains("`speed`"), "{bad}: {err}");
    }
}

/// A TU Delft log with every row written twice used to halve the measured
/// frequencies (its times come from counting rows): a row repeating the
/// one before it field for field is refused, naming the first repetition.
#[test]
fn a_log_with_repeated_rows_is_refused_naming_the_first_repetition() {
    let d = tmp("log-repeats");
    let bike = fixture_arg("tudelft_sbw_bicycle.toml");
    let rows: Vec<String> = log_rows(300, 3.0).into_iter().flat_map(|r| [r.clone(), r]).collect();
    let p = write_log(&d, "twice.log", &rows);
    let err = fails(&["fit", arg(&p), "--bike", &bike]);
    assert!(err.contains("twice.log:3") && err.contains("repeats line 2"), "{err}");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// The example's calibration and its first run in a fresh set folder.
fn small_set(name: &str) -> PathBuf {
    let s = tmp(name).join("set");
    copy_dir(&example_set().join("calibration"), &s.join("calibration"));
    copy_dir(&example_set().join("run01"), &s.join("run01"));
    s
}

/// Every IMU sample of a run replaced by its first orientation (a frozen
/// sensor), times kept.
fn freeze_imu(run: &Path) {
    for f in ["imu_frame.csv", "imu_handlebar.csv"] {
        let p = run.join(f);
        let text = std::fs::read_to_string(&p).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap().to_string();
        let rows: Vec<&str> = lines.filter(|l| !l.trim().is_empty()).collect();
        let first: Vec<&str> = rows[0].splitn(2, ',').collect();
        let frozen: Vec<String> = rows
            .iter()
            .map(|r| format!("{},{}", r.split(',').next().unwrap(), first[1]))
            .collect();
        std::fs::write(&p, format!("{header}\n{}\n", frozen.join("\n"))).unwrap();
    }
}

/// A run or log in which no kick is found (a frozen IMU, a 20-row log, a
/// log of noise alone) used to give `[]` with exit 0: `fit` exits 1 and
/// says why for each; `identify` with nothing usable left fails too.
#[test]
fn no_kick_found_is_a_failure_with_the_reason() {
    let s = small_set("no-kick");
    freeze_imu(&s.join("run01"));
    let out = bikedyn(&["fit", arg(&s), "--json"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("run01: no kick found: "), "{err}");
    let out = bikedyn(&["identify", arg(&s)]);
    assert!(!out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("no kick found"), "{}", text(&out.stderr));
    let d = tmp("no-kick-logs");
    let bike = fixture_arg("tudelft_sbw_bicycle.toml");
    for (name, rows, why) in [
        ("short.log", log_rows(20, 3.0), ""),
        ("tiny.log", log_rows(8, 3.0), "too few"),
        ("noise.log", log_rows(3000, 3.0), "noise"),
    ] {
        let p = write_log(&d, name, &rows);
        let out = bikedyn(&["fit", arg(&p), "--bike", &bike, "--json"]);
        let err = text(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}: no kick found: ")) && err.contains(why),
            "{err}"
        );
    }
}

/// A parameter file is read in the format it is in: TOML through
/// `/dev/stdin`, under a `.txt` name or with no extension (it used to be
/// read as the text format: "value: unexpected `\"`"); a benchmark text
/// file without extension is still read as text.
#[test]
fn a_parameter_file_is_read_in_the_format_of_its_content() {
    let d = tmp("formats");
    let thesis = bikedyn(&["params", "show", "thesis"]).stdout;
    let expected = ok_json(&["stability", "--bike", "thesis", "--json"]);
    for name in ["bike.txt", "bike"] {
        let p = d.join(name);
        std::fs::write(&p, &thesis).unwrap();
        assert_eq!(
            ok_json(&["stability", "--bike", arg(&p), "--json"])["v_w"],
            expected["v_w"],
            "{name}"
        );
    }
    let text_form = d.join("bluenose");
    std::fs::copy(fixture("BluenosePar.txt"), &text_form).unwrap();
    let a = ok_json(&["stability", "--bike", arg(&text_form), "--json"]);
    let b = ok_json(&["stability", "--bike", &fixture_arg("BluenosePar.txt"), "--json"]);
    assert_eq!(a["v_w"], b["v_w"]);
    if cfg!(unix) {
        use std::io::Write;
        use std::process::{Command, Stdio};
        let mut child = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
            .args(["stability", "--bike", "/dev/stdin", "--json"])
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(&thesis).unwrap();
        let out = child.wait_with_output().unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(stdout_json(&out)["v_w"], expected["v_w"]);
    }
}

/// A folder of a set that looks like a run but has no run.toml (missing,
/// or a folder of that name) used to be skipped without a word: it is
/// named in a warning; a folder that is no run (notes, a synthetic set's
/// truth) is not.
#[test]
fn a_run_folder_without_run_toml_is_named_in_a_warning() {
    let s = small_set("no-run-toml");
    copy_dir(&example_set().join("run02"), &s.join("run07"));
    std::fs::remove_file(s.join("run07/run.toml")).unwrap();
    copy_dir(&example_set().join("run03"), &s.join("run08"));
    std::fs::remove_file(s.join("run08/run.toml")).unwrap();
    std::fs::create_dir(s.join("run08/run.toml")).unwrap();
    std::fs::create_dir(s.join("docs")).unwrap();
    std::fs::write(s.join("docs/notes.txt"), "x\n").unwrap();
    // A synthetic set's truth files are CSV too, but no run's records.
    std::fs::create_dir(s.join("truth")).unwrap();
    std::fs::write(s.join("truth/run01_trajectory.csv"), "t,roll\n0,0\n").unwrap();
    let out = bikedyn(&["fit", arg(&s), "--json"]);
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains(&format!("warning: {}: left out", s.join("run07").display())),
        "{err}"
    );
    assert!(err.contains("run08: left out") && err.contains("not a file"), "{err}");
    assert!(!err.contains("docs") && !err.contains("truth"), "{err}");
    assert_eq!(stdout_json(&out).as_array().unwrap().len(), 1);
}

/// The real cause is stated: a nominal clock offset of -100 s moves the
/// speed record off the run (it used to say the wheel sensor gave no
/// speed); a set folder holding only its calibration is a calibration
/// with no kick (not "not a run folder"); a folder that cannot be read
/// says why; a 200 KB line of a run.toml is not echoed whole.
#[test]
fn the_real_cause_is_stated() {
    let s = small_set("causes-offset");
    let meta = s.join("run01/run.toml");
    let toml = std::fs::read_to_string(&meta).unwrap();
    let edited: Vec<String> = toml
        .lines()
        .map(|l| {
            if l.starts_with("nominal_offset_s") {
                "nominal_offset_s = -100".to_string()
            } else {
                l.to_string()
            }
        })
        .collect();
    std::fs::write(&meta, edited.join("\n") + "\n").unwrap();
    let err = fails(&["fit", arg(&s), "--nominal-clock"]);
    assert!(
        err.contains("nominal_offset_s") && err.contains("misses the window"),
        "{err}"
    );

    let s = small_set("causes-calibration");
    std::fs::remove_dir_all(s.join("run01")).unwrap();
    let err = fails(&["fit", arg(&s)]);
    assert!(
        err.contains("a calibration run") && !err.contains("not a run folder"),
        "{err}"
    );

    let missing = s.join("nowhere");
    let err = fails(&["fit", arg(&missing)]);
    assert!(err.contains("cannot be read"), "{err}");

    let s = small_set("causes-nested");
    let deep = format!("a = {}{}\n", "[".repeat(100_000), "]".repeat(100_000));
    std::fs::write(s.join("run01/run.toml"), deep).unwrap();
    let err = fails(&["fit", arg(&s)]);
    assert!(
        err.contains("run.toml") && err.len() < 2000,
        "{} bytes: {err:.3000}",
        err.len()
    );
}

/// `--plot-size 20000x20000px` was within the documented cap and took
/// 2.3 GB: the cap is 40 million pixels (refused above it, naming the
/// flag), and a figure at the cap stays well under 1 GB.
#[test]
fn the_plot_size_cap_keeps_memory_well_under_a_gigabyte() {
    let d = tmp("plot-size");
    let png = d.join("big.png");
    let base = ["eig", "--speeds", "0:10:0.1", "--format", "csv", "--plot", arg(&png)];
    let mut args = base.to_vec();
    args.extend(["--plot-size", "20000x20000px"]);
    let err = fails(&args);
    assert!(err.contains("--plot-size") && err.contains("40 million"), "{err}");
    assert!(!png.exists());
    let mut args = base.to_vec();
    args.extend(["--plot-size", "4470x4470px"]);
    let peak = peak_memory_kib(&args);
    assert!(png.exists());
    if let Some(kib) = peak {
        assert!(kib < 700 * 1024, "peak {kib} KiB");
    }
}

/// Runs `bikedyn args` to success and returns the peak resident memory
/// it reached (KiB), sampled from `/proc` while it runs (Linux; `None`
/// elsewhere). The peak is a high-water mark, so a late sample holds it.
fn peak_memory_kib(args: &[&str]) -> Option<u64> {
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status = format!("/proc/{}/status", child.id());
    let mut peak = None;
    loop {
        if let Ok(s) = std::fs::read_to_string(&status) {
            let hwm = s
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok());
            if hwm.is_some() {
                peak = peak.max(hwm);
            }
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    peak
}

/// On a real TU Delft log (`../shared`; skipped without it): a lean column
/// in degrees used to be reported as "no usable speed record"; each kick
/// now says its window is empty because the roll passes the fall angle at
/// once, and asks about degrees. The same log with every row written twice
/// (it halved the measured frequencies) is refused at its first repetition.
#[test]
fn a_real_log_in_degrees_or_doubled_states_the_cause() {
    let Some(dir) = shared("realdata/tudelft_sbw_kicks") else {
        return;
    };
    let Some(log) = std::fs::read_dir(dir.join("logs"))
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .find(|p| p.extension().is_some_and(|x| x == "log"))
    else {
        return;
    };
    let bike = dir.join("bicycle.toml");
    let text = std::fs::read_to_string(&log).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let rows: Vec<&str> = lines.filter(|l| !l.trim().is_empty()).collect();
    let d = tmp("real-logs");
    // lean_angle and lean_rate (columns 3 and 4) in degrees.
    let degrees: Vec<String> = rows
        .iter()
        .map(|r| {
            let mut f: Vec<String> = r.split(',').map(String::from).collect();
            for c in [2, 3] {
                f[c] = (f[c].parse::<f64>().unwrap().to_degrees()).to_string();
            }
            f.join(",")
        })
        .collect();
    let p = d.join("degrees.log");
    std::fs::write(&p, format!("{header}\n{}\n", degrees.join("\n"))).unwrap();
    let err = fails(&["fit", arg(&p), "--bike", arg(&bike)]);
    assert!(err.contains("fall angle") && err.contains("degrees"), "{err}");
    assert!(!err.contains("wheel sensor gave no speed"), "{err}");
    let doubled: Vec<&str> = rows.iter().flat_map(|r| [*r, *r]).collect();
    let p = d.join("doubled.log");
    std::fs::write(&p, format!("{header}\n{}\n", doubled.join("\n"))).unwrap();
    let err = fails(&["fit", arg(&p), "--bike", arg(&bike)]);
    assert!(err.contains("doubled.log:3") && err.contains("repeats line 2"), "{err}");
}

/// A steer controller whose speed window is empty (`Kc_v_min` = 6 m/s at
/// or above `Kc_v_max` = 2 m/s) never acts, and was analysed as absent
/// without a word: the file is refused, naming both fields; a window in
/// order passes.
#[test]
fn an_empty_speed_window_of_a_controller_is_refused_naming_both_fields() {
    let dir = tmp("controller-window");
    std::fs::create_dir_all(&dir).unwrap();
    let thesis = text(&bikedyn(&["params", "show", "--bike", "thesis"]).stdout);
    let file = |name: &str, lo: f64, hi: f64| {
        let p = dir.join(name);
        std::fs::write(
            &p,
            format!("{thesis}\nKc_roll_rate = 5\nKc_v_min = {lo}\nKc_v_max = {hi}\n"),
        )
        .unwrap();
        p
    };
    let bad = file("empty.toml", 6.0, 2.0);
    let err = fails(&["stability", "--bike", arg(&bad)]);
    assert!(
        err.contains("empty.toml") && err.contains("Kc_v_min") && err.contains("Kc_v_max"),
        "{err}"
    );
    let ok = file("window.toml", 2.0, 6.0);
    let out = bikedyn(&["stability", "--bike", arg(&ok)]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}
