//! Helpers every group of tests shares: running the `bikedyn` binary,
//! reading its output, scratch folders, the fixtures in `tests/data`, and the
//! development data in `../shared` (absent on a user's clone: tests that
//! need it print that they skipped).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub mod schema;

/// Runs the `bikedyn` binary of this build with `args`.
pub fn bikedyn(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_bikedyn")).args(args).output().unwrap()
}

/// Runs `bikedyn args` with standard output a pipe whose reading end is
/// closed at once (as `| head -0` does); returns the exit code and
/// standard error.
pub fn with_closed_stdout(args: &[&str]) -> (Option<i32>, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    (out.status.code(), text(&out.stderr))
}

/// The names in a folder, sorted.
pub fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Bytes of a command's output as text (lossy).
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// Standard output parsed as JSON; on failure the panic shows standard error.
pub fn stdout_json(out: &Output) -> serde_json::Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| panic!("{e}: {}", text(&out.stderr)))
}

/// Runs `bikedyn args`, asserts success and parses its JSON output.
pub fn ok_json(args: &[&str]) -> serde_json::Value {
    let out = bikedyn(args);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    stdout_json(&out)
}

/// A scratch folder for one group of tests, unique to this test process so
/// that concurrent runs never share files. The test harness has no hook at
/// exit, so the folders of earlier test processes that have ended are
/// removed the first time a process asks for one: only folders with the
/// marker file this function writes, and only of a process no longer
/// running (`/proc/PID`; elsewhere nothing is removed).
pub fn scratch(group: &str) -> PathBuf {
    static SWEPT: std::sync::Once = std::sync::Once::new();
    SWEPT.call_once(remove_scratch_of_ended_runs);
    let d = std::env::temp_dir().join(format!("bikedyn-{group}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let _ = std::fs::write(d.join(SCRATCH_MARKER), "");
    d
}

/// The file that marks a folder as a test scratch folder of `scratch`.
const SCRATCH_MARKER: &str = ".bikedyn-test-scratch";

fn remove_scratch_of_ended_runs() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(dir) = std::fs::read_dir(std::env::temp_dir()) else {
        return;
    };
    for e in dir.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name
            .strip_prefix("bikedyn-")
            .and_then(|rest| rest.rsplit_once('-'))
            .and_then(|(_, pid)| pid.parse::<u32>().ok())
        else {
            continue;
        };
        let path = e.path();
        if pid != std::process::id()
            && !Path::new(&format!("/proc/{pid}")).exists()
            && path.join(SCRATCH_MARKER).is_file()
        {
            let _ = std::fs::remove_dir_all(&path);
        }
    }
}

/// A fixture of `tests/data`.
pub fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)
}

/// `fixture` as a string, for command lines.
pub fn fixture_arg(name: &str) -> String {
    fixture(name).to_string_lossy().into_owned()
}

/// `../shared/<sub>` from the repository root, or `None` with a skip
/// message when the development data is not checked out.
pub fn shared(sub: &str) -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared").join(sub);
    if p.exists() {
        Some(p)
    } else {
        eprintln!(
            "skipped: {} not found (development data, absent on a user's clone)",
            p.display()
        );
        None
    }
}

/// The example measured set shipped with bikedyn (six synthetic runs of the
/// thesis bicycle with steer damping hidden, and their truth files).
pub fn example_set() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/hidden_steer_damping")
}

/// A fresh folder `name` under the scratch group `group` holding the
/// example set's runs `runs` (e.g. `calibration`, `run01`), copied.
pub fn example_runs(group: &str, name: &str, runs: &[&str]) -> PathBuf {
    let d = scratch(group).join(name);
    let _ = std::fs::remove_dir_all(&d);
    for r in runs {
        std::fs::create_dir_all(d.join(r)).unwrap();
        for f in std::fs::read_dir(example_set().join(r)).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, d.join(r).join(f.file_name().unwrap())).unwrap();
        }
    }
    d
}

/// Rewrite an IMU record's orientations (`time_s,q0,q1,q2,q3`, scalar
/// first, `v_global = R(q) v_sensor`): `f(t, q, t_end)` gives each
/// sample's new orientation.
pub fn rotate_orientations(
    path: &Path,
    f: impl Fn(f64, nalgebra::UnitQuaternion<f64>, f64) -> nalgebra::UnitQuaternion<f64>,
) {
    let s = std::fs::read_to_string(path).unwrap();
    let rows: Vec<&str> = s.lines().collect();
    let t_end: f64 = rows.last().unwrap().split(',').next().unwrap().trim().parse().unwrap();
    let mut out = String::from(rows[0]) + "\n";
    for line in &rows[1..] {
        let v: Vec<f64> = line.split(',').map(|x| x.trim().parse().unwrap()).collect();
        let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(v[1], v[2], v[3], v[4]));
        let r = f(v[0], q, t_end);
        out += &format!("{:.4},{:.7},{:.7},{:.7},{:.7}\n", v[0], r.w, r.i, r.j, r.k);
    }
    std::fs::write(path, out).unwrap();
}

/// A kick's state (roll 0.02 rad, steer -0.01 rad, rates 0.3 and 0.2 rad/s,
/// 5 m/s) and tight tolerances, for checks of simulated responses.
pub fn kick_and_tight_options() -> (
    bikedyn::runtime::simulate::InitialConditions,
    bikedyn::runtime::simulate::SimOptions,
) {
    use bikedyn::runtime::simulate::{Events, InitialConditions, SimOptions};
    let ic = InitialConditions {
        roll: 0.02,
        steer: -0.01,
        roll_rate: 0.3,
        steer_rate: 0.2,
        speed: 5.0,
        yaw: 0.0,
        ..InitialConditions::default()
    };
    let opts = SimOptions {
        rtol: 1e-12,
        atol: 1e-14,
        output_interval: 0.01,
        events: Events {
            roll_limit: Some(1.2),
            steer_limit: Some(1.45),
        },
        ..SimOptions::default()
    };
    (ic, opts)
}
