//! The tyre model with relaxation: its kick response as the tyres stiffen,
//! its energy, its command line, and the stiff solver it wants.

use super::*;

/// Kick response (3 N s at the saddle, 4.5 m/s, 3 s) of a free-speed model.
fn free_kick<N: MultibodyModel>(param: &[f64], opts: &SimOptions) -> bikedyn_runtime::simulate::Simulation {
    let inputs = Inputs {
        kicks: vec![Kick::at_saddle(0.0, 3.0)],
        pulses: vec![],
        feedback: None,
    };
    let ic = InitialConditions {
        speed: 4.5,
        ..Default::default()
    };
    simulate::<N>(param, &ic, &inputs, 3.0, opts).unwrap()
}

/// Tyre parameters scaled `k` times stiffer: cornering stiffness times `k`,
/// relaxation length divided by `k`.
fn stiff_tyres(k: f64) -> Vec<f64> {
    type T = bikedyn::generated::TyreFree;
    let mut p = default_parameters::<T>();
    for w in ["rear", "front"] {
        p[T::parameter_index(&format!("Ca_{w}")).unwrap()] *= k;
        p[T::parameter_index(&format!("sigma_{w}")).unwrap()] /= k;
    }
    p
}

/// Issue 7, point 1: a model with extra first-order states (lagged tyre
/// forces) integrates, and as the tyres stiffen its kick response approaches
/// the no-slip model's.
#[test]
fn stiff_tyres_approach_the_no_slip_kick_response() {
    type T = bikedyn::generated::TyreFree;
    type W = bikedyn::generated::ThesisWhippleFree;
    let opts = SimOptions::default();
    let reference = free_kick::<W>(&default_parameters::<W>(), &opts);
    let r_roll = reference.coordinate("theta").unwrap();
    let r_steer = reference.coordinate("gamma").unwrap();
    let peak = r_roll.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut previous = f64::INFINITY;
    let mut last = 0.0;
    for k in [1.0, 10.0, 100.0] {
        let sim = free_kick::<T>(&stiff_tyres(k), &opts);
        assert_eq!(sim.stop, StopReason::Completed, "k = {k}");
        assert_eq!(sim.t, reference.t);
        assert_eq!(sim.states, T::STATES);
        assert!(sim.max_constraint_residual() < 1e-9);
        let roll = sim.coordinate("theta").unwrap();
        let steer = sim.coordinate("gamma").unwrap();
        let dev = (0..roll.len())
            .map(|i| (roll[i] - r_roll[i]).abs().max((steer[i] - r_steer[i]).abs()))
            .fold(0.0f64, f64::max);
        let fy = sim.state("Fy_front").unwrap();
        println!(
            "tyres {k:>5}x stiffer: max roll/steer deviation from no slip {:.3e} rad = {:.2}% of the peak roll {:.4} rad; max front tyre force {:.1} N; {} rhs evaluations",
            dev,
            100.0 * dev / peak,
            peak,
            fy.iter().fold(0.0f64, |m, x| m.max(x.abs())),
            sim.stats.rhs_evaluations
        );
        assert!(fy.iter().any(|f| f.abs() > 1.0), "tyre forces never built up");
        assert!(dev < previous, "no convergence: {dev} after {previous}");
        previous = dev;
        last = dev / peak;
    }
    // First order in 1/k (measured: 13.4%, 1.0%, 0.10% of the peak roll for
    // k = 1, 10, 100): 100x stiffer tyres must be within 0.3% of the peak.
    assert!(
        last < 0.003,
        "deviation {last} of the peak roll with 100x stiffer tyres"
    );
}

/// Normal loads of the tyre model at a state, read from the model's own
/// expressions: rolling resistance (switched on in a copy of the
/// parameters) has power `-Crr N |v_c|^2 / S` with the regularised contact
/// speed `S = sqrt(|v_c|^2 + 0.05^2)`, and the tyre force rate has slope
/// `-S / sigma` in the force.
fn tyre_loads(param: &[f64], p: &[f64], dp: &[f64]) -> [f64; 2] {
    use bikedyn::runtime::model::CoordinateRole;
    type T = bikedyn::generated::TyreFree;
    let nq = T::nq();
    let mut q = param.to_vec();
    let mut loads = [0.0; 2];
    for (i, (w, role, radius)) in [
        ("rear", CoordinateRole::RearWheelRotation, "Rt"),
        ("front", CoordinateRole::FrontWheelRotation, "Rd"),
    ]
    .into_iter()
    .enumerate()
    {
        // The rolling-resistance moment `-Crr N R w / sqrt(w^2 + w0^2)`
        // about the axle, `w` the wheel's spin: its generalized force on
        // the wheel's rotation coordinate is the moment itself (the spin
        // moves one for one with that rate), and its power is the moment
        // times `w`. With Crr = 1 the two give `w`, then `N`.
        q[T::parameter_index(&format!("Crr_{w}")).unwrap()] = 1.0;
        let f = T::FORCES
            .iter()
            .position(|f| f.name == format!("rolling_resistance_{w}"))
            .unwrap();
        let rotation = T::COORDINATE_ROLES.iter().find(|(r, _)| *r == role).unwrap().1;
        let mut terms = vec![0.0; T::FORCES.len() * nq];
        T::applied_force_terms(&q, 0.0, p, dp, &mut terms);
        let power: f64 = (0..nq).map(|j| terms[f * nq + j] * dp[j]).sum();
        let moment = terms[f * nq + rotation];
        let spin = power / moment;
        let r = param[T::parameter_index(radius).unwrap()];
        let w0 = 0.05 / r;
        loads[i] = -moment * (spin * spin + w0 * w0).sqrt() / (r * spin);
    }
    loads
}

/// Issue 7, point 1: with relaxation (and no camber thrust, which is not a
/// dissipative force) the tyres dissipate: the total energy, kinetic plus
/// potential plus the elastic energy of the tyres' lateral compliance
/// `sigma F^2 / (2 C_alpha N)` per tyre (the relaxation law is a spring of
/// stiffness `C_alpha N / sigma` in series with the slip damper), never
/// increases.
#[test]
fn tyre_relaxation_never_increases_the_energy() {
    type T = bikedyn::generated::TyreFree;
    let mut param = default_parameters::<T>();
    for w in ["rear", "front"] {
        param[T::parameter_index(&format!("Cg_{w}")).unwrap()] = 0.0;
    }
    let opts = SimOptions {
        rtol: 1e-10,
        atol: 1e-12,
        ..Default::default()
    };
    let sim = free_kick::<T>(&param, &opts);
    assert_eq!(sim.stop, StopReason::Completed);
    let idx = |n: &str| T::parameter_index(n).unwrap();
    let weight = ["m2", "m3", "m4", "m5"].iter().map(|m| param[idx(m)]).sum::<f64>() * param[idx("g")];
    let mut energy = Vec::new();
    let mut mechanical_rises = 0;
    for i in 0..sim.t.len() {
        let n = tyre_loads(&sim.parameters, &sim.p[i], &sim.dp[i]);
        // The quasi-static loads carry the weight (checks the probe).
        assert!((n[0] + n[1] - weight).abs() < 1e-9 * weight, "{n:?} vs {weight}");
        let elastic: f64 = ["rear", "front"]
            .iter()
            .enumerate()
            .map(|(k, w)| {
                param[idx(&format!("sigma_{w}"))] * sim.z[i][k].powi(2) / (2.0 * param[idx(&format!("Ca_{w}"))] * n[k])
            })
            .sum();
        let mechanical = sim.kinetic_energy[i] + sim.potential_energy[i];
        if i > 0 && sim.t[i] > sim.t[i - 1] {
            let prev = sim.kinetic_energy[i - 1] + sim.potential_energy[i - 1];
            mechanical_rises += (mechanical > prev) as usize;
        }
        energy.push((sim.t[i], mechanical + elastic));
    }
    // After the kick (the first sample is before it).
    let e0 = energy[1].1;
    let worst = energy[1..]
        .windows(2)
        .map(|w| w[1].1 - w[0].1)
        .fold(f64::NEG_INFINITY, f64::max);
    let lost = e0 - energy.last().unwrap().1;
    println!(
        "energy after the kick {e0:.6} J, dissipated by the tyres in 3 s {lost:.4} J, largest rise between samples {worst:.3e} J; kinetic + potential alone rose between {mechanical_rises} of {} samples",
        energy.len() - 1
    );
    assert!(worst <= 1e-9 * e0, "energy rose by {worst} J");
    assert!(lost > 1e-3 * e0, "no dissipation: {lost} J");
}

/// `bikedyn simulate --model thesis_tyre_free` runs a kick and writes the
/// tyre forces as extra CSV columns.
#[test]
fn cli_simulates_the_tyre_model() {
    let dir = scratch("simulate").join("tyre");
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("tyre.csv");
    let out = bikedyn(&[
        "simulate",
        "--model",
        "tyre_free",
        "--speed",
        "4.5",
        "--kick",
        "0.5:3",
        "--duration",
        "3",
        "--out",
        csv.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(stdout.contains("stop: completed"), "{stdout}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    assert_eq!(
        &header[header.len() - 3..],
        ["constraint_residual", "Fy_rear", "Fy_front"]
    );
    let last: Vec<f64> = text
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(last[0], 3.0);
}

/// Issue 7, point 2: stiff effects. With tyres 100 times stiffer
/// (cornering stiffness x100, relaxation length 2 mm) the tyre dynamics are
/// ~10^3-10^4 1/s fast and bound DOP853's step by stability: Radau5
/// integrates the same kick in far fewer right-hand-side evaluations and
/// both agree. With a 0.2 mm relaxation length DOP853 gives up (its
/// stiffness detection) and says to use Radau5, which integrates it.
#[test]
fn stiff_tyres_need_far_fewer_evaluations_with_radau5() {
    type T = bikedyn::generated::TyreFree;
    let run = |param: &[f64], method| {
        let inputs = Inputs {
            kicks: vec![Kick::at_saddle(0.0, 3.0)],
            pulses: vec![],
            feedback: None,
        };
        let ic = InitialConditions {
            speed: 4.5,
            ..Default::default()
        };
        let opts = SimOptions {
            method,
            ..Default::default()
        };
        simulate::<T>(param, &ic, &inputs, 3.0, &opts)
    };
    let param = stiff_tyres(100.0);
    let explicit = run(&param, Method::Dop853).unwrap();
    let implicit = run(&param, Method::Radau5).unwrap();
    assert_eq!(implicit.stop, StopReason::Completed);
    // Same output grid (DOP853 accumulates its sample times).
    assert_eq!(implicit.t.len(), explicit.t.len());
    assert!(implicit.t.iter().zip(&explicit.t).all(|(a, b)| (a - b).abs() < 1e-9));
    assert!(implicit.max_constraint_residual() < 1e-9);
    let peak = explicit
        .coordinate("theta")
        .unwrap()
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let mut dev = 0.0f64;
    for name in ["theta", "gamma"] {
        let (a, b) = (explicit.coordinate(name).unwrap(), implicit.coordinate(name).unwrap());
        dev = a.iter().zip(&b).fold(dev, |m, (x, y)| m.max((x - y).abs()));
    }
    let (ne, ni) = (explicit.stats.rhs_evaluations, implicit.stats.rhs_evaluations);
    println!(
        "tyres 100x stiffer, rtol 1e-8: DOP853 {ne} evaluations ({} steps), Radau5 {ni} evaluations ({} steps), {:.1}x fewer; largest roll/steer difference {dev:.2e} rad ({:.1e} of the peak roll)",
        explicit.stats.accepted_steps + explicit.stats.rejected_steps,
        implicit.stats.accepted_steps + implicit.stats.rejected_steps,
        ne as f64 / ni as f64,
        dev / peak
    );
    assert!(ni * 5 < ne, "Radau5 {ni} vs DOP853 {ne} evaluations");
    // Measured 5.0e-5 of the peak: Radau5's samples come from its
    // collocation polynomial (order 4), DOP853's from a 7th-order one.
    assert!(dev < 1e-4 * peak, "methods disagree by {dev} rad");

    let mut param = default_parameters::<T>();
    for w in ["rear", "front"] {
        param[T::parameter_index(&format!("sigma_{w}")).unwrap()] = 2e-4;
    }
    match run(&param, Method::Dop853) {
        Err(bikedyn_runtime::simulate::SimulateError::Integrator { message, .. }) => {
            assert!(message.contains("radau5"), "{message}")
        }
        other => panic!("DOP853 on 0.2 mm relaxation: {:?}", other.map(|s| s.stats)),
    }
    let sim = run(&param, Method::Radau5).unwrap();
    assert_eq!(sim.stop, StopReason::Completed);
    println!(
        "relaxation length 0.2 mm: Radau5 {} evaluations ({} steps)",
        sim.stats.rhs_evaluations,
        sim.stats.accepted_steps + sim.stats.rejected_steps
    );

    // The CLI selects the method.
    let out = bikedyn(&[
        "simulate",
        "--model",
        "tyre_free",
        "--speed",
        "4.5",
        "--kick",
        "0:3",
        "--duration",
        "1",
        "--method",
        "radau5",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    println!("{stdout}");
    assert!(stdout.contains("radau5: simulated 1.000 s"), "{stdout}");
    let out = bikedyn(&["simulate", "--speed", "4.5", "--duration", "1", "--method", "euler"]);
    assert_eq!(out.status.code(), Some(2));
}

/// Radau5 reproduces DOP853 on the non-stiff thesis model too, and locates
/// a fall.
#[test]
fn radau5_matches_dop853_and_stops_at_a_fall() {
    let ic = InitialConditions {
        roll: 0.05,
        speed: 1.0,
        ..Default::default()
    };
    let run = |method| {
        let opts = SimOptions {
            method,
            rtol: 1e-10,
            atol: 1e-12,
            events: Events {
                roll_limit: Some(0.8),
                steer_limit: None,
            },
            ..Default::default()
        };
        simulate::<M>(&thesis_at(1.0), &ic, &Inputs::default(), 20.0, &opts).unwrap()
    };
    let (a, b) = (run(Method::Dop853), run(Method::Radau5));
    let (ta, tb) = match (a.stop, b.stop) {
        (StopReason::Fell { time: ta, .. }, StopReason::Fell { time: tb, roll }) => {
            assert!((roll.abs() - 0.8).abs() < 1e-8);
            (ta, tb)
        }
        s => panic!("expected two falls, got {s:?}"),
    };
    println!("fall at {ta:.9} s (DOP853), {tb:.9} s (Radau5)");
    // Measured 2.8e-6 s at rtol 1e-10 (the fall amplifies errors ~16x).
    assert!((ta - tb).abs() < 1e-5, "{ta} vs {tb}");
}
