//! `bikedyn identify`: close the loop on a measured set (issue 9). The
//! measured-run pipeline (`fit`) finds the kicks and their windows; the
//! numerics are `runtime::identify` (time-series residuals against the
//! nonlinear simulation, stepwise selection by BIC and cross-validation).
//! This module is the pipeline; [`candidates`] builds the candidates from
//! the effect library, [`segments`] cuts the measured windows, [`predict`]
//! gives the linear weave predictions, [`corrections`] screens parameter
//! corrections, `fits` runs the nonlinear fits, [`diagnosis`] relates the residual
//! pattern to effects, and [`report`] writes the summary and the report
//! folder.

pub mod candidates;
mod confounded;
pub mod corrections;
pub mod diagnosis;
pub mod discovery;
pub mod eigen_table;
mod error;
mod fits;
pub mod predict;
mod remaining;
pub mod report;
pub mod result;
pub mod segments;
pub mod time_series;
pub mod weave_errors;
mod words;

pub use error::IdentifyError;

use crate::bicycle::Bicycle;
use crate::fit::{bicycle_for, run_fit_in, FitError, FitOptions};
use crate::progress::{OnProgress, Progress};
use crate::registry::BuiltIn;
use bikedyn_runtime::identify::{Candidate, Identification, IdentifyOptions as FitSettings, RollChannel, Segment};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry};
use candidates::{candidates, identification_models};
use diagnosis::{diagnose, Finding};
use fits::{Identify, RunPlot};
use predict::{linear_equivalent, predict};
use segments::segments;
use std::collections::BTreeMap;
use std::marker::PhantomData;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The committed example set: six runs of the thesis bicycle made by
/// `bikedyn synth` with steer damping hidden (`examples/data/README.md`).
pub const EXAMPLE_SET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/hidden_steer_damping");

/// What to identify: the measured runs, the bicycle, the candidates.
#[derive(Clone, Debug)]
pub struct IdentifyRequest {
    /// Set folders (all runs) or run folders.
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    pub calibration: Option<PathBuf>,
    /// Bicycle (built-in name or parameter file); its effect parameters, if
    /// any, are part of the model before identification. `None`, the
    /// default: the built-in thesis bicycle for thesis-format runs; TU Delft
    /// logs need one ([`IdentifyRequest::bicycle`]).
    pub bike: Option<String>,
    /// Candidate effects to consider (empty, the default: every effect of
    /// the library that identification supports).
    pub effects: Vec<String>,
    /// Folds of the cross-validation over runs (default 4).
    pub folds: usize,
    /// Largest number of parameter corrections tried beside the effects,
    /// the ones that could explain most of the measured weave misfit first
    /// (`None`, the default: every one that could explain some of it;
    /// `Some(0)`: effects only; see [`corrections`]).
    pub corrections: Option<usize>,
    /// After the library, search the dictionary of generalized forces on
    /// the kicks' measured weave eigenvalues ([`discovery`]; default true).
    pub discover: bool,
    /// Most candidates one step of the library's search fits beyond its
    /// contenders, best predicted first: a compute budget for large sets
    /// (a fit of a hundred TU Delft kicks takes tens of seconds), whose
    /// report lists what a step left unfitted. `None`, the default: a step
    /// that adds nothing has fitted every candidate the score test
    /// predicted to gain.
    pub max_fits_per_step: Option<usize>,
    /// Raise each step's bar of a consistent held-out gain with the
    /// candidates it has fitted (a family-wise bar; default false, two
    /// standard errors for each: see
    /// [`bikedyn_runtime::identify::IdentifyOptions::family_wise_bar`]).
    pub family_wise_bar: bool,
}

impl Default for IdentifyRequest {
    fn default() -> Self {
        Self {
            inputs: Vec::new(),
            calibration: None,
            bike: None,
            effects: Vec::new(),
            folds: 4,
            corrections: None,
            discover: true,
            max_fits_per_step: None,
            family_wise_bar: false,
        }
    }
}

impl IdentifyRequest {
    /// The bicycle: as given, or the built-in thesis bicycle when the
    /// inputs are thesis-format runs ([`crate::fit::bicycle_for`]; logs
    /// need one).
    pub fn bicycle(&self) -> Result<&str, IdentifyError> {
        let inputs: Vec<_> = self
            .inputs
            .iter()
            .filter_map(|p| crate::runs::classify(p).ok())
            .flatten()
            .collect();
        Ok(bicycle_for(self.bike.as_deref(), &inputs).map_err(FitError::from)?)
    }
}

/// The models and candidates of an identification, chosen before any fit
/// among the models of registry `R` (the built-in models by default).
pub struct Plan<R: ModelRegistry = BuiltIn> {
    /// The bicycle, resolved.
    pub bike: Bicycle<R>,
    /// The nonlinear model the fits run through: free speed for
    /// thesis-style runs, the driven twin for logs with the speed imposed.
    pub model: &'static ModelInfo,
    /// Its driven-speed twin (same effects), for the weave predictions.
    pub driven_model: &'static ModelInfo,
    /// The model with extra states (the tyre model), if the registry has one
    /// that can represent the bicycle.
    pub alternative_model: Option<&'static ModelInfo>,
    /// The candidate effects.
    pub candidates: Vec<Candidate>,
    /// The inputs are logs whose speed a motor held: the model's speed is
    /// imposed (the measured speed over each window), not free.
    pub speed_imposed: bool,
}

/// Everything identification found, and what the report needs; its models
/// are those of registry `R`.
pub struct Outcome<R: ModelRegistry = BuiltIn> {
    /// The bicycle (as given, or `thesis`, the default for thesis-format runs).
    pub bike: String,
    /// The stepwise selection: fits before and after, each step's verdicts.
    pub identification: Identification,
    /// The measured segments fitted (one per kick).
    pub segments: Vec<Segment>,
    /// Runs and kicks left out, with the reason.
    pub skipped: Vec<String>,
    /// Of those, the runs and logs that could not be processed at all (as
    /// `fit` reports them): the command line's exit status is 1 when there
    /// are any, as `fit`'s is. A kick that is no weave is not one of them.
    pub failed_inputs: Vec<String>,
    /// The candidate effects tried.
    pub candidates: Vec<Candidate>,
    /// The residual diagnosis of the base model.
    pub findings: Vec<Finding>,
    /// Weave eigenvalue `[re, im]` (1/s) of each segment, base model.
    pub predicted_before: Vec<Option<[f64; 2]>>,
    /// The same with the identified effects.
    pub predicted_after: Vec<Option<[f64; 2]>>,
    /// The same with the values fitted without the segment's fold.
    pub predicted_held_out: Vec<Option<[f64; 2]>>,
    /// Identified effect values by symbol (tied symbols and held companions included).
    pub values_after: BTreeMap<String, f64>,
    /// The free-speed model fitted.
    pub model: &'static str,
    /// Its driven-speed twin (the weave predictions).
    pub driven_model: &'static str,
    /// Wall-clock time of the run (s).
    pub seconds: f64,
    /// Mean |steer rate| of each segment in the fitted simulation (rad/s).
    pub steer_rate: Vec<f64>,
    /// Whether each segment's measured eigenvalue counts as a weave in the
    /// eigenvalue figures ([`weave_errors`]).
    pub weave_kicks: Vec<bool>,
    /// The kicks kept out of the eigenvalue figures, with the reason.
    pub eigen_excluded: Vec<weave_errors::Excluded>,
    /// What the library leaves in the weave eigenvalues: a pattern in the
    /// kicks' states beyond their scatter, or none (`None`: too few kicks).
    pub remaining: Option<bikedyn_runtime::identify::remaining::Remaining>,
    /// Whether each channel's residual after identification follows the
    /// simulated states (empty without simulations).
    pub state_correlation: Vec<bikedyn_runtime::identify::state_correlation::StateCorrelation>,
    /// What the dictionary of generalized forces found beyond the library
    /// on the kicks' weave eigenvalues (`None`: not requested).
    pub discovery: Option<discovery::DiscoveryOutcome>,
    /// What the dictionary's terms that the model carries found beyond the
    /// library in the time series (`None`: not requested).
    pub time_series: Option<time_series::TimeSeriesOutcome>,
    /// The model's speed was imposed (logs of a motor-held speed).
    pub speed_imposed: bool,
    run_plot: Option<RunPlot>,
    registry: PhantomData<R>,
}

impl<R: ModelRegistry> Outcome<R> {
    /// The stated prior `(measured value, standard deviation)` of a
    /// corrected parameter (the bicycle file's `+/-`, or the model's default
    /// for its kind), as the plan's candidates declare it.
    pub fn stated_prior(&self, symbol: &str) -> Option<(f64, f64)> {
        self.candidates
            .iter()
            .flat_map(|c| &c.parameters)
            .find(|p| p.symbol == symbol)
            .and_then(|p| p.prior)
    }

    /// What the segments' roll channel measures (angle or rate).
    pub fn roll_channel(&self) -> RollChannel {
        self.segments.first().map_or(RollChannel::Angle, |s| s.roll_channel)
    }
}

/// Choose the models and candidates for a request: the first half of
/// [`run`], so a caller can say which model runs before the fits start.
pub fn plan(request: &IdentifyRequest) -> Result<Plan, IdentifyError> {
    plan_in::<BuiltIn>(request)
}

/// [`plan`] among the models of registry `R`: the bicycle is resolved
/// against them, and the candidates are the effects their files declare
/// (e.g. an effect of a user's own build script).
pub fn plan_in<R: ModelRegistry>(request: &IdentifyRequest) -> Result<Plan<R>, IdentifyError> {
    let speed_imposed = segments::speed_imposed(&request.inputs)?;
    let bike = Bicycle::<R>::resolve_in(request.bicycle()?)?;
    let (model, driven_model, alternative_model) = identification_models(&bike, speed_imposed)?;
    let candidates = candidates(model, alternative_model, &bike, &request.effects, speed_imposed)?;
    // A conclusion ("no effect warranted") means something only when
    // effects were tried.
    if candidates.is_empty() {
        return Err(IdentifyError::NoCandidates {
            bicycle: bike.name.clone(),
            model: model.name,
            effects: model.effects.to_vec(),
        });
    }
    Ok(Plan {
        bike,
        model,
        driven_model,
        alternative_model,
        candidates,
        speed_imposed,
    })
}

/// Run identification on the inputs: [`plan`], then [`run_plan`].
pub fn run(request: &IdentifyRequest, progress: OnProgress<'_>) -> Result<Outcome, IdentifyError> {
    run_in::<BuiltIn>(request, progress)
}

/// [`run`] among the models of registry `R`: [`plan_in`], then [`run_plan`].
pub fn run_in<R: ModelRegistry>(
    request: &IdentifyRequest,
    progress: OnProgress<'_>,
) -> Result<Outcome<R>, IdentifyError> {
    run_plan(&plan_in::<R>(request)?, request, progress)
}

/// [`run_plan`] on the built-in models, compiled once in the library (a
/// generic call would compile every model's equations again in the
/// caller's crate).
#[inline(never)]
pub fn run_builtin_plan(
    plan: &Plan,
    request: &IdentifyRequest,
    progress: OnProgress<'_>,
) -> Result<Outcome, IdentifyError> {
    run_plan(plan, request, progress)
}

/// Run identification as planned: the measured-run pipeline, the segments,
/// the stepwise fits, the predictions before and after, the diagnosis.
/// `progress` gets the measured runs processed (step `"runs"`) and each
/// candidate fitted (its name as the step).
pub fn run_plan<R: ModelRegistry>(
    plan: &Plan<R>,
    request: &IdentifyRequest,
    progress: OnProgress<'_>,
) -> Result<Outcome<R>, IdentifyError> {
    let start = std::time::Instant::now();
    let Plan {
        bike,
        model: free,
        driven_model: driven,
        alternative_model: alt,
        candidates: cands,
        ..
    } = plan;
    let (free, driven, alt) = (*free, *driven, *alt);
    let fit_options = FitOptions {
        inputs: request.inputs.clone(),
        calibration: request.calibration.clone(),
        bike: Some(request.bicycle()?.to_string()),
        ..FitOptions::default()
    };
    // The measured eigenvalues and their verdicts (`fit` judges them).
    let out = run_fit_in::<R>(&fit_options, progress)?;
    let segments::Segments {
        segments: segs,
        rejected,
        mut skipped,
    } = segments(&out);
    // The experiment's controller acts in every simulation of a kick, as it
    // did on the road.
    let segs: Vec<_> = segs
        .into_iter()
        .map(|s| s.with_feedback(bike.feedback.clone()))
        .collect();
    // Runs and logs `fit` skipped (no kick found among them) and folders
    // of a set left out for want of a run.toml.
    skipped.extend(out.errors.iter().cloned());
    skipped.extend(out.warnings.iter().cloned());
    let failed_inputs = out.errors.clone();
    if segs.len() < 2 {
        return Err(IdentifyError::TooFewKicks {
            found: segs.len(),
            skipped,
        });
    }
    // Parameter corrections that could explain the measured weave misfit
    // join the effects as candidates.
    let speeds: Vec<f64> = segs.iter().map(|s| s.mean_speed).collect();
    let predicted_before = predict(driven, bike, &BTreeMap::new(), &speeds)?;
    // Only the kicks whose measured eigenvalue is a weave count in the
    // eigenvalue figures and the screening of corrections.
    let (weave_kicks, eigen_excluded) = weave_errors::weave_kicks(&segs, &rejected, &predicted_before);
    let weave_predictions: Vec<Option<[f64; 2]>> = predicted_before
        .iter()
        .zip(&weave_kicks)
        .map(|(p, &k)| if k { *p } else { None })
        .collect();
    let mut cands = cands.clone();
    for c in corrections::screen(free, driven, bike, &segs, &weave_predictions, request.corrections)? {
        cands.push(corrections::candidate(free, &c));
    }
    let cands = &cands;
    let opts = FitSettings {
        folds: request.folds,
        max_fits_per_step: request.max_fits_per_step,
        family_wise_bar: request.family_wise_bar,
        ..FitSettings::default()
    };
    // The runtime reports each stage by name, from the fitting threads, with
    // how far the stage is where its size is known (a step's candidate fits,
    // its cross-validations).
    let fitted = AtomicUsize::new(0);
    let on_fit = |name: &str, count: Option<(usize, usize)>| {
        let n = fitted.fetch_add(1, Ordering::Relaxed) + 1;
        progress(Progress {
            step: name,
            done: count.map_or(n, |c| c.0),
            total: count.map(|c| c.1),
        })
    };
    let (id, run_plot) = R::with_model(
        free.name,
        Identify {
            bike,
            alt,
            segments: &segs,
            candidates: cands,
            opts: &opts,
            progress: &on_fit,
        },
    )
    .expect("registered model")?;
    let values_after = effect_values(&id.after, &id.after.values, cands);
    // A separating experiment is proposed only where the bicycle can do
    // it: kicks at speeds where the identified model's weave is a stable
    // oscillation (below the weave speed the bicycle falls before a weave
    // can be fitted).
    let mut id = id;
    for step in &mut id.steps {
        for c in &mut step.confounded {
            let speeds: Vec<f64> = c.designs.iter().map(|d| d.speed).collect();
            let weave = predict(driven, bike, &values_after, &speeds)?;
            let mut k = 0;
            c.designs.retain(|_| {
                let stable = weave[k].is_some_and(|[re, im]| re < 0.0 && im > 0.0);
                k += 1;
                stable
            });
        }
    }
    // Steer-rate amplitude of each segment, from the fitted simulation.
    let steer_rate: Vec<f64> = (0..segs.len())
        .map(|i| {
            run_plot
                .as_ref()
                .and_then(|rp| rp.after[i].as_ref())
                .map_or(f64::NAN, |sim| mean_abs_rate(&segs[i].t, &sim.steer))
        })
        .collect();
    let mut predicted_after = Vec::with_capacity(segs.len());
    for (i, &v) in speeds.iter().enumerate() {
        let vals = linear_equivalent(driven, &values_after, steer_rate[i]);
        predicted_after.push(predict(driven, bike, &vals, &[v])?[0]);
    }
    // Held out: each segment predicted with the values fitted without its fold.
    let mut predicted_held_out = vec![None; segs.len()];
    for (f, vals) in id.after.fold_values.iter().enumerate() {
        let idx: Vec<usize> = (0..segs.len()).filter(|&s| id.fold_of[s] == f).collect();
        let sp: Vec<f64> = idx.iter().map(|&s| speeds[s]).collect();
        let fold_vals = effect_values(&id.after, vals, cands);
        for (k, &s) in idx.iter().enumerate() {
            predicted_held_out[s] = predict(
                driven,
                bike,
                &linear_equivalent(driven, &fold_vals, steer_rate[s]),
                &sp[k..=k],
            )?[0];
        }
    }
    // What the library leaves: the counted kicks' residuals after
    // identification against their own scatter.
    let weave_residuals: Vec<bikedyn_runtime::identify::remaining::KickWeave> = (0..segs.len())
        .filter(|&i| weave_kicks[i])
        .filter_map(|i| {
            Some(bikedyn_runtime::identify::remaining::KickWeave {
                speed: segs[i].mean_speed,
                amplitude: Some(diagnosis::peak_roll(&segs[i])),
                measured: segs[i].weave?.0,
                base: predicted_before[i]?,
                after: predicted_after[i]?,
                held_out: predicted_held_out[i]?,
            })
        })
        .collect();
    let remaining = bikedyn_runtime::identify::remaining::remaining(&weave_residuals);
    // And in the time series: whether each channel's residual after
    // identification follows the simulated states.
    let state_correlation = run_plot
        .as_ref()
        .map(|rp| {
            let kicks: Vec<bikedyn_runtime::identify::state_correlation::KickSeries> = segs
                .iter()
                .zip(&rp.after)
                .filter_map(|(s, sim)| {
                    let sim = sim.as_ref()?;
                    Some(bikedyn_runtime::identify::state_correlation::KickSeries {
                        t: &s.t,
                        measured: [&s.roll, &s.steer],
                        simulated: [&sim.roll, &sim.steer],
                    })
                })
                .collect();
            bikedyn_runtime::identify::state_correlation::state_correlation(&kicks)
        })
        .unwrap_or_default();
    // Beyond the library: the dictionary of generalized forces on the
    // counted kicks' weave eigenvalues, held out by the identification's
    // own folds of runs.
    let discovery = if let (true, Some(why)) = (request.discover, discovery::not_warranted(remaining.as_ref())) {
        Some(why)
    } else if request.discover {
        let kicks: Vec<usize> = (0..segs.len()).filter(|&i| weave_kicks[i]).collect();
        let mut rows = Vec::new();
        let mut values = Vec::new();
        let mut folds = Vec::new();
        let mut base = Vec::new();
        for &i in &kicks {
            let Some((m, se)) = segs[i].weave else { continue };
            rows.push(bikedyn_runtime::identify::discovery::Row {
                speed: segs[i].mean_speed,
                measured: m,
                stderr: se,
            });
            values.push(linear_equivalent(driven, &values_after, steer_rate[i]));
            folds.push(id.fold_of[i]);
            base.push(predicted_before[i]);
        }
        // The library's result stands whatever the search meets: a failure
        // of the search is its outcome, not the identification's.
        Some(
            discovery::discover_on_kicks(driven, bike, &rows, &values, &folds, &base)
                .unwrap_or_else(|e| discovery::DiscoveryOutcome::NotRun { reason: e.to_string() }),
        )
    } else {
        None
    };
    // Beyond the library in the time series: the dictionary's terms that
    // the model carries, through the nonlinear simulation of every kick,
    // where the library leaves a structured residual in the weave or in
    // the time series (never fitted to what is within the scatter).
    let time_series = if !request.discover {
        None
    } else if !(remaining.as_ref().is_some_and(|r| r.structured) || state_correlation.iter().any(|c| c.significant)) {
        Some(time_series::TimeSeriesOutcome::NotRun {
            reason: "the library leaves no structured residual, in the weave eigenvalues or in the time series".into(),
        })
    } else {
        let terms = time_series::terms(free);
        R::with_model(
            free.name,
            time_series::Search {
                bike,
                segments: &segs,
                library: &id,
                candidates: cands,
                terms: &terms,
                opts: &opts,
                progress: &on_fit,
            },
        )
        .expect("registered model")
        .map(Some)
        // The library's result stands whatever the search meets.
        .unwrap_or_else(|e| Some(time_series::TimeSeriesOutcome::NotRun { reason: e.to_string() }))
    };
    // Steady bias: the base model's roll residual over the second half of
    // each window.
    let bias: Vec<f64> = run_plot
        .as_ref()
        .map(|rp| {
            segs.iter()
                .zip(&rp.before)
                .filter_map(|(s, sim)| {
                    let sim = sim.as_ref()?;
                    let h = s.t.len() / 2;
                    let n = (s.t.len() - h).max(1) as f64;
                    Some((h..s.t.len()).map(|k| s.roll[k] - sim.roll[k]).sum::<f64>() / n)
                })
                .collect()
        })
        .unwrap_or_default();
    let models: Vec<&ModelInfo> = std::iter::once(free).chain(alt).collect();
    let bias = if segs.iter().all(|s| s.roll_channel == RollChannel::Angle) {
        bias
    } else {
        Vec::new()
    };
    let findings = diagnose(
        &models,
        &segs,
        &predicted_before,
        &id.before.errors,
        &bias,
        plan.speed_imposed,
    );
    Ok(Outcome {
        bike: out.bike.clone(),
        identification: id,
        segments: segs,
        skipped,
        failed_inputs,
        candidates: cands.clone(),
        findings,
        predicted_before,
        predicted_after,
        predicted_held_out,
        values_after,
        model: free.name,
        driven_model: driven.name,
        seconds: start.elapsed().as_secs_f64(),
        steer_rate,
        weave_kicks,
        eigen_excluded,
        remaining,
        state_correlation,
        discovery,
        time_series,
        speed_imposed: plan.speed_imposed,
        run_plot,
        registry: PhantomData,
    })
}

/// Effect values of a fit, tied symbols and fixed companions included.
fn effect_values(
    fit: &bikedyn_runtime::identify::CandidateFit,
    values: &[f64],
    cands: &[Candidate],
) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    for (p, v) in fit.parameters.iter().zip(values) {
        m.insert(p.symbol.clone(), *v);
        for t in &p.tied {
            m.insert(t.clone(), *v);
        }
    }
    for c in cands.iter().filter(|c| fit.effects.contains(&c.name)) {
        for (s, v) in &c.fixed {
            m.insert(s.clone(), *v);
        }
    }
    m
}

/// Mean absolute rate of a sampled angle (rad/s).
fn mean_abs_rate(t: &[f64], x: &[f64]) -> f64 {
    let d: Vec<f64> = t
        .windows(2)
        .zip(x.windows(2))
        .filter(|(a, _)| a[1] > a[0])
        .map(|(a, b)| ((b[1] - b[0]) / (a[1] - a[0])).abs())
        .collect();
    d.iter().sum::<f64>() / d.len().max(1) as f64
}
