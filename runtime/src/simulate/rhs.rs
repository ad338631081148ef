//! The right-hand side of the reduced equations for the integrator: state
//! layout, dependent coordinates and velocities, accelerations.

use std::cell::{Cell, RefCell};

use crate::constraints::dependent_velocities;
use crate::linalg::{lu_factor, lu_solve};
use crate::model::MultibodyModel;
use crate::scalar::{Dual, Scalar};

use super::inputs::Inputs;
use super::SimulateError;

/// Where each quantity lives in the integrator's state vector `y`.
///
/// `y = [q (ni) | q' (ni) | ignorable coordinates (ng) | time | extra
/// first-order states (ne)]`: `q` are the model's independent coordinates
/// (`M::INDEPENDENT`, in order), the ignorable ones are all coordinates that
/// are neither independent nor dependent (`xc yc phi eps` for the thesis
/// models). Time is a state (`dt/dt = 1`): the system is autonomous for the
/// integrator, because ode_solvers 0.6.2's DOP853 evaluates its 12th stage
/// at `x` instead of `x + h` (its `c12` is 0, Hairer's is 1), which is
/// harmless only for autonomous systems. Extra first-order states `z`
/// (`M::STATES`, e.g. lagged tyre forces) are appended at the end; the
/// generated code reads them from the tail of the parameter vector, which
/// [`Evaluator`] refreshes from `y` at every evaluation.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StateLayout {
    /// Indices of the independent coordinates.
    pub independent: Vec<usize>,
    /// Indices of the ignorable coordinates (integrated from their rates).
    pub ignorable: Vec<usize>,
    /// Number of extra first-order states (`M::STATES.len()`).
    pub extra: usize,
}

impl StateLayout {
    /// The layout of model `M`.
    pub fn of<M: MultibodyModel>() -> Self {
        let ignorable = (0..M::nq())
            .filter(|j| !M::INDEPENDENT.contains(j) && !M::DEPENDENT.contains(j))
            .collect();
        StateLayout {
            independent: M::INDEPENDENT.to_vec(),
            ignorable,
            extra: M::STATES.len(),
        }
    }
    /// Number of independent coordinates.
    pub fn ni(&self) -> usize {
        self.independent.len()
    }
    /// Length of the state vector.
    pub fn len(&self) -> usize {
        2 * self.ni() + self.ignorable.len() + 1 + self.extra
    }
    /// Index of time.
    pub fn time(&self) -> usize {
        2 * self.ni() + self.ignorable.len()
    }
    /// Whether the state is empty (never, for a valid model).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Offset of the independent velocities.
    pub fn rates(&self) -> usize {
        self.ni()
    }
    /// Offset of the ignorable coordinates.
    pub fn ignorables(&self) -> usize {
        2 * self.ni()
    }
    /// Offset of the extra first-order states.
    pub fn extras(&self) -> usize {
        self.time() + 1
    }
}

/// Indices of the coordinates the simulation needs by role. All registered
/// bicycle models declare these roles (the thesis's coordinates, section 3.2).
#[derive(Clone, Copy, Debug)]
pub struct BicycleCoordinates {
    pub xc: usize,
    pub yc: usize,
    pub yaw: usize,
    pub roll: usize,
    pub pitch: usize,
    pub steer: usize,
    pub rear_wheel: usize,
    /// Positions of roll and steer within the independent coordinates.
    pub roll_ind: usize,
    pub steer_ind: usize,
}

impl BicycleCoordinates {
    /// The coordinates of model `M` by their declared roles.
    pub fn of<M: MultibodyModel>() -> Result<Self, SimulateError> {
        use crate::model::CoordinateRole as R;
        let find = |role| M::require_coordinate(role, "the nonlinear simulation");
        let roll = find(R::Roll)?;
        let steer = find(R::Steer)?;
        let ind = |j: usize, role: R| {
            M::INDEPENDENT
                .iter()
                .position(|&k| k == j)
                .ok_or(SimulateError::NotIndependent {
                    model: M::NAME,
                    role: role.describe(),
                    name: M::COORDINATES[j],
                })
        };
        Ok(BicycleCoordinates {
            xc: find(R::RearContactX)?,
            yc: find(R::RearContactY)?,
            yaw: find(R::Yaw)?,
            roll,
            pitch: find(R::Pitch)?,
            steer,
            rear_wheel: find(R::RearWheelRotation)?,
            roll_ind: ind(roll, R::Roll)?,
            steer_ind: ind(steer, R::Steer)?,
        })
    }
}

/// Forward speed of the rear contact point, `xc' cos(phi) + yc' sin(phi)`.
pub fn forward_speed<T: Scalar>(c: &BicycleCoordinates, p: &[T], dp: &[T]) -> T {
    let (s, co) = p[c.yaw].sin_cos();
    dp[c.xc] * co + dp[c.yc] * s
}

/// The rear wheel's rolling radius from the model's kinematics: forward
/// speed per unit rear-wheel spin rate in upright running (no parameter is
/// looked up by name).
pub fn rolling_radius<M: MultibodyModel>(param: &[f64], c: &BicycleCoordinates) -> Result<f64, SimulateError> {
    use crate::constraints::{solve_configuration, solve_velocities, NewtonOptions};
    let nq = M::nq();
    let mut param = param.to_vec();
    let mut p = vec![0.0; nq];
    M::upright_configuration(&param, M::INITIAL_GUESS, &mut p);
    p[c.roll] = 0.0;
    p[c.steer] = 0.0;
    let err =
        |e: crate::constraints::ConstraintError| SimulateError::InvalidInput(format!("upright configuration: {e}"));
    solve_configuration::<M, f64>(&param, 0.0, &mut p, &NewtonOptions::default()).map_err(err)?;
    let mut dp = vec![0.0; nq];
    let r = if let Some(k) = M::FORWARD_SPEED_PARAMETER {
        param[k] = 1.0;
        solve_velocities::<M, f64>(&param, 0.0, &p, &mut dp).map_err(err)?;
        1.0 / dp[c.rear_wheel]
    } else {
        dp[c.rear_wheel] = 1.0;
        solve_velocities::<M, f64>(&param, 0.0, &p, &mut dp).map_err(err)?;
        M::forward_speed(&param, &p, &dp)
    };
    if r.is_finite() && r > 0.0 {
        Ok(r)
    } else {
        Err(SimulateError::InvalidInput(format!(
            "model `{}`: no positive rolling radius from its kinematics ({r})",
            M::NAME
        )))
    }
}

/// Buffers of one evaluation (no allocation in the right-hand side).
#[derive(Clone, Debug)]
pub(crate) struct Workspace<T: Scalar = f64> {
    /// Full coordinates (dependent ones warm-start the next Newton solve).
    pub p: Vec<T>,
    /// Full velocities.
    pub dp: Vec<T>,
    /// Independent accelerations.
    pub ddq: Vec<T>,
    /// Max-norm of the holonomic residuals after the Newton solve.
    pub residual: f64,
    /// Newton iterations of the last solve.
    pub newton_iterations: usize,
    /// Coordinates and time of the previous evaluation (for the predictor).
    p_prev: Vec<T>,
    t_prev: f64,
    have_prev: bool,
    res: Vec<T>,
    step: Vec<T>,
    cq: Vec<T>,
    jac: Vec<T>,
    piv: Vec<usize>,
    d: Vec<T>,
    ct: Vec<T>,
    ddep: Vec<T>,
    x: Vec<T>,
    gamma: Vec<T>,
    e: Vec<T>,
    f: Vec<T>,
    mass: Vec<T>,
    qv: Vec<T>,
    qg: Vec<T>,
    qe: Vec<T>,
    qtot: Vec<T>,
    me: Vec<T>,
    mi: Vec<T>,
    depv: Vec<usize>,
    /// Output of `all_quantities` and the offsets of the quantities used.
    all: Vec<T>,
    off: AllOffsets,
}

/// Offsets into [`MultibodyModel::all_quantities`]'s output.
#[derive(Clone, Copy, Debug)]
struct AllOffsets {
    mass: usize,
    qv: usize,
    qg: usize,
    qe: usize,
    hconv: usize,
    nhconv: usize,
}

impl AllOffsets {
    fn of<M: MultibodyModel>() -> (Self, usize) {
        let find = |name: &str| {
            M::ALL_QUANTITIES_LAYOUT
                .iter()
                .find(|(n, _, _)| *n == name)
                .map(|(_, o, _)| *o)
                .expect("every generated model lays out the standard quantities")
        };
        let len = M::ALL_QUANTITIES_LAYOUT
            .iter()
            .map(|(_, o, l)| o + l)
            .max()
            .unwrap_or(0);
        (
            AllOffsets {
                mass: find("mass_matrix"),
                qv: find("quadratic_velocity_forces"),
                qg: find("gravity_forces"),
                qe: find("applied_forces"),
                hconv: find("holonomic_convective"),
                nhconv: find("nonholonomic_convective"),
            },
            len,
        )
    }
}

impl<T: Scalar> Workspace<T> {
    pub fn new<M: MultibodyModel>() -> Self {
        let nq = M::nq();
        let nh = M::HOLONOMIC.len();
        let nc = nh + M::NONHOLONOMIC.len();
        let ni = M::INDEPENDENT.len();
        let depv = dependent_velocities::<M>();
        let nd = depv.len();
        let (off, all_len) = AllOffsets::of::<M>();
        Workspace {
            all: vec![T::zero(); all_len],
            off,
            p: M::INITIAL_GUESS.iter().map(|&x| T::cst(x)).collect(),
            dp: vec![T::zero(); nq],
            ddq: vec![T::zero(); ni],
            residual: 0.0,
            newton_iterations: 0,
            p_prev: M::INITIAL_GUESS.iter().map(|&x| T::cst(x)).collect(),
            t_prev: 0.0,
            have_prev: false,
            res: vec![T::zero(); nh],
            step: vec![T::zero(); nh],
            cq: vec![T::zero(); nh * nq],
            jac: vec![T::zero(); nh * nh],
            piv: vec![0; nq.max(nc)],
            d: vec![T::zero(); nc * nq],
            ct: vec![T::zero(); nh],
            ddep: vec![T::zero(); nd * nd],
            x: vec![T::zero(); nd * (ni + 1)],
            gamma: vec![T::zero(); nc],
            e: vec![T::zero(); nq * ni],
            f: vec![T::zero(); nq],
            mass: vec![T::zero(); nq * nq],
            qv: vec![T::zero(); nq],
            qg: vec![T::zero(); nq],
            qe: vec![T::zero(); nq],
            qtot: vec![T::zero(); nq],
            me: vec![T::zero(); nq * ni],
            mi: vec![T::zero(); ni * ni],
            depv,
        }
    }
}

/// Newton tolerance on the max-norm of the holonomic residuals (m, rad).
pub const NEWTON_TOL: f64 = 1e-13;
const NEWTON_MAX: usize = 30;

fn max_abs<T: Scalar>(v: &[T]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.re().abs()))
}

/// Solve the holonomic constraints for the dependent coordinates of `w.p`
/// (the other coordinates are set), starting from the values in `w.p`.
/// With dual numbers the iteration runs on them too: once the values have
/// converged, a Newton step gives the dependent coordinates' derivatives
/// exactly (implicit function theorem), whatever derivatives it started
/// from; the loop makes at least one step.
fn newton<M: MultibodyModel, T: Scalar>(param: &[T], t: f64, w: &mut Workspace<T>) -> Result<(), SimulateError> {
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let dep = M::DEPENDENT;
    let tt = T::cst(t);
    M::holonomic_residuals(param, tt, &w.p, &mut w.res);
    let mut r = max_abs(&w.res);
    let mut it = 0;
    // At least one iteration: the result is then a function of the state
    // alone (to rounding), not of the warm start, which the integrator's
    // error control needs.
    while !(r <= NEWTON_TOL) || it == 0 {
        if it >= NEWTON_MAX || !r.is_finite() {
            return Err(SimulateError::Constraint {
                t,
                residual: r,
                iterations: it,
            });
        }
        M::holonomic_jacobian(param, tt, &w.p, &mut w.cq);
        for i in 0..nh {
            for (k, &j) in dep.iter().enumerate() {
                w.jac[i * nh + k] = w.cq[i * nq + j];
            }
        }
        lu_factor(&mut w.jac, nh, &mut w.piv[..nh]).map_err(|s| SimulateError::Singular {
            t,
            what: "holonomic constraint Jacobian",
            column: s.column,
            pivot: s.pivot,
        })?;
        lu_solve(&w.jac, nh, &w.piv[..nh], &mut w.res, 1);
        // Damped step: halve until the residual decreases (keeps Newton on
        // the branch it starts on).
        w.step.copy_from_slice(&w.res);
        let mut lambda = 1.0;
        loop {
            for (k, &j) in dep.iter().enumerate() {
                w.p[j] -= T::cst(lambda) * w.step[k];
            }
            M::holonomic_residuals(param, tt, &w.p, &mut w.res);
            let n = max_abs(&w.res);
            if n < r || lambda < 1e-3 || n <= NEWTON_TOL {
                r = n;
                break;
            }
            lambda *= 0.5;
            for (k, &j) in dep.iter().enumerate() {
                w.p[j] += T::cst(lambda) * w.step[k];
            }
        }
        it += 1;
    }
    w.residual = r;
    w.newton_iterations = it;
    Ok(())
}

/// The parameter vector with the extra states' tail: `param` as given when it
/// already has it, else extended with zeros.
pub(crate) fn with_state_tail<M: MultibodyModel>(param: &[f64]) -> Result<Vec<f64>, SimulateError> {
    let (np, nz) = (M::PARAMETERS.len(), M::STATES.len());
    if param.len() == np + nz {
        Ok(param.to_vec())
    } else if param.len() == np {
        let mut v = param.to_vec();
        v.resize(np + nz, 0.0);
        Ok(v)
    } else {
        Err(SimulateError::ParameterCount {
            model: M::NAME,
            expected: np + nz,
            got: param.len(),
        })
    }
}

/// Everything the model's equations need at one state: full `p`, `p'` and the
/// independent accelerations. Generic over the model; `f64` only.
pub struct Evaluator<'a, M: MultibodyModel> {
    /// Parameters followed by the extra states (`M::PARAMETERS.len() +
    /// M::STATES.len()` values; the tail holds the initial states).
    pub param: Vec<f64>,
    /// `param` with its state tail overwritten by the `z` of the state being
    /// evaluated (what the generated code reads).
    pub(crate) pz: RefCell<Vec<f64>>,
    pub layout: StateLayout,
    pub coords: BicycleCoordinates,
    pub inputs: &'a Inputs,
    pub(crate) ws: RefCell<Workspace>,
    /// First failure inside the right-hand side (the integrator's callback
    /// cannot return errors).
    pub(crate) error: RefCell<Option<SimulateError>>,
    pub(crate) evaluations: Cell<u64>,
    /// The integration segment `(start, end)` between breakpoints: inputs
    /// are evaluated inside it, so that a pulse edge at a segment end does
    /// not leak into the last stage of the last step.
    pub(crate) segment: Cell<(f64, f64)>,
    _m: std::marker::PhantomData<M>,
}

impl<'a, M: MultibodyModel> Evaluator<'a, M> {
    /// `param` holds the parameters, optionally followed by initial values of
    /// the extra states (zero when absent).
    pub fn new(param: &[f64], inputs: &'a Inputs) -> Result<Self, SimulateError> {
        let param = with_state_tail::<M>(param)?;
        if let Some(k) = param.iter().position(|x| !x.is_finite()) {
            let what = match M::PARAMETERS.get(k) {
                Some(name) => format!("parameter `{name}`"),
                None => format!("initial state `{}`", M::STATES[k - M::PARAMETERS.len()]),
            };
            return Err(SimulateError::NotFinite { what });
        }
        Ok(Evaluator {
            pz: RefCell::new(param.clone()),
            param,
            layout: StateLayout::of::<M>(),
            coords: BicycleCoordinates::of::<M>()?,
            inputs,
            ws: RefCell::new(Workspace::new::<M>()),
            error: RefCell::new(None),
            evaluations: Cell::new(0),
            segment: Cell::new((f64::NEG_INFINITY, f64::INFINITY)),
            _m: std::marker::PhantomData,
        })
    }

    /// Full coordinates and velocities from the state, then the independent
    /// accelerations (see [`evaluate_state`]). Results in the workspace.
    pub(crate) fn evaluate(&self, t: f64, y: &[f64], w: &mut Workspace) -> Result<(), SimulateError> {
        self.evaluations.set(self.evaluations.get() + 1);
        let mut pz = self.pz.borrow_mut();
        let at = At {
            layout: &self.layout,
            coords: &self.coords,
            inputs: self.inputs,
            segment: self.segment.get(),
        };
        evaluate_state::<M, f64>(&at, t, y, &mut pz, w)
    }

    /// State derivative `dy` at `(t, y)`.
    pub fn derivative(&self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), SimulateError> {
        let mut w = self.ws.borrow_mut();
        self.evaluate(t, y, &mut w)?;
        let pz = self.pz.borrow();
        state_derivative::<M, f64>(&self.layout, t, y, &pz, &w, dy);
        Ok(())
    }

    /// Full `(p, p')` at a state (a fresh workspace is not needed: uses the
    /// shared one).
    pub(crate) fn full_state(&self, t: f64, y: &[f64]) -> Result<(Vec<f64>, Vec<f64>), SimulateError> {
        let mut w = self.ws.borrow_mut();
        self.evaluate(t, y, &mut w)?;
        Ok((w.p.clone(), w.dp.clone()))
    }

    /// Constraint residuals at a full state: max-norm of the holonomic
    /// residuals `Res(p, t)` and of the velocity constraints `D p' - d`.
    pub fn residuals(&self, t: f64, p: &[f64], dp: &[f64]) -> (f64, f64) {
        let nq = M::nq();
        let nh = M::HOLONOMIC.len();
        let nnh = M::NONHOLONOMIC.len();
        let mut res = vec![0.0; nh];
        M::holonomic_residuals(&self.param, t, p, &mut res);
        let mut cq = vec![0.0; nh * nq];
        M::holonomic_jacobian(&self.param, t, p, &mut cq);
        let mut ct = vec![0.0; nh];
        M::holonomic_time_derivative(&self.param, t, p, &mut ct);
        let mut v = vec![0.0; nnh];
        M::nonholonomic_velocities(&self.param, t, p, dp, &mut v);
        let mut vel = max_abs(&v);
        for i in 0..nh {
            let s: f64 = (0..nq).map(|j| cq[i * nq + j] * dp[j]).sum::<f64>() + ct[i];
            vel = vel.max(s.abs());
        }
        (max_abs(&res), vel)
    }

    /// Generalized impulse of a lateral impulse `j` (N s, positive toward the
    /// rider's right, i.e. along minus the heading frame's y axis) applied at
    /// a point fixed in the rear frame, `s` in the rear frame's axes from the
    /// rear wheel centre: `H_P^T J` with `H_P = d r_P / d p` (thesis chain
    /// `r_P = [xc yc 0] + A_phi A_theta ([0 0 Rt] + A_beta s)`).
    pub fn lateral_impulse(&self, p: &[f64], s: [f64; 3], j: f64, rt: f64) -> Vec<f64> {
        let c = &self.coords;
        let idx = [c.xc, c.yc, c.yaw, c.roll, c.pitch];
        let v: Vec<Dual<5>> = idx.iter().enumerate().map(|(k, &i)| Dual::variable(p[i], k)).collect();
        let r = rear_frame_point(&v, s, rt);
        let (sp, cp) = p[c.yaw].sin_cos();
        // Direction: toward the rider's right = -(heading frame y axis).
        let dir = [sp, -cp, 0.0];
        let mut q = vec![0.0; M::nq()];
        for (k, &i) in idx.iter().enumerate() {
            q[i] = j * (0..3).map(|a| dir[a] * r[a].eps[k]).sum::<f64>();
        }
        q
    }

    /// Apply an impulse (generalized, `qhat`) to the state: `Mi dq' = E^T qhat`
    /// at the current configuration, positions unchanged.
    pub(crate) fn apply_impulse(&self, t: f64, y: &mut [f64], qhat: &[f64]) -> Result<(), SimulateError> {
        let mut w = self.ws.borrow_mut();
        self.evaluate(t, y, &mut w)?;
        // `w.mi` holds the LU factors of Mi, `w.e` is E.
        let ni = self.layout.ni();
        let nq = M::nq();
        let mut rhs: Vec<f64> = (0..ni)
            .map(|a| (0..nq).map(|r| w.e[r * ni + a] * qhat[r]).sum())
            .collect();
        lu_solve(&w.mi, ni, &w.piv[..ni], &mut rhs, 1);
        let r = self.layout.rates();
        for k in 0..ni {
            y[r + k] += rhs[k];
        }
        Ok(())
    }
}

/// What an evaluation reads besides the state: where things are in it,
/// the bicycle's coordinates, the inputs and the integration segment.
pub(crate) struct At<'a> {
    pub layout: &'a StateLayout,
    pub coords: &'a BicycleCoordinates,
    pub inputs: &'a Inputs,
    /// The integration segment `(start, end)` between breakpoints.
    pub segment: (f64, f64),
}

/// Full coordinates and velocities from the state, then the independent
/// accelerations (thesis eq. 40-47): Newton on the holonomic constraints
/// (warm-started), `D_dep p'_dep = d - D_ind q'`, `E`, `F`,
/// `Mi q'' = Qi`. Results in the workspace.
pub(crate) fn evaluate_state<M: MultibodyModel, T: Scalar>(
    at: &At<'_>,
    t: f64,
    y: &[T],
    pz: &mut [T],
    w: &mut Workspace<T>,
) -> Result<(), SimulateError> {
    evaluate_kinematics::<M, T>(at, t, y, pz, w)?;
    evaluate_dynamics::<M, T>(at, t, pz, w)
}

/// The first half of [`evaluate_state`]: the full coordinates `w.p` and
/// velocities `w.dp` from the state, without the dynamics. What a sample
/// of an output that depends on the motion alone (the forward speed)
/// needs: the mass matrix and forces are most of an evaluation's cost.
pub(crate) fn evaluate_kinematics<M: MultibodyModel, T: Scalar>(
    at: &At<'_>,
    t: f64,
    y: &[T],
    pz: &mut [T],
    w: &mut Workspace<T>,
) -> Result<(), SimulateError> {
    let l = at.layout;
    let ni = l.ni();
    let nq = M::nq();
    if let Some(k) = y.iter().position(|x| !x.re().is_finite()) {
        return Err(SimulateError::NotFinite {
            what: format!("state component {k} at t = {t}"),
        });
    }
    let nh = M::HOLONOMIC.len();
    let np = M::PARAMETERS.len();
    pz[np..].copy_from_slice(&y[l.extras()..l.extras() + l.extra]);
    let param = &*pz;
    let tt = T::cst(t);
    w.p_prev.copy_from_slice(&w.p);
    for (k, &j) in l.independent.iter().enumerate() {
        w.p[j] = y[k];
    }
    for (k, &j) in l.ignorable.iter().enumerate() {
        w.p[j] = y[l.ignorables() + k];
    }
    if w.have_prev {
        // Predictor: first-order change of the dependent coordinates from
        // the holonomic Jacobian of the previous evaluation,
        // `Cq_dep dp_dep = -(Cq_other dp_other + Ct dt)`. Without it a
        // large change of a coordinate the constraints depend on
        // periodically (the front wheel angle eps, which enters only as
        // eps + xi) would send Newton to another branch.
        for i in 0..nh {
            let mut r = w.ct[i] * T::cst(t - w.t_prev);
            for j in 0..nq {
                if !M::DEPENDENT.contains(&j) {
                    r += w.d[i * nq + j] * (w.p[j] - w.p_prev[j]);
                }
            }
            w.res[i] = r;
            for (k, &j) in M::DEPENDENT.iter().enumerate() {
                w.jac[i * nh + k] = w.d[i * nq + j];
            }
        }
        if lu_factor(&mut w.jac, nh, &mut w.piv[..nh]).is_ok() {
            lu_solve(&w.jac, nh, &w.piv[..nh], &mut w.res, 1);
            for (k, &j) in M::DEPENDENT.iter().enumerate() {
                w.p[j] -= w.res[k];
            }
        }
    }
    w.have_prev = false;
    if newton::<M, T>(param, t, w).is_err() {
        // Retry from the model's initial guess (a poor warm start).
        for &j in M::DEPENDENT {
            w.p[j] = T::cst(M::INITIAL_GUESS[j]);
        }
        newton::<M, T>(param, t, w)?;
    }
    let nc = nh + M::NONHOLONOMIC.len();
    let nd = w.depv.len();
    M::holonomic_jacobian(param, tt, &w.p, &mut w.d[..nh * nq]);
    M::nonholonomic_matrix(param, tt, &w.p, &mut w.d[nh * nq..]);
    M::holonomic_time_derivative(param, tt, &w.p, &mut w.ct);
    w.have_prev = true;
    w.t_prev = t;
    for i in 0..nc {
        for (k, &j) in w.depv.iter().enumerate() {
            w.ddep[i * nd + k] = w.d[i * nq + j];
        }
        for (k, &j) in l.independent.iter().enumerate() {
            w.x[i * (ni + 1) + k] = w.d[i * nq + j];
        }
        w.x[i * (ni + 1) + ni] = if i < nh { -w.ct[i] } else { T::zero() };
    }
    lu_factor(&mut w.ddep, nd, &mut w.piv[..nd]).map_err(|s| SimulateError::Singular {
        t,
        what: "velocity constraints (coordinate partitioning)",
        column: s.column,
        pivot: s.pivot,
    })?;
    lu_solve(&w.ddep, nd, &w.piv[..nd], &mut w.x, ni + 1);
    for (k, &j) in l.independent.iter().enumerate() {
        w.dp[j] = y[l.rates() + k];
    }
    for r in 0..nd {
        let mut v = w.x[r * (ni + 1) + ni];
        for k in 0..ni {
            v -= w.x[r * (ni + 1) + k] * y[l.rates() + k];
        }
        w.dp[w.depv[r]] = v;
    }
    Ok(())
}

/// The second half of [`evaluate_state`], after [`evaluate_kinematics`]
/// at the same `(t, y)`: the independent accelerations `w.ddq`.
fn evaluate_dynamics<M: MultibodyModel, T: Scalar>(
    at: &At<'_>,
    t: f64,
    pz: &mut [T],
    w: &mut Workspace<T>,
) -> Result<(), SimulateError> {
    let l = at.layout;
    let ni = l.ni();
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let nc = nh + M::NONHOLONOMIC.len();
    let nd = w.depv.len();
    let param = &*pz;
    let tt = T::cst(t);
    // Everything that needs the full velocities in one call (shared
    // common subexpressions).
    M::all_quantities(param, tt, &w.p, &w.dp, &mut w.all);
    let o = w.off;
    let nnh = nc - nh;
    w.gamma[..nh].copy_from_slice(&w.all[o.hconv..o.hconv + nh]);
    w.gamma[nh..].copy_from_slice(&w.all[o.nhconv..o.nhconv + nnh]);
    lu_solve(&w.ddep, nd, &w.piv[..nd], &mut w.gamma, 1);
    w.e.iter_mut().for_each(|x| *x = T::zero());
    w.f.iter_mut().for_each(|x| *x = T::zero());
    for (k, &j) in l.independent.iter().enumerate() {
        w.e[j * ni + k] = T::one();
    }
    for r in 0..nd {
        let j = w.depv[r];
        for k in 0..ni {
            w.e[j * ni + k] = -w.x[r * (ni + 1) + k];
        }
        w.f[j] = -w.gamma[r];
    }
    w.mass.copy_from_slice(&w.all[o.mass..o.mass + nq * nq]);
    w.qv.copy_from_slice(&w.all[o.qv..o.qv + nq]);
    w.qg.copy_from_slice(&w.all[o.qg..o.qg + nq]);
    w.qe.copy_from_slice(&w.all[o.qe..o.qe + nq]);
    let (a, b) = at.segment;
    let inset = 1e-9 * (b - a).min(1.0);
    let (tr, ts) = at.inputs.torques(t.max(a + inset).min(b - inset));
    w.qe[at.coords.roll] += T::cst(tr);
    w.qe[at.coords.steer] += T::cst(ts);
    if let Some(k) = &at.inputs.feedback {
        // The controller's torques from the state in the benchmark's signs
        // (the thesis's steer gamma is positive to the left: delta =
        // -gamma, and a steer torque T_delta is a generalized force
        // -T_delta on gamma; roll is positive to the right in both).
        let c = at.coords;
        let v = forward_speed(c, &w.p, &w.dp);
        let x = [w.p[c.roll], -w.p[c.steer], w.dp[c.roll], -w.dp[c.steer]];
        let [t_roll, t_steer] = k.torques(v, x);
        w.qe[c.roll] += t_roll;
        w.qe[c.steer] -= t_steer;
    }
    for r in 0..nq {
        let mut s = w.qv[r] + w.qg[r] + w.qe[r];
        for c in 0..nq {
            s -= w.mass[r * nq + c] * w.f[c];
        }
        w.qtot[r] = s;
    }
    for r in 0..nq {
        for k in 0..ni {
            let mut s = T::zero();
            for c in 0..nq {
                s += w.mass[r * nq + c] * w.e[c * ni + k];
            }
            w.me[r * ni + k] = s;
        }
    }
    for a in 0..ni {
        let mut qi = T::zero();
        for r in 0..nq {
            qi += w.e[r * ni + a] * w.qtot[r];
        }
        w.ddq[a] = qi;
        for b in 0..ni {
            let mut m = T::zero();
            for r in 0..nq {
                m += w.e[r * ni + a] * w.me[r * ni + b];
            }
            w.mi[a * ni + b] = m;
        }
    }
    lu_factor(&mut w.mi, ni, &mut w.piv[..ni]).map_err(|s| SimulateError::Singular {
        t,
        what: "reduced mass matrix",
        column: s.column,
        pivot: s.pivot,
    })?;
    lu_solve(&w.mi, ni, &w.piv[..ni], &mut w.ddq, 1);
    Ok(())
}

/// The state derivative from an evaluation at `(t, y)` (`pz`: the parameters
/// with the state's `z` in their tail, as [`evaluate_state`] left them).
pub(crate) fn state_derivative<M: MultibodyModel, T: Scalar>(
    l: &StateLayout,
    t: f64,
    y: &[T],
    pz: &[T],
    w: &Workspace<T>,
    dy: &mut [T],
) {
    let ni = l.ni();
    dy[..ni].copy_from_slice(&y[l.rates()..l.rates() + ni]);
    dy[ni..2 * ni].copy_from_slice(&w.ddq);
    for (k, &j) in l.ignorable.iter().enumerate() {
        dy[l.ignorables() + k] = w.dp[j];
    }
    dy[l.time()] = T::one();
    if l.extra > 0 {
        M::state_rates(pz, T::cst(t), &w.p, &w.dp, &mut dy[l.extras()..l.extras() + l.extra]);
    }
}

/// Position of a point fixed in the rear frame (thesis eq. 13-15 chain).
pub fn rear_frame_point<T: Scalar>(v: &[T], s: [f64; 3], rt: f64) -> [T; 3] {
    // v = [xc, yc, phi, theta, beta]
    let (sp, cp) = v[2].sin_cos();
    let (st, ct) = v[3].sin_cos();
    let (sb, cb) = v[4].sin_cos();
    // A_beta s (rotation about y) + [0 0 Rt]
    let a = [
        cb * T::cst(s[0]) + sb * T::cst(s[2]),
        T::cst(s[1]),
        -sb * T::cst(s[0]) + cb * T::cst(s[2]) + T::cst(rt),
    ];
    // A_theta (about x)
    let b = [a[0], ct * a[1] - st * a[2], st * a[1] + ct * a[2]];
    // A_phi (about z)
    [v[0] + cp * b[0] - sp * b[1], v[1] + sp * b[0] + cp * b[1], b[2]]
}
