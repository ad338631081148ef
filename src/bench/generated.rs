//! Figures of the generated code (its derivation, and its functions per
//! call) and of the linear analysis built on it (linearization,
//! eigenvalues, a design x speed sweep).

use super::{per_call, BenchError, BenchOptions};
use crate::bicycle::canonical_of;
use crate::generated::{ThesisWhipple, CODEGEN_REPORT};
use crate::models::default_parameters;
use bikedyn_runtime::eigen::eigenvalues;
use bikedyn_runtime::linearize::{canonical_matrices_general, parameter_vector, reduced_equations};
use bikedyn_runtime::parameters::ThesisParameters;
use bikedyn_runtime::scalar::Counted;
use bikedyn_runtime::MultibodyModel;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::hint::black_box;
use std::time::Instant;

/// The model whose generated functions and linearization are timed.
type M = ThesisWhipple;

/// Code generation in build.rs, as its report (`codegen_report.json`)
/// records the last build.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CodegenFigures {
    /// Whether the build derived the models (feature `derive`); without
    /// it, it took every model's committed generated code and timed nothing.
    #[serde(default = "derived_by_default")]
    pub derived: bool,
    /// Derivation and emission of every model (s), or `null` when nothing
    /// was derived.
    pub total_s: Option<f64>,
    /// Each model derived (empty when nothing was).
    pub models: Vec<ModelCodegen>,
}

/// A report without `derived` comes from a derivation (build.rs writes
/// `"derived": false` only when it took the committed code).
fn derived_by_default() -> bool {
    true
}

/// One model's derivation.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ModelCodegen {
    /// The model's name.
    pub model: String,
    /// Symbolic derivation (s).
    pub derivation_s: f64,
    /// Derivation and emission of its Rust code (s).
    pub derivation_and_emission_s: f64,
    /// Operations of its expressions as derived (no sharing).
    pub operations_before: u64,
    /// Operations of the emitted code, after optimisation.
    pub operations_after: u64,
}

/// Code generation figures of this build (read from its report; nothing is timed).
pub fn codegen() -> Result<CodegenFigures, BenchError> {
    serde_json::from_str(CODEGEN_REPORT).map_err(BenchError::CodegenReport)
}

/// The generated functions of one model, in f64, one state per call.
#[derive(Clone, Debug, Serialize)]
pub struct FunctionFigures {
    /// The model (`thesis_whipple`).
    pub model: &'static str,
    /// Calls timed per function.
    pub calls: usize,
    /// Each function, in the order of the generated trait.
    pub functions: Vec<FunctionTiming>,
    /// The functions above, one call each (ns per state).
    pub sum_ns: f64,
    /// Their flops together (per state).
    pub sum_flops: usize,
    /// `all_quantities`, which computes them all in one call (ns per state).
    pub all_quantities_ns: f64,
    /// Its flops (per state).
    pub all_quantities_flops: usize,
}

/// One generated function's time per call.
#[derive(Clone, Debug, Serialize)]
pub struct FunctionTiming {
    /// The function.
    pub name: &'static str,
    /// Wall-clock time per call (ns).
    pub ns_per_call: f64,
    /// Floating-point operations per call, as emitted (0 when the emitter
    /// counts none for it).
    pub flops: usize,
}

/// Flops of generated function `name` of `M`, as the emitter counted them.
fn flops(name: &str) -> usize {
    M::FLOPS.iter().find(|(n, _)| *n == name).map_or(0, |x| x.1)
}

/// Time `f` (call `i` writes into `buf`) over `reps` calls: generated function `name`.
fn timing(name: &'static str, reps: usize, buf: &mut [f64], mut f: impl FnMut(usize, &mut [f64])) -> FunctionTiming {
    let secs = per_call(reps, |i| {
        f(i, buf);
        black_box(&*buf);
    });
    FunctionTiming {
        name,
        ns_per_call: secs * 1e9,
        flops: flops(name),
    }
}

/// Time every generated function of the thesis model on a ring of states.
pub fn generated_functions(opts: &BenchOptions) -> FunctionFigures {
    let reps = if opts.quick { 20_000 } else { 400_000 };
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
    let s = &states;
    let b = &mut buf;
    // Each function through a generic helper (no indirect call inside the
    // timed loop: it would add a few ns to calls of tens of ns).
    let functions = vec![
        timing("mass_matrix", reps, b, |i, b| M::mass_matrix(&param, &s[i % 64].0, b)),
        timing("quadratic_velocity_forces", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::quadratic_velocity_forces(&param, p, dp, &mut b[..nq])
        }),
        timing("gravity_forces", reps, b, |i, b| {
            M::gravity_forces(&param, &s[i % 64].0, &mut b[..nq])
        }),
        timing("applied_forces", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::applied_forces(&param, 0.1, p, dp, &mut b[..nq])
        }),
        timing("upright_velocity_terms_jacobian", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::upright_velocity_terms_jacobian(&param, 0.0, p, dp, &mut b[..n_jac])
        }),
        timing("holonomic_residuals", reps, b, |i, b| {
            M::holonomic_residuals(&param, 0.1, &s[i % 64].0, &mut b[..nh])
        }),
        timing("holonomic_jacobian", reps, b, |i, b| {
            M::holonomic_jacobian(&param, 0.1, &s[i % 64].0, &mut b[..nh * nq])
        }),
        timing("holonomic_time_derivative", reps, b, |i, b| {
            M::holonomic_time_derivative(&param, 0.1, &s[i % 64].0, &mut b[..nh])
        }),
        timing("holonomic_convective", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::holonomic_convective(&param, 0.1, p, dp, &mut b[..nh])
        }),
        timing("nonholonomic_velocities", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::nonholonomic_velocities(&param, 0.1, p, dp, &mut b[..nnh])
        }),
        timing("nonholonomic_matrix", reps, b, |i, b| {
            M::nonholonomic_matrix(&param, 0.1, &s[i % 64].0, &mut b[..nnh * nq])
        }),
        timing("nonholonomic_convective", reps, b, |i, b| {
            let (p, dp) = &s[i % 64];
            M::nonholonomic_convective(&param, 0.1, p, dp, &mut b[..nnh])
        }),
        timing("kinetic_energy", reps, b, |i, _| {
            let (p, dp) = &s[i % 64];
            black_box(M::kinetic_energy(&param, p, dp));
        }),
        timing("potential_energy", reps, b, |i, _| {
            black_box(M::potential_energy(&param, &s[i % 64].0));
        }),
        timing("point_positions", reps, b, |i, b| {
            M::point_positions(&param, &s[i % 64].0, &mut b[..6])
        }),
    ];
    let n_all: usize = M::ALL_QUANTITIES_LAYOUT.iter().map(|x| x.2).sum();
    let mut all = vec![0.0; n_all];
    let t_all = per_call(reps, |i| {
        let (p, dp) = &s[i % 64];
        M::all_quantities(&param, 0.1, p, dp, &mut all);
        black_box(&all);
    });
    FunctionFigures {
        model: M::NAME,
        calls: reps,
        sum_ns: functions.iter().map(|f| f.ns_per_call).sum(),
        functions,
        sum_flops: M::FLOPS.iter().filter(|x| x.0 != "all_quantities").map(|x| x.1).sum(),
        all_quantities_ns: t_all * 1e9,
        all_quantities_flops: flops("all_quantities"),
    }
}

/// Linearization and eigenvalues of the thesis bicycle.
#[derive(Clone, Debug, Serialize)]
pub struct LinearizationFigures {
    /// Flops of one evaluation of the reduced equations `Mi q'' - Qi` at
    /// the solved configuration, counted (the f64 Newton iterations before
    /// it are not included).
    pub reduced_equations_flops: u64,
    /// The canonical matrices (M0, C1, K0, K2) from the generated
    /// equations, once per design, by the fast upright path (us; minimum of
    /// 5 rounds).
    pub linearization_us: f64,
    /// The same by the general path it replaced (the whole reduced system in
    /// 4-direction duals; us, minimum of 5 rounds).
    pub general_linearization_us: f64,
    /// Eigenvalues of the 4x4 state matrix at one speed (ns).
    pub eigenvalues_ns: f64,
    /// One speed point with its share of the linearization over 100 speeds (ns).
    pub speed_point_ns: f64,
}

/// Time the linearization of the thesis bicycle by both paths, and its
/// eigenvalues per speed.
pub fn linearization(opts: &BenchOptions) -> Result<LinearizationFigures, BenchError> {
    let thesis = ThesisParameters::thesis_bicycle();
    let reps = if opts.quick { 20_000 } else { 400_000 };
    let lin_reps = if opts.quick { 200 } else { 2000 };
    // The fast upright path and the general path it replaced (issue 10
    // point 10), measured alternately over 5 rounds, minimum of each: the
    // machine may be shared, and the minimum is the least disturbed figure.
    let (mut t_lin, mut t_lin_general) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        t_lin = t_lin.min(per_call(lin_reps, |_| {
            black_box(canonical_of(black_box(&thesis)).ok());
        }));
        t_lin_general = t_lin_general.min(per_call(lin_reps, |_| {
            black_box(canonical_matrices_general::<M, 4>(|s| black_box(&thesis).get(s)).ok());
        }));
    }
    let c = canonical_of(&thesis)?;
    let t_eig = per_call(reps, |i| {
        black_box(eigenvalues(&c, (i % 1000) as f64 * 0.01).ok());
    });
    // Flops of one evaluation of the reduced equations (constraint solve,
    // partitioning, generated M/Qv/Qgrav), counted with the Counted scalar.
    let pv = parameter_vector::<M>(|s| thesis.get(s), 5.0)?;
    let pc: Vec<Counted> = pv.iter().map(|&x| Counted(x)).collect();
    Counted::reset();
    let z = [Counted(0.0); 2];
    reduced_equations::<M, Counted>(&pc, Counted(0.0), &[Counted(0.01), Counted(0.02)], &z, &z)?;
    Ok(LinearizationFigures {
        reduced_equations_flops: Counted::count(),
        linearization_us: t_lin * 1e6,
        general_linearization_us: t_lin_general * 1e6,
        eigenvalues_ns: t_eig * 1e9,
        speed_point_ns: (t_eig + t_lin / 100.0) * 1e9,
    })
}

/// A design x speed stability sweep on every thread.
#[derive(Clone, Debug, Serialize)]
pub struct SweepFigures {
    /// Designs (the thesis bicycle with its steer axis moved by up to +-1 %).
    pub designs: usize,
    /// Speeds per design, evenly from 0 to 10 m/s.
    pub speeds: usize,
    /// Threads the sweep ran on.
    pub threads: usize,
    /// Wall-clock time of the sweep (s).
    pub seconds: f64,
    /// Per point (ns).
    pub ns_per_point: f64,
    /// Points where every eigenvalue has a negative real part.
    pub stable_points: usize,
}

/// Sweep the stability of designs near the thesis bicycle over speeds.
pub fn sweep(opts: &BenchOptions) -> SweepFigures {
    let thesis = ThesisParameters::thesis_bicycle();
    let (designs, speeds) = if opts.quick {
        (100usize, 1000usize)
    } else {
        (1000, 1000)
    };
    let t = Instant::now();
    let stable_points: usize = (0..designs)
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
    let seconds = t.elapsed().as_secs_f64();
    SweepFigures {
        designs,
        speeds,
        threads: rayon::current_num_threads(),
        seconds,
        ns_per_point: seconds / (designs * speeds) as f64 * 1e9,
        stable_points,
    }
}
