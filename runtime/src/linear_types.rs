//! The results and errors of a model's linearization and constraint
//! solution: the `MultibodyModel` trait names them, and `constraints` and
//! `linearize` compute them. They live below all three so that no module
//! depends on another in a cycle; `model`, `constraints` and `linearize`
//! re-export them at their usual paths.

use nalgebra::DMatrix;
use thiserror::Error;

/// A model lacks a meaning (role) that a job needs.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("model `{model}` declares no {kind} with the role `{role}`, which {job} needs (declare it in the model file: `coordinate_role` / `parameter_role`)")]
pub struct MissingRole {
    pub model: &'static str,
    /// `"coordinate"` or `"parameter"`.
    pub kind: &'static str,
    pub role: &'static str,
    /// The job that needs it, e.g. `"simulation output"`.
    pub job: &'static str,
}

/// Why the configuration could not be found.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum ConstraintError {
    /// Newton did not converge: for a bicycle this means the geometry has no
    /// ground contact (e.g. the front wheel cannot reach the ground).
    #[error("holonomic constraint `{constraint}` cannot be satisfied (residual {residual:.3e} after {iterations} Newton iterations): the geometry has no ground contact or the initial guess is too far")]
    NotSatisfiable {
        constraint: &'static str,
        residual: f64,
        iterations: usize,
    },
    /// The constraint Jacobian with respect to the dependent coordinates is singular.
    #[error("the constraint Jacobian is singular at column {column} for the {what}: its largest available pivot {pivot:.3e} is below 1e-14 times its largest entry {scale:.3e}, so the dependent coordinates are not determined by the constraints here")]
    SingularJacobian {
        what: &'static str,
        column: usize,
        pivot: f64,
        /// Largest entry magnitude of the Jacobian.
        scale: f64,
    },
    /// The model's closed-form upright configuration has no real value
    /// (e.g. the frame pitch when the front wheel cannot reach the ground).
    #[error("the front wheel cannot touch the ground: the model's upright configuration has no real value for `{coordinate}` with these parameters")]
    NoUprightConfiguration { coordinate: &'static str },
    /// A parameter, coordinate or result is NaN or infinite.
    #[error("non-finite value in {what}")]
    NotFinite { what: &'static str },
}

/// Linearization failures.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum LinearizeError {
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
    #[error(transparent)]
    MissingRole(#[from] MissingRole),
    #[error("model `{model}` has no parameter `{name}`")]
    MissingParameter { model: &'static str, name: String },
    #[error("model `{model}` needs a value of `{name}` ({doc}): the bicycle gives none and the model has no default")]
    NoValue {
        model: &'static str,
        name: &'static str,
        doc: &'static str,
    },
    #[error("the canonical form needs exactly 2 independent coordinates (roll, steer), model `{model}` has {n}")]
    NotRollSteer { model: &'static str, n: usize },
    #[error("the reduced mass matrix is singular")]
    SingularMass,
    /// The constraint solver converged to a root that is not the physical
    /// upright configuration: refusing is better than returning the
    /// matrices of another mechanism.
    #[error("the constraint solution is not the physical upright bicycle: {coordinate} = {value:.6} rad, but {what} gives {expected:.6} rad")]
    OffBranch {
        coordinate: &'static str,
        value: f64,
        expected: f64,
        what: &'static str,
    },
    /// A wheel of zero radius (a skate) that has a spin inertia: its spin
    /// rate, and so its gyroscopic moment, would be infinite.
    #[error("the {wheel} has zero radius ({radius_symbol} = 0) but a non-zero spin inertia ({inertia_symbol} = {inertia}): a skate wheel must have zero spin inertia")]
    SkateWithSpinInertia {
        wheel: &'static str,
        radius_symbol: &'static str,
        inertia_symbol: &'static str,
        inertia: f64,
    },
    /// The zero-radius limit could not be taken reliably (the matrices are
    /// not the quadratic polynomial in the radius that the closed form says).
    #[error("the zero-radius limit is not reliable here (departure from a quadratic in the radius: {departure:.3e}, relative to {scale:.3e})")]
    ZeroRadiusLimit { departure: f64, scale: f64 },
    #[error("model `{model}` declares no forward speed (no speed parameter and no speed coordinate)")]
    NoForwardSpeed { model: &'static str },
    #[error("model `{model}` has {n} independent coordinates or states, more than the linearization supports")]
    TooManyIndependent { model: &'static str, n: usize },
    #[error("model `{model}` has extra states or coordinates (tyre forces, a rider's lean): its linearization is a state-space model, not the roll-steer M, C, K (use state_space_at_speed)")]
    HasStates { model: &'static str },
}

/// `M`, `C`, `K` of `M q'' + C q' + K q = 0` (thesis eq. 48-50) about
/// upright straight running, in the model's independent coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearization {
    pub mass: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
}

/// A linearization and the stiffness at rest from the same evaluation.
pub type WithRest = (Linearization, DMatrix<f64>);

/// A state matrix (re-exported so generated code needs no nalgebra).
pub type StateMatrix = DMatrix<f64>;
