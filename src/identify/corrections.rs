//! Parameter corrections as candidates. A measured bicycle's parameters are
//! uncertain (inertias from pendulum swings, mass centres from hanging), so
//! a residual may come from a parameter error rather than a missing effect.
//! Every parameter whose model file declares an uncertainty may be
//! corrected, fitted with its uncertainty (the bicycle file's `+/-` where
//! it gives one, propagated to the model's parameters; else the model's
//! default for the parameter's kind) as a Gaussian prior so that it
//! moves only as far as the data demand; effects and corrections then
//! compete on the same footing (information criterion, cross-validation).
//!
//! Fitting every correction through the nonlinear simulation would cost a
//! full fit per parameter and step, so they are screened first on the
//! measured weave eigenvalues: the linear model's weave moves by `s_j`
//! (in standard errors of each measured eigenvalue) when parameter `j`
//! moves by one prior standard deviation, and the eigenvalue misfit `r`
//! falls by at most `(s_j . r)^2 / (s_j . s_j + 1)` when only `j` moves (the
//! `+1` is the prior). The corrections that explain most of the misfit this
//! way are the candidates.

use super::error::IdentifyError;
use super::predict::predict;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::{Candidate, EffectParameter, Segment};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry};
use std::collections::BTreeMap;

/// A parameter correction that passed the screen.
#[derive(Clone, Debug)]
pub struct Screened {
    /// Model parameter symbol.
    pub symbol: String,
    /// Its value in the bicycle and the prior standard deviation.
    pub value: f64,
    pub sd: f64,
    /// Whether `sd` comes from the bicycle file's `+/-` (else the model's
    /// default for the parameter's kind).
    pub from_file: bool,
    /// Largest fall of the weighted eigenvalue misfit (chi^2) it can give.
    pub reduction: f64,
}

/// The candidate name of a correction of parameter `symbol`.
pub fn correction_name(symbol: &str) -> String {
    format!("correct {symbol}")
}

/// The parameter a candidate corrects, if it is a correction.
pub fn corrected_parameter(candidate: &str) -> Option<&str> {
    candidate.strip_prefix("correct ")
}

/// Screen the declared-uncertain parameters of `free` (the identification
/// model) on the measured weave eigenvalues of `segments` against the
/// prediction of `driven` (`before`: its weave at each segment's speed),
/// and return the corrections whose possible misfit reduction is at least
/// one (one prior standard deviation's worth), best first, at most `max`
/// of them (`None`: all).
pub fn screen<R: ModelRegistry>(
    free: &ModelInfo,
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    segments: &[Segment],
    before: &[Option<[f64; 2]>],
    max: Option<usize>,
) -> Result<Vec<Screened>, IdentifyError> {
    if max == Some(0) {
        return Ok(Vec::new());
    }
    let rows: Vec<(f64, [f64; 2], [f64; 2], Option<[f64; 2]>)> = segments
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let (m, se) = s.weave?;
            Some((s.mean_speed, m, se, before.get(i).copied().flatten()))
        })
        .collect();
    screen_points(free, driven, bike, &rows, max)
}

/// [`screen`] on measured weave eigenvalues given as rows `(speed, measured
/// [re, im], standard errors, predicted)` (a table of published eigenvalues,
/// or the kicks of a set).
pub fn screen_points<R: ModelRegistry>(
    free: &ModelInfo,
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    rows: &[(f64, [f64; 2], [f64; 2], Option<[f64; 2]>)],
    max: Option<usize>,
) -> Result<Vec<Screened>, IdentifyError> {
    if max == Some(0) {
        return Ok(Vec::new());
    }
    // Measured eigenvalues with their standard errors, where both the fit
    // and the prediction exist.
    let used: Vec<(usize, [f64; 2], [f64; 2], [f64; 2])> = rows
        .iter()
        .enumerate()
        .filter_map(|(i, &(_, m, se, p))| {
            let p = p?;
            let ok = se.iter().all(|e| e.is_finite() && *e > 0.0);
            ok.then_some((i, m, se, p))
        })
        .collect();
    if used.is_empty() {
        return Ok(Vec::new());
    }
    let speeds: Vec<f64> = used.iter().map(|&(i, ..)| rows[i].0).collect();
    let r: Vec<f64> = used
        .iter()
        .flat_map(|&(_, m, se, p)| [(m[0] - p[0]) / se[0], (m[1] - p[1]) / se[1]])
        .collect();
    let mut out = Vec::new();
    for info in free.parameters.iter().filter(|p| p.effect.is_none()) {
        let (Some(u), Some(value)) = (info.uncertainty, bike.value(info.name)) else {
            continue;
        };
        let file_sd = bike.file_uncertainty(info.name);
        let sd = file_sd.unwrap_or_else(|| u.sigma(value));
        if !(sd > 0.0) || driven.parameter(info.name).is_none() {
            continue;
        }
        let moved = predict(
            driven,
            bike,
            &BTreeMap::from([(info.name.to_string(), value + sd)]),
            &speeds,
        )?;
        let mut s = Vec::with_capacity(r.len());
        for (k, &(_, _, se, p)) in used.iter().enumerate() {
            match moved[k] {
                Some(q) => s.extend([(q[0] - p[0]) / se[0], (q[1] - p[1]) / se[1]]),
                None => s.extend([0.0, 0.0]),
            }
        }
        let sr: f64 = s.iter().zip(&r).map(|(a, b)| a * b).sum();
        let ss: f64 = s.iter().map(|a| a * a).sum();
        let reduction = sr * sr / (ss + 1.0);
        if reduction >= 1.0 {
            out.push(Screened {
                symbol: info.name.to_string(),
                value,
                sd,
                from_file: file_sd.is_some(),
                reduction,
            });
        }
    }
    out.sort_by(|a, b| b.reduction.total_cmp(&a.reduction));
    out.truncate(max.unwrap_or(usize::MAX));
    Ok(out)
}

/// The candidate of a screened correction.
pub fn candidate(free: &ModelInfo, c: &Screened) -> Candidate {
    let doc = free.parameter(&c.symbol).map_or("", |p| p.doc);
    let unit = doc
        .rsplit_once('(')
        .map_or("", |(_, u)| u.trim_end_matches(')'))
        .to_string();
    Candidate {
        name: correction_name(&c.symbol),
        effects: Vec::new(),
        parameters: vec![EffectParameter {
            symbol: c.symbol.clone(),
            tied: Vec::new(),
            scale: c.sd,
            dissipative: false,
            unit: unit.clone(),
            initial: Some(c.value),
            lower: None,
            prior: Some((c.value, c.sd)),
        }],
        fixed: Vec::new(),
        speed_decay: false,
        reason: format!(
            "{} = {:.4} {unit}, known to +/- {:.3} {unit} ({}): within that, it could explain a \
             weighted weave-eigenvalue misfit of {:.1}",
            c.symbol,
            c.value,
            c.sd,
            if c.from_file {
                "the bicycle file's uncertainty"
            } else {
                "the model's default for its kind"
            },
            c.reduction
        ),
        alternative_model: false,
    }
}
