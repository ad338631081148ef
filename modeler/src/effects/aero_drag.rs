//! Aerodynamic drag in still air: a force `-1/2 rho CdA |v| v` at the rear
//! frame's mass centre (the instrumented frame carries most of the frontal
//! area of a riderless bicycle; move the point in this file for a rider).
//! `|v|` is regularised as `sqrt(v.v + v0^2)` with `v0 = 0.01 m/s` so that
//! exact derivatives exist at rest.

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{ratio, smooth_norm, velocity};
use crate::model::{Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let cda = m.parameter_with_default("CdA", "drag area, drag coefficient times frontal area (m^2)", 0.0);
    let rho = m.parameter_with_default("rho_air", "air density (kg/m^3)", 1.2);
    // Physical values only: a negative coefficient would feed energy in.
    m.lower_bound("CdA", 0.0, false);
    m.lower_bound("rho_air", 0.0, false);
    let point = parts.rear_frame_mass_centre;
    let v = velocity(point);
    let scale = -(ratio(1, 2) * rho * cda * smooth_norm(&v, ratio(1, 100)));
    m.dissipative_force(Force::AtPoint {
        name: "aero_drag".into(),
        point,
        force: std::array::from_fn(|k| scale.clone() * v[k].clone()),
    });
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted::plain("CdA", 0.3, true)];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "aero_drag",
        doc: "aerodynamic drag -1/2 rho_air CdA |v| v at the rear frame's mass centre",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &["rho_air"],
            speed_decay: true,
            signatures: &[Signature::SpeedDecay],
            reason: "the speed falls faster at higher speed: aerodynamic drag",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
