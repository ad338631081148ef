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
    // Labels at the crossing speeds.
    let speeds: Vec<f64> = cands.iter().map(|x| x.0).collect();
    let labelled = track(cp, &speeds)?;
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

    let (weave_real_pair_merge, weave_merge_eigenvalue) = match weave_merge(cp, v_min.max(0.0), v_max)? {
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

/// `(v_d, s_d)`: lowest speed in `[lo, hi]` where the two weave roots turn from real
/// to complex, and the double root there. The grid cell is bisected on the state
/// of the *weave-labelled* roots (labels carried by continuation from the cell's
/// lower end, so another pair merging in the same cell cannot be mistaken for it),
/// then `(s, v)` is polished by Newton on `p = p_s = 0`.
fn weave_merge<S: Spectrum + ?Sized>(cp: &S, lo: f64, hi: f64) -> Result<Option<(f64, f64)>, EigenError> {
    if !(hi > lo) {
        return Ok(None);
    }
    let grid: Vec<f64> = (0..=MERGE_GRID)
        .map(|i| lo + (hi - lo) * (i as f64 / MERGE_GRID as f64))
        .collect();
    let lab = track(cp, &grid)?;
    for i in 0..MERGE_GRID {
        if weave_state(&lab[i]) != Some(true) || weave_state(&lab[i + 1]) != Some(false) {
            continue;
        }
        let (mut a, mut b) = (grid[i], grid[i + 1]);
        let (mut la, mut lb) = (lab[i], lab[i + 1]);
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
        return Ok(Some(match double_root_newton(cp, s0, vm) {
            Some((v, s)) if (v - vm).abs() <= 1e-9 * vm.abs().max(1.0) && (s - s0).abs() <= 1e-3 * (1.0 + s0.abs()) => {
                (v, s)
            }
            _ => (vm, s0),
        }));
    }
    Ok(None)
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
