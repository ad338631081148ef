//! The dictionary of generalized forces that identification searches in the
//! measured time series when the library leaves a structured residual
//! (issue 37: find what no library names). Each term is a torque on the
//! roll or the steer equation, `Q = theta v^p s`, with its coefficient a
//! parameter of default zero (the term absent):
//!
//! - `s` a roll or steer angle or rate, `p` = 0, 1 or 2 (a spring, a
//!   damper, a roll-rate feedback, a coupling growing with speed as
//!   gyroscopic and trail terms do);
//! - a constant (a bias: a cable pulling the handlebar, a load off the
//!   plane of symmetry);
//! - a Coulomb-like torque `-T tanh(w / w0)` opposing the equation's own
//!   rate `w`, with `w0` = 0.02 rad/s (friction in a joint).
//!
//! The symbols are `Q_` and the runtime's term name
//! (`bikedyn_runtime::identify::discovery::Term::model_symbol`), in the
//! models' signs (the thesis's: steer positive to the left); a test of the
//! application checks that every term of the runtime's time-series
//! dictionary has its parameter here. The terms are not candidates of the
//! library search: discovery tries them after it, one term at a time, with
//! the library's selection refitted beside them.

use super::{BicycleParts, Effect, Identification};
use crate::expr::{coord, rate, ratio, Expr};
use crate::model::{Force, ModelBuilder};

/// The smoothing rate of the Coulomb-like terms (rad/s), as the runtime's
/// `COULOMB_SMOOTHING`.
const COULOMB_SMOOTHING: (i64, i64) = (1, 50);

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let v = m
        .model()
        .forward_speed
        .clone()
        .expect("bicycle models declare their forward speed before effects");
    let coordinates = [("roll", parts.roll.clone()), ("steer", parts.steer.clone())];
    for (equation, on) in &coordinates {
        let mut total: Option<Expr> = None;
        let mut add = |term: Expr| {
            total = Some(match total.take() {
                Some(t) => t + term,
                None => term,
            });
        };
        for (signal, of) in &coordinates {
            for (kind, value, unit) in [("", coord(of), "N m/rad"), ("_rate", rate(of), "N m s/rad")] {
                for power in 0..=2u8 {
                    let suffix = match power {
                        0 => String::new(),
                        1 => "_v".to_string(),
                        p => format!("_v{p}"),
                    };
                    let per = match power {
                        0 => String::new(),
                        1 => " per m/s".to_string(),
                        p => format!(" per (m/s)^{p}"),
                    };
                    let symbol = format!("Q_{equation}_torque_{signal}{kind}{suffix}");
                    let doc = format!(
                        "dictionary: {equation} torque from the {signal}{} times v^{power}, thesis signs ({unit}{per})",
                        if kind.is_empty() { " angle" } else { " rate" }
                    );
                    let k = m.parameter_with_default(&symbol, &doc, 0.0);
                    let speed = match power {
                        0 => None,
                        p => Some(v.clone().powi(i32::from(p))),
                    };
                    add(match speed {
                        Some(s) => k * s * value.clone(),
                        None => k * value.clone(),
                    });
                }
            }
        }
        let bias = m.parameter_with_default(
            &format!("Q_{equation}_torque_bias"),
            &format!("dictionary: constant {equation} torque, thesis signs (N m)"),
            0.0,
        );
        add(bias);
        let coulomb = m.parameter_with_default(
            &format!("Q_{equation}_torque_coulomb_{equation}_rate"),
            &format!("dictionary: Coulomb-like {equation} torque opposing the {equation} rate (N m)"),
            0.0,
        );
        let (n, d) = COULOMB_SMOOTHING;
        add(-(coulomb * (rate(on) / ratio(n, d)).tanh()));
        m.force(Force::Generalized {
            name: format!("dictionary_{equation}"),
            coordinate: on.clone(),
            expr: total.expect("the dictionary has terms"),
        });
    }
}

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "generalized_forces",
        doc: "the dictionary of generalized forces on the roll and steer equations that discovery searches (every coefficient zero by default)",
        apply,
        identification: Identification::OptOut(
            "the dictionary of discovery: its terms are tried one at a time after the library's search, never as one candidate",
        ),
    }
}
