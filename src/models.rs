//! Generic operations on the generated models, through the registry (no
//! model is named here): default parameters, verification, listing.

use crate::generated::{with_model, MODELS};
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::model::ParameterInfo;
use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn_runtime::registry::{ModelInfo, ModelVisitor};
use bikedyn_runtime::verify::{verify, with_effects_switched_on, VerifyOptions, VerifyReport};
use bikedyn_runtime::MultibodyModel;

/// The built-in bicycles' parameters (thesis form) by name.
pub fn built_in_thesis_parameters() -> [(&'static str, ThesisParameters); 2] {
    [
        ("thesis", ThesisParameters::thesis_bicycle()),
        (
            "benchmark",
            BenchmarkParameters::benchmark_bicycle()
                .to_thesis()
                .expect("the benchmark bicycle converts"),
        ),
    ]
}

/// True when every parameter the bicycle sets to a non-zero value (thesis
/// symbols and effect parameters, by `value`) is a parameter of the model.
pub fn fits(info: &ModelInfo, nonzero: &[(&str, f64)]) -> bool {
    nonzero.iter().all(|(n, _)| info.parameter(n).is_some())
}

/// The built-in bicycle a model is exercised with by default: among the
/// built-in bicycles it fits, the one that gives the most of its parameters
/// a non-zero value (the benchmark bicycle for models with the fork offset).
pub fn default_bicycle(info: &ModelInfo) -> ThesisParameters {
    let mut best: Option<(usize, ThesisParameters)> = None;
    for (_, p) in built_in_thesis_parameters() {
        let nonzero: Vec<(&str, f64)> = ThesisParameters::SYMBOLS
            .iter()
            .filter_map(|&s| p.get(s).filter(|&v| v != 0.0).map(|v| (s, v)))
            .collect();
        if !fits(info, &nonzero) {
            continue;
        }
        let used = nonzero.iter().filter(|(n, _)| info.parameter(n).is_some()).count();
        if best.as_ref().is_none_or(|(u, _)| used > *u) {
            best = Some((used, p));
        }
    }
    best.map(|b| b.1).unwrap_or_else(ThesisParameters::thesis_bicycle)
}

/// Default parameter vector of a model: its default built-in bicycle, the
/// model's defaults for effect parameters, at a forward speed of 4.5 m/s
/// (driven models; free-speed models get their speed from the state).
pub fn default_parameters<M: MultibodyModel>() -> Vec<f64> {
    let p = default_bicycle(&ModelInfo::of::<M>());
    parameter_vector::<M>(|s| p.get(s), 4.5).expect("built-in bicycles define every model parameter")
}

struct Verify<'a>(&'a VerifyOptions);
impl ModelVisitor for Verify<'_> {
    type Output = VerifyReport;
    fn visit<M: MultibodyModel>(self) -> VerifyReport {
        verify::<M>(&with_effects_switched_on::<M>(&default_parameters::<M>()), self.0)
    }
}

/// Verify one model by name (effect parameters switched on so that their
/// forces are checked); `None` for an unknown name.
pub fn verify_model(name: &str, opts: &VerifyOptions) -> Option<VerifyReport> {
    with_model(name, Verify(opts))
}

/// Every generated model.
pub fn models() -> &'static [ModelInfo] {
    MODELS
}

/// A model by name.
pub fn model_info(name: &str) -> Option<&'static ModelInfo> {
    MODELS.iter().find(|m| m.name == name)
}

/// Names of every model (for messages).
pub fn model_names() -> Vec<&'static str> {
    MODELS.iter().map(|m| m.name).collect()
}

/// Every effect parameter of any model, with its description (computed
/// once: sweeps resolve bicycles in their inner loop).
pub fn effect_parameters() -> &'static [&'static ParameterInfo] {
    static CACHE: std::sync::OnceLock<Vec<&'static ParameterInfo>> = std::sync::OnceLock::new();
    CACHE.get_or_init(|| {
        let mut out: Vec<&'static ParameterInfo> = Vec::new();
        for m in MODELS {
            for p in m.parameters {
                if p.effect.is_some() && !out.iter().any(|q| q.name == p.name) {
                    out.push(p);
                }
            }
        }
        out
    })
}

/// JSON record of a model, as `bikedyn models --json` prints it.
pub fn model_json(m: &ModelInfo) -> serde_json::Value {
    serde_json::json!({
        "name": m.name,
        "doc": m.doc,
        "base": m.base,
        "free_speed": m.free_speed,
        "effects": m.effects,
        "coordinates": m.coordinates.iter().enumerate().map(|(i, c)| serde_json::json!({
            "name": c,
            "independent": m.independent.contains(&i),
        })).collect::<Vec<_>>(),
        "states": m.states,
        "parameters": m.parameters.iter().map(|p| serde_json::json!({
            "name": p.name, "doc": p.doc, "default": p.default, "effect": p.effect,
        })).collect::<Vec<_>>(),
    })
}

/// The free-speed variant of a model: same base and effects, free speed
/// (itself if it already has free speed).
pub fn free_speed_variant(info: &'static ModelInfo) -> Option<&'static ModelInfo> {
    if info.free_speed {
        return Some(info);
    }
    MODELS
        .iter()
        .find(|m| m.free_speed && m.base == info.base && m.effects == info.effects)
}
