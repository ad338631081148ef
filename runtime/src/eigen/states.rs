//! Linear analysis of models with extra first-order states (lagged lateral
//! tyre forces): the lateral equations are `x' = A(v) x` with `x` the roll,
//! steer and lateral coordinates, their rates and the extra states, and no
//! second-order roll-steer form exists.
//!
//! The spectrum of `A(v)` holds the four modes of the bicycle (weave,
//! capsize, castering, or their merged pairs) and the modes the extra states
//! add (a tyre-force lag per wheel, and the lateral slip and yaw they free).
//! Which four eigenvalues are the bicycle's is decided at each speed by
//! participation factors (Pérez-Arriaga, Verghese and Schweppe 1982): the
//! share `|w_i x_i| / sum_j |w_j x_j|` of state `i` in the mode with right
//! and left eigenvectors `x`, `w`, independent of the states' units. The four
//! with the smallest share of the extra states (conjugate pairs kept whole)
//! are the bicycle's modes. (Not the largest share of roll and steer: a
//! tyre model's steer-dominated shimmy-like pair near 30 rad/s has more
//! steer in it than the weave at higher speeds, but it lives on the tyre
//! forces.) The bicycle's modes are labelled and tracked as in
//! [`crate::eigen`] (through their characteristic quartic) and give the weave
//! and capsize speeds. Where a bicycle mode merges with an extra one (a
//! leaning rider's slow lean with capsize, the fast lean with castering),
//! the chosen four change at once; the tracking does not carry labels across
//! such a jump but names the roots again by their pattern (the complex pair
//! is the weave, the larger real root capsize). Every other eigenvalue is an extra mode. Crossings
//! are found on the whole spectrum (where the count of eigenvalues with
//! positive real part changes) and labelled by the root that crosses; an
//! extra mode's is `Other(EXTRA)`.

use super::critical::{check_range, finish, named_speeds, stable_intervals};
use super::*;
use super::{crossing_grid, CROSSING_GRID};
use nalgebra::{DMatrix, DVector};

/// The label of a crossing of an extra (non roll-steer) mode.
pub const EXTRA: u8 = 4;

/// The lateral first-order equations `x' = A x` at one speed.
#[derive(Clone, Debug, PartialEq)]
pub struct LateralStates {
    /// State names (coordinates, `d` + coordinate for rates, extra states).
    pub names: Vec<String>,
    /// State matrix `A` (1/s, mixed units).
    pub a: DMatrix<f64>,
    /// Positions of roll, steer, roll rate and steer rate in the state.
    pub roll_steer: [usize; 4],
    /// Sign from the model's steer angle to the benchmark's (`-1` for the
    /// thesis's axes, whose steer angle is minus the benchmark's).
    pub steer_sign: f64,
    /// Positions of the extra states (those the rolling-without-slip
    /// bicycle lacks).
    pub extra: Vec<usize>,
    /// How many eigenvalues vanish at every speed (the heading of a model
    /// whose yaw is free: straight running in another direction is another
    /// steady motion). They are left out of the spectrum.
    pub neutral: usize,
}

/// A bicycle whose linear equations are first order (extra states).
pub trait StateSpaceBicycle: Sync {
    /// The lateral equations at forward speed `v` (m/s).
    fn lateral_states(&self, v: f64) -> Result<LateralStates, EigenError>;
}

/// The spectrum at one speed split into the bicycle's four modes and the
/// extra ones.
struct Split {
    /// Sorted by descending real, then imaginary part.
    bicycle: [C64; 4],
    /// Right eigenvectors of `bicycle`, restricted to `[phi, delta, phi',
    /// delta']` in the benchmark's signs.
    vectors: [[C64; 4]; 4],
    /// By descending real part.
    extra: Vec<C64>,
}

fn split(ls: &LateralStates, v: f64) -> Result<Split, EigenError> {
    let n = ls.a.nrows();
    if n < 4 || ls.a.ncols() != n || ls.roll_steer.iter().any(|&i| i >= n) {
        return Err(EigenError::InvalidArgument {
            what: format!("lateral state matrix of size {n} without roll, steer and their rates"),
        });
    }
    if !ls.a.iter().all(|x| x.is_finite()) {
        return Err(EigenError::NonFinite {
            what: format!("lateral state matrix at {v} m/s"),
        });
    }
    let z = nalgebra::linalg::Schur::try_new(ls.a.clone(), f64::EPSILON, 100 * n * n)
        .ok_or_else(|| EigenError::NoConvergence {
            what: format!("Schur form of the lateral state matrix at {v} m/s"),
        })?
        .complex_eigenvalues();
    let ac = ls.a.map(|x| C64::new(x, 0.0));
    let norm = ls.a.abs().max().max(1.0);
    // Numerically zero eigenvalues are real: where a root crosses zero
    // beside the neutral one, the double zero splits into a pair of size
    // rounding.
    let tiny = 1e-10 * norm;
    let z = z.map(|s| if s.norm() <= tiny { C64::new(s.re, 0.0) } else { s });
    // One entry per mode: real roots, and the upper member of each pair.
    let modes: Vec<C64> = z.iter().copied().filter(|s| s.im >= 0.0).collect();
    // (eigenvalue, score, right vector, largest share of one state)
    let mut scored = Vec::with_capacity(modes.len());
    for &s in &modes {
        let x = inverse_iteration(&ac, s, norm, false);
        let w = inverse_iteration(&ac, s, norm, true);
        let part: Vec<f64> = (0..n).map(|i| (w[i] * x[i]).norm()).collect();
        let total: f64 = part.iter().sum();
        let ok = total > 0.0 && total.is_finite();
        // Score: the share of everything but the extra states.
        let share = if ok {
            1.0 - ls.extra.iter().map(|&i| part[i]).sum::<f64>() / total
        } else {
            0.0
        };
        let single = if ok {
            part.iter().cloned().fold(0.0, f64::max) / total
        } else {
            0.0
        };
        scored.push((s, share, x, single));
    }
    // Leave out the neutral eigenvalues: the real ones living on one state
    // (the heading lives on the yaw angle alone), nearest zero; not a
    // physical root passing through zero there (capsize at its critical
    // speed is spread over roll, yaw and lateral motion). Its computed
    // value is rounding, which for stiff tyres is far from tiny.
    for _ in 0..ls.neutral {
        let pick = (0..scored.len())
            .filter(|&k| scored[k].0.im == 0.0 && scored[k].3 >= 0.9)
            .min_by(|&i, &j| scored[i].0.norm().total_cmp(&scored[j].0.norm()))
            .or_else(|| {
                (0..scored.len())
                    .filter(|&k| scored[k].0.im == 0.0)
                    .min_by(|&i, &j| scored[i].0.norm().total_cmp(&scored[j].0.norm()))
            });
        if let Some(k) = pick {
            scored.remove(k);
        }
    }
    let scored: Vec<(C64, f64, DVector<C64>)> = scored.into_iter().map(|(s, sc, x, _)| (s, sc, x)).collect();
    // Whole modes (a pair counts two) by ascending share of the extra
    // states, each taken while it fits in four. (Not the set of largest
    // summed score: at speed a tyre model's castering root lives half on
    // the tyre forces, and a sum would trade it with capsize for the
    // shimmy-like pair.) If that cannot fill four, the set of largest sum.
    let size = |s: &C64| if s.im > 0.0 { 2 } else { 1 };
    let mut order: Vec<usize> = (0..scored.len()).collect();
    order.sort_by(|&i, &j| scored[j].1.total_cmp(&scored[i].1));
    let mut chosen = Vec::new();
    let mut count = 0;
    for &k in &order {
        if count + size(&scored[k].0) <= 4 {
            count += size(&scored[k].0);
            chosen.push(k);
        }
    }
    if count != 4 {
        let mut best: Option<(f64, Vec<usize>)> = None;
        choose(&scored, &size, 0, 0, 0.0, &mut Vec::new(), &mut best);
        chosen = best
            .ok_or_else(|| EigenError::InvalidArgument {
                what: format!("no set of four roll-steer eigenvalues in the lateral spectrum at {v} m/s"),
            })?
            .1;
    }
    let mut bicycle = Vec::with_capacity(4);
    let mut extra = Vec::new();
    for (k, (s, _, x)) in scored.iter().enumerate() {
        let members: Vec<C64> = if s.im > 0.0 { vec![*s, s.conj()] } else { vec![*s] };
        if chosen.contains(&k) {
            let u = restrict(ls, x);
            for m in members {
                let vec = if m.im < 0.0 { u.map(|c| c.conj()) } else { u };
                bicycle.push((m, vec));
            }
        } else {
            extra.extend(members);
        }
    }
    bicycle.sort_by(|a, b| b.0.re.total_cmp(&a.0.re).then(b.0.im.total_cmp(&a.0.im)));
    extra.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
    Ok(Split {
        bicycle: std::array::from_fn(|k| bicycle[k].0),
        vectors: std::array::from_fn(|k| bicycle[k].1),
        extra,
    })
}

/// Exhaustive choice of modes `k >= from` completing `size` to four.
fn choose(
    scored: &[(C64, f64, DVector<C64>)],
    size: &dyn Fn(&C64) -> usize,
    from: usize,
    count: usize,
    score: f64,
    picked: &mut Vec<usize>,
    best: &mut Option<(f64, Vec<usize>)>,
) {
    if count == 4 {
        if best.as_ref().is_none_or(|b| score > b.0) {
            *best = Some((score, picked.clone()));
        }
        return;
    }
    for k in from..scored.len() {
        let sz = size(&scored[k].0);
        if count + sz <= 4 {
            picked.push(k);
            choose(
                scored,
                size,
                k + 1,
                count + sz,
                score + sz as f64 * scored[k].1,
                picked,
                best,
            );
            picked.pop();
        }
    }
}

/// A right (or, `left`, left) eigenvector of eigenvalue `s` by two steps of
/// inverse iteration with a shift just off `s` (the solve of `A - s I`
/// itself would be singular).
fn inverse_iteration(a: &DMatrix<C64>, s: C64, norm: f64, left: bool) -> DVector<C64> {
    let n = a.nrows();
    let shift = s + C64::new(1e-10 * (norm + s.norm()), 1e-10 * (norm + s.norm()));
    let mut m = if left { a.transpose() } else { a.clone() };
    for i in 0..n {
        m[(i, i)] -= shift;
    }
    let lu = m.lu();
    // A start vector with no special structure.
    let mut x = DVector::from_fn(n, |i, _| C64::new(1.0 + 0.37 * i as f64, 0.1 * ((i * 7) % 5) as f64));
    for _ in 0..3 {
        match lu.solve(&x) {
            Some(y) => {
                let nrm = y.norm();
                if !(nrm > 0.0 && nrm.is_finite()) {
                    break;
                }
                x = y / C64::new(nrm, 0.0);
            }
            None => break,
        }
    }
    x
}

/// `[phi, delta, phi', delta']` of a full eigenvector in the benchmark's
/// signs: unit 2-norm, phase making the larger of `phi`, `delta` real and
/// positive (as [`eigenvector_of`]).
fn restrict(ls: &LateralStates, x: &DVector<C64>) -> [C64; 4] {
    let sign = [1.0, ls.steer_sign, 1.0, ls.steer_sign];
    let mut u: [C64; 4] = std::array::from_fn(|k| x[ls.roll_steer[k]] * sign[k]);
    let k = if u[0].norm() >= u[1].norm() { 0 } else { 1 };
    let nk = u[k].norm();
    if nk > 0.0 && nk.is_finite() {
        let ph = u[k].conj() / nk;
        u = u.map(|c| c * ph);
        u[k] = C64::new(u[k].re, 0.0);
    }
    let nrm = u.iter().map(|c| c.norm_sqr()).sum::<f64>().sqrt();
    if nrm > 0.0 && nrm.is_finite() {
        u = u.map(|c| c / nrm);
    }
    u
}

/// The bicycle modes of a first-order model as a [`Spectrum`] (their
/// characteristic quartic `prod (s - s_k)`), so labels, tracking, the weave
/// merge and crossings work as for the second-order models.
struct Lateral<'a> {
    bike: &'a dyn StateSpaceBicycle,
    scale: f64,
}

impl<'a> Lateral<'a> {
    fn new(bike: &'a dyn StateSpaceBicycle) -> Result<Self, EigenError> {
        let mut l = Lateral { bike, scale: 1.0 };
        // As for the second-order models: where gravity and speed parts of
        // the s^2 coefficient balance.
        let (k0, k1) = (l.coefficients(0.0)?, l.coefficients(1.0)?);
        let r = (k0[2] / (k1[2] - k0[2])).abs().sqrt();
        if r.is_finite() && r > 0.0 {
            l.scale = r;
        }
        Ok(l)
    }

    fn split(&self, v: f64) -> Result<Split, EigenError> {
        if !v.is_finite() {
            return Err(EigenError::NonFinite {
                what: format!("speed {v}"),
            });
        }
        split(&self.bike.lateral_states(v)?, v)
    }
}

impl Spectrum for Lateral<'_> {
    fn coefficients(&self, v: f64) -> Result<[f64; 5], EigenError> {
        let r = self.split(v)?.bicycle;
        // prod (s - r_k), low order first; real up to rounding (pairs are
        // exactly conjugate).
        let mut c = [
            C64::new(1.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
        ];
        let mut deg = 0;
        for root in r {
            deg += 1;
            for i in (1..=deg).rev() {
                c[i] = c[i - 1] - root * c[i];
            }
            c[0] = -root * c[0];
        }
        Ok(std::array::from_fn(|i| c[i].re))
    }
    fn coefficient_rates(&self, v: f64) -> Result<[f64; 5], EigenError> {
        let h = 1e-5 * v.abs().max(1.0);
        let (a, b) = (self.coefficients(v + h)?, self.coefficients(v - h)?);
        Ok(std::array::from_fn(|i| (a[i] - b[i]) / (2.0 * h)))
    }
    fn roots_at(&self, v: f64) -> Result<[C64; 4], EigenError> {
        Ok(self.split(v)?.bicycle)
    }
    fn scale(&self) -> f64 {
        self.scale
    }
    fn mirror_symmetric(&self) -> bool {
        false
    }
}

/// The four roll-steer eigenvalues at speed `v`, by descending real part.
pub(crate) fn eigenvalues_of_states(bike: &dyn StateSpaceBicycle, v: f64) -> Result<[C64; 4], EigenError> {
    Lateral::new(bike)?.split(v).map(|s| s.bicycle)
}

/// Labelled sweep: the four bicycle modes as for every model, the extra
/// modes in [`EigenPoint::extra_eigenvalues`].
pub(crate) fn eigen_sweep_of_states(bike: &dyn StateSpaceBicycle, speeds: &[f64]) -> Result<EigenSweep, EigenError> {
    let family = Lateral::new(bike)?;
    let tracked = track(&family, speeds)?;
    let mut points = Vec::with_capacity(speeds.len());
    for (&v, l) in speeds.iter().zip(tracked) {
        let s = family.split(v)?;
        // The tracked roots are the split's, reordered by label.
        let eigenvectors = std::array::from_fn(|k| {
            let j = (0..4)
                .min_by(|&i, &j| {
                    (s.bicycle[i] - l.roots[k])
                        .norm()
                        .total_cmp(&(s.bicycle[j] - l.roots[k]).norm())
                })
                .unwrap_or(k);
            s.vectors[j]
        });
        points.push(EigenPoint {
            v,
            eigenvalues: l.roots,
            modes: l.labels,
            eigenvectors,
            extra_eigenvalues: s.extra,
        });
    }
    Ok(EigenSweep { points })
}

/// Critical speeds of a first-order model. The crossing speeds are those
/// where the count of eigenvalues with positive real part changes (the
/// whole spectrum, bracketed on a grid and bisected to rounding): a robust
/// test even where the capsize root passes through zero beside the neutral
/// heading (a double zero: each of the two is then known only to about
/// `sqrt(eps |A|)`, 1e-6 1/s, so the crossing speed to about 1e-4 m/s). Each
/// crossing is labelled by the root whose real part changes sign beside it
/// (a bicycle mode's label, or `Other(EXTRA)`). The weave merge comes from
/// the bicycle modes' quartic. Stable intervals are judged on the whole
/// spectrum.
pub(crate) fn critical_speeds_of_states(
    bike: &dyn StateSpaceBicycle,
    v_min: f64,
    v_max: f64,
) -> Result<CriticalSpeeds, EigenError> {
    check_range(v_min, v_max)?;
    let family = Lateral::new(bike)?;
    // The quartic's crossings are not needed (see above): `finish` without
    // candidates gives the weave merge.
    let mut out = finish(&family, Vec::new(), v_min, v_max)?;
    let unstable = |v: f64| -> Result<usize, EigenError> {
        let s = family.split(v)?;
        Ok(s.bicycle.iter().chain(&s.extra).filter(|z| z.re > 0.0).count())
    };
    let mut crossings = Vec::new();
    if v_max > v_min {
        let grid = crossing_grid(v_min, v_max);
        let counts: Vec<usize> = grid.iter().map(|&v| unstable(v)).collect::<Result<_, _>>()?;
        for i in 0..CROSSING_GRID {
            if counts[i] == counts[i + 1] {
                continue;
            }
            let (mut a, mut b) = (grid[i], grid[i + 1]);
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if m <= a || m >= b {
                    break;
                }
                if unstable(m)? == counts[i] {
                    a = m;
                } else {
                    b = m;
                }
            }
            let v = 0.5 * (a + b);
            // Which root crossed: the one whose real part has changed sign
            // between speeds a little below and above (1e-3 m/s: beyond the
            // rounding of a root near the neutral double zero, about 1e-6
            // 1/s, yet within the grid cell).
            let h = (1e-3 * v.abs().max(1.0)).min(0.25 * (grid[i + 1] - grid[i]));
            let sides = eigen_sweep_of_states(bike, &[v - h, v + h])?;
            let (lo, hi) = (&sides.points[0], &sides.points[1]);
            let flipped = (0..4).find(|&k| (lo.eigenvalues[k].re > 0.0) != (hi.eigenvalues[k].re > 0.0));
            let (mode, z) = match flipped {
                Some(k) => (hi.modes[k], hi.eigenvalues[k]),
                None => {
                    let z = hi
                        .extra_eigenvalues
                        .iter()
                        .zip(&lo.extra_eigenvalues)
                        .find(|(a, b)| (a.re > 0.0) != (b.re > 0.0))
                        .map(|(a, _)| *a)
                        .unwrap_or_default();
                    (Mode::Other(EXTRA), z)
                }
            };
            // Its frequency at the crossing itself.
            let at = family.split(v)?;
            let z = at
                .bicycle
                .iter()
                .chain(&at.extra)
                .copied()
                .min_by(|a, b| (a - z).norm().total_cmp(&(b - z).norm()))
                .unwrap_or(z);
            crossings.push(Crossing {
                speed: v,
                mode,
                direction: if counts[i + 1] > counts[i] {
                    CrossingDirection::Destabilizing
                } else {
                    CrossingDirection::Stabilizing
                },
                kind: if z.im != 0.0 {
                    CrossingKind::ComplexPair
                } else {
                    CrossingKind::RealRoot
                },
                frequency: z.im.abs(),
            });
        }
    }
    crossings.sort_by(|a, b| a.speed.partial_cmp(&b.speed).unwrap_or(std::cmp::Ordering::Equal));
    crossings.dedup_by(|a, b| a.speed == b.speed && a.mode == b.mode);
    (out.weave_speed, out.capsize_speed) = named_speeds(&crossings);
    out.stable_intervals = stable_intervals(v_min, v_max, &crossings, |v| Ok(unstable(v)? == 0))?;
    out.crossings = crossings;
    Ok(out)
}
