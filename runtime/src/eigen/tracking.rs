//! Mode tracking: the four roots labelled weave, capsize, castering (or a
//! merged pair) at every speed, by continuation from an anchor speed where
//! the pattern of the roots names them (one complex pair and two real
//! roots), matching the roots from one speed to the next.

use super::float;
use super::*;

/// All 24 permutations of 0..4, identity first.
const PERMS: [[usize; 4]; 24] = {
    let mut out = [[0usize; 4]; 24];
    let mut n = 0;
    let mut a = 0;
    while a < 4 {
        let mut b = 0;
        while b < 4 {
            let mut c = 0;
            while c < 4 {
                if a != b && a != c && b != c {
                    let d = 6 - a - b - c;
                    out[n] = [a, b, c, d];
                    n += 1;
                }
                c += 1;
            }
            b += 1;
        }
        a += 1;
    }
    out
};

/// Labelled roots of one branch set: `roots[i]` carries `labels[i]`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Labelled {
    pub roots: [C64; 4],
    pub labels: [Mode; 4],
}

fn rank(m: Mode) -> u16 {
    m.rank()
}

impl Labelled {
    /// Canonical order: by label rank; within a label, descending imaginary then real part.
    pub(super) fn canonical(mut self) -> Self {
        let mut idx = [0usize, 1, 2, 3];
        crate::small_sort::sort4_by(&mut idx, |&i, &j| {
            rank(self.labels[i])
                .cmp(&rank(self.labels[j]))
                .then(
                    self.roots[j]
                        .im
                        .partial_cmp(&self.roots[i].im)
                        .unwrap_or(std::cmp::Ordering::Equal),
                )
                .then(
                    self.roots[j]
                        .re
                        .partial_cmp(&self.roots[i].re)
                        .unwrap_or(std::cmp::Ordering::Equal),
                )
        });
        let (r, l) = (self.roots, self.labels);
        for k in 0..4 {
            self.roots[k] = r[idx[k]];
            self.labels[k] = l[idx[k]];
        }
        self
    }

    /// Mirror to negative speed: roots negated, labels kept.
    fn mirrored(self) -> Self {
        let mut r = self.roots;
        for x in r.iter_mut() {
            *x = neg(*x);
        }
        Labelled {
            roots: r,
            labels: self.labels,
        }
        .canonical()
    }
}

/// Anchor pattern: exactly one complex pair and two real roots, in any
/// order: the pair is the weave, the larger real root capsize and the
/// smaller castering.
fn classify_anchor(z: &[C64; 4]) -> Option<[Mode; 4]> {
    let reals: Vec<usize> = (0..4).filter(|&i| z[i].im == 0.0).collect();
    let [a, b] = reals[..] else {
        return None;
    };
    let (big, small) = if z[a].re >= z[b].re { (a, b) } else { (b, a) };
    let mut l = [Mode::Weave; 4];
    l[big] = Mode::Capsize;
    l[small] = Mode::Castering;
    Some(l)
}

/// Fallback classification when no anchor speed exists (input sorted desc).
fn classify_fallback(z: &[C64; 4]) -> [Mode; 4] {
    let n_real = z.iter().filter(|x| x.im == 0.0).count();
    if n_real == 4 {
        return [Mode::Weave, Mode::Weave, Mode::Capsize, Mode::Castering];
    }
    if let Some(l) = classify_anchor(z) {
        return l;
    }
    // two complex pairs: the pair with the larger imaginary part is weave
    let mut top = 0;
    for i in 1..4 {
        if z[i].im > z[top].im {
            top = i;
        }
    }
    let mut l = [Mode::Other(2); 4];
    l[top] = Mode::Weave;
    if let Some(j) = (0..4).find(|&j| j != top && z[j] == z[top].conj()) {
        l[j] = Mode::Weave;
    }
    l
}

/// Best matching of `new` roots to `prev` branches. Returns the reordered new roots
/// and whether the matching is unambiguous.
fn match_roots(prev: &Labelled, new: &[C64; 4]) -> ([C64; 4], bool) {
    // The 16 squared distances once, then the 24 sums of four.
    let mut d = [[0.0f64; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            d[i][j] = (prev.roots[i] - new[j]).norm_sqr();
        }
    }
    // Each permutation's sum written out with constant indices (a loop
    // over the table, with its index checks, was a tenth of the browser's
    // stability map, 2026-12-01): the same sums in the same order, and the
    // first least one chosen, as before.
    macro_rules! sums {
        ($($k:literal)*) => {
            [$(d[0][PERMS[$k][0]] + d[1][PERMS[$k][1]] + d[2][PERMS[$k][2]] + d[3][PERMS[$k][3]]),*]
        };
    }
    let costs: [f64; 24] = sums!(0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23);
    let mut best = (f64::INFINITY, 0usize);
    for (pi, &cost) in costs.iter().enumerate() {
        if cost < best.0 {
            best = (cost, pi);
        }
    }
    let p = PERMS[best.1];
    let out = [new[p[0]], new[p[1]], new[p[2]], new[p[3]]];
    // Squared distances (no square root or `hypot` in this inner loop of
    // every continuation): `dmax <= 0.3 sep`. `float::max` and `min`, not
    // `f64`'s, which are calls in WebAssembly (3 % of the browser's
    // stability map, 2026-11-29); a NaN distance is skipped by both.
    let mut dmax2 = 0.0f64;
    let mut sep2 = f64::INFINITY;
    for i in 0..4 {
        dmax2 = float::max(dmax2, (prev.roots[i] - out[i]).norm_sqr());
        for j in i + 1..4 {
            if prev.labels[i] != prev.labels[j] {
                sep2 = float::min(sep2, (prev.roots[i] - prev.roots[j]).norm_sqr());
                sep2 = float::min(sep2, (out[i] - out[j]).norm_sqr());
            }
        }
    }
    (out, dmax2 <= 0.09 * sep2)
}

/// A complex-conjugate pair is one mode: when two named real modes `A`, `B`
/// form a pair, the pair becomes the merged mode `A-B` and no other label
/// changes. Two *real* roots sharing a merged label (the pair split again) take
/// its components, the lower rank on the larger root. For `Other` labels the
/// old rule stays: the pair takes the lower-ranked label and the displaced one
/// passes to the other root with the pair's label; two real roots sharing a
/// non-weave label become capsize (larger) and castering (smaller).
fn pair_rule(z: &[C64; 4], mut l: [Mode; 4]) -> [Mode; 4] {
    for i in 0..4 {
        if z[i].im <= 0.0 {
            continue;
        }
        let Some(j) = (0..4).find(|&j| j != i && z[j] == z[i].conj()) else {
            continue;
        };
        if l[i] == l[j] {
            continue;
        }
        if let Some(m) = Mode::merge(l[i], l[j]) {
            l[i] = m;
            l[j] = m;
            continue;
        }
        let (lo, hi) = if rank(l[i]) <= rank(l[j]) {
            (l[i], l[j])
        } else {
            (l[j], l[i])
        };
        if let Some(k) = (0..4).find(|&k| k != i && k != j && l[k] == lo) {
            l[k] = hi;
        }
        l[i] = lo;
        l[j] = lo;
    }
    for i in 0..4 {
        for j in i + 1..4 {
            if l[i] == l[j] && l[i] != Mode::Weave && z[i].im == 0.0 && z[j].im == 0.0 {
                let (big, small) = if z[i].re >= z[j].re { (i, j) } else { (j, i) };
                let (a, b) = l[i].components().unwrap_or((Mode::Capsize, Mode::Castering));
                l[big] = a;
                l[small] = b;
            }
        }
    }
    l
}

/// Whether the roots moved by a finite amount over a vanishing speed step:
/// a model with extra states (see [`StateSpaceBicycle`]) chooses its four
/// bicycle modes from a larger spectrum at each speed, and where a bicycle
/// mode merges with an extra one (a leaning rider's lean with capsize, or
/// with castering) the chosen four change at once. (Roots that only collide
/// move by the square root of the step, 1e-6 of their size at most; the
/// threshold 1e-3 lies between.) The quartic's roots of a second-order model
/// are continuous in speed and never jump.
fn jumped(prev: &[C64; 4], new: &[C64; 4]) -> bool {
    let size = prev.iter().chain(new).map(|z| z.norm()).fold(1.0, float::max);
    let moved = (0..4).map(|k| (prev[k] - new[k]).norm()).fold(0.0, float::max);
    moved > 1e-3 * size
}

/// Continue labelled roots from `v0` (>= 0) to `v1` (>= 0) adaptively.
pub(super) fn continue_to<S: Spectrum + ?Sized>(
    cp: &S,
    start: Labelled,
    v0: f64,
    v1: f64,
) -> Result<Labelled, EigenError> {
    let mut cur = start;
    let mut v = v0;
    if v0 == v1 {
        return Ok(cur);
    }
    let hmin = 1e-12 * float::max(float::max(v0.abs(), v1.abs()), 1.0);
    let mut h = v1 - v0;
    let mut guard = 0usize;
    while v != v1 {
        guard += 1;
        if guard > 2_000_000 {
            return Err(EigenError::NoConvergence {
                what: "mode continuation".into(),
            });
        }
        let vt = if (v1 - v).abs() <= h.abs() * (1.0 + 1e-12) {
            v1
        } else {
            v + h
        };
        let z = cp.roots_at(vt)?;
        let (m, ok) = match_roots(&cur, &z);
        if ok || h.abs() <= hmin {
            // A jump is no continuation: the labels start again from the
            // pattern of the roots where it applies.
            let labels = if !ok && jumped(&cur.roots, &m) {
                classify_anchor(&m).unwrap_or_else(|| pair_rule(&m, cur.labels))
            } else {
                pair_rule(&m, cur.labels)
            };
            cur = Labelled { roots: m, labels };
            v = vt;
            h *= 2.0;
            if h.abs() > (v1 - v).abs() && v != v1 {
                h = v1 - v;
            }
        } else {
            h *= 0.5;
        }
    }
    Ok(cur)
}

/// Characteristic speed of the bicycle, `sqrt(g |b0| / |b2|)` (where the gravity and
/// speed terms of `k2` balance; 3.4 m/s for the benchmark), 1 m/s if undefined.
pub(super) fn speed_scale(cp: &CharPoly) -> f64 {
    let r = (cp.g * cp.b0 / cp.b2).abs().sqrt();
    if r.is_finite() && r > 0.0 {
        r
    } else {
        let r = (cp.g * cp.d0 / cp.d2).abs().sqrt();
        if r.is_finite() && r > 0.0 {
            r
        } else {
            1.0
        }
    }
}

/// Anchor speed and labels (a property of the bicycle only, independent of the
/// requested speeds): the first speed of the ladder `30 vs * 2^k` (k = 0..10), then
/// `30 vs / 1.25^k` (k = 1..80), with the pattern *one complex pair + two real roots*
/// (`vs` = [`speed_scale`]); otherwise the fallback classification at `30 vs`.
fn anchor<S: Spectrum + ?Sized>(cp: &S) -> Result<(f64, Labelled), EigenError> {
    let base = 30.0 * cp.scale();
    let ladder = (0..=10)
        .map(|k| base * 2f64.powi(k))
        .chain((1..=80).map(|k| base / 1.25f64.powi(k)));
    for v in ladder {
        // A ladder speed where the quartic solver does not converge (extreme
        // speeds of unusual designs, e.g. 4.6e5 m/s for a two-mass-skate
        // variant) is skipped: the anchor is only a starting point.
        let Ok(z) = cp.roots_at(v) else {
            continue;
        };
        if let Some(l) = classify_anchor(&z) {
            return Ok((v, Labelled { roots: z, labels: l }));
        }
    }
    let z = cp.roots_at(base)?;
    Ok((
        base,
        Labelled {
            roots: z,
            labels: classify_fallback(&z),
        },
    ))
}

/// Labels at every `|v|` of `speeds` (any order, any sign). Returns labelled roots in
/// canonical order, one per input speed. Every speed is reached by continuation
/// from the anchor, so labels do not depend on which other speeds are requested.
pub(crate) fn track<S: Spectrum + ?Sized>(cp: &S, speeds: &[f64]) -> Result<Vec<Labelled>, EigenError> {
    if speeds.is_empty() {
        return Ok(Vec::new());
    }
    for &v in speeds {
        if !v.is_finite() {
            return Err(EigenError::NonFinite {
                what: format!("speed {v}"),
            });
        }
    }
    let (va, start) = anchor(cp)?;
    let mut out = vec![start; speeds.len()];
    // A mirror-symmetric family is tracked in |v| and mirrored; any other
    // family (damping, controllers: not even in v) along the signed speed,
    // continuing through zero.
    let sym = cp.mirror_symmetric();
    let key = |v: f64| if sym { v.abs() } else { v };
    let by_key = |i: &usize, j: &usize| {
        key(speeds[*i])
            .partial_cmp(&key(speeds[*j]))
            .unwrap_or(std::cmp::Ordering::Equal)
    };
    // above the anchor: ascending; below: descending
    let mut up: Vec<usize> = (0..speeds.len()).filter(|&i| key(speeds[i]) > va).collect();
    up.sort_by(by_key);
    let mut down: Vec<usize> = (0..speeds.len()).filter(|&i| key(speeds[i]) <= va).collect();
    down.sort_by(|i, j| by_key(j, i));
    for chain in [up, down] {
        let (mut vcur, mut cur) = (va, start);
        for i in chain {
            let v = key(speeds[i]);
            cur = continue_to(cp, cur, vcur, v)?.canonical();
            vcur = v;
            out[i] = if sym && speeds[i] < 0.0 { cur.mirrored() } else { cur };
        }
    }
    Ok(out)
}
