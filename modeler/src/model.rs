//! Declaring a multibody model: coordinates, parameters, frames built from
//! elementary rotations, points, bodies, constraints and applied forces.
//!
//! A [`ModelBuilder`] collects declarations; [`ModelBuilder::build`] validates
//! the whole model at once and reports every problem it finds
//! ([`ModelError::Invalid`]), then freezes it into a [`Model`] that the
//! derivation stage ([`crate::derive`]) consumes.

// The handles live with the expressions that refer to them (`expr`
// depends on no other module); they are the model's vocabulary, so they are
// named from here too.
pub use crate::expr::{Axis, BodyId, FrameId, PointId, GROUND};
use crate::expr::{Expr, Tensor3, Vec3};
use std::collections::BTreeSet;
use std::fmt;

/// How the runtime treats a coordinate when it reduces the equations
/// (generalized coordinate partitioning, thesis section 3.8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// Independent coordinate (e.g. roll, steer).
    Independent,
    /// Dependent position, solved from the holonomic constraints.
    Dependent,
    /// Ignorable: appears in no equation but is needed for the configuration.
    Ignorable,
}

/// What a coordinate means to the jobs that read it (simulation output and
/// plots, measured-run residuals, identification). A model file declares
/// the meanings it has with [`ModelBuilder::coordinate_role`]; the emitted
/// metadata carries them (`MultibodyModel::COORDINATE_ROLES`), so no job
/// finds a coordinate by its name. The variant names mirror
/// `bikedyn_runtime::model::CoordinateRole` (the emitted code names them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CoordinateRole {
    /// Ground-plane position of the rear contact, forward axis X (m).
    RearContactX,
    /// Ground-plane position of the rear contact, lateral axis Y (m).
    RearContactY,
    /// Heading of the rear frame (rad).
    Yaw,
    /// Lean of the rear frame (rad).
    Roll,
    /// Pitch of the rear frame (rad).
    Pitch,
    /// Steer angle about the steer axis (rad).
    Steer,
    /// Rotation of the rear wheel relative to the rear frame (rad).
    RearWheelRotation,
    /// Rotation of the front wheel relative to the fork (rad).
    FrontWheelRotation,
    /// Angle locating the front contact on the rim (rad).
    FrontContactRimAngle,
}

impl CoordinateRole {
    /// The variant's name, as the emitted code spells it.
    pub fn variant(self) -> &'static str {
        match self {
            CoordinateRole::RearContactX => "RearContactX",
            CoordinateRole::RearContactY => "RearContactY",
            CoordinateRole::Yaw => "Yaw",
            CoordinateRole::Roll => "Roll",
            CoordinateRole::Pitch => "Pitch",
            CoordinateRole::Steer => "Steer",
            CoordinateRole::RearWheelRotation => "RearWheelRotation",
            CoordinateRole::FrontWheelRotation => "FrontWheelRotation",
            CoordinateRole::FrontContactRimAngle => "FrontContactRimAngle",
        }
    }
}

/// What a parameter means to the jobs that need it (see
/// [`CoordinateRole`]); mirrors `bikedyn_runtime::model::ParameterRole`.
/// The forward-speed and gravity parameters are declared by
/// [`ModelBuilder::forward_speed`] and [`ModelBuilder::gravity`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum ParameterRole {
    /// Rear wheel radius (m).
    RearWheelRadius,
    /// Front wheel radius (m).
    FrontWheelRadius,
}

impl ParameterRole {
    /// The variant's name, as the emitted code spells it.
    pub fn variant(self) -> &'static str {
        match self {
            ParameterRole::RearWheelRadius => "RearWheelRadius",
            ParameterRole::FrontWheelRadius => "FrontWheelRadius",
        }
    }
}

/// A generalized coordinate.
#[derive(Clone, Debug)]
pub struct Coordinate {
    pub name: String,
    pub doc: String,
    pub role: Role,
    /// Initial guess for the constraint solver (rad or m).
    pub guess: f64,
    /// The coordinate's value in the physical upright configuration as an
    /// expression in parameters and the other coordinates, when the model
    /// knows it in closed form (e.g. the frame pitch from the geometry). The
    /// constraint solver starts there and the runtime checks that it lands
    /// on this branch (not a flipped frame or the top of a rim).
    pub upright: Option<Expr>,
    /// What the coordinate means to the jobs (roll, steer, ...), if declared.
    pub meaning: Option<CoordinateRole>,
}

/// A parameter.
#[derive(Clone, Debug)]
pub struct Parameter {
    pub name: String,
    /// Meaning and unit, e.g. "steer-axis viscous damping (N m s/rad)".
    pub doc: String,
    /// Value when a bicycle's parameter file does not give it (effect
    /// parameters: the value at which the effect is absent). `None`: the
    /// bicycle must give it.
    pub default: Option<f64>,
    /// The effect that declared this parameter, if any.
    pub effect: Option<String>,
    /// What the parameter means to the jobs (wheel radii), if declared.
    pub meaning: Option<ParameterRole>,
    /// Physical lower bound, if any: `(bound, strict)`; a value below it (or
    /// at it, when strict) is refused when a bicycle is read.
    pub lower: Option<(f64, bool)>,
    /// Measurement uncertainty of a measured parameter (one standard
    /// deviation): what identification may correct, and how far.
    pub uncertainty: Option<Uncertainty>,
}

/// One standard deviation of a measured parameter; mirrors
/// `bikedyn_runtime::model::Uncertainty`. The constants are the defaults
/// bikedyn's models state per kind of measurement, for bicycle files that
/// give no `+/-`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Uncertainty {
    /// A fraction of the value.
    Relative(f64),
    /// In the parameter's unit.
    Absolute(f64),
}

impl Uncertainty {
    /// Moments of inertia from pendulum or torsion measurements: 10 %.
    pub const INERTIA: Uncertainty = Uncertainty::Relative(0.10);
    /// Masses from weighing: 2 %.
    pub const MASS: Uncertainty = Uncertainty::Relative(0.02);
    /// Mass-centre coordinates from hanging or balancing: 2 cm.
    pub const MASS_CENTRE: Uncertainty = Uncertainty::Absolute(0.02);
    /// Frame geometry from a tape and an inclinometer (axle and head-tube
    /// points; trail and steer tilt follow from them): 5 mm.
    pub const GEOMETRY: Uncertainty = Uncertainty::Absolute(0.005);
    /// Wheel radii from a roll-out: 2 mm.
    pub const WHEEL_RADIUS: Uncertainty = Uncertainty::Absolute(0.002);
}

/// An extra first-order state (beyond the coordinates and their rates),
/// e.g. a tyre's lagged lateral force: `dz/dt = rate(param, t, p, p', z)`.
#[derive(Clone, Debug)]
pub struct State {
    pub name: String,
    /// Meaning and unit.
    pub doc: String,
    pub rate: Expr,
    /// The effect that declared it.
    pub effect: Option<String>,
}

/// An effect applied to a model (see [`crate::effects`]).
#[derive(Clone, Debug, PartialEq)]
pub struct EffectInfo {
    pub name: String,
    pub doc: String,
    /// How identification tests it (see [`crate::identification::Identification`]);
    /// `None` for an effect declared without the effect library's `apply`.
    pub identification: Option<crate::identification::Identification>,
}

/// A frame: its parent and the elementary rotations (about the rotated
/// frame's own axes, applied left to right) that lead from parent to it.
#[derive(Clone, Debug)]
pub struct Frame {
    pub name: String,
    pub parent: FrameId,
    pub rotations: Vec<(Axis, Expr)>,
}

/// A point: `base + sum_k A_{frame_k} v_k` (global position).
#[derive(Clone, Debug)]
pub struct Point {
    pub name: String,
    pub base: Option<PointId>,
    pub offsets: Vec<(FrameId, Vec3)>,
}

/// A rigid body.
#[derive(Clone, Debug)]
pub struct Body {
    pub name: String,
    pub frame: FrameId,
    pub mass: Expr,
    /// Inertia tensor about the mass centre, in body axes.
    pub inertia: Tensor3,
    pub mass_centre: PointId,
}

/// A holonomic constraint `Res(p, t) = 0`.
#[derive(Clone, Debug)]
pub enum Holonomic {
    /// A general residual expression (scleronomic or rheonomic).
    Residual { name: String, expr: Expr },
    /// A global component of a point's position is zero (e.g. contact height).
    PointComponent { name: String, point: PointId, axis: Axis },
    /// The derivative of a point's global component with respect to a
    /// coordinate is zero (e.g. the contact point is the lowest of the rim).
    PointComponentStationary {
        name: String,
        point: PointId,
        axis: Axis,
        coordinate: String,
    },
}

/// A nonholonomic constraint, linear in the velocities.
#[derive(Clone, Debug)]
pub enum Nonholonomic {
    /// A global component of the velocity of the material point of `body`
    /// that coincides with `point` is zero (rolling without slip).
    ContactVelocity {
        name: String,
        body: BodyId,
        point: PointId,
        axis: Axis,
    },
    /// A general expression linear in the rates.
    Linear { name: String, expr: Expr },
}

/// An applied force.
#[derive(Clone, Debug)]
pub enum Force {
    /// A generalized force on one coordinate (e.g. a steer torque or damper).
    Generalized {
        name: String,
        coordinate: String,
        expr: Expr,
    },
    /// A force at a body's mass centre, components in `frame`.
    AtMassCentre {
        name: String,
        body: BodyId,
        frame: FrameId,
        force: Vec3,
    },
    /// A force (ground components) whose virtual work is `F . dr_P`, with
    /// `r_P` the declared position of `point`. For a point fixed in a body
    /// this is a force on that body; for a geometric point such as a wheel's
    /// contact it works on the point's travel (power `F . v_P`).
    AtPoint { name: String, point: PointId, force: Vec3 },
    /// A torque (ground components) on a body: virtual work `T . dtheta_body`.
    Torque { name: String, body: BodyId, torque: Vec3 },
    /// A force (ground components) on the material point of `body` that
    /// coincides with `point` (e.g. a tyre force on the rim at the contact):
    /// virtual work `F . dr` of that material point, power `F . v_material`.
    OnBodyAtPoint {
        name: String,
        body: BodyId,
        point: PointId,
        force: Vec3,
    },
}

/// An applied force with its provenance.
#[derive(Clone, Debug)]
pub struct AppliedForce {
    pub force: Force,
    /// The effect that declared it, if any.
    pub effect: Option<String>,
    /// A dissipative force never does positive work (`p'^T Q <= 0` at every
    /// state); `bikedyn verify` checks it.
    pub dissipative: bool,
}

impl AppliedForce {
    /// Name of the force.
    pub fn name(&self) -> &str {
        match &self.force {
            Force::Generalized { name, .. }
            | Force::AtMassCentre { name, .. }
            | Force::AtPoint { name, .. }
            | Force::Torque { name, .. }
            | Force::OnBodyAtPoint { name, .. } => name,
        }
    }
}

/// A file a model is declared in, as a model file declares it: its path
/// and, for the files inside the modeler, its text (`include_str!` of the
/// file itself). The text is hashed into the committed generated code's
/// inputs hash, so that any edit of the file is noticed and named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SourceFile {
    pub path: &'static str,
    pub text: Option<&'static str>,
}

impl SourceFile {
    /// A file whose text is part of the model's inputs.
    pub const fn new(path: &'static str, text: &'static str) -> SourceFile {
        SourceFile { path, text: Some(text) }
    }
}

/// A path alone: a user's model file outside the modeler (derived at every
/// build, so nothing needs its text).
impl From<&'static str> for SourceFile {
    fn from(path: &'static str) -> SourceFile {
        SourceFile { path, text: None }
    }
}

/// A file a model came from, as the model records it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    pub path: String,
    /// FNV-1a hash of the file's text, when the model file gave it.
    pub text_hash: Option<u64>,
}

/// A frozen, validated model.
#[derive(Clone, Debug)]
pub struct Model {
    pub name: String,
    pub doc: String,
    /// Files the model is declared in: its model files and the effects it
    /// applies (named in the generated header).
    pub sources: Vec<Source>,
    /// The base model this one is declared from (its own name for a base).
    pub base: String,
    /// True when forward speed is a degree of freedom (no driving constraint).
    pub free_speed: bool,
    /// Effects applied, in order.
    pub effects: Vec<EffectInfo>,
    /// Forward speed of the bicycle (m/s) as an expression in parameters,
    /// coordinates and rates (e.g. the driving parameter `V`, or `Rt psi'`).
    pub forward_speed: Option<Expr>,
    pub coordinates: Vec<Coordinate>,
    pub parameters: Vec<Parameter>,
    pub frames: Vec<Frame>,
    pub points: Vec<Point>,
    pub bodies: Vec<Body>,
    pub holonomic: Vec<Holonomic>,
    pub nonholonomic: Vec<Nonholonomic>,
    pub forces: Vec<AppliedForce>,
    /// Extra first-order states.
    pub states: Vec<State>,
    /// Points whose global positions are emitted.
    pub points_of_interest: Vec<PointId>,
    /// Gravity: parameter name and the global axis it acts against (Z up).
    pub gravity: Option<(String, Axis)>,
}

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

/// Collects declarations; see the module docs.
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    m: Model,
    /// The effect being applied (see [`ModelBuilder::begin_effect`]).
    effect: Option<String>,
    /// Roles given to names that were not declared: `(name, role)`,
    /// reported by [`ModelBuilder::build`].
    unresolved_roles: Vec<(String, &'static str)>,
}

impl Model {
    /// Check that the model declares every coordinate role the `jobs` need
    /// (e.g. [`BICYCLE_JOBS`]); the error lists each missing role with its
    /// job.
    pub fn check_roles(&self, jobs: &[(&'static str, &[CoordinateRole])]) -> Result<(), ModelError> {
        let mut problems = Vec::new();
        for &(job, roles) in jobs {
            for role in roles {
                if !self.coordinates.iter().any(|c| c.meaning == Some(*role)) {
                    problems.push(Diagnostic::MissingRole {
                        role: role.variant(),
                        job,
                    });
                }
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(ModelError::Invalid {
                model: self.name.clone(),
                problems,
            })
        }
    }

    /// Start declaring a model.
    pub fn builder(name: &str) -> ModelBuilder {
        ModelBuilder {
            effect: None,
            unresolved_roles: Vec::new(),
            m: Model {
                name: name.to_string(),
                doc: String::new(),
                sources: Vec::new(),
                base: name.to_string(),
                free_speed: false,
                effects: Vec::new(),
                forward_speed: None,
                coordinates: Vec::new(),
                parameters: Vec::new(),
                frames: vec![Frame {
                    name: "ground".into(),
                    parent: GROUND,
                    rotations: vec![],
                }],
                points: Vec::new(),
                bodies: Vec::new(),
                holonomic: Vec::new(),
                nonholonomic: Vec::new(),
                forces: Vec::new(),
                states: Vec::new(),
                points_of_interest: Vec::new(),
                gravity: None,
            },
        }
    }

    /// Parameter by name.
    pub fn parameter(&self, name: &str) -> Option<&Parameter> {
        self.parameters.iter().find(|p| p.name == name)
    }

    /// Index of a coordinate.
    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// Names of the holonomic constraints.
    pub fn holonomic_names(&self) -> Vec<String> {
        self.holonomic
            .iter()
            .map(|h| match h {
                Holonomic::Residual { name, .. }
                | Holonomic::PointComponent { name, .. }
                | Holonomic::PointComponentStationary { name, .. } => name.clone(),
            })
            .collect()
    }

    /// Names of the nonholonomic constraints.
    pub fn nonholonomic_names(&self) -> Vec<String> {
        self.nonholonomic
            .iter()
            .map(|h| match h {
                Nonholonomic::ContactVelocity { name, .. } | Nonholonomic::Linear { name, .. } => name.clone(),
            })
            .collect()
    }
}

impl ModelBuilder {
    /// Documentation line of the model.
    pub fn doc(mut self, doc: &str) -> Self {
        self.m.doc = doc.to_string();
        self
    }
    /// A file the model is declared in (shown in generated headers; with
    /// its text, part of the inputs hash of the committed code).
    pub fn source(mut self, file: impl Into<SourceFile>) -> Self {
        self.add_source(file);
        self
    }
    /// Record one more file the model comes from (an effect's file, a
    /// variant's base model file); a path already recorded is kept once.
    pub fn add_source(&mut self, file: impl Into<SourceFile>) {
        let file = file.into();
        if self.m.sources.iter().any(|s| s.path == file.path) {
            return;
        }
        self.m.sources.push(Source {
            path: file.path.to_string(),
            text_hash: file.text.map(|t| crate::hash::fnv1a(t.as_bytes())),
        });
    }
    /// Declare a coordinate (and its rate).
    pub fn coordinate(&mut self, name: &str, role: Role, guess: f64, doc: &str) -> Expr {
        self.m.coordinates.push(Coordinate {
            name: name.into(),
            doc: doc.into(),
            role,
            guess,
            upright: None,
            meaning: None,
        });
        Expr::Coord(name.into())
    }
    /// Declare a parameter the bicycle must give.
    pub fn parameter(&mut self, name: &str, doc: &str) -> Expr {
        self.m.parameters.push(Parameter {
            name: name.into(),
            doc: doc.into(),
            default: None,
            effect: self.effect.clone(),
            meaning: None,
            lower: None,
            uncertainty: None,
        });
        Expr::Param(name.into())
    }
    /// Declare a parameter with a default value (effect parameters: the
    /// value at which the effect is absent, usually 0).
    pub fn parameter_with_default(&mut self, name: &str, doc: &str, default: f64) -> Expr {
        self.m.parameters.push(Parameter {
            name: name.into(),
            doc: doc.into(),
            default: Some(default),
            effect: self.effect.clone(),
            meaning: None,
            lower: None,
            uncertainty: None,
        });
        Expr::Param(name.into())
    }
    /// The coordinate's exact value in the physical upright configuration
    /// (see [`Coordinate::upright`]).
    pub fn upright_value(&mut self, coordinate: &str, value: Expr) {
        if let Some(c) = self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            c.upright = Some(value);
        }
    }
    /// A physical lower bound of parameter `parameter`: values below
    /// `bound` (or equal to it, when `strict`) are refused when a bicycle is
    /// read, e.g. a negative damping coefficient or a zero relaxation length.
    pub fn lower_bound(&mut self, parameter: &str, bound: f64, strict: bool) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(p) => p.lower = Some((bound, strict)),
            None => self.unresolved_roles.push((parameter.to_string(), "lower bound")),
        }
    }
    /// Declare how well a measured parameter is known (see [`Uncertainty`]).
    pub fn uncertainty(&mut self, parameter: &str, uncertainty: Uncertainty) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(p) => p.uncertainty = Some(uncertainty),
            None => self.unresolved_roles.push((parameter.to_string(), "uncertainty")),
        }
    }
    /// Declare what coordinate `coordinate` means (see [`CoordinateRole`]).
    /// An undeclared name or a meaning given to two coordinates is reported
    /// by [`ModelBuilder::build`].
    pub fn coordinate_role(&mut self, coordinate: &str, role: CoordinateRole) {
        match self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            Some(c) => c.meaning = Some(role),
            None => self.unresolved_roles.push((coordinate.to_string(), role.variant())),
        }
    }
    /// Declare what parameter `parameter` means (see [`ParameterRole`]).
    pub fn parameter_role(&mut self, parameter: &str, role: ParameterRole) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(c) => c.meaning = Some(role),
            None => self.unresolved_roles.push((parameter.to_string(), role.variant())),
        }
    }
    /// Change a coordinate's role (for model variants, e.g. free speed).
    pub fn set_role(&mut self, coordinate: &str, role: Role) {
        if let Some(c) = self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            c.role = role;
        }
    }
    /// Mark the model as a variant of `base` (shown in the registry).
    pub fn set_base(&mut self, base: &str) {
        self.m.base = base.to_string();
    }
    /// Declare that forward speed is a degree of freedom.
    pub fn set_free_speed(&mut self, free: bool) {
        self.m.free_speed = free;
    }
    /// The forward speed of the bicycle (m/s) as an expression.
    pub fn forward_speed(&mut self, speed: Expr) {
        self.m.forward_speed = Some(speed);
    }
    /// Rename the model (variants built from another model's declaration).
    pub fn set_name(&mut self, name: &str) {
        self.m.name = name.to_string();
    }
    /// Start applying an effect: parameters and forces declared until
    /// [`ModelBuilder::end_effect`] belong to it.
    pub fn begin_effect(&mut self, name: &str, doc: &str) {
        self.m.effects.push(EffectInfo {
            name: name.into(),
            doc: doc.into(),
            identification: None,
        });
        self.effect = Some(name.to_string());
    }
    /// How identification tests the effect being applied.
    pub fn declare_identification(&mut self, identification: crate::identification::Identification) {
        if let Some(e) = self.m.effects.last_mut() {
            e.identification = Some(identification);
        }
    }
    /// Stop attributing declarations to the current effect.
    pub fn end_effect(&mut self) {
        self.effect = None;
    }
    /// The model as declared so far (read-only; effects inspect bodies,
    /// points and parameters through it).
    pub fn model(&self) -> &Model {
        &self.m
    }
    /// Declare a frame reached from `parent` by elementary rotations.
    pub fn frame(&mut self, name: &str, parent: FrameId, rotations: Vec<(Axis, Expr)>) -> FrameId {
        self.m.frames.push(Frame {
            name: name.into(),
            parent,
            rotations,
        });
        FrameId(self.m.frames.len() - 1)
    }
    /// Declare a point `base + sum A_frame v`.
    pub fn point(&mut self, name: &str, base: Option<PointId>, offsets: Vec<(FrameId, Vec3)>) -> PointId {
        self.m.points.push(Point {
            name: name.into(),
            base,
            offsets,
        });
        PointId(self.m.points.len() - 1)
    }
    /// Declare a rigid body.
    pub fn body(&mut self, name: &str, frame: FrameId, mass: Expr, inertia: Tensor3, mass_centre: PointId) -> BodyId {
        self.m.bodies.push(Body {
            name: name.into(),
            frame,
            mass,
            inertia,
            mass_centre,
        });
        BodyId(self.m.bodies.len() - 1)
    }
    /// Move a body's mass centre to another point (for model variants).
    pub fn move_mass_centre(&mut self, body: BodyId, point: PointId) {
        self.m.bodies[body.0].mass_centre = point;
    }
    /// Replace the documentation line (for model variants).
    pub fn set_doc(&mut self, doc: &str) {
        self.m.doc = doc.to_string();
    }
    /// Add a holonomic constraint.
    pub fn holonomic(&mut self, c: Holonomic) {
        self.m.holonomic.push(c);
    }
    /// Add a nonholonomic constraint.
    pub fn nonholonomic(&mut self, c: Nonholonomic) {
        self.m.nonholonomic.push(c);
    }
    /// Remove a nonholonomic constraint by name (effects that replace one,
    /// e.g. tyre slip replacing a wheel's lateral no-slip condition); false
    /// when there is none of that name.
    pub fn remove_nonholonomic(&mut self, name: &str) -> bool {
        let before = self.m.nonholonomic.len();
        self.m.nonholonomic.retain(|n| match n {
            Nonholonomic::ContactVelocity { name: k, .. } | Nonholonomic::Linear { name: k, .. } => k != name,
        });
        self.m.nonholonomic.len() < before
    }
    /// Declare an extra first-order state with its rate `dz/dt`; returns the
    /// state as an expression.
    pub fn state(&mut self, name: &str, doc: &str, rate: Expr) -> Expr {
        self.m.states.push(State {
            name: name.into(),
            doc: doc.into(),
            rate,
            effect: self.effect.clone(),
        });
        Expr::State(name.into())
    }
    /// Add an applied force (conservative or of unknown sign of power).
    pub fn force(&mut self, f: Force) {
        self.m.forces.push(AppliedForce {
            force: f,
            effect: self.effect.clone(),
            dissipative: false,
        });
    }
    /// Add a dissipative force: its power `p'^T Q` is never positive
    /// (checked by `bikedyn verify`).
    pub fn dissipative_force(&mut self, f: Force) {
        self.m.forces.push(AppliedForce {
            force: f,
            effect: self.effect.clone(),
            dissipative: true,
        });
    }
    /// Emit the global position of this point.
    pub fn point_of_interest(&mut self, p: PointId) {
        self.m.points_of_interest.push(p);
    }
    /// Uniform gravity of magnitude `param` acting along minus `up`.
    pub fn gravity(&mut self, param: &str, up: Axis) {
        self.m.gravity = Some((param.into(), up));
    }

    /// Validate everything and freeze the model.
    pub fn build(self) -> Result<Model, ModelError> {
        let mut problems: Vec<Diagnostic> = self
            .unresolved_roles
            .iter()
            .map(|(name, role)| Diagnostic::Undeclared {
                kind: "coordinate or parameter",
                name: name.clone(),
                used_in: format!("the role `{role}`"),
            })
            .collect();
        problems.extend(validate(&self.m));
        if problems.is_empty() {
            Ok(self.m)
        } else {
            Err(ModelError::Invalid {
                model: self.m.name.clone(),
                problems,
            })
        }
    }
}

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{coord, num, param, rate, vec3};

    #[test]
    fn validation_reports_every_problem_at_once() {
        let mut m = Model::builder("broken");
        let th = m.coordinate("theta", Role::Independent, 0.0, "angle");
        m.coordinate("theta", Role::Dependent, 0.0, "again");
        m.parameter("L", "length");
        let f = m.frame("pendulum", GROUND, vec![(Axis::Y, th + coord("undeclared"))]);
        let p = m.point(
            "tip",
            None,
            vec![(f, vec3(param("L") * rate("theta"), num(0), param("missing")))],
        );
        let _ = m.body("bob", f, param("m"), crate::expr::inertia_wheel(num(1), num(1)), p);
        let err = m.build().unwrap_err();
        let ModelError::Invalid { problems, .. } = &err;
        let has = |d: &Diagnostic| problems.contains(d);
        assert!(has(&Diagnostic::Duplicate {
            kind: "coordinate",
            name: "theta".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "coordinate",
            name: "undeclared".into(),
            used_in: "frame `pendulum`".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "parameter",
            name: "missing".into(),
            used_in: "point `tip`".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "parameter",
            name: "m".into(),
            used_in: "mass of body `bob`".into()
        }));
        assert!(has(&Diagnostic::RateInGeometry {
            item: "point `tip`".into()
        }));
        assert!(has(&Diagnostic::HolonomicCount {
            dependent: 1,
            constraints: 0
        }));
        assert!(has(&Diagnostic::DegreesOfFreedom {
            coordinates: 2,
            independent: 1,
            constraints: 0
        }));
        let text = err.to_string();
        assert!(text.contains("7 problems") || problems.len() >= 7, "{text}");
    }

    #[test]
    fn asymmetric_inertia_and_time_in_geometry_are_reported() {
        let mut m = Model::builder("bad");
        let th = m.coordinate("theta", Role::Independent, 0.0, "angle");
        let f = m.frame("a", GROUND, vec![(Axis::Z, th * crate::expr::time())]);
        let p = m.point("c", None, vec![(f, vec3(num(1), num(0), num(0)))]);
        let mut i = crate::expr::inertia_wheel(num(1), num(2));
        i[0][1] = num(3);
        m.body("b", f, num(1), i, p);
        let ModelError::Invalid { problems, .. } = m.build().unwrap_err();
        assert!(problems.contains(&Diagnostic::AsymmetricInertia { body: "b".into() }));
        assert!(problems.contains(&Diagnostic::TimeDependentGeometry {
            item: "frame `a`".into()
        }));
    }

    #[test]
    fn the_thesis_models_validate() {
        let models = crate::models::all().unwrap();
        let thesis = models.iter().find(|m| m.name == "thesis_whipple").unwrap();
        assert_eq!(thesis.coordinates.len(), 9);
        assert_eq!(thesis.holonomic.len(), 3);
        assert_eq!(thesis.nonholonomic.len(), 4);
        let names: Vec<&str> = thesis.coordinates.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps", "xi"]);
        let offset = models.iter().find(|m| m.name == "whipple_offset").unwrap();
        assert!(offset.parameters.iter().any(|p| p.name == "d4"));
    }

    /// A bicycle model without a role a job needs is refused when it is
    /// generated, naming the role and the job (issue 16, point 1).
    #[test]
    fn a_model_without_the_roles_the_jobs_need_is_refused_at_generation() {
        let models = crate::models::all().unwrap();
        for m in &models {
            m.check_roles(BICYCLE_JOBS).unwrap();
        }
        let mut m = models.iter().find(|m| m.name == "whipple_offset").unwrap().clone();
        for c in m.coordinates.iter_mut() {
            if c.meaning == Some(CoordinateRole::Steer) {
                c.meaning = None;
            }
        }
        let err = m.check_roles(BICYCLE_JOBS).unwrap_err().to_string();
        assert!(
            err.contains("`Steer`") && err.contains("the linear roll-steer analysis"),
            "{err}"
        );
        assert!(err.contains("identification residuals"), "{err}");
        assert!(!err.contains("`Roll`"), "{err}");
    }
}
