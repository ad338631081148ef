//! A steer-torque state-feedback controller `T_steer = K(v) x`, with
//! `x = [roll, steer, roll rate, steer rate]` (thesis signs: roll positive
//! leaning right, steer positive turning left) and each gain linear in the
//! forward speed `v`: `K_i(v) = K_i + K_i_v v`.
//!
//! The TU Delft steer-by-wire bicycle's steer-into-lean assist (after Schwab
//! et al. 2008; `../shared/realdata/README.md`) is, below 6.5 m/s, a steer
//! torque `2 (6.5 - v)` times the roll rate in the benchmark convention
//! (steer positive to the right). In thesis signs the steer torque changes
//! sign, so it is `Kc_roll_rate = -13`, `Kc_roll_rate_v = 2`, all other
//! gains 0. Above 6.5 m/s that law switches to roll feedback; give a
//! parameter file per speed range for such runs.

use super::{BicycleParts, Effect};
use crate::expr::{coord, rate, Expr};
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
    let mut torque = crate::expr::num(0);
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
        expr: torque,
    });
}

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "steer_controller",
        doc: "steer-torque state feedback T = K(v) [roll, steer, roll rate, steer rate], gains linear in speed",
        apply,
    }
}
