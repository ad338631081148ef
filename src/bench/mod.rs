//! `bikedyn bench`: timing and operation-count figures of the generated
//! code, the linear analysis, the measured-run pipeline and the
//! simulation; or one full identification on a synthetic set
//! ([`identify_bench`]). Figures are measured, never asserted: timings
//! depend on the machine (docs/performance.md records them with their
//! targets).
//!
//! Each section is a function of its own returning typed figures, so a
//! front end may show one section as soon as it is measured (the command
//! line does); [`bench`] runs them all.

mod generated;
mod identify;
mod measured;
mod simulate;

pub use generated::{
    codegen, generated_functions, linearization, sweep, CodegenFigures, FunctionFigures, FunctionTiming,
    LinearizationFigures, ModelCodegen, SweepFigures,
};
pub use identify::{identify_bench, IdentifyBench, IdentifyBenchOptions};
pub use measured::{measured_runs, LogTiming, MeasuredRunFigures};
pub use simulate::{simulation, OutputTiming, SimulationFigures, VariantTiming};

use crate::bicycle::BicycleError;
use crate::runs::ReadError;
use bikedyn_runtime::constraints::ConstraintError;
use bikedyn_runtime::eigen::EigenError;
use bikedyn_runtime::linearize::LinearizeError;
use bikedyn_runtime::simulate::SimulateError;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;
use thiserror::Error;

/// How long to measure.
#[derive(Clone, Copy, Debug, Default)]
pub struct BenchOptions {
    /// Fewer repetitions, for a quick look (default: false). Full / quick:
    /// 400,000 / 20,000 calls of each generated function, 2,000 / 200
    /// linearizations, 1,000 / 100 designs of 1,000 speeds in the sweep,
    /// 30 / 5 repetitions of the measured-run pipeline, 50 / 5 simulations
    /// of each variant.
    pub quick: bool,
}

/// Every figure of `bikedyn bench`, section by section.
#[derive(Clone, Debug, Serialize)]
pub struct BenchFigures {
    /// Code generation in build.rs, from the last build's report.
    pub codegen: CodegenFigures,
    /// The generated functions of one model, per call.
    pub generated_functions: FunctionFigures,
    /// Linearization and eigenvalues of the thesis bicycle.
    pub linearization: LinearizationFigures,
    /// A design x speed stability sweep on every thread.
    pub sweep: SweepFigures,
    /// The measured-run pipeline of `bikedyn fit`, on one thread.
    pub measured_runs: MeasuredRunFigures,
    /// Nonlinear simulation of a kick response.
    pub simulation: SimulationFigures,
}

/// Why a bench could not run.
#[derive(Debug, Error)]
pub enum BenchError {
    /// The code-generation report that build.rs wrote is no JSON of the
    /// expected shape (a build script of another version).
    #[error("the code-generation report of this build (codegen_report.json) cannot be read")]
    CodegenReport(#[source] serde_json::Error),
    /// The system's temporary folder, where the bench writes its runs, is
    /// missing: a bench never creates it (nor leaves one).
    #[error("the temporary folder {} (TMPDIR) does not exist or is no folder: create it, or set TMPDIR to an existing folder", path.display())]
    NoTempDir {
        /// The folder (`std::env::temp_dir()`).
        path: PathBuf,
    },
    /// The thesis bicycle's canonical matrices failed.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The parameter vector or a linearization failed.
    #[error(transparent)]
    Linearize(#[from] LinearizeError),
    /// The constraints of the counted evaluation could not be solved.
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
    /// An eigenvalue computation failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// A simulation or right-hand-side evaluation failed.
    #[error(transparent)]
    Simulate(#[from] SimulateError),
    /// A run or log of the measured-run bench could not be read.
    #[error(transparent)]
    Read(#[from] ReadError),
    /// The synthetic run of the measured-run bench could not be written.
    #[error(transparent)]
    WriteRun(#[from] bikedyn_report::experiment::synth::WriteRunError),
    /// The synthetic set of the identification bench could not be made.
    #[error(transparent)]
    Synth(#[from] crate::synth::SynthError),
    /// The identification bench's identification failed.
    #[error(transparent)]
    Identify(#[from] crate::identify::IdentifyError),
}

/// Every section of `bikedyn bench`, in the order the command line shows them.
pub fn bench(opts: &BenchOptions) -> Result<BenchFigures, BenchError> {
    Ok(BenchFigures {
        codegen: codegen()?,
        generated_functions: generated_functions(opts),
        linearization: linearization(opts)?,
        sweep: sweep(opts),
        measured_runs: measured_runs(opts)?,
        simulation: simulation(opts)?,
    })
}

/// Seconds per call of `f` over `reps` calls, after a warm-up of up to
/// 1,000 calls (caches, branch predictors, lazily set-up tables).
fn per_call(reps: usize, mut f: impl FnMut(usize)) -> f64 {
    for i in 0..reps.min(1000) {
        f(i);
    }
    let t = Instant::now();
    for i in 0..reps {
        f(i);
    }
    t.elapsed().as_secs_f64() / reps as f64
}

/// A scratch folder `name-<pid>` in the system's temporary folder, which
/// must exist: a bench never creates a missing `TMPDIR` (nor leaves one).
fn scratch(name: &str) -> Result<PathBuf, BenchError> {
    let root = std::env::temp_dir();
    if !root.is_dir() {
        return Err(BenchError::NoTempDir { path: root });
    }
    Ok(root.join(format!("{name}-{}", std::process::id())))
}
