//! Levenberg-Marquardt for the identification's fits, on the block-arrow
//! structure of [`Normal`]: every kick's initial state beside the shared
//! effect parameters. With no effect parameter free, each kick is fitted on
//! its own (and a falling kick also from its measured speed); with both
//! free, joint steps while they are accepted, then steps over the effect
//! parameters' profile. Parameters on a floor or ceiling are held there
//! while the data pull them outward (projected Levenberg-Marquardt), and a
//! trial whose own dissipative parameter is settled on its floor ends.

use super::normal::{Normal, SegmentJacobian};
use super::nuisance::SPEED;
use super::problem::{Free, Problem};
use super::{Bound, EffectParameter, NUISANCE};
use rayon::prelude::*;

/// Levenberg-Marquardt on the block-arrow problem (see [`Normal`]):
/// Marquardt's damping of the normal equations, the damping lowered after
/// a step that lowers the cost and raised until one does. It stops when an
/// accepted step changes the cost or the parameters (on their scales) by
/// less than 1e-6 relative (the simulations are accurate to about 1e-8, and
/// the parameters' uncertainty is far larger than what further iterations
/// would change), or after `patience` times the parameters of one segment
/// (plus one) residual evaluations.
///
/// With no effect parameter free the segments are independent problems,
/// and each is fitted on its own ([`fit_each_segment`]): its own damping,
/// convergence test and budget.
///
/// With effect parameters and the segments' states free together, the
/// joint steps are taken while they are accepted ([`joint_lm`]); at the
/// first refused one the fit goes on over the effect parameters' profile
/// ([`profiled_lm`]: each segment's state fitted on its own at every trial
/// value), where joint steps under one damping crawled.
///
/// A trial fit also ends when one of its own dissipative parameters
/// (`settled_on_floor`) has been held on its floor, the data pulling it
/// below, through [`SETTLED_STEPS`] accepted steps in a row that each
/// lowered the cost by less than [`SLOW_STEP`] relative: the trial's verdict
/// is then settled (a dissipative parameter on its floor is not physics, and
/// a trial that is not physical is never added to the model, so nothing is
/// built on the unconverged rest). Such a fit used to crawl to its budget:
/// the tyre candidate's relaxation length on its 1 cm floor, with stiff
/// lagged force states, spent 911 of an identification's 1240 s.
pub(super) fn lm_fit<'s, 'a>(mut p: Problem<'s, 'a>, patience: usize) -> Problem<'s, 'a> {
    let k = p.k_packed();
    if p.n_free() == 0 {
        return p;
    }
    // With no shared parameter free the problem separates: each segment's
    // initial state is its own least-squares problem. Fitted together under
    // one damping and one accept-or-reject, the segment the model fits
    // worst (a kick below the weave speed, its fall sensitive to the start)
    // held every other one to its short steps, and the fit ran out of
    // budget unconverged (the base fit of the oracle's steer_damping_small:
    // 110 of 112 evaluations, two kicks holding 95 % of the cost). Apart,
    // each segment gets its own damping, convergence test and budget, and
    // the minimum is the same.
    if k == 0 {
        let from_measured_speed = p.from_measured_speed;
        fit_each_segment_from(&mut p, patience, from_measured_speed);
        return p;
    }
    let profile_when_refused = p.free == Free::All && p.segs.len() > 1;
    let mut state = LmState::new(&p, patience);
    if joint_lm(&mut p, &mut state, profile_when_refused) == JointEnd::Refused {
        profiled_lm(&mut p, patience, &mut state);
    }
    p
}

/// Convergence tolerance of the fits: an accepted step that changes the
/// cost or the parameters (on their scales) by less than this, relative,
/// ends a fit (the simulations are accurate to about 1e-8, and the
/// parameters' uncertainty is far larger than what further iterations
/// would change).
const TOL: f64 = 1e-6;

/// What carries from the joint iterations into the profiled ones.
struct LmState {
    lambda: f64,
    settling: FloorSettling,
    /// Residual evaluations spent, in simulations of the whole problem (a
    /// profiled trial's fits of the segments one by one count as their
    /// simulations over the number of segments).
    evals: usize,
    /// The fit's budget of them: `patience` times the free parameters of
    /// the effect and of one segment (plus one), four times over. The
    /// profiled iterations share it with the joint ones, so that going on
    /// over the profile never spends more simulations than joint steps
    /// could have.
    budget: usize,
}

impl LmState {
    fn new(p: &Problem<'_, '_>, patience: usize) -> Self {
        let k = p.k_packed();
        LmState {
            lambda: 1e-3,
            settling: FloorSettling::default(),
            evals: 1,
            budget: patience.max(1) * (k + p.setup.nuisance() + 1) * 4,
        }
    }
}

/// How the joint iterations ended.
#[derive(PartialEq)]
enum JointEnd {
    /// Converged, settled, out of budget, or not simulable: the fit ends.
    Done,
    /// A step was refused, and the fit goes on profiled.
    Refused,
}

/// The cost of the problem at its current point: the weighted squares of
/// every segment's residuals and the priors' penalty.
fn cost(p: &Problem<'_, '_>) -> Option<f64> {
    let r = p.all_residuals()?;
    Some(r.iter().flatten().map(|x| x * x).sum::<f64>() + p.prior_penalty())
}

/// The prior rows of one iteration at the packed point `x`, with a stiff
/// row for each parameter held on its bound (the active set), and whether
/// one of the trial's own dissipative parameters is among those held on
/// their floor.
///
/// A parameter on its floor or ceiling whose descent direction points
/// beyond it is held there for the iteration, so the other parameters take
/// a full step rather than one computed as if it could move and then cut
/// by projection. The gradient is needed only for parameters on a bound
/// (most fits have none): it is not computed for the others.
fn active_rows(
    p: &Problem<'_, '_>,
    blocks: &[SegmentJacobian],
    res: &[Vec<f64>],
    x: &[f64],
    k: usize,
) -> (Vec<(usize, f64, f64)>, bool) {
    let mut prior = p.prior_normal_rows();
    let descent: Vec<f64> = (0..k)
        .map(|j| {
            if p.setup.parameters[j].on_bound(x[j]).is_none() {
                return 0.0;
            }
            let data: f64 = blocks
                .iter()
                .zip(res)
                .filter(|(b, _)| b.a.ncols() > j)
                .map(|(b, r)| b.a.column(j).iter().zip(r).map(|(a, r)| a * r).sum::<f64>())
                .sum();
            let priors: f64 = prior.iter().filter(|row| row.0 == j).map(|&(_, sd, r)| r / sd).sum();
            -(data + priors)
        })
        .collect();
    let held = held_on_bound(&p.setup.parameters[..k], &x[..k], &descent);
    let on_floor = held.iter().any(|j| {
        p.settled_on_floor.contains(j) && matches!(p.setup.parameters[*j].on_bound(x[*j]), Some(Bound::Floor(_)))
    });
    for j in held {
        prior.push((j, 1e-9 * p.setup.parameters[j].scale, 0.0));
    }
    (prior, on_floor)
}

/// `x + dx`, with the first `k` (shared) values beyond a parameter's floor
/// or ceiling projected back onto it (projected Levenberg-Marquardt): the
/// parameter stays where the response still moves with it, so a later step
/// can bring it back inside.
fn projected(p: &Problem<'_, '_>, x: &[f64], dx: &[f64], k: usize) -> Vec<f64> {
    let mut trial: Vec<f64> = x.iter().zip(dx).map(|(a, b)| a + b).collect();
    for (t, q) in trial.iter_mut().zip(&p.setup.parameters).take(k) {
        *t = q.simulated(*t);
    }
    trial
}

/// Length of `d` on the parameters' `scales`.
fn scaled_norm(d: &[f64], scales: &[f64]) -> f64 {
    d.iter().zip(scales).map(|(d, s)| (d / s).powi(2)).sum::<f64>().sqrt()
}

/// Levenberg-Marquardt on the whole problem at once: every free value in
/// one step, one damping, one accept-or-reject. With `stop_when_refused`,
/// it hands over to [`profiled_lm`] at the first refused step.
fn joint_lm(p: &mut Problem<'_, '_>, state: &mut LmState, stop_when_refused: bool) -> JointEnd {
    let k = p.k_packed();
    let Some(mut c) = cost(p) else { return JointEnd::Done };
    let scales = p.scales();
    while state.evals < state.budget {
        let (Some(blocks), Some(res)) = (p.jacobian_blocks(), p.all_residuals()) else {
            return JointEnd::Done;
        };
        let x = p.pack();
        let (prior, on_floor) = active_rows(p, &blocks, &res, &x, k);
        loop {
            let step = Normal::new(&blocks, &res, &prior, k, state.lambda).and_then(|n| n.step());
            let Some(dx) = step.filter(|d| d.iter().all(|v| v.is_finite())) else {
                state.lambda *= 10.0;
                if state.lambda > 1e12 {
                    return JointEnd::Done;
                }
                continue;
            };
            let trial = projected(p, &x, &dx, k);
            let dx: Vec<f64> = trial.iter().zip(&x).map(|(t, a)| t - a).collect();
            p.unpack(&trial);
            state.evals += 1;
            match cost(p) {
                Some(ct) if ct < c => {
                    let df = (c - ct) / c.max(f64::MIN_POSITIVE);
                    let dn = scaled_norm(&dx, &scales);
                    let xn = scaled_norm(&x, &scales);
                    c = ct;
                    state.lambda = (state.lambda / 3.0).max(1e-12);
                    if df <= TOL || dn <= TOL * (xn + TOL) || state.settling.settled_after(on_floor, df) {
                        return JointEnd::Done;
                    }
                    break;
                }
                _ => {
                    p.unpack(&x);
                    if stop_when_refused {
                        return JointEnd::Refused;
                    }
                    state.lambda *= 4.0;
                    if state.lambda > 1e12 || state.evals >= state.budget {
                        return JointEnd::Done;
                    }
                }
            }
        }
    }
    JointEnd::Done
}

/// Levenberg-Marquardt on the profile of the shared parameters: at every
/// trial value of them, each segment's initial state is fitted again on
/// its own ([`fit_each_segment`], from the step's linear prediction), and
/// the trial is judged by the cost there. The step is Kaufman's
/// variable-projection step: the segments' blocks eliminated undamped, the
/// damping on the shared parameters alone.
///
/// Why: joint steps crawl once the effect parameters and the kicks' initial
/// states trade along a narrow curved valley, one damping holding every
/// kick to the steps of the one the linearization fits worst. On the
/// oracle's `steer_damping_small`, rolling resistance's joint fit was
/// refused eight times after three steps and then spent over a hundred
/// evaluations, each accepted step lowering the cost by about 1e-5 of
/// itself, and ended at `Crr` = 0.0236 with cost 6,968, where each kick's
/// states fitted again at that same `Crr` gave 6,945 and the profile's
/// minimum was 6,927 near `Crr` = 0.0254. Each profiled trial costs a
/// short fit per kick, so the joint steps are taken while they are
/// accepted (most fits converge so), the profile takes over at the first
/// refusal, and its trials share the joint fit's budget of simulations
/// ([`LmState::budget`]): a fit started where no value of the effect's
/// parameters fits the kicks (a discovered Coulomb torque at a smoothing
/// rate of 4 rad/s on a set with a higher front mass centre, its cost 150
/// times the model's) spent a minute refitting its kicks on a separate
/// budget of trials.
fn profiled_lm(p: &mut Problem<'_, '_>, patience: usize, state: &mut LmState) {
    // The segments' blocks are eliminated with a damping far below any the
    // joint fit uses, only to keep an ill-determined initial state (a
    // kick's steer offset on a short window) from a singular block.
    const SEGMENT_DAMPING: f64 = 1e-9;
    // The profile is known only as well as the segments' own fits converge
    // (each to TOL of its cost, from a start that differs from trial to
    // trial): a trial within ten times that of the current cost, lower or
    // higher, ends the fit, where a tighter test refused step after step
    // on the noise of the inner fits (the friction law with rolling
    // resistance on the oracle's steer_friction_large: 26 trials within
    // 4e-6 of the cost, to the end of the budget).
    const PROFILE_TOL: f64 = 10.0 * TOL;
    // A profiled trial costs a fit of every segment, where a refused joint
    // step costs one simulation of each: after a refusal the damping rises
    // at once to where it shortens the step (0.1 of the curvature, then
    // ten times more each refusal), and three refusals in a row, the last
    // at about a tenth of the Gauss-Newton step, end the fit. Raised by
    // four from the small damping that accepted steps leave, it took a
    // dozen refused trials to shorten the step at all (a friction law
    // whose torque the control set's data hold at zero: 20 refused trials
    // of some 200 simulations each, within 1.3e-4 of the cost).
    const REFUSALS: usize = 3;
    let mut refused_in_row = 0;
    let k = p.setup.k();
    let segments = p.segs.len().max(1);
    let spend = |state: &mut LmState, inner: usize| state.evals += inner.div_ceil(segments);
    spend(state, fit_each_segment(p, patience));
    let Some(mut c) = cost(p) else { return };
    let scales = p.scales();
    'outer: while state.evals < state.budget {
        let (Some(blocks), Some(res)) = (p.jacobian_blocks(), p.all_residuals()) else {
            return;
        };
        let x = p.pack();
        let (prior, on_floor) = active_rows(p, &blocks, &res, &x, k);
        loop {
            let step = Normal::damped(&blocks, &res, &prior, k, state.lambda, SEGMENT_DAMPING).and_then(|n| n.step());
            let Some(dx) = step.filter(|d| d.iter().all(|v| v.is_finite())) else {
                state.lambda *= 10.0;
                if state.lambda > 1e12 {
                    break 'outer;
                }
                continue;
            };
            let trial = projected(p, &x, &dx, k);
            p.unpack(&trial);
            spend(state, fit_each_segment(p, patience));
            match cost(p) {
                Some(ct) if ct < c => {
                    let df = (c - ct) / c.max(f64::MIN_POSITIVE);
                    let dg: Vec<f64> = p.g.iter().zip(&x).map(|(t, a)| t - a).collect();
                    let dn = scaled_norm(&dg, &scales[..k]);
                    let xn = scaled_norm(&x[..k], &scales[..k]);
                    c = ct;
                    refused_in_row = 0;
                    state.lambda = (state.lambda / 3.0).max(1e-12);
                    if df <= PROFILE_TOL || dn <= TOL * (xn + TOL) || state.settling.settled_after(on_floor, df) {
                        break 'outer;
                    }
                    break;
                }
                refused => {
                    p.unpack(&x);
                    refused_in_row += 1;
                    if refused.is_some_and(|ct| ct - c <= PROFILE_TOL * c) || refused_in_row >= REFUSALS {
                        break 'outer;
                    }
                    state.lambda = (state.lambda * 10.0).max(0.1);
                    if state.evals >= state.budget {
                        break 'outer;
                    }
                }
            }
        }
    }
}

/// Fit each segment's initial state on its own (in parallel) with the
/// effect parameters held at `p.g`, starting from `p.x0`.
///
/// With `from_measured_speed`, each segment is also fitted from its
/// measured initial speed, held while the other states are fitted and then
/// freed, and the better of the two fits is kept. A kick below the weave
/// speed falls within its window, and its fit has more than one minimum:
/// from the first samples' state the fit can trade the speed for the
/// fall's timing and stop far from it. On the oracle's control_a, run08
/// (kicked at 3.48 m/s) was fitted at 4.22 m/s with a weighted error of
/// 1,103, a sixth of the set's; started near the measured speed the same
/// model fits it at 3.40 m/s with 4. Every candidate's fit starts from the
/// base model's states, so a kick left in the wrong minimum there is a
/// gain for whichever candidate's path happens to leave it: a cause that
/// is not one.
///
/// Returns the residual evaluations spent, summed over the segments (each
/// a simulation of one segment).
fn fit_each_segment_from(p: &mut Problem<'_, '_>, patience: usize, from_measured_speed: bool) -> usize {
    let fitted: Vec<(usize, [f64; NUISANCE], usize)> = p
        .segs
        .par_iter()
        .map(|&s| {
            let one = Problem::new(p.setup, vec![s], Free::Nuisance, p.g.clone(), p.x0.clone());
            let (here, mut evals) = fit_alone(one, patience);
            if !from_measured_speed || p.setup.nuisance() <= SPEED {
                return (s, here.x0[s], evals);
            }
            let mut start = p.x0.clone();
            start[s][SPEED] = p.setup.segments[s].initial[SPEED];
            let mut anchored = Problem::new(p.setup, vec![s], Free::Nuisance, p.g.clone(), start);
            anchored.anchor_speed = true;
            let (anchored, anchored_evals) = fit_alone(anchored, patience);
            let (freed, freed_evals) = fit_alone(
                Problem::new(p.setup, vec![s], Free::Nuisance, p.g.clone(), anchored.x0),
                patience,
            );
            evals += anchored_evals + freed_evals;
            let better = match (cost(&here), cost(&freed)) {
                (Some(a), Some(b)) if b < a => freed.x0[s],
                (None, Some(_)) => freed.x0[s],
                _ => here.x0[s],
            };
            (s, better, evals)
        })
        .collect();
    let mut evals = 0;
    for (s, x, spent) in fitted {
        p.x0[s] = x;
        evals += spent;
    }
    evals
}

/// One segment's initial state fitted by joint steps (its problem has no
/// shared parameter, so nothing to profile), and the residual evaluations
/// it took.
fn fit_alone<'s, 'a>(mut one: Problem<'s, 'a>, patience: usize) -> (Problem<'s, 'a>, usize) {
    let mut state = LmState::new(&one, patience);
    joint_lm(&mut one, &mut state, false);
    (one, state.evals)
}

/// [`fit_each_segment_from`] the current states alone.
fn fit_each_segment(p: &mut Problem<'_, '_>, patience: usize) -> usize {
    fit_each_segment_from(p, patience, false)
}

/// Accepted steps in a row, each lowering the cost by less than
/// [`SLOW_STEP`] with a trial's own dissipative parameter held on its floor,
/// that settle the trial's verdict (see [`lm_fit`]).
const SETTLED_STEPS: usize = 3;
/// Relative cost decrease below which an accepted step is slow: a thousand
/// times the fits' convergence tolerance.
const SLOW_STEP: f64 = 1e-3;

/// The count behind a trial's verdict settled on a floor (see [`lm_fit`]).
#[derive(Default)]
struct FloorSettling {
    /// Accepted slow steps in a row with a settling parameter held.
    steps: usize,
}

impl FloorSettling {
    /// After an accepted step that lowered the cost by `df` (relative),
    /// taken with (`on_floor`) or without one of the trial's own
    /// dissipative parameters held on its floor: whether the fit ends.
    fn settled_after(&mut self, on_floor: bool, df: f64) -> bool {
        self.steps = if on_floor && df < SLOW_STEP { self.steps + 1 } else { 0 };
        self.steps >= SETTLED_STEPS
    }
}

/// The parameters to hold on their bound for one iteration: those on a
/// floor or ceiling whose steepest-descent direction `descent` (minus the
/// gradient of the cost) points beyond it. The test is the gradient's sign
/// (projected Newton), not the Gauss-Newton step's, so a parameter the
/// data pull back inside is released at the next iteration even when a
/// correlated parameter would make the full step point outward.
fn held_on_bound(parameters: &[EffectParameter], x: &[f64], descent: &[f64]) -> Vec<usize> {
    parameters
        .iter()
        .zip(x.iter().zip(descent))
        .enumerate()
        .filter(|(_, (q, (&v, &d)))| match q.on_bound(v) {
            Some(Bound::Floor(_)) => d < 0.0,
            Some(Bound::Ceiling(_)) => d > 0.0,
            None => false,
        })
        .map(|(j, _)| j)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounded(symbol: &str) -> EffectParameter {
        let mut q = super::super::candidate::smoothing_rate(Some(0.002), Some(0.1));
        q.symbol = symbol.into();
        q
    }

    #[test]
    fn a_parameter_on_its_bound_is_held_only_while_the_data_pull_it_outward() {
        let q = vec![bounded("a"), bounded("b"), bounded("c"), bounded("d"), bounded("e")];
        // a: on the ceiling, pulled up (outward): held. b: on the ceiling,
        // pulled down (inward): released. c: on the floor, pulled down:
        // held. d: on the floor, pulled up: released. e: inside: free.
        let x = [0.1, 0.1, 0.002, 0.002, 0.03];
        let descent = [1.0, -1.0, -1.0, 1.0, 1.0];
        assert_eq!(held_on_bound(&q, &x, &descent), vec![0, 2]);
        // Unbounded parameters are never held.
        let mut free = bounded("f");
        free.lower = None;
        free.upper = None;
        assert!(held_on_bound(&[free], &[0.1], &[1.0]).is_empty());
    }

    #[test]
    fn a_trial_settles_on_its_floor_only_after_slow_steps_in_a_row_held_there() {
        let slow = SLOW_STEP / 2.0;
        let fast = SLOW_STEP * 2.0;
        let mut s = FloorSettling::default();
        assert!(!s.settled_after(true, slow));
        assert!(!s.settled_after(true, slow));
        assert!(s.settled_after(true, slow), "three slow steps held on the floor");
        // A fast step, or a step with the parameter released, starts the count again.
        let mut s = FloorSettling::default();
        for (on_floor, df) in [
            (true, slow),
            (true, slow),
            (true, fast),
            (true, slow),
            (false, slow),
            (true, slow),
        ] {
            assert!(!s.settled_after(on_floor, df), "after ({on_floor}, {df})");
        }
        assert!(!s.settled_after(true, slow));
        assert!(s.settled_after(true, slow));
    }
}
