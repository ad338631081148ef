//! Simulation figures of `bikedyn bench` (issue 7), printed: simulated
//! seconds per wall-clock second for a 5 s kick response of the thesis
//! model at rtol 1e-8, and right-hand-side evaluations per second.

use anyhow::Result;
use bikedyn::bench::SimulationFigures;

/// Print the simulation section.
pub fn simulation(s: &SimulationFigures) -> Result<()> {
    outln!(
        "\n== nonlinear simulation (thesis model, 5 s response to a 3 N s saddle kick at 4.5 m/s, rtol 1e-8, best of {}) ==",
        s.repetitions
    );
    for o in &s.outputs {
        let label = format!("output every {} s", o.output_interval_s);
        outln!(
            "  driven speed, no effects, {label:<20}: {:>7.3} ms per run = {:>6.0}x real time; {:>5} rhs evaluations ({} steps), {:>5.2} us per evaluation incl. sampling = {:.0} evaluations/s (target: > 2000x real time, 5 s in < 2.5 ms)",
            o.ms,
            o.real_time,
            o.rhs_evaluations,
            o.steps,
            o.us_per_evaluation,
            o.evaluations_per_s
        );
    }
    outln!(
        "  right-hand side alone (Newton with predictor, velocity solve, all_quantities, Mi q'' = Qi): {:.2} us per evaluation = {:.0} evaluations/s",
        s.rhs_us,
        s.rhs_per_s
    );
    for v in &s.variants {
        outln!(
            "  {:<48} ({}): {:>7.3} ms per run = {:>6.0}x real time; {:>5} rhs evaluations, {:>5.2} us per evaluation",
            v.label,
            v.model,
            v.ms,
            v.real_time,
            v.rhs_evaluations,
            v.us_per_evaluation
        );
    }
    outln!("  peer anchor: a Python/sympy implementation at about 0.2 ms per right-hand-side evaluation");
    Ok(())
}
