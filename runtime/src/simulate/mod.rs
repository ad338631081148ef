//! Integration of the full nonlinear equations of any generated model.
//!
//! # Formulation (thesis section 3.8, eq. 40-47)
//!
//! The state is `y = [q, q', g, z]` ([`StateLayout`]): the independent
//! coordinates `q` of the model (`M::INDEPENDENT`: roll theta and steer gamma
//! for a driven-speed model; theta, rear wheel rotation psi and gamma for a
//! free-speed one) and their rates, the ignorable coordinates `g` (those that
//! are neither independent nor dependent: `xc yc phi eps` with rolling
//! constraints, `xc eps` with tyre slip, where `yc` and `phi` are
//! independent), and the extra first-order states `z` of `M::STATES` (e.g.
//! the lagged lateral tyre forces of `tyre_relaxation`). At every evaluation
//! of the right-hand side:
//!
//! 1. the dependent positions (`M::DEPENDENT`: pitch beta, the front contact
//!    angle xi and, in driven models, psi) are solved from the holonomic
//!    constraints `Res(p, t) = 0` by Newton's method, warm-started from the
//!    previous evaluation, to a max-norm residual of 1e-13;
//! 2. all non-independent velocities solve `D_dep p'_dep = d - D_ind q'` with
//!    `D = [Cq; B]` (holonomic at velocity level, and the rolling
//!    constraints), so the velocity constraints hold to rounding;
//! 3. with `p' = E q' + ...` and `p'' = E q'' + F` (`E = [I; -D_dep^-1 D_ind]`,
//!    `F = [0; -D_dep^-1 (dCq/dp p' p' ; dB/dp p' p')]`) the reduced equations
//!    `Mi q'' = Qi`, `Mi = E^T M E`, `Qi = E^T (Qv + Qgrav + Qext + Qin - M F)`
//!    give `q''`; `Qin` are the torque pulses of [`Inputs`];
//! 4. the ignorable coordinates are integrated from their rates (the
//!    dependent velocities of step 2); time is a state too (`t' = 1`), which
//!    makes the system autonomous for the integrator (see [`StateLayout`]);
//! 5. the generated code reads `z` from the tail of the parameter vector
//!    (`M::STATES`), so `z` is written there before step 1, and
//!    `z' = M::state_rates(param + z, t, p, p')` with the full `p, p'`.
//!
//! Initial conditions: the independent rates other than roll and steer (the
//! rear wheel's with free speed; with tyre slip also `yc` and `phi`) solve
//! `speed = V` and `z' = 0` for the given `z(0)` (zero unless the parameter
//! vector carries a tail): the extra states start at rest, which upright
//! is rolling without lateral slip. A kick is a finite impulse, so with
//! tyre slip it makes the wheels slide sideways until the tyre forces build
//! up; `z` does not jump.
//!
//! # Drift control
//!
//! There is no constraint drift to stabilise: the dependent positions are
//! never integrated but re-solved at every evaluation, so the holonomic
//! residual stays at the Newton tolerance (reported for every output sample
//! as `constraint_residual`, about 1e-15 in practice); the dependent
//! velocities are solved from the constraint matrix, so the velocity-level
//! residual is at rounding. The ignorable coordinates (position and heading)
//! are not constrained by any holonomic equation; their error is the
//! integrator's, controlled by the tolerances like every other state. This is
//! the thesis's own coordinate partitioning; it is valid as long as `D_dep`
//! is regular (it is, for every configuration with both wheels on the ground
//! and the steer away from 90 degrees); a singular `D_dep` is reported as
//! [`SimulateError::Singular`].
//!
//! # Integrator
//!
//! [`Method::Dop853`] (default): `ode_solvers` 0.6.2 (`Dop853`, Hairer's
//! DOP853: explicit Runge-Kutta of order 8(5,3), adaptive step with error
//! control, 7th-order dense output), chosen because it uses the workspace's
//! nalgebra 0.34 (no second nalgebra, a few seconds of build time) and is a
//! faithful port of Hairer's code. The Whipple model with or without mild
//! dissipation is not stiff.
//!
//! [`Method::Radau5`]: Radau IIA of order 5 (implicit, L-stable, adaptive,
//! dense output; Hairer's RADAU5 scheme) from `differential-equations` 0.7
//! (without features it depends on no nalgebra at all), for stiff effects:
//! with a tyre relaxation length of a fraction of a millimetre the tyre
//! forces relax at `|v| / sigma` ~ 10^4 1/s, which limits DOP853's step by
//! stability, not accuracy. The Jacobian is by forward differences over the
//! model's state (one evaluation per component); the crate scales the
//! tolerances as RADAU5 does (`rtol -> 0.1 rtol^(2/3)`), and the Newton
//! tolerance is set as in Hairer's code. Its samples come from the
//! collocation polynomial (order 4, DOP853's is 7), so at equal rtol the two
//! methods' samples agree to about 1e-4 of the amplitude; events are located
//! from a step point, not from a sample.
//!
//! Kicks and pulse edges are breakpoints: the integration restarts there, so
//! the error control never steps over a discontinuity.
//!
//! # Layout
//!
//! Here: the options, the result and the error of a run ([`SimOptions`],
//! [`Method`], [`Simulation`], [`SimulateError`]). The steps of a run each
//! have a file: `inputs.rs` (initial conditions, kicks, pulses, events),
//! `rhs.rs` (the right-hand side above), `initial.rs` (the consistent
//! initial state), `integrate.rs` (DOP853 and Radau5 behind one call) and
//! `run.rs` ([`simulate`]: segments, kicks, sampling, event location). What
//! is built on runs: `sensitivity.rs`, `fit.rs`, `trajectory.rs`.

mod inputs;
mod rhs;
pub mod sensitivity;

pub mod fit;
pub mod trajectory;

mod initial;
mod integrate;
mod run;

pub use inputs::{
    Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, StopReason, TorquePulse, MAX_STATE_RATES,
};
pub use rhs::{forward_speed, BicycleCoordinates, Evaluator, StateLayout};

pub(crate) use initial::imposed_speed_parameter;
pub use initial::initial_state;
pub(crate) use integrate::DynSystem;
pub use run::simulate;

use serde::Serialize;
use thiserror::Error;

/// Why a simulation failed.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum SimulateError {
    /// The model lacks a coordinate role the simulation needs.
    #[error(transparent)]
    MissingRole(#[from] crate::model::MissingRole),
    /// Roll and steer must be independent coordinates.
    #[error("the {role} coordinate `{name}` of model `{model}` is not independent")]
    NotIndependent {
        model: &'static str,
        role: &'static str,
        name: &'static str,
    },
    #[error("model `{model}` takes {expected} parameters, {got} given")]
    ParameterCount {
        model: &'static str,
        expected: usize,
        got: usize,
    },
    #[error("model `{model}` needs parameter `{name}`")]
    MissingParameter { model: &'static str, name: &'static str },
    /// An option or input is out of range.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    #[error("non-finite value in {what}")]
    NotFinite { what: String },
    /// Newton did not satisfy the holonomic constraints.
    #[error("holonomic constraints not satisfiable at t = {t} s (residual {residual:.3e} after {iterations} Newton iterations): the wheels cannot both touch the ground here")]
    Constraint { t: f64, residual: f64, iterations: usize },
    /// A matrix of the coordinate partitioning is singular.
    #[error("{what} singular at t = {t} s (column {column}, pivot {pivot:.3e})")]
    Singular {
        t: f64,
        what: &'static str,
        column: usize,
        pivot: f64,
    },
    /// The integrator gave up.
    #[error("integrator failed at t = {t} s: {message}")]
    Integrator { t: f64, message: String },
}

/// The smallest relative tolerance the integrators can meet (Hairer's floor
/// of DOP853, ten units of rounding): below it the rounding of each step
/// exceeds the tolerance, so a smaller request could only be clamped.
pub const MIN_RTOL: f64 = 10.0 * f64::EPSILON;

/// Integration options, with documented defaults.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct SimOptions {
    /// Relative tolerance (default 1e-8).
    pub rtol: f64,
    /// Absolute tolerance (default 1e-10).
    pub atol: f64,
    /// Output sample interval (s, default 0.01); samples come from the
    /// integrator's dense output, the step size is independent of it.
    pub output_interval: f64,
    /// Events that stop the run.
    pub events: Events,
    /// Integration method (default DOP853).
    pub method: Method,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            rtol: 1e-8,
            atol: 1e-10,
            output_interval: 0.01,
            events: Events::default(),
            method: Method::default(),
        }
    }
}

/// Integration method.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub enum Method {
    /// DOP853 (explicit Runge-Kutta 8(5,3), `ode_solvers`): the default, for
    /// models that are not stiff.
    #[default]
    Dop853,
    /// Radau IIA of order 5 (implicit, L-stable, Hairer's RADAU5 scheme;
    /// `differential-equations`), Jacobian by forward differences: for stiff
    /// effects such as very short tyre relaxation lengths.
    Radau5,
}

impl Method {
    /// Every method, by its command-line name.
    pub const ALL: [(&'static str, Method); 2] = [("dop853", Method::Dop853), ("radau5", Method::Radau5)];
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Dop853 => "dop853",
            Method::Radau5 => "radau5",
        }
    }
}

impl std::str::FromStr for Method {
    type Err = SimulateError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(s))
            .map(|(_, m)| *m)
            .ok_or_else(|| {
                SimulateError::InvalidInput(format!(
                    "unknown integration method `{s}` (expected {})",
                    Self::ALL.map(|(n, _)| n).join(" or ")
                ))
            })
    }
}

/// Integrator statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SimStats {
    /// Right-hand-side evaluations (including those of the output samples and
    /// event location).
    pub rhs_evaluations: u64,
    pub accepted_steps: u64,
    pub rejected_steps: u64,
}

/// A simulated run: samples of every coordinate and rate and the diagnostics.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Simulation {
    /// Model name.
    pub model: &'static str,
    /// Coordinate names, in the order of `p` and `dp`.
    pub coordinates: Vec<&'static str>,
    /// What the coordinates mean, as the model declares it: `(role, index)`.
    #[serde(skip)]
    pub roles: &'static [(crate::model::CoordinateRole, usize)],
    /// Parameter vector used.
    pub parameters: Vec<f64>,
    /// Sample times (s). A kick gives two samples at its time: before and after.
    pub t: Vec<f64>,
    /// Coordinates at each sample.
    pub p: Vec<Vec<f64>>,
    /// Rates at each sample.
    pub dp: Vec<Vec<f64>>,
    /// Forward speed of the rear contact point (m/s).
    pub speed: Vec<f64>,
    /// Kinetic energy (J).
    pub kinetic_energy: Vec<f64>,
    /// Potential energy of gravity (J).
    pub potential_energy: Vec<f64>,
    /// Max-norm of the holonomic residuals `Res(p, t)` (m, rad).
    pub constraint_residual: Vec<f64>,
    /// Max-norm of the velocity constraints `D p' - d` (m/s, rad/s).
    pub velocity_residual: Vec<f64>,
    /// Names of the model's extra first-order states (`M::STATES`; empty
    /// for most models).
    pub states: Vec<&'static str>,
    /// Extra states at each sample (e.g. tyre lateral forces, N).
    pub z: Vec<Vec<f64>>,
    pub stop: StopReason,
    pub stats: SimStats,
    pub options: SimOptions,
}

impl Simulation {
    /// Column of a coordinate by name.
    pub fn coordinate(&self, name: &str) -> Option<Vec<f64>> {
        let j = self.coordinates.iter().position(|c| *c == name)?;
        Some(self.p.iter().map(|p| p[j]).collect())
    }
    /// Column of the coordinate with meaning `role` (roll, steer, ...).
    pub fn coordinate_of(&self, role: crate::model::CoordinateRole) -> Option<Vec<f64>> {
        let j = self.roles.iter().find(|(r, _)| *r == role)?.1;
        Some(self.p.iter().map(|p| p[j]).collect())
    }
    /// Rate of the coordinate with meaning `role`.
    pub fn rate_of(&self, role: crate::model::CoordinateRole) -> Option<Vec<f64>> {
        let j = self.roles.iter().find(|(r, _)| *r == role)?.1;
        Some(self.dp.iter().map(|p| p[j]).collect())
    }
    /// [`Simulation::coordinate_of`], or an error naming the role and the job.
    pub fn require_coordinate(
        &self,
        role: crate::model::CoordinateRole,
        job: &'static str,
    ) -> Result<Vec<f64>, crate::model::MissingRole> {
        self.coordinate_of(role).ok_or(crate::model::MissingRole {
            model: self.model,
            kind: "coordinate",
            role: role.describe(),
            job,
        })
    }
    /// Rate of a coordinate by name.
    pub fn rate(&self, name: &str) -> Option<Vec<f64>> {
        let j = self.coordinates.iter().position(|c| *c == name)?;
        Some(self.dp.iter().map(|p| p[j]).collect())
    }
    /// Largest holonomic residual over the run.
    pub fn max_constraint_residual(&self) -> f64 {
        self.constraint_residual.iter().fold(0.0, |m, x| m.max(*x))
    }
    /// Largest velocity-constraint residual over the run.
    pub fn max_velocity_residual(&self) -> f64 {
        self.velocity_residual.iter().fold(0.0, |m, x| m.max(*x))
    }
    /// Largest relative change of the total energy `T + V` over the run,
    /// `max |E(t) - E(0)| / |E(0)|` (after the last kick: kicks inject energy).
    pub fn relative_energy_drift(&self) -> f64 {
        let e: Vec<f64> = self
            .kinetic_energy
            .iter()
            .zip(&self.potential_energy)
            .map(|(k, v)| k + v)
            .collect();
        if e.is_empty() {
            return 0.0;
        }
        // Start after the last duplicated (kick) time.
        let start = (1..self.t.len())
            .rev()
            .find(|&i| self.t[i] == self.t[i - 1])
            .unwrap_or(0);
        let e0 = e[start];
        e[start..].iter().fold(0.0f64, |m, x| m.max((x - e0).abs())) / e0.abs().max(f64::MIN_POSITIVE)
    }

    /// Column of an extra state by name.
    pub fn state(&self, name: &str) -> Option<Vec<f64>> {
        let j = self.states.iter().position(|c| *c == name)?;
        Some(self.z.iter().map(|z| z[j]).collect())
    }
}
