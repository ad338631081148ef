//! Steer Coulomb friction, smoothed: a torque `-T tanh(gamma' / w)` between
//! the fork and the rear frame.
//!
//! The smoothing rate `w` (rad/s) replaces the discontinuous sign function.
//! Near zero steer rate the friction acts as a viscous damper of coefficient
//! `T / w`; with the steer-axis inertia `I_s` of a bicycle's front assembly
//! (about 0.1 kg m^2) its time constant is `I_s w / T`. The default
//! `w = 0.1 rad/s` keeps that above 10 ms for torques up to 1 N m, so the
//! equations stay non-stiff for an explicit integrator at rtol 1e-8 (a step
//! of a few ms), while steer rates of a weave (about 1 rad/s) are ten times
//! `w`, where `tanh` is within 1e-8 of its limit.
//!
//! Identification fits `w` with the torque. The rate is not only numerical:
//! as a kick's weave dies out the steer rate passes through `w` on every
//! swing, and where the steer sticks and how the last swings decay depend on
//! it. A headset is not a tanh either, so no fixed `w` is right for every
//! bicycle; the data choose it. Fitted with `w` held at its default on an
//! independent simulator's set made with Coulomb friction smoothed at
//! 0.02 rad/s, the torque came out 23 % high and the criterion about 1,000
//! worse than with `w` free (which finds 0.021).

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, LinearEquivalent, Signature};
use crate::expr::rate;
use crate::model::{Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let t = m.parameter_with_default("T_steer", "steer Coulomb friction torque (N m)", 0.0);
    let w = m.parameter_with_default(
        "w_steer",
        "smoothing rate of the steer friction, tanh(gamma'/w) (rad/s)",
        0.1,
    );
    // Physical values only: negative friction would feed energy in, and the
    // smoothing rate divides.
    m.lower_bound("T_steer", 0.0, false);
    m.lower_bound("w_steer", 0.0, true);
    m.dissipative_force(Force::Generalized {
        name: "steer_friction".into(),
        coordinate: parts.steer.clone(),
        expr: -(t * (rate(&parts.steer) / w).tanh()),
    });
}

/// The parameters identification fits for this effect: the torque, and the
/// smoothing rate as a shape of the law. Below 2 mrad/s (0.1 deg/s, below
/// what a steer-rate signal resolves) the rate is held there: smaller rates
/// change no measured response and only stiffen the equations. Above
/// 0.1 rad/s, a tenth of a weave's steer rates, the law no longer saturates
/// over a swing: it is a viscous damper of `T / w`, which `steer_damping`
/// stands for, and the two candidates could not be told apart.
const FITTED: &[Fitted] = &[
    Fitted::plain("T_steer", 0.05, true),
    Fitted {
        floor: Some(0.002),
        ceiling: Some(0.1),
        shape: true,
        ..Fitted::plain("w_steer", 0.05, false)
    },
];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "steer_friction",
        doc: "steer Coulomb friction, torque -T_steer tanh(gamma'/w_steer)",
        apply,
        // Coulomb friction's smoothed law linearizes to a stiff damper
        // `T / w` about upright: the eigenvalue prediction uses its
        // describing function instead.
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::AmplitudeDependentDamping, Signature::WeaveDampingAndFrequency],
            reason: "decay that depends on amplitude (faster at small amplitude): Coulomb friction in the headset",
            linear_equivalent: Some(LinearEquivalent::DescribingFunctionDamping {
                torque: "T_steer",
                damping: "c_steer",
            }),
            own_model: false,
        }),
    }
}
