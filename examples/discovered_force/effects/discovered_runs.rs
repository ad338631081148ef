//! `discovered_runs`: generalized forces found by `bikedyn identify` beyond the
//! effect library (dictionary search on the roll and steer equations).
//!
//! - a steer torque from the roll angle, steering into the lean: 3.0428 +- 0.0252 N m/rad (95 %)
use bikedyn_modeler::effects::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
#[allow(unused_imports)]
use bikedyn_modeler::expr::{coord, rate, Expr};
use bikedyn_modeler::model::{Force, ModelBuilder};
#[allow(unused_variables)]
pub fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let v = m
        .model()
        .forward_speed
        .clone()
        .expect("bicycle models declare their forward speed before effects");
    let k0 = m.parameter_with_default(
        "discovered_runs_k0",
        "steer_torque_roll coefficient, thesis signs (N m/rad)",
        0.0,
    );
    m.force(Force::Generalized {
        name: "discovered_runs_0".into(),
        coordinate: parts.steer.clone(),
        expr: k0 * coord(&parts.roll),
    });
}
const FITTED: &[Fitted] = &[Fitted::plain("discovered_runs_k0", 3.043e0, false)];
/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "discovered_runs",
        doc: "generalized forces found by identify beyond the effect library",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::WeaveDampingAndFrequency],
            reason: "found by the dictionary search of identify on measured data",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
