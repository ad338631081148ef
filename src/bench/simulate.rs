//! Simulation figures (issue 7): simulated seconds per wall-clock second
//! of a 5 s kick response of the thesis model at rtol 1e-8, and
//! right-hand-side evaluations per second.

use super::{BenchError, BenchOptions};
use crate::generated::{Extended, ExtendedFree, ThesisWhipple, ThesisWhippleFree};
use crate::models::default_parameters;
use bikedyn_runtime::simulate::{
    initial_state, simulate, Evaluator, InitialConditions, Inputs, Kick, SimOptions, Simulation,
};
use bikedyn_runtime::MultibodyModel;
use serde::Serialize;
use std::time::Instant;

/// Length of the simulated response (s).
const RESPONSE_S: f64 = 5.0;

/// Simulation figures, each the best of its repetitions (the least
/// disturbed on a shared machine).
#[derive(Clone, Debug, Serialize)]
pub struct SimulationFigures {
    /// Repetitions of each simulation.
    pub repetitions: usize,
    /// The thesis model at driven speed with no effects, by output interval.
    pub outputs: Vec<OutputTiming>,
    /// The right-hand side alone, on states along a motion (us per evaluation).
    pub rhs_us: f64,
    /// The same as evaluations per second.
    pub rhs_per_s: f64,
    /// The thesis model's other registered variants (output every 0.1 s).
    pub variants: Vec<VariantTiming>,
}

/// One simulation of the driven-speed thesis model.
#[derive(Clone, Debug, Serialize)]
pub struct OutputTiming {
    /// Output interval (s).
    pub output_interval_s: f64,
    /// Wall-clock time of the 5 s response (ms).
    pub ms: f64,
    /// Simulated over wall-clock time.
    pub real_time: f64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Integrator steps, accepted and rejected.
    pub steps: u64,
    /// Wall-clock time per evaluation, sampling included (us).
    pub us_per_evaluation: f64,
    /// Evaluations per second, sampling included.
    pub evaluations_per_s: f64,
}

/// One variant of the thesis model.
#[derive(Clone, Debug, Serialize)]
pub struct VariantTiming {
    /// What it adds, in words.
    pub label: &'static str,
    /// The generated model.
    pub model: &'static str,
    /// Wall-clock time of the 5 s response (ms).
    pub ms: f64,
    /// Simulated over wall-clock time.
    pub real_time: f64,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
    /// Wall-clock time per evaluation (us).
    pub us_per_evaluation: f64,
}

/// The best time (s) of `reps` (at least one) simulations of a 3 N s saddle kick at 4.5
/// m/s, and the last simulation.
fn time_run<M: MultibodyModel>(
    param: &[f64],
    reps: usize,
    output_interval: f64,
) -> Result<(f64, Simulation), BenchError> {
    let ic = InitialConditions {
        speed: 4.5,
        ..Default::default()
    };
    let inputs = Inputs {
        kicks: vec![Kick::at_saddle(0.0, 3.0)],
        pulses: vec![],
        feedback: None,
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
        let sim = simulate::<M>(param, &ic, &inputs, RESPONSE_S, &opts)?;
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(sim);
    }
    // `reps` is one of this module's constants, never zero.
    Ok((best, last.expect("reps > 0")))
}

/// Time one model variant with some effect parameters set.
fn variant<M: MultibodyModel>(
    label: &'static str,
    effects: &[(&str, f64)],
    reps: usize,
) -> Result<VariantTiming, BenchError> {
    let mut param = default_parameters::<M>();
    for (name, v) in effects {
        if let Some(i) = M::PARAMETERS.iter().position(|p| p == name) {
            param[i] = *v;
        }
    }
    let (secs, sim) = time_run::<M>(&param, reps, 0.1)?;
    let n = sim.stats.rhs_evaluations;
    Ok(VariantTiming {
        label,
        model: M::NAME,
        ms: secs * 1e3,
        real_time: RESPONSE_S / secs,
        rhs_evaluations: n,
        us_per_evaluation: secs / n as f64 * 1e6,
    })
}

/// Time the simulations (see [`SimulationFigures`]).
pub fn simulation(opts: &BenchOptions) -> Result<SimulationFigures, BenchError> {
    let reps = if opts.quick { 5 } else { 50 };
    type M = ThesisWhipple;
    let param = default_parameters::<M>();
    let mut outputs = Vec::new();
    for dt in [0.1, 0.01] {
        let (secs, sim) = time_run::<M>(&param, reps, dt)?;
        let n = sim.stats.rhs_evaluations;
        outputs.push(OutputTiming {
            output_interval_s: dt,
            ms: secs * 1e3,
            real_time: RESPONSE_S / secs,
            rhs_evaluations: n,
            steps: sim.stats.accepted_steps + sim.stats.rejected_steps,
            us_per_evaluation: secs / n as f64 * 1e6,
            evaluations_per_s: n as f64 / secs,
        });
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
    let n = if opts.quick { 20_000 } else { 400_000 };
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
    // Free speed and effects: the same 5 s kick response (output every
    // 0.1 s) through the other registered variants of the thesis model.
    let effects: &[(&str, f64)] = &[
        ("c_steer", 0.2),
        ("Crr_rear", 0.008),
        ("Crr_front", 0.008),
        ("CdA", 0.4),
        ("rho_air", 1.2),
    ];
    let variants = vec![
        variant::<ThesisWhippleFree>("free speed, no effects", &[], reps)?,
        variant::<Extended>("driven speed, steer damping", effects, reps)?,
        variant::<ExtendedFree>("free speed, damping + rolling resistance + drag", effects, reps)?,
    ];
    Ok(SimulationFigures {
        repetitions: reps,
        outputs,
        rhs_us: per * 1e6,
        rhs_per_s: 1.0 / per,
        variants,
    })
}
