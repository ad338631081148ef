//! The interface every generated multibody model implements.
//!
//! Notation follows the thesis (section 3): `p` are the generalized
//! coordinates, `dp` their time derivatives, `param` the model's parameters in
//! the order of [`MultibodyModel::PARAMETERS`], `t` time (s). Matrices are
//! written row-major into caller-provided slices; nothing allocates.
//!
//! The equations of motion in Lagrange's first kind are
//! `M p'' + Cq^T lambda_h + B^T lambda_nh = Qv + Qgrav + Qext`, with the
//! holonomic constraints `Res(p, t) = 0` (velocity level `Cq p' + Ct = 0`,
//! acceleration level `Cq p'' + dCqdp + ... = 0`) and the nonholonomic ones
//! `B p' = 0` (acceleration level `B p'' + dBdp = 0`).

pub use crate::linear_types::MissingRole;
use crate::scalar::Scalar;

/// A parameter of a generated model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParameterInfo {
    pub name: &'static str,
    /// Meaning and unit.
    pub doc: &'static str,
    /// Value used when a bicycle does not give the parameter (for an
    /// effect's parameters: the value at which the effect is absent).
    pub default: Option<f64>,
    /// The effect that declared it.
    pub effect: Option<&'static str>,
    /// Physical lower bound `(bound, strict)`, if declared.
    pub lower: Option<(f64, bool)>,
    /// How well the parameter is known when a bicycle file states no
    /// uncertainty (measured parameters only): identification may correct
    /// it, within this standard deviation as a Gaussian prior.
    pub uncertainty: Option<Uncertainty>,
}

/// Positions within `independent` (coordinate indices) of the independent
/// coordinates with no declared role in `roles`: those the rolling bicycle
/// lacks, which a model adds with a body of its own (a leaning rider's
/// `lean`). The lateral position and yaw that tyre slip frees have roles.
pub fn added_coordinates(independent: &[usize], roles: &[(CoordinateRole, usize)]) -> Vec<usize> {
    (0..independent.len())
        .filter(|&k| !roles.iter().any(|&(_, j)| j == independent[k]))
        .collect()
}

/// The unit at the end of a parameter's description, as in `"trail (m)"`
/// or `"steer-axis viscous damping coefficient (N m s/rad)"`; `None` when
/// the description does not end in one.
pub fn unit_of(doc: &str) -> Option<&str> {
    doc.strip_suffix(')')?.rsplit_once('(').map(|(_, u)| u)
}

/// A parameter's measurement uncertainty, one standard deviation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Uncertainty {
    /// A fraction of the value (inertias: 0.10).
    Relative(f64),
    /// In the parameter's unit (mass-centre coordinates: 0.02 m).
    Absolute(f64),
}

impl Uncertainty {
    /// The standard deviation for a parameter of value `value`.
    pub fn sigma(self, value: f64) -> f64 {
        match self {
            Uncertainty::Relative(r) => r * value.abs(),
            Uncertainty::Absolute(a) => a,
        }
    }
}

impl ParameterInfo {
    /// Why `value` is not a physical value of this parameter, if it is not:
    /// not finite, or below its declared lower bound.
    pub fn refuses(&self, value: f64) -> Option<String> {
        if !value.is_finite() {
            return Some(format!("`{}` must be a finite number, found {value}", self.name));
        }
        match self.lower {
            Some((b, true)) if value <= b => Some(format!(
                "`{}` must be greater than {b}, found {value} ({})",
                self.name, self.doc
            )),
            Some((b, false)) if value < b => Some(format!(
                "`{}` must be at least {b}, found {value} ({})",
                self.name, self.doc
            )),
            _ => None,
        }
    }
}

/// An applied force of a generated model (one row of
/// [`MultibodyModel::applied_force_terms`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ForceInfo {
    pub name: &'static str,
    pub effect: Option<&'static str>,
    /// Its power `p'^T Q` is never positive.
    pub dissipative: bool,
}

/// What a coordinate means to the jobs that read it: simulation output and
/// plots, measured-run residuals, identification. A model file declares the
/// meanings it has; jobs look coordinates up by meaning
/// ([`MultibodyModel::coordinate_with_role`]), never by name, and a model
/// without a meaning a job needs is refused with a message naming both
/// ([`MissingRole`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
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
    /// Every role, in order.
    pub const ALL: [CoordinateRole; 9] = [
        CoordinateRole::RearContactX,
        CoordinateRole::RearContactY,
        CoordinateRole::Yaw,
        CoordinateRole::Roll,
        CoordinateRole::Pitch,
        CoordinateRole::Steer,
        CoordinateRole::RearWheelRotation,
        CoordinateRole::FrontWheelRotation,
        CoordinateRole::FrontContactRimAngle,
    ];
    /// The role in words (`"roll"`, `"rear wheel rotation"`).
    pub fn describe(self) -> &'static str {
        match self {
            CoordinateRole::RearContactX => "rear contact X",
            CoordinateRole::RearContactY => "rear contact Y",
            CoordinateRole::Yaw => "yaw",
            CoordinateRole::Roll => "roll",
            CoordinateRole::Pitch => "pitch",
            CoordinateRole::Steer => "steer",
            CoordinateRole::RearWheelRotation => "rear wheel rotation",
            CoordinateRole::FrontWheelRotation => "front wheel rotation",
            CoordinateRole::FrontContactRimAngle => "front contact rim angle",
        }
    }
}

/// What a parameter means to the jobs that need it (see
/// [`CoordinateRole`]). Forward speed and gravity have their own constants
/// ([`MultibodyModel::FORWARD_SPEED_PARAMETER`],
/// [`MultibodyModel::GRAVITY_PARAMETER`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ParameterRole {
    /// Rear wheel radius (m).
    RearWheelRadius,
    /// Front wheel radius (m).
    FrontWheelRadius,
}

impl ParameterRole {
    /// The role in words.
    pub fn describe(self) -> &'static str {
        match self {
            ParameterRole::RearWheelRadius => "rear wheel radius",
            ParameterRole::FrontWheelRadius => "front wheel radius",
        }
    }
}

/// An effect applied to a model, with what identification needs to test it,
/// as its effect file declares (see the modeler's `effects` module, whose
/// types these mirror).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EffectDeclaration {
    pub name: &'static str,
    pub doc: &'static str,
    /// `None` for an effect declared without the effect library's `apply`
    /// (identification then never tests it, and says so).
    pub identification: Option<EffectIdentification>,
}

/// How identification tests an effect, or why it never does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum EffectIdentification {
    /// A candidate.
    Candidate(CandidateDeclaration),
    /// Never a candidate, for this reason.
    OptOut(&'static str),
}

/// How a candidate effect is fitted and recognised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CandidateDeclaration {
    /// The parameters fitted.
    pub fitted: &'static [FittedParameter],
    /// Parameters held at the bicycle's value (or their default).
    pub held: &'static [&'static str],
    /// It shows as a loss of speed during the response.
    pub speed_decay: bool,
    /// The residual patterns of the base model that point to it.
    pub signatures: &'static [Signature],
    /// Why those patterns point to it.
    pub reason: &'static str,
    /// Its stand-in in the linear (eigenvalue) prediction, if any.
    pub linear_equivalent: Option<LinearEquivalent>,
    /// Fitted with a model of its own (it changes the degrees of freedom).
    pub own_model: bool,
}

/// A fitted parameter of a candidate effect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FittedParameter {
    pub symbol: &'static str,
    /// Parameters that take the same value.
    pub tied: &'static [&'static str],
    /// Typical magnitude, in the parameter's unit.
    pub scale: f64,
    /// It dissipates energy (must come out positive to be physical).
    pub dissipative: bool,
    /// Floor of the fit, if any.
    pub floor: Option<f64>,
    /// Ceiling of the fit, if any.
    pub ceiling: Option<f64>,
    /// The fit starts from the parameter's default.
    pub start_at_default: bool,
    /// A parameter of the law's shape, not of the effect's size: it starts
    /// from the bicycle's value, and a bicycle file setting it does not
    /// declare the effect present.
    pub shape: bool,
}

/// Residual patterns of the base model that the diagnosis tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Signature {
    /// Measured weave more damped and slower than predicted.
    WeaveDampingAndFrequency,
    /// Damping that grows as the amplitude falls.
    AmplitudeDependentDamping,
    /// A steady lean after the kick.
    SteadyLean,
    /// A weave frequency error that grows with speed.
    FrequencyShiftWithSpeed,
    /// A loss of speed during the response.
    SpeedDecay,
}

impl Signature {
    /// Every pattern, in the order the diagnosis reports them.
    pub const ALL: [Signature; 5] = [
        Signature::WeaveDampingAndFrequency,
        Signature::AmplitudeDependentDamping,
        Signature::SteadyLean,
        Signature::FrequencyShiftWithSpeed,
        Signature::SpeedDecay,
    ];
}

/// A linear stand-in for an effect whose linearization is not useful.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinearEquivalent {
    /// Coulomb friction torque `torque` as the viscous damping `damping` of
    /// its describing function at the response's amplitude (`c_eq = 4 T /
    /// (pi A)` for a sinusoid of rate amplitude `A`).
    DescribingFunctionDamping {
        torque: &'static str,
        damping: &'static str,
    },
}

/// A generated model. All functions are associated (no `self`): a model is a
/// type, its code is monomorphised for each scalar.
pub trait MultibodyModel: Send + Sync + 'static {
    /// Model name, as declared in the modeler.
    const NAME: &'static str;
    /// One-line description.
    const DOC: &'static str;
    /// The base model it is declared from (itself for a base model).
    const BASE: &'static str;
    /// True when forward speed is a degree of freedom.
    const FREE_SPEED: bool;
    /// Effects of the library applied to it.
    const EFFECTS: &'static [&'static str];
    /// Every parameter with its meaning, default and effect, in the order
    /// of [`MultibodyModel::PARAMETERS`].
    const PARAMETER_INFO: &'static [ParameterInfo];
    /// Applied forces, in the order of `applied_force_terms`.
    const FORCES: &'static [ForceInfo];
    /// Index of the parameter that imposes the forward speed (driven
    /// models), if any.
    const FORWARD_SPEED_PARAMETER: Option<usize>;
    /// Index of the independent coordinate whose rate carries the forward
    /// speed (free-speed models), if any.
    const SPEED_COORDINATE: Option<usize>;
    /// Index of the gravitational-acceleration parameter, if any.
    const GRAVITY_PARAMETER: Option<usize>;
    /// The effects applied, with their identification declarations.
    const EFFECT_DECLARATIONS: &'static [EffectDeclaration] = &[];
    /// Declared meanings of coordinates: `(role, coordinate index)`.
    const COORDINATE_ROLES: &'static [(CoordinateRole, usize)] = &[];
    /// Declared meanings of parameters: `(role, parameter index)`.
    const PARAMETER_ROLES: &'static [(ParameterRole, usize)] = &[];
    /// Extra first-order states (e.g. lagged tyre forces). Generated code
    /// reads them from the `param` slice after the parameters: slices passed
    /// to a model with states hold `PARAMETERS.len() + STATES.len()` values.
    const STATES: &'static [&'static str];
    /// Meaning and unit of each extra state.
    const STATE_DOCS: &'static [&'static str];
    /// Generalized coordinates, in order.
    const COORDINATES: &'static [&'static str];
    /// Parameters, in the order of the `param` slices.
    const PARAMETERS: &'static [&'static str];
    /// Names of the holonomic constraints (rows of `Res`, `Cq`).
    const HOLONOMIC: &'static [&'static str];
    /// Names of the nonholonomic constraints (rows of `B`).
    const NONHOLONOMIC: &'static [&'static str];
    /// Names of the points of interest (e.g. wheel contacts).
    const POINTS: &'static [&'static str];
    /// Indices of the independent coordinates (e.g. roll, steer).
    const INDEPENDENT: &'static [usize];
    /// Indices of the dependent positions solved from the holonomic
    /// constraints (one per constraint, in order).
    const DEPENDENT: &'static [usize];
    /// Initial guess of every coordinate for the constraint solver.
    const INITIAL_GUESS: &'static [f64];
    /// Layout of [`MultibodyModel::all_quantities`]'s output: `(function
    /// name, offset, length)` for every buffer quantity, in order.
    const ALL_QUANTITIES_LAYOUT: &'static [(&'static str, usize, usize)];
    /// Floating-point operations per call of each generated function
    /// (after common-subexpression elimination), by function name.
    const FLOPS: &'static [(&'static str, usize)];

    /// Number of coordinates.
    fn nq() -> usize {
        Self::COORDINATES.len()
    }
    /// Index of a coordinate by name.
    fn coordinate_index(name: &str) -> Option<usize> {
        Self::COORDINATES.iter().position(|c| *c == name)
    }
    /// Index of a parameter by name.
    fn parameter_index(name: &str) -> Option<usize> {
        Self::PARAMETERS.iter().position(|c| *c == name)
    }
    /// Index of the coordinate with meaning `role`, if the model declares it.
    fn coordinate_with_role(role: CoordinateRole) -> Option<usize> {
        Self::COORDINATE_ROLES.iter().find(|(r, _)| *r == role).map(|&(_, i)| i)
    }
    /// Index of the parameter with meaning `role`, if the model declares it.
    fn parameter_with_role(role: ParameterRole) -> Option<usize> {
        Self::PARAMETER_ROLES.iter().find(|(r, _)| *r == role).map(|&(_, i)| i)
    }
    /// [`MultibodyModel::coordinate_with_role`], or an error naming the
    /// role and the job that needs it.
    fn require_coordinate(role: CoordinateRole, job: &'static str) -> Result<usize, MissingRole> {
        Self::coordinate_with_role(role).ok_or(MissingRole {
            model: Self::NAME,
            kind: "coordinate",
            role: role.describe(),
            job,
        })
    }
    /// [`MultibodyModel::parameter_with_role`], or an error naming the
    /// role and the job that needs it.
    fn require_parameter(role: ParameterRole, job: &'static str) -> Result<usize, MissingRole> {
        Self::parameter_with_role(role).ok_or(MissingRole {
            model: Self::NAME,
            kind: "parameter",
            role: role.describe(),
            job,
        })
    }

    /// Mass matrix `M(p)`, `nq x nq` (thesis eq. 32).
    fn mass_matrix<T: Scalar>(param: &[T], p: &[T], out: &mut [T]);
    /// Quadratic-velocity forces `Qv(p, p') = -d(M p')/dp p' + dT/dp` (eq. 36).
    fn quadratic_velocity_forces<T: Scalar>(param: &[T], p: &[T], dp: &[T], out: &mut [T]);
    /// Gravity forces `Qgrav(p)` (eq. 38).
    fn gravity_forces<T: Scalar>(param: &[T], p: &[T], out: &mut [T]);
    /// Applied generalized forces `Qext(p, p', t)` (zero for a model without effects).
    fn applied_forces<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// Holonomic residuals `Res(p, t)`.
    fn holonomic_residuals<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]);
    /// `Cq = dRes/dp`, `nh x nq`.
    fn holonomic_jacobian<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]);
    /// `Ct = dRes/dt`, `nh`.
    fn holonomic_time_derivative<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]);
    /// `dCqdp = d(Cq p')/dp p'`, `nh`.
    fn holonomic_convective<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// Nonholonomic constraint velocities (e.g. contact-point velocities), `nnh`.
    fn nonholonomic_velocities<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// `B = d(velocities)/dp'`, `nnh x nq`.
    fn nonholonomic_matrix<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]);
    /// `dBdp = d(B p')/dp p'`, `nnh`.
    fn nonholonomic_convective<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// Kinetic energy `T = 1/2 p'^T M p'` (J).
    fn kinetic_energy<T: Scalar>(param: &[T], p: &[T], dp: &[T]) -> T;
    /// Potential energy of gravity `V` (J), with `Qgrav = -dV/dp`.
    fn potential_energy<T: Scalar>(param: &[T], p: &[T]) -> T;
    /// Every buffer quantity at once (one shared set of common
    /// subexpressions), concatenated as [`MultibodyModel::ALL_QUANTITIES_LAYOUT`] says.
    fn all_quantities<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// Global positions of the points of interest, `3 x npoints` (x, y, z per point).
    fn point_positions<T: Scalar>(param: &[T], p: &[T], out: &mut [T]);
    /// Generalized force of each applied force, `nforces x nq` (their sum is
    /// `applied_forces`).
    fn applied_force_terms<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
    /// Forward speed of the bicycle (m/s) as the model declares it.
    fn forward_speed<T: Scalar>(param: &[T], p: &[T], dp: &[T]) -> T;
    /// The physical upright configuration: coordinates the model gives in
    /// closed form (e.g. frame pitch and the front contact's rim angle from
    /// the geometry) take that value, the others keep their value in `p`.
    fn upright_configuration<T: Scalar>(param: &[T], p: &[T], out: &mut [T]);
    /// The velocity terms and their first derivatives at `(p, p', t)`
    /// upright, for the exact linearization (row-major): rows `Qv + Qext`
    /// (nq), `dCqdp` (nh), `dBdp` (nnh); columns the value, the derivatives
    /// in the coordinates [`MultibodyModel::INDEPENDENT`] then
    /// [`MultibodyModel::DEPENDENT`], then in every rate. Symbolic
    /// derivatives, evaluated in `f64` with the independent coordinates at
    /// zero and the ignorable ones (without a closed-form upright value) at
    /// their initial guess when it is zero: those entries of `p` are not
    /// read.
    fn upright_velocity_terms_jacobian(param: &[f64], t: f64, p: &[f64], dp: &[f64], out: &mut [f64]);
    /// Exact linearization about the steady motion with independent rates
    /// `dq0`, and the stiffness at rest, with this model's dual width
    /// (generated: `linearize::linearize_with_rest::<Self, {ni}, {2 ni}>`).
    fn linearize_with_rest_exact(
        param: &[f64],
        dq0: &[f64],
    ) -> Result<crate::linear_types::WithRest, crate::linear_types::LinearizeError>;
    /// State matrix over `[q, q', z]` with this model's dual width
    /// (generated: `linearize::state_space_dual::<Self, {2 ni + nz}>`).
    fn state_space_exact(
        param: &[f64],
        dq0: &[f64],
    ) -> Result<crate::linear_types::StateMatrix, crate::linear_types::LinearizeError>;
    /// Rates of the extra states, `STATES.len()` values.
    fn state_rates<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]);
}
