//! A generated model with its parameters as a [`LinearBicycle`] (and, with
//! extra states or coordinates, a [`StateSpaceBicycle`]): the eigen
//! analyses' view of any model, from its exact linearization at each speed.
//!
//! Apart because it adapts the linearization to the eigen module's traits,
//! including the choice of the lateral states of a first-order model.

use super::at_speed::{linearize_at_speed, parameter_vector, state_space_at_speed};
use crate::eigen::{EigenError, LateralStates, LinearBicycle, SpeedMatrices, StateSpaceBicycle};
use crate::linear_types::LinearizeError;
use crate::model::{CoordinateRole, MultibodyModel};
use nalgebra::{DMatrix, Matrix2};

/// A generated model with its parameters, as a [`LinearBicycle`]: its
/// roll-steer equations at each speed come from the exact linearization at
/// that speed ([`linearize_at_speed`]), in the benchmark's sign convention
/// (the steer angle of the thesis axes is minus the benchmark's, so the
/// off-diagonal entries change sign). Any effect enters: damping,
/// friction's describing function, a speed-scheduled controller.
///
/// A model with extra first-order states (tyre forces) has no second-order
/// roll-steer form: it gives its lateral first-order equations instead
/// ([`StateSpaceBicycle`], from [`state_space_at_speed`]), which the eigen
/// analyses use themselves.
pub struct LinearModel<M: MultibodyModel> {
    param: Vec<f64>,
    /// Positions of roll and steer within the independent coordinates.
    roll_steer: [usize; 2],
    /// For a model with extra states: which states of
    /// [`state_space_at_speed`] are lateral, and how many eigenvalues are
    /// neutral (see [`lateral_states_of`]).
    lateral: Option<(Vec<usize>, usize)>,
    _model: std::marker::PhantomData<M>,
}

impl<M: MultibodyModel> LinearModel<M> {
    /// The model with its parameters filled from `lookup` (missing ones:
    /// the model's defaults).
    pub fn new(lookup: impl Fn(&str) -> Option<f64>) -> Result<Self, LinearizeError> {
        let param = parameter_vector::<M>(&lookup, 0.0)?;
        let position = |role| -> Result<usize, LinearizeError> {
            let j = M::require_coordinate(role, "the linear roll-steer analysis")?;
            M::INDEPENDENT
                .iter()
                .position(|&i| i == j)
                .ok_or(LinearizeError::NotRollSteer {
                    model: M::NAME,
                    n: M::INDEPENDENT.len(),
                })
        };
        let roll_steer = [position(CoordinateRole::Roll)?, position(CoordinateRole::Steer)?];
        // A second-order roll-steer form exists only when roll and steer
        // are all the lateral freedom there is: extra states (tyre forces)
        // or an extra coordinate (a rider's lean) need the state space.
        let lateral = if M::STATES.is_empty() && extra_coordinates::<M>().is_empty() {
            None
        } else {
            Some(lateral_states_of::<M>(&param, roll_steer)?)
        };
        Ok(LinearModel {
            param,
            roll_steer,
            lateral,
            _model: std::marker::PhantomData,
        })
    }
}

/// Positions within the independent coordinates of those the rolling
/// bicycle lacks ([`crate::model::added_coordinates`]).
fn extra_coordinates<M: MultibodyModel>() -> Vec<usize> {
    crate::model::added_coordinates(M::INDEPENDENT, M::COORDINATE_ROLES)
}

/// The lateral states of a model with extra states: every state of
/// [`state_space_at_speed`] but the speed coordinate and its rate (the
/// longitudinal motion, uncoupled from the lateral at upright straight
/// running) and the coordinates nothing depends on (lateral position, yaw,
/// wheel rotations: their columns of `A` vanish, each adds a zero
/// eigenvalue, and dropping them leaves the other eigenvalues exact since
/// `A` is block triangular in them). A column is structurally zero when it
/// is exactly zero at two unrelated speeds; dropping a state can empty
/// another's column (yaw feeds only the lateral position), hence the loop.
///
/// Also the number of neutral eigenvalues that remain (the heading when the
/// yaw stays, as with tyre slip: a zero eigenvalue at every speed), counted
/// as those below `1e-10 max |A_ij|` at both probe speeds (their rounding is
/// about `1e-16 max |A_ij|`).
fn lateral_states_of<M: MultibodyModel>(
    param: &[f64],
    roll_steer: [usize; 2],
) -> Result<(Vec<usize>, usize), LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let probes = [
        state_space_at_speed::<M>(param, 1.3)?,
        state_space_at_speed::<M>(param, 4.7)?,
    ];
    let n = probes[0].a.nrows();
    // The speed coordinate's position and rate (states k and ni + k).
    let speed = M::SPEED_COORDINATE.and_then(|c| M::INDEPENDENT.iter().position(|&j| j == c));
    let mut keep: Vec<usize> = (0..n)
        .filter(|&i| speed.is_none_or(|k| i != k && i != ni + k))
        .collect();
    let essential = [roll_steer[0], roll_steer[1], ni + roll_steer[0], ni + roll_steer[1]];
    loop {
        let before = keep.len();
        let current = keep.clone();
        keep.retain(|&j| {
            essential.contains(&j)
                || probes
                    .iter()
                    .any(|p| current.iter().any(|&i| i != j && p.a[(i, j)] != 0.0) || p.a[(j, j)] != 0.0)
        });
        if keep.len() == before {
            break;
        }
    }
    let neutral = probes
        .iter()
        .map(|p| {
            let a = DMatrix::from_fn(keep.len(), keep.len(), |i, j| p.a[(keep[i], keep[j])]);
            let tol = 1e-10 * a.abs().max().max(1.0);
            a.complex_eigenvalues().iter().filter(|z| z.norm() <= tol).count()
        })
        .min()
        .unwrap_or(0);
    Ok((keep, neutral))
}

impl<M: MultibodyModel> StateSpaceBicycle for LinearModel<M> {
    fn lateral_states(&self, v: f64) -> Result<LateralStates, EigenError> {
        let (keep, neutral) = match &self.lateral {
            Some((k, n)) => (k.as_slice(), *n),
            None => (&[][..], 0),
        };
        let ss = state_space_at_speed::<M>(&self.param, v).map_err(|e| EigenError::Linearization {
            speed: v,
            what: e.to_string(),
        })?;
        let ni = M::INDEPENDENT.len();
        let at = |j: usize| keep.iter().position(|&k| k == j).unwrap_or(usize::MAX);
        let [r, s] = self.roll_steer;
        Ok(LateralStates {
            names: keep.iter().map(|&k| ss.names[k].clone()).collect(),
            a: DMatrix::from_fn(keep.len(), keep.len(), |i, j| ss.a[(keep[i], keep[j])]),
            roll_steer: [at(r), at(s), at(ni + r), at(ni + s)],
            // The generated models use the thesis's axes (see `at_speed`).
            steer_sign: -1.0,
            // Extra: the first-order states and the coordinates (and
            // their rates) the rolling bicycle lacks.
            extra: {
                let coords = extra_coordinates::<M>();
                (0..keep.len())
                    .filter(|&i| keep[i] >= 2 * ni || coords.iter().any(|&k| keep[i] == k || keep[i] == ni + k))
                    .collect()
            },
            neutral,
        })
    }
}

impl<M: MultibodyModel> LinearBicycle for LinearModel<M> {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        if self.lateral.is_some() {
            return Err(EigenError::Linearization {
                speed: v,
                what: LinearizeError::HasStates { model: M::NAME }.to_string(),
            });
        }
        let lin = linearize_at_speed::<M>(&self.param, v).map_err(|e| EigenError::Linearization {
            speed: v,
            what: e.to_string(),
        })?;
        let [r, s] = self.roll_steer;
        let pick = |m: &DMatrix<f64>| Matrix2::new(m[(r, r)], -m[(r, s)], -m[(s, r)], m[(s, s)]);
        Ok(SpeedMatrices {
            mass: pick(&lin.mass),
            damping: pick(&lin.damping),
            stiffness: pick(&lin.stiffness),
        })
    }
    fn first_order(&self) -> Option<&dyn StateSpaceBicycle> {
        self.lateral.is_some().then_some(self as &dyn StateSpaceBicycle)
    }
}
