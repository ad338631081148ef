//! Fitting one candidate model: Levenberg-Marquardt over the effect
//! parameters and every kick's nuisances together (a `Problem` says which
//! are free), the residual statistics of each kick ([`SegmentError`]), the
//! standard errors inflated for autocorrelated residuals, and the check that
//! dissipative parameters stay positive. The held-out half of judging a fit
//! is [`cross_validate`](super::cross_validate).

use super::levenberg_marquardt::{lm_fit, SPEED};
use super::normal::{Normal, SegmentJacobian};
use super::nuisance::nuisance_scale;
use super::{bic, cross_validate, EffectParameter, IdentifyError, Segment, Setup, Weights, NUISANCE};
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;
use std::sync::atomic::Ordering;
use std::sync::Mutex;

/// Which parameters a fit frees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Free {
    /// Effect parameters and every segment's initial state.
    All,
    /// Effect parameters only (initial states held).
    Shared,
    /// Initial states only (effect parameters held).
    Nuisance,
}

/// One fit: the segments taking part, which parameters are free, and the
/// current effect values and initial states.
pub(super) struct Problem<'s, 'a> {
    pub(super) setup: &'s Setup<'a>,
    /// Segments taking part.
    pub(super) segs: Vec<usize>,
    pub(super) free: Free,
    pub(super) g: Vec<f64>,
    pub(super) x0: Vec<[f64; NUISANCE]>,
    /// Last residuals per segment, for the Jacobian at the same point.
    pub(super) cache: Mutex<Option<(Vec<f64>, Vec<Vec<f64>>)>>,
    /// Effect parameters (indices into `g`) whose being held on their floor
    /// settles the fit's verdict: a trial's own dissipative parameters
    /// (see [`lm_fit`]). Empty for every other fit.
    pub(super) settled_on_floor: Vec<usize>,
    /// Hold each segment's initial speed where it is (its Jacobian column
    /// zeroed, so a step never moves it): the first stage of a fit from
    /// the measured speed (see [`fit_each_segment`]).
    pub(super) anchor_speed: bool,
    /// With no effect parameter free: also fit each segment from its
    /// measured initial speed and keep the better fit (see
    /// [`fit_each_segment_from`](super::levenberg_marquardt)). Set for the
    /// fits whose states every later fit starts from (a model's own fit),
    /// not for the held-out kicks of a cross-validation, which start from
    /// those.
    pub(super) from_measured_speed: bool,
}

impl<'s, 'a> Problem<'s, 'a> {
    /// The problem of `setup` over the segments `segs`, with `free`
    /// parameters starting from effect values `g` and window starts `x0`.
    pub(super) fn new(
        setup: &'s Setup<'a>,
        segs: Vec<usize>,
        free: Free,
        g: Vec<f64>,
        x0: Vec<[f64; NUISANCE]>,
    ) -> Self {
        Problem {
            setup,
            segs,
            free,
            g,
            x0,
            cache: Mutex::new(None),
            settled_on_floor: Vec::new(),
            anchor_speed: false,
            from_measured_speed: false,
        }
    }
}

impl Problem<'_, '_> {
    /// Effect parameters at the head of the packed vector: all of them,
    /// unless only the initial states are free.
    pub(super) fn k_packed(&self) -> usize {
        if self.free == Free::Nuisance {
            0
        } else {
            self.setup.k()
        }
    }
    pub(super) fn n_free(&self) -> usize {
        match self.free {
            Free::All => self.setup.k() + self.setup.nuisance() * self.segs.len(),
            Free::Shared => self.setup.k(),
            Free::Nuisance => self.setup.nuisance() * self.segs.len(),
        }
    }
    pub(super) fn pack(&self) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.n_free());
        if self.free != Free::Nuisance {
            x.extend(&self.g);
        }
        if self.free != Free::Shared {
            for &s in &self.segs {
                x.extend((0..self.setup.nuisance()).map(|j| self.x0[s][self.setup.nuisance_index(j)]));
            }
        }
        x
    }
    pub(super) fn unpack(&mut self, x: &[f64]) {
        let mut i = 0;
        if self.free != Free::Nuisance {
            let k = self.setup.k();
            self.g.copy_from_slice(&x[..k]);
            i = k;
        }
        if self.free != Free::Shared {
            for &s in &self.segs {
                let nn = self.setup.nuisance();
                for j in 0..nn {
                    self.x0[s][self.setup.nuisance_index(j)] = x[i + j];
                }
                i += nn;
            }
        }
    }
    /// The parameters with a prior while they are free: `(column, sd)`.
    pub(super) fn prior_rows(&self) -> Vec<(usize, f64)> {
        if self.free == Free::Nuisance {
            return Vec::new();
        }
        self.setup
            .parameters
            .iter()
            .enumerate()
            .filter_map(|(j, p)| p.prior.map(|(_, sd)| (j, sd)))
            .collect()
    }
    /// Residuals of the priors (after the data's).
    pub(super) fn prior_residuals(&self) -> Vec<f64> {
        self.prior_rows()
            .into_iter()
            .map(|(j, sd)| {
                let mean = self.setup.parameters[j].prior.map_or(0.0, |(m, _)| m);
                (self.g[j] - mean) / sd
            })
            .collect()
    }
    /// The priors' penalty: Huber's, `r^2` within `gross_beyond` (c) of
    /// the mean and `2 c |r| - c^2` beyond ([`EffectParameter::gross_beyond`]).
    pub(super) fn prior_penalty(&self) -> f64 {
        self.prior_rows()
            .into_iter()
            .zip(self.prior_residuals())
            .map(|((j, _), r)| huber(r, self.setup.parameters[j].gross_beyond))
            .sum()
    }
    /// The priors as rows of the normal equations `(column, sd, residual)`,
    /// with Huber's weight `min(1, c / |r|)` folded into the standard
    /// deviation and the residual (iteratively reweighted: the step is
    /// Gauss-Newton on the penalty's quadratic model at the current value).
    pub(super) fn prior_normal_rows(&self) -> Vec<(usize, f64, f64)> {
        self.prior_rows()
            .into_iter()
            .zip(self.prior_residuals())
            .map(|((j, sd), r)| {
                let c = self.setup.parameters[j].gross_beyond;
                let w = if r.abs() > c { (c / r.abs()).sqrt() } else { 1.0 };
                (j, sd / w, r * w)
            })
            .collect()
    }
    pub(super) fn all_residuals(&self) -> Option<Vec<Vec<f64>>> {
        let x = self.pack();
        if let Some((cx, r)) = self.cache.lock().ok()?.as_ref() {
            if *cx == x {
                return Some(r.clone());
            }
        }
        let r: Option<Vec<Vec<f64>>> = self
            .segs
            .par_iter()
            .map(|&s| self.setup.residuals(&self.g, s, &self.x0[s]).ok())
            .collect();
        let r = r?;
        *self.cache.lock().ok()? = Some((x, r.clone()));
        Some(r)
    }
}

impl Problem<'_, '_> {
    /// Jacobian blocks at the current point, one per segment taking part:
    /// by forward sensitivities (one simulation in dual numbers per
    /// segment), else by forward differences (a column costs one
    /// simulation of one segment).
    pub(super) fn jacobian_blocks(&self) -> Option<Vec<SegmentJacobian>> {
        let base = self.all_residuals()?;
        let k = self.k_packed();
        let nn = if self.free == Free::Shared {
            0
        } else {
            self.setup.nuisance()
        };
        let (shared, nuisance) = (k > 0, nn > 0);
        let exact: Vec<Option<SegmentJacobian>> = self
            .segs
            .par_iter()
            .zip(&base)
            .map(|(&s, r)| {
                self.setup
                    .jacobian(&self.g, s, &self.x0[s], shared, nuisance)
                    .filter(|j| j.a.nrows() == r.len() && j.b.nrows() == r.len())
            })
            .collect();
        // Columns by differences where the sensitivities did not apply:
        // (segment position, shared parameter or nuisance j).
        let mut tasks = Vec::new();
        for p in (0..self.segs.len()).filter(|&p| exact[p].is_none()) {
            tasks.extend((0..k).map(|j| (p, false, j)));
            tasks.extend((0..nn).map(|j| (p, true, j)));
        }
        let cols: Option<Vec<(usize, bool, usize, Vec<f64>)>> = tasks
            .par_iter()
            .map(|&(p, nuisance, j)| {
                let s = self.segs[p];
                let mut g = self.g.clone();
                let mut x0 = self.x0[s];
                let h = if nuisance {
                    let at = self.setup.nuisance_index(j);
                    let h = 1e-3 * nuisance_scale(at, self.setup.extra_states).max(x0[at].abs());
                    x0[at] += h;
                    h
                } else {
                    let h = 1e-3 * self.setup.parameters[j].scale.max(g[j].abs());
                    g[j] += h;
                    h
                };
                let r = self.setup.residuals(&g, s, &x0).ok()?;
                Some((
                    p,
                    nuisance,
                    j,
                    r.iter().zip(&base[p]).map(|(a, b)| (a - b) / h).collect(),
                ))
            })
            .collect();
        let mut blocks: Vec<SegmentJacobian> = base
            .iter()
            .zip(exact)
            .map(|(r, e)| {
                e.unwrap_or_else(|| SegmentJacobian {
                    a: DMatrix::zeros(r.len(), k),
                    b: DMatrix::zeros(r.len(), nn),
                })
            })
            .collect();
        for (p, nuisance, j, d) in cols? {
            let m = if nuisance { &mut blocks[p].b } else { &mut blocks[p].a };
            m.column_mut(j).copy_from_slice(&d);
        }
        if self.anchor_speed && nn > SPEED {
            for b in &mut blocks {
                b.b.column_mut(SPEED).fill(0.0);
            }
        }
        Some(blocks)
    }

    /// Scale of each free parameter in packed order (steps are measured
    /// against it).
    pub(super) fn scales(&self) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.n_free());
        if self.free != Free::Nuisance {
            x.extend(self.setup.parameters.iter().map(|p| p.scale));
        }
        if self.free != Free::Shared {
            for _ in &self.segs {
                x.extend(
                    (0..self.setup.nuisance())
                        .map(|j| nuisance_scale(self.setup.nuisance_index(j), self.setup.extra_states)),
                );
            }
        }
        x
    }
}

/// Residual statistics of one segment, unweighted.
#[derive(Clone, Debug, Default, Serialize)]
pub struct SegmentError {
    /// RMS roll residual (rad).
    pub roll_rms: f64,
    /// RMS steer residual (rad).
    pub steer_rms: f64,
    /// RMS speed residual (m/s).
    pub speed_rms: f64,
    /// Lag-1 autocorrelation of the roll and steer residuals.
    pub rho: f64,
    #[serde(skip)]
    pub channel_ss: [f64; 3],
    #[serde(skip)]
    pub channel_n: [usize; 3],
}

impl SegmentError {
    pub(super) fn of(r: &[f64], seg: &Segment, w: Weights) -> SegmentError {
        let n = seg.t.len();
        let (roll, rest) = r.split_at(n);
        let (steer, speed) = rest.split_at(n);
        let ss = |x: &[f64], s: f64| x.iter().map(|a| (a * s) * (a * s)).sum::<f64>();
        let channel_ss = [ss(roll, w.roll), ss(steer, w.steer), ss(speed, w.speed)];
        let channel_n = [n, n, speed.len()];
        let rms = |c: usize| (channel_ss[c] / channel_n[c].max(1) as f64).sqrt();
        let lag1 = |x: &[f64]| {
            let m = x.iter().sum::<f64>() / x.len().max(1) as f64;
            let num: f64 = x.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum();
            let den: f64 = x.iter().map(|a| (a - m) * (a - m)).sum();
            if den > 0.0 {
                (num / den).clamp(0.0, 0.999)
            } else {
                0.0
            }
        };
        SegmentError {
            roll_rms: rms(0),
            steer_rms: rms(1),
            speed_rms: rms(2),
            rho: 0.5 * (lag1(roll) + lag1(steer)),
            channel_ss,
            channel_n,
        }
    }
}

/// Result of fitting one candidate model.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateFit {
    /// Effect names in the model (empty: the base model).
    pub effects: Vec<String>,
    pub parameters: Vec<EffectParameter>,
    /// Fitted values and standard errors of the effect parameters.
    pub values: Vec<f64>,
    pub stderr: Vec<f64>,
    /// Fitted initial state of each segment.
    #[serde(skip)]
    pub nuisance: Vec<[f64; NUISANCE]>,
    /// Errors per segment at the fit.
    pub errors: Vec<SegmentError>,
    /// Errors per segment held out (cross-validation).
    pub held_out: Vec<SegmentError>,
    /// Effect values fitted without each fold (fold of each segment).
    #[serde(skip)]
    pub fold_values: Vec<Vec<f64>>,
    /// Bayesian information criterion with effective sample sizes.
    pub bic: f64,
    /// Cross-validated weighted error (mean squared weighted residual).
    pub cv: f64,
    /// Weighted sum of squares at the fit.
    pub chi2: f64,
    /// Simulations run for this candidate.
    pub simulations: usize,
    /// Whether every dissipative parameter is positive.
    pub physical: bool,
}

/// Options of identification.
#[derive(Clone, Debug)]
pub struct IdentifyOptions {
    /// Folds of the cross-validation (by run, see [`folds_by_run`](super::folds_by_run)).
    pub folds: usize,
    /// Largest number of effects and corrections added beside the speed
    /// loss (rolling resistance and drag, which do not count).
    pub max_effects: usize,
    /// LM evaluation budget (patience) per fit.
    pub patience: usize,
    /// Most candidates a step fits beyond its contenders (those the score
    /// test ranks close to the best, always fitted), in the order of their
    /// predicted gain: a compute budget (a fit of a hundred TU Delft kicks
    /// takes tens of seconds), never a verdict; the report lists the
    /// candidates it left unfitted.
    pub max_fits_per_step: usize,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        IdentifyOptions {
            folds: 4,
            max_effects: 3,
            patience: 4,
            max_fits_per_step: 8,
        }
    }
}

/// Fit a model with the setup's effect parameters free, starting from `g0`
/// and the initial states `x0`, then cross-validate it. `fold_of[s]` is the
/// fold of segment `s`.
pub fn fit_candidate(
    setup: &Setup<'_>,
    effects: Vec<String>,
    g0: &[f64],
    x0: &[[f64; NUISANCE]],
    fold_of: &[usize],
    opts: &IdentifyOptions,
    reference: Option<&CandidateFit>,
) -> Result<CandidateFit, IdentifyError> {
    fit_trial(setup, effects, g0, x0, fold_of, opts, reference, 0..0)
}

/// [`fit_candidate`] for a trial of the search: `own` are the indices of
/// the trial's own parameters (those after the current model's; empty for
/// any other fit), and a fit that holds one of its dissipative ones on its
/// floor while the cost no longer falls ends there, not physical (see
/// [`lm_fit`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_trial(
    setup: &Setup<'_>,
    effects: Vec<String>,
    g0: &[f64],
    x0: &[[f64; NUISANCE]],
    fold_of: &[usize],
    opts: &IdentifyOptions,
    reference: Option<&CandidateFit>,
    own: std::ops::Range<usize>,
) -> Result<CandidateFit, IdentifyError> {
    let nseg = setup.segments.len();
    if nseg == 0 {
        return Err(IdentifyError::NoData);
    }
    let sims_before = setup.simulations.load(Ordering::Relaxed);
    let all: Vec<usize> = (0..nseg).collect();
    // A fit where every segment's initial state moves: effect parameters
    // and states together (the base model: states alone).
    let free = if setup.k() == 0 { Free::Nuisance } else { Free::All };
    let mut problem = Problem::new(setup, all.clone(), free, g0.to_vec(), x0.to_vec());
    problem.from_measured_speed = true;
    problem.settled_on_floor = own
        .filter(|&j| setup.parameters.get(j).is_some_and(|q| q.dissipative))
        .collect();
    let full = lm_fit(problem, opts.patience);
    let simulations = || setup.simulations.load(Ordering::Relaxed) - sims_before;
    let res = full.all_residuals().ok_or_else(|| IdentifyError::Simulation {
        run: setup.segments[0].run.clone(),
        message: "the fitted model does not simulate every segment".into(),
    })?;
    let errors: Vec<SegmentError> = res
        .iter()
        .zip(setup.segments)
        .zip(&setup.weights)
        .map(|((r, s), w)| SegmentError::of(r, s, *w))
        .collect();
    let chi2: f64 = res.iter().flatten().map(|x| x * x).sum();
    // Values beyond a parameter's floor or ceiling were simulated at it.
    let g: Vec<f64> = full
        .g
        .iter()
        .zip(&setup.parameters)
        .map(|(&v, p)| p.simulated(v))
        .collect();
    let nuisance = full.x0.clone();

    // Standard errors of the effect parameters from the Jacobian at the
    // fit: the shared block of (J^T J)^-1 is the inverse of the reduced
    // matrix of the normal equations without damping.
    let mut stderr = vec![f64::NAN; setup.k()];
    if setup.k() > 0 {
        if let (Some(blocks), Some(res)) = (full.jacobian_blocks(), full.all_residuals()) {
            let n: usize = res.iter().map(Vec::len).sum::<usize>() + full.prior_rows().len();
            let p = full.n_free() as f64;
            let rho = errors.iter().map(|e| e.rho).sum::<f64>() / errors.len() as f64;
            let s2 = chi2 / (n as f64 - p).max(1.0) * (1.0 + rho) / (1.0 - rho);
            let prior: Vec<(usize, f64, f64)> = full
                .prior_normal_rows()
                .into_iter()
                .map(|(j, sd, _)| (j, sd, 0.0))
                .collect();
            if let Some(inv) = Normal::new(&blocks, &res, &prior, setup.k(), 0.0).and_then(|nm| nm.s.try_inverse()) {
                for (i, s) in stderr.iter_mut().enumerate() {
                    *s = (inv[(i, i)] * s2).sqrt();
                }
            }
        }
    }
    let physical = setup
        .parameters
        .iter()
        .zip(&full.g)
        .all(|(p, v)| !p.dissipative || *v > p.lower.unwrap_or(0.0));
    let mut fit = CandidateFit {
        effects,
        parameters: setup.parameters.clone(),
        values: g.clone(),
        stderr,
        nuisance: nuisance.clone(),
        errors,
        held_out: vec![SegmentError::default(); nseg],
        fold_values: Vec::new(),
        bic: f64::NAN,
        cv: f64::NAN,
        chi2,
        simulations: 0,
        physical,
    };
    // Cross-validation is the costly half: a candidate is cross-validated
    // apart ([`cross_validate`]), only when selection needs its held-out
    // error (not when the information criterion or physics rejects it).
    match reference {
        Some(r) => fit.bic = bic(&fit, r),
        None => cross_validate(setup, &mut fit, fold_of, opts),
    }
    fit.simulations = simulations();
    Ok(fit)
}

/// Overall RMS of a channel over segments (rad or m/s).
pub fn pooled_rms(errors: &[SegmentError], channel: usize) -> f64 {
    let (ss, n) = errors.iter().fold((0.0, 0usize), |(a, b), e| {
        (a + e.channel_ss[channel], b + e.channel_n[channel])
    });
    (ss / n.max(1) as f64).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_statistics_unweight_and_count_channels() {
        let t: Vec<f64> = (0..20).map(|k| k as f64 * 0.01).collect();
        let z = vec![0.0; 20];
        let s = Segment::new("r".into(), 0.0, t, z.clone(), z, vec![0.0], vec![5.0], None).unwrap();
        let w = Weights {
            roll: 0.1,
            steer: 0.2,
            speed: 0.5,
        };
        let mut r = vec![1.0; 20];
        r.extend(vec![2.0; 20]);
        r.push(4.0);
        let e = SegmentError::of(&r, &s, w);
        assert!((e.roll_rms - 0.1).abs() < 1e-12);
        assert!((e.steer_rms - 0.4).abs() < 1e-12);
        assert!((e.speed_rms - 2.0).abs() < 1e-12);
        assert_eq!(e.channel_n, [20, 20, 1]);
    }
}

/// Huber's penalty of a standardised residual `r` with its turn at `c`:
/// `r^2` within, `2 c |r| - c^2` beyond (continuous with its slope).
fn huber(r: f64, c: f64) -> f64 {
    if r.abs() <= c || !(c > 0.0) {
        r * r
    } else {
        2.0 * c * r.abs() - c * c
    }
}

#[cfg(test)]
mod prior_tests {
    use super::huber;

    #[test]
    fn the_prior_penalty_is_gaussian_within_its_turn_and_linear_beyond() {
        let c = 3.0;
        for r in [-2.9, -1.0, 0.0, 0.5, 3.0] {
            assert_eq!(huber(r, c), r * r);
        }
        // Continuous, with the Gaussian's slope at the turn (2 c), and
        // growing by 2 c per standard deviation beyond it.
        let e = 1e-7;
        assert!((huber(c + e, c) - huber(c - e, c)).abs() < 1e-5);
        assert!(((huber(c + 2.0 * e, c) - huber(c + e, c)) / e - 2.0 * c).abs() < 1e-4);
        assert!((huber(-8.0, c) - (2.0 * c * 8.0 - c * c)).abs() < 1e-12);
        // Five standard deviations out: 21 instead of 25; at ten, 51
        // instead of 100 (a gross error costs far less than a Gaussian says).
        assert_eq!(huber(5.0, c), 21.0);
        assert_eq!(huber(10.0, c), 51.0);
    }
}
