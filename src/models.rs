//! Generic operations on the generated models, through the registry (no
//! model is named here): default parameters, verification, listing.

use crate::generated::{with_model, MODELS};
use crate::registry::BuiltIn;
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::model::ParameterInfo;
use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::verify::{verify, with_effects_switched_on};
/// The verification job's options and per-model report.
pub use bikedyn_runtime::verify::{VerifyOptions, VerifyReport};
use bikedyn_runtime::MultibodyModel;
use serde::Serialize;
use std::any::TypeId;
use std::sync::{Mutex, OnceLock, PoisonError};

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
        // A model's added body (a leaning rider) is there only when the
        // bicycle gives it.
        && required_added_parameters(info).all(|p| nonzero.iter().any(|(n, _)| *n == p.name))
}

/// The parameters of a model's added bodies, which have no default and no
/// form's table holds (a leaning rider's `m6`, `k_lean`, ...): a bicycle
/// must give each for the model to represent it.
pub(crate) fn required_added_parameters(info: &ModelInfo) -> impl Iterator<Item = &'static ParameterInfo> + '_ {
    info.parameters.iter().enumerate().filter_map(move |(i, p)| {
        (p.default.is_none() && info.forward_speed_parameter != Some(i) && !ThesisParameters::SYMBOLS.contains(&p.name))
            .then_some(p)
    })
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
    let example = |s: &str| EXAMPLE_ADDED_BODIES.iter().find(|(n, _)| *n == s).map(|&(_, v)| v);
    parameter_vector::<M>(|s| p.get(s).or_else(|| example(s)), 4.5)
        .expect("built-in bicycles and the example added bodies define every model parameter")
}

/// Values of the parameters of bodies a model adds to the bicycle, which
/// no built-in bicycle sets and which have no default (a bicycle file must
/// give them), for running such a model on its default bicycle (`verify`,
/// the benchmarks): a rider's upper body of 40 kg, its mass centre 0.2 m
/// above a lean axis 0.9 m above the ground, with a 2000 N m/rad hip
/// and trunk (the upper body of the benchmark's rider split in
/// `tests/linear_analysis/leaning_rider.rs`).
const EXAMPLE_ADDED_BODIES: &[(&str, f64)] = &[
    ("xL", 0.3),
    ("zL", 0.6),
    ("x6", 0.0),
    ("z6", 0.2),
    ("m6", 40.0),
    ("I6x", 2.5),
    ("I6y", 2.8),
    ("I6z", 1.0),
    ("I6xz", -1.0),
    ("k_lean", 2000.0),
];

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

/// The verification job (`bikedyn verify`): every generated derivative of
/// `model` (`None`: every built-in model) against central finite
/// differences at `options.states` random states.
pub fn verify_models(model: Option<&str>, options: &VerifyOptions) -> Result<Verification, UnknownModel> {
    let names: Vec<&str> = match model {
        Some(m) => vec![m],
        None => model_names(),
    };
    let reports = names
        .into_iter()
        .map(|n| {
            verify_model(n, options).ok_or_else(|| UnknownModel {
                model: n.to_string(),
                known: model_names().join(", "),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Verification {
        passed: reports.iter().all(|r| r.passed),
        reports,
    })
}

/// A model name the registry does not have.
#[derive(Debug, thiserror::Error)]
#[error("unknown model `{model}` (models: {known})")]
pub struct UnknownModel {
    pub model: String,
    pub known: String,
}

/// What the verification job found.
#[derive(Clone, Debug)]
pub struct Verification {
    /// Every quantity of every model within its tolerance.
    pub passed: bool,
    /// Each model's checks.
    pub reports: Vec<VerifyReport>,
}

/// One quantity of one model, as `verify --json` lists them.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VerifiedQuantity {
    /// The model.
    pub model: String,
    /// The quantity (`Cq`, `dBdp`, `M symmetric`, ...).
    pub name: String,
    /// Largest error over the states, relative to the reference's largest
    /// magnitude at that state.
    pub max_rel_error: f64,
    /// The tolerance it is held to.
    pub tolerance: f64,
    /// Whether it is within it.
    pub passed: bool,
}

/// `verify --json`: the verdict and every quantity of every model.
#[derive(Clone, Debug, serde::Serialize)]
pub struct VerificationJson {
    pub passed: bool,
    pub quantities: Vec<VerifiedQuantity>,
}

impl Verification {
    /// The verdict and every quantity, flat (the JSON of `verify --json`).
    pub fn to_json(&self) -> VerificationJson {
        VerificationJson {
            passed: self.passed,
            quantities: self
                .reports
                .iter()
                .flat_map(|r| {
                    r.quantities.iter().map(move |q| VerifiedQuantity {
                        model: r.model.clone(),
                        name: q.name.clone(),
                        max_rel_error: q.max_rel_error,
                        tolerance: q.tolerance,
                        passed: q.passed,
                    })
                })
                .collect(),
        }
    }
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

/// Every effect parameter of any built-in model, and every parameter of a
/// body a model adds (a leaning rider's), with its description: what a
/// parameter file may set beyond its form's symbols.
pub fn effect_parameters() -> &'static [&'static ParameterInfo] {
    effect_parameters_in::<BuiltIn>()
}

/// [`effect_parameters`] of the models of registry `R`, with its
/// description.
pub fn effect_parameters_in<R: ModelRegistry>() -> &'static [&'static ParameterInfo] {
    &index::<R>().effect_parameters
}

/// What bicycle resolution and model choice read from a registry, computed
/// once per registry: sweeps resolve bicycles in their inner loop.
pub(crate) struct Index {
    /// Every parameter of any model beyond the thesis form's: effect
    /// parameters and those of added bodies (first declaration of each name).
    pub effect_parameters: Vec<&'static ParameterInfo>,
    /// The driven-speed models, by increasing number of parameters (stable,
    /// so ties keep registry order).
    pub driven_by_size: Vec<&'static ModelInfo>,
    /// Per model of `driven_by_size`: the thesis symbols it has, and those
    /// of them that are effect parameters (bit `i` for
    /// `ThesisParameters::SYMBOLS[i]`).
    pub thesis_masks: Vec<(u64, u64)>,
}

impl Index {
    fn of(models: &'static [ModelInfo]) -> Index {
        let mut effect_parameters: Vec<&'static ParameterInfo> = Vec::new();
        for m in models {
            for (i, p) in m.parameters.iter().enumerate() {
                // Beside the effects' parameters, those of the bodies a
                // model adds to the bicycle (a leaning rider's): no form's
                // table holds them either, and a file sets them alike.
                let added = p.effect.is_some()
                    || (!ThesisParameters::SYMBOLS.contains(&p.name) && m.forward_speed_parameter != Some(i));
                if added && !effect_parameters.iter().any(|q| q.name == p.name) {
                    effect_parameters.push(p);
                }
            }
        }
        let mut driven_by_size: Vec<&'static ModelInfo> = models.iter().filter(|m| !m.free_speed).collect();
        driven_by_size.sort_by_key(|m| m.parameters.len());
        let thesis_masks = driven_by_size
            .iter()
            .map(|m| {
                ThesisParameters::SYMBOLS
                    .iter()
                    .enumerate()
                    .fold((0u64, 0u64), |(has, effect), (i, s)| match m.parameter(s) {
                        Some(p) => (has | 1 << i, effect | (p.effect.is_some() as u64) << i),
                        None => (has, effect),
                    })
            })
            .collect();
        Index {
            effect_parameters,
            driven_by_size,
            thesis_masks,
        }
    }
}

/// The [`Index`] of registry `R`. The built-in registry's is a plain
/// `OnceLock` (no lock on the sweeps' path); other registries' are kept,
/// one per registry type, behind a mutex taken once per lookup.
pub(crate) fn index<R: ModelRegistry>() -> &'static Index {
    static BUILT_IN: OnceLock<Index> = OnceLock::new();
    static OTHERS: Mutex<Vec<(TypeId, &'static Index)>> = Mutex::new(Vec::new());
    if TypeId::of::<R>() == TypeId::of::<BuiltIn>() {
        return BUILT_IN.get_or_init(|| Index::of(R::models()));
    }
    // The list only grows and each entry is complete when pushed, so a
    // poisoned lock still holds a valid list.
    let mut others = OTHERS.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(&(_, i)) = others.iter().find(|(t, _)| *t == TypeId::of::<R>()) {
        return i;
    }
    // One per registry type for the life of the process.
    let i: &'static Index = Box::leak(Box::new(Index::of(R::models())));
    others.push((TypeId::of::<R>(), i));
    i
}

/// A generated model as `bikedyn models --json` lists it (also the
/// explorer's and Python's `models()`): the JSON is this type's derived
/// serialization.
#[derive(Clone, Debug, Serialize)]
pub struct ModelRecord {
    /// The model's name (`--model NAME`).
    pub name: &'static str,
    /// What it models, in words.
    pub doc: &'static str,
    /// The base model its effects are added to.
    pub base: &'static str,
    /// Whether the forward speed is a state (else the speed is imposed).
    pub free_speed: bool,
    /// The effects applied, by name.
    pub effects: &'static [&'static str],
    /// The generalized coordinates, in the model's order.
    pub coordinates: Vec<CoordinateRecord>,
    /// Extra first-order states (lagged tyre forces, a controller's).
    pub states: &'static [&'static str],
    /// Every parameter, in the model's order.
    pub parameters: Vec<ParameterRecord>,
}

/// A generalized coordinate of a model.
#[derive(Clone, Debug, Serialize)]
pub struct CoordinateRecord {
    /// Its name (angles in rad, positions in m).
    pub name: &'static str,
    /// Whether it is independent (else solved from the constraints).
    pub independent: bool,
}

/// A parameter of a model.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterRecord {
    /// Its symbol (as in parameter files).
    pub name: &'static str,
    /// Meaning and unit.
    pub doc: &'static str,
    /// The value used when a bicycle does not give it (in its unit; for an
    /// effect's parameter the value at which the effect is absent), or
    /// `null`: the bicycle must give it.
    pub default: Option<f64>,
    /// The effect that declared it, or `null` for the bicycle's own.
    pub effect: Option<&'static str>,
}

impl ModelRecord {
    /// The record of model `m`.
    pub fn of(m: &ModelInfo) -> ModelRecord {
        ModelRecord {
            name: m.name,
            doc: m.doc,
            base: m.base,
            free_speed: m.free_speed,
            effects: m.effects,
            coordinates: m
                .coordinates
                .iter()
                .enumerate()
                .map(|(i, &name)| CoordinateRecord {
                    name,
                    independent: m.independent.contains(&i),
                })
                .collect(),
            states: m.states,
            parameters: m
                .parameters
                .iter()
                .map(|p| ParameterRecord {
                    name: p.name,
                    doc: p.doc,
                    default: p.default,
                    effect: p.effect,
                })
                .collect(),
        }
    }
}

/// The free-speed variant of a model: same base and effects, free speed
/// (itself if it already has free speed).
pub fn free_speed_variant(info: &'static ModelInfo) -> Option<&'static ModelInfo> {
    free_speed_variant_in::<BuiltIn>(info)
}

/// [`free_speed_variant`] among the models of registry `R`.
pub fn free_speed_variant_in<R: ModelRegistry>(info: &'static ModelInfo) -> Option<&'static ModelInfo> {
    if info.free_speed {
        return Some(info);
    }
    R::models()
        .iter()
        .find(|m| m.free_speed && m.base == info.base && m.effects == info.effects)
}
