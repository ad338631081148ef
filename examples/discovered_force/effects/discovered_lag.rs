//! `discovered_lag`: generalized forces found by `bikedyn identify` beyond the
//! effect library (dictionary search on the roll and steer equations).
//!
//! - a steer torque from the roll rate, steering into the lean (a roll-rate feedback, as a controller or a rider applies): 5.9770 +- 0.0521 N m s/rad (95 %), through a first-order lag of 0.1496 +- 0.0016 s (95 %) (an actuator, a tyre or a controller with its own dynamics)
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
        "discovered_lag_k0",
        "steer_torque_roll_rate_lagged coefficient, thesis signs (N m s/rad)",
        0.0,
    );
    let tau0 = m.parameter_with_default(
        "discovered_lag_tau0",
        "time constant of the lag of steer_torque_roll_rate_lagged (s)",
        0.149579,
    );
    m.lower_bound("discovered_lag_tau0", 0.0, true);
    let z0 = m.state(
        "discovered_lag_z0",
        "lagged steer_torque_roll_rate_lagged torque (N m)",
        (k0 * rate(&parts.roll) - Expr::State("discovered_lag_z0".into())) / tau0,
    );
    m.force(Force::Generalized {
        name: "discovered_lag_0".into(),
        coordinate: parts.steer.clone(),
        expr: z0,
    });
}
const FITTED: &[Fitted] = &[Fitted::plain("discovered_lag_k0", 5.977e0, false)];
/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "discovered_lag",
        doc: "generalized forces found by identify beyond the effect library",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::WeaveDampingAndFrequency],
            reason: "found by the dictionary search of identify on measured data",
            linear_equivalent: None,
            own_model: true,
        }),
    }
}
