//! Steady running at a given forward speed, for any model: its parameter
//! vector, the independent rates that carry the speed (through a driven
//! model's speed parameter or a free-speed model's speed coordinate), the
//! exact linearization over all independent coordinates and its roll-steer
//! block, and the first-order state space of a model with extra states.
//!
//! Apart because it is where a speed becomes a model's inputs: the
//! canonical matrices and the linear model both start here.

use super::reduced::reduced_system;
use crate::constraints::{solve_configuration, NewtonOptions};
use crate::linalg::solve_in_place;
use crate::linear_types::{Linearization, LinearizeError};
use crate::model::MultibodyModel;
use crate::scalar::{Dual, Scalar};
use nalgebra::DMatrix;

/// Positions, within the independent coordinates, of roll and steer: all
/// independent coordinates except the one that carries the forward speed.
pub fn lateral_indices<M: MultibodyModel>() -> Vec<usize> {
    (0..M::INDEPENDENT.len())
        .filter(|&k| Some(M::INDEPENDENT[k]) != M::SPEED_COORDINATE)
        .collect()
}

/// Exact linearization about upright straight running at forward speed
/// `speed` (m/s), over all independent coordinates, for any model: a driven
/// model gets the speed through its speed parameter, a free-speed model
/// through the rate of its speed coordinate (found from the model's own
/// forward-speed expression). `param` is the full parameter vector (a driven
/// model's speed entry is overwritten).
pub fn linearize_at_speed<M: MultibodyModel>(param: &[f64], speed: f64) -> Result<Linearization, LinearizeError> {
    if !M::STATES.is_empty() {
        return Err(LinearizeError::HasStates { model: M::NAME });
    }
    let (param, dq0) = speed_setup::<M>(param, speed)?;
    M::linearize_with_rest_exact(&param, &dq0).map(|(l, _)| l)
}

/// A linear state-space model `x' = A x` about upright straight running.
#[derive(Clone, Debug)]
pub struct StateSpace {
    /// State names: the independent coordinates, their rates (`d` + name),
    /// then the model's extra states.
    pub names: Vec<String>,
    pub a: DMatrix<f64>,
}

/// Exact linearization of a model with extra first-order states (or any
/// model) at forward speed `speed`: `x = [q, q', z]` with `q` the
/// independent coordinates and `z` the extra states (at zero, their steady
/// value in straight running). `q''` comes from the reduced equations, `z'`
/// from the model's state rates evaluated with the full velocities.
pub fn state_space_at_speed<M: MultibodyModel>(param: &[f64], speed: f64) -> Result<StateSpace, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let nz = M::STATES.len();
    let (param, dq0) = speed_setup::<M>(param, speed)?;
    let _ = (ni, nz);
    let a = M::state_space_exact(&param, &dq0)?;
    let mut names: Vec<String> = M::INDEPENDENT.iter().map(|&j| M::COORDINATES[j].to_string()).collect();
    names.extend(M::INDEPENDENT.iter().map(|&j| format!("d{}", M::COORDINATES[j])));
    names.extend(M::STATES.iter().map(|s| s.to_string()));
    Ok(StateSpace { names, a })
}

/// The state matrix of [`state_space_at_speed`] with dual numbers of width
/// `N = 2 x` independent coordinates `+` extra states (called by each
/// generated model with its own `N`).
pub fn state_space_dual<M: MultibodyModel, const N: usize>(
    param: &[f64],
    dq0: &[f64],
) -> Result<DMatrix<f64>, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let nz = M::STATES.len();
    let np = M::PARAMETERS.len();
    let mut pd: Vec<Dual<N>> = param.iter().map(|&x| Dual::cst(x)).collect();
    for k in 0..nz {
        pd[np + k] = Dual::variable(param[np + k], 2 * ni + k);
    }
    let q: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(0.0, k)).collect();
    let dq: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(dq0[k], ni + k)).collect();
    let sys = reduced_system::<M, Dual<N>>(&pd, Dual::zero(), &q, &dq, &vec![Dual::zero(); ni])?;
    // q'' = Mi^-1 Qi = -Mi^-1 Ec(q'' = 0).
    let mut mi = sys.mi.clone();
    let mut rhs: Vec<Dual<N>> = sys.ec.iter().map(|&e| -e).collect();
    solve_in_place(&mut mi, ni, &mut rhs, 1).map_err(|_| LinearizeError::SingularMass)?;
    let mut zdot = vec![Dual::<N>::zero(); nz];
    M::state_rates(&pd, Dual::zero(), &sys.p, &sys.dp, &mut zdot);
    let n = 2 * ni + nz;
    let mut a = DMatrix::zeros(n, n);
    for k in 0..ni {
        a[(k, ni + k)] = 1.0;
    }
    for r in 0..ni {
        for c in 0..n {
            a[(ni + r, c)] = rhs[r].eps[c];
        }
    }
    for r in 0..nz {
        for c in 0..n {
            a[(2 * ni + r, c)] = zdot[r].eps[c];
        }
    }
    Ok(a)
}

/// The parameter vector and independent rates for steady running at `speed`.
pub(super) fn speed_setup<M: MultibodyModel>(
    param: &[f64],
    speed: f64,
) -> Result<(Vec<f64>, Vec<f64>), LinearizeError> {
    let mut param = param.to_vec();
    let mut dq0 = vec![0.0; M::INDEPENDENT.len()];
    speed_rates::<M>(&mut param, speed, &mut dq0)?;
    Ok((param, dq0))
}

/// Set `param` and the independent rates `dq0` (one per independent
/// coordinate, zero on entry) for steady running at `speed`.
pub(super) fn speed_rates<M: MultibodyModel>(
    param: &mut [f64],
    speed: f64,
    dq0: &mut [f64],
) -> Result<(), LinearizeError> {
    if let Some(k) = M::FORWARD_SPEED_PARAMETER {
        param[k] = speed;
    } else if let Some(c) = M::SPEED_COORDINATE {
        // Forward speed is linear in the rates: its slope in the speed
        // coordinate's rate, at the upright configuration.
        let mut p: Vec<f64> = M::INITIAL_GUESS.to_vec();
        for &j in M::INDEPENDENT {
            p[j] = 0.0;
        }
        solve_configuration::<M, f64>(param, 0.0, &mut p, &NewtonOptions::default())?;
        let mut unit = vec![0.0; M::nq()];
        unit[c] = 1.0;
        let slope = M::forward_speed(param, &p, &unit);
        if !(slope.abs() > 0.0) || !slope.is_finite() {
            return Err(LinearizeError::NoForwardSpeed { model: M::NAME });
        }
        let k = M::INDEPENDENT
            .iter()
            .position(|&j| j == c)
            .expect("the speed coordinate is independent");
        dq0[k] = speed / slope;
    } else if speed != 0.0 {
        return Err(LinearizeError::NoForwardSpeed { model: M::NAME });
    }
    Ok(())
}

/// The roll-steer block of a linearization (see [`lateral_indices`]).
pub fn lateral_block<M: MultibodyModel>(lin: &Linearization) -> Linearization {
    let idx = lateral_indices::<M>();
    let n = idx.len();
    let pick = |m: &DMatrix<f64>| DMatrix::from_fn(n, n, |i, j| m[(idx[i], idx[j])]);
    Linearization {
        mass: pick(&lin.mass),
        damping: pick(&lin.damping),
        stiffness: pick(&lin.stiffness),
    }
}

/// Fill a model's parameter vector by name from `lookup`; the forward-speed
/// parameter of a driven model gets `speed`, and a parameter `lookup` does
/// not know takes the model's default (effect parameters: absent). A model
/// with extra states gets them appended, at zero (see
/// [`MultibodyModel::STATES`]).
pub fn parameter_vector<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
    speed: f64,
) -> Result<Vec<f64>, LinearizeError> {
    let mut v: Vec<f64> = M::PARAMETER_INFO
        .iter()
        .enumerate()
        .map(|(i, info)| {
            if Some(i) == M::FORWARD_SPEED_PARAMETER {
                Some(speed)
            } else {
                lookup(info.name).or(info.default)
            }
            .ok_or(LinearizeError::NoValue {
                model: M::NAME,
                name: info.name,
                doc: info.doc,
            })
        })
        .collect::<Result<_, _>>()?;
    v.extend(M::STATES.iter().map(|_| 0.0));
    Ok(v)
}
