//! `bikedyn bench`: figures for the generated code and the stability
//! pipeline (printed, never asserted; timings depend on the machine).

use bikedyn::bicycle::canonical_of;
use bikedyn::generated::{ThesisWhipple, CODEGEN_REPORT};
use bikedyn::models::default_parameters;
use bikedyn::runtime::eigen::eigenvalues;
use bikedyn::runtime::parameters::ThesisParameters;
use bikedyn::runtime::scalar::Counted;
use bikedyn::runtime::MultibodyModel;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::Instant;

fn per_call(reps: usize, mut f: impl FnMut(usize)) -> f64 {
    // Warm up, then time `reps` calls.
    for i in 0..reps.min(1000) {
        f(i);
    }
    let t = Instant::now();
    for i in 0..reps {
        f(i);
    }
    t.elapsed().as_secs_f64() / reps as f64
}

/// Print the figures. `quick` uses fewer repetitions.
pub fn run(quick: bool) -> anyhow::Result<()> {
    let reps = if quick { 20_000 } else { 400_000 };
    outln!("== code generation (build.rs, last build) ==");
    let report: serde_json::Value = serde_json::from_str(CODEGEN_REPORT)?;
    if report["derived"] == false {
        outln!(
            "this build took every model's committed generated code (nothing derived); `cargo build --release --features derive` derives them and records the timings"
        );
    } else {
        outln!(
            "all {} models: derivation + emission {:.2} s (budget 30 s)",
            report["models"].as_array().map_or(0, |m| m.len()),
            report["total_s"].as_f64().unwrap_or(f64::NAN)
        );
    }
    for m in report["models"].as_array().into_iter().flatten() {
        outln!(
            "model {:<16} derivation {:>6.2} s   derivation + emission {:>6.2} s   operations {:>9} before / {:>6} after optimisation",
            m["model"].as_str().unwrap_or("?"),
            m["derivation_s"].as_f64().unwrap_or(f64::NAN),
            m["derivation_and_emission_s"].as_f64().unwrap_or(f64::NAN),
            m["operations_before"],
            m["operations_after"]
        );
    }

    outln!("\n== generated functions of thesis_whipple (f64, one state per call, {reps} calls) ==");
    type M = ThesisWhipple;
    let param = default_parameters::<M>();
    let nq = M::nq();
    let (nh, nnh) = (M::HOLONOMIC.len(), M::NONHOLONOMIC.len());
    // A small ring of states so the calls are not constant-folded.
    let states: Vec<(Vec<f64>, Vec<f64>)> = (0..64)
        .map(|k| {
            let x = k as f64 / 64.0;
            let p: Vec<f64> = (0..nq)
                .map(|j| M::INITIAL_GUESS[j] + 0.3 * (x * (j + 1) as f64).sin())
                .collect();
            let dp: Vec<f64> = (0..nq).map(|j| (x * 3.0 + j as f64).cos()).collect();
            (p, dp)
        })
        .collect();
    let n_jac = (nq + nh + nnh) * (1 + M::INDEPENDENT.len() + M::DEPENDENT.len() + nq);
    let mut buf = vec![0.0; (nq * nq).max(n_jac)];
    let flops = |name: &str| M::FLOPS.iter().find(|(n, _)| *n == name).map(|x| x.1).unwrap_or(0);
    let mut total = 0.0;
    // Rows are collected and printed after the timing (a failed write to
    // standard output is then an error of this function).
    let mut lines = Vec::new();
    let mut row = |name: &str, secs: f64| {
        total += secs;
        lines.push(format!(
            "  {name:<28} {:>8.1} ns/call   {:>6} flops/call",
            secs * 1e9,
            flops(name)
        ));
    };
    let s = &states;
    row(
        "mass_matrix",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::mass_matrix(&param, p, &mut buf);
            black_box(&buf);
        }),
    );
    row(
        "quadratic_velocity_forces",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::quadratic_velocity_forces(&param, p, dp, &mut buf[..nq]);
            black_box(&buf);
        }),
    );
    row(
        "gravity_forces",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::gravity_forces(&param, p, &mut buf[..nq]);
            black_box(&buf);
        }),
    );
    row(
        "applied_forces",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::applied_forces(&param, 0.1, p, dp, &mut buf[..nq]);
            black_box(&buf);
        }),
    );
    row(
        "upright_velocity_terms_jacobian",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::upright_velocity_terms_jacobian(&param, 0.0, p, dp, &mut buf[..n_jac]);
            black_box(&buf);
        }),
    );
    row(
        "holonomic_residuals",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::holonomic_residuals(&param, 0.1, p, &mut buf[..nh]);
            black_box(&buf);
        }),
    );
    row(
        "holonomic_jacobian",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::holonomic_jacobian(&param, 0.1, p, &mut buf[..nh * nq]);
            black_box(&buf);
        }),
    );
    row(
        "holonomic_time_derivative",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::holonomic_time_derivative(&param, 0.1, p, &mut buf[..nh]);
            black_box(&buf);
        }),
    );
    row(
        "holonomic_convective",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::holonomic_convective(&param, 0.1, p, dp, &mut buf[..nh]);
            black_box(&buf);
        }),
    );
    row(
        "nonholonomic_velocities",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::nonholonomic_velocities(&param, 0.1, p, dp, &mut buf[..nnh]);
            black_box(&buf);
        }),
    );
    row(
        "nonholonomic_matrix",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::nonholonomic_matrix(&param, 0.1, p, &mut buf[..nnh * nq]);
            black_box(&buf);
        }),
    );
    row(
        "nonholonomic_convective",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            M::nonholonomic_convective(&param, 0.1, p, dp, &mut buf[..nnh]);
            black_box(&buf);
        }),
    );
    row(
        "kinetic_energy",
        per_call(reps, |i| {
            let (p, dp) = &s[i % 64];
            black_box(M::kinetic_energy(&param, p, dp));
        }),
    );
    row(
        "potential_energy",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            black_box(M::potential_energy(&param, p));
        }),
    );
    row(
        "point_positions",
        per_call(reps, |i| {
            let (p, _) = &s[i % 64];
            M::point_positions(&param, p, &mut buf[..6]);
            black_box(&buf);
        }),
    );
    for l in &lines {
        outln!("{l}");
    }
    let singles: usize = M::FLOPS.iter().filter(|x| x.0 != "all_quantities").map(|x| x.1).sum();
    outln!(
        "  {:<28} {:>8.1} ns/state  {:>6} flops/state",
        "sum of the calls above",
        total * 1e9,
        singles
    );
    let n_all: usize = M::ALL_QUANTITIES_LAYOUT.iter().map(|x| x.2).sum();
    let mut all = vec![0.0; n_all];
    let t_all = per_call(reps, |i| {
        let (p, dp) = &s[i % 64];
        M::all_quantities(&param, 0.1, p, dp, &mut all);
        black_box(&all);
    });
    outln!(
        "  {:<28} {:>8.1} ns/state  {:>6} flops/state (target: under 1000 ns)",
        "all_quantities (one call)",
        t_all * 1e9,
        flops("all_quantities")
    );

    outln!("\n== linearization and eigenvalues (thesis bicycle) ==");
    let thesis = ThesisParameters::thesis_bicycle();
    let lin_reps = if quick { 200 } else { 2000 };
    // The fast upright path and the general path it replaced (the whole
    // reduced system in 4-direction duals, issue 10 point 10), measured
    // alternately over 5 rounds, minimum of each: the machine may be shared,
    // and the minimum is the least disturbed figure.
    let (mut t_lin, mut t_lin_general) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        t_lin = t_lin.min(per_call(lin_reps, |_| {
            black_box(canonical_of(black_box(&thesis)).ok());
        }));
        t_lin_general = t_lin_general.min(per_call(lin_reps, |_| {
            black_box(
                bikedyn_runtime::linearize::canonical_matrices_general::<M, 4>(|s| black_box(&thesis).get(s)).ok(),
            );
        }));
    }
    let c = canonical_of(&thesis)?;
    let t_eig = per_call(reps, |i| {
        black_box(eigenvalues(&c, (i % 1000) as f64 * 0.01).ok());
    });
    // Flops of one evaluation of the reduced equations (constraint solve,
    // partitioning, generated M/Qv/Qgrav), counted with the Counted scalar.
    let pv = bikedyn_runtime::linearize::parameter_vector::<M>(|s| thesis.get(s), 5.0)?;
    let pc: Vec<Counted> = pv.iter().map(|&x| Counted(x)).collect();
    Counted::reset();
    let z = [Counted(0.0); 2];
    bikedyn_runtime::linearize::reduced_equations::<M, Counted>(
        &pc,
        Counted(0.0),
        &[Counted(0.01), Counted(0.02)],
        &z,
        &z,
    )?;
    let reduced_flops = Counted::count();
    outln!("  reduced equations Ec = Mi q'' - Qi, one evaluation at the solved configuration: {reduced_flops} flops (counted; the f64 Newton iterations before it are not included)");
    outln!(
        "  exact linearization (canonical M0, C1, K0, K2 from the generated equations, once per design): {:>8.2} us (fast upright path: f64 Newton only when the closed-form guess misses the constraints, 2-direction duals for the configuration terms, the velocity terms from their generated symbolic Jacobian in f64 by the chain rule, one real LU, scratch buffers on the stack; target: under 5 us{})",
        t_lin * 1e6,
        if t_lin < 5e-6 { ", target met" } else { ", not met here" }
    );
    outln!(
        "  exact linearization, previous method (general path: the whole reduced system in 4-direction duals; model chosen directly): {:>8.2} us, ~{} flops (~5 flops per dual op); two full linearizations before that: ~18 us",
        t_lin_general * 1e6,
        5 * reduced_flops
    );
    outln!(
        "  eigenvalues of the 4x4 state matrix per speed point:                                     {:>8.1} ns",
        t_eig * 1e9
    );
    outln!("  one speed point including its share of the linearization over 100 speeds:               {:>8.1} ns (target: under 2000 ns per core)", (t_eig + t_lin / 100.0) * 1e9);

    let (designs, speeds) = if quick { (100usize, 1000usize) } else { (1000, 1000) };
    let t = Instant::now();
    let stable: usize = (0..designs)
        .into_par_iter()
        .map(|k| {
            let mut p = thesis;
            p.steer_point_x *= 1.0 + 0.02 * (k as f64 / designs as f64 - 0.5);
            match canonical_of(&p) {
                Ok(c) => (0..speeds)
                    .filter(|&i| {
                        eigenvalues(&c, i as f64 * 10.0 / speeds as f64)
                            .map(|e| e.iter().all(|s| s.re < 0.0))
                            .unwrap_or(false)
                    })
                    .count(),
                Err(_) => 0,
            }
        })
        .sum();
    let el = t.elapsed().as_secs_f64();
    outln!(
        "  design x speed sweep: {designs} designs x {speeds} speeds = {} points on {} threads in {:.3} s ({:.0} ns/point; {stable} stable points) (target: 10^6 points under 2 s)",
        designs * speeds,
        rayon::current_num_threads(),
        el,
        el / (designs * speeds) as f64 * 1e9
    );
    super::bench::experiment(quick)?;
    super::bench_simulate::run(quick)?;
    Ok(())
}
