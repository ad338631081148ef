//! The integrators behind one call: DOP853 (`ode_solvers`) and Radau5
//! (`differential-equations`) run on the model's right-hand side, sampled on
//! a grid or to an end time, stopped by the roll and steer events.
//!
//! Kept apart from the run itself ([`super::simulate`]) because this is the
//! one place that knows the two crates' interfaces: their system traits,
//! Radau5's padded fixed-size state, and the dense-output quirks worked
//! around here (see the module docs of [`super`] for the choice of methods).

use differential_equations::prelude::{
    ControlFlag, ImplicitRungeKutta, Interpolation, Matrix as DeMatrix, Solout, Solution, IVP, ODE,
};
use ode_solvers::{DVector, Dop853, OutputType, System};

use super::{Evaluator, Events, Method, SimOptions, SimStats, SimulateError};
use crate::model::MultibodyModel;

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
pub(super) fn event_value<M: MultibodyModel>(eval: &Evaluator<'_, M>, ev: &Events, y: &[f64]) -> (f64, usize) {
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
pub(super) enum Sampling {
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
pub(super) struct Samples {
    pub(super) t: Vec<f64>,
    pub(super) y: Vec<Vec<f64>>,
    pub(super) stopped_from: Option<(f64, Vec<f64>)>,
}

/// Integrate from `(t0, y0)` to `t1 > t0` with `opts.method`, sampled as
/// `sampling` says: the one place where DOP853 and Radau5 are run. Counts the
/// steps into `stats`; an error of the model's evaluation takes precedence
/// over the integrator's own.
pub(super) fn integrate<M: MultibodyModel>(
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
pub(super) fn integrate_to<M: MultibodyModel>(
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
