//! The leaning-rider model (`rider_lean`, Moore 2012's rider lean): the
//! rider's upper body hinged to the rear frame about a longitudinal axis
//! through the saddle, with a spring and damper.
//!
//! The independent check is the rigid-rider limit. The benchmark bicycle's
//! rear body B (Meijaard et al. 2007, Table 1) is split here, by the
//! parallel-axis theorem, into a lower part (frame, legs and pelvis) and an
//! upper body, so that the two together have B's mass, mass centre and
//! inertia. With the lean spring stiff, the leaning-rider bicycle must then
//! have the benchmark's eigenvalues, and approach them as the stiffness
//! grows; with a soft spring it must not.

use crate::common::*;
use bikedyn::bicycle::Bicycle;
use bikedyn::runtime::eigen::{critical_speeds_of, eigen_sweep_of, EigenSweep};
use bikedyn::simulate::{choose_model, run};
use bikedyn_runtime::simulate::{InitialConditions, Inputs, SimOptions};
use nalgebra::Complex;

/// Benchmark-form values of the benchmark bicycle with B replaced by the
/// lower part, plus the rider keys (upright axes: x forward, z up, from
/// the rear wheel centre; the upper body's inertia about its own mass
/// centre), with lean stiffness `k` (N m/rad) and damping `c` (N m s/rad).
fn split_benchmark(k: f64, c: f64) -> Vec<(String, f64, Option<f64>)> {
    let b = Bicycle::resolve("benchmark").unwrap();
    let get = |s: &str| b.value(s).unwrap();
    let r_rear = get("rR");
    // B in benchmark axes (x forward, y right, z down; origin at the rear
    // contact), inertia about its mass centre.
    let (m_b, x_b, z_b) = (get("mB"), get("xB"), get("zB"));
    let (ixx, iyy, izz, ixz) = (get("IBxx"), get("IByy"), get("IBzz"), get("IBxz"));
    // The upper body: 40 kg, its mass centre 1.1 m above the ground and
    // 2 cm ahead of B's; its own inertia in the same axes.
    let (m_u, x_u, z_u) = (40.0, x_b + 0.02, -1.1);
    let (uxx, uyy, uzz, uxz) = (2.5, 2.8, 1.0, 1.0);
    // The lower part: what is left of B.
    let m_l = m_b - m_u;
    let (x_l, z_l) = ((m_b * x_b - m_u * x_u) / m_l, (m_b * z_b - m_u * z_u) / m_l);
    // Parallel-axis terms of a point mass `m` at `(dx, dz)` from B's mass
    // centre: xx, yy, zz and the xz product (tensor entry, -m dx dz).
    let shift = |m: f64, dx: f64, dz: f64| (m * dz * dz, m * (dx * dx + dz * dz), m * dx * dx, -m * dx * dz);
    let (su, sl) = (shift(m_u, x_u - x_b, z_u - z_b), shift(m_l, x_l - x_b, z_l - z_b));
    let lower = (
        ixx - uxx - su.0 - sl.0,
        iyy - uyy - su.1 - sl.1,
        izz - uzz - su.2 - sl.2,
        ixz - uxz - su.3 - sl.3,
    );
    assert!(
        lower.0 > 0.0 && lower.2 > 0.0 && lower.0 * lower.2 > lower.3 * lower.3,
        "lower part {lower:?}"
    );
    // The lean axis 0.9 m above the ground, above B's mass centre.
    let (x_s, h_s) = (x_b, 0.9);
    let mut values: Vec<(String, f64, Option<f64>)> = [
        "w", "c", "lam", "g", "rR", "mR", "IRxx", "IRyy", "xH", "zH", "mH", "IHxx", "IHyy", "IHzz", "IHxz", "rF", "mF",
        "IFxx", "IFyy",
    ]
    .iter()
    .map(|s| (s.to_string(), get(s), None))
    .collect();
    for (s, v) in [
        ("mB", m_l),
        ("xB", x_l),
        ("zB", z_l),
        ("IBxx", lower.0),
        ("IByy", lower.1),
        ("IBzz", lower.2),
        ("IBxz", lower.3),
        // Rider keys: upright axes with z up, so heights change sign and
        // so does the xz product (y and z both turn over).
        ("xL", x_s),
        ("zL", h_s - r_rear),
        ("x6", x_u - x_s),
        ("z6", -z_u - h_s),
        ("m6", m_u),
        ("I6x", uxx),
        ("I6y", uyy),
        ("I6z", uzz),
        ("I6xz", -uxz),
        ("k_lean", k),
        ("c_lean", c),
    ] {
        values.push((s.to_string(), v, None));
    }
    values
}

fn sweep(bike: &Bicycle, speeds: &[f64]) -> EigenSweep {
    let linear = bike.linear_with(None).unwrap();
    eigen_sweep_of(&linear, speeds).unwrap()
}

/// Largest distance between the four roll-steer eigenvalues of two sweeps
/// at the same speeds (each sorted by real, then imaginary part).
fn largest_difference(a: &EigenSweep, b: &EigenSweep) -> f64 {
    let sorted = |e: &[Complex<f64>; 4]| {
        let mut v = e.to_vec();
        v.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
        v
    };
    a.points
        .iter()
        .zip(&b.points)
        .flat_map(|(p, q)| {
            sorted(&p.eigenvalues)
                .into_iter()
                .zip(sorted(&q.eigenvalues))
                .map(|(x, y)| (x - y).norm())
                .collect::<Vec<_>>()
        })
        .fold(0.0, f64::max)
}

const SPEEDS: [f64; 6] = [0.5, 2.0, 4.0, 5.0, 6.0, 8.0];

#[test]
fn a_rider_stiffly_held_upright_gives_the_rigid_rider_benchmark_eigenvalues() {
    let benchmark = sweep(&Bicycle::resolve("benchmark").unwrap(), &SPEEDS);
    let stiff = Bicycle::from_values("split benchmark", &split_benchmark(1e9, 0.0)).unwrap();
    assert_eq!(stiff.model(None).unwrap().name, "rider_lean");
    let s = sweep(&stiff, &SPEEDS);
    // The lean is a mode of its own beside the four roll-steer modes.
    assert!(s.points.iter().all(|p| p.extra_eigenvalues.len() == 2));
    let error = largest_difference(&s, &benchmark);
    // The stiffer the spring, the closer: the error is the spring's
    // compliance, falling as 1/k (rounding sets in below about 1e-7).
    let softer = Bicycle::from_values("split benchmark", &split_benchmark(1e7, 0.0)).unwrap();
    let error_softer = largest_difference(&sweep(&softer, &SPEEDS), &benchmark);
    println!(
        "largest eigenvalue difference from the benchmark: k = 1e7: {error_softer:.2e}, k = 1e9: {error:.2e} (1/s)"
    );
    assert!(error < 3e-6, "k = 1e9: {error:e}");
    assert!(
        error_softer > 50.0 * error,
        "k = 1e7: {error_softer:e} against {error:e}"
    );
    // The weave and capsize speeds of the benchmark (Meijaard et al. 2007:
    // 4.292 and 6.024 m/s).
    let c = critical_speeds_of(&stiff.linear_with(None).unwrap(), 0.0, 10.0).unwrap();
    assert!((c.weave_speed.unwrap() - 4.2924).abs() < 1e-3, "{:?}", c.weave_speed);
    assert!(
        (c.capsize_speed.unwrap() - 6.0243).abs() < 1e-3,
        "{:?}",
        c.capsize_speed
    );
}

#[test]
fn a_rider_leaning_on_a_soft_spring_changes_the_bicycle_modes() {
    let benchmark = sweep(&Bicycle::resolve("benchmark").unwrap(), &SPEEDS);
    let soft = Bicycle::from_values("split benchmark", &split_benchmark(2000.0, 100.0)).unwrap();
    let s = sweep(&soft, &SPEEDS);
    // Not the rigid rider: the upper body's own motion moves the modes.
    assert!(largest_difference(&s, &benchmark) > 1e-2);
    // A damped rider: the lean mode decays at every speed.
    for p in &s.points {
        assert!(
            p.extra_eigenvalues.iter().all(|e| e.re < 0.0),
            "{} m/s: {:?}",
            p.v,
            p.extra_eigenvalues
        );
    }
}

#[test]
fn a_stiffly_held_rider_rides_like_the_rigid_rider_bicycle_in_the_nonlinear_equations() {
    // Free forward speed, a lean of 3 deg and a roll rate: large enough
    // for the nonlinear terms, and the rider's own mode (a 1e6 N m/rad
    // spring: about 630 rad/s) far faster than the bicycle's.
    let stiff = Bicycle::from_values("split benchmark", &split_benchmark(1e6, 0.0)).unwrap();
    let rigid = Bicycle::resolve("benchmark").unwrap();
    let ic = InitialConditions {
        roll: 3f64.to_radians(),
        roll_rate: 0.3,
        speed: 4.6,
        ..Default::default()
    };
    let opts = SimOptions {
        rtol: 1e-10,
        atol: 1e-12,
        output_interval: 0.05,
        ..Default::default()
    };
    let simulate = |b: &Bicycle| {
        let model = choose_model(b, None, true).unwrap();
        run(b, model, &ic, &Inputs::default(), 3.0, &opts).unwrap()
    };
    let (a, b) = (simulate(&stiff), simulate(&rigid));
    assert_eq!(a.model, "rider_lean_free");
    let (roll_a, roll_b) = (a.coordinate("theta").unwrap(), b.coordinate("theta").unwrap());
    let (steer_a, steer_b) = (a.coordinate("gamma").unwrap(), b.coordinate("gamma").unwrap());
    let lean = a.coordinate("lean").unwrap();
    let mut deviation = 0.0f64;
    for i in 0..roll_a.len().min(roll_b.len()) {
        deviation = deviation
            .max((roll_a[i] - roll_b[i]).abs())
            .max((steer_a[i] - steer_b[i]).abs());
    }
    let largest_lean = lean.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    println!("roll and steer deviation {deviation:.2e} rad, largest lean {largest_lean:.2e} rad");
    assert_eq!(roll_a.len(), roll_b.len());
    assert!(deviation < 1e-4, "{deviation:e}");
    assert!(largest_lean < 1e-4, "{largest_lean:e}");
}

#[test]
fn a_leaning_rider_file_without_its_lean_stiffness_is_refused_naming_it() {
    let mut values = split_benchmark(2000.0, 100.0);
    values.retain(|(k, _, _)| k != "k_lean");
    let e = Bicycle::from_values("no stiffness", &values)
        .and_then(|b| b.linear_with(None).map(|_| ()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("k_lean") && e.contains("N m/rad"), "{e}");
}

#[test]
fn a_leaning_rider_of_negative_mass_is_refused_naming_the_field() {
    let mut values = split_benchmark(2000.0, 100.0);
    for (k, v, _) in values.iter_mut() {
        if k == "m6" {
            *v = -40.0;
        }
    }
    let e = Bicycle::from_values("negative rider", &values)
        .err()
        .expect("refused")
        .to_string();
    assert!(e.contains("m6"), "{e}");
}

#[test]
fn the_command_line_runs_a_leaning_rider_file_through_its_model() {
    let dir = scratch("leaning-rider");
    let file = dir.join("rider.toml");
    let mut toml = String::from("form = \"benchmark\"\n");
    for (k, v, _) in split_benchmark(2000.0, 100.0) {
        toml.push_str(&format!("{k} = {v:?}\n"));
    }
    std::fs::write(&file, toml).unwrap();
    let f = file.to_str().unwrap();
    let eig = ok_json(&["eig", "--bike", f, "--speeds", "4:6:1", "--json"]);
    let points = eig.as_array().expect("one entry per speed");
    assert_eq!(points.len(), 3);
    assert!(
        points
            .iter()
            .all(|p| p["extra_eigenvalues"].as_array().map(Vec::len) == Some(2)),
        "{eig}"
    );
    let stability = ok_json(&["stability", "--bike", f, "--json"]);
    assert_eq!(stability["model"], "rider_lean", "{stability}");
    let vw = stability["weave_speed"].as_f64().unwrap();
    assert!((4.0..4.6).contains(&vw), "{stability}");
    // No canonical form: the reason is given, with the state space instead.
    let out = bikedyn(&["canonical", "--bike", f]);
    let said = text_of(&out);
    assert!(said.contains("lean"), "{said}");
    let sim = bikedyn(&[
        "simulate",
        "--bike",
        f,
        "--speed",
        "5",
        "--duration",
        "1",
        "--roll",
        "2",
        "--free-speed",
    ]);
    assert!(sim.status.success(), "{}", text(&sim.stderr));
    // Runs of the rider's bicycle with a hidden steer damper: identify
    // runs through the leaning-rider model and finds the damper among the
    // library's effects. (With the corrections of measured parameters too,
    // the rider's 2 cm mass-centre priors let corrections take a share of
    // it on these 12 runs: a limit of identification's, not the model's.)
    let set = dir.join("set");
    let synth = bikedyn(&[
        "synth",
        "--bike",
        f,
        "--effects",
        "c_steer=0.3",
        "--runs",
        "12",
        "--seed",
        "11",
        "--out",
        set.to_str().unwrap(),
    ]);
    assert!(synth.status.success(), "{}", text(&synth.stderr));
    let id = ok_json(&[
        "identify",
        set.to_str().unwrap(),
        "--bike",
        f,
        "--folds",
        "4",
        "--corrections",
        "0",
        "--json",
    ]);
    assert_eq!(id["model"], "rider_lean_free", "{}", id["model"]);
    assert_eq!(id["driven_model"], "rider_lean", "{}", id["driven_model"]);
    assert_eq!(
        id["selected_effects"],
        serde_json::json!(["steer_damping"]),
        "{}",
        id["selected_effects"]
    );
    let c = id["parameters"]["c_steer"]["value"].as_f64().unwrap();
    assert!((c - 0.3).abs() < 0.3 * 0.15, "c_steer {c}");
}

fn text_of(out: &std::process::Output) -> String {
    format!("{}{}", text(&out.stdout), text(&out.stderr))
}
