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

mod inputs;
mod rhs;
pub mod sensitivity;

pub mod fit;
pub mod trajectory;

pub use inputs::{
    Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, StopReason, TorquePulse, MAX_STATE_RATES,
};
pub use rhs::{forward_speed, BicycleCoordinates, Evaluator, StateLayout};

use differential_equations::prelude::{
    ControlFlag, ImplicitRungeKutta, Interpolation, Matrix as DeMatrix, Solout, Solution, IVP, ODE,
};
use ode_solvers::{DVector, Dop853, OutputType, System};
use serde::Serialize;
use thiserror::Error;

use crate::model::MultibodyModel;

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

/// The explicit integrator's view of a system: its right-hand side and its
/// stop test behind references to closures, so that DOP853 is compiled once
/// for every model and scalar type (a `System` generic over the model
/// would be a copy of the whole solver per model, most of the library's
/// compile time for nothing: one indirect call per right-hand side is
/// nothing beside the model's evaluation).
pub(crate) struct DynSystem<'f> {
    /// `dy = f(y)`; the time is the state's clock component.
    pub(crate) f: &'f dyn Fn(&[f64], &mut [f64]),
    /// Ends the integration after the step that produced `y`.
    pub(crate) stop: &'f dyn Fn(&[f64]) -> bool,
}

impl System<f64, DVector<f64>> for DynSystem<'_> {
    fn system(&self, _x: f64, y: &DVector<f64>, dy: &mut DVector<f64>) {
        (self.f)(y.as_slice(), dy.as_mut_slice())
    }
    fn solout(&mut self, _t: f64, y: &DVector<f64>, _dy: &DVector<f64>) -> bool {
        (self.stop)(y.as_slice())
    }
}

/// The implicit integrator's view of the model. `differential-equations`
/// 0.7.0's Radau5 starts its Newton iteration from `Y::zeros()`, which is
/// empty for `Vec<f64>`, so the state is a fixed-size array: the model's `n`
/// components, padded with components whose rate is zero.
struct Padded<'f> {
    n: usize,
    f: &'f dyn Fn(&[f64], &mut [f64]),
}

impl<const N: usize> ODE<f64, [f64; N]> for Padded<'_> {
    fn diff(&self, _t: f64, y: &[f64; N], dy: &mut [f64; N]) {
        dy.fill(0.0);
        (self.f)(&y[..self.n], &mut dy[..self.n]);
    }
    /// Forward differences over the model's components only (the padding is
    /// constant).
    fn jacobian(&self, t: f64, y: &[f64; N], j: &mut DeMatrix<f64>) {
        let n = self.n;
        for r in 0..j.nrows() {
            for c in 0..j.ncols() {
                j[(r, c)] = 0.0;
            }
        }
        let (mut f0, mut f1) = ([0.0; N], [0.0; N]);
        self.diff(t, y, &mut f0);
        let mut yp = *y;
        for c in 0..n {
            let h = f64::EPSILON.sqrt() * y[c].abs().max(1.0);
            yp[c] = y[c] + h;
            self.diff(t, &yp, &mut f1);
            yp[c] = y[c];
            for r in 0..n {
                j[(r, c)] = (f1[r] - f0[r]) / h;
            }
        }
    }
}

/// Output of the implicit integrator: dense samples at `times`, and a stop
/// at the end of the first step where `stop` holds (that end point is pushed
/// too, so that an event is seen and located).
struct Sampler<'f> {
    stop: &'f dyn Fn(&[f64]) -> bool,
    times: Vec<f64>,
    next: usize,
    /// Start `(t, y)` of the step at whose end `stop` held: a step point, as
    /// accurate as the integration (the samples inside a step come from
    /// Radau5's collocation polynomial, of order 4 only).
    stopped_from: &'f std::cell::RefCell<Option<(f64, Vec<f64>)>>,
}

impl<const N: usize> Solout<f64, [f64; N]> for Sampler<'_> {
    fn solout<I>(
        &mut self,
        t_curr: f64,
        t_prev: f64,
        y_curr: &[f64; N],
        y_prev: &[f64; N],
        interpolator: &mut I,
        solution: &mut Solution<f64, [f64; N]>,
    ) -> ControlFlag<f64, [f64; N]>
    where
        I: Interpolation<f64, [f64; N]> + ?Sized,
    {
        // The last step ends at the segment end up to rounding.
        let tol = 1e-12 * t_curr.abs().max(1.0);
        while let Some(&t) = self.times.get(self.next) {
            if t > t_curr + tol {
                break;
            }
            let y = if (t - t_curr).abs() <= tol {
                *y_curr
            } else {
                match interpolator.interpolate(t) {
                    Ok(y) => y,
                    Err(_) => break,
                }
            };
            solution.push(t, y);
            self.next += 1;
        }
        if (self.stop)(y_curr) {
            *self.stopped_from.borrow_mut() = Some((t_prev, y_prev.to_vec()));
            if solution.t.last().is_none_or(|&t| t < t_curr) {
                solution.push(t_curr, *y_curr);
            }
            return ControlFlag::Terminate;
        }
        ControlFlag::Continue
    }
}

/// Samples `(t, y)` of a Radau5 run, its accepted and rejected steps, and
/// the start of the step where it stopped early.
type RadauRun = (Vec<f64>, Vec<Vec<f64>>, usize, usize, Option<(f64, Vec<f64>)>);

/// Radau5 on the state padded to `N` components, sampled at `times` (the
/// last one the end) and stopped by `stop` (for [`integrate`]).
fn radau_padded<const N: usize>(
    f: &dyn Fn(&[f64], &mut [f64]),
    stop: &dyn Fn(&[f64]) -> bool,
    opts: &SimOptions,
    t0: f64,
    y0: &[f64],
    times: Vec<f64>,
) -> Result<RadauRun, (f64, String)> {
    let n = y0.len();
    let t1 = *times.last().expect("at least one sample time");
    let mut y = [0.0; N];
    y[..n].copy_from_slice(y0);
    let sys = Padded { n, f };
    // Hairer's RADAU5 Newton stopping tolerance for the scaled rtol; the
    // crate's fixed default (3.2e-3) ignores rtol and stops the Newton
    // iteration too early for tight tolerances.
    let scaled_rtol = 0.1 * opts.rtol.powf(2.0 / 3.0);
    let newton_tol = (10.0 * f64::EPSILON / scaled_rtol).max(0.03f64.min(scaled_rtol.sqrt()));
    let method = ImplicitRungeKutta::radau5()
        .rtol(opts.rtol)
        .atol(opts.atol)
        .newton_tol(newton_tol)
        .max_steps(10_000_000);
    let stopped_from = std::cell::RefCell::new(None);
    let sampler = Sampler {
        stop,
        times,
        next: 0,
        stopped_from: &stopped_from,
    };
    let sol = IVP::ode(&sys, t0, t1, y)
        .method(method)
        .solout(sampler)
        .solve()
        .map_err(|e| {
            use differential_equations::error::Error as E;
            // The crate's error carries the state; say what happened.
            match e {
                E::MaxSteps { t, .. } => (t, "Radau5: maximum number of steps reached".to_string()),
                E::StepSize { t, .. } => (t, "Radau5: step size too small".to_string()),
                E::Stiffness { t, .. } => (t, "Radau5: stiffness detected".to_string()),
                E::LinearAlgebra { t, msg, .. } => (t, format!("Radau5: {msg}")),
                E::BadInput { msg } => (t0, format!("Radau5: {msg}")),
                other => (t0, format!("Radau5: {other:?}")),
            }
        })?;
    let ys = sol.y.iter().map(|y| y[..n].to_vec()).collect();
    let from = stopped_from.into_inner().map(|(t, y)| (t, y[..n].to_vec()));
    Ok((sol.t, ys, sol.steps.accepted, sol.steps.rejected, from))
}

/// Smallest event margin (`limit - |angle|`, rad) and which event it is
/// (0 roll, 1 steer).
fn event_value<M: MultibodyModel>(eval: &Evaluator<'_, M>, ev: &Events, y: &[f64]) -> (f64, usize) {
    let c = &eval.coords;
    let mut g = (f64::INFINITY, 0);
    if let Some(l) = ev.roll_limit {
        g = (l - y[c.roll_ind].abs(), 0);
    }
    if let Some(l) = ev.steer_limit {
        let s = l - y[c.steer_ind].abs();
        if s < g.0 {
            g = (s, 1);
        }
    }
    g
}

/// No event: integration to a given time (event location, the end of a
/// segment whose samples stopped short).
const NO_EVENTS: Events = Events {
    roll_limit: None,
    steer_limit: None,
};

/// What [`integrate`] returns.
#[derive(Clone, Copy, Debug)]
enum Sampling {
    /// Dense output at `t0 + k (t1 - t0) / n`, `k = 0..=n` (the start
    /// included, the last exactly `t1`), stopping after the first step at
    /// whose end an event of `events` fires.
    Grid { n: usize, events: Events },
    /// The state at `t1` alone, from the last step point (no dense output,
    /// no events).
    End,
}

/// Samples of [`integrate`]: times (s), states and, after an early stop of
/// Radau5, the start `(t, y)` of its last step (a step point, more accurate
/// than its samples, to locate the event from).
struct Samples {
    t: Vec<f64>,
    y: Vec<Vec<f64>>,
    stopped_from: Option<(f64, Vec<f64>)>,
}

/// Integrate from `(t0, y0)` to `t1 > t0` with `opts.method`, sampled as
/// `sampling` says: the one place where DOP853 and Radau5 are run. Counts the
/// steps into `stats`; an error of the model's evaluation takes precedence
/// over the integrator's own.
fn integrate<M: MultibodyModel>(
    eval: &Evaluator<'_, M>,
    opts: &SimOptions,
    t0: f64,
    y0: &[f64],
    t1: f64,
    sampling: Sampling,
    stats: &mut SimStats,
) -> Result<Samples, SimulateError> {
    let (grid, events) = match sampling {
        Sampling::Grid { n, events } => (Some(n), events),
        Sampling::End => (None, NO_EVENTS),
    };
    let dx = |n: usize| (t1 - t0) / n as f64;
    // Time is the state's clock component (see `StateLayout`); the first
    // error of the model's evaluation is kept and the integration driven to
    // an end with NaN rates.
    let f = |y: &[f64], dy: &mut [f64]| {
        if eval.error.borrow().is_some() {
            dy.fill(f64::NAN);
            return;
        }
        if let Err(e) = eval.derivative(y[eval.layout.time()], y, dy) {
            *eval.error.borrow_mut() = Some(e);
            dy.fill(f64::NAN);
        }
    };
    let stop = |y: &[f64]| eval.error.borrow().is_some() || event_value(eval, &events, y).0 <= 0.0;
    let samples = match opts.method {
        Method::Dop853 => {
            let (x_end, dx, output) = match grid {
                // Integrate slightly past the segment end: ode_solvers 0.6.2
                // pushes an *extrapolated* dense sample at `x_end` whenever its
                // next grid time is within 1e-9 of `x_end`, even from a step
                // that ends before it. With the end off the grid the sample at
                // `t1` is interpolated from the step that contains it.
                Some(n) => (t1 + (1e-6f64).min(0.01 * dx(n)).max(1e-8), dx(n), OutputType::Dense),
                None => (t1, t1 - t0, OutputType::Sparse),
            };
            let mut s = Dop853::new(
                DynSystem { f: &f, stop: &stop },
                t0,
                x_end,
                dx,
                DVector::from_column_slice(y0),
                opts.rtol,
                opts.atol,
            );
            s.set_output(output);
            let r = s.integrate();
            if let Some(e) = eval.error.borrow_mut().take() {
                return Err(e);
            }
            let st = r.map_err(|e| SimulateError::Integrator {
                t: t0,
                message: format!("DOP853: {e} (for stiff effects use the Radau5 method, --method radau5)"),
            })?;
            stats.accepted_steps += st.accepted_steps as u64;
            stats.rejected_steps += st.rejected_steps as u64;
            let mut t = s.x_out().clone();
            if grid.is_some() {
                if let Some(last) = t.last_mut() {
                    if (*last - t1).abs() <= 1e-9 * t1.abs().max(1.0) {
                        *last = t1;
                    }
                }
            }
            // Without a grid only the end point is wanted (not every step's).
            let from = if grid.is_some() { 0 } else { t.len().saturating_sub(1) };
            let y = s.y_out()[from..].iter().map(|v| v.as_slice().to_vec()).collect();
            Samples {
                t: t.split_off(from),
                y,
                stopped_from: None,
            }
        }
        Method::Radau5 => {
            let times: Vec<f64> = match grid {
                Some(n) => (1..=n)
                    .map(|k| if k == n { t1 } else { t0 + k as f64 * dx(n) })
                    .collect(),
                None => vec![t1],
            };
            // A few padded sizes (each is a monomorphisation of the solver).
            let r = match y0.len() {
                0..=12 => radau_padded::<12>(&f, &stop, opts, t0, y0, times),
                13..=16 => radau_padded::<16>(&f, &stop, opts, t0, y0, times),
                17..=32 => radau_padded::<32>(&f, &stop, opts, t0, y0, times),
                n => {
                    return Err(SimulateError::InvalidInput(format!(
                        "Radau5 supports states of up to 32 components, model `{}` has {n}",
                        M::NAME
                    )))
                }
            };
            if let Some(e) = eval.error.borrow_mut().take() {
                return Err(e);
            }
            let (mut t, mut y, accepted, rejected, stopped_from) =
                r.map_err(|(t, message)| SimulateError::Integrator { t, message })?;
            stats.accepted_steps += accepted as u64;
            stats.rejected_steps += rejected as u64;
            if grid.is_some() {
                t.insert(0, t0);
                y.insert(0, y0.to_vec());
            }
            Samples { t, y, stopped_from }
        }
    };
    if samples.y.is_empty() {
        return Err(SimulateError::Integrator {
            t: t0,
            message: format!(
                "{} returned no end point",
                if opts.method == Method::Radau5 {
                    "Radau5"
                } else {
                    "DOP853"
                }
            ),
        });
    }
    Ok(samples)
}

/// Integrate from `(t0, y0)` to `t1` and return the final state ([`integrate`]
/// without samples or events).
fn integrate_to<M: MultibodyModel>(
    eval: &Evaluator<'_, M>,
    t0: f64,
    y0: &[f64],
    t1: f64,
    opts: &SimOptions,
    stats: &mut SimStats,
) -> Result<Vec<f64>, SimulateError> {
    if t1 <= t0 {
        return Ok(y0.to_vec());
    }
    let samples = integrate(eval, opts, t0, y0, t1, Sampling::End, stats)?;
    Ok(samples.y.into_iter().last().expect("integrate checks the end point"))
}

/// The parameter that imposes the forward speed in a driven model (whose
/// independent coordinates are roll and steer alone); the initial
/// conditions' speed sets it.
pub(crate) fn imposed_speed_parameter<M: MultibodyModel>() -> Option<usize> {
    M::FORWARD_SPEED_PARAMETER.filter(|_| M::INDEPENDENT.len() == 2)
}

/// The state vector for given initial conditions (consistent with all
/// constraints), and the parameter vector with the speed set for a driven
/// model.
pub fn initial_state<M: MultibodyModel>(
    param: &[f64],
    ic: &InitialConditions,
) -> Result<(Vec<f64>, Vec<f64>), SimulateError> {
    for (name, x) in [
        ("roll", ic.roll),
        ("steer", ic.steer),
        ("roll rate", ic.roll_rate),
        ("steer rate", ic.steer_rate),
        ("speed", ic.speed),
        ("yaw", ic.yaw),
    ] {
        if !x.is_finite() {
            return Err(SimulateError::NotFinite {
                what: format!("initial {name}"),
            });
        }
    }
    if ic.state_rates.iter().any(|r| !r.is_finite()) {
        return Err(SimulateError::NotFinite {
            what: "initial rate of an extra state".into(),
        });
    }
    // A rate for a state the model does not have would be dropped.
    if ic.state_rates.iter().skip(M::STATES.len()).any(|r| *r != 0.0) {
        return Err(SimulateError::InvalidInput(format!(
            "initial rates {:?} of extra states, but model `{}` has {} ({:?})",
            ic.state_rates,
            M::NAME,
            M::STATES.len(),
            M::STATES
        )));
    }
    let mut param = rhs::with_state_tail::<M>(param)?;
    if let Some(k) = imposed_speed_parameter::<M>() {
        if k < param.len() {
            param[k] = ic.speed;
        }
    }
    let inputs = Inputs::default();
    let eval = Evaluator::<M>::new(&param, &inputs)?;
    let l = &eval.layout;
    let c = eval.coords;
    let mut y = vec![0.0; l.len()];
    for (k, &j) in l.independent.iter().enumerate() {
        y[k] = M::INITIAL_GUESS[j];
    }
    for (k, &j) in l.ignorable.iter().enumerate() {
        y[l.ignorables() + k] = M::INITIAL_GUESS[j];
    }
    y[l.time()] = 0.0;
    y[c.roll_ind] = ic.roll;
    y[c.steer_ind] = ic.steer;
    y[l.rates() + c.roll_ind] = ic.roll_rate;
    y[l.rates() + c.steer_ind] = ic.steer_rate;
    // Yaw is ignorable with rolling constraints, independent with tyre slip.
    if let Some(k) = l.ignorable.iter().position(|&j| j == c.yaw) {
        y[l.ignorables() + k] = ic.yaw;
    } else if let Some(k) = l.independent.iter().position(|&j| j == c.yaw) {
        y[k] = ic.yaw;
    }
    let np = M::PARAMETERS.len();
    y[l.extras()..].copy_from_slice(&param[np..]);
    // The independent rates besides roll and steer: the rate that carries
    // the forward speed (the rear wheel's, in a free-speed model) and, with
    // tyre slip, the lateral ones (yc, phi). They solve `speed = ic.speed`
    // and `z' = ic.state_rates` (by default zero: the extra states at rest;
    // upright, that is rolling without lateral slip), one equation per
    // extra state. A coordinate the rolling bicycle lacks (no declared
    // role: a rider's lean) starts at rest relative to the frame, as roll
    // and steer start where they are given.
    let added = crate::model::added_coordinates(&l.independent, M::COORDINATE_ROLES);
    let others: Vec<usize> = (0..l.ni())
        .filter(|&k| k != c.roll_ind && k != c.steer_ind && !added.contains(&k))
        .collect();
    if !others.is_empty() {
        if others.len() != 1 + l.extra {
            return Err(SimulateError::InvalidInput(format!(
                "model `{}` has {} independent coordinates besides roll and steer and {} extra states (expected one more coordinate than states)",
                M::NAME,
                others.len(),
                l.extra
            )));
        }
        let mut rates = ic.state_rates.to_vec();
        rates.resize(l.extra, 0.0);
        solve_free_rates(&eval, &mut y, &others, ic.speed, &rates)?;
    }
    // Check that the configuration exists.
    eval.full_state(0.0, &y)?;
    Ok((y, param))
}

/// Set the rates `y[rates + k]`, `k` in `others`, so that the forward speed
/// is `speed` and the extra states change at `state_rates`: Newton's method
/// with a finite-difference Jacobian (the conditions are affine in the rates
/// except through the regularised contact speeds of effects like tyre slip).
fn solve_free_rates<M: MultibodyModel>(
    eval: &Evaluator<'_, M>,
    y: &mut [f64],
    others: &[usize],
    speed: f64,
    state_rates: &[f64],
) -> Result<(), SimulateError> {
    let l = eval.layout.clone();
    let m = others.len();
    let mut dy = vec![0.0; l.len()];
    let mut residual = |y: &[f64]| -> Result<Vec<f64>, SimulateError> {
        let (p, dp) = eval.full_state(0.0, y)?;
        let mut r = vec![forward_speed(&eval.coords, &p, &dp) - speed];
        if l.extra > 0 {
            eval.derivative(0.0, y, &mut dy)?;
            r.extend(dy[l.extras()..].iter().zip(state_rates).map(|(a, b)| a - b));
        }
        Ok(r)
    };
    for _ in 0..20 {
        let r0 = residual(y)?;
        if r0.iter().all(|x| *x == 0.0) {
            return Ok(());
        }
        let mut jac = nalgebra::DMatrix::<f64>::zeros(m, m);
        for (col, &k) in others.iter().enumerate() {
            let i = l.rates() + k;
            let h = 1e-6 * y[i].abs().max(1.0);
            let keep = y[i];
            y[i] = keep + h;
            let r1 = residual(y)?;
            y[i] = keep;
            for row in 0..m {
                jac[(row, col)] = (r1[row] - r0[row]) / h;
            }
        }
        let step = jac.lu().solve(&nalgebra::DVector::from_vec(r0)).ok_or_else(|| {
            SimulateError::InvalidInput(
                "the free independent rates do not set the forward speed and the extra states' rates".into(),
            )
        })?;
        let mut small = true;
        for (col, &k) in others.iter().enumerate() {
            let i = l.rates() + k;
            small &= step[col].abs() <= 1e-12 * y[i].abs().max(1.0);
            y[i] -= step[col];
        }
        // Stop once the update is at rounding level (the conditions are
        // affine or nearly so: two or three iterations).
        if small {
            return Ok(());
        }
    }
    let r = residual(y)?;
    Err(SimulateError::InvalidInput(format!(
        "no initial rates give forward speed {speed} m/s with the extra states changing at {state_rates:?} (residual {r:?})"
    )))
}

/// Simulate model `M` with parameters `param` from `ic` for `duration`
/// seconds with the perturbations `inputs`.
///
/// A relative tolerance below [`MIN_RTOL`] is refused rather than clamped:
/// the run would not be as accurate as asked.
pub fn simulate<M: MultibodyModel>(
    param: &[f64],
    ic: &InitialConditions,
    inputs: &Inputs,
    duration: f64,
    opts: &SimOptions,
) -> Result<Simulation, SimulateError> {
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(SimulateError::InvalidInput(format!(
            "duration must be positive, got {duration}"
        )));
    }
    if !(opts.rtol >= MIN_RTOL && opts.rtol < 1.0 && opts.atol > 0.0 && opts.atol.is_finite()) {
        return Err(SimulateError::InvalidInput(format!(
            "tolerances out of range (rtol {} in [{MIN_RTOL:.1e}, 1), atol {} positive and finite)",
            opts.rtol, opts.atol
        )));
    }
    if !(opts.output_interval > 0.0 && opts.output_interval.is_finite()) {
        return Err(SimulateError::InvalidInput("output interval must be positive".into()));
    }
    if duration / opts.output_interval > 1e7 {
        return Err(SimulateError::InvalidInput(
            "more than 10^7 output samples: increase the output interval".into(),
        ));
    }
    for p in &inputs.pulses {
        if !(p.duration > 0.0 && p.duration.is_finite() && p.start.is_finite() && p.amplitude.is_finite()) {
            return Err(SimulateError::InvalidInput(format!("bad torque pulse {p:?}")));
        }
    }
    for k in &inputs.kicks {
        if !(k.time.is_finite() && k.impulse.is_finite() && k.ahead.is_finite() && k.height.is_finite()) {
            return Err(SimulateError::InvalidInput(format!("bad kick {k:?}")));
        }
        if !(k.time >= 0.0 && k.time < duration) {
            return Err(SimulateError::InvalidInput(format!(
                "kick at t = {} s is outside the run [0, {}) s",
                crate::number_text::format_significant(k.time, 10),
                crate::number_text::format_significant(duration, 10)
            )));
        }
    }
    let (mut y, param) = initial_state::<M>(param, ic)?;
    let eval = Evaluator::<M>::new(&param, inputs)?;
    if event_value(&eval, &opts.events, &y).0 <= 0.0 {
        return Err(SimulateError::InvalidInput(format!(
            "the initial roll {:.4} rad or steer {:.4} rad is already at its limit ({:?})",
            ic.roll, ic.steer, opts.events
        )));
    }
    let rt = rhs::rolling_radius::<M>(&param, &eval.coords)?;
    // Kick points in rear-frame axes, from the upright reference pitch.
    let (p_up, _) = {
        let mut yu = y.clone();
        let c = &eval.coords;
        yu[c.roll_ind] = 0.0;
        yu[c.steer_ind] = 0.0;
        eval.full_state(0.0, &yu)?
    };
    let beta0 = p_up[eval.coords.pitch];
    let kick_point = |k: &Kick| {
        // roll-frame vector from the rear wheel centre, rotated into frame axes (A_beta^T).
        let (sb, cb) = beta0.sin_cos();
        let (a, h) = (k.ahead, k.height - rt);
        [cb * a - sb * h, 0.0, sb * a + cb * h]
    };

    let mut sim = Simulation {
        model: M::NAME,
        coordinates: M::COORDINATES.to_vec(),
        roles: M::COORDINATE_ROLES,
        parameters: param.clone(),
        t: vec![],
        p: vec![],
        dp: vec![],
        speed: vec![],
        kinetic_energy: vec![],
        potential_energy: vec![],
        constraint_residual: vec![],
        velocity_residual: vec![],
        states: M::STATES.to_vec(),
        z: vec![],
        stop: StopReason::Completed,
        stats: SimStats::default(),
        options: *opts,
    };
    let push = |sim: &mut Simulation, t: f64, y: &[f64]| -> Result<(), SimulateError> {
        let (p, dp) = eval.full_state(t, y)?;
        let (r, v) = eval.residuals(t, &p, &dp);
        sim.t.push(t);
        sim.speed.push(forward_speed(&eval.coords, &p, &dp));
        sim.kinetic_energy.push(M::kinetic_energy(&param, &p, &dp));
        sim.potential_energy.push(M::potential_energy(&param, &p));
        sim.constraint_residual.push(r);
        sim.velocity_residual.push(v);
        sim.z.push(y[eval.layout.extras()..].to_vec());
        sim.p.push(p);
        sim.dp.push(dp);
        Ok(())
    };

    let mut cuts: Vec<f64> = inputs
        .breakpoints()
        .into_iter()
        .filter(|&b| b > 0.0 && b < duration)
        .collect();
    cuts.push(duration);
    let mut t0 = 0.0;
    let mut first = true;
    'segments: for &t1 in &cuts {
        // Kicks at the segment start (those at or before 0 act at 0). The
        // sample before a kick is the previous segment's last (or, at 0,
        // pushed here); the kicked state starts the segment.
        let kicks: Vec<&Kick> = inputs
            .kicks
            .iter()
            .filter(|k| k.time == t0 || (first && k.time <= 0.0))
            .collect();
        let kicked = !kicks.is_empty();
        if kicked && first {
            push(&mut sim, t0, &y)?;
        }
        for k in kicks {
            let (p, _) = eval.full_state(t0, &y)?;
            let qhat = eval.lateral_impulse(&p, kick_point(k), k.impulse, rt);
            eval.apply_impulse(t0, &mut y, &qhat)?;
        }
        let n = ((t1 - t0) / opts.output_interval - 1e-9).ceil().max(1.0) as usize;
        eval.segment.set((t0, t1));
        let sampling = Sampling::Grid { n, events: opts.events };
        let Samples {
            t: ts,
            y: ys,
            mut stopped_from,
        } = integrate(&eval, opts, t0, &y, t1, sampling, &mut sim.stats)?;
        // The first sample is the segment start: skip it unless this is the
        // first segment or a kick changed the state.
        let skip = if first || kicked { 0 } else { 1 };
        let mut prev: Option<(f64, Vec<f64>)> = None;
        for (t, yv) in ts.iter().zip(ys.iter()).skip(skip) {
            let yv = yv.as_slice();
            let (g, which) = event_value(&eval, &opts.events, yv);
            if g <= 0.0 {
                // Locate the crossing between the previous sample and this one.
                // From the previous sample, or from the start of Radau5's
                // last step, which is more accurate than its samples.
                let (ta, ya) = match stopped_from.take() {
                    Some((t_step, y_step)) if t_step < *t => (t_step, y_step),
                    _ => prev.clone().unwrap_or((t0, y.clone())),
                };
                let (te, ye) = locate_event(&eval, opts, ta, &ya, *t, &mut sim.stats)?;
                if te > ta {
                    push(&mut sim, te, &ye)?;
                }
                let c = &eval.coords;
                sim.stop = if which == 0 {
                    StopReason::Fell {
                        time: te,
                        roll: ye[c.roll_ind],
                    }
                } else {
                    StopReason::SteerStop {
                        time: te,
                        steer: ye[c.steer_ind],
                    }
                };
                break 'segments;
            }
            push(&mut sim, *t, yv)?;
            prev = Some((*t, yv.to_vec()));
        }
        let last_t = *ts.last().expect("dense output has the start point");
        if (last_t - t1).abs() > 1e-9 * t1.abs().max(1.0) {
            // The dense output stopped short of the segment end (the step
            // cap or an early stop); finish without output.
            let ya = ys.last().expect("non-empty").clone();
            y = integrate_to(&eval, last_t, &ya, t1, opts, &mut sim.stats)?;
        } else {
            y = ys.last().expect("non-empty").clone();
        }
        t0 = t1;
        first = false;
    }
    sim.stats.rhs_evaluations = eval.evaluations.get();
    Ok(sim)
}

/// Find the event time in `(ta, tb)` (margin positive at `ta`, not at `tb`)
/// by the Illinois variant of regula falsi, re-integrating from `ta`.
fn locate_event<M: MultibodyModel>(
    eval: &Evaluator<'_, M>,
    opts: &SimOptions,
    ta: f64,
    ya: &[f64],
    tb: f64,
    stats: &mut SimStats,
) -> Result<(f64, Vec<f64>), SimulateError> {
    let g = |y: &[f64]| event_value(eval, &opts.events, y).0;
    let (mut a, mut ga) = (ta, g(ya));
    let yb = integrate_to(eval, ta, ya, tb, opts, stats)?;
    let (mut b, mut gb) = (tb, g(&yb));
    if ga <= 0.0 {
        return Ok((ta, ya.to_vec()));
    }
    let mut best = (tb, yb, gb.abs());
    let mut side = 0;
    for _ in 0..60 {
        if (b - a) < 1e-10 {
            break;
        }
        let tm = (a * gb - b * ga) / (gb - ga);
        let tm = if tm.is_finite() && tm > a && tm < b {
            tm
        } else {
            0.5 * (a + b)
        };
        let ym = integrate_to(eval, ta, ya, tm, opts, stats)?;
        let gm = g(&ym);
        let done = gm.abs() < 1e-12;
        if gm.abs() < best.2 {
            best = (tm, ym, gm.abs());
        }
        if gm <= 0.0 {
            b = tm;
            gb = gm;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            a = tm;
            ga = gm;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
        if done {
            break;
        }
    }
    Ok((best.0, best.1))
}
