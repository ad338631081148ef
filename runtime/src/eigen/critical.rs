//! Critical speeds from exact smooth functions of the speed.
//!
//! With `u = v^2` the characteristic quartic has coefficients
//! `k4`, `k3 = v a3`, `k2 = g b0 + u b2`, `k1 = v (g d0 + u d2)`,
//! `k0 = g^2 e0 + g u e1 + u^2 e2` ([`CharPoly`]). Then:
//! * a **real root crosses zero** where `k0 = det(g K0 + v^2 K2) = 0`: a quadratic in
//!   `u`, solved in closed form (cancellation-free formula);
//! * a **complex pair crosses the imaginary axis** (`s = +-i w`) where the Hurwitz
//!   determinant `H = k1 k2 k3 - k4 k1^2 - k0 k3^2 = 0` with `w^2 = k1/k3 > 0`.
//!   `H / v^2` is again a quadratic in `u`, solved in closed form (if `a3 = 0`, the
//!   condition degenerates to `k1 = 0`, handled separately);
//! * the **direction** of each crossing is the sign of `Re ds/dv = -Re(p_v / p_s)` at
//!   the crossing root (exact derivatives of the coefficient polynomials);
//! * the **weave merge** `v_d` is bracketed on a labelled grid (the two weave roots
//!   are real below and complex above), bisected on the count of real roots, and
//!   polished by Newton on the double-root system `p(s, v) = 0`, `p_s(s, v) = 0`.

use super::*;

/// Real roots of `a x^2 + b x + c = 0` (simple roots only: a double root is a
/// tangency, not a crossing).
fn quadratic_real_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    if a == 0.0 {
        if b == 0.0 {
            return vec![];
        }
        return vec![-c / b];
    }
    let disc = b * b - 4.0 * a * c;
    if !(disc > 0.0) {
        return vec![];
    }
    let q = -0.5 * (b + disc.sqrt().copysign(b));
    let mut r = vec![q / a];
    if q != 0.0 {
        r.push(c / q);
    } else {
        r.push(0.0);
    }
    r.retain(|x| x.is_finite());
    r
}

/// `(p, p_s, p_ss, p_v, p_sv)` at complex `s` and speed `v`.
fn derivs<S: Spectrum + ?Sized>(cp: &S, s: C64, v: f64) -> (C64, C64, C64, C64, C64) {
    let nan = [f64::NAN; 5];
    let k = cp.coefficients(v).unwrap_or(nan);
    let kd = cp.coefficient_rates(v).unwrap_or(nan);
    let zero = C64::new(0.0, 0.0);
    let (mut p, mut ps, mut pss, mut pv, mut psv) = (zero, zero, zero, zero, zero);
    for i in (0..5).rev() {
        pss = pss * s + ps * 2.0;
        ps = ps * s + p;
        p = p * s + k[i];
        psv = psv * s + pv;
        pv = pv * s + kd[i];
    }
    (p, ps, pss, pv, psv)
}

fn direction<S: Spectrum + ?Sized>(cp: &S, s: C64, v: f64) -> Option<CrossingDirection> {
    let (_, ps, _, pv, _) = derivs(cp, s, v);
    if ps.norm_sqr() == 0.0 || !ps.norm_sqr().is_finite() {
        return None;
    }
    let dsdv = -pv / ps;
    if dsdv.re > 0.0 {
        Some(CrossingDirection::Destabilizing)
    } else if dsdv.re < 0.0 {
        Some(CrossingDirection::Stabilizing)
    } else {
        None
    }
}

/// Critical speeds and all real-part zero crossings in `[v_min, v_max]`.
///
/// * `crossings`: every speed in the range (negative speeds included if the range
///   contains them) where a real root passes through zero or a complex pair
///   crosses the imaginary axis, ascending, with the label of the crossing root
///   (tracked as in [`eigen_sweep`]) and the direction with increasing speed.
/// * `weave_speed` (`v_w`): the lowest speed `>= 0` in the range where an
///   oscillation containing the weave becomes stable (a stabilizing complex-pair
///   crossing of `weave`, `weave-capsize` or `weave-castering`); `capsize_speed`
///   (`v_c`): the lowest speed `>= 0` in the range where the capsize mode (alone or
///   merged with castering) becomes unstable;
///   `weave_real_pair_merge` (`v_d`): the lowest speed `>= 0` in the range where the
///   two real weave roots merge into the weave pair (with the double root in
///   `weave_merge_eigenvalue`). Each is `None` if it does not occur in the range.
/// * `stable_intervals`: maximal closed sub-intervals where all real parts are
///   negative (endpoints are crossing speeds or the range ends; interior checked at
///   midpoints between consecutive crossings).
///
/// Crossings exactly at `v = 0` (possible only for a bicycle that is oscillatory at
/// rest) and tangential touches are not reported.
pub fn critical_speeds(c: &CanonicalMatrices, v_min: f64, v_max: f64) -> Result<CriticalSpeeds, EigenError> {
    check_range(v_min, v_max)?;
    let cp = CharPoly::new(c)?;
    let g = cp.g;
    let in_range = |v: f64| v >= v_min && v <= v_max;
    // (speed, kind, omega)
    let mut cands: Vec<(f64, CrossingKind, f64)> = Vec::new();
    let push_u = |u: f64, kind: CrossingKind, w: f64, cands: &mut Vec<(f64, CrossingKind, f64)>| {
        if u > 0.0 && u.is_finite() {
            let v = u.sqrt();
            for v in [v, -v] {
                if in_range(v) {
                    cands.push((v, kind, w));
                }
            }
        }
    };
    // Real root through zero: k0(u) = e2 u^2 + g e1 u + g^2 e0.
    for u in quadratic_real_roots(cp.e2, g * cp.e1, g * g * cp.e0) {
        push_u(u, CrossingKind::RealRoot, 0.0, &mut cands);
    }
    // Complex pair through the imaginary axis.
    if cp.a3 != 0.0 {
        // H/u = (g d0 + u d2)(g b0 + u b2) a3 - k4 (g d0 + u d2)^2 - (g^2 e0 + g u e1 + u^2 e2) a3^2
        let (a3, k4) = (cp.a3, cp.k4);
        let (p0, p1) = (g * cp.d0, cp.d2); // k1/v = p0 + p1 u
        let (q0, q1) = (g * cp.b0, cp.b2); // k2 = q0 + q1 u
        let (r0, r1, r2) = (g * g * cp.e0, g * cp.e1, cp.e2); // k0
        let h2 = a3 * p1 * q1 - k4 * p1 * p1 - a3 * a3 * r2;
        let h1 = a3 * (p0 * q1 + p1 * q0) - 2.0 * k4 * p0 * p1 - a3 * a3 * r1;
        let h0 = a3 * p0 * q0 - k4 * p0 * p0 - a3 * a3 * r0;
        for u in quadratic_real_roots(h2, h1, h0) {
            let w2 = (p0 + p1 * u) / a3;
            if w2 > 0.0 {
                push_u(u, CrossingKind::ComplexPair, w2.sqrt(), &mut cands);
            }
        }
    } else if cp.d2 != 0.0 {
        // k3 == 0: need k1 = 0, then k4 w^4 - k2 w^2 + k0 = 0 with w^2 > 0.
        let u = -g * cp.d0 / cp.d2;
        if u > 0.0 {
            let k = cp.coeffs(u.sqrt());
            for w2 in quadratic_real_roots(k[4], -k[2], k[0]) {
                if w2 > 0.0 {
                    push_u(u, CrossingKind::ComplexPair, w2.sqrt(), &mut cands);
                }
            }
        }
    }
    cands.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));

    finish(&cp, cands, v_min, v_max)
}

/// A speed range `[v_min, v_max]` must be finite and ordered.
pub(crate) fn check_range(v_min: f64, v_max: f64) -> Result<(), EigenError> {
    if !v_min.is_finite() || !v_max.is_finite() {
        return Err(EigenError::NonFinite {
            what: format!("speed range [{v_min}, {v_max}]"),
        });
    }
    if v_min > v_max {
        return Err(EigenError::InvalidArgument {
            what: format!("v_min = {v_min} > v_max = {v_max}"),
        });
    }
    Ok(())
}

/// Labels, directions, the named critical speeds, the stable intervals and
/// the weave merge from the crossing candidates `(speed, kind, frequency)`
/// (sorted by speed) of any family.
pub(crate) fn finish<S: Spectrum + ?Sized>(
    cp: &S,
    cands: Vec<(f64, CrossingKind, f64)>,
    v_min: f64,
    v_max: f64,
) -> Result<CriticalSpeeds, EigenError> {
    // Labels at the crossing speeds, and at the grid speeds of the weave
    // merge's search near a collision of roots (one continuation from the
    // anchor for both).
    let (merge_lo, merge_hi) = (v_min.max(0.0), v_max);
    let grid = merge_grid(merge_lo, merge_hi);
    let near = if merge_hi > merge_lo {
        near_collisions(cp, &grid)
    } else {
        Some(Vec::new())
    };
    let mut speeds: Vec<f64> = cands.iter().map(|x| x.0).collect();
    speeds.extend(near.iter().flatten().map(|&i| grid[i]));
    let mut labelled = track(cp, &speeds)?;
    let near_labelled = labelled.split_off(cands.len());
    let mut crossings = Vec::new();
    for ((v, kind, w), l) in cands.iter().zip(&labelled) {
        let target = C64::new(0.0, *w);
        let Some(dir) = direction(cp, target, *v) else {
            continue;
        };
        let mut best = 0;
        for k in 1..4 {
            if (l.roots[k] - target).norm_sqr() < (l.roots[best] - target).norm_sqr() {
                best = k;
            }
        }
        crossings.push(Crossing {
            speed: *v,
            mode: l.labels[best],
            direction: dir,
            kind: *kind,
            frequency: *w,
        });
    }

    // The weave speed is where an oscillatory mode containing the weave
    // stabilizes (the weave pair, or a weave root merged with capsize or
    // castering); the capsize speed is where the capsize mode (alone or merged
    // with castering) destabilizes.
    let (weave_speed, capsize_speed) = named_speeds(&crossings);

    let stable_intervals = stable_intervals(v_min, v_max, &crossings, |v| {
        Ok(cp.roots_at(v)?.iter().all(|z| z.re < 0.0))
    })?;

    let merge = match near {
        Some(near) => merge_near(cp, &grid, &near, &near_labelled)?,
        None => weave_merge_on_labelled_grid(cp, merge_lo, merge_hi)?,
    };
    let (weave_real_pair_merge, weave_merge_eigenvalue) = match merge {
        Some((v, s)) => (Some(v), Some(s)),
        None => (None, None),
    };
    Ok(CriticalSpeeds {
        weave_real_pair_merge,
        weave_merge_eigenvalue,
        weave_speed,
        capsize_speed,
        crossings,
        stable_intervals,
    })
}

/// The weave speed (the first stabilizing complex-pair crossing of a mode
/// containing the weave, at `v >= 0`) and the capsize speed (the first
/// destabilizing crossing of the capsize mode, alone or merged with
/// castering) among `crossings` (ascending).
pub(crate) fn named_speeds(crossings: &[Crossing]) -> (Option<f64>, Option<f64>) {
    let weave_speed = crossings
        .iter()
        .find(|x| {
            x.speed >= 0.0
                && x.mode.involves(Mode::Weave)
                && x.kind == CrossingKind::ComplexPair
                && x.direction == CrossingDirection::Stabilizing
        })
        .map(|x| x.speed);
    let capsize_speed = crossings
        .iter()
        .find(|x| {
            x.speed >= 0.0
                && x.mode.involves(Mode::Capsize)
                && !x.mode.involves(Mode::Weave)
                && x.direction == CrossingDirection::Destabilizing
        })
        .map(|x| x.speed);
    (weave_speed, capsize_speed)
}

/// Maximal sub-intervals of `[v_min, v_max]` where `stable_at` holds: the
/// range is cut at the crossing speeds and each piece is judged at its
/// midpoint (the spectrum cannot change stability between crossings).
pub(crate) fn stable_intervals(
    v_min: f64,
    v_max: f64,
    crossings: &[Crossing],
    stable_at: impl Fn(f64) -> Result<bool, EigenError>,
) -> Result<Vec<[f64; 2]>, EigenError> {
    let mut breaks = vec![v_min];
    breaks.extend(crossings.iter().map(|x| x.speed).filter(|&v| v > v_min && v < v_max));
    breaks.push(v_max);
    breaks.dedup();
    let mut out: Vec<[f64; 2]> = Vec::new();
    if breaks.len() == 1 {
        if stable_at(v_min)? {
            out.push([v_min, v_max]);
        }
    } else {
        for w in breaks.windows(2) {
            if stable_at(0.5 * (w[0] + w[1]))? {
                match out.last_mut() {
                    Some(last) if last[1] == w[0] => last[1] = w[1],
                    _ => out.push([w[0], w[1]]),
                }
            }
        }
    }
    Ok(out)
}

/// Grid intervals used to bracket `v_d`.
const MERGE_GRID: usize = 512;

/// `Some(false)`: a complex pair whose mode contains the weave (the weave
/// pair, or a weave root merged with capsize or castering); `Some(true)`: no
/// such pair and at least two real weave roots.
fn weave_state(l: &Labelled) -> Option<bool> {
    if (0..4).any(|k| l.roots[k].im != 0.0 && l.labels[k].involves(Mode::Weave)) {
        return Some(false);
    }
    let real_weave = (0..4)
        .filter(|&k| l.labels[k] == Mode::Weave && l.roots[k].im == 0.0)
        .count();
    (real_weave >= 2).then_some(true)
}

/// Real part of the oscillatory weave-containing pair (the double root just
/// after it formed).
fn weave_mean(l: &Labelled) -> f64 {
    let w: Vec<f64> = (0..4)
        .filter(|&k| l.roots[k].im != 0.0 && l.labels[k].involves(Mode::Weave))
        .map(|k| l.roots[k].re)
        .collect();
    w.iter().sum::<f64>() / w.len().max(1) as f64
}

/// `(v_d, s_d)`: lowest speed of the grid's range where the two weave roots turn
/// from real to complex, and the double root there. The merge is bracketed on a grid
/// of `MERGE_GRID` cells ([`merge_grid`]), bisected on the state of the
/// *weave-labelled* roots (labels carried by continuation from the bracket's lower
/// end, so another pair merging in the same bracket cannot be mistaken for it), then
/// `(s, v)` is polished by Newton on `p = p_s = 0` ([`merge_in`]).
///
/// Only the cells near a collision of roots can hold a merge (elsewhere the labels
/// cannot change): `near` ([`near_collisions`]) holds the grid speeds at their ends,
/// `labelled` their labelled roots, and the cells are searched lowest first. A
/// family without a discriminant labels every grid speed instead
/// ([`weave_merge_on_labelled_grid`]); both find the same merge
/// (`weave_merge_is_bracketed_alike_by_the_discriminant`).
fn merge_near<S: Spectrum + ?Sized>(
    cp: &S,
    grid: &[f64],
    near: &[usize],
    labelled: &[Labelled],
) -> Result<Option<(f64, f64)>, EigenError> {
    for k in 1..near.len() {
        if near[k] != near[k - 1] + 1 {
            continue;
        }
        let (a, b) = ((grid[near[k - 1]], labelled[k - 1]), (grid[near[k]], labelled[k]));
        if let Some(found) = merge_in(cp, a, b)? {
            return Ok(Some(found));
        }
    }
    Ok(None)
}

/// The grid of the merge search on `[lo, hi]`.
fn merge_grid(lo: f64, hi: f64) -> Vec<f64> {
    (0..=MERGE_GRID)
        .map(|i| lo + (hi - lo) * (i as f64 / MERGE_GRID as f64))
        .collect()
}

/// The indices (ascending) of the grid speeds near which roots may collide, so
/// that a merge can only lie in a cell between two of them: within one cell of
/// a cell where the number of real roots changes (by the discriminant's
/// invariants; a repeated root counts as a number of its own), and within two
/// of a local minimum of the discriminant's magnitude over the grid (two
/// collisions in one cell that leave the number as it was, such as the weave
/// merging as capsize and castering part, dip it toward zero between grid
/// speeds of one sign). A grid speed within rounding of a collision may take
/// the wrong count: hence the cell on either side. `None` if the family has no
/// discriminant or it is not finite somewhere on the grid.
fn near_collisions<S: Spectrum + ?Sized>(cp: &S, grid: &[f64]) -> Option<Vec<usize>> {
    let mut delta = Vec::with_capacity(grid.len());
    let mut real = Vec::with_capacity(grid.len());
    for &v in grid {
        let (d, n) = cp.discriminant(v)?;
        if !d.is_finite() {
            return None;
        }
        delta.push(d.abs());
        real.push(n);
    }
    let last = grid.len() - 1;
    let mut near = vec![false; grid.len()];
    let mut mark = |lo: usize, hi: usize| {
        for n in near.iter_mut().take(hi.min(last) + 1).skip(lo) {
            *n = true;
        }
    };
    for i in 0..last {
        if real[i] != real[i + 1] {
            mark(i.saturating_sub(1), i + 2);
        }
    }
    for i in 0..=last {
        let below = i == 0 || delta[i] <= delta[i - 1];
        let above = i == last || delta[i] <= delta[i + 1];
        if below && above {
            mark(i.saturating_sub(2), i + 2);
        }
    }
    Some((0..grid.len()).filter(|&i| near[i]).collect())
}

/// [`merge_near`] with every grid speed labelled (for a family without a
/// discriminant).
pub(super) fn weave_merge_on_labelled_grid<S: Spectrum + ?Sized>(
    cp: &S,
    lo: f64,
    hi: f64,
) -> Result<Option<(f64, f64)>, EigenError> {
    if !(hi > lo) {
        return Ok(None);
    }
    let grid = merge_grid(lo, hi);
    let lab = track(cp, &grid)?;
    for i in 0..MERGE_GRID {
        if let Some(found) = merge_in(cp, (grid[i], lab[i]), (grid[i + 1], lab[i + 1]))? {
            return Ok(Some(found));
        }
    }
    Ok(None)
}

/// The weave merge in the bracket `[a, b]` with the labelled roots at its
/// ends, if the weave roots are real at `a` and form a pair at `b`.
fn merge_in<S: Spectrum + ?Sized>(
    cp: &S,
    (mut a, mut la): (f64, Labelled),
    (mut b, mut lb): (f64, Labelled),
) -> Result<Option<(f64, f64)>, EigenError> {
    if weave_state(&la) != Some(true) || weave_state(&lb) != Some(false) {
        return Ok(None);
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let lm = continue_to(cp, la, a, m)?.canonical();
        if weave_state(&lm) == Some(true) {
            a = m;
            la = lm;
        } else {
            b = m;
            lb = lm;
        }
    }
    let vm = 0.5 * (a + b);
    // the double root: real part of the (just formed) weave pair above the merge
    // (below it the two weave-labelled roots need not be the merging ones, see
    // the pair rule in the module docs)
    let s0 = weave_mean(&lb);
    Ok(Some(match double_root_newton(cp, s0, vm) {
        Some((v, s)) if (v - vm).abs() <= 1e-9 * vm.abs().max(1.0) && (s - s0).abs() <= 1e-3 * (1.0 + s0.abs()) => {
            (v, s)
        }
        _ => (vm, s0),
    }))
}

/// Newton on `p(s, v) = 0`, `p_s(s, v) = 0` (real `s`).
fn double_root_newton<S: Spectrum + ?Sized>(cp: &S, mut s: f64, mut v: f64) -> Option<(f64, f64)> {
    for _ in 0..30 {
        let (p, ps, pss, pv, psv) = derivs(cp, C64::new(s, 0.0), v);
        let (p, ps, pss, pv, psv) = (p.re, ps.re, pss.re, pv.re, psv.re);
        let det = ps * psv - pv * pss;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let ds = (-p * psv + pv * ps) / det;
        let dv = (-ps * ps + pss * p) / det;
        s += ds;
        v += dv;
        if !(s.is_finite() && v.is_finite()) {
            return None;
        }
        if dv.abs() <= 4e-15 * v.abs().max(1.0) && ds.abs() <= 1e-12 * s.abs().max(1.0) {
            return Some((v, s));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_form::meijaard_canonical_of_values;
    use crate::parameters::BenchmarkParameters;
    use crate::random::SplitMix64;

    /// Random designs about the benchmark bicycle: every value scaled by
    /// 0.6-1.4, the trail and steer-axis tilt drawn over wide ranges (some
    /// designs have no weave merge in the range, some merge other pairs).
    fn random_family(rng: &mut SplitMix64) -> Option<CharPoly> {
        let draws: Vec<f64> = (0..26).map(|_| rng.next_f64()).collect();
        family(|sym, x| {
            let u = draws[BenchmarkParameters::SYMBOLS
                .iter()
                .position(|s| *s == sym)
                .expect("a symbol")];
            let within = |lo: f64, hi: f64| lo + (hi - lo) * u;
            match sym {
                "g" => x,
                "c" => within(-0.1, 0.3),
                "lam" => within(-0.3, 0.8),
                "xB" | "xH" | "IBxz" | "IHxz" => x * within(-0.5, 2.0),
                _ => x * within(0.6, 1.4),
            }
        })
    }

    /// The canonical form's characteristic polynomial of the benchmark
    /// bicycle with values changed by `change`.
    fn family(change: impl Fn(&str, f64) -> f64) -> Option<CharPoly> {
        let p = BenchmarkParameters::benchmark_bicycle();
        let x: [f64; 26] = BenchmarkParameters::SYMBOLS.map(|k| change(k, p.get(k).expect("a benchmark symbol")));
        let c = meijaard_canonical_of_values(&x);
        CharPoly::new(&c).ok()
    }

    /// The same merge or none, by both methods, on `[lo, hi]`; whether one
    /// was found.
    fn same_merge(cp: &CharPoly, lo: f64, hi: f64) -> Option<bool> {
        let (Ok(fast), Ok(grid)) = (finish(cp, Vec::new(), lo, hi), weave_merge_on_labelled_grid(cp, lo, hi)) else {
            return None;
        };
        let fast = fast.weave_real_pair_merge.zip(fast.weave_merge_eigenvalue);
        match (fast, grid) {
            (None, None) => Some(false),
            (Some((v, s)), Some((vg, sg))) => {
                assert!(
                    (v - vg).abs() <= 1e-12 * vg.abs().max(1.0),
                    "{v} vs {vg} on [{lo}, {hi}]: {cp:?}"
                );
                assert!(
                    (s - sg).abs() <= 1e-9 * sg.abs().max(1.0),
                    "{s} vs {sg} on [{lo}, {hi}]: {cp:?}"
                );
                Some(true)
            }
            other => panic!("{other:?} on [{lo}, {hi}]: {cp:?}"),
        }
    }

    /// Over the explorer's map of trail and steer-axis tilt (101 x 101
    /// designs, 0-10 m/s), where some designs have the weave merge and the
    /// capsize-castering merge in one cell of the grid (four real roots on
    /// one side, none on the other: the discriminant keeps its sign, the
    /// number of real roots does not), both methods find the same merge.
    #[test]
    fn weave_merge_of_the_trail_and_tilt_map_is_bracketed_alike() {
        let mut found = 0;
        for i in 0..=100 {
            for j in 0..=100 {
                let (c, lam) = (0.02 + 0.0012 * i as f64, 0.1 + 0.004 * j as f64);
                let cp = family(|k, x| match k {
                    "c" => c,
                    "lam" => lam,
                    _ => x,
                })
                .expect("a valid design");
                found += usize::from(same_merge(&cp, 0.0, 10.0).expect("both methods succeed"));
            }
        }
        assert!(found > 5000, "{found}");
    }

    /// The weave merge bracketed by the discriminant's sign changes is the
    /// one a labelled grid finds, on a thousand random designs and three
    /// speed ranges: the same speed and double root to 1e-12, or neither.
    #[test]
    fn weave_merge_is_bracketed_alike_by_the_discriminant() {
        let mut rng = SplitMix64::new(20261129);
        let (mut compared, mut found) = (0, 0);
        for _ in 0..1000 {
            let Some(cp) = random_family(&mut rng) else { continue };
            for (lo, hi) in [(0.0, 10.0), (0.0, 3.0), (2.0, 40.0)] {
                if let Some(merged) = same_merge(&cp, lo, hi) {
                    compared += 1;
                    found += usize::from(merged);
                }
            }
        }
        assert!(
            compared > 2000 && found > 500,
            "{compared} compared, {found} with a merge"
        );
    }
}
