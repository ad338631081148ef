//! The time-series residuals of a candidate model and their Jacobian. A
//! [`Setup`] maps effect values to the model's parameter vector, simulates
//! each kick from its window-start state with the full nonlinear
//! equations, and divides measured minus simulated channels by their noise
//! scales. The Jacobian comes from one simulation in dual numbers per kick
//! (forward sensitivities). A [`ModelFactory`] makes the setup of a model
//! chosen at run time, so that selection can simulate one candidate with
//! an alternative model.

use super::normal::SegmentJacobian;
use super::{Candidate, EffectParameter, IdentifyError, RollChannel, Segment, Weights};
use super::{EXTRA_STATES, INITIAL_MOTION, NUISANCE, STEER_BIAS};
use crate::model::MultibodyModel;
use crate::scalar::Dual;
use crate::simulate::sensitivity::{interpolate, response_with, Carried, Directions};
use crate::simulate::{simulate, Events, InitialConditions, Inputs, Method, SimOptions};
use nalgebra::{DMatrix, DVector};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Makes the fitting setup of one model (type-erased, so identification
/// can switch models for a candidate without compiling every pair).
pub trait ModelFactory: Sync {
    fn setup<'a>(
        &self,
        segments: &'a [Segment],
        weights: &[Weights],
        active: &[&Candidate],
    ) -> Result<Setup<'a>, IdentifyError>;
}

/// The [`ModelFactory`] of model `M` with base parameters `base`.
pub struct Factory<M> {
    pub base: Vec<f64>,
    pub model: std::marker::PhantomData<fn() -> M>,
}

impl<M: MultibodyModel> Factory<M> {
    pub fn new(base: Vec<f64>) -> Self {
        Factory {
            base,
            model: std::marker::PhantomData,
        }
    }
}

impl<M: MultibodyModel> ModelFactory for Factory<M> {
    fn setup<'a>(
        &self,
        segments: &'a [Segment],
        weights: &[Weights],
        active: &[&Candidate],
    ) -> Result<Setup<'a>, IdentifyError> {
        Setup::new::<M>(&self.base, segments, weights, active)
    }
}

/// The fitting problem: a base parameter vector of `M`, the segments, and
/// the active effect parameters.
pub struct Setup<'a> {
    pub base: Vec<f64>,
    pub segments: &'a [Segment],
    /// Channel scales of each segment.
    pub weights: Vec<Weights>,
    pub options: SimOptions,
    /// Active effect parameters: the entries of `base` each sets, as
    /// `(index, coefficient, offset)`: entry = offset + coefficient x value
    /// (primary and tied symbols: coefficient 1, offset 0).
    slots: Vec<Vec<(usize, f64, f64)>>,
    pub parameters: Vec<EffectParameter>,
    simulate: fn(&[f64], &Segment, &[f64; NUISANCE], &SimOptions) -> Result<Sim, String>,
    sensitivities: SensitivityFn,
    /// Number of the model's extra first-order states (each kick's window
    /// start fits their values and rates beside its motion).
    pub(super) extra_states: usize,
    /// The segments' steer bias is a nuisance ([`Segment::steer_bias`]).
    pub(super) steer_bias: bool,
    /// Number of the model's parameters (the extra states' initial values
    /// follow them in a simulation's parameter vector).
    model_parameters: usize,
    /// Simulations run so far (a simulation in dual numbers counts as one).
    pub(super) simulations: AtomicUsize,
}

/// The simulated channels of a segment and their derivatives along the
/// directions (one vector per direction, the channels concatenated as in
/// the residuals), or `None` where forward sensitivities do not apply.
type SensitivityFn =
    fn(&[f64], &Segment, &[f64; NUISANCE], &SimOptions, &Directions, usize) -> Option<(Sim, Vec<Vec<f64>>)>;

/// Simulated channels at the segment's sample times.
pub struct Sim {
    pub roll: Vec<f64>,
    pub steer: Vec<f64>,
    pub speed: Vec<f64>,
}

/// Linear interpolation of samples (a dual number's derivatives
/// interpolated alike), holding the last value after a stop (a fall ends
/// the simulation).
fn interp<T: Carried>(ts: &[f64], xs: &[T], t: f64) -> T {
    if ts.is_empty() {
        return T::cst(f64::NAN);
    }
    let Ok(v) = interpolate(ts, t, |k| Ok::<T, std::convert::Infallible>(xs[k]));
    v
}

fn simulate_segment<M: MultibodyModel>(
    param: &[f64],
    seg: &Segment,
    x0: &[f64; NUISANCE],
    opts: &SimOptions,
) -> Result<Sim, String> {
    let dt = sample_interval(seg);
    let opts = SimOptions {
        output_interval: dt,
        ..*opts
    };
    // The lean path (samples of the channels alone), else the full
    // simulation below.
    if let Some((sim, _)) = sampled::<M, f64>(param, seg, x0, &opts, &Directions::default()) {
        return Ok(sim);
    }
    // The explicit method failed on the lean path: a stiff candidate (a
    // steep friction law); the implicit one takes over.
    let stiff = SimOptions {
        method: Method::Radau5,
        ..opts
    };
    let ic = initial_conditions(x0, M::STATES.len());
    let param = with_extra_states::<M>(param, x0);
    let inputs = Inputs {
        feedback: seg.feedback.clone(),
        ..Inputs::default()
    };
    let sim = simulate::<M>(&param, &ic, &inputs, seg.duration() + dt, &stiff).map_err(|e| e.to_string())?;
    use crate::model::CoordinateRole as R;
    let roll = match seg.roll_channel {
        RollChannel::Angle => sim.require_coordinate(R::Roll, "identification residuals"),
        RollChannel::Rate => sim.rate_of(R::Roll).ok_or(crate::model::MissingRole {
            model: sim.model,
            kind: "coordinate",
            role: R::Roll.describe(),
            job: "identification residuals",
        }),
    }
    .map_err(|e| e.to_string())?;
    let steer = sim
        .require_coordinate(R::Steer, "identification residuals")
        .map_err(|e| e.to_string())?;
    Ok(Sim {
        roll: seg.t.iter().map(|&t| interp(&sim.t, &roll, t)).collect(),
        steer: seg.t.iter().map(|&t| interp(&sim.t, &steer, t)).collect(),
        speed: seg.speed_t.iter().map(|&t| interp(&sim.t, &sim.speed, t)).collect(),
    })
}

/// The simulation's output interval for a segment: its sample interval.
fn sample_interval(seg: &Segment) -> f64 {
    (seg.t.get(1).copied().unwrap_or(0.01) - seg.t[0]).max(1e-3)
}

/// The parameter vector with the extra states at the window start in its
/// tail (where the simulation reads their initial values).
fn with_extra_states<M: MultibodyModel>(param: &[f64], x0: &[f64; NUISANCE]) -> Vec<f64> {
    let np = M::PARAMETERS.len();
    let mut p = param[..np.min(param.len())].to_vec();
    p.extend_from_slice(&x0[INITIAL_MOTION..INITIAL_MOTION + M::STATES.len().min(EXTRA_STATES)]);
    p
}

/// The initial motion of a window start, with the rates of the model's
/// `extra` states.
fn initial_conditions(x0: &[f64; NUISANCE], extra: usize) -> InitialConditions {
    let mut state_rates = [0.0; EXTRA_STATES];
    let e = extra.min(EXTRA_STATES);
    state_rates[..e].copy_from_slice(&x0[INITIAL_MOTION + e..INITIAL_MOTION + 2 * e]);
    InitialConditions {
        roll: x0[0],
        steer: x0[1],
        roll_rate: x0[2],
        steer_rate: x0[3],
        speed: x0[4],
        yaw: 0.0,
        state_rates,
    }
}

/// A segment's channels at its sample times from [`response`] (DOP853), with
/// their derivatives along `dirs` when `T` is a dual number; `None` when the
/// explicit method fails (a stiff candidate).
fn sampled<M: MultibodyModel, T: Carried>(
    param: &[f64],
    seg: &Segment,
    x0: &[f64; NUISANCE],
    opts: &SimOptions,
    dirs: &Directions,
) -> Option<(Sim, Vec<Vec<f64>>)> {
    let dt = sample_interval(seg);
    let opts = SimOptions {
        output_interval: dt,
        ..*opts
    };
    let ic = initial_conditions(x0, M::STATES.len());
    let param = &with_extra_states::<M>(param, x0);
    let r = response_with::<M, T>(
        param,
        &ic,
        dirs,
        seg.duration() + dt,
        &opts,
        &seg.speed_t,
        seg.feedback.as_ref(),
    )
    .ok()?;
    let roll = match seg.roll_channel {
        RollChannel::Angle => &r.roll,
        RollChannel::Rate => &r.roll_rate,
    };
    let at = |xs: &[T], ts: &[f64]| -> Vec<T> { ts.iter().map(|&t| interp(&r.t, xs, t)).collect() };
    let roll = at(roll, &seg.t);
    let steer = at(&r.steer, &seg.t);
    let speed = r.speed;
    let columns: Vec<Vec<f64>> = (0..T::DIRECTIONS)
        .map(|d| {
            roll.iter()
                .chain(&steer)
                .chain(&speed)
                .map(|x| x.derivative(d))
                .collect()
        })
        .collect();
    let value = |xs: &[T]| xs.iter().map(|x| x.re()).collect();
    Some((
        Sim {
            roll: value(&roll),
            steer: value(&steer),
            speed: value(&speed),
        },
        columns,
    ))
}

/// The dual width of the sensitivities: a kick's initial state and one
/// effect parameter in one pass; more directions take more passes. One
/// width only, because every width compiles every model's equations again.
const WIDTH: usize = 6;

/// [`sampled`] with derivatives along `nd` directions, in passes of
/// [`WIDTH`] directions.
fn segment_sensitivities<M: MultibodyModel>(
    param: &[f64],
    seg: &Segment,
    x0: &[f64; NUISANCE],
    opts: &SimOptions,
    dirs: &Directions,
    nd: usize,
) -> Option<(Sim, Vec<Vec<f64>>)> {
    let mut columns = Vec::with_capacity(nd);
    let mut sim = None;
    for first in (0..nd.max(1)).step_by(WIDTH) {
        let inside = |d: usize| (first..first + WIDTH).contains(&d).then(|| d - first);
        let pass = Directions {
            parameters: dirs
                .parameters
                .iter()
                .filter_map(|&(i, d, c)| Some((i, inside(d)?, c)))
                .collect(),
            initial: dirs.initial.map(|d| d.and_then(inside)),
            state_rates: dirs.state_rates.map(|d| d.and_then(inside)),
        };
        let (s, c) = sampled::<M, Dual<WIDTH>>(param, seg, x0, opts, &pass)?;
        columns.extend(c.into_iter().take(nd - first));
        sim.get_or_insert(s);
    }
    Some((sim?, columns))
}

impl<'a> Setup<'a> {
    /// A setup for model `M` with the effect parameters of `candidates`
    /// active (their fixed values written into `base`).
    pub fn new<M: MultibodyModel>(
        base: &[f64],
        segments: &'a [Segment],
        weights: &[Weights],
        candidates: &[&Candidate],
    ) -> Result<Self, IdentifyError> {
        if M::STATES.len() > EXTRA_STATES {
            return Err(IdentifyError::TooManyStates {
                model: M::NAME,
                states: M::STATES.len(),
            });
        }
        let index = |s: &str| {
            M::PARAMETERS
                .iter()
                .position(|p| *p == s)
                .ok_or_else(|| IdentifyError::UnknownParameter {
                    model: M::NAME,
                    symbol: s.to_string(),
                })
        };
        let mut base = base.to_vec();
        let mut slots = Vec::new();
        let mut parameters = Vec::new();
        for c in candidates {
            for (s, v) in &c.fixed {
                base[index(s)?] = *v;
            }
            for p in &c.parameters {
                let slot = if p.moves.is_empty() {
                    let mut idx = vec![(index(&p.symbol)?, 1.0, 0.0)];
                    for t in &p.tied {
                        idx.push((index(t)?, 1.0, 0.0));
                    }
                    idx
                } else {
                    let origin = p.initial.unwrap_or(0.0);
                    let mut idx = Vec::with_capacity(p.moves.len());
                    for (s, c) in &p.moves {
                        let i = index(s)?;
                        idx.push((i, *c, base[i] - c * origin));
                    }
                    idx
                };
                slots.push(slot);
                parameters.push(p.clone());
            }
        }
        Ok(Setup {
            base,
            segments,
            weights: weights.to_vec(),
            options: SimOptions {
                rtol: 1e-8,
                atol: 1e-10,
                output_interval: 0.01,
                // The measured response decides; a fall in the simulation
                // only stops it (its last value is held).
                events: Events {
                    roll_limit: Some(1.2),
                    steer_limit: Some(1.45),
                },
                ..SimOptions::default()
            },
            slots,
            parameters,
            simulate: simulate_segment::<M>,
            sensitivities: segment_sensitivities::<M>,
            extra_states: M::STATES.len(),
            steer_bias: segments.iter().any(|s| s.steer_bias),
            model_parameters: M::PARAMETERS.len(),
            simulations: AtomicUsize::new(0),
        })
    }

    /// Nuisances per segment: the initial motion, the model's extra states
    /// and their rates, and the steer bias.
    pub(super) fn nuisance(&self) -> usize {
        INITIAL_MOTION + 2 * self.extra_states + self.steer_bias as usize
    }

    /// Where the segment's nuisances sit in a `[f64; NUISANCE]`, in the
    /// order of the Jacobian's columns: the initial motion, the extra
    /// states and their rates, then the steer bias ([`STEER_BIAS`]).
    pub(super) fn nuisance_index(&self, j: usize) -> usize {
        if j < INITIAL_MOTION + 2 * self.extra_states {
            j
        } else {
            STEER_BIAS
        }
    }

    /// Number of shared (effect) parameters.
    pub fn k(&self) -> usize {
        self.slots.len()
    }

    /// Parameter vector of `M` for effect values `g`.
    pub fn param(&self, g: &[f64]) -> Vec<f64> {
        let mut p = self.base.clone();
        for ((slot, &v), info) in self.slots.iter().zip(g).zip(&self.parameters) {
            let v = info.simulated(v);
            for &(i, c, offset) in slot {
                p[i] = offset + c * v;
            }
        }
        p
    }

    /// The value of effect parameter `j` at which the model is the base
    /// one (the base vector's value of its symbol; a derived correction's
    /// starting value).
    pub fn base_value(&self, j: usize) -> f64 {
        let (i, c, offset) = self.slots[j][0];
        (self.base[i] - offset) / c
    }

    /// Weighted residuals of one segment (roll, steer, speed blocks).
    pub fn residuals(&self, g: &[f64], i: usize, x0: &[f64; NUISANCE]) -> Result<Vec<f64>, String> {
        let seg = &self.segments[i];
        self.simulations.fetch_add(1, Ordering::Relaxed);
        let s = (self.simulate)(&self.param(g), seg, x0, &self.options)?;
        let w = self.weights[i];
        let mut r = Vec::with_capacity(seg.len());
        r.extend(seg.roll.iter().zip(&s.roll).map(|(m, p)| (m - p) / w.roll));
        let bias = x0[STEER_BIAS];
        r.extend(seg.steer.iter().zip(&s.steer).map(|(m, p)| (m - p - bias) / w.steer));
        r.extend(seg.speed.iter().zip(&s.speed).map(|(m, p)| (m - p) / w.speed));
        if r.iter().any(|x| !x.is_finite()) {
            return Err("non-finite residual".into());
        }
        Ok(r)
    }

    /// The Jacobian of segment `i`'s weighted residuals by forward
    /// sensitivities (one simulation in dual numbers): the columns of the
    /// effect parameters when `shared`, then those of its initial state
    /// when `nuisance`; `None` where they do not apply (a stiff candidate,
    /// more than 10 columns).
    pub(super) fn jacobian(
        &self,
        g: &[f64],
        i: usize,
        x0: &[f64; NUISANCE],
        shared: bool,
        nuisance: bool,
    ) -> Option<SegmentJacobian> {
        let seg = &self.segments[i];
        let k = if shared { self.k() } else { 0 };
        let nn = if nuisance { self.nuisance() } else { 0 };
        let mut dirs = Directions::default();
        if shared {
            for (j, (slot, info)) in self.slots.iter().zip(&self.parameters).enumerate() {
                // Beyond its floor or ceiling the parameter is simulated at
                // the bound: the response does not move with it.
                if info.held_at_bound(g[j]) {
                    continue;
                }
                dirs.parameters.extend(slot.iter().map(|&(p, c, _)| (p, j, c)));
            }
        }
        if nuisance {
            for (d, dir) in dirs.initial.iter_mut().enumerate() {
                *dir = Some(k + d);
            }
            // The extra states' initial values sit in the parameter
            // vector's tail; their rates are initial conditions.
            let extra = self.extra_states;
            for e in 0..extra {
                dirs.parameters
                    .push((self.model_parameters + e, k + INITIAL_MOTION + e, 1.0));
                dirs.state_rates[e] = Some(k + INITIAL_MOTION + extra + e);
            }
        }
        self.simulations.fetch_add(1, Ordering::Relaxed);
        let opts = self.sensitivity_options();
        // The steer bias is no simulation direction: its column is set
        // below.
        let simulated = k + nn - (nuisance && self.steer_bias) as usize;
        let (_, columns) = (self.sensitivities)(&self.param(g), seg, x0, &opts, &dirs, simulated)?;
        let w = self.weights[i];
        let (nr, ns) = (seg.roll.len(), seg.steer.len());
        let scale = |row: usize| {
            if row < nr {
                w.roll
            } else if row < nr + ns {
                w.steer
            } else {
                w.speed
            }
        };
        let rows = columns.first().map_or(seg.len(), Vec::len);
        let column = |d: usize| DVector::from_iterator(rows, columns[d].iter().enumerate().map(|(r, x)| -x / scale(r)));
        let mut a = DMatrix::zeros(rows, k);
        let mut b = DMatrix::zeros(rows, nn);
        for d in 0..k {
            a.set_column(d, &column(d));
        }
        for d in 0..simulated - k {
            b.set_column(d, &column(k + d));
        }
        if nuisance && self.steer_bias {
            // d r / d bias = -1 / w_steer on the steer rows.
            let mut bias = DVector::zeros(rows);
            for r in nr..(nr + ns).min(rows) {
                bias[r] = -1.0 / w.steer;
            }
            b.set_column(nn - 1, &bias);
        }
        let finite = a.iter().chain(b.iter()).all(|x| x.is_finite());
        finite.then_some(SegmentJacobian { a, b })
    }

    /// The integrator's options for the sensitivities: ten times the
    /// residuals' tolerances. The residuals define the objective, whose
    /// changes a fit compares to a part in a million, and keep the tight
    /// ones. The Jacobian only steers the steps and gives the standard
    /// errors and the score test, which need a few digits, not eight; and
    /// its simulation carries six derivative directions beside the state in
    /// the integrator's error control, which at the residuals' tolerance
    /// took more steps than the response needs (`bench --identify`: 6.1 s,
    /// 4.3 s at this one, with the same selection and digits).
    fn sensitivity_options(&self) -> SimOptions {
        SimOptions {
            rtol: 10.0 * self.options.rtol,
            atol: 10.0 * self.options.atol,
            ..self.options
        }
    }

    /// Simulated channels of one segment as the sensors read them (the
    /// steer with the kick's bias), for plots.
    pub fn simulated(&self, g: &[f64], seg: &Segment, x0: &[f64; NUISANCE]) -> Result<Sim, String> {
        let mut sim = (self.simulate)(&self.param(g), seg, x0, &self.options)?;
        for s in &mut sim.steer {
            *s += x0[STEER_BIAS];
        }
        Ok(sim)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_holds_the_last_value_after_a_stop() {
        let ts = [0.0, 1.0, 2.0];
        let xs = [0.0, 2.0, 4.0];
        assert_eq!(interp(&ts, &xs, 0.5), 1.0);
        assert_eq!(interp(&ts, &xs, 5.0), 4.0);
        assert_eq!(interp(&ts, &xs, -1.0), 0.0);
    }
}
