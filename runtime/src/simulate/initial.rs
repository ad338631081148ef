//! Consistent initial states: the state vector of a simulation from its
//! initial conditions (roll, steer, their rates, the speed, the yaw and the
//! extra states' rates), with the dependent coordinates and the free
//! independent rates solved so that every constraint holds.
//!
//! Kept apart from the integration because the forward sensitivities
//! (`sensitivity.rs`) start from the same state and the same imposed speed.

use super::rhs;
use super::{forward_speed, Evaluator, InitialConditions, Inputs, SimulateError};
use crate::model::MultibodyModel;

/// The parameter that imposes the forward speed in a driven model (whose
/// independent coordinates are roll and steer alone); the initial
/// conditions' speed sets it.
pub(crate) fn imposed_speed_parameter<M: MultibodyModel>() -> Option<usize> {
    M::FORWARD_SPEED_PARAMETER.filter(|_| M::INDEPENDENT.len() == 2)
}

/// The state vector for given initial conditions (consistent with all
/// constraints), and the parameter vector with the speed set for a driven
/// model.
pub fn initial_state<M: MultibodyModel>(
    param: &[f64],
    ic: &InitialConditions,
) -> Result<(Vec<f64>, Vec<f64>), SimulateError> {
    for (name, x) in [
        ("roll", ic.roll),
        ("steer", ic.steer),
        ("roll rate", ic.roll_rate),
        ("steer rate", ic.steer_rate),
        ("speed", ic.speed),
        ("yaw", ic.yaw),
    ] {
        if !x.is_finite() {
            return Err(SimulateError::NotFinite {
                what: format!("initial {name}"),
            });
        }
    }
    if ic.state_rates.iter().any(|r| !r.is_finite()) {
        return Err(SimulateError::NotFinite {
            what: "initial rate of an extra state".into(),
        });
    }
    // A rate for a state the model does not have would be dropped.
    if ic.state_rates.iter().skip(M::STATES.len()).any(|r| *r != 0.0) {
        return Err(SimulateError::InvalidInput(format!(
            "initial rates {:?} of extra states, but model `{}` has {} ({:?})",
            ic.state_rates,
            M::NAME,
            M::STATES.len(),
            M::STATES
        )));
    }
    let mut param = rhs::with_state_tail::<M>(param)?;
    if let Some(k) = imposed_speed_parameter::<M>() {
        if k < param.len() {
            param[k] = ic.speed;
        }
    }
    let inputs = Inputs::default();
    let eval = Evaluator::<M>::new(&param, &inputs)?;
    let l = &eval.layout;
    let c = eval.coords;
    let mut y = vec![0.0; l.len()];
    for (k, &j) in l.independent.iter().enumerate() {
        y[k] = M::INITIAL_GUESS[j];
    }
    for (k, &j) in l.ignorable.iter().enumerate() {
        y[l.ignorables() + k] = M::INITIAL_GUESS[j];
    }
    y[l.time()] = 0.0;
    y[c.roll_ind] = ic.roll;
    y[c.steer_ind] = ic.steer;
    y[l.rates() + c.roll_ind] = ic.roll_rate;
    y[l.rates() + c.steer_ind] = ic.steer_rate;
    // Yaw is ignorable with rolling constraints, independent with tyre slip.
    if let Some(k) = l.ignorable.iter().position(|&j| j == c.yaw) {
        y[l.ignorables() + k] = ic.yaw;
    } else if let Some(k) = l.independent.iter().position(|&j| j == c.yaw) {
        y[k] = ic.yaw;
    }
    let np = M::PARAMETERS.len();
    y[l.extras()..].copy_from_slice(&param[np..]);
    // The independent rates besides roll and steer: the rate that carries
    // the forward speed (the rear wheel's, in a free-speed model) and, with
    // tyre slip, the lateral ones (yc, phi). They solve `speed = ic.speed`
    // and `z' = ic.state_rates` (by default zero: the extra states at rest;
    // upright, that is rolling without lateral slip), one equation per
    // extra state. A coordinate the rolling bicycle lacks (no declared
    // role: a rider's lean) starts at rest relative to the frame, as roll
    // and steer start where they are given.
    let added = crate::model::added_coordinates(&l.independent, M::COORDINATE_ROLES);
    let others: Vec<usize> = (0..l.ni())
        .filter(|&k| k != c.roll_ind && k != c.steer_ind && !added.contains(&k))
        .collect();
    if !others.is_empty() {
        if others.len() != 1 + l.extra {
            return Err(SimulateError::InvalidInput(format!(
                "model `{}` has {} independent coordinates besides roll and steer and {} extra states (expected one more coordinate than states)",
                M::NAME,
                others.len(),
                l.extra
            )));
        }
        let mut rates = ic.state_rates.to_vec();
        rates.resize(l.extra, 0.0);
        solve_free_rates(&eval, &mut y, &others, ic.speed, &rates)?;
    }
    // Check that the configuration exists.
    eval.full_state(0.0, &y)?;
    Ok((y, param))
}

/// Set the rates `y[rates + k]`, `k` in `others`, so that the forward speed
/// is `speed` and the extra states change at `state_rates`: Newton's method
/// with a finite-difference Jacobian (the conditions are affine in the rates
/// except through the regularised contact speeds of effects like tyre slip).
fn solve_free_rates<M: MultibodyModel>(
    eval: &Evaluator<'_, M>,
    y: &mut [f64],
    others: &[usize],
    speed: f64,
    state_rates: &[f64],
) -> Result<(), SimulateError> {
    let l = eval.layout.clone();
    let m = others.len();
    let mut dy = vec![0.0; l.len()];
    let mut residual = |y: &[f64]| -> Result<Vec<f64>, SimulateError> {
        let (p, dp) = eval.full_state(0.0, y)?;
        let mut r = vec![forward_speed(&eval.coords, &p, &dp) - speed];
        if l.extra > 0 {
            eval.derivative(0.0, y, &mut dy)?;
            r.extend(dy[l.extras()..].iter().zip(state_rates).map(|(a, b)| a - b));
        }
        Ok(r)
    };
    for _ in 0..20 {
        let r0 = residual(y)?;
        if r0.iter().all(|x| *x == 0.0) {
            return Ok(());
        }
        let mut jac = nalgebra::DMatrix::<f64>::zeros(m, m);
        for (col, &k) in others.iter().enumerate() {
            let i = l.rates() + k;
            let h = 1e-6 * y[i].abs().max(1.0);
            let keep = y[i];
            y[i] = keep + h;
            let r1 = residual(y)?;
            y[i] = keep;
            for row in 0..m {
                jac[(row, col)] = (r1[row] - r0[row]) / h;
            }
        }
        let step = jac.lu().solve(&nalgebra::DVector::from_vec(r0)).ok_or_else(|| {
            SimulateError::InvalidInput(
                "the free independent rates do not set the forward speed and the extra states' rates".into(),
            )
        })?;
        let mut small = true;
        for (col, &k) in others.iter().enumerate() {
            let i = l.rates() + k;
            small &= step[col].abs() <= 1e-12 * y[i].abs().max(1.0);
            y[i] -= step[col];
        }
        // Stop once the update is at rounding level (the conditions are
        // affine or nearly so: two or three iterations).
        if small {
            return Ok(());
        }
    }
    let r = residual(y)?;
    Err(SimulateError::InvalidInput(format!(
        "no initial rates give forward speed {speed} m/s with the extra states changing at {state_rates:?} (residual {r:?})"
    )))
}
