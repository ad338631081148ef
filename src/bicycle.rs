//! Bicycles as users name them (built-in names or parameter files), mapped to
//! the generated model that represents them and to their canonical matrices.

use crate::generated::{ThesisWhipple, WhippleOffset};
use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::linearize::{canonical_matrices, LinearizeError};
use bikedyn_runtime::parameters::{
    BenchmarkParameters, ParameterError, ParameterSet, ParameterWarning, ThesisParameters,
};
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
}

/// A resolved bicycle.
#[derive(Clone, Debug)]
pub struct Bicycle {
    /// Built-in name or file path.
    pub name: String,
    /// Parameters as given (thesis or benchmark form).
    pub parameters: ParameterSet,
    /// Validation warnings (e.g. triangle inequality of inertia tensors).
    pub warnings: Vec<ParameterWarning>,
}

impl Bicycle {
    /// Resolve `thesis`, `benchmark` or a parameter file (TOML in either form,
    /// or the `name = value[+/-std]` text form of bicycleparameters/HumanControl).
    pub fn resolve(spec: &str) -> Result<Bicycle, BicycleError> {
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
            path if Path::new(path).exists() => ParameterSet::load(path)?,
            _ => return Err(BicycleError::NotFound { spec: spec.to_string() }),
        };
        Ok(Bicycle {
            name: spec.to_string(),
            parameters,
            warnings,
        })
    }

    /// Thesis-form parameters (converted if given in benchmark form).
    pub fn thesis(&self) -> Result<ThesisParameters, BicycleError> {
        Ok(self.parameters.to_thesis()?)
    }

    /// Canonical matrices from the generated multibody equations.
    pub fn canonical(&self) -> Result<CanonicalMatrices, BicycleError> {
        canonical_of(&self.thesis()?).map_err(|source| BicycleError::Linearize {
            bike: self.name.clone(),
            source,
        })
    }

    /// The same bicycle with one parameter changed. `symbol` is a thesis
    /// symbol (`Rt`, `x4`, `d4`, ...) or a benchmark symbol (`c`, `lam`, ...).
    pub fn with_parameter(&self, symbol: &str, value: f64) -> Result<Bicycle, BicycleError> {
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
        })
    }

    /// Value of a thesis or benchmark symbol.
    pub fn value(&self, symbol: &str) -> Option<f64> {
        self.thesis()
            .ok()
            .and_then(|t| t.get(symbol))
            .or_else(|| self.parameters.to_benchmark().ok().and_then(|b| b.get(symbol)))
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

/// Canonical matrices of thesis-form parameters: the thesis model when the
/// fork mass centre is on the steer axis (`d4 = 0`), the offset variant
/// otherwise.
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
pub fn canonical_of(p: &ThesisParameters) -> Result<CanonicalMatrices, LinearizeError> {
    if p.rear_wheel_radius == 0.0 || p.front_wheel_radius == 0.0 {
        return canonical_zero_radius(p);
    }
    if p.fork_com_offset == 0.0 {
        canonical_matrices::<ThesisWhipple>(|s| p.get(s))
    } else {
        canonical_matrices::<WhippleOffset>(|s| p.get(s))
    }
}

/// Canonical matrices of a bicycle with one or both wheel radii zero (see
/// [`canonical_of`]).
fn canonical_zero_radius(p: &ThesisParameters) -> Result<CanonicalMatrices, LinearizeError> {
    use bikedyn_runtime::parameters::body;
    if p.rear_wheel_radius == 0.0 && p.rear_wheel_i_axial != 0.0 {
        return Err(LinearizeError::SkateWithSpinInertia {
            wheel: body::REAR_WHEEL,
            radius_symbol: "Rt (rR)",
            inertia_symbol: "I2y (IRyy)",
            inertia: p.rear_wheel_i_axial,
        });
    }
    if p.front_wheel_radius == 0.0 && p.front_wheel_i_axial != 0.0 {
        return Err(LinearizeError::SkateWithSpinInertia {
            wheel: body::FRONT_WHEEL,
            radius_symbol: "Rd (rF)",
            inertia_symbol: "I5y (IFyy)",
            inertia: p.front_wheel_i_axial,
        });
    }
    let bench = p
        .to_benchmark()
        .map_err(|e| LinearizeError::Parameters(e.to_string()))?;
    // Step: a tenth of the wheelbase keeps every sample a plain bicycle.
    let h = 0.1 * bench.wheelbase;
    let at = |s: f64| -> Result<CanonicalMatrices, LinearizeError> {
        let mut b = bench;
        if p.rear_wheel_radius == 0.0 {
            b.rear_wheel_radius = s;
        }
        if p.front_wheel_radius == 0.0 {
            b.front_wheel_radius = s;
        }
        let t = b.to_thesis().map_err(|e| LinearizeError::Parameters(e.to_string()))?;
        canonical_of(&t)
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
                    return Err(LinearizeError::ZeroRadiusLimit { departure, scale });
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
