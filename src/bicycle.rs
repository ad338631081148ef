//! Bicycles as users name them (built-in names or parameter files), mapped to
//! the generated model that represents them and to their canonical matrices.

use crate::models::{effect_parameters_in, fits, index};
use crate::registry::BuiltIn;
use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::eigen::LinearBicycle;
use bikedyn_runtime::linearize::{canonical_matrices, LinearModel, LinearizeError};
use bikedyn_runtime::parameters::{
    BenchmarkParameters, ParameterError, ParameterSet, ParameterWarning, ThesisParameters,
};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::MultibodyModel;
use std::collections::BTreeMap;
use std::marker::PhantomData;
use std::path::Path;
use thiserror::Error;

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
    #[error("unknown parameter `{name}`: use a thesis symbol ({thesis}) or a benchmark symbol ({benchmark})")]
    UnknownParameter {
        name: String,
        thesis: String,
        benchmark: String,
    },
    #[error("`{spec}` is neither a built-in bicycle (thesis, benchmark) nor an existing file")]
    NotFound { spec: String },
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
    #[error("the canonical form M0, C1, K0, K2 holds for the Whipple bicycle; with {effects} the linear equations depend on speed otherwise")]
    NotCanonical { effects: String },
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
    registry: PhantomData<R>,
}

impl Bicycle {
    /// Resolve `thesis`, `benchmark` or a parameter file (TOML in either form,
    /// or the `name = value[+/-std]` text form of bicycleparameters/HumanControl)
    /// against the built-in models.
    pub fn resolve(spec: &str) -> Result<Bicycle, BicycleError> {
        Self::resolve_in(spec)
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
                let (set, effects, warnings) = ParameterSet::load_with_extra(path, &extra)?;
                for (name, &value) in &effects {
                    check_effect_value_in::<R>(name, value, path)?;
                }
                return Ok(Bicycle {
                    name: spec.to_string(),
                    parameters: set,
                    warnings,
                    effects,
                    registry: PhantomData,
                });
            }
            _ => return Err(BicycleError::NotFound { spec: spec.to_string() }),
        };
        Ok(Bicycle {
            name: spec.to_string(),
            parameters,
            warnings,
            effects: BTreeMap::new(),
            registry: PhantomData,
        })
    }

    /// Parameters this bicycle sets to a non-zero value: thesis symbols and
    /// effect parameters (with their values).
    pub fn nonzero_parameters(&self) -> Result<Vec<(&'static str, f64)>, BicycleError> {
        let t = self.thesis()?;
        let mut out: Vec<(&'static str, f64)> = ThesisParameters::SYMBOLS
            .iter()
            .filter_map(|&s| t.get(s).filter(|&v| v != 0.0).map(|v| (s, v)))
            .collect();
        for p in effect_parameters_in::<R>() {
            if let Some(&v) = self.effects.get(p.name) {
                if Some(v) != p.default && v != 0.0 {
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
                .ok_or_else(|| BicycleError::NoModelFits {
                    bike: self.name.clone(),
                    nonzero: nonzero.iter().map(|(s, _)| *s).collect::<Vec<_>>().join(", "),
                }),
        }
    }

    /// Lookup of every parameter by symbol: thesis form, then benchmark
    /// form, then the effect parameters given (absent ones: the model default).
    pub fn lookup(&self) -> Result<impl Fn(&str) -> Option<f64> + '_, BicycleError> {
        let t = self.thesis()?;
        Ok(move |s: &str| t.get(s).or_else(|| self.effects.get(s).copied()))
    }

    /// Canonical matrices through a chosen model (`None`: the default model).
    pub fn canonical_with(&self, model: Option<&str>) -> Result<CanonicalMatrices, BicycleError> {
        if model.is_none() && self.effects.is_empty() {
            let t = self.thesis()?;
            if let Some(info) = default_model_of::<R>(&t) {
                if t.rear_wheel_radius != 0.0 && t.front_wheel_radius != 0.0 {
                    return R::with_model(info.name, Canonical(&|s: &str| t.get(s)))
                        .expect("registered model")
                        .map_err(|source| BicycleError::Linearize {
                            bike: self.name.clone(),
                            source,
                        });
                }
            }
        }
        let nonzero = self.nonzero_parameters()?;
        let info = self.model_for(model, &nonzero)?;
        let active: Vec<String> = nonzero
            .into_iter()
            .filter(|(s, _)| info.parameter(s).is_some_and(|p| p.effect.is_some()))
            .map(|(s, v)| format!("{s} = {v}"))
            .collect();
        if !active.is_empty() {
            return Err(BicycleError::NotCanonical {
                effects: active.join(", "),
            });
        }
        let t = self.thesis()?;
        if t.rear_wheel_radius == 0.0 || t.front_wheel_radius == 0.0 {
            // No effect is active here, so the matrices are the Whipple
            // bicycle's, which the built-in models give for any registry.
            return canonical_zero_radius(&t);
        }
        let lookup = self.lookup()?;
        R::with_model(info.name, Canonical(&lookup))
            .expect("registered model")
            .map_err(|source| BicycleError::Linearize {
                bike: self.name.clone(),
                source,
            })
    }

    /// The linear roll-steer equations of this bicycle at every speed,
    /// through model `model` (`None`: the default model, [`Bicycle::model`]):
    /// the canonical matrices when the equations have that form (no effect
    /// active), otherwise the model linearized at each speed (damping,
    /// controllers, drag: any effect).
    pub fn linear_with(&self, model: Option<&str>) -> Result<Linear, BicycleError> {
        let nonzero = self.nonzero_parameters()?;
        let info = self.model_for(model, &nonzero)?;
        // A model with extra states has no canonical form (nor M, C, K).
        let canonical = if info.states.is_empty() {
            self.canonical_with(model)
        } else {
            Err(BicycleError::NotCanonical {
                effects: info.states.join(", "),
            })
        };
        match canonical {
            Ok(c) => {
                return Ok(Linear {
                    model: info.name,
                    canonical: Some(c),
                    equations: Box::new(c),
                })
            }
            Err(BicycleError::NotCanonical { .. }) => {}
            Err(e) => return Err(e),
        }
        let lookup = self.lookup()?;
        let equations = R::with_model(info.name, MakeLinear(&lookup))
            .expect("registered model")
            .map_err(|source| BicycleError::Linearize {
                bike: self.name.clone(),
                source,
            })?;
        Ok(Linear {
            model: info.name,
            canonical: None,
            equations,
        })
    }

    /// Thesis-form parameters (converted if given in benchmark form).
    pub fn thesis(&self) -> Result<ThesisParameters, BicycleError> {
        Ok(self.parameters.to_thesis()?)
    }

    /// Canonical matrices from the generated multibody equations, through
    /// the default model.
    pub fn canonical(&self) -> Result<CanonicalMatrices, BicycleError> {
        self.canonical_with(None)
    }

    /// The same bicycle with one parameter changed. `symbol` is a thesis
    /// symbol (`Rt`, `x4`, `d4`, ...) or a benchmark symbol (`c`, `lam`, ...).
    pub fn with_parameter(&self, symbol: &str, value: f64) -> Result<Bicycle<R>, BicycleError> {
        if effect_parameters_in::<R>().iter().any(|p| p.name == symbol) {
            check_effect_value_in::<R>(symbol, value, &self.name)?;
            let mut b = self.clone();
            b.effects.insert(symbol.to_string(), value);
            b.name = format!("{} ({symbol} = {value})", self.name);
            return Ok(b);
        }
        let parameters = if ThesisParameters::SYMBOLS.contains(&symbol) {
            ParameterSet::Thesis(set_field(&self.thesis()?, symbol, value)?)
        } else if BenchmarkParameters::SYMBOLS.contains(&symbol) {
            ParameterSet::Benchmark(set_field(&self.parameters.to_benchmark()?, symbol, value)?)
        } else {
            return Err(BicycleError::UnknownParameter {
                name: symbol.to_string(),
                thesis: ThesisParameters::SYMBOLS.join(", "),
                benchmark: BenchmarkParameters::SYMBOLS.join(", "),
            });
        };
        let warnings = parameters.validate()?;
        Ok(Bicycle {
            name: format!("{} ({symbol} = {value})", self.name),
            parameters,
            warnings,
            effects: self.effects.clone(),
            registry: PhantomData,
        })
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

/// Set one serde-named field (the parameter symbol) of a parameter struct.
fn set_field<P: serde::Serialize + serde::de::DeserializeOwned>(
    p: &P,
    symbol: &str,
    value: f64,
) -> Result<P, BicycleError> {
    let mut v = serde_json::to_value(p).expect("parameter structs serialize");
    v[symbol] = serde_json::Value::from(value);
    serde_json::from_value(v).map_err(|_| BicycleError::UnknownParameter {
        name: symbol.to_string(),
        thesis: ThesisParameters::SYMBOLS.join(", "),
        benchmark: BenchmarkParameters::SYMBOLS.join(", "),
    })
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

/// The linear roll-steer equations of a bicycle through the model chosen.
pub struct Linear {
    /// The generated model they come from.
    pub model: &'static str,
    /// The canonical matrices, when the equations have that form.
    pub canonical: Option<CanonicalMatrices>,
    /// The equations at every speed.
    pub equations: Box<dyn LinearBicycle + Send>,
}

impl LinearBicycle for Linear {
    fn at_speed(&self, v: f64) -> Result<bikedyn_runtime::eigen::SpeedMatrices, bikedyn_runtime::eigen::EigenError> {
        self.equations.at_speed(v)
    }
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        self.canonical.as_ref()
    }
    fn first_order(&self) -> Option<&dyn bikedyn_runtime::eigen::StateSpaceBicycle> {
        self.equations.first_order()
    }
}

struct MakeLinear<'a, F: Fn(&str) -> Option<f64>>(&'a F);
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for MakeLinear<'_, F> {
    type Output = Result<Box<dyn LinearBicycle + Send>, LinearizeError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        Ok(Box::new(LinearModel::<M>::new(self.0)?))
    }
}

struct Canonical<'a, F: Fn(&str) -> Option<f64>>(&'a F);
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for Canonical<'_, F> {
    type Output = Result<CanonicalMatrices, LinearizeError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        canonical_matrices::<M>(self.0)
    }
}

/// Canonical matrices of thesis-form parameters, through the model that fits
/// them (the thesis model when the fork mass centre is on the steer axis,
/// the offset variant otherwise; chosen from the registry by parameters).
///
/// A wheel of zero radius (a skate, as in the two-mass-skate bicycle of
/// Kooijman et al. 2011) has its contact point at the wheel centre. The
/// generated model cannot represent it directly (its driving constraint
/// divides by the rear radius and the rim angle of the front contact is then
/// undetermined), so the zero-radius bicycle is reached as a limit: with the
/// wheel's spin inertia zero, the canonical matrices are polynomials of
/// degree 2 in the wheel radii at fixed benchmark geometry (Meijaard et al.
/// 2007, eqs. A 1 - A 27: the radii enter through `mT zT`, `ITxx`, `ITxz`,
/// `zA`, `IAxx`, `IAxz`, `uA`, none above the second power). They are
/// evaluated at radius `h, 2h, 3h` and extrapolated exactly to 0; a fourth
/// radius `4h` checks that the third difference vanishes.
pub fn canonical_of(p: &ThesisParameters) -> Result<CanonicalMatrices, BicycleError> {
    // The default model directly (what `Bicycle::canonical_with` does first),
    // without building a `Bicycle`: this runs once per design in a sweep.
    if p.rear_wheel_radius != 0.0 && p.front_wheel_radius != 0.0 {
        if let Some(info) = default_model_of::<BuiltIn>(p) {
            return crate::generated::with_model(info.name, Canonical(&|s: &str| p.get(s)))
                .expect("registered model")
                .map_err(|source| BicycleError::Linearize {
                    bike: "parameters".into(),
                    source,
                });
        }
    }
    Bicycle::<BuiltIn> {
        name: "parameters".into(),
        parameters: ParameterSet::Thesis(*p),
        warnings: Vec::new(),
        effects: BTreeMap::new(),
        registry: PhantomData,
    }
    .canonical()
}

/// Canonical matrices of a bicycle with one or both wheel radii zero (see
/// [`canonical_of`]).
fn canonical_zero_radius(p: &ThesisParameters) -> Result<CanonicalMatrices, BicycleError> {
    let lin = |source| BicycleError::Linearize {
        bike: "zero-radius bicycle".into(),
        source,
    };
    use bikedyn_runtime::parameters::body;
    if p.rear_wheel_radius == 0.0 && p.rear_wheel_i_axial != 0.0 {
        return Err(lin(LinearizeError::SkateWithSpinInertia {
            wheel: body::REAR_WHEEL,
            radius_symbol: "Rt (rR)",
            inertia_symbol: "I2y (IRyy)",
            inertia: p.rear_wheel_i_axial,
        }));
    }
    if p.front_wheel_radius == 0.0 && p.front_wheel_i_axial != 0.0 {
        return Err(lin(LinearizeError::SkateWithSpinInertia {
            wheel: body::FRONT_WHEEL,
            radius_symbol: "Rd (rF)",
            inertia_symbol: "I5y (IFyy)",
            inertia: p.front_wheel_i_axial,
        }));
    }
    let bench = p.to_benchmark()?;
    // Step: a tenth of the wheelbase keeps every sample a plain bicycle.
    let h = 0.1 * bench.wheelbase;
    let at = |s: f64| -> Result<CanonicalMatrices, BicycleError> {
        let mut b = bench;
        if p.rear_wheel_radius == 0.0 {
            b.rear_wheel_radius = s;
        }
        if p.front_wheel_radius == 0.0 {
            b.front_wheel_radius = s;
        }
        canonical_of(&b.to_thesis()?)
    };
    let f = [at(h)?, at(2.0 * h)?, at(3.0 * h)?, at(4.0 * h)?];
    let combine = |w: [f64; 4], get: &dyn Fn(&CanonicalMatrices) -> f64| -> f64 {
        w.iter().zip(&f).map(|(wi, fi)| wi * get(fi)).sum()
    };
    type Entry = fn(&CanonicalMatrices) -> nalgebra::Matrix2<f64>;
    let entries: [Entry; 4] = [|c| c.m0, |c| c.c1, |c| c.k0, |c| c.k2];
    let mut out = [nalgebra::Matrix2::zeros(); 4];
    for (m, get) in entries.iter().enumerate() {
        // Rounding is relative to the matrix, not to an entry that may be
        // structurally zero.
        let scale = f.iter().fold(0.0f64, |a, c| a.max(get(c).amax()));
        for i in 0..2 {
            for j in 0..2 {
                let e = |c: &CanonicalMatrices| get(c)[(i, j)];
                // Third difference: zero for a quadratic, up to rounding.
                let departure = combine([-1.0, 3.0, -3.0, 1.0], &e).abs();
                if departure.is_nan() || departure > 1e-9 * scale {
                    return Err(lin(LinearizeError::ZeroRadiusLimit { departure, scale }));
                }
                // Lagrange extrapolation of a quadratic to radius 0.
                out[m][(i, j)] = combine([3.0, -3.0, 1.0, 0.0], &e);
            }
        }
    }
    Ok(CanonicalMatrices {
        m0: out[0],
        c1: out[1],
        k0: out[2],
        k2: out[3],
        g: bench.g,
    })
}
