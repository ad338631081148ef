//! Two derivations started at once on one machine: Symbolica's licence
//! allows one thread per user, and a second process that starts it aborts.
//! The modeler's guard makes the second wait, with a message, and both
//! finish (issue 35, point 5).
#![cfg(feature = "derive")]

use bikedyn_modeler::codegen::{generate, symbolica_guard};
use bikedyn_modeler::expr::{inertia_wheel, num, vec3};
use bikedyn_modeler::model::{Axis, Model, Role, GROUND};
use std::path::PathBuf;
use std::process::Command;

/// The environment variable that makes `one_derivation` run, naming its
/// output folder.
const OUT: &str = "BIKEDYN_LOCK_TEST_OUT";

/// A pendulum: the smallest model the modeler derives.
fn pendulum() -> Model {
    let mut m = Model::builder("lock_test_pendulum")
        .doc("a point mass on a massless rod (test of the Symbolica guard)")
        .source("modeler/tests/symbolica_lock.rs");
    let th = m.coordinate(
        "theta",
        Role::Independent,
        0.0,
        "rod angle from the downward vertical (rad)",
    );
    let l = m.parameter("l", "rod length (m)");
    let mass = m.parameter("m", "mass (kg)");
    m.parameter("g", "gravitational acceleration (m/s^2)");
    m.gravity("g", Axis::Z);
    let rod = m.frame("rod", GROUND, vec![(Axis::Y, th)]);
    let bob = m.point("bob", None, vec![(rod, vec3(num(0), num(0), -l))]);
    m.body("bob", rod, mass, inertia_wheel(num(0), num(0)), bob);
    m.build().expect("a valid model")
}

/// One derivation as a process of its own, started twice at once by
/// `two_derivations_started_at_once_both_finish`. It holds the guard for a
/// second before deriving, so that the two overlap however fast the
/// derivation is.
#[test]
#[ignore = "a child process of two_derivations_started_at_once_both_finish"]
fn one_derivation() {
    let out = PathBuf::from(std::env::var_os(OUT).expect("started by the parent test"));
    let _held = symbolica_guard();
    std::thread::sleep(std::time::Duration::from_secs(1));
    generate(&[pendulum()], &out).expect("derivation");
}

#[test]
fn two_derivations_started_at_once_both_finish() {
    let exe = std::env::current_exe().expect("the test binary");
    let base = std::env::temp_dir().join(format!("bikedyn-lock-test-{}", std::process::id()));
    let children: Vec<_> = (0..2)
        .map(|i| {
            let out = base.join(i.to_string());
            std::fs::create_dir_all(&out).expect("scratch folder");
            Command::new(&exe)
                .args([
                    "one_derivation",
                    "--exact",
                    "--ignored",
                    "--nocapture",
                    "--test-threads=1",
                ])
                .env(OUT, &out)
                .output_async()
        })
        .collect();
    let outputs: Vec<_> = children
        .into_iter()
        .map(|c| c.wait_with_output().expect("child"))
        .collect();
    let mut waited = 0;
    for (i, o) in outputs.iter().enumerate() {
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "derivation {i} failed: {err}");
        assert!(base.join(i.to_string()).join("lock_test_pendulum.rs").is_file());
        waited += usize::from(err.contains("waiting for Symbolica"));
    }
    assert_eq!(waited, 1, "exactly one derivation waits for the other");
    let _ = std::fs::remove_dir_all(&base);
}

/// Start a command with its output captured, without waiting for it.
trait OutputAsync {
    fn output_async(&mut self) -> std::process::Child;
}

impl OutputAsync for Command {
    fn output_async(&mut self) -> std::process::Child {
        self.stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start the test binary")
    }
}
