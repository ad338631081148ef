//! The layout of a kick's nuisance parameters: the state at its window
//! start (the initial motion, and for a tyre model the lagged forces and
//! their rates) and the steer sensor's offset, fitted per kick beside the
//! shared effect parameters. Every model uses the same fixed-size layout,
//! so a fit's nuisances carry over between models with and without extra
//! states; the scales here set the difference steps and the fit's step
//! measure.

/// Room for the per-segment nuisance parameters, the state at the window
/// start: the initial motion ([`INITIAL_MOTION`]: roll, steer (rad), roll
/// rate, steer rate (rad/s), forward speed (m/s)), then, for a model with
/// `e` extra first-order states (`M::STATES`, at most [`EXTRA_STATES`]: a
/// tyre model's lagged lateral forces, N), their values (`e` entries) and
/// their rates (`e` entries, N/s). A window starts just after a kick,
/// while the forces still lag behind the slip the kick gave the wheels:
/// neither is at rest, and the rates set the slip (the free lateral
/// velocities are solved from them). A model without extra states leaves
/// those entries at zero. The last entry ([`STEER_BIAS`]) is a sensor
/// nuisance, not a state: the measured steer's offset over the window.
pub const NUISANCE: usize = INITIAL_MOTION + 2 * EXTRA_STATES + 1;

/// Where the initial forward speed sits in a segment's nuisances.
pub(super) const SPEED: usize = INITIAL_MOTION - 1;

/// Where a kick's steer bias (rad) sits in its nuisances: the offset of the
/// measured steer angle over the window, fitted per kick. A steer angle
/// taken from two orientation sensors (frame and handlebar) inherits the
/// difference of their heading references, which drift and carry errors of
/// a degree or more that the calibration at rest cannot fix (each run's
/// heading fusion settles anew), and an encoder's zero is set by hand; a
/// mechanical candidate asked to explain such an offset would take up a
/// sensor error (a few degrees of steer is what a lateral mass offset of
/// centimetres gives). It is held at the same index in every model, so a
/// fit's nuisances carry over between models with and without extra
/// states.
pub const STEER_BIAS: usize = NUISANCE - 1;
/// Scale of the steer bias (rad).
const STEER_BIAS_SCALE: f64 = 0.01;
/// Number of initial-motion nuisances (roll, steer, their rates, speed).
pub const INITIAL_MOTION: usize = 5;
/// Most extra first-order states a model may have for identification.
pub const EXTRA_STATES: usize = crate::simulate::MAX_STATE_RATES;
/// Scales of the initial-motion nuisances (difference steps and LM scaling).
const MOTION_SCALE: [f64; INITIAL_MOTION] = [0.01, 0.01, 0.1, 0.1, 0.1];
/// Scales of an extra state (a tyre force, N) and of its rate (N/s).
const STATE_SCALE: [f64; 2] = [10.0, 100.0];

/// A window-start state from the initial motion, the extra states at rest.
pub fn at_rest(motion: [f64; INITIAL_MOTION]) -> [f64; NUISANCE] {
    let mut x = [0.0; NUISANCE];
    x[..INITIAL_MOTION].copy_from_slice(&motion);
    x
}

/// The scale of nuisance `j` of a model with `extra` extra states.
pub(super) fn nuisance_scale(j: usize, extra: usize) -> f64 {
    if j == STEER_BIAS {
        STEER_BIAS_SCALE
    } else if j < INITIAL_MOTION {
        MOTION_SCALE[j]
    } else if j < INITIAL_MOTION + extra {
        STATE_SCALE[0]
    } else {
        STATE_SCALE[1]
    }
}
