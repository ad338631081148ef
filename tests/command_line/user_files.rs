//! Nothing of the user's is deleted or overwritten (issue 35, point 3): an
//! output folder is replaced only when bikedyn wrote it (its marker lists
//! every file in it), folders are written beside their place and renamed
//! in, runs at once never lose each other's output, killed runs' temporaries
//! are cleaned on the next run, and no output replaces an input.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

const MARKER: &str = ".bikedyn-output";

fn tmp(name: &str) -> PathBuf {
    let d = scratch("user-files").join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn arg(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `bikedyn synth --runs N --seed SEED --out DIR [extra]`.
fn synth(dir: &Path, runs: usize, seed: u64, extra: &[&str]) -> std::process::Output {
    let (runs, seed) = (runs.to_string(), seed.to_string());
    let mut args = vec!["synth", "--runs", &runs, "--seed", &seed, "--out", arg(dir)];
    args.extend(extra);
    bikedyn(&args)
}

/// Every file under `dir` (relative, `/`-separated), sorted.
fn files_under(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![(dir.to_path_buf(), String::new())];
    while let Some((d, prefix)) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let e = e.unwrap();
            let name = format!("{prefix}{}", e.file_name().to_string_lossy());
            if e.file_type().unwrap().is_dir() {
                stack.push((e.path(), format!("{name}/")));
            } else {
                out.push(name);
            }
        }
    }
    out.sort();
    out
}

/// A folder holds one whole output of bikedyn: its marker names `kind`
/// and lists exactly the other files in it.
fn assert_whole_output(dir: &Path, kind: &str) {
    let marker = std::fs::read_to_string(dir.join(MARKER)).unwrap();
    assert_eq!(marker.lines().next(), Some(kind), "{marker}");
    let mut listed: Vec<String> = marker
        .lines()
        .skip(1)
        .filter(|l| !l.starts_with('#'))
        .map(String::from)
        .collect();
    listed.sort();
    let present: Vec<String> = files_under(dir).into_iter().filter(|f| f != MARKER).collect();
    assert_eq!(listed, present);
}

/// No hidden temporary of bikedyn's beside `dir` (staged or moved-aside
/// folders, temporary files).
fn assert_no_temporaries_beside(dir: &Path) {
    let name = dir.file_name().unwrap().to_string_lossy().into_owned();
    let left: Vec<String> = entries(dir.parent().unwrap())
        .into_iter()
        .filter(|n| n.starts_with(&format!(".{name}.")))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// The id of a process that has ended (so its temporaries are stale).
fn ended_pid() -> u32 {
    let mut child = Command::new("true").spawn().unwrap();
    let pid = child.id();
    child.wait().unwrap();
    pid
}

/// A small table of weave eigenvalues for a fast `identify --eigenvalues`.
fn eigenvalue_table(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let t = dir.join("weave.csv");
    std::fs::write(&t, "v,re,im\n3,-0.5,5\n4,-1,5.5\n5,-1.5,6\n6,-2,6.5\n7,-2.5,7\n").unwrap();
    t
}

/// `synth --force --out DIR` used to delete whatever DIR held (a thesis's
/// `docs/`, measured runs). It replaces only a set synth wrote, recognised
/// by its marker, and only while the set holds no file it did not write;
/// a set of an earlier bikedyn (no marker) is refused with what to do.
/// Every refusal names the folder (or the file) and leaves it as it was.
#[test]
fn synth_refuses_to_replace_a_folder_it_did_not_write() {
    let h = tmp("not-a-set");
    std::fs::create_dir_all(h.join("docs")).unwrap();
    std::fs::write(h.join("docs/t.tex"), "x\n").unwrap();
    let out = synth(&h, 1, 1, &["--force"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(arg(&h)) && stderr.contains(MARKER) && stderr.contains("remove this one yourself"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(h.join("docs/t.tex")).unwrap(), "x\n");

    // A set of an earlier bikedyn, or a measured set: no marker.
    let older = tmp("older-set");
    assert!(synth(&older, 1, 1, &[]).status.success());
    std::fs::remove_file(older.join(MARKER)).unwrap();
    let before = files_under(&older);
    let out = synth(&older, 1, 2, &["--force"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("older than this one"), "{stderr}");
    assert_eq!(files_under(&older), before);

    // synth's own set with a user's file added: refused, naming the file.
    let own = tmp("own-set");
    assert!(synth(&own, 1, 1, &[]).status.success());
    std::fs::write(own.join("run01/notes.txt"), "kept\n").unwrap();
    let out = synth(&own, 1, 2, &["--force"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("notes.txt") && stderr.contains("move it out"),
        "{stderr}"
    );
    assert_eq!(std::fs::read_to_string(own.join("run01/notes.txt")).unwrap(), "kept\n");
    // Without it, the set is replaced whole.
    std::fs::remove_file(own.join("run01/notes.txt")).unwrap();
    let out = synth(&own, 2, 2, &["--force"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_whole_output(&own, "bikedyn synthetic set");
    assert_no_temporaries_beside(&own);
}

/// Two `synth --out S` at once both reported success while one set was
/// silently removed. Each writes beside S and renames its set in; the one
/// that finds S written meanwhile fails with a clear error and removes
/// nothing, so S holds one whole set.
#[test]
fn two_synth_runs_into_one_folder_never_lose_a_set() {
    let s = tmp("concurrent");
    let spawn = |seed: &str| {
        Command::new(env!("CARGO_BIN_EXE_bikedyn"))
            .args(["synth", "--runs", "3", "--seed", seed, "--out", arg(&s)])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("1"), spawn("5"));
    let outs = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
    let ok = outs.iter().filter(|o| o.status.success()).count();
    assert_eq!(ok, 1, "exactly one set is written");
    let failed = outs.iter().find(|o| !o.status.success()).unwrap();
    let stderr = text(&failed.stderr);
    assert!(
        stderr.contains(arg(&s)) && (stderr.contains("appeared or changed") || stderr.contains("is not empty")),
        "{stderr}"
    );
    assert_whole_output(&s, "bikedyn synthetic set");
    assert_eq!(
        entries(&s),
        vec![MARKER, "calibration", "run01", "run02", "run03", "truth"]
    );
    assert_no_temporaries_beside(&s);
}

/// `identify --report R` over an earlier report deleted a user's file
/// placed in R. A report folder is replaced only while it holds nothing
/// but the files a report wrote; otherwise the run is refused before any
/// work, naming the file. A folder holding another kind of output (a
/// synthetic set) is refused too.
#[test]
fn identify_report_refuses_to_delete_a_file_it_did_not_write() {
    let dir = tmp("report");
    let table = eigenvalue_table(&dir);
    let r = dir.join("R");
    let identify = |report: &Path| {
        bikedyn(&[
            "identify",
            "--eigenvalues",
            arg(&table),
            "--bike",
            "thesis",
            "--report",
            arg(report),
        ])
    };
    let out = identify(&r);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_whole_output(&r, "bikedyn identify report");
    std::fs::write(r.join("notes.txt"), "mine\n").unwrap();
    let out = identify(&r);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(&format!("{}/notes.txt", r.display())), "{stderr}");
    assert_eq!(std::fs::read_to_string(r.join("notes.txt")).unwrap(), "mine\n");
    std::fs::remove_file(r.join("notes.txt")).unwrap();
    assert!(identify(&r).status.success());
    assert_whole_output(&r, "bikedyn identify report");

    let set = dir.join("set");
    assert!(synth(&set, 1, 1, &[]).status.success());
    let out = identify(&set);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("holds a bikedyn synthetic set"), "{stderr}");
    assert_whole_output(&set, "bikedyn synthetic set");
}

/// `fit --plot DIR` wrote its plots into DIR beside whatever it held (a
/// killed run left a partial folder under the final name). The plots are
/// staged and renamed in, and only earlier plots of `fit` are replaced.
#[test]
fn fit_plots_are_written_whole_and_replace_only_earlier_plots() {
    let p = tmp("fit-plots");
    let fit = || bikedyn(&["fit", arg(&example_set()), "--plot", arg(&p)]);
    let out = fit();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_whole_output(&p, "bikedyn fit plots");
    assert!(p.join("continuation_measured.svg").is_file());
    assert!(fit().status.success());
    assert_whole_output(&p, "bikedyn fit plots");
    assert_no_temporaries_beside(&p);
    std::fs::write(p.join("paper.tex"), "x\n").unwrap();
    let out = fit();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("paper.tex") && !stderr.contains("progress:"),
        "{stderr}"
    );
}

/// A SIGKILL mid-write left hidden temporaries for ever, and a killed
/// staged output its partial folder. The next run writing into the same
/// folder removes bikedyn's own temporaries whose process has ended, and
/// nothing else: not a running process's, not files of other names. An
/// earlier output moved aside by a run killed before its new output was in
/// place is moved back.
#[test]
fn stale_temporaries_of_killed_runs_are_cleaned_on_the_next_run() {
    if !Path::new("/proc/self").exists() {
        eprintln!("skipped: needs /proc to tell ended processes");
        return;
    }
    let dir = tmp("stale");
    std::fs::create_dir_all(&dir).unwrap();
    let dead = ended_pid();
    let live = std::process::id();
    let stale_file = format!(".big.tmp-{dead}-0.csv");
    let stale_folder = format!(".set.partial-{dead}");
    let kept = [
        format!(".big.tmp-{live}-0.csv"),
        format!("big.tmp-{dead}-0.csv"),
        format!(".notes.tmp-{dead}.csv"),
        ".draft.tmp-x-1.csv".to_string(),
    ];
    std::fs::write(dir.join(&stale_file), "half").unwrap();
    std::fs::create_dir_all(dir.join(&stale_folder).join("run01")).unwrap();
    for k in &kept {
        std::fs::write(dir.join(k), "someone's").unwrap();
    }
    // A set moved aside by a killed `synth --force` (the new one not yet
    // in its place).
    let set = dir.join("set");
    assert!(synth(&set, 1, 1, &[]).status.success());
    let before = files_under(&set);
    std::fs::rename(&set, dir.join(format!(".set.old-{dead}"))).unwrap();

    let out = bikedyn(&[
        "eig",
        "--bike",
        "benchmark",
        "--format",
        "csv",
        "--output",
        arg(&dir.join("eig.csv")),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let mut expected: Vec<String> = kept.to_vec();
    expected.extend(["eig.csv".to_string(), "set".to_string()]);
    expected.sort();
    assert_eq!(entries(&dir), expected);
    assert_eq!(files_under(&set), before);
}

/// A SIGKILL of a staged output (`synth --force` over a set) at any moment
/// leaves the old set or the new one under the folder's name, whole; its
/// temporaries go with the next run.
#[test]
fn a_killed_synth_leaves_the_old_set_or_the_new_one() {
    let s = tmp("killed");
    assert!(synth(&s, 1, 1, &[]).status.success());
    for delay_ms in [50, 250, 600] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
            .args(["synth", "--runs", "8", "--seed", "7", "--force", "--out", arg(&s)])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = child.kill();
        child.wait().unwrap();
        if s.exists() {
            assert_whole_output(&s, "bikedyn synthetic set");
        } else {
            // Killed between its two renames: the old set waits beside
            // its place, and the next run puts it back.
            let aside = format!(".killed.old-{}", child.id());
            assert!(entries(s.parent().unwrap()).contains(&aside));
        }
    }
    // The next run beside it cleans what the killed ones left.
    let other = s.with_file_name("killed-next");
    let _ = std::fs::remove_dir_all(&other);
    assert!(synth(&other, 1, 1, &[]).status.success());
    assert_whole_output(&s, "bikedyn synthetic set");
    assert_no_temporaries_beside(&s);
}

/// `eig --bike b.toml --output b.toml` overwrote its input, and so did
/// `simulate --out`; `--output X --plot X` wrote one over the other. An
/// output that is an input (by any path: `./`, a link, a hard link) or
/// another output is refused before any work, naming both flags, and the
/// file is left as it was.
#[cfg(unix)]
#[test]
fn an_output_is_never_an_input_or_another_output() {
    let dir = tmp("output-is-input");
    std::fs::create_dir_all(&dir).unwrap();
    let b = dir.join("b.toml");
    let params = bikedyn(&["params", "convert", "--to", "thesis", "benchmark", "--output", arg(&b)]);
    assert!(params.status.success(), "{}", text(&params.stderr));
    let original = std::fs::read(&b).unwrap();
    let dotted = dir.join(".").join("b.toml");
    std::os::unix::fs::symlink(&b, dir.join("link.toml")).unwrap();
    std::fs::hard_link(&b, dir.join("hard.toml")).unwrap();
    let (link, hard) = (dir.join("link.toml"), dir.join("hard.toml"));
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (
            vec!["eig", "--bike", arg(&b), "--output", arg(&b)],
            "--output",
            "--bike",
        ),
        (
            vec!["eig", "--bike", arg(&b), "--output", arg(&dotted)],
            "--output",
            "--bike",
        ),
        (
            vec!["eig", "--bike", arg(&link), "--output", arg(&b)],
            "--output",
            "--bike",
        ),
        (
            vec!["eig", "--bike", arg(&hard), "--output", arg(&b)],
            "--output",
            "--bike",
        ),
        (vec!["eig", "--bike", arg(&b), "--plot", arg(&b)], "--plot", "--bike"),
        (
            vec![
                "simulate",
                "--bike",
                arg(&b),
                "--speed",
                "5",
                "--duration",
                "1",
                "--out",
                arg(&b),
            ],
            "--out",
            "--bike",
        ),
        (
            vec![
                "sweep",
                "--bike",
                arg(&b),
                "--param",
                "c",
                "--values",
                "0:0.1:0.1",
                "--output",
                arg(&b),
            ],
            "--output",
            "--bike",
        ),
        (
            vec!["params", "convert", "--to", "benchmark", arg(&b), "--output", arg(&b)],
            "--output",
            "FILE",
        ),
    ];
    for (args, out_flag, in_flag) in &cases {
        let out = bikedyn(args);
        let stderr = text(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(&format!("{out_flag} ")) && stderr.contains(&format!("given as {in_flag}")),
            "{args:?}: {stderr}"
        );
        assert_eq!(std::fs::read(&b).unwrap(), original, "{args:?}");
    }
    let x = dir.join("x.svg");
    let out = bikedyn(&["eig", "--bike", "benchmark", "--output", arg(&x), "--plot", arg(&x)]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--output") && stderr.contains("--plot") && stderr.contains("same file"),
        "{stderr}"
    );
    assert!(!x.exists());
    // An input inside an output folder (replaced whole when written).
    let table = eigenvalue_table(&dir.join("tables"));
    let report = dir.join("tables");
    let out = bikedyn(&[
        "identify",
        "--eigenvalues",
        arg(&table),
        "--bike",
        "thesis",
        "--report",
        arg(&report),
    ]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("--report") && stderr.contains("--eigenvalues"),
        "{stderr}"
    );
    assert!(table.is_file());
}
