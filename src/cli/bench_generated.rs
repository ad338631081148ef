//! `bikedyn bench`: the figures of the generated code and the stability
//! pipeline, printed (measured by `bikedyn::bench`; never asserted, timings
//! depend on the machine).

use anyhow::Result;
use bikedyn::bench::{CodegenFigures, FunctionFigures, LinearizationFigures, SweepFigures};

/// Print the code-generation section.
pub fn codegen(c: &CodegenFigures) -> Result<()> {
    outln!("== code generation (build.rs, last build) ==");
    if !c.derived {
        outln!(
            "this build took every model's committed generated code (nothing derived); `cargo build --release --features derive` derives them and records the timings"
        );
    } else {
        outln!(
            "all {} models: derivation + emission {:.2} s (budget 30 s)",
            c.models.len(),
            c.total_s.unwrap_or(f64::NAN)
        );
    }
    for m in &c.models {
        outln!(
            "model {:<16} derivation {:>6.2} s   derivation + emission {:>6.2} s   operations {:>9} before / {:>6} after optimisation",
            m.model,
            m.derivation_s,
            m.derivation_and_emission_s,
            m.operations_before,
            m.operations_after
        );
    }
    Ok(())
}

/// Print the generated functions' section.
pub fn functions(f: &FunctionFigures) -> Result<()> {
    outln!(
        "\n== generated functions of {} (f64, one state per call, {} calls) ==",
        f.model,
        f.calls
    );
    for t in &f.functions {
        outln!(
            "  {:<28} {:>8.1} ns/call   {:>6} flops/call",
            t.name,
            t.ns_per_call,
            t.flops
        );
    }
    outln!(
        "  {:<28} {:>8.1} ns/state  {:>6} flops/state",
        "sum of the calls above",
        f.sum_ns,
        f.sum_flops
    );
    outln!(
        "  {:<28} {:>8.1} ns/state  {:>6} flops/state (target: under 1000 ns)",
        "all_quantities (one call)",
        f.all_quantities_ns,
        f.all_quantities_flops
    );
    Ok(())
}

/// Print the linearization and eigenvalue figures.
pub fn linearization(l: &LinearizationFigures) -> Result<()> {
    outln!("\n== linearization and eigenvalues (thesis bicycle) ==");
    outln!(
        "  reduced equations Ec = Mi q'' - Qi, one evaluation at the solved configuration: {} flops (counted; the f64 Newton iterations before it are not included)",
        l.reduced_equations_flops
    );
    outln!(
        "  exact linearization (canonical M0, C1, K0, K2 from the generated equations, once per design): {:>8.2} us (fast upright path: f64 Newton only when the closed-form guess misses the constraints, 2-direction duals for the configuration terms, the velocity terms from their generated symbolic Jacobian in f64 by the chain rule, one real LU, scratch buffers on the stack; target: under 5 us{})",
        l.linearization_us,
        if l.linearization_us < 5.0 { ", target met" } else { ", not met here" }
    );
    // About 5 flops per dual operation of the general path's 4 directions.
    outln!(
        "  exact linearization, previous method (general path: the whole reduced system in 4-direction duals; model chosen directly): {:>8.2} us, ~{} flops (~5 flops per dual op); two full linearizations before that: ~18 us",
        l.general_linearization_us,
        5 * l.reduced_equations_flops
    );
    outln!(
        "  eigenvalues of the 4x4 state matrix per speed point:                                     {:>8.1} ns",
        l.eigenvalues_ns
    );
    outln!(
        "  one speed point including its share of the linearization over 100 speeds:               {:>8.1} ns (target: under 2000 ns per core)",
        l.speed_point_ns
    );
    Ok(())
}

/// Print the design x speed sweep.
pub fn sweep(s: &SweepFigures) -> Result<()> {
    outln!(
        "  design x speed sweep: {} designs x {} speeds = {} points on {} threads in {:.3} s ({:.0} ns/point; {} stable points) (target: 10^6 points under 2 s)",
        s.designs,
        s.speeds,
        s.designs * s.speeds,
        s.threads,
        s.seconds,
        s.ns_per_point,
        s.stable_points
    );
    Ok(())
}
