//! The score test of the candidates of a selection step, before any is
//! fitted.
//!
//! A full fit of a candidate costs tens of simulations of every kick, and
//! most candidates of a step explain nothing. A candidate nested in the
//! current model (its parameters at their base values give the current
//! model: an effect at zero, a correction at the measured value) is first
//! judged by the Gauss-Newton step from the current fit: the linearised
//! model's best residuals with the candidate's parameters free (with their
//! priors), the already selected ones and every kick's initial state free
//! as in the fit. Their information criterion is the score test's
//! prediction of what the fit can reach near the current model; a
//! candidate whose prediction does not lower the criterion is not fitted,
//! nor one that explains much less of the misfit than the best (the rule is
//! in [`super::identify`]).
//!
//! One simulation of each kick in dual numbers gives the derivatives along
//! every candidate at once (the columns of the initial states are shared),
//! so the screen of a step costs about what one Jacobian of a fit with all
//! candidates' parameters costs. Candidates simulated with another model
//! (the tyre model) or not nested are not screened: they are fitted. Nor
//! is a candidate whose law is not smooth at its base value (Coulomb
//! friction): its score at zero torque misses the stick and slip of a
//! finite one (on an independent set, a fitted gain 54 times the
//! prediction), so it is always fitted.

use super::normal::{Normal, SegmentJacobian};
use super::problem::{Free, Problem};
use super::Candidate;
use super::{bic, CandidateFit, ModelFactory, Segment, SegmentError, Weights};
use nalgebra::{DMatrix, DVector};
use std::collections::BTreeSet;
use std::sync::atomic::Ordering;

/// What one step's screen looks at.
pub(super) struct Screen<'s> {
    /// The factory of the main model and of the alternative one (the tyre
    /// model), if any.
    pub main: &'s dyn ModelFactory,
    pub alternative: Option<&'s dyn ModelFactory>,
    pub segments: &'s [Segment],
    pub weights: &'s [Weights],
    /// Candidates in the current model, in the order of its parameters.
    pub selected: &'s [&'s Candidate],
    /// Candidates of the step.
    pub remaining: &'s [&'s Candidate],
    /// The current model's fit.
    pub current: &'s CandidateFit,
    /// The fit whose residuals give the criterion's effective sample sizes
    /// (the base model of the search).
    pub reference: &'s CandidateFit,
}

/// The screen of a step.
pub(super) struct Screened {
    /// The criterion of the linearised best fit with no candidate added
    /// (the current fit one Gauss-Newton step further): the reference of
    /// the predictions.
    pub reference: Option<f64>,
    /// Each remaining candidate's predicted information criterion (in
    /// order); `None` where the screen does not apply (it is fitted).
    pub predictions: Vec<Option<f64>>,
    /// The predicted criterion of pairs of nested candidates (indices into
    /// the remaining ones, the smaller first) whose joint linearised fit
    /// beats each member's alone: two effects that each explain part of a
    /// misfit the other cannot (a damper beside an inertia error) may pass
    /// together where neither passes alone.
    pub pairs: Vec<((usize, usize), f64)>,
    /// Simulations run.
    pub simulations: usize,
}

/// The information criterion of the linearised best fit at `res` with the columns `cols` of the shared
/// parameters (values `g`, priors from `parameters`) and every segment's
/// initial state free.
fn predict(
    s: &Screen<'_>,
    setup: &super::Setup<'_>,
    blocks: &[SegmentJacobian],
    res: &[Vec<f64>],
    g: &[f64],
    cols: &[usize],
) -> Option<f64> {
    let k = cols.len();
    let sub: Vec<SegmentJacobian> = blocks
        .iter()
        .map(|b| SegmentJacobian {
            a: DMatrix::from_fn(b.a.nrows(), k, |r, c| b.a[(r, cols[c])]),
            b: b.b.clone(),
        })
        .collect();
    let prior: Vec<(usize, f64, f64)> = cols
        .iter()
        .enumerate()
        .filter_map(|(c, &j)| {
            let (mean, sd) = setup.parameters[j].prior?;
            Some((c, sd, (g[j] - mean) / sd))
        })
        .collect();
    let dx = Normal::new(&sub, res, &prior, k, 1e-9).and_then(|nm| nm.step())?;
    if dx.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let dg = DVector::from_column_slice(&dx[..k]);
    // The criterion weighs the weighted sum of squares at the search's
    // scales, the sum the linearised step minimised.
    let mut chi2 = 0.0;
    let errors: Vec<SegmentError> = sub
        .iter()
        .zip(res)
        .enumerate()
        .map(|(m, (b, r))| {
            let nn = setup.nuisance();
            let di = DVector::from_column_slice(&dx[k + m * nn..k + (m + 1) * nn]);
            let moved = &b.a * &dg + &b.b * di;
            let r: Vec<f64> = r.iter().zip(moved.iter()).map(|(a, d)| a + d).collect();
            chi2 += r.iter().map(|x| x * x).sum::<f64>();
            SegmentError::of(&r, &s.segments[m], s.weights[m])
        })
        .collect();
    let predicted = CandidateFit {
        errors,
        values: vec![0.0; k],
        chi2,
        ..s.current.clone()
    };
    let bic = bic(&predicted, s.reference);
    // A prediction that is not finite says nothing: the candidate is fitted.
    bic.is_finite().then_some(bic)
}

/// The score test of every remaining candidate. Nested candidates share
/// one simulation per kick; a candidate simulated with another model or
/// not nested in the current one is linearised at its starting values
/// instead (its own simulation per kick).
pub(super) fn screen(s: &Screen<'_>) -> Screened {
    let mut out = Screened {
        reference: None,
        predictions: vec![None; s.remaining.len()],
        pairs: Vec::new(),
        simulations: 0,
    };
    let in_alternative = s.selected.iter().any(|c| c.alternative_model);
    let current_factory = match (in_alternative, s.alternative) {
        (true, Some(f)) => f,
        (true, None) => return out,
        (false, _) => s.main,
    };
    let ks = s.current.values.len();
    // Nested candidates whose symbols are distinct from the current
    // model's and from each other's (a shared symbol is one column for two
    // candidates: those are linearised apart).
    let symbols = |c: &Candidate| -> Vec<String> {
        c.parameters
            .iter()
            .flat_map(|p| {
                std::iter::once(p.symbol.clone())
                    .chain(p.tied.iter().cloned())
                    .chain(p.moves.iter().map(|(s, _)| s.clone()))
            })
            .collect()
    };
    let mut seen: BTreeSet<String> = s.selected.iter().flat_map(|c| symbols(c)).collect();
    let mut group: Vec<usize> = Vec::new();
    let mut apart: Vec<usize> = Vec::new();
    for (i, c) in s.remaining.iter().enumerate() {
        let own = symbols(c);
        // An empty candidate, or one whose law is not smooth at its base
        // value (its linearisation there says little): not screened.
        if c.parameters.is_empty() || c.nonsmooth {
            continue;
        }
        if c.alternative_model != in_alternative || own.iter().any(|x| seen.contains(x)) {
            apart.push(i);
            continue;
        }
        seen.extend(own);
        group.push(i);
    }
    // The point: the current fit, every grouped parameter at its base
    // value (the model's value for it: zero for an effect, the measured
    // value for a correction). A candidate with a floor above that value
    // is not nested there: it is linearised apart.
    let group_setup = |group: &[usize]| {
        let mut active: Vec<&Candidate> = s.selected.to_vec();
        active.extend(group.iter().map(|&i| s.remaining[i]));
        current_factory
            .setup(s.segments, s.weights, &active)
            .ok()
            .filter(|setup| setup.k() >= ks)
    };
    let Some(mut setup) = group_setup(&group) else {
        return out;
    };
    let mut j = ks;
    let mut nested_group = Vec::new();
    for &i in &group {
        let mut nested = true;
        for p in &s.remaining[i].parameters {
            let v = setup.base_value(j);
            nested &= !p.held_at_bound(v);
            j += 1;
        }
        if nested {
            nested_group.push(i);
        } else {
            apart.push(i);
        }
    }
    if nested_group.len() < group.len() {
        group = nested_group;
        let Some(s2) = group_setup(&group) else {
            return out;
        };
        setup = s2;
    }
    let mut g = s.current.values.clone();
    let mut columns: Vec<Vec<usize>> = Vec::new();
    for &i in &group {
        let mut cols = Vec::new();
        for _ in &s.remaining[i].parameters {
            let j = g.len();
            g.push(setup.base_value(j));
            cols.push(j);
        }
        columns.push(cols);
    }
    let problem = Problem::new(
        &setup,
        (0..s.segments.len()).collect(),
        Free::All,
        g.clone(),
        s.current.nuisance.clone(),
    );
    if let (Some(blocks), Some(res)) = (problem.jacobian_blocks(), problem.all_residuals()) {
        let base: Vec<usize> = (0..ks).collect();
        out.reference = predict(s, &setup, &blocks, &res, &g, &base);
        for (n, &i) in group.iter().enumerate() {
            let cols: Vec<usize> = base.iter().chain(&columns[n]).copied().collect();
            out.predictions[i] = predict(s, &setup, &blocks, &res, &g, &cols);
        }
        // Pairs: the same linearisation with both members' columns free.
        for a in 0..group.len() {
            for b in a + 1..group.len() {
                let (ia, ib) = (group[a], group[b]);
                let (Some(pa), Some(pb)) = (out.predictions[ia], out.predictions[ib]) else {
                    continue;
                };
                let cols: Vec<usize> = base.iter().chain(&columns[a]).chain(&columns[b]).copied().collect();
                if let Some(p) = predict(s, &setup, &blocks, &res, &g, &cols).filter(|p| *p < pa.min(pb)) {
                    out.pairs.push(((ia.min(ib), ia.max(ib)), p));
                }
            }
        }
    }
    out.simulations += setup.simulations.load(Ordering::Relaxed);
    // The others, each at its starting values with its own model.
    for &i in &apart {
        let c = s.remaining[i];
        let mut active: Vec<&Candidate> = s.selected.to_vec();
        active.push(c);
        let factory = match (c.alternative_model || in_alternative, s.alternative) {
            (true, Some(f)) => f,
            (true, None) => continue,
            (false, _) => s.main,
        };
        let Ok(setup) = factory.setup(s.segments, s.weights, &active) else {
            continue;
        };
        let mut g = s.current.values.clone();
        g.extend(c.parameters.iter().map(|p| p.initial.unwrap_or(0.1 * p.scale)));
        if g.len() != setup.k() {
            continue;
        }
        let problem = Problem::new(
            &setup,
            (0..s.segments.len()).collect(),
            Free::All,
            g.clone(),
            s.current.nuisance.clone(),
        );
        if let (Some(blocks), Some(res)) = (problem.jacobian_blocks(), problem.all_residuals()) {
            let cols: Vec<usize> = (0..setup.k()).collect();
            out.predictions[i] = predict(s, &setup, &blocks, &res, &g, &cols);
        }
        out.simulations += setup.simulations.load(Ordering::Relaxed);
    }
    out
}
