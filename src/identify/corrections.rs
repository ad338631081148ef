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
//!
//! Besides the model's own parameters, the quantities of the bicycle file
//! that the model holds in several parameters are corrected as a whole
//! ([`FILE_QUANTITIES`]): the front assembly's mass centre. The thesis
//! model splits it between the steer-axis point `(x4, z4)`, the front
//! wheel centre from that point `(x5, z5)` and the offset from the axis
//! `d4`, so a correction of `z4` alone would also move the steering
//! geometry. A correction of `zH` moves those parameters together along the
//! tangent of the file's conversion (the steer axis and the wheels stay
//! where they are), and the predictions and `fitted.toml` apply it through
//! the exact conversion.

use super::error::IdentifyError;
use super::predict::predict;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::{Candidate, EffectParameter, Segment};
use bikedyn_runtime::model::unit_of;
use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry};
use std::collections::BTreeMap;

/// Quantities of the bicycle file (benchmark symbols; x forward, z down,
/// from the rear contact point) corrected as a whole: the handlebar and
/// fork assembly's mass centre, with the models' default uncertainty of a
/// mass-centre coordinate unless the file gives one.
pub const FILE_QUANTITIES: [&str; 2] = ["xH", "zH"];

/// Standard deviation of a mass-centre coordinate when the file gives none
/// (m), as the models declare for theirs.
const MASS_CENTRE_SD: f64 = 0.02;

/// The model parameters that a file quantity moves, with the coefficients
/// of the tangent of the file's conversion (central differences of 0.1 mm),
/// when the model has all of them and they are more than one (a quantity
/// held in one parameter is that parameter's own correction).
pub fn moves_of<R: ModelRegistry>(free: &ModelInfo, bike: &Bicycle<R>, symbol: &str) -> Option<Vec<(String, f64)>> {
    const H: f64 = 1e-4;
    let v0 = bike.value(symbol)?;
    let up = bike.with_parameter(symbol, v0 + H).ok()?.thesis().ok()?;
    let down = bike.with_parameter(symbol, v0 - H).ok()?.thesis().ok()?;
    let mut out = Vec::new();
    for s in ThesisParameters::SYMBOLS {
        let c = (up.get(s)? - down.get(s)?) / (2.0 * H);
        if c.abs() > 1e-9 {
            free.parameter(s)?;
            out.push((s.to_string(), c));
        }
    }
    (out.len() > 1).then_some(out)
}

/// A parameter correction, with what it could explain on the base model.
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
    /// For a quantity of the file ([`FILE_QUANTITIES`]), the model
    /// parameters it moves and their coefficients; empty for a model
    /// parameter.
    pub moves: Vec<(String, f64)>,
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
/// and return every correction, ordered by the misfit it could explain
/// within its prior on the base model, best first, at most `max` of them
/// (`None`: all).
///
/// The order is no verdict: a correction that explains little of the base
/// model's weave misfit may explain much once an effect is in the model
/// (or on the kicks' time series rather than their eigenvalues), and each
/// step's score test judges every candidate again at the current fit. On
/// an oracle set with the rear frame's roll inertia 25 % high, a gate of
/// one unit here kept `correct I3x` (0.7) from ever being tried.
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
    // (symbol, value, prior sd, whether the file gave it, moved parameters)
    let mut quantities: Vec<(String, f64, f64, bool, Vec<(String, f64)>)> = Vec::new();
    for info in free.parameters.iter().filter(|p| p.effect.is_none()) {
        let (Some(u), Some(value)) = (info.uncertainty, bike.value(info.name)) else {
            continue;
        };
        let file_sd = bike.file_uncertainty(info.name);
        let sd = file_sd.unwrap_or_else(|| u.sigma(value));
        if !(sd > 0.0) || driven.parameter(info.name).is_none() {
            continue;
        }
        quantities.push((info.name.to_string(), value, sd, file_sd.is_some(), Vec::new()));
    }
    for symbol in FILE_QUANTITIES {
        let (Some(value), Some(moves)) = (bike.value(symbol), moves_of(free, bike, symbol)) else {
            continue;
        };
        if moves.iter().any(|(s, _)| driven.parameter(s).is_none()) {
            continue;
        }
        let file_sd = bike.file_uncertainty(symbol);
        quantities.push((
            symbol.to_string(),
            value,
            file_sd.unwrap_or(MASS_CENTRE_SD),
            file_sd.is_some(),
            moves,
        ));
    }
    for (symbol, value, sd, from_file, moves) in quantities {
        let moved = match predict(driven, bike, &BTreeMap::from([(symbol.clone(), value + sd)]), &speeds) {
            Ok(m) => m,
            // A file quantity one deviation away may not convert (a mass
            // centre below the ground): it is then no candidate.
            Err(_) if !moves.is_empty() => continue,
            Err(e) => return Err(e),
        };
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
        out.push(Screened {
            symbol,
            value,
            sd,
            from_file,
            reduction,
            moves,
        });
    }
    out.sort_by(|a, b| b.reduction.total_cmp(&a.reduction));
    out.truncate(max.unwrap_or(usize::MAX));
    Ok(out)
}

/// The candidate of a screened correction.
/// Whether a parameter is physical only when positive: a mass (kg) or a
/// principal moment of inertia (kg m^2; `I3x`, `IBxx`; not a product such
/// as `I3zx` or `IBxz`, whose sign is free).
pub fn positive_quantity(symbol: &str, unit: &str) -> bool {
    let axes: Vec<char> = symbol.chars().rev().take_while(|c| c.is_ascii_lowercase()).collect();
    match unit {
        "kg" => true,
        "kg m^2" => !axes.is_empty() && axes.iter().all(|&a| a == axes[0]),
        _ => false,
    }
}

pub fn candidate(free: &ModelInfo, c: &Screened) -> Candidate {
    // A model parameter's doc, or the file quantity's description.
    let doc = free
        .parameter(&c.symbol)
        .map(|p| p.doc)
        .or_else(|| BenchmarkParameters::describe(&c.symbol))
        .unwrap_or("");
    let unit = unit_of(doc).unwrap_or_default().to_string();
    Candidate {
        name: correction_name(&c.symbol),
        effects: Vec::new(),
        parameters: vec![EffectParameter {
            symbol: c.symbol.clone(),
            tied: Vec::new(),
            moves: c.moves.clone(),
            scale: c.sd,
            // A mass or a principal moment of inertia below zero is no
            // bicycle: such a fit is refused as not physical (it absorbs
            // something the library lacks).
            dissipative: positive_quantity(&c.symbol, &unit),
            unit: unit.clone(),
            initial: Some(c.value),
            lower: None,
            upper: None,
            shape: false,
            prior: Some((c.value, c.sd)),
            gross_beyond: bikedyn_runtime::identify::PLAUSIBLE_PRIOR_SDS,
        }],
        fixed: Vec::new(),
        speed_decay: false,
        reason: format!(
            "{}{} = {:.4} {unit}, known to +/- {:.3} {unit} ({}): within that, it could explain a \
             weighted weave-eigenvalue misfit of {:.1}",
            if c.moves.is_empty() {
                String::new()
            } else {
                let moved: Vec<&str> = c.moves.iter().map(|(s, _)| s.as_str()).collect();
                let what = doc.rsplit_once(" (").map_or(doc, |(w, _)| w);
                format!(
                    "the file's {what} (moving {} together, the steer axis kept): ",
                    moved.join(", ")
                )
            },
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
        nonsmooth: false,
    }
}
