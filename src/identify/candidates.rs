//! What identification tests: the models it runs through (chosen by
//! capability) and the candidate effects, from the declarations in the
//! effect files.

use super::error::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::{Candidate, EffectParameter};
use bikedyn_runtime::model::{unit_of, CandidateDeclaration, EffectIdentification, LinearEquivalent};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry};
use std::collections::BTreeMap;

/// The identification model, its driven twin, and the alternative model
/// (free speed, with states: the tyre model) if the registry has one. Each is
/// chosen by capability among the models of the bicycle's registry: it can
/// represent the bicycle (has every parameter the bicycle sets) and carries
/// the most effects.
///
/// With `speed_imposed` (logs of a bicycle whose hub motor holds the speed)
/// the fits run through the driven twin, and the alternative model is the
/// driven one with states.
pub fn identification_models<R: ModelRegistry>(
    bike: &Bicycle<R>,
    speed_imposed: bool,
) -> Result<(&'static ModelInfo, &'static ModelInfo, Option<&'static ModelInfo>), IdentifyError> {
    let nonzero = bike.nonzero_parameters()?;
    let (free, driven) = identification_model_pair(bike)?;
    let fitted = if speed_imposed { driven } else { free };
    // With a `[feedback]` controller, no model with extra states: its
    // linear equations (the weave predictions) have no `M, C, K` to close
    // the loop on.
    let alt = R::models()
        .iter()
        .filter(|_| bike.feedback.is_none())
        .filter(|m| {
            m.free_speed == !speed_imposed
                && !m.states.is_empty()
                && crate::models::fits(m, &nonzero)
                && free
                    .effects
                    .iter()
                    .filter(|e| **e != DICTIONARY_EFFECT)
                    .all(|e| m.effects.contains(e))
        })
        .max_by_key(|m| m.effects.len());
    Ok((fitted, driven, alt))
}

/// The free-speed model without extra states that can represent the
/// bicycle, carries the effect parameters its file names and then the most
/// effects (every candidate of the library on every geometry), and its
/// driven-speed twin (same effects).
fn identification_model_pair<R: ModelRegistry>(
    bike: &Bicycle<R>,
) -> Result<(&'static ModelInfo, &'static ModelInfo), IdentifyError> {
    let nonzero = bike.nonzero_parameters()?;
    // An effect the bicycle file names, even at zero (to be fitted from
    // there), asks for the models that carry it: a registry may hold
    // several effects no built-in model has.
    let named = |m: &ModelInfo| bike.effects.keys().filter(|k| m.parameter(k).is_some()).count();
    let free = R::models()
        .iter()
        .filter(|m| m.free_speed && m.states.is_empty() && crate::models::fits(m, &nonzero))
        .max_by_key(|m| (named(m), m.effects.len()))
        .ok_or_else(|| IdentifyError::NoFreeSpeedModel {
            bicycle: bike.name.clone(),
        })?;
    let driven = R::models()
        .iter()
        .find(|m| !m.free_speed && m.effects == free.effects && crate::models::fits(m, &nonzero))
        .ok_or(IdentifyError::NoDrivenTwin { model: free.name })?;
    Ok((free, driven))
}

/// The candidates for a model: every effect it carries whose effect file
/// declares it a candidate (and is in `only` when given), with what its
/// declaration says: fitted parameters, ties, floors, held companions,
/// speed decay and the reason. An effect declared "own model" (tyre slip)
/// comes from the alternative model `alt`.
///
/// Not candidates: an effect whose fitted parameters the bicycle file sets
/// (a controller declared with its gains is a known input of the
/// experiment, not something to find), and, with `speed_imposed`, the
/// speed-decay effects (the motor replaces what they would dissipate).
pub fn candidates<R: ModelRegistry>(
    info: &ModelInfo,
    alt: Option<&ModelInfo>,
    bike: &Bicycle<R>,
    only: &[String],
    speed_imposed: bool,
) -> Result<Vec<Candidate>, IdentifyError> {
    let declared = |m: &ModelInfo| -> Vec<(&'static str, CandidateDeclaration)> {
        m.effect_declarations
            .iter()
            .filter_map(|e| match e.identification {
                Some(EffectIdentification::Candidate(c)) => Some((e.name, c)),
                _ => None,
            })
            .collect()
    };
    let mut pool: Vec<(&ModelInfo, &'static str, CandidateDeclaration)> = declared(info)
        .into_iter()
        .filter(|(_, c)| !c.own_model)
        .map(|(n, c)| (info, n, c))
        .collect();
    if let Some(a) = alt {
        pool.extend(
            declared(a)
                .into_iter()
                .filter(|(_, c)| c.own_model)
                .map(|(n, c)| (a, n, c)),
        );
    }
    for o in only {
        if !pool.iter().any(|(_, n, _)| n == o) {
            return Err(IdentifyError::NotACandidate {
                effect: o.clone(),
                known: pool.iter().map(|(_, n, _)| *n).collect(),
            });
        }
    }
    let mut out = Vec::new();
    for (info, effect, d) in pool {
        if !(only.is_empty() || only.iter().any(|o| o == effect)) {
            continue;
        }
        // Its size, not the shape of its law (a friction's smoothing rate),
        // says whether the file declares the effect.
        let declared_by_bike = d
            .fitted
            .iter()
            .filter(|f| !f.shape)
            .any(|f| bike.effects.get(f.symbol).is_some_and(|&v| v != 0.0));
        if declared_by_bike || (speed_imposed && d.speed_decay) {
            // Asked for by name, it is not dropped without a word.
            if only.iter().any(|o| o == effect) {
                return Err(IdentifyError::ExcludedCandidate {
                    effect: effect.to_string(),
                    reason: if declared_by_bike {
                        format!(
                            "the bicycle `{}` sets its parameters (a known input of the experiment, not something to find)",
                            bike.name
                        )
                    } else {
                        "the runs' speed is imposed (a motor held it), so a loss of speed has nothing to explain"
                            .to_string()
                    },
                });
            }
            continue;
        }
        let unit = |sym: &str| {
            info.parameter(sym)
                .and_then(|p| unit_of(p.doc))
                .unwrap_or_default()
                .to_string()
        };
        out.push(Candidate {
            name: effect.to_string(),
            effects: vec![effect.to_string()],
            parameters: d
                .fitted
                .iter()
                .map(|f| EffectParameter {
                    symbol: f.symbol.to_string(),
                    tied: f.tied.iter().map(|t| t.to_string()).collect(),
                    moves: Vec::new(),
                    scale: f.scale,
                    dissipative: f.dissipative,
                    unit: unit(f.symbol),
                    initial: if f.shape {
                        bike.value(f.symbol)
                    } else if f.start_at_default {
                        info.parameter(f.symbol).and_then(|p| p.default)
                    } else {
                        None
                    },
                    lower: f.floor,
                    upper: f.ceiling,
                    shape: f.shape,
                    prior: None,
                    gross_beyond: bikedyn_runtime::identify::PLAUSIBLE_PRIOR_SDS,
                })
                .collect(),
            fixed: d
                .held
                .iter()
                .filter_map(|sym| bike.value(sym).map(|v| (sym.to_string(), v)))
                .collect(),
            speed_decay: d.speed_decay,
            reason: d.reason.to_string(),
            alternative_model: d.own_model,
            nonsmooth: matches!(
                d.linear_equivalent,
                Some(LinearEquivalent::DescribingFunctionDamping { .. })
            ),
        });
    }
    Ok(out)
}

/// Effects a model carries that identification never tests, with the
/// reason their files give (or that they declare nothing).
pub fn not_candidates(info: &ModelInfo) -> Vec<(&'static str, String)> {
    info.effect_declarations
        .iter()
        .filter_map(|e| match e.identification {
            Some(EffectIdentification::Candidate(_)) => None,
            Some(EffectIdentification::OptOut(why)) => Some((e.name, why.to_string())),
            None => Some((e.name, "its effect file declares no identification".to_string())),
        })
        .collect()
}

/// The effect that carries the dictionary in the derived models.
pub const DICTIONARY_EFFECT: &str = "generalized_forces";

/// The values of a candidate set's parameters (tied symbols and held
/// companions included) by symbol.
pub(super) fn values_map(set: &[&Candidate], values: &[f64]) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    let mut it = values.iter();
    for c in set {
        for (s, v) in &c.fixed {
            m.insert(s.clone(), *v);
        }
        for p in &c.parameters {
            let v = *it.next().unwrap_or(&0.0);
            let v = p.lower.map_or(v, |lo| v.max(lo));
            m.insert(p.symbol.clone(), v);
            for t in &p.tied {
                m.insert(t.clone(), v);
            }
        }
    }
    m
}
