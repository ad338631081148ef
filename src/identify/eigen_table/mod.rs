//! `identify --eigenvalues FILE.csv`: effects and parameter corrections
//! fitted to a table of measured weave eigenvalues, where no time series
//! exists (published tables, a colleague's fits).
//!
//! The table: one row per speed, columns by position: speed (m/s), real
//! part (1/s), imaginary part (rad/s), and optionally the standard errors
//! of the real and imaginary parts. A first row that is not numbers is a
//! header in whatever words its authors chose; commas, semicolons, tabs or
//! spaces separate the fields; `#` starts a comment line.
//!
//! The residual of a row is measured minus predicted (the driven-speed
//! model's weave at the row's speed), divided by its standard errors (one
//! when the table gives none). Candidates are the effects with a
//! linearization (Coulomb friction needs the response's amplitude, which a
//! table does not give; speed decay has no weave) and the corrections of
//! the declared-uncertain parameters that could explain most of the misfit
//! (Gaussian priors as in the time-series fits). Selection is forward
//! stepwise as there: a candidate is kept if it lowers the BIC (unknown
//! residual scale: `n ln(chi2 / n) + k ln n`) and the leave-one-speed-out
//! error (each row predicted with the values fitted to the others).

use super::candidates::{candidates, identification_models, values_map};
use super::corrections;
use super::discovery::{discover_on_table, DiscoveryOutcome};
use super::predict::predict;
use super::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::discovery::Row;
use bikedyn_runtime::identify::least_squares::levenberg_marquardt;
use bikedyn_runtime::identify::remaining::{remaining, KickWeave, Remaining};
use bikedyn_runtime::identify::{Candidate, Verdict, PLAUSIBLE_PRIOR_SDS};
use bikedyn_runtime::model::{CandidateDeclaration, EffectIdentification, LinearEquivalent};
use bikedyn_runtime::registry::ModelInfo;
use serde::Serialize;

mod read;
mod report;
pub use super::result::EigenPoint;
use super::result::{
    estimates, CandidateTrial, Details, Errors, Estimate, FittedValue, HeldOutErrors, IdentifyResult, Source,
    TableDetails,
};
use super::words::verdict_text;
pub use read::read_eigen_table;
pub use report::{table_summary, write_table_report};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// What to identify from a table.
#[derive(Clone, Debug)]
pub struct TableRequest {
    /// The table.
    pub path: PathBuf,
    /// Bicycle (built-in name or parameter file).
    pub bike: String,
    /// Candidate effects (empty: every one with a linearization).
    pub effects: Vec<String>,
    /// Largest number of parameter corrections tried beside the effects
    /// (`None`: every one that could explain some of the misfit).
    pub corrections: Option<usize>,
    /// After the library, search the dictionary of generalized forces for
    /// what it leaves (`super::discovery`).
    pub discover: bool,
}

/// One candidate tried at one step.
#[derive(Clone, Debug, Serialize)]
pub struct TableTrial {
    pub step: usize,
    pub name: String,
    /// Fitted values by symbol, with standard errors.
    pub values: BTreeMap<String, (f64, f64)>,
    pub bic_change: f64,
    /// Leave-one-speed-out error (mean squared weighted residual).
    pub cv: f64,
    pub base_cv: f64,
    /// Why it was or was not selected, with its numbers (the held-out
    /// error is the leave-one-speed-out error); in JSON `outcome`, as the
    /// run-set reports name it.
    #[serde(rename = "outcome")]
    pub verdict: Verdict,
}

/// What identification from a table found. Its JSON is the
/// identification's one schema ([`IdentifyResult`], `source:
/// "eigenvalue_table"`).
#[derive(Clone, Debug, Serialize)]
#[serde(into = "IdentifyResult")]
pub struct TableOutcome {
    pub table: PathBuf,
    pub driven_model: &'static str,
    pub points: Vec<EigenPoint>,
    pub selected: Vec<String>,
    /// Fitted values by symbol.
    pub parameters: BTreeMap<String, Estimate>,
    pub trials: Vec<TableTrial>,
    /// Candidates not tried, with the reason.
    pub not_tried: Vec<(String, String)>,
    /// Weave eigenvalue per row, before and after (1/s).
    pub predicted_before: Vec<Option<[f64; 2]>>,
    pub predicted_after: Vec<Option<[f64; 2]>>,
    /// RMS |measured - predicted| (1/s), before and after; after held out
    /// (each row with the values fitted to the others).
    pub eigen_rms_before: f64,
    pub eigen_rms_after: f64,
    pub eigen_rms_held_out: f64,
    /// What the library leaves in the table: a pattern in speed beyond the
    /// rows' scatter, or none (`None`: too few rows).
    pub remaining: Option<Remaining>,
    /// What the dictionary of generalized forces found beyond the library
    /// (`None`: not requested).
    pub discovery: Option<DiscoveryOutcome>,
}

impl From<TableOutcome> for IdentifyResult {
    fn from(o: TableOutcome) -> Self {
        IdentifyResult::from(&o)
    }
}

impl From<&TableOutcome> for IdentifyResult {
    fn from(o: &TableOutcome) -> Self {
        let errors = |eigen_rms: f64, held: f64| Errors {
            eigen_rms,
            eigen_weighted_rms: None,
            median_run_roll_rms: None,
            median_run_steer_rms: None,
            roll_rms: None,
            steer_rms: None,
            speed_rms: None,
            held_out: HeldOutErrors {
                eigen_rms: held,
                eigen_weighted_rms: None,
                roll_rms: None,
                steer_rms: None,
                speed_rms: None,
            },
            per_run: Vec::new(),
        };
        let mut base: Vec<String> = Vec::new();
        let mut candidates = Vec::new();
        let mut step = 0;
        for t in &o.trials {
            if t.step != step {
                step = t.step;
                base = o.selected[..(step - 1).min(o.selected.len())].to_vec();
            }
            candidates.push(CandidateTrial {
                step: t.step,
                name: t.name.clone(),
                members: vec![t.name.clone()],
                extends: base.clone(),
                score: Some(t.bic_change).filter(|x| x.is_finite()),
                predicted_score: None,
                cv: Some(t.cv).filter(|x| x.is_finite()),
                base_cv: t.base_cv,
                values: Some(
                    t.values
                        .iter()
                        .map(|(s, &(value, stderr))| FittedValue {
                            symbol: s.clone(),
                            value,
                            stderr,
                        })
                        .collect(),
                ),
                selected: t.verdict.added(),
                outcome: t.verdict.clone(),
                verdict: verdict_text(&t.verdict),
            });
        }
        IdentifyResult {
            source: Source::EigenvalueTable,
            selected_effects: o.selected.clone(),
            parameters: o.parameters.clone(),
            candidates,
            error_before: errors(o.eigen_rms_before, o.eigen_rms_before),
            error_after: errors(o.eigen_rms_after, o.eigen_rms_held_out),
            driven_model: o.driven_model,
            remaining: o.remaining.clone(),
            discovery: o.discovery.clone(),
            details: Details::Table(TableDetails {
                table: o.table.clone(),
                points: o.points.clone(),
                not_tried: o.not_tried.clone(),
                predicted_before: o.predicted_before.clone(),
                predicted_after: o.predicted_after.clone(),
            }),
        }
    }
}

struct Fit {
    values: Vec<f64>,
    stderr: Vec<f64>,
    chi2: f64,
}

/// The most folds of a table's cross-validation: tables up to this many
/// rows leave one row out at a time; longer ones are split into this many
/// folds.
pub const MAX_TABLE_FOLDS: usize = 10;

/// Identify effects and corrections from a measured eigenvalue table.
pub fn identify_table(req: &TableRequest) -> Result<TableOutcome, IdentifyError> {
    identify_table_in::<crate::registry::BuiltIn>(req)
}

/// [`identify_table`] with the models of registry `R` (a user's crate with
/// effects of its own, such as an effect file that identify wrote).
pub fn identify_table_in<R: bikedyn_runtime::registry::ModelRegistry>(
    req: &TableRequest,
) -> Result<TableOutcome, IdentifyError> {
    let points = read_eigen_table(&req.path)?;
    let bike = Bicycle::<R>::resolve_in(&req.bike)?;
    let (_, driven, _) = identification_models(&bike, false)?;
    let mut not_tried: Vec<(String, String)> = Vec::new();
    let mut cands: Vec<Candidate> = Vec::new();
    for c in candidates(driven, None, &bike, &req.effects, true)? {
        if needs_amplitude(driven, &c.name) {
            not_tried.push((
                c.name.clone(),
                "its linear equivalent depends on the response's amplitude, which a table does not give".into(),
            ));
        } else {
            cands.push(c);
        }
    }
    // An effect named on the command line that a table cannot try is an
    // error, not a silent "not tried" beside a conclusion about the others.
    if let Some((effect, reason)) = not_tried.iter().find(|(n, _)| req.effects.contains(n)) {
        return Err(IdentifyError::NotTriableFromTable {
            effect: effect.clone(),
            reason: reason.clone(),
            triable: candidates(driven, None, &bike, &[], true)?
                .into_iter()
                .filter(|c| !needs_amplitude(driven, &c.name))
                .map(|c| c.name)
                .collect(),
        });
    }
    let speeds: Vec<f64> = points.iter().map(|p| p.speed).collect();
    let before = predict(driven, &bike, &BTreeMap::new(), &speeds)?;
    // Corrections: the same screen as for time series, on the rows.
    let se = |p: &EigenPoint| p.stderr.unwrap_or([1.0, 1.0]);
    let rows: Vec<(f64, [f64; 2], [f64; 2], Option<[f64; 2]>)> = points
        .iter()
        .zip(&before)
        .map(|(p, b)| (p.speed, p.eigenvalue, se(p), *b))
        .collect();
    for s in corrections::screen_points(driven, driven, &bike, &rows, req.corrections)? {
        cands.push(corrections::candidate(driven, &s));
    }
    let residuals = |vals: &BTreeMap<String, f64>, idx: &[usize]| -> Result<Vec<f64>, IdentifyError> {
        let sp: Vec<f64> = idx.iter().map(|&i| speeds[i]).collect();
        let pred = predict(driven, &bike, vals, &sp)?;
        let mut r = Vec::with_capacity(2 * idx.len());
        for (&i, p) in idx.iter().zip(pred) {
            let (m, s) = (points[i].eigenvalue, se(&points[i]));
            // No weave predicted: as far off as the measured eigenvalue's size.
            let p = p.unwrap_or([m[0] + m[1].abs(), 0.0]);
            r.extend([(m[0] - p[0]) / s[0], (m[1] - p[1]) / s[1]]);
        }
        Ok(r)
    };
    let all: Vec<usize> = (0..points.len()).collect();
    let n = 2.0 * points.len() as f64;
    let bic = |chi2: f64, k: usize| n * (chi2 / n).max(1e-300).ln() + k as f64 * n.ln();
    let chi2_of = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    // Held-out rows: each row predicted with the values fitted to the rows
    // of the other folds. Up to MAX_TABLE_FOLDS rows this is leave one speed
    // out; beyond, rows are dealt to that many folds in turn, so the cost
    // grows with the rows rather than with their square (leaving each of 300
    // rows out took over 300 s).
    let folds = points.len().min(MAX_TABLE_FOLDS);
    let held_out = |set: &[&Candidate]| -> Result<(f64, Vec<Option<[f64; 2]>>), IdentifyError> {
        let mut ss = vec![0.0; points.len()];
        let mut held = vec![None; points.len()];
        for fold in 0..folds {
            let (test, train): (Vec<usize>, Vec<usize>) = all.iter().partition(|&&j| j % folds == fold);
            let vals = if set.is_empty() {
                BTreeMap::new()
            } else {
                values_map(set, &fit(set, &|v| residuals(v, &train))?.values)
            };
            let test_speeds: Vec<f64> = test.iter().map(|&i| speeds[i]).collect();
            let predicted = predict(driven, &bike, &vals, &test_speeds)?;
            for (&i, p) in test.iter().zip(predicted) {
                ss[i] = chi2_of(&residuals(&vals, &[i])?) / 2.0;
                held[i] = p;
            }
        }
        Ok((ss.iter().sum::<f64>() / ss.len() as f64, held))
    };
    let mut selected: Vec<&Candidate> = Vec::new();
    let mut current_chi2 = chi2_of(&residuals(&BTreeMap::new(), &all)?);
    let mut current_bic = bic(current_chi2, 0);
    let (mut current_cv, mut held_pred) = held_out(&[])?;
    let mut current_fit = Fit {
        values: vec![],
        stderr: vec![],
        chi2: current_chi2,
    };
    let mut trials = Vec::new();
    for step in 1..=3 {
        let mut best: Option<(usize, Fit, f64, f64, Vec<Option<[f64; 2]>>)> = None;
        let mut best_implausible: Option<(usize, Fit, f64, f64, Vec<Option<[f64; 2]>>)> = None;
        for (ci, c) in cands.iter().enumerate() {
            if selected.iter().any(|s| s.name == c.name) {
                continue;
            }
            let set: Vec<&Candidate> = selected.iter().copied().chain([c]).collect();
            let f = fit(&set, &|v| residuals(v, &all))?;
            let k: usize = set.iter().map(|c| c.parameters.len()).sum();
            let db = bic(f.chi2, k) - current_bic;
            let physical = set
                .iter()
                .flat_map(|c| &c.parameters)
                .zip(&f.values)
                .all(|(p, v)| !p.dissipative || *v > p.lower.unwrap_or(0.0));
            let (cv, held) = if physical && db < 0.0 {
                held_out(&set)?
            } else {
                (f64::NAN, vec![])
            };
            // A correction further from its measured value than
            // PLAUSIBLE_PRIOR_SDS of its uncertainty more likely absorbs
            // what the library lacks (the discovery's business): as in the
            // runs' search, it is added only when no plausible candidate
            // passes the step.
            let farthest = set
                .iter()
                .flat_map(|c| &c.parameters)
                .zip(&f.values)
                .filter_map(|(p, v)| p.prior.map(|(m, sd)| (p.symbol.clone(), *v, (v - m).abs() / sd)))
                .max_by(|a, b| a.2.total_cmp(&b.2))
                .filter(|far| far.2 > PLAUSIBLE_PRIOR_SDS);
            // A candidate that passes is `Added` until the step's best is
            // known (below).
            let verdict = if !physical {
                Verdict::NotPhysical
            } else if db >= 0.0 {
                Verdict::NoCriterionGain { bic_change: db }
            } else if !(cv < current_cv) {
                Verdict::HeldOutNotLower {
                    cv,
                    base_cv: current_cv,
                }
            } else if let Some((symbol, value, prior_sds)) = farthest.clone() {
                Verdict::ImplausibleUnderPrior {
                    symbol,
                    value,
                    prior_sds,
                }
            } else {
                Verdict::Added {
                    bic_change: db,
                    cv,
                    base_cv: current_cv,
                    held_out_gain: None,
                }
            };
            let names = set.iter().flat_map(|c| c.parameters.iter().map(|p| p.symbol.clone()));
            trials.push(TableTrial {
                step,
                name: c.name.clone(),
                values: names
                    .zip(f.values.iter().zip(&f.stderr).map(|(v, s)| (*v, *s)))
                    .collect(),
                bic_change: db,
                cv,
                base_cv: current_cv,
                verdict,
            });
            let passes = physical && db < 0.0 && cv < current_cv;
            let slot = if farthest.is_some() {
                &mut best_implausible
            } else {
                &mut best
            };
            if passes && slot.as_ref().is_none_or(|b| db < b.2) {
                *slot = Some((ci, f, db, cv, held));
            }
        }
        if best.is_none() {
            best = best_implausible;
        }
        let Some((ci, f, db, cv, held)) = best else { break };
        // The step's other passing candidates came after the best in the
        // order of the criterion.
        for t in trials.iter_mut().filter(|t| t.step == step && t.name != cands[ci].name) {
            if let Verdict::Added { bic_change, .. } = t.verdict {
                t.verdict = Verdict::CriterionAboveAdded {
                    bic_change,
                    added: cands[ci].name.clone(),
                };
            }
        }
        // A correction beyond its prior added because no plausible
        // candidate passed.
        if let Some(t) = trials.iter_mut().find(|t| t.step == step && t.name == cands[ci].name) {
            if matches!(t.verdict, Verdict::ImplausibleUnderPrior { .. }) {
                t.verdict = Verdict::Added {
                    bic_change: db,
                    cv,
                    base_cv: current_cv,
                    held_out_gain: None,
                };
            }
        }
        selected.push(&cands[ci]);
        current_bic += db;
        current_cv = cv;
        current_chi2 = f.chi2;
        held_pred = held;
        current_fit = f;
    }
    let _ = current_chi2;
    let vals = values_map(&selected, &current_fit.values);
    let after = predict(driven, &bike, &vals, &speeds)?;
    let rms = |pred: &[Option<[f64; 2]>]| {
        let d: Vec<f64> = points
            .iter()
            .zip(pred)
            .filter_map(|(p, q)| q.map(|q| (p.eigenvalue[0] - q[0]).powi(2) + (p.eigenvalue[1] - q[1]).powi(2)))
            .collect();
        (d.iter().sum::<f64>() / d.len().max(1) as f64).sqrt()
    };
    let held_pred = if selected.is_empty() { before.clone() } else { held_pred };
    // What the library leaves: the rows' residuals against their scatter
    // about a pattern in speed (a table gives no amplitudes).
    let remaining = remaining(
        &points
            .iter()
            .enumerate()
            .filter_map(|(i, p)| {
                Some(KickWeave {
                    speed: speeds[i],
                    amplitude: None,
                    measured: p.eigenvalue,
                    base: before[i]?,
                    after: after[i]?,
                    held_out: held_pred[i]?,
                })
            })
            .collect::<Vec<_>>(),
    );
    let discovery = if let (true, Some(why)) = (req.discover, super::discovery::not_warranted(remaining.as_ref())) {
        Some(why)
    } else if req.discover {
        let rows: Vec<Row> = points
            .iter()
            .map(|p| Row {
                speed: p.speed,
                measured: p.eigenvalue,
                stderr: se(p),
            })
            .collect();
        // The library's result stands whatever the search meets.
        Some(
            discover_on_table(driven, &bike, &rows, &selected, &current_fit.values, folds)
                .unwrap_or_else(|e| DiscoveryOutcome::NotRun { reason: e.to_string() }),
        )
    } else {
        None
    };
    let parameters = estimates(
        selected.iter().flat_map(|c| c.parameters.iter()),
        &current_fit.values,
        &current_fit.stderr,
    );
    Ok(TableOutcome {
        discovery,
        table: req.path.clone(),
        driven_model: driven.name,
        selected: selected.iter().map(|c| c.name.clone()).collect(),
        parameters,
        trials,
        not_tried,
        eigen_rms_before: rms(&before),
        eigen_rms_after: rms(&after),
        eigen_rms_held_out: rms(&held_pred),
        remaining,
        predicted_before: before,
        predicted_after: after,
        points,
    })
}

/// Whether an effect's linear equivalent needs the response's amplitude.
fn needs_amplitude(info: &ModelInfo, effect: &str) -> bool {
    info.effect_declarations.iter().any(|e| {
        e.name == effect
            && matches!(
                e.identification,
                Some(EffectIdentification::Candidate(CandidateDeclaration {
                    linear_equivalent: Some(LinearEquivalent::DescribingFunctionDamping { .. }),
                    ..
                }))
            )
    })
}

/// Levenberg-Marquardt over the parameters of `set` (a few), with their
/// priors as extra residual rows; forward-difference Jacobian (a
/// prediction costs microseconds; `least_squares`). Standard errors from
/// `(J^T J)^-1 s^2`.
fn fit(
    set: &[&Candidate],
    residuals: &dyn Fn(&BTreeMap<String, f64>) -> Result<Vec<f64>, IdentifyError>,
) -> Result<Fit, IdentifyError> {
    let params: Vec<_> = set.iter().flat_map(|c| c.parameters.iter()).collect();
    let k = params.len();
    let eval = |x: &[f64]| -> Result<Vec<f64>, IdentifyError> {
        let mut r = residuals(&values_map(set, x))?;
        for (p, v) in params.iter().zip(x) {
            if let Some((m, sd)) = p.prior {
                r.push((v - m) / sd);
            }
        }
        Ok(r)
    };
    let x0: Vec<f64> = params
        .iter()
        .map(|p| p.prior.map(|(m, _)| m).or(p.initial).unwrap_or(0.1 * p.scale))
        .collect();
    let scales: Vec<f64> = params.iter().map(|p| p.scale).collect();
    let cost = |r: &[f64]| r.iter().map(|a| a * a).sum::<f64>();
    let f = levenberg_marquardt(x0, &scales, 1e-6, &eval)?;
    let x = f.x;
    let data = residuals(&values_map(set, &x))?;
    let n_data = data.len();
    let chi2 = cost(&data);
    let s2 = chi2 / (n_data as f64 - k as f64).max(1.0);
    let stderr = match f.jacobian.tr_mul(&f.jacobian).try_inverse() {
        Some(inv) => (0..k).map(|i| (inv[(i, i)] * s2).sqrt()).collect(),
        None => vec![f64::NAN; k],
    };
    let values = params
        .iter()
        .zip(&x)
        .map(|(p, &v)| p.lower.map_or(v, |lo| v.max(lo)))
        .collect();
    Ok(Fit { values, stderr, chi2 })
}
