//! Candidates the data cannot tell apart, and the data that would.
//!
//! Two candidates are confounded when their parameters move the simulated
//! responses in nearly the same way once every kick's initial state has
//! taken up what it can: their columns of the Fisher information,
//! reduced to the shared parameters (the Schur complement the fit's
//! normal equations form), are nearly parallel. The measure is the largest
//! canonical correlation between the two candidates' parameter blocks of
//! that reduced matrix (for one parameter each, the cosine of the angle
//! between their reduced sensitivities, which is minus the correlation of
//! their estimates). Near one, a fit of either explains what the other
//! would, and selection between them is arbitrary.
//!
//! Two candidates that both pass cross-validation are also not separated
//! by these runs when neither predicts the held-out runs consistently
//! better than the other (their paired held-out gain is within two
//! standard errors): the data then support either, whatever their
//! correlation, and the report says so rather than name one as the cause.
//!
//! Which data would separate them is answered the same way on kicks that
//! were not measured: the measured median kick repeated at other speeds,
//! with three times its amplitude, and as a steer kick (the same initial
//! rate put on the steer instead of the roll, as a steer-torque impulse
//! gives). Each design's correlation comes from its own sensitivities; a
//! design whose correlation is well below the data's would tell the
//! candidates apart.

use super::normal::{Normal, SegmentJacobian};
use super::{at_rest, Candidate, ModelFactory, Segment, Setup, NUISANCE};
use nalgebra::DMatrix;
use rayon::prelude::*;
use serde::Serialize;

/// Two candidates' parameters that the data hardly tell apart.
#[derive(Clone, Debug, Serialize)]
pub struct Confounding {
    /// The candidate selected and its rival.
    pub chosen: String,
    pub rival: String,
    /// Largest canonical correlation of their reduced Fisher information
    /// on the measured kicks (0: independent, 1: indistinguishable).
    pub correlation: f64,
    /// When the rival also passed cross-validation: its held-out gain over
    /// the chosen candidate, paired run by run (weighted mean square of
    /// the held-out residuals, chosen minus rival: positive when the rival
    /// predicts better), and that gain's standard error.
    pub held_out_gain: Option<HeldOutGain>,
    /// Both lie beyond their priors (the encompassing test's choice and a
    /// rival correction of the same kind, cross-validated beside it): the
    /// runs call for one such correction without telling which.
    pub beyond_priors: bool,
    /// Designs of further kicks and the correlation each would give on its
    /// own, best separating first.
    pub designs: Vec<Design>,
}

/// A paired held-out gain and its standard error (weighted mean square of
/// the held-out residuals, dimensionless).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct HeldOutGain {
    pub gain: f64,
    pub stderr: f64,
}

impl HeldOutGain {
    /// Whether the gain is within two standard errors of zero, either way:
    /// the runs' scatter hides any difference (the test selection applies
    /// to a candidate's gain over the base). A gain that is not a number
    /// is not within anything.
    pub fn within_scatter(&self) -> bool {
        self.gain.is_finite() && self.stderr.is_finite() && self.gain.abs() <= 2.0 * self.stderr
    }
}

impl Confounding {
    /// Whether the data leave the two candidates unseparated: their
    /// estimates correlate at or above [`CONFOUNDED`], or both passed
    /// cross-validation and neither predicts the held-out runs
    /// consistently better.
    pub fn not_separated(&self) -> bool {
        self.correlation >= CONFOUNDED || self.predicts_alike()
    }

    /// Whether both passed cross-validation and their held-out errors
    /// differ within the runs' scatter.
    pub fn predicts_alike(&self) -> bool {
        self.held_out_gain.is_some_and(|h| h.within_scatter())
    }
}

/// A kick that was not measured and how well it would separate two
/// candidates.
#[derive(Clone, Debug, Serialize)]
pub struct Design {
    /// What the kick is ("kicks at 2.5 m/s", "three times the amplitude",
    /// "a steer-torque kick").
    pub description: String,
    /// Forward speed (m/s) of the kick.
    pub speed: f64,
    pub correlation: f64,
}

/// Correlations at or above this mark two candidates as confounded (their
/// estimates share over 80 % of their variance).
pub const CONFOUNDED: f64 = 0.9;

/// The reduced Fisher information `sum_i A_i^T A_i - A_i^T B_i (B_i^T
/// B_i)^-1 B_i^T A_i` of the setup's shared parameters at `g`, from the
/// exact Jacobians of the segments `segs` with initial states `x0`.
fn reduced_information(setup: &Setup<'_>, g: &[f64], segs: &[usize], x0: &[[f64; NUISANCE]]) -> Option<DMatrix<f64>> {
    let blocks: Vec<SegmentJacobian> = segs
        .par_iter()
        .map(|&s| setup.jacobian(g, s, &x0[s], true, true))
        .collect::<Option<Vec<_>>>()?;
    let res: Vec<Vec<f64>> = blocks.iter().map(|b| vec![0.0; b.a.nrows()]).collect();
    Some(Normal::new(&blocks, &res, &[], setup.k(), 0.0)?.s)
}

/// Largest canonical correlation between the parameter blocks `a` and `b`
/// (column indices) of the information matrix `f`; `None` when either
/// block carries no information.
pub fn canonical_correlation(f: &DMatrix<f64>, a: &[usize], b: &[usize]) -> Option<f64> {
    let pick = |r: &[usize], c: &[usize]| DMatrix::from_fn(r.len(), c.len(), |i, j| f[(r[i], c[j])]);
    let inv_sqrt = |m: DMatrix<f64>| -> Option<DMatrix<f64>> {
        let e = m.symmetric_eigen();
        let top = e.eigenvalues.iter().fold(0.0f64, |x, v| x.max(*v));
        if !(top > 0.0) || e.eigenvalues.iter().any(|v| !(*v > 1e-12 * top)) {
            return None;
        }
        let d = DMatrix::from_diagonal(&e.eigenvalues.map(|v| 1.0 / v.sqrt()));
        Some(&e.eigenvectors * d * e.eigenvectors.transpose())
    };
    let (wa, wb) = (inv_sqrt(pick(a, a))?, inv_sqrt(pick(b, b))?);
    let m = wa * pick(a, b) * wb;
    let s = m.singular_values();
    Some(s.iter().fold(0.0f64, |x, v| x.max(*v)).min(1.0))
}

/// The correlation of candidates whose parameters are the columns `a` and
/// `b` of `setup` (made by `factory` with `active`, values `g`) on the
/// measured segments with initial states `x0`; and, when at least
/// [`CONFOUNDED`] or when `designs_wanted` (the pair is not separated
/// otherwise), the designs built from the median measured kick over
/// `speeds`.
#[allow(clippy::too_many_arguments)]
pub fn confounding(
    setup: &Setup<'_>,
    factory: &dyn ModelFactory,
    active: &[&Candidate],
    g: &[f64],
    x0: &[[f64; NUISANCE]],
    a: &[usize],
    b: &[usize],
    speeds: &[f64],
    designs_wanted: bool,
) -> Option<(f64, Vec<Design>)> {
    let all: Vec<usize> = (0..setup.segments.len()).collect();
    let f = reduced_information(setup, g, &all, x0)?;
    let measured = canonical_correlation(&f, a, b)?;
    if measured < CONFOUNDED && !designs_wanted {
        return Some((measured, Vec::new()));
    }
    // The median kick by duration, at its fitted initial state.
    let mut order = all.clone();
    order.sort_by(|&i, &j| setup.segments[i].duration().total_cmp(&setup.segments[j].duration()));
    let m = order[order.len() / 2];
    let template = &setup.segments[m];
    let x = x0[m];
    let rate = x[2].abs().max(x[3].abs()).max(0.2);
    let mut kicks: Vec<(String, [f64; NUISANCE])> = speeds
        .iter()
        .map(|&v| (format!("kicks at {v:.1} m/s"), at_rest([x[0], x[1], x[2], x[3], v])))
        .collect();
    kicks.push((
        format!("three times the amplitude (at {:.1} m/s)", x[4]),
        at_rest([3.0 * x[0], 3.0 * x[1], 3.0 * x[2], 3.0 * x[3], x[4]]),
    ));
    kicks.push((
        format!("a steer-torque kick (steer rate {rate:.2} rad/s at {:.1} m/s)", x[4]),
        at_rest([0.0, 0.0, 0.0, rate, x[4]]),
    ));
    let segments: Vec<Segment> = kicks
        .iter()
        .map(|(_, x)| {
            let mut s = template.clone();
            s.initial = *x;
            s.mean_speed = x[4];
            s
        })
        .collect();
    let weights = vec![setup.weights[m]; segments.len()];
    let virtual_setup = factory.setup(&segments, &weights, active).ok()?;
    let states: Vec<[f64; NUISANCE]> = kicks.iter().map(|(_, x)| *x).collect();
    let mut designs: Vec<Design> = (0..kicks.len())
        .into_par_iter()
        .filter_map(|i| {
            let f = reduced_information(&virtual_setup, g, &[i], &states)?;
            Some(Design {
                description: kicks[i].0.clone(),
                speed: states[i][4],
                correlation: canonical_correlation(&f, a, b)?,
            })
        })
        .collect();
    designs.sort_by(|p, q| p.correlation.total_cmp(&q.correlation));
    Some((measured, designs))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Information `J^T J` of sensitivity columns.
    fn information(columns: &[Vec<f64>]) -> DMatrix<f64> {
        let j = DMatrix::from_fn(columns[0].len(), columns.len(), |r, c| columns[c][r]);
        j.tr_mul(&j)
    }

    #[test]
    fn two_candidates_are_not_separated_when_correlated_or_when_both_pass_and_predict_alike() {
        let pair = |correlation: f64, held_out_gain: Option<HeldOutGain>| Confounding {
            chosen: "correct z3".into(),
            rival: "correct x3".into(),
            correlation,
            held_out_gain,
            beyond_priors: false,
            designs: Vec::new(),
        };
        let gain = |gain: f64, stderr: f64| Some(HeldOutGain { gain, stderr });
        // Correlated estimates: not separable, whatever the held-out runs.
        assert!(pair(0.95, None).not_separated());
        assert!(pair(0.95, gain(0.01, 0.001)).not_separated());
        // Below the mark, a rival that did not pass (no gain) is separated.
        assert!(!pair(0.884, None).not_separated());
        // Both passed: a gain within two standard errors either way leaves
        // them unseparated; beyond, the runs tell them apart.
        assert!(pair(0.884, gain(0.0016, 0.0010)).not_separated());
        assert!(pair(0.884, gain(-0.0019, 0.0010)).predicts_alike());
        assert!(!pair(0.884, gain(0.0021, 0.0010)).not_separated());
        assert!(!pair(0.5, gain(-0.0030, 0.0010)).not_separated());
        // A gain that could not be computed is no evidence that they
        // predict alike.
        assert!(!pair(0.5, gain(f64::NAN, f64::NAN)).not_separated());
    }

    #[test]
    fn canonical_correlation_is_the_cosine_of_the_sensitivities() {
        let a = vec![1.0, 2.0, 0.5, -1.0];
        let b = vec![0.3, -1.0, 2.0, 0.7];
        let cos = {
            let ab: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let n = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
            (ab / (n(&a) * n(&b))).abs()
        };
        let f = information(&[a.clone(), b.clone()]);
        assert!((canonical_correlation(&f, &[0], &[1]).unwrap() - cos).abs() < 1e-12);
        // Parallel sensitivities (a scaled) cannot be told apart.
        let f = information(&[a.clone(), a.iter().map(|x| -3.0 * x).collect()]);
        assert!((canonical_correlation(&f, &[0], &[1]).unwrap() - 1.0).abs() < 1e-9);
        // Orthogonal ones are independent.
        let f = information(&[vec![1.0, 0.0, 0.0], vec![0.0, 1.0, 0.0]]);
        assert!(canonical_correlation(&f, &[0], &[1]).unwrap() < 1e-12);
        // A block of two parameters whose span holds the third's
        // sensitivity: correlation one, though neither column is parallel.
        let c: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x + 2.0 * y).collect();
        let f = information(&[a, b, c]);
        assert!((canonical_correlation(&f, &[0, 1], &[2]).unwrap() - 1.0).abs() < 1e-9);
        // No information on a parameter: no correlation to speak of.
        let f = information(&[vec![1.0, 2.0], vec![0.0, 0.0]]);
        assert!(canonical_correlation(&f, &[0], &[1]).is_none());
    }
}
