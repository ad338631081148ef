//! Bicycles as users name them (built-in names or parameter files), mapped to
//! the generated model that represents them and to their canonical matrices.
//! The files' formats are read and written in [`files`].

use crate::models::{effect_parameters_in, fits, index};
use crate::registry::BuiltIn;
use bikedyn_runtime::feedback::GainSchedule;
use bikedyn_runtime::linearize::LinearizeError;
use bikedyn_runtime::parameters::{moore, BenchmarkParameters, ParameterError, ParameterSet};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry};
use files::{LoadedSet, ParameterSetFile};
use std::collections::BTreeMap;
use std::marker::PhantomData;
use std::path::Path;
use thiserror::Error;

pub mod files;
mod linear;
pub use linear::{canonical_of, Linear};
// The runtime's parameter types that appear in a bicycle and its options:
// front ends name them from here, not from the runtime.
pub use bikedyn_runtime::parameters::{Form, ParameterWarning, ThesisParameters};

/// Built-in bicycles.
pub const BUILT_IN: &[(&str, &str)] = &[
    (
        "thesis",
        "the instrumented bicycle of Martin Recuero (2009), section 4.4 (default)",
    ),
    ("benchmark", "the benchmark bicycle of Meijaard et al. (2007), Table 1"),
];

/// Errors of resolving or analysing a bicycle.
#[derive(Debug, Error)]
pub enum BicycleError {
    #[error(transparent)]
    Parameters(#[from] ParameterError),
    #[error("linearization of `{bike}` failed: {source}")]
    Linearize { bike: String, source: LinearizeError },
    #[error("unknown parameter `{name}`{suggestion}: effect parameters are {effects}; masses, inertias and geometry are thesis symbols ({thesis}) or benchmark symbols ({benchmark})")]
    UnknownParameter {
        name: String,
        /// ` (did you mean `X`?)` for a close symbol, else empty.
        suggestion: String,
        effects: String,
        thesis: String,
        benchmark: String,
    },
    #[error("{file}: {warning}; lengths are in metres (pass --allow-units if this value is meant)")]
    LooksLikeMillimetres { file: String, warning: String },
    #[error("`{spec}` is neither a built-in bicycle (thesis, benchmark) nor an existing file")]
    NotFound { spec: String },
    #[error("{bike}: `{symbol}` = {value} is not a finite number")]
    NotFinite { bike: String, symbol: String, value: f64 },
    #[error("unknown model `{name}` (models: {known})")]
    UnknownModel { name: String, known: String },
    #[error("model `{model}` cannot represent `{bike}`: it has no parameter {missing} (see `bikedyn models`)")]
    ModelDoesNotFit {
        model: String,
        bike: String,
        missing: String,
    },
    #[error("{file}: {why}")]
    EffectParameter { file: String, why: String },
    #[error("no generated model has every parameter `{bike}` sets ({nonzero})")]
    NoModelFits { bike: String, nonzero: String },
    #[error("`{bike}` gives part of model `{model}`'s added body: it also needs {missing}")]
    MissingValues {
        bike: String,
        model: String,
        missing: String,
    },
    #[error("the canonical form M0, C1, K0, K2 holds for the Whipple bicycle; with {effects} the linear equations depend on speed otherwise")]
    NotCanonical { effects: String },
    #[error("{bike}: its [feedback] closes the loop on the roll-steer equations M, C, K, which model `{model}` does not have (its extra states or coordinates: {states}); use a model without them")]
    FeedbackOnStates {
        bike: String,
        model: String,
        states: String,
    },
}

/// A resolved bicycle, against the models of registry `R` (the built-in
/// models by default): its effect parameters are those of `R`'s models, and
/// its model is chosen among them.
#[derive(Clone, Debug)]
pub struct Bicycle<R: ModelRegistry = BuiltIn> {
    /// Built-in name or file path.
    pub name: String,
    /// Parameters as given (thesis or benchmark form).
    pub parameters: ParameterSet,
    /// Validation warnings (e.g. triangle inequality of inertia tensors).
    pub warnings: Vec<ParameterWarning>,
    /// Effect parameters given in the file, by symbol (absent: the model's
    /// default, at which the effect is absent).
    pub effects: BTreeMap<String, f64>,
    /// Standard deviations the file gives (`value+/-std`), by the file's
    /// symbols; empty when it gives none.
    pub uncertainties: BTreeMap<String, f64>,
    /// Full-state feedback on the roll and steer torques, as the file's
    /// `[feedback]` table declares it (a controller as the experiment ran
    /// it, possibly scheduled over speed). The linear analyses close the
    /// loop with it.
    pub feedback: Option<GainSchedule>,
    registry: PhantomData<R>,
}

/// Whether a parameter file with a length that looks like millimetres
/// (over 10 m) is accepted with a warning instead of refused.
static ALLOW_IMPLAUSIBLE_UNITS: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Accept parameter files whose lengths look like millimetres (the
/// command line's `--allow-units`), for this process: a length over 10 m is
/// then a warning, not an error.
pub fn allow_implausible_units(allow: bool) {
    ALLOW_IMPLAUSIBLE_UNITS.store(allow, std::sync::atomic::Ordering::Relaxed);
}

/// Refuse parameters whose lengths look like millimetres (a length over
/// 10 m), unless [`allow_implausible_units`] was set: `source` names the
/// file, or the bicycle and the value set.
fn refuse_millimetres(warnings: &[ParameterWarning], source: &str) -> Result<(), BicycleError> {
    if ALLOW_IMPLAUSIBLE_UNITS.load(std::sync::atomic::Ordering::Relaxed) {
        return Ok(());
    }
    match warnings
        .iter()
        .find(|w| matches!(w, ParameterWarning::LooksLikeMillimetres { .. }))
    {
        Some(w) => Err(BicycleError::LooksLikeMillimetres {
            file: source.to_string(),
            warning: w.to_string(),
        }),
        None => Ok(()),
    }
}

impl Bicycle {
    /// Resolve `thesis`, `benchmark` or a parameter file (TOML in either form,
    /// or the `name = value[+/-std]` text form of bicycleparameters/HumanControl)
    /// against the built-in models.
    pub fn resolve(spec: &str) -> Result<Bicycle, BicycleError> {
        Self::resolve_in(spec)
    }

    /// [`Bicycle::from_values_in`] against the built-in models.
    pub fn from_values(name: &str, values: &[(String, f64, Option<f64>)]) -> Result<Bicycle, BicycleError> {
        Self::from_values_in(name, values)
    }
}

impl<R: ModelRegistry> Bicycle<R> {
    /// [`Bicycle::resolve`] against the models of registry `R`: a parameter
    /// file may set the effect parameters of `R`'s models, and the bicycle's
    /// model is chosen among them.
    pub fn resolve_in(spec: &str) -> Result<Bicycle<R>, BicycleError> {
        let (parameters, warnings) = match spec {
            "thesis" => {
                let p = ThesisParameters::thesis_bicycle();
                let w = p.validate()?;
                (ParameterSet::Thesis(p), w)
            }
            "benchmark" => {
                let p = BenchmarkParameters::benchmark_bicycle();
                let w = p.validate()?;
                (ParameterSet::Benchmark(p), w)
            }
            path if Path::new(path).exists() => {
                let extra: Vec<&str> = effect_parameters_in::<R>().iter().map(|p| p.name).collect();
                return Self::loaded(spec, ParameterSet::load_with_extra(path, &extra)?);
            }
            _ => return Err(BicycleError::NotFound { spec: spec.to_string() }),
        };
        Ok(Bicycle {
            name: spec.to_string(),
            parameters,
            warnings,
            effects: BTreeMap::new(),
            uncertainties: BTreeMap::new(),
            feedback: None,
            registry: PhantomData,
        })
    }

    /// A bicycle from the text of a parameter file (TOML in either form, or
    /// the text form of bicycleparameters and HumanControl) that is not on
    /// disk, such as a file dropped on the browser explorer: read and
    /// checked as [`Bicycle::resolve_in`] reads a file, with the same
    /// messages; `file_name` names it (and its extension `.toml` says
    /// TOML, as for a file).
    pub fn from_file_text_in(file_name: &str, text: &str) -> Result<Bicycle<R>, BicycleError> {
        let extra: Vec<&str> = effect_parameters_in::<R>().iter().map(|p| p.name).collect();
        Self::loaded(
            file_name,
            ParameterSet::from_file_text_with_extra(text, file_name, &extra)?,
        )
    }

    /// A bicycle of a read parameter file, its effect values checked.
    fn loaded(file: &str, loaded: LoadedSet) -> Result<Bicycle<R>, BicycleError> {
        for (name, &value) in &loaded.effects {
            check_effect_value_in::<R>(name, value, file)?;
        }
        check_effect_windows_in::<R>(&loaded.effects, file)?;
        refuse_millimetres(&loaded.warnings, file)?;
        Ok(Bicycle {
            name: file.to_string(),
            parameters: loaded.set,
            warnings: loaded.warnings,
            effects: loaded.effects,
            uncertainties: loaded.uncertainties,
            feedback: loaded.feedback,
            registry: PhantomData,
        })
    }

    /// A bicycle from named values, as a notebook holds them (a Python
    /// dict): every benchmark symbol (Meijaard et al. 2007, Table 1; the
    /// parameter dict of bicycleparameters' `Meijaard2007ParameterSet`) or
    /// every thesis symbol, in SI units, plus any effect parameters of
    /// `R`'s models. A value may carry its standard deviation (kept as a
    /// file's `+/-` is). J. K. Moore's (2012) parameters with a leaning
    /// rider, the dict of bicycleparameters' `MooreRiderLean2012ParameterSet`
    /// (or without the rider, `Moore2012ParameterSet`), are read too:
    /// converted to the benchmark form and the `rider_lean` model's rider
    /// (see [`moore`]). `v` (the nominal speed some sets carry) is not a
    /// bicycle parameter and is ignored: speeds are given to each analysis.
    /// `name` names the bicycle in messages; errors name the key.
    pub fn from_values_in(name: &str, values: &[(String, f64, Option<f64>)]) -> Result<Bicycle<R>, BicycleError> {
        let effect_names: Vec<&str> = effect_parameters_in::<R>().iter().map(|p| p.name).collect();
        let bad = |key: &str, why: String| BicycleError::EffectParameter {
            file: name.to_string(),
            why: format!("`{key}`: {why}"),
        };
        let mut effects = BTreeMap::new();
        let mut uncertainties = BTreeMap::new();
        let mut geometry: Vec<(&str, f64)> = Vec::new();
        for (key, value, sd) in values {
            let key = key.as_str();
            if !value.is_finite() {
                return Err(bad(key, format!("{value} is not a finite number")));
            }
            if let Some(sd) = sd {
                if !(sd.is_finite() && *sd >= 0.0) {
                    return Err(bad(
                        key,
                        format!("standard deviation {sd} is not a finite, non-negative number"),
                    ));
                }
            }
            if key == "v" {
                continue;
            }
            if effect_names.contains(&key) {
                check_effect_value_in::<R>(key, *value, name)?;
                effects.insert(key.to_string(), *value);
            } else if ThesisParameters::SYMBOLS.contains(&key)
                || BenchmarkParameters::SYMBOLS.contains(&key)
                || moore::is_moore_symbol(key)
            {
                geometry.push((key, *value));
            } else {
                return Err(unknown_parameter::<R>(key));
            }
            if let Some(sd) = sd {
                uncertainties.insert(key.to_string(), *sd);
            }
        }
        // J. K. Moore's parameters (bicycleparameters'
        // `MooreRiderLean2012ParameterSet`): converted to the benchmark form
        // and the leaning rider's parameters, which join the effects.
        let (parameters, warnings) = if moore::is_moore_set(geometry.iter().map(|(k, _)| *k)) {
            if let Some((k, _)) = geometry.iter().find(|(k, _)| uncertainties.contains_key(*k)) {
                return Err(bad(
                    k,
                    "a standard deviation of Moore's parameters would not reach the converted ones; give nominal values"
                        .to_string(),
                ));
            }
            let mut text = format!("form = \"{}\"\n", moore::MOORE_FORM);
            for (k, v) in &geometry {
                text.push_str(&format!("{k} = {v:?}\n"));
            }
            let rider: Vec<&str> = effect_names
                .iter()
                .copied()
                .filter(|n| moore::RIDER_LEAN_PARAMETERS.contains(n))
                .collect();
            let (parameters, converted, warnings) = ParameterSet::from_toml_str_with_extra(&text, name, &rider)?;
            for (k, v) in converted {
                if effects.contains_key(&k) {
                    return Err(bad(
                        &k,
                        "the leaning rider is given twice: in Moore's keys and in the rider_lean model's; give one of them"
                            .to_string(),
                    ));
                }
                check_effect_value_in::<R>(&k, v, name)?;
                effects.insert(k, v);
            }
            (parameters, warnings)
        } else {
            // The form is the one whose symbols are given: a thesis-only
            // symbol makes it the thesis form (the two share `g` and a few
            // names).
            let thesis = geometry
                .iter()
                .any(|(k, _)| ThesisParameters::SYMBOLS.contains(k) && !BenchmarkParameters::SYMBOLS.contains(k));
            let mut text = format!("form = \"{}\"\n", if thesis { "thesis" } else { "benchmark" });
            for (k, v) in &geometry {
                text.push_str(&format!("{k} = {v:?}\n"));
            }
            let (parameters, _, warnings) = ParameterSet::from_toml_str_with_extra(&text, name, &[])?;
            (parameters, warnings)
        };
        check_effect_windows_in::<R>(&effects, name)?;
        refuse_millimetres(&warnings, name)?;
        Ok(Bicycle {
            name: name.to_string(),
            parameters,
            warnings,
            effects,
            uncertainties,
            feedback: None,
            registry: PhantomData,
        })
    }

    /// Standard deviation of parameter `symbol` (a thesis or benchmark
    /// symbol) from the uncertainties the file gives: the file's own value
    /// for one of its symbols, else first-order propagation through the
    /// conversion between forms, taking the file's uncertainties as
    /// independent. `None` when the file gives none that reach `symbol`.
    pub fn file_uncertainty(&self, symbol: &str) -> Option<f64> {
        if let Some(&sd) = self.uncertainties.get(symbol) {
            return Some(sd);
        }
        let value = self.value(symbol)?;
        let mut var = 0.0;
        for (given, &sd) in &self.uncertainties {
            let Some(v0) = self.value(given) else { continue };
            if !(sd > 0.0) {
                continue;
            }
            // One step of a standard deviation each way, whichever is a
            // valid bicycle (a step may break the triangle inequality).
            let moved = [sd, -sd]
                .into_iter()
                .find_map(|h| self.with_parameter(given, v0 + h).ok()?.value(symbol));
            if let Some(m) = moved {
                var += (m - value) * (m - value);
            }
        }
        (var > 0.0).then(|| var.sqrt())
    }

    /// Why no model fits: a model that has every parameter the bicycle sets
    /// but lacks values of its added body's (a leaning rider's `k_lean`
    /// left out) is named with them; otherwise the parameters set.
    fn why_no_model_fits(&self, nonzero: &[(&'static str, f64)]) -> BicycleError {
        let given = |name: &str| nonzero.iter().any(|(n, _)| *n == name);
        let near = index::<R>()
            .driven_by_size
            .iter()
            .find(|m| nonzero.iter().all(|(n, _)| m.parameter(n).is_some()));
        if let Some(m) = near {
            let missing: Vec<String> = crate::models::required_added_parameters(m)
                .filter(|p| !given(p.name))
                .map(|p| format!("`{}` ({})", p.name, p.doc))
                .collect();
            if !missing.is_empty() {
                return BicycleError::MissingValues {
                    bike: self.name.clone(),
                    model: m.name.to_string(),
                    missing: missing.join(", "),
                };
            }
        }
        BicycleError::NoModelFits {
            bike: self.name.clone(),
            nonzero: nonzero.iter().map(|(s, _)| *s).collect::<Vec<_>>().join(", "),
        }
    }

    /// Parameters this bicycle sets to a non-zero value: thesis symbols and
    /// effect parameters (with their values), and every parameter of an
    /// added body it gives (a leaning rider's, even at zero).
    pub fn nonzero_parameters(&self) -> Result<Vec<(&'static str, f64)>, BicycleError> {
        let t = self.thesis()?;
        let mut out: Vec<(&'static str, f64)> = ThesisParameters::SYMBOLS
            .iter()
            .filter_map(|&s| t.get(s).filter(|&v| v != 0.0).map(|v| (s, v)))
            .collect();
        for p in effect_parameters_in::<R>() {
            if let Some(&v) = self.effects.get(p.name) {
                // An effect at its absent value asks for no model; a
                // parameter of an added body (no default) asks for the
                // model with that body whatever its value.
                if p.default.is_none() || (Some(v) != p.default && v != 0.0) {
                    out.push((p.name, v));
                }
            }
        }
        Ok(out)
    }

    /// The model to run this bicycle through: `name` if given (it must have
    /// every parameter the bicycle sets), otherwise the smallest driven-speed
    /// model that has them all (the thesis model for a bicycle with its fork
    /// mass centre on the steer axis and no effects).
    pub fn model(&self, name: Option<&str>) -> Result<&'static ModelInfo, BicycleError> {
        self.model_for(name, &self.nonzero_parameters()?)
    }

    /// [`Bicycle::model`] with the non-zero parameters already known.
    fn model_for(
        &self,
        name: Option<&str>,
        nonzero: &[(&'static str, f64)],
    ) -> Result<&'static ModelInfo, BicycleError> {
        match name {
            Some(n) => {
                let info = R::models()
                    .iter()
                    .find(|m| m.name == n)
                    .ok_or_else(|| BicycleError::UnknownModel {
                        name: n.to_string(),
                        known: R::models().iter().map(|m| m.name).collect::<Vec<_>>().join(", "),
                    })?;
                let missing: Vec<String> = nonzero
                    .iter()
                    .filter(|(s, _)| info.parameter(s).is_none())
                    .map(|(s, v)| format!("`{s}` (= {v})"))
                    .collect();
                if missing.is_empty() {
                    Ok(info)
                } else {
                    Err(BicycleError::ModelDoesNotFit {
                        model: n.to_string(),
                        bike: self.name.clone(),
                        missing: missing.join(", "),
                    })
                }
            }
            // Smallest first, so only the models smaller than the one chosen
            // are tested (once per design in a sweep); ties keep registry order.
            None => index::<R>()
                .driven_by_size
                .iter()
                .find(|m| fits(m, nonzero))
                .copied()
                .ok_or_else(|| self.why_no_model_fits(nonzero)),
        }
    }

    /// Lookup of every parameter by symbol: thesis form, then benchmark
    /// form, then the effect parameters given (absent ones: the model default).
    pub fn lookup(&self) -> Result<impl Fn(&str) -> Option<f64> + '_, BicycleError> {
        let t = self.thesis()?;
        Ok(move |s: &str| t.get(s).or_else(|| self.effects.get(s).copied()))
    }

    /// Thesis-form parameters (converted if given in benchmark form).
    pub fn thesis(&self) -> Result<ThesisParameters, BicycleError> {
        Ok(self.parameters.to_thesis()?)
    }

    /// The geometry derived from the parameters, whatever their form
    /// (Meijaard et al. 2007, appendix A; benchmark axes): each row is
    /// `(symbol, value, unit, what)`.
    pub fn derived_geometry(&self) -> Result<bikedyn_runtime::geometry::DerivedGeometry, BicycleError> {
        Ok(bikedyn_runtime::geometry::DerivedGeometry::of(
            &self.parameters.to_benchmark()?,
        ))
    }

    /// The same bicycle with one parameter changed. `symbol` is a thesis
    /// symbol (`Rt`, `x4`, `d4`, ...) or a benchmark symbol (`c`, `lam`, ...).
    /// The file's standard deviation of `symbol`, if any, is dropped: a
    /// value set is not measured.
    pub fn with_parameter(&self, symbol: &str, value: f64) -> Result<Bicycle<R>, BicycleError> {
        // (A NaN would otherwise fail the parameter table's conversion and
        // be reported as an unknown parameter.)
        if !value.is_finite() {
            return Err(BicycleError::NotFinite {
                bike: self.name.clone(),
                symbol: symbol.to_string(),
                value,
            });
        }
        if effect_parameters_in::<R>().iter().any(|p| p.name == symbol) {
            check_effect_value_in::<R>(symbol, value, &self.name)?;
            let mut b = self.clone();
            b.effects.insert(symbol.to_string(), value);
            b.uncertainties.remove(symbol);
            check_effect_windows_in::<R>(&b.effects, &self.name)?;
            b.name = format!("{} ({symbol} = {value})", self.name);
            return Ok(b);
        }
        let parameters = if ThesisParameters::SYMBOLS.contains(&symbol) {
            ParameterSet::Thesis(set_field(&self.thesis()?, symbol, value)?)
        } else if BenchmarkParameters::SYMBOLS.contains(&symbol) {
            ParameterSet::Benchmark(set_field(&self.parameters.to_benchmark()?, symbol, value)?)
        } else {
            return Err(unknown_parameter::<R>(symbol));
        };
        let warnings = parameters.validate()?;
        let name = format!("{} ({symbol} = {value})", self.name);
        // A value set here is checked as a file's would be (a wheelbase of
        // 1020 is millimetres, not metres).
        refuse_millimetres(&warnings, &name)?;
        // A value set is set, not measured: the file's `+/-` of that symbol
        // no longer applies (the others do).
        let mut uncertainties = self.uncertainties.clone();
        uncertainties.remove(symbol);
        Ok(Bicycle {
            name,
            parameters,
            warnings,
            effects: self.effects.clone(),
            uncertainties,
            feedback: self.feedback.clone(),
            registry: PhantomData,
        })
    }

    /// The effect parameters the file set, as TOML lines that any
    /// parameter file may end with (neither form's table holds them), so
    /// that a converted or refitted file keeps them, then its `[feedback]`
    /// table; empty when there are none.
    pub fn effects_toml(&self) -> String {
        let mut s = String::new();
        for (k, v) in &self.effects {
            s.push_str(&format!("{k} = {v:e}\n"));
        }
        // The controller, as a table after every key (a table must come
        // last in TOML); only its non-zero gains.
        if let Some(f) = &self.feedback {
            let list = |xs: Vec<f64>| xs.iter().map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ");
            s.push_str(&format!("\n[feedback]\nspeeds = [{}]\n", list(f.speeds().to_vec())));
            for (j, name) in bikedyn_runtime::feedback::GAIN_NAMES.iter().enumerate() {
                let values: Vec<f64> = f.gains().iter().map(|k| k[(j / 4, j % 4)]).collect();
                if values.iter().any(|&x| x != 0.0) {
                    s.push_str(&format!("{name} = [{}]\n", list(values)));
                }
            }
        }
        s
    }

    /// Value of a thesis or benchmark symbol.
    pub fn value(&self, symbol: &str) -> Option<f64> {
        self.thesis()
            .ok()
            .and_then(|t| t.get(symbol))
            .or_else(|| self.parameters.to_benchmark().ok().and_then(|b| b.get(symbol)))
            .or_else(|| self.effects.get(symbol).copied())
            .or_else(|| {
                effect_parameters_in::<R>()
                    .iter()
                    .find(|p| p.name == symbol)
                    .and_then(|p| p.default)
            })
    }
}

/// Refuse a non-physical value of effect parameter `name` (not finite, or
/// below the lower bound its effect file declares), naming `file`.
pub fn check_effect_value(name: &str, value: f64, file: &str) -> Result<(), BicycleError> {
    check_effect_value_in::<BuiltIn>(name, value, file)
}

/// [`check_effect_value`] for the effect parameters of registry `R`.
pub fn check_effect_value_in<R: ModelRegistry>(name: &str, value: f64, file: &str) -> Result<(), BicycleError> {
    match effect_parameters_in::<R>()
        .iter()
        .find(|p| p.name == name)
        .and_then(|p| p.refuses(value))
    {
        Some(why) => Err(BicycleError::EffectParameter {
            file: file.to_string(),
            why,
        }),
        None => Ok(()),
    }
}

/// Refuse a speed window of an effect that is empty: a parameter
/// `X_v_min` at or above its `X_v_max` (each as given in `effects`, else
/// its default), so the effect never acts (a steer controller with
/// `Kc_v_min = 6`, `Kc_v_max = 2` m/s would be analysed as absent without a
/// word). Named by `file` and both fields.
pub fn check_effect_windows_in<R: ModelRegistry>(
    effects: &BTreeMap<String, f64>,
    file: &str,
) -> Result<(), BicycleError> {
    let params = effect_parameters_in::<R>();
    let value = |name: &str| {
        effects
            .get(name)
            .copied()
            .or_else(|| params.iter().find(|p| p.name == name).and_then(|p| p.default))
    };
    for min in params.iter().filter(|p| p.name.ends_with("_v_min")) {
        let max = format!("{}_v_max", min.name.trim_end_matches("_v_min"));
        // Only a window the file sets (a bound of its own) can be its slip.
        if !effects.contains_key(min.name) && !effects.contains_key(&max) {
            continue;
        }
        if let (Some(lo), Some(hi)) = (value(min.name), value(&max)) {
            if lo >= hi {
                return Err(BicycleError::EffectParameter {
                    file: file.to_string(),
                    why: format!(
                        "`{}` = {lo} m/s is not below `{max}` = {hi} m/s: the effect would act at no speed; the window is {} to {max}",
                        min.name, min.name
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The error for a symbol that names no parameter, listing the effect
/// parameters first (what `--effects` is for) and suggesting the closest
/// symbol of any kind when one is close.
fn unknown_parameter<R: ModelRegistry>(symbol: &str) -> BicycleError {
    let effects: Vec<&str> = effect_parameters_in::<R>().iter().map(|p| p.name).collect();
    let closest = effects
        .iter()
        .chain(ThesisParameters::SYMBOLS.iter())
        .chain(BenchmarkParameters::SYMBOLS.iter())
        .map(|c| (edit_distance(&symbol.to_lowercase(), &c.to_lowercase()), *c))
        .min();
    let suggestion = match closest {
        Some((d, c)) if d <= 2.max(symbol.len() / 3) && d < symbol.len() => format!(" (did you mean `{c}`?)"),
        _ => String::new(),
    };
    BicycleError::UnknownParameter {
        name: symbol.to_string(),
        suggestion,
        effects: effects.join(", "),
        thesis: ThesisParameters::SYMBOLS.join(", "),
        benchmark: BenchmarkParameters::SYMBOLS.join(", "),
    }
}

/// Levenshtein distance (for suggestions among a few dozen symbols).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(row[j + 1] + 1);
            prev = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// Set one serde-named field (the parameter symbol) of a parameter struct.
// The field itself, not a round trip through JSON values: a stability map
// sets two parameters per design, and the round trip was a tenth of the
// map's time in the browser's module (2026-11-29).
fn set_field<P: Clone + SetField>(p: &P, symbol: &str, value: f64) -> Result<P, BicycleError> {
    let mut p = p.clone();
    *p.field_mut(symbol)
        .ok_or_else(|| unknown_parameter::<BuiltIn>(symbol))? = value;
    Ok(p)
}

/// A parameter struct's field by symbol.
trait SetField {
    fn field_mut(&mut self, symbol: &str) -> Option<&mut f64>;
}
impl SetField for ThesisParameters {
    fn field_mut(&mut self, symbol: &str) -> Option<&mut f64> {
        self.get_mut(symbol)
    }
}
impl SetField for BenchmarkParameters {
    fn field_mut(&mut self, symbol: &str) -> Option<&mut f64> {
        self.get_mut(symbol)
    }
}

/// The default model of a bicycle without effect parameters, as
/// [`Bicycle::model`] chooses it among the models of registry `R`, by bit
/// masks over the thesis symbols (the choice is made once per design in a
/// sweep, so it avoids comparing names). `None` when no model fits or the
/// one chosen has a non-zero thesis symbol as an effect parameter: the
/// general choice reports why.
fn default_model_of<R: ModelRegistry>(t: &ThesisParameters) -> Option<&'static ModelInfo> {
    let index = index::<R>();
    let nonzero = t
        .values()
        .iter()
        .enumerate()
        .fold(0u64, |m, (i, &v)| m | ((v != 0.0) as u64) << i);
    let k = index.thesis_masks.iter().position(|&(has, _)| nonzero & !has == 0)?;
    (nonzero & index.thesis_masks[k].1 == 0).then(|| index.driven_by_size[k])
}
