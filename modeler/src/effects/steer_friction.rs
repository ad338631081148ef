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

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted::plain("T_steer", 0.05, true)];

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
            held: &["w_steer"],
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
