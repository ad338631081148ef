//! Nonlinear simulation: constraint residuals, energy, small-amplitude
//! agreement with the linearized equations, events, kicks and pulses.

use crate::common::*;
use bikedyn::ThesisWhipple;
use bikedyn_runtime::linearize::linearize;
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::parameters::ThesisParameters;
use bikedyn_runtime::simulate::{
    simulate, Events, InitialConditions, Inputs, Kick, Method, PulseShape, PulseTarget, SimOptions, StopReason,
    TorquePulse,
};
use bikedyn_runtime::MultibodyModel;
use nalgebra::{Matrix2, Matrix4, Vector4};

type M = ThesisWhipple;

mod tyres;
mod weave_fits;

/// The thesis bicycle's parameters for model `M` (every model here has the
/// thesis geometry or the offset one, which is the thesis's at `d4 = 0`),
/// effects absent, speed parameter 4.5 m/s.
fn default_parameters<M: MultibodyModel>() -> Vec<f64> {
    let p = ThesisParameters::thesis_bicycle();
    parameter_vector::<M>(|s| p.get(s), 4.5).expect("the thesis bicycle gives every parameter")
}

fn thesis_at(speed: f64) -> Vec<f64> {
    let mut p = default_parameters::<M>();
    p[M::FORWARD_SPEED_PARAMETER.unwrap()] = speed;
    p
}

/// Linear solution `x(t) = exp(A t) x0` of `M q'' + C q' + K q = 0`.
fn linear_response(speed: f64, x0: Vector4<f64>, t: f64) -> Vector4<f64> {
    let lin = linearize::<M>(&thesis_at(speed)).unwrap();
    let m = Matrix2::from_fn(|i, j| lin.mass[(i, j)]);
    let c = Matrix2::from_fn(|i, j| lin.damping[(i, j)]);
    let k = Matrix2::from_fn(|i, j| lin.stiffness[(i, j)]);
    let mi = m.try_inverse().unwrap();
    let (mk, mc) = (-mi * k, -mi * c);
    let a = Matrix4::new(
        0.0,
        0.0,
        1.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        mk[(0, 0)],
        mk[(0, 1)],
        mc[(0, 0)],
        mc[(0, 1)],
        mk[(1, 0)],
        mk[(1, 1)],
        mc[(1, 0)],
        mc[(1, 1)],
    );
    (a * t).exp() * x0
}

fn max_deviation_from_linear(speed: f64, roll_rate: f64) -> (f64, f64) {
    let ic = InitialConditions {
        roll_rate,
        speed,
        ..Default::default()
    };
    let opts = SimOptions {
        rtol: 1e-11,
        atol: 1e-13,
        output_interval: 0.05,
        ..Default::default()
    };
    let sim = simulate::<M>(&thesis_at(speed), &ic, &Inputs::default(), 3.0, &opts).unwrap();
    let roll = sim.coordinate("theta").unwrap();
    let steer = sim.coordinate("gamma").unwrap();
    let (mut dev, mut amp) = (0.0f64, 0.0f64);
    for (i, &t) in sim.t.iter().enumerate() {
        let x = linear_response(speed, Vector4::new(0.0, 0.0, roll_rate, 0.0), t);
        dev = dev.max((x[0] - roll[i]).abs()).max((x[1] - steer[i]).abs());
        amp = amp.max(x[0].abs()).max(x[1].abs());
    }
    (dev, amp)
}

/// Small amplitude: the nonlinear response matches the linear solution at the
/// same speed, and the deviation is second order in the amplitude.
#[test]
fn small_amplitude_matches_linear_solution() {
    for speed in [3.0, 4.5, 7.0] {
        let (d1, a1) = max_deviation_from_linear(speed, 0.01);
        let (d2, _) = max_deviation_from_linear(speed, 0.02);
        println!(
            "V = {speed}: amplitude {a1:.3e} rad, max deviation {d1:.3e} rad; doubled: {d2:.3e} (ratio {:.2})",
            d2 / d1
        );
        assert!(d1 < 1e-2 * a1, "deviation {d1} vs amplitude {a1}");
        // Quadratic (or cubic, by symmetry) growth: ratio 4 to 8, not 2.
        assert!(d2 / d1 > 3.5 && d2 / d1 < 8.5, "ratio {}", d2 / d1);
    }
}

/// The holonomic residual stays below 1e-9 throughout a large-amplitude run,
/// and the velocity constraints hold to rounding.
#[test]
fn constraint_residual_stays_at_solver_tolerance() {
    let ic = InitialConditions {
        roll: 0.2,
        steer: -0.3,
        roll_rate: 0.5,
        speed: 5.0,
        ..Default::default()
    };
    let sim = simulate::<M>(&thesis_at(5.0), &ic, &Inputs::default(), 5.0, &SimOptions::default()).unwrap();
    assert_eq!(sim.stop, StopReason::Completed);
    println!(
        "max holonomic residual {:.3e}, max velocity residual {:.3e}, {} rhs evaluations",
        sim.max_constraint_residual(),
        sim.max_velocity_residual(),
        sim.stats.rhs_evaluations
    );
    assert!(sim.max_constraint_residual() < 1e-9);
    assert!(sim.max_velocity_residual() < 1e-9);
    // The driving constraint holds the speed exactly.
    for s in &sim.speed {
        assert!((s - 5.0).abs() < 1e-9, "speed {s}");
    }
}

/// Below the weave speed the bicycle falls: the run stops at the roll limit,
/// located to within the integration tolerance.
#[test]
fn slow_bicycle_falls_and_the_event_is_located() {
    let ic = InitialConditions {
        roll: 0.05,
        speed: 1.0,
        ..Default::default()
    };
    let opts = SimOptions {
        events: Events {
            roll_limit: Some(0.8),
            steer_limit: None,
        },
        ..Default::default()
    };
    let sim = simulate::<M>(&thesis_at(1.0), &ic, &Inputs::default(), 20.0, &opts).unwrap();
    match sim.stop {
        StopReason::Fell { time, roll } => {
            assert!((roll.abs() - 0.8).abs() < 1e-8, "roll at event {roll}");
            assert!(time < 20.0);
            assert_eq!(*sim.t.last().unwrap(), time);
        }
        s => panic!("expected a fall, got {s:?}"),
    }
}

/// A steer stop ends the run when the handlebar swings to its limit.
#[test]
fn steer_stop_event() {
    let ic = InitialConditions {
        steer_rate: 3.0,
        speed: 1.0,
        ..Default::default()
    };
    let opts = SimOptions {
        events: Events {
            roll_limit: None,
            steer_limit: Some(0.3),
        },
        ..Default::default()
    };
    let sim = simulate::<M>(&thesis_at(1.0), &ic, &Inputs::default(), 10.0, &opts).unwrap();
    assert!(matches!(sim.stop, StopReason::SteerStop { steer, .. } if (steer.abs() - 0.3).abs() < 1e-8));
}

/// A kick to the right at the saddle makes the roll rate jump positive, with
/// the position unchanged and the constraints still satisfied; its velocity
/// jump is linear in the impulse.
#[test]
fn kick_at_the_saddle_rolls_the_bicycle_right() {
    let run = |j: f64| {
        let inputs = Inputs {
            kicks: vec![Kick::at_saddle(0.5, j)],
            pulses: vec![],
            feedback: None,
        };
        simulate::<M>(
            &thesis_at(4.5),
            &InitialConditions::default(),
            &inputs,
            1.0,
            &SimOptions::default(),
        )
        .unwrap()
    };
    let jump = |sim: &bikedyn_runtime::simulate::Simulation| {
        let i = (1..sim.t.len())
            .find(|&i| sim.t[i] == sim.t[i - 1])
            .expect("kick sample pair");
        let j = M::coordinate_index("theta").unwrap();
        assert_eq!(sim.p[i][j], sim.p[i - 1][j]);
        (sim.dp[i][j] - sim.dp[i - 1][j], sim.constraint_residual[i])
    };
    let (d1, r1) = jump(&run(2.0));
    let (d2, _) = jump(&run(4.0));
    println!("roll-rate jump {d1} rad/s for 2 N s");
    assert!(d1 > 0.1, "roll-rate jump {d1}");
    assert!((d2 / d1 - 2.0).abs() < 1e-9);
    assert!(r1 < 1e-9);
}

/// A steer-torque pulse produces a response; a roll-torque pulse to the right
/// rolls the bicycle right.
#[test]
fn torque_pulses_act_with_the_right_sign() {
    let pulse = |target, shape| Inputs {
        kicks: vec![],
        pulses: vec![TorquePulse {
            target,
            shape,
            start: 0.2,
            duration: 0.1,
            amplitude: 5.0,
        }],
        feedback: None,
    };
    let run = |inputs: &Inputs| {
        simulate::<M>(
            &thesis_at(4.5),
            &InitialConditions::default(),
            inputs,
            0.4,
            &SimOptions::default(),
        )
        .unwrap()
    };
    let s = run(&pulse(PulseTarget::Roll, PulseShape::HalfSine));
    let roll = s.coordinate("theta").unwrap();
    assert!(*roll.last().unwrap() > 1e-3);
    let s = run(&pulse(PulseTarget::Steer, PulseShape::Rectangular));
    let steer = s.coordinate("gamma").unwrap();
    // Positive steer torque turns the handlebar left (positive gamma) at first.
    let i = s.t.iter().position(|&t| t >= 0.3).unwrap();
    assert!(steer[i] > 1e-3, "steer {}", steer[i]);
}

/// Bad inputs are errors, never panics.
#[test]
fn bad_inputs_are_errors() {
    let p = thesis_at(4.5);
    let ic = InitialConditions::default();
    let o = SimOptions::default();
    assert!(simulate::<M>(&p, &ic, &Inputs::default(), -1.0, &o).is_err());
    assert!(simulate::<M>(&p, &ic, &Inputs::default(), f64::NAN, &o).is_err());
    assert!(simulate::<M>(&p[..3], &ic, &Inputs::default(), 1.0, &o).is_err());
    let bad = InitialConditions {
        roll: f64::INFINITY,
        ..ic
    };
    assert!(simulate::<M>(&p, &bad, &Inputs::default(), 1.0, &o).is_err());
    let o2 = SimOptions { rtol: 0.0, ..o };
    assert!(simulate::<M>(&p, &ic, &Inputs::default(), 1.0, &o2).is_err());
    // Roll beyond 90 degrees: no ground contact.
    let fallen = InitialConditions { roll: 2.0, ..ic };
    let e = simulate::<M>(&p, &fallen, &Inputs::default(), 1.0, &o);
    assert!(e.is_err(), "{e:?}");
}

/// `bikedyn simulate` writes the documented CSV columns and a plot.
#[test]
fn cli_simulate_writes_csv_and_plot() {
    let dir = scratch("simulate");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("run.csv");
    let svg = dir.join("run.svg");
    let out = bikedyn(&[
        "simulate",
        "--speed",
        "4.5",
        "--roll-rate",
        "10",
        "--kick",
        "0.5:2",
        "--pulse",
        "steer:1:0.2:0.5:halfsine",
        "--duration",
        "2",
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("stop: completed"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let mut expected = vec!["t"];
    expected.extend(M::COORDINATES);
    let rates: Vec<String> = M::COORDINATES.iter().map(|c| format!("d{c}")).collect();
    expected.extend(rates.iter().map(|s| s.as_str()));
    expected.extend(["speed", "kinetic_energy", "potential_energy", "constraint_residual"]);
    assert_eq!(header, expected);
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert!(rows.len() > 200);
    assert!(rows
        .iter()
        .all(|r| r.len() == header.len() && r[header.len() - 1] < 1e-9));
    assert_eq!(rows.last().unwrap()[0], 2.0);
    let svg_text = std::fs::read_to_string(&svg).unwrap();
    assert!(svg_text.contains("<svg") && svg_text.contains("roll"));

    // A fall is reported; bad arguments are clear errors.
    let out = bikedyn(&["simulate", "--speed", "1", "--roll", "5", "--duration", "20"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("fell: roll reached 57.30 deg"));
    for bad in [
        vec!["simulate", "--speed", "4", "--duration", "1", "--kick", "x:1"],
        vec!["simulate", "--speed", "4", "--duration", "1", "--pulse", "yaw:0:1:1"],
        vec!["simulate", "--speed", "4", "--duration", "-1"],
        vec!["simulate", "--speed", "4", "--duration", "1", "--model", "nope"],
        vec!["simulate", "--speed", "4", "--duration", "1", "--plot", "x.gif"],
    ] {
        let out = bikedyn(&bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("error:"));
    }
}

/// The physical side of a synthetic run: launch, release, kick, free response;
/// continuous angles, monotonic rear wheel, seeded (same seed, same run).
#[test]
fn synthetic_run_trajectory() {
    use bikedyn_runtime::simulate::trajectory::{trajectory_for_run, RunPlan};
    let plan = RunPlan::random(7);
    assert!(plan.speed >= 3.0 && plan.speed <= 7.0 && plan.launch_duration >= 2.0);
    let (tr, sim) = trajectory_for_run::<M>(&thesis_at(plan.speed), &plan, None, &SimOptions::default()).unwrap();
    let (tr2, _) = trajectory_for_run::<M>(&thesis_at(plan.speed), &plan, None, &SimOptions::default()).unwrap();
    assert_eq!(tr, tr2);
    assert!(sim.max_constraint_residual() < 1e-9);
    let n = tr.t.len();
    assert!(tr.t.windows(2).all(|w| w[1] > w[0]));
    assert!(tr.rear_wheel_angle.windows(2).all(|w| w[1] >= w[0]));
    let end = plan.launch_duration + plan.kick_delay + plan.free_duration;
    if sim.stop == StopReason::Completed {
        assert!((tr.t[n - 1] - end).abs() < 1e-9, "{} vs {end}", tr.t[n - 1]);
    }
    // Angles continuous (no jump larger than a 1 ms step allows).
    for v in [&tr.roll, &tr.steer, &tr.yaw, &tr.pitch] {
        assert!(v.windows(2).all(|w| (w[1] - w[0]).abs() < 0.02));
    }
    // Upright-ish during the launch, a clear response after the kick.
    let release = tr.t.iter().position(|&t| t >= plan.launch_duration).unwrap();
    assert!(tr.roll[..release].iter().all(|r| r.abs() < 2f64.to_radians()));
    let peak = tr.roll[release..].iter().fold(0.0f64, |m, r| m.max(r.abs()));
    assert!(peak > 2f64.to_radians(), "peak roll after the kick {peak}");
    // Speed ramps from rest to the release speed.
    assert_eq!(tr.speed[0], 0.0);
    assert!((tr.speed[release] - plan.speed).abs() < 1e-9);
}

/// Issue 7, point 2: free speed, no dissipation: the total energy drifts by
/// less than 1e-8 (relative) over 10 s, and the holonomic residual stays
/// below 1e-9.
#[test]
fn free_speed_energy_drift_below_1e8_over_10_s() {
    let ic = InitialConditions {
        roll: 0.1,
        steer: 0.05,
        roll_rate: 0.3,
        speed: 5.0,
        ..Default::default()
    };
    let opts = SimOptions {
        rtol: 1e-11,
        atol: 1e-12,
        ..Default::default()
    };
    let sim = simulate::<bikedyn::generated::ThesisWhippleFree>(
        &bikedyn::models::default_parameters::<bikedyn::generated::ThesisWhippleFree>(),
        &ic,
        &Inputs::default(),
        10.0,
        &opts,
    )
    .unwrap();
    assert_eq!(sim.stop, StopReason::Completed);
    let drift = sim.relative_energy_drift();
    let speed = &sim.speed;
    println!(
        "energy drift {drift:.3e}, residual {:.3e}, speed {:.4} -> {:.4} m/s, {} evaluations",
        sim.max_constraint_residual(),
        speed[0],
        speed[speed.len() - 1],
        sim.stats.rhs_evaluations
    );
    assert!((speed[0] - 5.0).abs() < 1e-12, "initial speed {}", speed[0]);
    assert!(drift < 1e-8, "energy drift {drift}");
    assert!(sim.max_constraint_residual() < 1e-9);
    // The speed is free: it changes during the (energy-conserving) motion.
    let (lo, hi) = speed
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(l, h), s| (l.min(*s), h.max(*s)));
    assert!(hi - lo > 1e-4, "speed constant: {lo} {hi}");
}

/// A trajectory keeps its times strictly increasing: samples a rounding
/// error apart (an event next to an output time) are one sample, also once
/// shifted by an offset (the sensor side adds the rest before the launch;
/// `synth --runs 12 --seed 7` once stopped at its eleventh run with "t must
/// increase").
#[test]
fn trajectory_times_stay_strictly_increasing() {
    use bikedyn_runtime::simulate::trajectory::Trajectory;
    let t0 = 5.4294732057153;
    let mut a = Trajectory {
        t: vec![0.0, 1.0],
        ..Default::default()
    };
    for v in [
        &mut a.yaw,
        &mut a.roll,
        &mut a.pitch,
        &mut a.steer,
        &mut a.rear_wheel_angle,
        &mut a.speed,
    ] {
        *v = vec![0.0; 2];
    }
    let b = Trajectory {
        t: vec![0.0, t0, t0 + 4.0 * f64::EPSILON, t0 + 1e-3],
        yaw: vec![0.0; 4],
        roll: vec![0.0, 1.0, 2.0, 3.0],
        pitch: vec![0.0; 4],
        steer: vec![0.0; 4],
        rear_wheel_angle: vec![0.0; 4],
        speed: vec![0.0; 4],
    };
    a.append(&b, 2.5);
    assert!(a.t.windows(2).all(|w| w[1] > w[0]), "{:?}", a.t);
    assert_eq!(a.t.len(), 5);
    assert_eq!(a.roll, vec![0.0, 0.0, 0.0, 1.0, 3.0]);

    let dir = scratch("simulation-synth-seed7");
    let out = bikedyn(&[
        "synth",
        "--runs",
        "12",
        "--seed",
        "7",
        "--out",
        dir.join("set").to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
}

/// Initial rates of extra states are a tyre model's (its lagged forces);
/// given to a model without such states, or not finite, they are refused
/// rather than dropped.
#[test]
fn initial_rates_of_states_the_model_lacks_are_refused() {
    use bikedyn::generated::TyreFree;
    use bikedyn_runtime::simulate::SimulateError;
    let opts = SimOptions::default();
    let ic = InitialConditions {
        state_rates: [100.0, 0.0],
        ..InitialConditions::default()
    };
    let e = simulate::<M>(&default_parameters::<M>(), &ic, &Inputs::default(), 0.5, &opts).unwrap_err();
    assert!(
        matches!(&e, SimulateError::InvalidInput(m) if m.contains("thesis_whipple") && m.contains("has 0")),
        "{e}"
    );
    let ic = InitialConditions {
        state_rates: [f64::NAN, 0.0],
        ..InitialConditions::default()
    };
    let e = simulate::<TyreFree>(&default_parameters::<TyreFree>(), &ic, &Inputs::default(), 0.5, &opts).unwrap_err();
    assert!(matches!(e, SimulateError::NotFinite { .. }), "{e}");
    // The tyre model takes them.
    let ic = InitialConditions {
        state_rates: [100.0, -50.0],
        ..InitialConditions::default()
    };
    simulate::<TyreFree>(&default_parameters::<TyreFree>(), &ic, &Inputs::default(), 0.5, &opts).unwrap();
}

/// The simulation job is the one call behind `bikedyn simulate` (and
/// Python's `simulate`): the library's outcome and the command line's CSV
/// are the same run, sample for sample, and the job's summary carries the
/// run's own statistics.
#[test]
fn the_simulation_job_and_the_command_line_give_the_same_run() {
    use bikedyn::bicycle::Bicycle;
    use bikedyn::simulate::{simulate as simulate_job, SimulateRequest};
    let bike = Bicycle::resolve("thesis").unwrap();
    let request = SimulateRequest {
        initial: InitialConditions {
            roll: 3f64.to_radians(),
            speed: 5.0,
            ..InitialConditions::default()
        },
        inputs: Inputs {
            kicks: vec![Kick::at_saddle(0.5, 2.0)],
            ..Inputs::default()
        },
        duration: 2.0,
        ..SimulateRequest::default()
    };
    let outcome = simulate_job(&bike, &request).unwrap();
    let summary = outcome.summary();
    let sim = &outcome.simulation;
    assert_eq!(outcome.model.name, sim.model);
    assert_eq!(summary.rhs_evaluations, sim.stats.rhs_evaluations);
    assert_eq!(summary.simulated_seconds, 2.0);
    assert!(!summary.free_speed);

    let csv = scratch("simulate-job").join("run.csv");
    let out = bikedyn(&[
        "simulate",
        "--speed",
        "5",
        "--roll",
        "3",
        "--kick",
        "0.5:2",
        "--duration",
        "2",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains(&format!("model {}", sim.model)),
        "{}",
        text(&out.stdout)
    );
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), sim.t.len());
    let n = sim.coordinates.len();
    for (row, (p, dp)) in rows.iter().zip(sim.p.iter().zip(&sim.dp)) {
        for (a, b) in row[1..=n].iter().zip(p) {
            assert!((a - b).abs() <= 1e-11 * b.abs().max(1e-3), "{a} against {b}");
        }
        for (a, b) in row[n + 1..=2 * n].iter().zip(dp) {
            assert!((a - b).abs() <= 1e-11 * b.abs().max(1e-3), "{a} against {b}");
        }
    }
}
