//! Rolling resistance at each wheel: the tyre's rolling-resistance moment
//! `M_y = Crr N R` about the wheel's axle, opposing its spin (Pacejka, Tire
//! and Vehicle Dynamics, 3rd ed. 2012, section 4.3.2: the hysteresis of the
//! tyre moves the normal load ahead of the contact centre by `Crr R`).
//!
//! With rolling without slip the moment slows the wheel, and the ground's
//! longitudinal constraint force takes up `M_y / R = Crr N` at the contact:
//! the same speed loss as a force `Crr N` at the hub along the wheel's
//! heading, to which it is exactly equivalent. A force at the geometric
//! contact point instead (this effect's earlier form) leaves out the moment
//! of the displaced normal load, which has a component about the roll axis
//! as soon as the wheel is steered: it damped the thesis bicycle's weave by
//! 0.15 1/s at 6 m/s for `Crr = 0.018`, a steer torque no tyre makes, where
//! the moment form (and an independent simulator that applies the force at
//! the hubs) moves it by under 0.01 1/s.
//!
//! The power is `-Crr N R w^2 / sqrt(w^2 + w0^2) <= 0`, `w` the wheel's
//! absolute angular velocity about its axle; `w0 = v0 / R` with
//! `v0 = 0.05 m/s` keeps exact derivatives at rest (above 1 m/s the moment
//! differs from the unregularised one by less than 0.13 %). The normal load
//! `N` is the quasi-static load from the current geometry
//! ([`super::static_normal_loads`]).

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{angular_velocity, dot3, frame_axis, ratio};
use crate::model::{Axis, Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let crr_r = m.parameter_with_default("Crr_rear", "rolling resistance coefficient of the rear tyre (-)", 0.0);
    let crr_f = m.parameter_with_default("Crr_front", "rolling resistance coefficient of the front tyre (-)", 0.0);
    // Physical values only: a negative coefficient would feed energy in.
    m.lower_bound("Crr_rear", 0.0, false);
    m.lower_bound("Crr_front", 0.0, false);
    let (n_rear, n_front) = super::static_normal_loads(m, parts);
    for (name, crr, n, wheel, axes, radius) in [
        (
            "rolling_resistance_rear",
            crr_r,
            n_rear,
            parts.rear_wheel,
            parts.rear_wheel_axes,
            parts.rear_wheel_radius.clone(),
        ),
        (
            "rolling_resistance_front",
            crr_f,
            n_front,
            parts.front_wheel,
            parts.front_wheel_axes,
            parts.front_wheel_radius.clone(),
        ),
    ] {
        // The wheel spins about its y axis (the axle).
        let axle = frame_axis(axes, Axis::Y);
        let spin = dot3(&angular_velocity(axes), &axle);
        let w0 = ratio(1, 20) / radius.clone();
        let smooth = (spin.clone().powi(2) + w0.powi(2)).sqrt();
        let scale = -(crr * n * radius * spin / smooth);
        m.dissipative_force(Force::Torque {
            name: name.into(),
            body: wheel,
            torque: std::array::from_fn(|k| scale.clone() * axle[k].clone()),
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
        doc: "rolling resistance, moment Crr N R about each wheel's axle opposing its spin (N: quasi-static load)",
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
