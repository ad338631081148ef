//! Rolling resistance at each wheel: a force of magnitude `Crr N` opposing
//! the travel of the wheel's contact point.
//!
//! The force works on the contact point's travel velocity `v_c` (the rate of
//! the geometric contact point, not of the material point, which has zero
//! velocity under rolling without slip), so its power is `-Crr N |v_c| <= 0`.
//! The normal load `N` is the quasi-static load from the current geometry
//! ([`super::static_normal_loads`]). `|v_c|` is regularised as `sqrt(v_c.v_c + v0^2)` with
//! `v0 = 0.05 m/s` so that exact derivatives exist at rest; above 1 m/s the
//! force differs from the unregularised one by less than 0.13 %.

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{ratio, smooth_norm, velocity};
use crate::model::{Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let crr_r = m.parameter_with_default("Crr_rear", "rolling resistance coefficient of the rear tyre (-)", 0.0);
    let crr_f = m.parameter_with_default("Crr_front", "rolling resistance coefficient of the front tyre (-)", 0.0);
    // Physical values only: a negative coefficient would feed energy in.
    m.lower_bound("Crr_rear", 0.0, false);
    m.lower_bound("Crr_front", 0.0, false);
    let (n_rear, n_front) = super::static_normal_loads(m, parts);
    for (name, crr, n, contact) in [
        ("rolling_resistance_rear", crr_r, n_rear, parts.rear_contact),
        ("rolling_resistance_front", crr_f, n_front, parts.front_contact),
    ] {
        let v = velocity(contact);
        let speed = smooth_norm(&v, ratio(1, 20));
        let scale = -(crr * n / speed);
        m.dissipative_force(Force::AtPoint {
            name: name.into(),
            point: contact,
            force: std::array::from_fn(|k| scale.clone() * v[k].clone()),
        });
    }
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted {
        tied: &["Crr_front"],
        ..Fitted::plain("Crr_rear", 0.005, true)
    }];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "rolling_resistance",
        doc: "rolling resistance, force Crr N opposing each contact point's travel (N: quasi-static load)",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: true,
            signatures: &[Signature::SpeedDecay],
            reason: "the speed falls during the response about evenly at all speeds: rolling resistance of the tyres",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
