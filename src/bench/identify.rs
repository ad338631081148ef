//! `bikedyn bench --identify`: one full identification on a synthetic set
//! made in a temporary folder, timed (issue 17's target: under 5 s on 2
//! cores).

use super::{scratch, BenchError};
use crate::identify::{plan, run_builtin_plan, IdentifyRequest, Outcome};
use crate::progress::{OnProgress, Progress};
use crate::synth::{synth, SynthOptions, SynthRun};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// The set identified.
#[derive(Clone, Debug)]
pub struct IdentifyBenchOptions {
    /// Runs of the set (default 12).
    pub runs: usize,
    /// Seed of the run plans (default 22).
    pub seed: u64,
    /// Effects hidden in the thesis bicycle, `(symbol, value)` in the
    /// parameter's unit (default: steer damping `c_steer` = 0.25 N m s/rad).
    pub hidden: Vec<(String, f64)>,
}

impl Default for IdentifyBenchOptions {
    fn default() -> Self {
        IdentifyBenchOptions {
            runs: 12,
            seed: 22,
            hidden: vec![("c_steer".to_string(), 0.25)],
        }
    }
}

/// The identification timed, and what it found.
#[derive(Serialize)]
pub struct IdentifyBench {
    /// The temporary folder the set was made in (removed after).
    pub set: PathBuf,
    /// The runs of the set, as `synth` made them.
    pub runs: Vec<SynthRun>,
    /// The free-speed model fitted.
    pub model: &'static str,
    /// Its driven-speed twin (the weave predictions).
    pub driven_model: &'static str,
    /// Kicks identified from.
    pub kicks: usize,
    /// Wall-clock time of the identification, planning included (s).
    pub seconds: f64,
    /// Threads it ran on.
    pub threads: usize,
    /// Simulations it ran.
    pub simulations: usize,
    /// Everything identification found (`crate::identify::report::summary`
    /// puts it in words).
    #[serde(skip)]
    pub outcome: Outcome,
}

/// Make the set (the thesis bicycle at 4-6.5 m/s with `opts.hidden`), then
/// identify from it with every default of `bikedyn identify`. `progress`
/// gets the synthesis (step `"runs simulated"`) and the identification.
pub fn identify_bench(opts: &IdentifyBenchOptions, progress: OnProgress<'_>) -> Result<IdentifyBench, BenchError> {
    let dir = scratch("bikedyn-bench-identify")?;
    // Left by an earlier bench of a process with the same id.
    let _ = std::fs::remove_dir_all(&dir);
    let result = identify_in(&dir, opts, progress);
    // A scratch folder of this process only: its loss is no error.
    let _ = std::fs::remove_dir_all(&dir);
    result
}

fn identify_in(
    dir: &std::path::Path,
    opts: &IdentifyBenchOptions,
    progress: OnProgress<'_>,
) -> Result<IdentifyBench, BenchError> {
    let synth_opts = SynthOptions {
        effects: opts.hidden.clone(),
        speeds: [4.0, 6.5],
        runs: opts.runs,
        seed: opts.seed,
        out: dir.to_path_buf(),
        ..SynthOptions::default()
    };
    let mut runs = Vec::new();
    synth(&synth_opts, &mut |r: &SynthRun| {
        runs.push(r.clone());
        progress(Progress {
            step: "runs simulated",
            done: runs.len(),
            total: Some(opts.runs),
        });
    })?;
    let request = IdentifyRequest {
        inputs: vec![dir.to_path_buf()],
        ..IdentifyRequest::default()
    };
    let t = Instant::now();
    let plan = plan(&request)?;
    let outcome = run_builtin_plan(&plan, &request, progress)?;
    let seconds = t.elapsed().as_secs_f64();
    Ok(IdentifyBench {
        set: dir.to_path_buf(),
        runs,
        model: plan.model.name,
        driven_model: plan.driven_model.name,
        kicks: outcome.segments.len(),
        seconds,
        threads: rayon::current_num_threads(),
        simulations: outcome.identification.simulations,
        outcome,
    })
}
