//! The run itself: [`simulate`] checks its options and inputs, splits the
//! time at kicks and pulse edges, applies each kick's impulse, integrates
//! each segment, samples every output and stops at the first roll or steer
//! event, located by regula falsi (`locate_event`).
//!
//! Kept apart from the integrators (`integrate.rs`), which it calls, and
//! from the initial state (`initial.rs`), which it starts from.

use super::initial::initial_state;
use super::integrate::{event_value, integrate, integrate_to, Samples, Sampling};
use super::rhs;
use super::{
    forward_speed, Evaluator, InitialConditions, Inputs, Kick, SimOptions, SimStats, SimulateError, Simulation,
    StopReason, MIN_RTOL,
};
use crate::model::MultibodyModel;

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
