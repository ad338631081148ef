//! Which parameters move the weave and capsize speeds, and the eigenvalues
//! at a speed, and by how much: exact derivatives with respect to every
//! parameter of a bicycle (`bikedyn sensitivity`; issue 36, item 2).
//!
//! The method is in `bikedyn_runtime::sensitivity`: eigenvalue derivatives
//! from the left and right null vectors of `P(s) = s^2 M0 + s v C1 + g K0 +
//! v^2 K2`, critical-speed derivatives by the implicit function theorem on
//! `Re s(v, p) = 0`, and the exact parameter derivatives of the canonical
//! matrices from their closed form (Meijaard et al. 2007, appendix A) in
//! dual numbers. The matrices themselves (and so the eigenvalues and the
//! critical speeds) are the generated model's, as every other command
//! reports them; the closed form must agree with them to 1e-8 before its
//! derivatives are used.
//!
//! The parameters are the 26 of the form the bicycle was given in (or the
//! one asked for): the benchmark form (Meijaard et al. 2007, Table 1), of
//! which the canonical matrices are closed-form functions, or the thesis
//! form, through the conversion between the two, also in dual numbers. The
//! result is for the Whipple
//! bicycle, which is what the canonical form describes: a bicycle with an
//! effect (damping, friction, a controller) is refused, since the generated
//! code gives first derivatives only and the mixed derivatives a
//! linearization's parameter sensitivity needs are not available exactly.

use crate::bicycle::{Bicycle, BicycleError};
use crate::registry::ModelRegistry;
use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::eigen::critical_speeds;
use bikedyn_runtime::parameters::{Form, ParameterSet};
/// Why the numerics could not differentiate (a double eigenvalue, a
/// crossing tangent to the axis), the source of [`SensitivityError::Runtime`].
pub use bikedyn_runtime::sensitivity::SensitivityError as RuntimeError;
use bikedyn_runtime::sensitivity::{
    critical_speed_sensitivities, eigenvalue_sensitivities, CanonicalJacobian, CriticalSensitivity, ModeSensitivity,
};
use serde::Serialize;
use thiserror::Error;

/// How far the closed-form matrices may depart from the generated model's
/// (relative to each matrix's largest entry) before the derivatives of the
/// one are refused for the other. The two agree to about 1e-13 on real and
/// random designs (`tests/linear_analysis/real_designs.rs` asserts 1e-9).
pub const CLOSED_FORM_TOLERANCE: f64 = 1e-8;

/// What [`sensitivity`] computes.
#[derive(Clone, Debug, PartialEq)]
pub struct SensitivityOptions {
    /// Generated model (`None`: the bicycle's default model).
    pub model: Option<String>,
    /// The parameters differentiated with respect to: those of this form
    /// (`None`: the form the bicycle was given in).
    pub form: Option<Form>,
    /// Speed (m/s) of the eigenvalue derivatives; `None`: none.
    pub speed: Option<f64>,
    /// The critical speeds are searched on 0 to this speed (m/s).
    pub speed_max: f64,
}

impl Default for SensitivityOptions {
    fn default() -> Self {
        SensitivityOptions {
            model: None,
            form: None,
            speed: None,
            speed_max: 10.0,
        }
    }
}

/// The eigenvalue derivatives at one speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EigenvaluesAt {
    /// Forward speed (m/s).
    pub speed: f64,
    /// One entry per real eigenvalue and per conjugate pair (its root with
    /// positive imaginary part), in mode order.
    pub modes: Vec<ModeSensitivity>,
}

/// The sensitivities of a bicycle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sensitivity {
    /// The bicycle (built-in name or file).
    pub bike: String,
    /// The generated model of the matrices.
    pub model: &'static str,
    /// The parameters' form: `benchmark` (Meijaard et al. 2007, Table 1
    /// symbols) or `thesis` (Martin Recuero 2009); SI units.
    pub parameter_form: &'static str,
    /// The searched speeds' upper end (m/s).
    pub speed_max: f64,
    /// The weave speed's sensitivity; `None` when there is no weave
    /// crossing in the range.
    pub weave_speed: Option<CriticalSensitivity>,
    /// The capsize speed's; `None` when there is no capsize crossing.
    pub capsize_speed: Option<CriticalSensitivity>,
    /// The eigenvalues' at the speed asked for.
    pub eigenvalues: Option<EigenvaluesAt>,
    /// Largest relative difference between the closed-form canonical
    /// matrices and the generated model's.
    pub closed_form_departure: f64,
}

/// Errors of [`sensitivity`].
#[derive(Debug, Error)]
pub enum SensitivityError {
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    #[error("{bike}: sensitivities are exact for the canonical form (the Whipple bicycle) only: {why}")]
    NotCanonical { bike: String, why: String },
    #[error("{bike}: the closed-form canonical matrices depart from the generated model's by {departure:e} (relative), more than {CLOSED_FORM_TOLERANCE:e}: their derivatives would not be those of the model")]
    ClosedFormDisagrees { bike: String, departure: f64 },
    #[error("speed {speed}: the speed of the eigenvalue derivatives must be a finite number (m/s)")]
    NonFiniteSpeed { speed: f64 },
    #[error("upper end of the searched speeds {speed_max}: must be a positive finite speed (m/s)")]
    BadSpeedMax { speed_max: f64 },
    #[error("{bike}: no weave or capsize crossing between 0 and {speed_max} m/s, so there is no critical speed to differentiate")]
    NoCrossing { bike: String, speed_max: f64 },
    #[error("{bike}: {source}")]
    Runtime { bike: String, source: RuntimeError },
}

/// The sensitivities of `bike`'s weave and capsize speeds (searched on 0 to
/// `options.speed_max`) and, at `options.speed`, of its eigenvalues, to
/// every benchmark parameter. Fails when the bicycle has no canonical form
/// (an effect is active), when neither critical speed exists in the range
/// and no speed is asked for, or at a double eigenvalue or a tangent
/// crossing (no derivative there).
pub fn sensitivity<R: ModelRegistry>(
    bike: &Bicycle<R>,
    options: &SensitivityOptions,
) -> Result<Sensitivity, SensitivityError> {
    if let Some(v) = options.speed {
        if !v.is_finite() {
            return Err(SensitivityError::NonFiniteSpeed { speed: v });
        }
    }
    if !(options.speed_max.is_finite() && options.speed_max > 0.0) {
        return Err(SensitivityError::BadSpeedMax {
            speed_max: options.speed_max,
        });
    }
    let (c, jac, model, form) = canonical_and_jacobian(bike, options.model.as_deref(), options.form)?;
    let runtime = |source| SensitivityError::Runtime {
        bike: bike.name.clone(),
        source,
    };
    let crit = critical_speeds(&c, 0.0, options.speed_max).map_err(|e| runtime(e.into()))?;
    if crit.weave_speed.is_none() && crit.capsize_speed.is_none() && options.speed.is_none() {
        return Err(SensitivityError::NoCrossing {
            bike: bike.name.clone(),
            speed_max: options.speed_max,
        });
    }
    let (weave, capsize) = critical_speed_sensitivities(&c, &jac, &crit).map_err(runtime)?;
    let eigenvalues = match options.speed {
        Some(v) => Some(EigenvaluesAt {
            speed: v,
            modes: eigenvalue_sensitivities(&c, &jac, v).map_err(runtime)?,
        }),
        None => None,
    };
    Ok(Sensitivity {
        bike: bike.name.clone(),
        model,
        parameter_form: form.name(),
        speed_max: options.speed_max,
        weave_speed: weave,
        capsize_speed: capsize,
        eigenvalues,
        closed_form_departure: jac.departure(&c),
    })
}

/// The canonical matrices of `bike` through `model`, the Jacobian of the
/// closed-form matrices with respect to the parameters of `form` (default:
/// the bicycle's own), checked to agree with the generated model's.
fn canonical_and_jacobian<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: Option<&str>,
    form: Option<Form>,
) -> Result<(CanonicalMatrices, CanonicalJacobian, &'static str, Form), SensitivityError> {
    let lin = bike.linear_with(model)?;
    let Some(c) = lin.canonical else {
        let why = bike
            .canonical_with(model)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_else(|| format!("model `{}` has no canonical form", lin.model));
        return Err(SensitivityError::NotCanonical {
            bike: bike.name.clone(),
            why,
        });
    };
    let form = form.unwrap_or(match bike.parameters {
        ParameterSet::Thesis(_) => Form::Thesis,
        ParameterSet::Benchmark(_) => Form::Benchmark,
    });
    let jac = match form {
        Form::Benchmark => CanonicalJacobian::of(&bike.parameters.to_benchmark().map_err(BicycleError::from)?),
        Form::Thesis => CanonicalJacobian::of_thesis(&bike.thesis()?).map_err(BicycleError::from)?,
    };
    let departure = jac.departure(&c);
    if departure.is_nan() || departure > CLOSED_FORM_TOLERANCE {
        return Err(SensitivityError::ClosedFormDisagrees {
            bike: bike.name.clone(),
            departure,
        });
    }
    Ok((c, jac, lin.model, form))
}

/// The standard deviations of a bicycle's eigenvalues that its file's
/// standard deviations imply, to first order with the exact eigenvalue
/// derivatives (parameters independent, as for [`speed_uncertainties`]).
pub struct EigenvalueSpread {
    canonical: CanonicalMatrices,
    jacobian: CanonicalJacobian,
    standard_deviations: std::collections::BTreeMap<String, f64>,
}

impl EigenvalueSpread {
    /// The spread of `bike` through `model`; `None` when its file gives
    /// no standard deviations.
    pub fn of<R: ModelRegistry>(bike: &Bicycle<R>, model: Option<&str>) -> Result<Option<Self>, SensitivityError> {
        if bike.uncertainties.is_empty() {
            return Ok(None);
        }
        let (canonical, jacobian, _, _) = canonical_and_jacobian(bike, model, None)?;
        Ok(Some(EigenvalueSpread {
            canonical,
            jacobian,
            standard_deviations: bike.uncertainties.clone(),
        }))
    }

    /// At speed `v` (m/s): one entry per real eigenvalue and per conjugate
    /// pair (its root with positive imaginary part; the conjugate's are the
    /// same); `None` where an eigenvalue is double (no derivative there).
    pub fn at(&self, v: f64) -> Option<Vec<EigenvalueUncertainty>> {
        let modes = eigenvalue_sensitivities(&self.canonical, &self.jacobian, v).ok()?;
        Some(
            modes
                .iter()
                .map(|m| {
                    let mut var = [0.0f64; 2];
                    for d in &m.derivatives {
                        if let Some(sd) = self.standard_deviations.get(d.parameter) {
                            var[0] += (d.derivative[0] * sd).powi(2);
                            var[1] += (d.derivative[1] * sd).powi(2);
                        }
                    }
                    EigenvalueUncertainty {
                        mode: m.mode,
                        eigenvalue: m.eigenvalue,
                        standard_deviation: [var[0].sqrt(), var[1].sqrt()],
                    }
                })
                .collect(),
        )
    }

    /// The standard deviations `[re, im]` of each of `eigenvalues` at
    /// speed `v` (`[NaN, NaN]` where there is none).
    pub fn of_eigenvalues(&self, v: f64, eigenvalues: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let at = self.at(v).unwrap_or_default();
        eigenvalues
            .iter()
            .map(|z| {
                let scale = 1.0 + z[0].abs() + z[1].abs();
                at.iter()
                    .map(|u| ((u.eigenvalue[0] - z[0]).abs() + (u.eigenvalue[1] - z[1].abs()).abs(), u))
                    .filter(|(d, _)| *d < 1e-6 * scale)
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .map_or([f64::NAN; 2], |(_, u)| u.standard_deviation)
            })
            .collect()
    }
}

/// The standard deviations of the canonical matrices' entries (and of
/// `g`, which no file gives one for: 0) that a file's standard deviations
/// imply, to first order with the closed form's exact derivatives, the
/// file's parameters taken as independent. `None` when the file gives none.
pub fn canonical_uncertainties<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: Option<&str>,
) -> Result<Option<CanonicalMatrices>, SensitivityError> {
    if bike.uncertainties.is_empty() {
        return Ok(None);
    }
    let (_, jac, _, _) = canonical_and_jacobian(bike, model, None)?;
    let sd = |pick: &dyn Fn(&bikedyn_runtime::sensitivity::CanonicalDerivative) -> nalgebra::Matrix2<f64>| {
        let mut var = nalgebra::Matrix2::zeros();
        for (k, symbol) in jac.symbols.iter().enumerate() {
            if let Some(s) = bike.uncertainties.get(*symbol) {
                var += pick(&jac.d[k]).map(|x| (x * s).powi(2));
            }
        }
        var.map(f64::sqrt)
    };
    Ok(Some(CanonicalMatrices {
        m0: sd(&|d| d.m0),
        c1: sd(&|d| d.c1),
        k0: sd(&|d| d.k0),
        k2: sd(&|d| d.k2),
        g: 0.0,
    }))
}

/// The critical speeds' standard deviations (m/s) over a sweep of one
/// parameter ([`speed_spread_over`]), one per value (`None` where a value
/// leaves no exact derivative or no such speed).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepSpread {
    pub weave_speed: Vec<Option<f64>>,
    pub capsize_speed: Vec<Option<f64>>,
}

/// The standard deviations of the weave and capsize speeds of `bike` with
/// `param` set to each of `values`, from the file's standard deviations
/// without `param`'s own (a swept parameter is set, not measured), to
/// first order as [`speed_uncertainties`]. `None` when setting `param`
/// changes the file's form (a thesis symbol on a benchmark file: the
/// deviations would no longer name the parameters differentiated).
pub fn speed_spread_over<R: ModelRegistry>(
    bike: &Bicycle<R>,
    param: &str,
    values: &[f64],
    options: &SensitivityOptions,
) -> Option<SweepSpread> {
    let mut out = SweepSpread {
        weave_speed: Vec::with_capacity(values.len()),
        capsize_speed: Vec::with_capacity(values.len()),
    };
    for &x in values {
        let u = match bike.with_parameter(param, x) {
            Ok(mut b) => {
                if b.parameters.form() != bike.parameters.form() {
                    return None;
                }
                b.uncertainties.remove(param);
                speed_uncertainties(&b, options).ok().flatten()
            }
            Err(_) => None,
        };
        out.weave_speed.push(
            u.as_ref()
                .and_then(|u| u.weave_speed.as_ref().map(|x| x.standard_deviation)),
        );
        out.capsize_speed.push(
            u.as_ref()
                .and_then(|u| u.capsize_speed.as_ref().map(|x| x.standard_deviation)),
        );
    }
    Some(out)
}

/// An eigenvalue with its standard deviation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EigenvalueUncertainty {
    /// Mode name.
    pub mode: &'static str,
    /// The eigenvalue `[re, im]` (1/s).
    pub eigenvalue: [f64; 2],
    /// Standard deviations of its real and imaginary parts (1/s).
    pub standard_deviation: [f64; 2],
}

/// One parameter's part in a critical speed's variance.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct VarianceShare {
    /// Parameter symbol (the file's own form).
    pub parameter: &'static str,
    /// Its standard deviation, as the file gives it.
    pub standard_deviation: f64,
    /// `(dv/dp sd_p)^2` over the speed's variance.
    pub share: f64,
}

/// A critical speed's standard deviation from the file's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedUncertainty {
    /// The critical speed (m/s).
    pub speed: f64,
    /// Its standard deviation (m/s): `sqrt(sum (dv/dp sd_p)^2)`.
    pub standard_deviation: f64,
    /// The parameters' shares of the variance, largest first (those with a
    /// standard deviation only).
    pub shares: Vec<VarianceShare>,
}

/// The standard deviations of the weave and capsize speeds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StabilityUncertainty {
    pub weave_speed: Option<SpeedUncertainty>,
    pub capsize_speed: Option<SpeedUncertainty>,
}

/// The standard deviations of `bike`'s weave and capsize speeds that the
/// standard deviations its file gives (`value+/-sd`) imply, to first
/// order: `sd_v^2 = sum_p (dv/dp sd_p)^2`, with the exact derivatives of
/// [`sensitivity`] in the file's own form and the file's standard
/// deviations taken as independent (what the files' `+/-` values are:
/// measurement errors of each parameter apart). `None` when the file gives
/// none. Linear propagation holds while the speeds are near linear over a
/// standard deviation of each parameter; the shares say which parameters'
/// measurement limits the speed's.
pub fn speed_uncertainties<R: ModelRegistry>(
    bike: &Bicycle<R>,
    options: &SensitivityOptions,
) -> Result<Option<StabilityUncertainty>, SensitivityError> {
    if bike.uncertainties.is_empty() {
        return Ok(None);
    }
    let s = sensitivity(
        bike,
        &SensitivityOptions {
            form: None,
            speed: None,
            ..options.clone()
        },
    )?;
    let of = |c: &Option<CriticalSensitivity>| {
        c.as_ref().map(|c| {
            let terms: Vec<(&'static str, f64, f64)> = c
                .derivatives
                .iter()
                .filter_map(|d| {
                    let sd = *bike.uncertainties.get(d.parameter)?;
                    Some((d.parameter, sd, (d.derivative * sd).powi(2)))
                })
                .collect();
            let variance: f64 = terms.iter().map(|t| t.2).sum();
            let mut shares: Vec<VarianceShare> = terms
                .iter()
                .map(|&(parameter, standard_deviation, v)| VarianceShare {
                    parameter,
                    standard_deviation,
                    share: if variance > 0.0 { v / variance } else { 0.0 },
                })
                .collect();
            shares.sort_by(|a, b| b.share.total_cmp(&a.share));
            SpeedUncertainty {
                speed: c.speed,
                standard_deviation: variance.sqrt(),
                shares,
            }
        })
    };
    Ok(Some(StabilityUncertainty {
        weave_speed: of(&s.weave_speed),
        capsize_speed: of(&s.capsize_speed),
    }))
}
