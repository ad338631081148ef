//! Forward sensitivities: a simulation's response together with its exact
//! first derivatives with respect to parameters and initial conditions,
//! from one integration.
//!
//! Identification fits effect parameters and every kick's initial state to
//! measured responses, and its Jacobian is the derivative of the simulated
//! response along each of them. Forward differences of whole simulations
//! give it at the price of one simulation per column, run at a tolerance
//! tight enough for the difference to mean something. Here the state
//! carries, beside each component `y_i`, its derivatives `S_i = dy_i/dθ`
//! along `N` directions, and the right-hand side is evaluated once in
//! `N`-direction dual numbers: the dual part of `f(y + S ε, θ + ε)` is
//! `f_y S + f_θ`, the right-hand side of the variational equations, exact to
//! rounding. Everything inside the right-hand side follows: the dependent
//! coordinates through Newton's method run in dual numbers (at the solution,
//! one step gives their derivatives by the implicit function theorem), the
//! dependent velocities and the reduced mass matrix through the dual LU
//! solves. The integrator's error control covers the derivatives as well,
//! so they are as accurate as the response itself.
//!
//! The initial state's derivatives come from central differences of
//! [`initial_state`] (an algebraic map: the constraint solve and, in a
//! free-speed model, the rates that set the speed), with the components that
//! the initial conditions set directly (roll, steer and their rates) exact.
//!
//! The same code with plain `f64` (no direction) is the lean path for
//! residuals alone: samples on a grid, no energies or constraint residuals.

use ode_solvers::{DVector, Dop853, OutputType};
use std::cell::RefCell;

use super::rhs::{
    evaluate_kinematics, evaluate_state, forward_speed, state_derivative, At, BicycleCoordinates, StateLayout,
    Workspace,
};
use super::{
    imposed_speed_parameter, initial_state, DynSystem, Events, InitialConditions, Inputs, SimOptions, SimulateError,
    MAX_STATE_RATES,
};
use crate::feedback::GainSchedule;
use crate::model::MultibodyModel;
use crate::scalar::{Dual, Scalar};

/// A scalar the integrator can carry as a value and its derivatives:
/// `f64` (no derivative) or [`Dual`].
pub trait Carried: Scalar {
    /// Number of derivative directions.
    const DIRECTIONS: usize;
    /// The scalar with value `re` and derivatives `eps` (`DIRECTIONS` long).
    fn gather(re: f64, eps: &[f64]) -> Self;
    /// Write the derivatives into `eps` and return the value.
    fn scatter(self, eps: &mut [f64]) -> f64;
    /// The derivative along direction `d`.
    fn derivative(self, d: usize) -> f64;
}

impl Carried for f64 {
    const DIRECTIONS: usize = 0;
    #[inline(always)]
    fn gather(re: f64, _: &[f64]) -> Self {
        re
    }
    #[inline(always)]
    fn scatter(self, _: &mut [f64]) -> f64 {
        self
    }
    fn derivative(self, _: usize) -> f64 {
        0.0
    }
}

impl<const N: usize> Carried for Dual<N> {
    const DIRECTIONS: usize = N;
    #[inline(always)]
    fn gather(re: f64, eps: &[f64]) -> Self {
        let mut d = Dual { re, eps: [0.0; N] };
        d.eps.copy_from_slice(eps);
        d
    }
    #[inline(always)]
    fn scatter(self, eps: &mut [f64]) -> f64 {
        eps.copy_from_slice(&self.eps);
        self.re
    }
    fn derivative(self, d: usize) -> f64 {
        self.eps[d]
    }
}

/// What the derivative directions are: parameters and initial conditions,
/// each moving with unit rate along one direction (parameters tied to each
/// other move along the same one).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Directions {
    /// `(parameter index, direction, weight)`: the parameter moves by
    /// `weight` per unit along the direction (1 for a parameter itself; a
    /// combination of parameters, such as a correction of a quantity the
    /// model holds in several, gives each its coefficient). Indices past
    /// the model's parameters are the extra states' initial values (the
    /// parameter vector's tail).
    pub parameters: Vec<(usize, usize, f64)>,
    /// The direction of the initial roll, steer, roll rate, steer rate and
    /// speed (rad, rad, rad/s, rad/s, m/s), if they have one.
    pub initial: [Option<usize>; 5],
    /// The direction of the extra states' initial rates
    /// ([`InitialConditions::state_rates`]), if they have one.
    pub state_rates: [Option<usize>; MAX_STATE_RATES],
}

/// A response sampled on a uniform grid, with derivatives along the
/// [`Directions`] when `T` is a dual number.
#[derive(Clone, Debug)]
pub struct Response<T> {
    /// Sample times (s), from 0 by the output interval.
    pub t: Vec<f64>,
    /// Roll angle (rad) and rate (rad/s).
    pub roll: Vec<T>,
    pub roll_rate: Vec<T>,
    /// Steer angle (rad).
    pub steer: Vec<T>,
    /// Forward speed (m/s) at the times asked for, linear between the
    /// grid's samples (the last value held after a stop).
    pub speed: Vec<T>,
    /// Time (s) of the step at whose end a fall or steer-stop event fired:
    /// the samples end there.
    pub stopped: Option<f64>,
}

/// The integrator's view of the state and its derivatives.
struct Variational<'a, M: MultibodyModel, T: Carried> {
    at: At<'a>,
    n: usize,
    /// Parameters with their seeds (state tail refreshed per evaluation).
    pz: RefCell<Vec<T>>,
    ws: RefCell<Workspace<T>>,
    y: RefCell<Vec<T>>,
    dy: RefCell<Vec<T>>,
    events: Events,
    error: RefCell<Option<SimulateError>>,
    _m: std::marker::PhantomData<M>,
}

impl<M: MultibodyModel, T: Carried> Variational<'_, M, T> {
    fn gather(&self, big: &[f64], y: &mut [T]) {
        let nd = T::DIRECTIONS;
        for (i, v) in y.iter_mut().enumerate() {
            *v = T::gather(big[i], &big[self.n + i * nd..self.n + (i + 1) * nd]);
        }
    }
    fn stop(&self, big: &[f64]) -> bool {
        let c = self.at.coords;
        self.events.roll_limit.is_some_and(|l| big[c.roll_ind].abs() >= l)
            || self.events.steer_limit.is_some_and(|l| big[c.steer_ind].abs() >= l)
    }
}

impl<M: MultibodyModel, T: Carried> Variational<'_, M, T> {
    fn rhs(&self, big: &[f64], dbig: &mut [f64]) {
        if self.error.borrow().is_some() {
            dbig.fill(f64::NAN);
            return;
        }
        let mut y = self.y.borrow_mut();
        let mut dy = self.dy.borrow_mut();
        self.gather(big, &mut y);
        let t = big[self.at.layout.time()];
        let mut pz = self.pz.borrow_mut();
        let mut w = self.ws.borrow_mut();
        if let Err(e) = evaluate_state::<M, T>(&self.at, t, &y, &mut pz, &mut w) {
            *self.error.borrow_mut() = Some(e);
            dbig.fill(f64::NAN);
            return;
        }
        state_derivative::<M, T>(self.at.layout, t, &y, &pz, &w, &mut dy);
        let (nd, n) = (T::DIRECTIONS, self.n);
        let (head, tail) = dbig.split_at_mut(n);
        for (i, v) in dy.iter().enumerate() {
            head[i] = v.scatter(&mut tail[i * nd..(i + 1) * nd]);
        }
    }
}

/// Simulate model `M` from `ic` for `duration` seconds without inputs,
/// sampled every `opts.output_interval` seconds (DOP853 with `opts`'s
/// tolerances and events), with the derivatives of every sample along
/// `directions` when `T` is a dual number (`f64`: the response alone).
/// `param` may carry the extra states' initial values in its tail (zero
/// without), and a direction may move them (indices past the parameters).
/// `speed_at` lists the times (s) at which the forward speed is wanted.
pub fn response<M: MultibodyModel, T: Carried>(
    param: &[f64],
    ic: &InitialConditions,
    directions: &Directions,
    duration: f64,
    opts: &SimOptions,
    speed_at: &[f64],
) -> Result<Response<T>, SimulateError> {
    response_with::<M, T>(param, ic, directions, duration, opts, speed_at, None)
}

/// [`response`] with a controller closed around the equations (a bicycle
/// file's `[feedback]` table, [`Inputs::feedback`]): its torques enter the
/// right-hand side, and so the derivatives, as every other force does.
pub fn response_with<M: MultibodyModel, T: Carried>(
    param: &[f64],
    ic: &InitialConditions,
    directions: &Directions,
    duration: f64,
    opts: &SimOptions,
    speed_at: &[f64],
    feedback: Option<&GainSchedule>,
) -> Result<Response<T>, SimulateError> {
    let nd = T::DIRECTIONS;
    if !(duration > 0.0 && duration.is_finite()) {
        return Err(SimulateError::InvalidInput(format!(
            "duration must be positive, got {duration}"
        )));
    }
    if !(opts.output_interval > 0.0 && duration / opts.output_interval <= 1e7) {
        return Err(SimulateError::InvalidInput("output interval must be positive".into()));
    }
    // Parameters, and the extra states' initial values in the tail.
    let np = M::PARAMETERS.len() + M::STATES.len();
    // Without derivatives (`f64`) the directions are not used.
    let out_of_range = nd > 0
        && (directions
            .parameters
            .iter()
            .any(|&(i, d, w)| i >= np || d >= nd || !w.is_finite())
            || directions
                .initial
                .iter()
                .chain(&directions.state_rates)
                .flatten()
                .any(|&d| d >= nd));
    if out_of_range {
        return Err(SimulateError::InvalidInput(format!(
            "sensitivity directions {directions:?} outside {np} parameters and {nd} directions"
        )));
    }
    let (y0, param) = initial_state::<M>(param, ic)?;
    let layout = StateLayout::of::<M>();
    let coords = BicycleCoordinates::of::<M>()?;
    let n = y0.len();
    let c = coords;
    if opts.events.roll_limit.is_some_and(|l| y0[c.roll_ind].abs() >= l)
        || opts.events.steer_limit.is_some_and(|l| y0[c.steer_ind].abs() >= l)
    {
        return Err(SimulateError::InvalidInput(format!(
            "the initial roll {:.4} rad or steer {:.4} rad is already at its limit ({:?})",
            ic.roll, ic.steer, opts.events
        )));
    }

    // Parameters with their seeds; a driven model's speed parameter moves
    // with the initial speed (`initial_state` sets it from there).
    let mut seeds = vec![vec![0.0; nd]; param.len()];
    for &(i, d, w) in directions.parameters.iter().filter(|_| nd > 0) {
        seeds[i][d] += w;
    }
    if let (Some(k), Some(d), true) = (imposed_speed_parameter::<M>(), directions.initial[4], nd > 0) {
        seeds[k] = vec![0.0; nd];
        seeds[k][d] = 1.0;
    }
    let pz: Vec<T> = param.iter().zip(&seeds).map(|(&v, e)| T::gather(v, e)).collect();

    // The state and its derivatives: `[y | dy_0/dθ, dy_1/dθ, ...]`.
    let mut big = vec![0.0; n * (1 + nd)];
    big[..n].copy_from_slice(&y0);
    if nd > 0 {
        let s0 = initial_sensitivities::<M>(&param, ic, directions, nd, &seeds)?;
        for i in 0..n {
            big[n + i * nd..n + (i + 1) * nd].copy_from_slice(&s0[i]);
        }
        // What the initial conditions set directly is exact.
        let rates = layout.rates();
        for (row, which) in [
            (c.roll_ind, 0),
            (c.steer_ind, 1),
            (rates + c.roll_ind, 2),
            (rates + c.steer_ind, 3),
        ] {
            let s = &mut big[n + row * nd..n + (row + 1) * nd];
            s.fill(0.0);
            if let Some(d) = directions.initial[which] {
                s[d] = 1.0;
            }
        }
    }

    let inputs = Inputs {
        feedback: feedback.cloned(),
        ..Inputs::default()
    };
    let sys = Variational::<M, T> {
        at: At {
            layout: &layout,
            coords: &coords,
            inputs: &inputs,
            segment: (0.0, duration),
        },
        n,
        pz: RefCell::new(pz),
        ws: RefCell::new(Workspace::new::<M>()),
        y: RefCell::new(vec![T::zero(); n]),
        dy: RefCell::new(vec![T::zero(); n]),
        events: opts.events,
        error: RefCell::new(None),
        _m: std::marker::PhantomData,
    };
    let dx = opts.output_interval;
    // Past the end, off the grid: see `integrate` (ode_solvers 0.6.2 pushes
    // an extrapolated sample at an end within 1e-9 of a grid time).
    let x_end = duration + (1e-6f64).min(0.01 * dx).max(1e-8);
    // The integrator borrows the system through closures (its buffers and
    // first error stay readable afterwards; DOP853 is compiled once, see
    // `DynSystem`).
    let f = |big: &[f64], dbig: &mut [f64]| sys.rhs(big, dbig);
    let stop = |big: &[f64]| sys.error.borrow().is_some() || sys.stop(big);
    let mut solver = Dop853::new(
        DynSystem { f: &f, stop: &stop },
        0.0,
        x_end,
        dx,
        DVector::from_vec(big),
        opts.rtol,
        opts.atol,
    );
    solver.set_output(OutputType::Dense);
    let result = solver.integrate();
    if let Some(e) = sys.error.borrow_mut().take() {
        return Err(e);
    }
    result.map_err(|e| SimulateError::Integrator {
        t: 0.0,
        message: format!("DOP853: {e}"),
    })?;
    let ts = solver.x_out();
    let ys = solver.y_out();
    let last = ys.last().map(|b| b.as_slice());
    let stopped = last.filter(|b| sys.stop(b)).and_then(|_| ts.last().copied());
    let mut out = Response {
        t: Vec::with_capacity(ts.len()),
        roll: Vec::with_capacity(ts.len()),
        roll_rate: Vec::with_capacity(ts.len()),
        steer: Vec::with_capacity(ts.len()),
        speed: Vec::new(),
        stopped,
    };
    let rates = layout.rates();
    let mut y = vec![T::zero(); n];
    for (&t, b) in ts.iter().zip(ys) {
        if t > duration + 1e-9 * duration.max(1.0) {
            break;
        }
        let b = b.as_slice();
        sys.gather(b, &mut y);
        out.t.push(t.min(duration));
        out.roll.push(y[c.roll_ind]);
        out.roll_rate.push(y[rates + c.roll_ind]);
        out.steer.push(y[c.steer_ind]);
    }
    if out.t.is_empty() {
        return Err(SimulateError::Integrator {
            t: 0.0,
            message: "DOP853 returned no sample".into(),
        });
    }
    // The speed is a function of the full velocities, which take a
    // constraint solve: it is evaluated only at the grid samples that the
    // times asked for fall between (a wheel sensor gives a few a second,
    // the grid a hundred).
    let mut at_sample: Vec<Option<T>> = vec![None; out.t.len()];
    let mut speed_of = |k: usize| -> Result<T, SimulateError> {
        if let Some(v) = at_sample[k] {
            return Ok(v);
        }
        sys.gather(ys[k].as_slice(), &mut y);
        let mut pz = sys.pz.borrow_mut();
        let mut w = sys.ws.borrow_mut();
        evaluate_kinematics::<M, T>(&sys.at, ys[k][layout.time()], &y, &mut pz, &mut w)?;
        let v = forward_speed(&coords, &w.p, &w.dp);
        at_sample[k] = Some(v);
        Ok(v)
    };
    for &t in speed_at {
        out.speed.push(interpolate(&out.t, t, &mut speed_of)?);
    }
    Ok(out)
}

/// The value at `t` of samples taken at the times `ts` (not empty, in
/// increasing order): linear between the two samples around `t`, the first
/// or last held outside them (a fall ends a simulation early). `value(k)`
/// gives sample `k`; only the samples used are asked for.
pub fn interpolate<T: Scalar, E>(ts: &[f64], t: f64, mut value: impl FnMut(usize) -> Result<T, E>) -> Result<T, E> {
    let last = ts.len() - 1;
    if !(t > ts[0]) {
        return value(0);
    }
    if t >= ts[last] {
        return value(last);
    }
    let k = ts.partition_point(|&x| x <= t);
    let w = (t - ts[k - 1]) / (ts[k] - ts[k - 1]);
    let (a, b) = (value(k - 1)?, value(k)?);
    Ok(a + (b - a) * T::cst(w))
}

/// The initial state's derivatives along each direction, `[component][direction]`,
/// by central differences of [`initial_state`], each direction's step a
/// millionth of the largest input it moves (at least 0.01 in its units).
fn initial_sensitivities<M: MultibodyModel>(
    param: &[f64],
    ic: &InitialConditions,
    directions: &Directions,
    nd: usize,
    seeds: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, SimulateError> {
    let ic_values = [ic.roll, ic.steer, ic.roll_rate, ic.steer_rate, ic.speed];
    let moved = |d: usize, h: f64| -> Result<Vec<f64>, SimulateError> {
        let mut p = param.to_vec();
        for (i, s) in seeds.iter().enumerate() {
            p[i] += h * s[d];
        }
        let mut v = ic_values;
        for (k, dir) in directions.initial.iter().enumerate() {
            if *dir == Some(d) {
                v[k] += h;
            }
        }
        let mut state_rates = ic.state_rates;
        for (k, dir) in directions.state_rates.iter().enumerate() {
            if *dir == Some(d) {
                state_rates[k] += h;
            }
        }
        let moved_ic = InitialConditions {
            roll: v[0],
            steer: v[1],
            roll_rate: v[2],
            steer_rate: v[3],
            speed: v[4],
            yaw: ic.yaw,
            state_rates,
        };
        Ok(initial_state::<M>(&p, &moved_ic)?.0)
    };
    let mut s: Vec<Vec<f64>> = Vec::new();
    for d in 0..nd {
        let mut size = 1e-2f64;
        for (i, sd) in seeds.iter().enumerate() {
            if sd[d] != 0.0 {
                size = size.max(param[i].abs());
            }
        }
        for (k, dir) in directions.initial.iter().enumerate() {
            if *dir == Some(d) {
                size = size.max(ic_values[k].abs());
            }
        }
        for (k, dir) in directions.state_rates.iter().enumerate() {
            if *dir == Some(d) {
                size = size.max(ic.state_rates[k].abs());
            }
        }
        let h = 1e-6 * size;
        let (plus, minus) = (moved(d, h)?, moved(d, -h)?);
        if s.is_empty() {
            s = vec![vec![0.0; nd]; plus.len()];
        }
        for (row, (a, b)) in s.iter_mut().zip(plus.iter().zip(&minus)) {
            row[d] = (a - b) / (2.0 * h);
        }
    }
    Ok(s)
}
