//! The parts a model declares: coordinates and their roles, parameters and
//! their uncertainties, extra states, the effects applied, frames, points,
//! bodies, holonomic and nonholonomic constraints and applied forces.
//!
//! Apart from the [`Model`](super::Model) that holds them and the builder
//! that collects them because they are the model's data vocabulary, read
//! by the derivation and the emitter as much as by the builder.

use crate::expr::{Axis, BodyId, Expr, FrameId, PointId, Tensor3, Vec3};

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
/// the meanings it has with [`ModelBuilder::coordinate_role`](super::ModelBuilder::coordinate_role); the emitted
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
/// [`ModelBuilder::forward_speed`](super::ModelBuilder::forward_speed) and
/// [`ModelBuilder::gravity`](super::ModelBuilder::gravity).
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
