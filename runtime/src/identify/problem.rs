//! One fit's problem: which parameters are free ([`Free`]), the effect
//! values and every kick's initial state, packed into one vector and back,
//! the residuals with the priors' rows, and the Jacobian blocks and scales
//! the solver ([`lm_fit`](super::levenberg_marquardt::lm_fit)) works on. The fits
//! that pose problems are in [`fit`](super::fit).

use super::normal::SegmentJacobian;
use super::nuisance::{nuisance_scale, SPEED};
use super::{Setup, NUISANCE};
use nalgebra::DMatrix;
use rayon::prelude::*;
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
    /// (see [`lm_fit`](super::levenberg_marquardt::lm_fit)). Empty for every other fit.
    pub(super) settled_on_floor: Vec<usize>,
    /// Hold each segment's initial speed where it is (its Jacobian column
    /// zeroed, so a step never moves it): the first stage of a fit from
    /// the measured speed (see
    /// [`fit_each_segment`](super::levenberg_marquardt::fit_each_segment)).
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
    /// The priors' penalty: `r^2` within `gross_beyond` (c) of the mean and
    /// `c^2 (1 + 2 ln(|r| / c))` beyond ([`EffectParameter::gross_beyond`],
    /// [`heavy_tailed`]).
    pub(super) fn prior_penalty(&self) -> f64 {
        self.prior_rows()
            .into_iter()
            .zip(self.prior_residuals())
            .map(|((j, _), r)| heavy_tailed(r, self.setup.parameters[j].gross_beyond))
            .sum()
    }
    /// The priors as rows of the normal equations `(column, sd, residual)`,
    /// with the tail's weight `min(1, (c / |r|)^2)` folded into the
    /// standard deviation and the residual (iteratively reweighted: the
    /// step is Gauss-Newton on the penalty's quadratic model at the current
    /// value, whose slope there is the tail's, `2 c^2 / r`).
    pub(super) fn prior_normal_rows(&self) -> Vec<(usize, f64, f64)> {
        self.prior_rows()
            .into_iter()
            .zip(self.prior_residuals())
            .map(|((j, sd), r)| {
                let c = self.setup.parameters[j].gross_beyond;
                let w = if r.abs() > c { c / r.abs() } else { 1.0 };
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

/// The prior's penalty of a standardised residual `r` with its turn at
/// `c`: `r^2` within, `c^2 (1 + 2 ln(|r| / c))` beyond (continuous with its
/// slope, `2 c` at the turn). Beyond the turn the pull back toward the
/// measured value falls as `2 c^2 / |r|`: a Cauchy-like tail, which lets
/// data that contradict a measurement by far overrule it (O'Hagan and
/// Pericchi 2012, "Bayesian heavy-tailed models and conflict resolution:
/// a review", Brazilian Journal of Probability and Statistics 26(4)).
/// Huber's linear tail, used before, kept a constant pull, which held a
/// grossly wrong measurement short of its true value and left the rest of
/// the error to another parameter: on the oracle's
/// front_steer_inertia_higher (the front assembly's inertia about the
/// steer axis doubled, ten of its standard deviations), `I4z` stopped at
/// 0.069 of the true 0.077 kg m^2, its data fit then lost to the front
/// wheel's diametral inertia, and the wrong parameter was corrected.
fn heavy_tailed(r: f64, c: f64) -> f64 {
    if r.abs() <= c || !(c > 0.0) {
        r * r
    } else {
        c * c * (1.0 + 2.0 * (r.abs() / c).ln())
    }
}

#[cfg(test)]
mod prior_tests {
    use super::heavy_tailed;

    #[test]
    fn the_prior_penalty_is_gaussian_within_its_turn_and_its_pull_falls_beyond() {
        let c = 3.0;
        for r in [-2.9, -1.0, 0.0, 0.5, 3.0] {
            assert_eq!(heavy_tailed(r, c), r * r);
        }
        // Continuous, with the Gaussian's slope at the turn (2 c).
        let e = 1e-7;
        assert!((heavy_tailed(c + e, c) - heavy_tailed(c - e, c)).abs() < 1e-5);
        assert!(((heavy_tailed(c + 2.0 * e, c) - heavy_tailed(c + e, c)) / e - 2.0 * c).abs() < 1e-4);
        // Symmetric, and beyond the turn the slope is 2 c^2 / |r|: at ten
        // standard deviations a third of the turn's, where a linear tail
        // keeps 2 c.
        assert_eq!(heavy_tailed(-8.0, c), heavy_tailed(8.0, c));
        let slope = |r: f64| (heavy_tailed(r + e, c) - heavy_tailed(r - e, c)) / (2.0 * e);
        assert!((slope(10.0) - 2.0 * c * c / 10.0).abs() < 1e-5);
        assert!(slope(10.0) < slope(5.0) && slope(5.0) < 2.0 * c);
        // Ten standard deviations out: about 30.7 instead of a Gaussian's
        // 100 (or a linear tail's 51).
        assert!((heavy_tailed(10.0, c) - 9.0 * (1.0 + 2.0 * (10.0f64 / 3.0).ln())).abs() < 1e-12);
        assert!(heavy_tailed(10.0, c) < 31.0);
    }
}
