//! Simulation figures for `bikedyn bench` (issue 7): simulated seconds per
//! wall-clock second for a 5 s kick response of the thesis model at rtol 1e-8,
//! and right-hand-side evaluations per second. Printed, never asserted.

use bikedyn::generated::{Extended, ExtendedFree, ThesisWhipple, ThesisWhippleFree};
use bikedyn::models::default_parameters;
use bikedyn::runtime::simulate::{
    initial_state, simulate, Evaluator, InitialConditions, Inputs, Kick, SimOptions, Simulation,
};
use bikedyn::runtime::MultibodyModel;
use std::time::Instant;

fn time_run<M: MultibodyModel>(param: &[f64], reps: usize, output_interval: f64) -> anyhow::Result<(f64, Simulation)> {
    let ic = InitialConditions {
        speed: 4.5,
        ..Default::default()
    };
    let inputs = Inputs {
        kicks: vec![Kick::at_saddle(0.0, 3.0)],
        pulses: vec![],
    };
    let opts = SimOptions {
        rtol: 1e-8,
        atol: 1e-10,
        output_interval,
        ..Default::default()
    };
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..reps {
        let t = Instant::now();
        let sim = simulate::<M>(param, &ic, &inputs, 5.0, &opts)?;
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(sim);
    }
    Ok((best, last.expect("reps > 0")))
}

/// Time one model variant with some effect parameters set.
fn variant<M: MultibodyModel>(label: &str, effects: &[(&str, f64)], reps: usize) -> anyhow::Result<()> {
    let mut param = default_parameters::<M>();
    for (name, v) in effects {
        if let Some(i) = M::PARAMETERS.iter().position(|p| p == name) {
            param[i] = *v;
        }
    }
    let (secs, sim) = time_run::<M>(&param, reps, 0.1)?;
    let n = sim.stats.rhs_evaluations as f64;
    outln!(
        "  {label:<48} ({}): {:>7.3} ms per run = {:>6.0}x real time; {:>5} rhs evaluations, {:>5.2} us per evaluation",
        M::NAME,
        secs * 1e3,
        5.0 / secs,
        sim.stats.rhs_evaluations,
        secs / n * 1e6
    );
    Ok(())
}

/// Print the simulation figures.
pub fn run(quick: bool) -> anyhow::Result<()> {
    let reps = if quick { 5 } else { 50 };
    outln!("\n== nonlinear simulation (thesis model, 5 s response to a 3 N s saddle kick at 4.5 m/s, rtol 1e-8, best of {reps}) ==");
    type M = ThesisWhipple;
    let param = default_parameters::<M>();
    for (label, dt) in [("output every 0.1 s", 0.1), ("output every 0.01 s", 0.01)] {
        let (secs, sim) = time_run::<M>(&param, reps, dt)?;
        let n = sim.stats.rhs_evaluations as f64;
        outln!(
            "  driven speed, no effects, {label:<20}: {:>7.3} ms per run = {:>6.0}x real time; {:>5} rhs evaluations ({} steps), {:>5.2} us per evaluation incl. sampling = {:.0} evaluations/s (target: > 2000x real time, 5 s in < 2.5 ms)",
            secs * 1e3,
            5.0 / secs,
            sim.stats.rhs_evaluations,
            sim.stats.accepted_steps + sim.stats.rejected_steps,
            secs / n * 1e6,
            n / secs
        );
    }
    // The right-hand side alone, on the states of a run.
    let ic = InitialConditions {
        roll: 0.1,
        roll_rate: 0.5,
        speed: 4.5,
        ..Default::default()
    };
    let (y0, p) = initial_state::<M>(&param, &ic)?;
    let inputs = Inputs::default();
    let eval = Evaluator::<M>::new(&p, &inputs)?;
    let mut dy = vec![0.0; y0.len()];
    let n = if quick { 20_000 } else { 400_000 };
    let mut y = y0.clone();
    let t = Instant::now();
    for k in 0..n {
        // Small steps along the motion so the Newton warm start is realistic.
        let h = 1e-4 * ((k % 100) as f64);
        for i in 0..y.len() {
            y[i] = y0[i] + h * dy[i];
        }
        eval.derivative(h, &y, &mut dy)?;
    }
    let per = t.elapsed().as_secs_f64() / n as f64;
    outln!(
        "  right-hand side alone (Newton with predictor, velocity solve, all_quantities, Mi q'' = Qi): {:.2} us per evaluation = {:.0} evaluations/s",
        per * 1e6,
        1.0 / per
    );
    // Free speed and effects: the same 5 s kick response (output every
    // 0.1 s) through the other registered variants of the thesis model.
    let effects: &[(&str, f64)] = &[
        ("c_steer", 0.2),
        ("Crr_rear", 0.008),
        ("Crr_front", 0.008),
        ("CdA", 0.4),
        ("rho_air", 1.2),
    ];
    variant::<ThesisWhippleFree>("free speed, no effects", &[], reps)?;
    variant::<Extended>("driven speed, steer damping", effects, reps)?;
    variant::<ExtendedFree>("free speed, damping + rolling resistance + drag", effects, reps)?;
    outln!("  peer anchor: a Python/sympy implementation at about 0.2 ms per right-hand-side evaluation");
    Ok(())
}
