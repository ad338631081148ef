//! Steer-axis viscous damping: a torque `-c_steer gamma'` between the fork
//! and the rear frame (bearing and headset seals, cable drag).

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::rate;
use crate::model::{Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let c = m.parameter_with_default("c_steer", "steer-axis viscous damping coefficient (N m s/rad)", 0.0);
    // Physical values only: a negative coefficient would feed energy in.
    m.lower_bound("c_steer", 0.0, false);
    m.dissipative_force(Force::Generalized {
        name: "steer_damping".into(),
        coordinate: parts.steer.clone(),
        expr: -(c * rate(&parts.steer)),
    });
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted::plain("c_steer", 0.1, true)];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "steer_damping",
        doc: "steer-axis viscous damping, torque -c_steer gamma'",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::WeaveDampingAndFrequency],
            reason: "excess weave damping with a lower weave frequency: viscous damping in the headset slows the steer",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
