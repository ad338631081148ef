//! Validation of a whole model at once: every problem it has, as
//! [`Diagnostic`]s in one [`ModelError`], and the coordinate roles the
//! runtime's jobs need ([`BICYCLE_JOBS`]).
//!
//! Apart from the builder because it reads the frozen model alone, after
//! every declaration, so that a model file's mistakes are all reported
//! together rather than one per build.

use super::{CoordinateRole, Force, Holonomic, Model, Nonholonomic, ParameterRole, Role};
use crate::expr::Expr;
use std::collections::BTreeSet;
use std::fmt;

/// One problem found by validation.
#[derive(Clone, Debug, PartialEq)]
pub enum Diagnostic {
    Duplicate {
        kind: &'static str,
        name: String,
    },
    Undeclared {
        kind: &'static str,
        name: String,
        used_in: String,
    },
    TimeDependentGeometry {
        item: String,
    },
    RateInGeometry {
        item: String,
    },
    HolonomicCount {
        dependent: usize,
        constraints: usize,
    },
    DegreesOfFreedom {
        coordinates: usize,
        independent: usize,
        constraints: usize,
    },
    NoBodies,
    AsymmetricInertia {
        body: String,
    },
    NoIndependentCoordinates,
    /// A job of the runtime needs a coordinate with this role.
    MissingRole {
        role: &'static str,
        job: &'static str,
    },
}

/// The jobs of bikedyn's runtime and the coordinate roles each needs (the
/// runtime looks coordinates up by these roles; see
/// `bikedyn_runtime::model::MultibodyModel::require_coordinate`). A bicycle
/// model is checked against them when it is generated
/// ([`Model::check_roles`]), so a missing role stops the build, not a run.
pub const BICYCLE_JOBS: &[(&str, &[CoordinateRole])] = &[
    (
        "the linear roll-steer analysis",
        &[CoordinateRole::Roll, CoordinateRole::Steer],
    ),
    (
        "the nonlinear simulation and the run's trajectory",
        &[
            CoordinateRole::Yaw,
            CoordinateRole::Roll,
            CoordinateRole::Pitch,
            CoordinateRole::Steer,
            CoordinateRole::RearWheelRotation,
        ],
    ),
    (
        "identification residuals",
        &[CoordinateRole::Roll, CoordinateRole::Steer],
    ),
];

impl fmt::Display for Diagnostic {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Diagnostic::Duplicate { kind, name } => write!(f, "{kind} `{name}` is declared twice"),
            Diagnostic::MissingRole { role, job } => {
                write!(f, "no coordinate has the role `{role}`, which {job} needs (declare it with `coordinate_role`)")
            }
            Diagnostic::Undeclared { kind, name, used_in } => {
                write!(f, "{kind} `{name}` is used in {used_in} but not declared")
            }
            Diagnostic::TimeDependentGeometry { item } => {
                write!(f, "{item} depends on time; only constraints and forces may")
            }
            Diagnostic::RateInGeometry { item } => {
                write!(f, "{item} uses a coordinate rate; positions depend on coordinates only")
            }
            Diagnostic::HolonomicCount { dependent, constraints } => write!(
                f,
                "{dependent} dependent coordinates but {constraints} holonomic constraints to solve them"
            ),
            Diagnostic::DegreesOfFreedom { coordinates, independent, constraints } => write!(
                f,
                "{coordinates} coordinates - {independent} independent velocities != {constraints} constraints (holonomic + nonholonomic)"
            ),
            Diagnostic::NoBodies => write!(f, "the model has no bodies"),
            Diagnostic::AsymmetricInertia { body } => {
                write!(f, "inertia tensor of body `{body}` is not symmetric")
            }
            Diagnostic::NoIndependentCoordinates => write!(f, "no independent coordinate declared"),
        }
    }
}

/// Model errors.
#[derive(Clone, Debug, PartialEq)]
pub enum ModelError {
    /// Validation found these problems (all of them, not just the first).
    Invalid { model: String, problems: Vec<Diagnostic> },
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ModelError::Invalid { model, problems } => {
                writeln!(f, "model `{model}` is invalid ({} problems):", problems.len())?;
                for p in problems {
                    writeln!(f, "  - {p}")?;
                }
                Ok(())
            }
        }
    }
}
impl std::error::Error for ModelError {}

fn duplicates<'a>(kind: &'static str, names: impl Iterator<Item = &'a str>, out: &mut Vec<Diagnostic>) {
    let mut seen = BTreeSet::new();
    for n in names {
        if !seen.insert(n) {
            out.push(Diagnostic::Duplicate {
                kind,
                name: n.to_string(),
            });
        }
    }
}

/// Every problem of the model, in declaration order.
pub fn validate(m: &Model) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    duplicates("coordinate", m.coordinates.iter().map(|c| c.name.as_str()), &mut out);
    duplicates(
        "coordinate role",
        m.coordinates
            .iter()
            .filter_map(|c| c.meaning.map(CoordinateRole::variant)),
        &mut out,
    );
    duplicates(
        "parameter role",
        m.parameters
            .iter()
            .filter_map(|c| c.meaning.map(ParameterRole::variant)),
        &mut out,
    );
    duplicates("parameter", m.parameters.iter().map(|c| c.name.as_str()), &mut out);
    duplicates("frame", m.frames.iter().map(|c| c.name.as_str()), &mut out);
    duplicates("point", m.points.iter().map(|c| c.name.as_str()), &mut out);
    duplicates("body", m.bodies.iter().map(|c| c.name.as_str()), &mut out);
    let coords: BTreeSet<&str> = m.coordinates.iter().map(|c| c.name.as_str()).collect();
    let params: BTreeSet<&str> = m.parameters.iter().map(|c| c.name.as_str()).collect();

    // (expression, where it is used, geometry?)
    let mut uses: Vec<(&Expr, String, bool)> = Vec::new();
    for f in &m.frames {
        for (_, e) in &f.rotations {
            uses.push((e, format!("frame `{}`", f.name), true));
        }
    }
    for p in &m.points {
        for (_, v) in &p.offsets {
            for e in v {
                uses.push((e, format!("point `{}`", p.name), true));
            }
        }
    }
    for b in &m.bodies {
        uses.push((&b.mass, format!("mass of body `{}`", b.name), true));
        for row in &b.inertia {
            for e in row {
                uses.push((e, format!("inertia of body `{}`", b.name), true));
            }
        }
        let sym = (0..3).all(|i| (0..3).all(|j| b.inertia[i][j] == b.inertia[j][i]));
        if !sym {
            out.push(Diagnostic::AsymmetricInertia { body: b.name.clone() });
        }
    }
    for h in &m.holonomic {
        match h {
            Holonomic::Residual { name, expr } => uses.push((expr, format!("holonomic constraint `{name}`"), false)),
            Holonomic::PointComponentStationary { name, coordinate, .. } => {
                if !coords.contains(coordinate.as_str()) {
                    out.push(Diagnostic::Undeclared {
                        kind: "coordinate",
                        name: coordinate.clone(),
                        used_in: format!("holonomic constraint `{name}`"),
                    });
                }
            }
            Holonomic::PointComponent { .. } => {}
        }
    }
    for n in &m.nonholonomic {
        if let Nonholonomic::Linear { name, expr } = n {
            uses.push((expr, format!("nonholonomic constraint `{name}`"), false));
        }
    }
    for f in &m.forces {
        match &f.force {
            Force::Generalized { name, coordinate, expr } => {
                uses.push((expr, format!("force `{name}`"), false));
                if !coords.contains(coordinate.as_str()) {
                    out.push(Diagnostic::Undeclared {
                        kind: "coordinate",
                        name: coordinate.clone(),
                        used_in: format!("force `{name}`"),
                    });
                }
            }
            Force::AtMassCentre { name, force, .. } | Force::AtPoint { name, force, .. } => {
                for e in force {
                    uses.push((e, format!("force `{name}`"), false));
                }
            }
            Force::Torque { name, torque, .. } => {
                for e in torque {
                    uses.push((e, format!("force `{name}`"), false));
                }
            }
            Force::OnBodyAtPoint { name, force, .. } => {
                for e in force {
                    uses.push((e, format!("force `{name}`"), false));
                }
            }
        }
    }
    for st in &m.states {
        uses.push((&st.rate, format!("rate of state `{}`", st.name), false));
    }
    for c in &m.coordinates {
        if let Some(e) = &c.upright {
            uses.push((e, format!("upright value of `{}`", c.name), true));
        }
    }
    duplicates("state", m.states.iter().map(|c| c.name.as_str()), &mut out);
    let states: BTreeSet<&str> = m.states.iter().map(|c| c.name.as_str()).collect();
    if let Some(v) = &m.forward_speed {
        uses.push((v, "the forward speed".to_string(), false));
    }
    for (e, used_in, geometry) in uses {
        let mut names = BTreeSet::new();
        e.names(&mut names);
        for (kind, name) in names {
            let ok = match kind {
                "state" => states.contains(name.as_str()) && !geometry,
                "parameter" => params.contains(name.as_str()),
                "coordinate" | "rate" => coords.contains(name.as_str()),
                _ => true,
            };
            if !ok {
                let kind = if kind == "rate" { "coordinate" } else { kind };
                out.push(Diagnostic::Undeclared {
                    kind,
                    name,
                    used_in: used_in.clone(),
                });
            } else if geometry && (kind == "kinematics" || kind == "kinematic rate") {
                out.push(Diagnostic::RateInGeometry { item: used_in.clone() });
            } else if geometry && kind == "time" {
                out.push(Diagnostic::TimeDependentGeometry { item: used_in.clone() });
            } else if geometry && kind == "rate" {
                out.push(Diagnostic::RateInGeometry { item: used_in.clone() });
            }
        }
    }
    if let Some((g, _)) = &m.gravity {
        if !params.contains(g.as_str()) {
            out.push(Diagnostic::Undeclared {
                kind: "parameter",
                name: g.clone(),
                used_in: "gravity".into(),
            });
        }
    }
    if m.bodies.is_empty() {
        out.push(Diagnostic::NoBodies);
    }
    let dependent = m.coordinates.iter().filter(|c| c.role == Role::Dependent).count();
    if dependent != m.holonomic.len() {
        out.push(Diagnostic::HolonomicCount {
            dependent,
            constraints: m.holonomic.len(),
        });
    }
    let independent = m.coordinates.iter().filter(|c| c.role == Role::Independent).count();
    if independent == 0 {
        out.push(Diagnostic::NoIndependentCoordinates);
    }
    let nc = m.holonomic.len() + m.nonholonomic.len();
    if m.coordinates.len() != independent + nc {
        out.push(Diagnostic::DegreesOfFreedom {
            coordinates: m.coordinates.len(),
            independent,
            constraints: nc,
        });
    }
    out
}
