//! Tyre lateral slip with a relaxation length, at each wheel, replacing the
//! wheel's lateral no-slip constraint.
//!
//! Each wheel keeps rolling without longitudinal slip (its contact's
//! material velocity along the wheel's heading in the ground plane is zero)
//! but may slide sideways. The lateral force `F` (along the ground-plane
//! lateral direction, positive to the left) is an extra first-order state
//! with the relaxation law
//!
//! `sigma / |v| dF/dt + F = F_ss`,  `F_ss = -N (C_alpha v_lat / |v| + C_gamma camber)`,
//!
//! where `v_lat` is the lateral velocity of the rim point at the contact,
//! `|v|` the travel speed of the contact point (regularised as
//! `sqrt(v.v + v0^2)`, `v0 = 0.05 m/s`), `v_lat / |v|` the slip angle (small
//! angles), `camber` the sine of the wheel plane's lean (the vertical
//! component of the axle, positive leaning right, whose thrust points
//! right), and `N` the quasi-static normal load
//! ([`super::static_normal_loads`]). The force acts on the rim at the contact.
//!
//! With lateral slip the rear contact's lateral position `yc` and the yaw
//! `phi` become independent coordinates (partitioning valid while the
//! heading |phi| < 90 degrees, as in any kick response).
//!
//! Defaults are for a city-bike tyre: cornering stiffness 14 per rad times
//! the normal load (the issue's 11-17 per rad; Dressel 2013, "Measuring and
//! modeling the mechanical properties of bicycle tires", PhD thesis, Univ.
//! of Wisconsin-Milwaukee, measured city and road tyres in that range),
//! camber stiffness 0.9 per rad times the load (Dressel 2013: about 0.7-1.1),
//! relaxation length 0.2 m (0.1-0.3 m).

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{dot3, frame_axis, material_velocity, num, ratio, smooth_norm, velocity, Vec3};
use crate::model::{Axis, Force, ModelBuilder, Nonholonomic, Role};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let (n_rear, n_front) = super::static_normal_loads(m, parts);
    for (wheel, body, axes, contact, n, ca, cg, sigma) in [
        (
            "rear",
            parts.rear_wheel,
            parts.rear_wheel_axes,
            parts.rear_contact,
            n_rear,
            14.0,
            0.9,
            0.2,
        ),
        (
            "front",
            parts.front_wheel,
            parts.front_wheel_axes,
            parts.front_contact,
            n_front,
            14.0,
            0.9,
            0.2,
        ),
    ] {
        let c_alpha = m.parameter_with_default(
            &format!("Ca_{wheel}"),
            &format!("{wheel} tyre cornering stiffness per unit normal load (1/rad)"),
            ca,
        );
        let c_gamma = m.parameter_with_default(
            &format!("Cg_{wheel}"),
            &format!("{wheel} tyre camber stiffness per unit normal load (1/rad)"),
            cg,
        );
        let sigma = m.parameter_with_default(
            &format!("sigma_{wheel}"),
            &format!("{wheel} tyre relaxation length (m)"),
            sigma,
        );
        // The relaxation length divides (a zero length is the no-slip limit,
        // which is another model); stiffnesses cannot be negative.
        m.lower_bound(&format!("sigma_{wheel}"), 0.0, true);
        m.lower_bound(&format!("Ca_{wheel}"), 0.0, false);
        m.lower_bound(&format!("Cg_{wheel}"), 0.0, false);
        // Ground-plane heading t = axle x Z and lateral direction n = Z x t.
        let axle = frame_axis(axes, Axis::Y);
        let heading: Vec3 = [axle[1].clone(), -axle[0].clone(), num(0)];
        let h = (axle[0].clone().powi(2) + axle[1].clone().powi(2)).sqrt();
        let lateral: Vec3 = [axle[0].clone() / h.clone(), axle[1].clone() / h, num(0)];
        let vm = material_velocity(body, contact);
        // Replace the global X/Y no-slip pair by longitudinal no-slip.
        m.remove_nonholonomic(&format!("{wheel}_rolling_x"));
        m.remove_nonholonomic(&format!("{wheel}_rolling_y"));
        m.nonholonomic(Nonholonomic::Linear {
            name: format!("{wheel}_rolling_longitudinal"),
            expr: dot3(&vm, &heading),
        });
        let v_lat = dot3(&vm, &lateral);
        let speed = smooth_norm(&velocity(contact), ratio(1, 20));
        let camber = axle[2].clone();
        let f_ss = -(n * (c_alpha * v_lat / speed.clone() + c_gamma * camber));
        let name = format!("Fy_{wheel}");
        let f_rate = speed / sigma * (f_ss - crate::expr::Expr::State(name.clone()));
        let f = m.state(
            &name,
            &format!("{wheel} tyre lateral force, positive to the left (N)"),
            f_rate,
        );
        m.force(Force::OnBodyAtPoint {
            name: format!("tyre_lateral_{wheel}"),
            body,
            point: contact,
            force: std::array::from_fn(|k| f.clone() * lateral[k].clone()),
        });
    }
    m.set_role(&parts.rear_contact_lateral, Role::Independent);
    m.set_role(&parts.yaw, Role::Independent);
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted {
    tied: &["sigma_front"],
    floor: Some(0.01),
    start_at_default: true,
    ..Fitted::plain("sigma_rear", 0.2, true)
}];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "tyre_relaxation",
        doc: "tyre lateral slip, cornering and camber stiffness with relaxation length, replacing lateral no-slip",
        apply,
        // A relaxation length toward zero is a rigid, stiff tyre: below 1 cm
        // the fit is held there (tyres measure 0.1-0.3 m), and it starts
        // from the default rather than a stiff tenth of it.
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::FrequencyShiftWithSpeed],
            reason: "a weave frequency shift growing with speed: lateral tyre slip with relaxation (fitted: the relaxation length; cornering and camber stiffness at the model's defaults)",
            linear_equivalent: None,
            own_model: true,
        }),
    }
}
