//! Linear analysis of any model: the roll-steer equations
//! `M(v) q'' + C(v) q' + K(v) q = 0` at each forward speed `v`, whatever
//! their dependence on the speed (steer damping, friction's describing
//! function, a speed-scheduled controller, drag and rolling resistance).
//!
//! The canonical form of Meijaard et al. (2007) is the special case where
//! `M` is constant, `C` linear and `K` quadratic in `v`: [`LinearBicycle`]s
//! that have it ([`CanonicalMatrices`]) keep the exact closed-form path
//! ([`eigen_sweep`], [`critical_speeds`]). Every other one goes through the
//! same mode tracking (labels by continuation from an anchor speed, see the
//! module docs of [`crate::eigen`]) on the characteristic quartic
//! `det(M s^2 + C s + K)` formed at each speed, and its critical speeds are
//! found as the canonical ones are, from smooth functions of the speed: a
//! real root crosses zero where `k0(v) = det K(v) = 0`, a complex pair
//! crosses the imaginary axis where the Hurwitz determinant
//! `H = k1 k2 k3 - k4 k1^2 - k0 k3^2` vanishes with `k1 / k3 > 0`. Without
//! closed forms, both are bracketed on a grid of the speed range and
//! bisected to rounding; the direction of each crossing uses speed
//! derivatives of the coefficients by central differences.

use super::critical::{check_range, finish};
use super::states::{self, StateSpaceBicycle};
use super::*;
use nalgebra::Matrix4;

/// The linear roll-steer equations at one speed, `M q'' + C q' + K q = 0`,
/// `q = [roll phi, steer delta]` in the benchmark's sign convention.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedMatrices {
    /// Mass matrix (kg m^2).
    pub mass: Matrix2<f64>,
    /// Damping matrix (kg m^2/s).
    pub damping: Matrix2<f64>,
    /// Stiffness matrix (kg m^2/s^2).
    pub stiffness: Matrix2<f64>,
}

impl SpeedMatrices {
    /// State matrix `A` of `x' = A x`, `x = [phi, delta, phi', delta']`;
    /// `None` when the mass matrix is singular.
    pub fn state_matrix(&self) -> Option<Matrix4<f64>> {
        let minv = self.mass.try_inverse()?;
        let mut a = Matrix4::zeros();
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        a.fixed_view_mut::<2, 2>(2, 0).copy_from(&(-(minv * self.stiffness)));
        a.fixed_view_mut::<2, 2>(2, 2).copy_from(&(-(minv * self.damping)));
        Some(a)
    }

    /// Coefficients `[k0, k1, k2, k3, k4]` of `det(M s^2 + C s + K)`.
    pub fn characteristic(&self) -> [f64; 5] {
        let (m, c, k) = (&self.mass, &self.damping, &self.stiffness);
        [det2(k), mixed(c, k), mixed(m, k) + det2(c), mixed(m, c), det2(m)]
    }
}

/// A bicycle whose linear equations are known at every speed: the
/// canonical matrices of a Whipple bicycle, or any generated model
/// linearized at each speed (`bikedyn_runtime::linearize::LinearModel`).
///
/// A model with extra first-order states (lagged tyre forces) has no
/// second-order roll-steer form: it answers [`LinearBicycle::first_order`]
/// and its `at_speed` fails; the analyses here ([`eigen_sweep_of`],
/// [`critical_speeds_of`], [`eigenvalues_of`]) take that path themselves.
pub trait LinearBicycle: Sync {
    /// The roll-steer equations at forward speed `v` (m/s).
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError>;
    /// The canonical form, when the equations have it (the exact path).
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        None
    }
    /// The first-order lateral equations, for a model with extra states.
    fn first_order(&self) -> Option<&dyn StateSpaceBicycle> {
        None
    }
}

impl LinearBicycle for CanonicalMatrices {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        Ok(SpeedMatrices {
            mass: self.m0,
            damping: self.damping(v),
            stiffness: self.stiffness(v),
        })
    }
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        Some(self)
    }
}

impl<T: LinearBicycle + ?Sized> LinearBicycle for Box<T> {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        (**self).at_speed(v)
    }
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        (**self).canonical()
    }
    fn first_order(&self) -> Option<&dyn StateSpaceBicycle> {
        (**self).first_order()
    }
}

impl<T: LinearBicycle + ?Sized> LinearBicycle for &T {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        (**self).at_speed(v)
    }
    fn canonical(&self) -> Option<&CanonicalMatrices> {
        (**self).canonical()
    }
    fn first_order(&self) -> Option<&dyn StateSpaceBicycle> {
        (**self).first_order()
    }
}

/// The characteristic quartics of a [`LinearBicycle`] without canonical
/// form.
struct General<'a> {
    bike: &'a dyn LinearBicycle,
    scale: f64,
}

impl<'a> General<'a> {
    fn new(bike: &'a dyn LinearBicycle) -> Result<Self, EigenError> {
        // The speed scale as for the canonical form: where the gravity and
        // speed parts of k2 balance, k2(v) ~ k2(0) + v^2 (k2(1) - k2(0)).
        let k0 = bike.at_speed(0.0)?.characteristic();
        let k1 = bike.at_speed(1.0)?.characteristic();
        let r = (k0[2] / (k1[2] - k0[2])).abs().sqrt();
        let scale = if r.is_finite() && r > 0.0 { r } else { 1.0 };
        Ok(General { bike, scale })
    }

    fn checked(&self, v: f64) -> Result<[f64; 5], EigenError> {
        if !v.is_finite() {
            return Err(EigenError::NonFinite {
                what: format!("speed {v}"),
            });
        }
        let m = self.bike.at_speed(v)?;
        let k = m.characteristic();
        if !k.iter().all(|x| x.is_finite()) {
            return Err(EigenError::NonFinite {
                what: format!("linear equations at {v} m/s"),
            });
        }
        let scale = (m.mass[(0, 0)] * m.mass[(1, 1)]).abs() + (m.mass[(0, 1)] * m.mass[(1, 0)]).abs();
        if !(k[4].abs() > 1e-12 * scale) {
            return Err(EigenError::SingularMassMatrix { det: k[4], scale });
        }
        Ok(k)
    }
}

impl Spectrum for General<'_> {
    fn coefficients(&self, v: f64) -> Result<[f64; 5], EigenError> {
        self.checked(v)
    }
    fn coefficient_rates(&self, v: f64) -> Result<[f64; 5], EigenError> {
        // Central differences: only the sign of Re ds/dv at a crossing and
        // the Newton polish of the weave merge use them.
        let h = 1e-5 * v.abs().max(1.0);
        let (a, b) = (self.checked(v + h)?, self.checked(v - h)?);
        Ok(std::array::from_fn(|i| (a[i] - b[i]) / (2.0 * h)))
    }
    fn roots_at(&self, v: f64) -> Result<[C64; 4], EigenError> {
        quartic_roots(&self.checked(v)?).ok_or_else(|| EigenError::NoConvergence {
            what: format!(
                "quartic roots at v = {} m/s",
                crate::number_text::format_significant(v, 10)
            ),
        })
    }
    fn scale(&self) -> f64 {
        self.scale
    }
    fn mirror_symmetric(&self) -> bool {
        false
    }
    fn discriminant(&self, v: f64) -> Option<(f64, Option<u8>)> {
        quartic::discriminant(&self.checked(v).ok()?)
    }
}

/// The four eigenvalues at speed `v` (no labels), sorted by descending real
/// part, then imaginary part.
pub fn eigenvalues_of(bike: &dyn LinearBicycle, v: f64) -> Result<[Complex<f64>; 4], EigenError> {
    if let Some(s) = bike.first_order() {
        return states::eigenvalues_of_states(s, v);
    }
    match bike.canonical() {
        Some(c) => eigenvalues(c, v),
        None => General::new(bike)?.roots_at(v),
    }
}

/// [`eigen_sweep`] for any [`LinearBicycle`]: eigenvalues, continuous mode
/// labels and mode shapes at each speed.
pub fn eigen_sweep_of(bike: &dyn LinearBicycle, speeds: &[f64]) -> Result<EigenSweep, EigenError> {
    if let Some(s) = bike.first_order() {
        return states::eigen_sweep_of_states(s, speeds);
    }
    if let Some(c) = bike.canonical() {
        return eigen_sweep(c, speeds);
    }
    let family = General::new(bike)?;
    let tracked = track(&family, speeds)?;
    let mut points = Vec::with_capacity(speeds.len());
    for (&v, l) in speeds.iter().zip(tracked) {
        let m = bike.at_speed(v)?;
        points.push(EigenPoint {
            v,
            eigenvalues: l.roots,
            modes: l.labels,
            eigenvectors: vectors(&m, &l.roots),
            extra_eigenvalues: Vec::new(),
        });
    }
    Ok(EigenSweep { points })
}

/// A speed's eigenvalues and their mode labels, as an [`EigenPoint`] has
/// them, without the eigenvectors.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelledEigenvalues {
    /// Forward speed (m/s).
    pub v: f64,
    /// The four eigenvalues (1/s).
    pub eigenvalues: [Complex<f64>; 4],
    /// Mode label of each eigenvalue.
    pub modes: [Mode; 4],
    /// The extra eigenvalues of a first-order model (see [`EigenPoint`]).
    pub extra_eigenvalues: Vec<Complex<f64>>,
}

impl From<&EigenPoint> for LabelledEigenvalues {
    /// The point's eigenvalues and labels, without its eigenvectors.
    fn from(p: &EigenPoint) -> Self {
        LabelledEigenvalues {
            v: p.v,
            eigenvalues: p.eigenvalues,
            modes: p.modes,
            extra_eigenvalues: p.extra_eigenvalues.clone(),
        }
    }
}

/// [`eigen_sweep_of`] without the eigenvectors: the same eigenvalues and
/// labels (the labels come from tracking the roots over speed, not from
/// the vectors). A diagram over speed draws no more, and the vectors were
/// about a tenth of computing one in the browser (2026-11-30).
pub fn eigenvalue_sweep_of(bike: &dyn LinearBicycle, speeds: &[f64]) -> Result<Vec<LabelledEigenvalues>, EigenError> {
    if let Some(s) = bike.first_order() {
        // Its extra eigenvalues come from the split that gives the vectors.
        let points = states::eigen_sweep_of_states(s, speeds)?.points;
        return Ok(points
            .into_iter()
            .map(|p| LabelledEigenvalues {
                v: p.v,
                eigenvalues: p.eigenvalues,
                modes: p.modes,
                extra_eigenvalues: p.extra_eigenvalues,
            })
            .collect());
    }
    // As `eigen_sweep` (closed forms) and `eigen_sweep_of` track them.
    let tracked = match bike.canonical() {
        Some(c) => track(&CharPoly::new(c)?, speeds)?,
        None => track(&General::new(bike)?, speeds)?,
    };
    Ok(speeds
        .iter()
        .zip(tracked)
        .map(|(&v, l)| LabelledEigenvalues {
            v,
            eigenvalues: l.roots,
            modes: l.labels,
            extra_eigenvalues: Vec::new(),
        })
        .collect())
}

/// [`critical_speeds`] for any [`LinearBicycle`] over `[v_min, v_max]`.
pub fn critical_speeds_of(bike: &dyn LinearBicycle, v_min: f64, v_max: f64) -> Result<CriticalSpeeds, EigenError> {
    if let Some(s) = bike.first_order() {
        return states::critical_speeds_of_states(s, v_min, v_max);
    }
    if let Some(c) = bike.canonical() {
        return critical_speeds(c, v_min, v_max);
    }
    check_range(v_min, v_max)?;
    let family = General::new(bike)?;
    let cands = crossing_candidates(&family, v_min, v_max)?;
    finish(&family, cands, v_min, v_max)
}

/// Crossing candidates `(speed, kind, frequency)` of a spectrum without
/// closed forms, ascending: a real root crosses zero where `k0` changes sign,
/// a complex pair crosses the imaginary axis where the Hurwitz determinant
/// changes sign with `w^2 = k1 / k3 > 0`. Bracketed on a grid, bisected.
fn crossing_candidates<S: Spectrum + ?Sized>(
    family: &S,
    v_min: f64,
    v_max: f64,
) -> Result<Vec<(f64, CrossingKind, f64)>, EigenError> {
    let hurwitz = |k: &[f64; 5]| k[1] * k[2] * k[3] - k[4] * k[1] * k[1] - k[0] * k[3] * k[3];
    let mut cands: Vec<(f64, CrossingKind, f64)> = Vec::new();
    if v_max > v_min {
        let grid = crossing_grid(v_min, v_max);
        let ks: Vec<[f64; 5]> = grid.iter().map(|&v| family.coefficients(v)).collect::<Result<_, _>>()?;
        for i in 0..CROSSING_GRID {
            let (a, b) = (grid[i], grid[i + 1]);
            // A real root through zero: k0 changes sign.
            if let Some(v) = bisect(family, a, b, |k| k[0], ks[i][0], ks[i + 1][0])? {
                cands.push((v, CrossingKind::RealRoot, 0.0));
            }
            // A complex pair through the imaginary axis: H changes sign with
            // w^2 = k1 / k3 > 0 there.
            if let Some(v) = bisect(family, a, b, hurwitz, hurwitz(&ks[i]), hurwitz(&ks[i + 1]))? {
                let k = family.coefficients(v)?;
                let w2 = k[1] / k[3];
                if w2 > 0.0 && w2.is_finite() {
                    cands.push((v, CrossingKind::ComplexPair, w2.sqrt()));
                }
            }
        }
    }
    cands.sort_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(std::cmp::Ordering::Equal));
    Ok(cands)
}

/// The zero of `f(coefficients(v))` in `[a, b]` when `fa`, `fb` have opposite
/// signs (bisection to rounding), `None` otherwise. An exact zero at the
/// lower end counts for the cell below, so a grid point is found once.
fn bisect<S: Spectrum + ?Sized>(
    family: &S,
    mut a: f64,
    mut b: f64,
    f: impl Fn(&[f64; 5]) -> f64,
    mut fa: f64,
    fb: f64,
) -> Result<Option<f64>, EigenError> {
    if fb == 0.0 {
        return Ok(Some(b));
    }
    if !(fa * fb < 0.0) {
        return Ok(None);
    }
    for _ in 0..200 {
        let m = 0.5 * (a + b);
        if m <= a || m >= b {
            break;
        }
        let fm = f(&family.coefficients(m)?);
        if fm == 0.0 {
            return Ok(Some(m));
        }
        if (fm < 0.0) == (fa < 0.0) {
            a = m;
            fa = fm;
        } else {
            b = m;
        }
    }
    Ok(Some(0.5 * (a + b)))
}

/// Eigenvectors of the four roots, conjugate pairs exactly conjugate.
fn vectors(m: &SpeedMatrices, roots: &[C64; 4]) -> [[Complex<f64>; 4]; 4] {
    let mut vecs = [[C64::new(0.0, 0.0); 4]; 4];
    for k in 0..4 {
        let s = roots[k];
        vecs[k] = if s.im < 0.0 {
            let up = eigenvector_of(m, s.conj());
            [up[0].conj(), up[1].conj(), up[2].conj(), up[3].conj()]
        } else {
            eigenvector_of(m, s)
        };
    }
    vecs
}

#[cfg(test)]
mod tests {
    use super::super::critical::weave_merge_on_labelled_grid;
    use super::*;
    use crate::closed_form::meijaard_canonical;
    use crate::parameters::BenchmarkParameters;

    /// The benchmark bicycle with trail `c` and a steer damper
    /// `c_steer` (N m s/rad): no canonical form, so the general path.
    struct Damped {
        canonical: CanonicalMatrices,
        c_steer: f64,
    }

    impl LinearBicycle for Damped {
        fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
            let mut m = self.canonical.at_speed(v)?;
            m.damping[(1, 1)] += self.c_steer;
            Ok(m)
        }
    }

    /// Without the eigenvectors, a sweep has the eigenvalues and labels of
    /// the whole one, bit for bit, on the closed-form path and the general.
    #[test]
    fn eigenvalue_sweep_is_the_eigen_sweep_without_its_vectors() {
        let speeds: Vec<f64> = (0..=200).map(|k| 0.05 * k as f64).collect();
        let canonical = meijaard_canonical(&BenchmarkParameters::benchmark_bicycle());
        let damped = Damped {
            canonical,
            c_steer: 0.3,
        };
        for bike in [&canonical as &dyn LinearBicycle, &damped] {
            let whole = eigen_sweep_of(bike, &speeds).expect("a sweep");
            let values = eigenvalue_sweep_of(bike, &speeds).expect("a sweep");
            assert_eq!(whole.points.len(), values.len());
            for (p, q) in whole.points.iter().zip(&values) {
                assert_eq!(
                    (p.v, p.eigenvalues, p.modes, &p.extra_eigenvalues),
                    (q.v, q.eigenvalues, q.modes, &q.extra_eigenvalues)
                );
            }
        }
    }

    /// On the general path (steer damping: no canonical form) the weave
    /// merge bracketed by the discriminant is the one a labelled grid
    /// finds, over trails and dampers, or neither finds one.
    #[test]
    fn weave_merge_of_damped_designs_is_bracketed_alike_by_the_discriminant() {
        let mut found = 0;
        for i in 0..=40 {
            for j in 0..=10 {
                let mut p = BenchmarkParameters::benchmark_bicycle();
                p.trail = -0.02 + 0.005 * i as f64;
                let bike = Damped {
                    canonical: meijaard_canonical(&p),
                    c_steer: 0.05 * j as f64,
                };
                let family = General::new(&bike).expect("a design");
                let fast = finish(&family, Vec::new(), 0.0, 10.0).expect("critical speeds");
                let grid = weave_merge_on_labelled_grid(&family, 0.0, 10.0).expect("the labelled grid");
                match (fast.weave_real_pair_merge.zip(fast.weave_merge_eigenvalue), grid) {
                    (None, None) => {}
                    (Some((v, s)), Some((vg, sg))) => {
                        found += 1;
                        assert!(
                            (v - vg).abs() <= 1e-12 * vg.max(1.0),
                            "{v} vs {vg}, c {}, c_steer {}",
                            p.trail,
                            bike.c_steer
                        );
                        assert!((s - sg).abs() <= 1e-9 * sg.abs().max(1.0), "{s} vs {sg}");
                    }
                    other => panic!("{other:?}, c {}, c_steer {}", p.trail, bike.c_steer),
                }
            }
        }
        assert!(found > 200, "{found}");
    }
}
