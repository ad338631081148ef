//! Linear predictions of the weave eigenvalue (1/s): the driven-speed
//! model with effect values on top of the bicycle, each effect replaced by
//! its declared linear equivalent; the tyre model through its state-space
//! linearization.

use super::candidates::identification_models;
use super::error::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::feedback::GainSchedule;
use bikedyn_runtime::identify::discovery::PlantAt;
use bikedyn_runtime::linearize::{lateral_block, linearize_at_speed, parameter_vector, state_space_at_speed};
use bikedyn_runtime::model::{CandidateDeclaration, EffectIdentification, LinearEquivalent};
use bikedyn_runtime::parameters::BenchmarkParameters;
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::MultibodyModel;
use std::collections::BTreeMap;

/// Weave eigenvalue `[re, im]` of a linearization (the complex pair with
/// the highest frequency), if any, with the bicycle's `[feedback]` at
/// speed `v` closed around it.
fn weave_of(
    l: &bikedyn_runtime::linearize::Linearization,
    feedback: Option<&GainSchedule>,
    v: f64,
) -> Option<[f64; 2]> {
    let m = nalgebra::Matrix2::from_fn(|i, j| l.mass[(i, j)]);
    let mut c = nalgebra::Matrix2::from_fn(|i, j| l.damping[(i, j)]);
    let mut k = nalgebra::Matrix2::from_fn(|i, j| l.stiffness[(i, j)]);
    if let Some(f) = feedback {
        // The gains are in the benchmark's signs (steer positive to the
        // right); the models' steer is positive to the left: S K S with
        // S = diag(1, -1), as the linear analyses convert.
        let s = nalgebra::Matrix2::new(1.0, 0.0, 0.0, -1.0);
        let (kp, kd) = f.stiffness_and_damping(v);
        k += s * kp * s;
        c += s * kd * s;
    }
    let mi = m.try_inverse()?;
    let (a, b) = (-mi * k, -mi * c);
    let mut s = nalgebra::Matrix4::zeros();
    s[(0, 2)] = 1.0;
    s[(1, 3)] = 1.0;
    for i in 0..2 {
        for j in 0..2 {
            s[(2 + i, j)] = a[(i, j)];
            s[(2 + i, 2 + j)] = b[(i, j)];
        }
    }
    s.complex_eigenvalues()
        .iter()
        .filter(|z| z.im > 1e-9)
        .max_by(|x, y| x.im.total_cmp(&y.im))
        .map(|z| [z.re, z.im])
}

struct WeaveCurve<'a> {
    lookup: &'a dyn Fn(&str) -> Option<f64>,
    speeds: &'a [f64],
    feedback: Option<&'a GainSchedule>,
}

impl ModelVisitor for WeaveCurve<'_> {
    type Output = Result<Vec<Option<[f64; 2]>>, IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let p = parameter_vector::<M>(self.lookup, 1.0)?;
        Ok(self
            .speeds
            .iter()
            .map(|&v| {
                linearize_at_speed::<M>(&p, v)
                    .ok()
                    .and_then(|l| weave_of(&lateral_block::<M>(&l), self.feedback, v))
            })
            .collect())
    }
}

/// Predicted weave eigenvalues of the driven model with effect values
/// `values` set on top of the bicycle, at each of `speeds` (m/s); `driven`
/// is a model of the bicycle's registry.
pub fn predict<R: ModelRegistry>(
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    values: &BTreeMap<String, f64>,
    speeds: &[f64],
) -> Result<Vec<Option<[f64; 2]>>, IdentifyError> {
    // A corrected quantity of the bicycle file that the model holds in
    // several parameters (the front assembly's mass centre) goes through
    // the file's exact conversion; the rest overlays the model's values.
    let file_quantities: Vec<(&String, f64)> = values
        .iter()
        .filter(|(k, _)| driven.parameter(k).is_none() && BenchmarkParameters::SYMBOLS.contains(&k.as_str()))
        .map(|(k, v)| (k, *v))
        .collect();
    let corrected;
    let bike = if file_quantities.is_empty() {
        bike
    } else {
        let mut b = bike.clone();
        for (k, v) in &file_quantities {
            b = b.with_parameter(k, *v)?;
        }
        corrected = b;
        &corrected
    };
    let values: BTreeMap<String, f64> = values
        .iter()
        .filter(|(k, _)| !file_quantities.iter().any(|(q, _)| q == k))
        .map(|(k, v)| (k.clone(), *v))
        .collect();
    let values = &values;
    let base = bike.lookup()?;
    let lookup = |s: &str| values.get(s).copied().or_else(|| base(s));
    let guide = R::with_model(
        driven.name,
        WeaveCurve {
            lookup: &lookup,
            speeds,
            feedback: bike.feedback.as_ref(),
        },
    )
    .expect("registered model")?;
    // Effects the driven model lacks (the tyre model's) are predicted with
    // the alternative model's state-space linearization.
    if let Some(alt) = values
        .keys()
        .any(|k| driven.parameter(k).is_none())
        .then(|| identification_models(bike, false).ok().and_then(|m| m.2))
        .flatten()
    {
        if bike.feedback.is_some() {
            return Err(crate::bicycle::BicycleError::FeedbackOnStates {
                bike: bike.name.clone(),
                model: alt.name.to_string(),
                states: alt.states.join(", "),
            }
            .into());
        }
        return R::with_model(
            alt.name,
            StateSpaceWeave {
                lookup: &lookup,
                speeds,
                guide: &guide,
            },
        )
        .expect("registered model");
    }
    Ok(guide)
}

struct PlantCurve<'a> {
    lookup: &'a dyn Fn(&str) -> Option<f64>,
    speeds: &'a [f64],
    feedback: Option<&'a GainSchedule>,
}

impl ModelVisitor for PlantCurve<'_> {
    type Output = Result<Vec<Option<PlantAt>>, IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let p = parameter_vector::<M>(self.lookup, 1.0)?;
        // The models' steer is positive to the left; the benchmark's (and
        // the gains') to the right: S X S with S = diag(1, -1).
        let s = nalgebra::Matrix2::new(1.0, 0.0, 0.0, -1.0);
        Ok(self
            .speeds
            .iter()
            .map(|&v| {
                let l = linearize_at_speed::<M>(&p, v).ok()?;
                let l = lateral_block::<M>(&l);
                let m = |x: &nalgebra::DMatrix<f64>| s * nalgebra::Matrix2::from_fn(|i, j| x[(i, j)]) * s;
                Some(PlantAt {
                    mass: m(&l.mass),
                    damping: m(&l.damping),
                    stiffness: m(&l.stiffness),
                    feedback: self.feedback.map_or(nalgebra::Matrix2x4::zeros(), |f| f.at(v)),
                })
            })
            .collect())
    }
}

/// The linear roll-steer equations of the driven model with effect values
/// `values` on top of the bicycle, in the benchmark's signs, with the
/// bicycle's `[feedback]` gains apart, at each of `speeds` (m/s); `None`
/// where the model cannot be linearized. Only for effects the driven model
/// holds (a model with extra states has no `M, C, K`): `None` for all when
/// a value is of another model.
pub fn plants<R: ModelRegistry>(
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    values: &BTreeMap<String, f64>,
    speeds: &[f64],
) -> Result<Option<Vec<Option<PlantAt>>>, IdentifyError> {
    if values
        .keys()
        .any(|k| driven.parameter(k).is_none() && !BenchmarkParameters::SYMBOLS.contains(&k.as_str()))
    {
        return Ok(None);
    }
    let mut b = bike.clone();
    let mut own = BTreeMap::new();
    for (k, v) in values {
        if driven.parameter(k).is_none() {
            b = b.with_parameter(k, *v)?;
        } else {
            own.insert(k.clone(), *v);
        }
    }
    let base = b.lookup()?;
    let lookup = |s: &str| own.get(s).copied().or_else(|| base(s));
    R::with_model(
        driven.name,
        PlantCurve {
            lookup: &lookup,
            speeds,
            feedback: b.feedback.as_ref(),
        },
    )
    .expect("registered model")
    .map(Some)
}

/// Effect values for a linear (eigenvalue) prediction: each effect whose
/// file declares a linear equivalent is replaced by it. Coulomb steer
/// friction has no useful linearization about upright (the smoothed law
/// linearizes to a stiff damper `T / w`), so it declares its
/// describing-function equivalent viscous damping at the response's steer
/// rate: for a sinusoid of amplitude `A`, `c_eq = 4 T / (pi A)`, with
/// `A = (pi / 2) mean|rate|`.
pub fn linear_equivalent(
    info: &ModelInfo,
    values: &BTreeMap<String, f64>,
    mean_abs_steer_rate: f64,
) -> BTreeMap<String, f64> {
    let mut v = values.clone();
    for e in info.effect_declarations {
        let Some(EffectIdentification::Candidate(CandidateDeclaration {
            linear_equivalent: Some(LinearEquivalent::DescribingFunctionDamping { torque, damping }),
            ..
        })) = e.identification
        else {
            continue;
        };
        if let Some(t) = v.get(torque).copied().filter(|t| *t != 0.0) {
            let amp = std::f64::consts::FRAC_PI_2 * mean_abs_steer_rate;
            let c_eq = if amp > 0.0 {
                4.0 * t / (std::f64::consts::PI * amp)
            } else {
                0.0
            };
            *v.entry(damping.into()).or_insert(0.0) += c_eq;
            v.insert(torque.into(), 0.0);
        }
    }
    v
}

/// Weave eigenvalues of a model with extra states (state-space
/// linearization): the complex eigenvalue nearest each `guide` (the no-slip
/// model's weave).
struct StateSpaceWeave<'a> {
    lookup: &'a dyn Fn(&str) -> Option<f64>,
    speeds: &'a [f64],
    guide: &'a [Option<[f64; 2]>],
}

impl ModelVisitor for StateSpaceWeave<'_> {
    type Output = Result<Vec<Option<[f64; 2]>>, IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let p = parameter_vector::<M>(self.lookup, 1.0)?;
        Ok(self
            .speeds
            .iter()
            .zip(self.guide)
            .map(|(&v, g)| {
                let g = (*g)?;
                let ss = state_space_at_speed::<M>(&p, v).ok()?;
                ss.a.complex_eigenvalues()
                    .iter()
                    .filter(|z| z.im > 1e-9)
                    .min_by(|x, y| {
                        let d = |z: &nalgebra::Complex<f64>| (z.re - g[0]).hypot(z.im - g[1]);
                        d(x).total_cmp(&d(y))
                    })
                    .map(|z| [z.re, z.im])
            })
            .collect())
    }
}
