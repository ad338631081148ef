//! The `canonical` job: a bicycle's linear roll-steer equations in the
//! canonical form of Meijaard et al. (2007), `M0 q'' + v C1 q' + (g K0 +
//! v^2 K2) q = f`, with the standard deviations of their entries that the
//! parameter file's `+/-` values imply; or, for a model without that form,
//! its state-space matrices `x' = A(v) x + B(v) u` at the speeds asked.
//!
//! The command line and Python call [`canonical`] and [`state_space`] and
//! print or convert the typed result; its JSON is the serialization of the
//! types below.

use crate::bicycle::{Bicycle, BicycleError, Linear};
use crate::registry::ModelRegistry;
/// M, C1, K0 and K2 of the canonical form (the numerics' own result type).
pub use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::eigen::{EigenError, LinearBicycle};
use nalgebra::Matrix2;
use serde::Serialize;

/// What the `canonical` job computes.
#[derive(Clone, Debug, Default)]
pub struct CanonicalOptions {
    /// The model (default: the bicycle's default model).
    pub model: Option<String>,
    /// Speeds (m/s) of the state-space matrices, for a model without
    /// canonical form.
    pub speeds: Vec<f64>,
}

/// A 2 x 2 matrix row by row, with entries at the round-off of the largest
/// written as 0: the generated expressions reach a structural zero (the
/// benchmark's `C1[0][0]`) as a difference of products, e.g. -4.4e-15
/// beside 33.9, which cannot be told from zero in double precision.
pub type Rows2 = [[f64; 2]; 2];

fn rows_without_round_off(m: &Matrix2<f64>) -> Rows2 {
    let tol = 8.0 * f64::EPSILON * m.amax();
    CanonicalMatrices::rows(&m.map(|x| if x.abs() <= tol { 0.0 } else { x }))
}

/// The four canonical matrices, row by row (benchmark coordinates roll and
/// steer; `M0` in kg m^2, `C1` in kg m, `K0` in kg m, `K2` in kg).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CanonicalRows {
    /// Mass matrix.
    #[serde(rename = "M0")]
    pub m0: Rows2,
    /// Velocity-dependent damping-like matrix (times v).
    #[serde(rename = "C1")]
    pub c1: Rows2,
    /// Gravity-dependent stiffness matrix (times g).
    #[serde(rename = "K0")]
    pub k0: Rows2,
    /// Velocity-dependent stiffness matrix (times v^2).
    #[serde(rename = "K2")]
    pub k2: Rows2,
}

impl CanonicalRows {
    fn of(c: &CanonicalMatrices) -> Self {
        Self {
            m0: rows_without_round_off(&c.m0),
            c1: rows_without_round_off(&c.c1),
            k0: rows_without_round_off(&c.k0),
            k2: rows_without_round_off(&c.k2),
        }
    }
}

/// The canonical form of a bicycle's equations.
#[derive(Clone, Debug, Serialize)]
pub struct CanonicalForm {
    /// The generated model they come from.
    pub model: String,
    /// The matrices.
    #[serde(flatten)]
    pub matrices: CanonicalRows,
    /// Gravity (m/s^2).
    pub g: f64,
    /// Standard deviations of the entries from the file's `+/-` values
    /// (first order, exact derivatives, parameters independent); absent
    /// for a file without them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub standard_deviations: Option<CanonicalRows>,
    /// Why the standard deviations could not be computed although the file
    /// has `+/-` values (not serialized: a note for the reader).
    #[serde(skip)]
    pub standard_deviations_missing: Option<String>,
    /// The matrices as computed (round-off kept), for text output.
    #[serde(skip)]
    pub exact: CanonicalMatrices,
}

/// The state-space matrices of a bicycle's lateral equations at one speed.
#[derive(Clone, Debug, Serialize)]
pub struct StateSpaceAt {
    /// Forward speed (m/s).
    pub speed: f64,
    /// State matrix `A`, row by row (1/s and 1/s^2 blocks).
    #[serde(rename = "A")]
    pub a: Vec<Vec<f64>>,
    /// Input matrix `B = [0; M^-1]` for the roll and steer torques
    /// (1/(kg m^2)); absent for models with extra states, whose torque
    /// inputs are not formed.
    #[serde(rename = "B", skip_serializing_if = "Option::is_none")]
    pub b: Option<Vec<Vec<f64>>>,
}

/// A bicycle's lateral equations in state-space form over speed.
#[derive(Clone, Debug, Serialize)]
pub struct StateSpace {
    /// The generated model they come from.
    pub model: String,
    /// The state's names: `roll, steer, roll_rate, steer_rate` (benchmark
    /// signs, rad and rad/s), or for a model with extra first-order states
    /// its own coordinates, rates (`d` + coordinate) and extra states.
    #[serde(rename = "state")]
    pub states: Vec<String>,
    /// The inputs' names (`roll_torque, steer_torque`, N m), when formed.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub inputs: Vec<String>,
    /// Whether the state is in the model's own coordinates and signs (a
    /// model with extra states) rather than the benchmark's.
    #[serde(skip)]
    pub model_coordinates: bool,
    /// The names of the extra states (those the rolling-without-slip
    /// bicycle lacks), when the state is the model's own.
    #[serde(skip)]
    pub extra_states: Vec<String>,
    /// The matrices at each speed asked.
    #[serde(rename = "state_space")]
    pub at: Vec<StateSpaceAt>,
}

/// A model without canonical form: why, and its state-space matrices.
#[derive(Clone, Debug, Serialize)]
pub struct NoCanonicalForm {
    /// Always `null`: the JSON says there is no canonical form.
    pub canonical: Option<()>,
    /// Why there is none.
    pub why: String,
    /// The state-space matrices at the speeds asked.
    #[serde(flatten)]
    pub state_space: StateSpace,
}

/// The result of the `canonical` job.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum CanonicalReport {
    /// The canonical matrices.
    Canonical(CanonicalForm),
    /// No canonical form: the state-space matrices.
    StateSpace(NoCanonicalForm),
}

/// Errors of the job.
#[derive(Debug, thiserror::Error)]
pub enum CanonicalError {
    /// The bicycle or model.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The equations at a speed.
    #[error("at {speed} m/s: {source}")]
    AtSpeed {
        /// The speed (m/s).
        speed: f64,
        /// What failed.
        source: EigenError,
    },
    /// A singular mass matrix.
    #[error("singular mass matrix at {0} m/s")]
    SingularMass(f64),
    /// A speed that is not a finite number.
    #[error("speed {0} m/s is not a finite number")]
    Speed(f64),
}

/// The `canonical` job: the canonical form of `bike`'s equations with
/// standard deviations, or why it has none and its state-space matrices
/// at `opts.speeds`.
pub fn canonical<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &CanonicalOptions,
) -> Result<CanonicalReport, CanonicalError> {
    let lin = bike.linear_with(opts.model.as_deref())?;
    match &lin.canonical {
        Some(c) => {
            let (sd, missing) = match crate::sensitivity::canonical_uncertainties(bike, opts.model.as_deref()) {
                Ok(sd) => (sd, None),
                Err(e) => (None, Some(e.to_string())),
            };
            Ok(CanonicalReport::Canonical(CanonicalForm {
                model: lin.model.to_string(),
                matrices: CanonicalRows::of(c),
                g: c.g,
                standard_deviations: sd.as_ref().map(CanonicalRows::of),
                standard_deviations_missing: missing,
                exact: *c,
            }))
        }
        None => {
            let state_space = state_space_of(&lin, &opts.speeds)?;
            let why = if state_space.model_coordinates {
                format!(
                    "model `{}` has extra states or coordinates ({}): its lateral equations have no second-order roll-steer form",
                    lin.model,
                    state_space.extra_states.join(", ")
                )
            } else {
                bike.canonical_with(opts.model.as_deref())
                    .err()
                    .map(|e| e.to_string())
                    .unwrap_or_default()
            };
            Ok(CanonicalReport::StateSpace(NoCanonicalForm {
                canonical: None,
                why,
                state_space,
            }))
        }
    }
}

/// The state-space matrices of `bike`'s lateral equations through `model`
/// at `speeds` (m/s): `x = [roll, steer, roll rate, steer rate]` with the
/// torque inputs, or, for a model with extra first-order states, its own
/// lateral states without inputs.
pub fn state_space<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: Option<&str>,
    speeds: &[f64],
) -> Result<StateSpace, CanonicalError> {
    state_space_of(&bike.linear_with(model)?, speeds)
}

fn state_space_of(lin: &Linear, speeds: &[f64]) -> Result<StateSpace, CanonicalError> {
    if let Some(&v) = speeds.iter().find(|v| !v.is_finite()) {
        return Err(CanonicalError::Speed(v));
    }
    let rows = |m: &dyn Fn(usize, usize) -> f64, r: usize, c: usize| -> Vec<Vec<f64>> {
        (0..r).map(|i| (0..c).map(|j| m(i, j)).collect()).collect()
    };
    if let Some(first) = lin.first_order() {
        let mut states = Vec::new();
        let mut extra_states = Vec::new();
        let mut at = Vec::with_capacity(speeds.len());
        for &v in speeds {
            let l = first
                .lateral_states(v)
                .map_err(|source| CanonicalError::AtSpeed { speed: v, source })?;
            states = l.names.clone();
            extra_states = l.extra.iter().map(|&i| l.names[i].clone()).collect();
            at.push(StateSpaceAt {
                speed: v,
                a: rows(&|i, j| l.a[(i, j)], l.a.nrows(), l.a.ncols()),
                b: None,
            });
        }
        return Ok(StateSpace {
            model: lin.model.to_string(),
            states,
            inputs: Vec::new(),
            model_coordinates: true,
            extra_states,
            at,
        });
    }
    let mut at = Vec::with_capacity(speeds.len());
    for &v in speeds {
        let m = lin
            .at_speed(v)
            .map_err(|source| CanonicalError::AtSpeed { speed: v, source })?;
        let a = m.state_matrix().ok_or(CanonicalError::SingularMass(v))?;
        let minv = m.mass.try_inverse().ok_or(CanonicalError::SingularMass(v))?;
        // B = [0; M^-1]: the torques act on the accelerations.
        let b = rows(&|i, j| if i < 2 { 0.0 } else { minv[(i - 2, j)] }, 4, 2);
        at.push(StateSpaceAt {
            speed: v,
            a: rows(&|i, j| a[(i, j)], 4, 4),
            b: Some(b),
        });
    }
    Ok(StateSpace {
        model: lin.model.to_string(),
        states: ["roll", "steer", "roll_rate", "steer_rate"].map(String::from).to_vec(),
        inputs: ["roll_torque", "steer_torque"].map(String::from).to_vec(),
        model_coordinates: false,
        extra_states: Vec::new(),
        at,
    })
}
