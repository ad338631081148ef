//! A steer-torque state-feedback controller `T_steer = K(v) x`, with
//! `x = [roll, steer, roll rate, steer rate]` (thesis signs: roll positive
//! leaning right, steer positive turning left) and each gain linear in the
//! forward speed `v` inside a speed window:
//! `K_i(v) = (K_i + K_i_v v) S(v - Kc_v_min) S(Kc_v_max - v)`,
//! with `S` a unit step. The window is how assist laws that switch off are
//! written: the balance-assist law of Moore's lab, `k (v_s - v)` on the
//! roll rate below `v_s` and nothing above, is `Kc_roll_rate = k v_s`,
//! `Kc_roll_rate_v = -k`, `Kc_v_max = v_s`.
//!
//! The step is smooth, `S(x) = (1 + x / sqrt(x^2 + w^2)) / 2` with
//! `w = 1e-6 m/s`, so that the equations keep exact, finite derivatives at
//! every speed (the linearization and the integrator need them; an
//! exponential step such as `tanh` overflows in its derivative far from the
//! switch). It is within `w^2 / (4 x^2)` of 0 or 1 at a distance `x` from
//! the switch: 3e-11 at 0.1 m/s, and 1 to rounding at the defaults
//! (`Kc_v_min = -1e6`, `Kc_v_max = 1e6` m/s).
//!
//! The TU Delft steer-by-wire bicycle's steer-into-lean assist (after Schwab
//! et al. 2008; `../shared/realdata/README.md`) is, below 6.5 m/s, a steer
//! torque `2 (6.5 - v)` times the roll rate in the benchmark convention
//! (steer positive to the right). In thesis signs the steer torque changes
//! sign, so it is `Kc_roll_rate = -13`, `Kc_roll_rate_v = 2`, all other
//! gains 0, with `Kc_v_max = 6.5`. Above 6.5 m/s that law switches to roll
//! feedback; give a parameter file per speed range for such runs.

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{coord, num, rate, ratio, Expr};
use crate::model::{Force, ModelBuilder};

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let v = m
        .model()
        .forward_speed
        .clone()
        .expect("bicycle models declare their forward speed before effects");
    let states: [(&str, &str, Expr); 4] = [
        ("roll", "N m/rad", coord(&parts.roll)),
        ("steer", "N m/rad", coord(&parts.steer)),
        ("roll_rate", "N m s/rad", rate(&parts.roll)),
        ("steer_rate", "N m s/rad", rate(&parts.steer)),
    ];
    let v_min = m.parameter_with_default(
        "Kc_v_min",
        "speed below which the steer controller is off (m/s)",
        -1e6,
    );
    let v_max = m.parameter_with_default(
        "Kc_v_max",
        "speed above which the steer controller is off (m/s)",
        1e6,
    );
    // Smooth unit step of width w = 0.01 m/s (see the module docs).
    let step = |x: Expr| ratio(1, 2) * (num(1) + x.clone() / (x.powi(2) + ratio(1, 1_000_000_000_000)).sqrt());
    let window = step(v.clone() - v_min) * step(v_max - v.clone());
    let mut torque = num(0);
    for (name, unit, x) in states {
        let k = m.parameter_with_default(
            &format!("Kc_{name}"),
            &format!("steer-torque feedback gain on {} at zero speed ({unit})", name.replace('_', " ")),
            0.0,
        );
        let kv = m.parameter_with_default(
            &format!("Kc_{name}_v"),
            &format!(
                "change of the {} gain per unit forward speed ({unit} per m/s)",
                name.replace('_', " ")
            ),
            0.0,
        );
        torque = torque + (k + kv * v.clone()) * x;
    }
    m.force(Force::Generalized {
        name: "steer_controller".into(),
        coordinate: parts.steer.clone(),
        expr: window * torque,
    });
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted::plain("Kc_roll_rate", 1.0, false)];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "steer_controller",
        doc: "steer-torque state feedback T = K(v) [roll, steer, roll rate, steer rate], gains linear in speed within a speed window [Kc_v_min, Kc_v_max]",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::WeaveDampingAndFrequency],
            reason: "a steer torque in phase with the roll rate: a controller or rider acting on the handlebar",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
