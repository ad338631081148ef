//! Eigenvalues, eigenvectors, mode labels and critical speeds of the canonical
//! linear bicycle `M0 q'' + v C1 q' + (g K0 + v^2 K2) q = 0` (Meijaard et al. 2007),
//! state `x = [phi, delta, phi', delta']`.
//!
//! # Numerics
//! The eigenvalues are the roots of the characteristic quartic
//! `det(M0 s^2 + v C1 s + g K0 + v^2 K2) = k4 s^4 + k3 s^3 + k2 s^2 + k1 s + k0`,
//! whose coefficients are polynomials in `v` computed from the 2x2 entries
//! ([`CharPoly`]). Roots: Ferrari factorisation into two real quadratics, Newton
//! refinement of the factorisation, then guarded Newton polish of every root on the
//! quartic (see `quartic.rs`); conjugate pairs are exactly conjugate, real roots have
//! imaginary part exactly `0.0`. Negative speeds use the exact symmetry
//! `roots(-v) = -roots(v)`.
//!
//! # Mode classification rule
//! Labels are attached to continuous root branches, not to sorted positions, and
//! depend only on the bicycle and the speed (not on which other speeds are asked):
//! 1. *Anchor.* Let `vs = sqrt(g |b0| / |b2|)` be the bicycle's characteristic speed
//!    (where gravity and speed terms of the `s^2` coefficient balance; 3.4 m/s for
//!    the benchmark). On the ladder `30 vs * 2^k` (k = 0..10), then `30 vs / 1.25^k`,
//!    take the first speed where the spectrum is *one complex pair + two real roots*.
//!    There the pair is `Weave`, the more negative real root `Castering`, the other
//!    real root `Capsize` (the generic high-speed picture of an uncontrolled
//!    bicycle: castering goes to `-inf` roughly like `-v`, the weave frequency grows
//!    like `v`, capsize stays small). If no ladder speed has that pattern, fall back
//!    at `30 vs` to: four real roots sorted descending `[Weave, Weave, Capsize,
//!    Castering]`; two complex pairs: the pair with the larger imaginary part
//!    `Weave`, the other `Other(2)`.
//! 2. *Continuation.* Every requested speed is reached from the anchor by adaptive
//!    continuation: between consecutive speeds the roots are matched by the
//!    permutation of least total squared displacement, and the step is halved until
//!    the largest displacement is at most 0.3 times the smallest distance between
//!    roots carrying *different* labels (roots sharing a label, e.g. the two weave
//!    roots at the double root `v_d`, may be close or swap freely). Hence labels
//!    never swap when roots merely pass close to each other (e.g. the capsize root
//!    and a real weave root: an avoided crossing keeps the order along the real
//!    axis). Only at an exact collision of differently-labelled roots (step below
//!    `1e-12 max(1, |v|)`) is the minimal-displacement matching accepted as is.
//! 3. *A conjugate pair is one mode.* If two roots with different labels collide
//!    and leave the real axis as a pair, the pair takes the lower-ranked label
//!    (weave < capsize < castering < other) and the displaced label passes to the
//!    other root that carried the pair's label (e.g. a real weave root merging with
//!    capsize into an oscillation: the pair becomes weave and the remaining real weave
//!    root becomes capsize). Two real roots sharing a non-weave label (a
//!    capsize/castering pair that split again) become capsize (larger) and castering
//!    (smaller).
//! 4. Below the merge speed `v_d` the two real roots continuing the weave pair are
//!    both labelled `Weave` (for the benchmark at `v = 0`: `+5.53` and `+3.13`;
//!    `-3.13` is capsize and `-5.53` castering).
//! 5. Negative speeds: `roots(-v) = -roots(v)` with the same labels.
//!
//! In an [`EigenPoint`] the eigenvalues are ordered by label: weave roots first
//! (upper root of the pair, or the larger real root, first), then capsize, then
//! castering, then `Other(k)` by `k`. [`eigenvalues`] (unlabelled fast path) sorts by
//! descending real part, then descending imaginary part.

use nalgebra::{Complex, Matrix2};

use crate::canonical::CanonicalMatrices;

mod critical;
mod float;
mod general;
mod quartic;
mod states;
mod tracking;

pub use critical::critical_speeds;
pub use general::{
    critical_speeds_of, eigen_sweep_of, eigenvalue_sweep_of, eigenvalues_of, LabelledEigenvalues, LinearBicycle,
    SpeedMatrices,
};
use quartic::{quartic_roots, sort_desc, C64};
pub use states::{LateralStates, StateSpaceBicycle};
use tracking::*;

// Shared by the general model's and the state-space model's crossing
// searches (`general`, `states`), so neither child reaches into the other.
/// The grid of [`CROSSING_GRID`] cells over `[v_min, v_max]`.
fn crossing_grid(v_min: f64, v_max: f64) -> Vec<f64> {
    (0..=CROSSING_GRID)
        .map(|i| v_min + (v_max - v_min) * (i as f64 / CROSSING_GRID as f64))
        .collect()
}

/// Grid intervals over the speed range that bracket the crossings of a
/// general model (crossings closer than a cell apart may be missed; a
/// bicycle's are tenths of m/s apart or more over 0-10 m/s).
const CROSSING_GRID: usize = 400;

/// Errors of the eigen analysis. Functions never panic and never return NaN.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EigenError {
    /// `M0` is singular (or numerically so): the quartic is not of degree 4.
    #[error("singular mass matrix M0: det M0 = {det:.3e} is at most 1e-12 times |m11 m22| + |m12 m21| = {scale:.3e}")]
    SingularMassMatrix {
        /// Determinant of `M0`.
        det: f64,
        /// `|m11 m22| + |m12 m21|`, the size of the determinant's terms.
        scale: f64,
    },
    /// A matrix entry, `g`, or a speed is NaN or infinite.
    #[error("non-finite input: {what}")]
    NonFinite {
        /// What was non-finite.
        what: String,
    },
    /// An iterative step did not converge within its iteration cap.
    #[error("no convergence: {what}")]
    NoConvergence {
        /// Which step failed.
        what: String,
    },
    /// The linear equations of a model could not be formed at a speed.
    #[error("linearization at {speed} m/s: {what}")]
    Linearization {
        /// Speed (m/s).
        speed: f64,
        /// What failed.
        what: String,
    },
    /// Invalid argument (e.g. `v_min > v_max`).
    #[error("invalid argument: {what}")]
    InvalidArgument {
        /// Description.
        what: String,
    },
}

/// Mode label of an eigenvalue.
///
/// * `Weave`: the oscillatory steer/roll mode. Below the merge speed `v_d` the
///   weave "pair" is two *real* roots; both carry the label `Weave` and
///   [`EigenPoint::is_oscillatory`] tells the two regimes apart. (Benchmark at
///   `v = 0`: the four roots are `+-3.13`, `+-5.53`; the weave roots are `+5.53`
///   and `+3.13`, which merge at `v_d = 0.684` into the double root `3.78`.)
/// * `Capsize`: the slow, real roll mode (benchmark: unstable above `v_c`).
/// * `Castering`: the fast, real, strongly stable steer mode.
/// * `Other(k)`: a mode the classification rule could not name (only in the
///   fallback, for a bicycle with two complex pairs at every anchor speed: the
///   second pair is `Other(2)`).
///
/// See the module documentation for the classification rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Mode {
    /// Weave (complex pair above `v_d`, two real roots below).
    Weave,
    /// Capsize (real).
    Capsize,
    /// Castering (real).
    Castering,
    /// A weave root and the capsize root merged into a complex pair.
    WeaveCapsize,
    /// A weave root and the castering root merged into a complex pair.
    WeaveCastering,
    /// The capsize and castering roots merged into a complex pair (the thesis
    /// bicycle from 0.19 to 2.55 m/s).
    CapsizeCastering,
    /// Unclassified.
    Other(u8),
}

impl Mode {
    /// Lower-case name: "weave", "capsize", "castering", "weave-capsize",
    /// "weave-castering", "capsize-castering", "other".
    pub fn name(&self) -> &'static str {
        match self {
            Mode::Weave => "weave",
            Mode::Capsize => "capsize",
            Mode::Castering => "castering",
            Mode::WeaveCapsize => "weave-capsize",
            Mode::WeaveCastering => "weave-castering",
            Mode::CapsizeCastering => "capsize-castering",
            Mode::Other(_) => "other",
        }
    }

    /// Output order: weave, capsize, castering, the merged pairs, other.
    pub fn rank(&self) -> u16 {
        match self {
            Mode::Weave => 0,
            Mode::Capsize => 1,
            Mode::Castering => 2,
            Mode::WeaveCapsize => 3,
            Mode::WeaveCastering => 4,
            Mode::CapsizeCastering => 5,
            Mode::Other(k) => 6 + *k as u16,
        }
    }

    /// The merged mode of a pair formed by `a` and `b` (either order), if both
    /// are distinct named real modes.
    pub fn merge(a: Mode, b: Mode) -> Option<Mode> {
        let (lo, hi) = if a.rank() <= b.rank() { (a, b) } else { (b, a) };
        match (lo, hi) {
            (Mode::Weave, Mode::Capsize) => Some(Mode::WeaveCapsize),
            (Mode::Weave, Mode::Castering) => Some(Mode::WeaveCastering),
            (Mode::Capsize, Mode::Castering) => Some(Mode::CapsizeCastering),
            _ => None,
        }
    }

    /// The two modes of a merged pair, lower rank first.
    pub fn components(&self) -> Option<(Mode, Mode)> {
        match self {
            Mode::WeaveCapsize => Some((Mode::Weave, Mode::Capsize)),
            Mode::WeaveCastering => Some((Mode::Weave, Mode::Castering)),
            Mode::CapsizeCastering => Some((Mode::Capsize, Mode::Castering)),
            _ => None,
        }
    }

    /// Whether this mode is, or contains, `m` (e.g. `CapsizeCastering`
    /// involves `Capsize`).
    pub fn involves(&self, m: Mode) -> bool {
        *self == m || self.components().is_some_and(|(a, b)| a == m || b == m)
    }
}

/// Eigen-analysis at one speed.
#[derive(Clone, Debug, PartialEq)]
pub struct EigenPoint {
    /// Forward speed (m/s).
    pub v: f64,
    /// The four eigenvalues (1/s).
    pub eigenvalues: [Complex<f64>; 4],
    /// Mode label of each eigenvalue.
    pub modes: [Mode; 4],
    /// Eigenvector `k` belongs to eigenvalue `k`; state `x = [phi, delta, phi', delta']`,
    /// unit 2-norm, phase fixed so that the largest-modulus component of `[phi, delta]`
    /// is real and positive.
    pub eigenvectors: [[Complex<f64>; 4]; 4],
    /// Eigenvalues of the modes beyond the four roll-steer modes (a model
    /// with extra first-order states, e.g. lagged tyre forces: see
    /// [`StateSpaceBicycle`]), by descending real part; empty otherwise.
    pub extra_eigenvalues: Vec<Complex<f64>>,
}

impl EigenPoint {
    /// Whether eigenvalue `k` is part of a complex-conjugate pair (nonzero imaginary part).
    pub fn is_oscillatory(&self, k: usize) -> bool {
        k < 4 && self.eigenvalues[k].im != 0.0
    }

    /// Index of the first eigenvalue with mode `m`, if any.
    pub fn index_of(&self, m: Mode) -> Option<usize> {
        self.modes.iter().position(|x| *x == m)
    }

    /// Whether all real parts are strictly negative (extra modes included).
    pub fn is_stable(&self) -> bool {
        self.eigenvalues
            .iter()
            .chain(&self.extra_eigenvalues)
            .all(|s| s.re < 0.0)
    }
}

/// Eigen-analysis over a list of speeds, labels tracked continuously.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct EigenSweep {
    /// One point per requested speed, in the order given.
    pub points: Vec<EigenPoint>,
}

/// Direction of a real-part zero crossing with increasing speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum CrossingDirection {
    /// Real part goes from negative to positive (loss of stability).
    Destabilizing,
    /// Real part goes from positive to negative (gain of stability).
    Stabilizing,
}

/// Kind of a crossing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum CrossingKind {
    /// A complex pair crosses the imaginary axis (Hopf; Hurwitz determinant zero).
    ComplexPair,
    /// A real root passes through zero (`det(g K0 + v^2 K2) = 0`).
    RealRoot,
}

/// A speed where a real part crosses zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Crossing {
    /// Speed (m/s).
    pub speed: f64,
    /// Mode whose real part crosses.
    pub mode: Mode,
    /// Direction with increasing speed.
    pub direction: CrossingDirection,
    /// Complex pair or real root.
    pub kind: CrossingKind,
    /// Imaginary part at the crossing (`0` for a real root; `> 0` for a pair).
    pub frequency: f64,
}

/// Critical speeds in a speed range.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct CriticalSpeeds {
    /// `v_d`: speed where the two real weave roots merge into the weave pair.
    pub weave_real_pair_merge: Option<f64>,
    /// The double real eigenvalue (1/s) of the weave at `v_d` (3.7829 for the benchmark).
    pub weave_merge_eigenvalue: Option<f64>,
    /// `v_w`: weave Hopf speed (first stabilizing weave crossing).
    pub weave_speed: Option<f64>,
    /// `v_c`: capsize speed (first destabilizing capsize crossing).
    pub capsize_speed: Option<f64>,
    /// Every speed in the range where a real part crosses zero, ascending.
    pub crossings: Vec<Crossing>,
    /// Maximal intervals `[lo, hi]` within the range where all real parts are < 0.
    pub stable_intervals: Vec<[f64; 2]>,
}

/// Characteristic quartic `det(M0 s^2 + v C1 s + g K0 + v^2 K2)` as polynomials in
/// the speed: with `u = v^2`,
/// `k4 = det M0`, `k3 = v a3`, `k2 = g b0 + u b2`, `k1 = v (g d0 + u d2)`,
/// `k0 = g^2 e0 + g u e1 + u^2 e2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CharPoly {
    /// `g` (m/s^2).
    pub g: f64,
    /// `det M0`.
    pub k4: f64,
    /// `k3 / v`.
    pub a3: f64,
    /// `k2 = g b0 + v^2 b2`.
    pub b0: f64,
    /// See `b0`.
    pub b2: f64,
    /// `k1 = v (g d0 + v^2 d2)`.
    pub d0: f64,
    /// See `d0`.
    pub d2: f64,
    /// `k0 = g^2 e0 + g v^2 e1 + v^4 e2` (`e0 = det K0`, `e2 = det K2`).
    pub e0: f64,
    /// See `e0`.
    pub e1: f64,
    /// See `e0`.
    pub e2: f64,
}

/// `x11 y22 + y11 x22 - x12 y21 - y12 x21` (the mixed determinant; `det X` when `X = Y`
/// counts twice).
fn mixed(x: &Matrix2<f64>, y: &Matrix2<f64>) -> f64 {
    x[(0, 0)] * y[(1, 1)] + y[(0, 0)] * x[(1, 1)] - x[(0, 1)] * y[(1, 0)] - y[(0, 1)] * x[(1, 0)]
}

/// Accurate 2x2 determinant (Kahan's FMA algorithm).
fn det2(m: &Matrix2<f64>) -> f64 {
    let w = m[(0, 1)] * m[(1, 0)];
    let err = float::mul_add(-m[(0, 1)], m[(1, 0)], w);
    float::mul_add(m[(0, 0)], m[(1, 1)], -w) + err
}

impl CharPoly {
    /// Coefficient polynomials of `c`. Errors on non-finite entries or singular `M0`
    /// (`|det M0| <= 1e-12 (|m11 m22| + |m12 m21|)`).
    pub fn new(c: &CanonicalMatrices) -> Result<Self, EigenError> {
        for (name, m) in [("M0", &c.m0), ("C1", &c.c1), ("K0", &c.k0), ("K2", &c.k2)] {
            if !m.iter().all(|x| x.is_finite()) {
                return Err(EigenError::NonFinite {
                    what: format!("matrix {name}"),
                });
            }
        }
        if !c.g.is_finite() {
            return Err(EigenError::NonFinite { what: "g".into() });
        }
        let k4 = det2(&c.m0);
        let scale = (c.m0[(0, 0)] * c.m0[(1, 1)]).abs() + (c.m0[(0, 1)] * c.m0[(1, 0)]).abs();
        if !(k4.is_finite() && scale.is_finite()) {
            return Err(EigenError::NonFinite {
                what: format!(
                    "det M0 overflows double precision (M0 entries up to {:.3e})",
                    c.m0.amax()
                ),
            });
        }
        if !(k4.abs() > 1e-12 * scale) {
            return Err(EigenError::SingularMassMatrix { det: k4, scale });
        }
        let (m, c1, k0, k2) = (&c.m0, &c.c1, &c.k0, &c.k2);
        let cp = CharPoly {
            g: c.g,
            k4,
            a3: mixed(m, c1),
            b0: mixed(m, k0),
            b2: mixed(m, k2) + det2(c1),
            d0: mixed(c1, k0),
            d2: mixed(c1, k2),
            e0: det2(k0),
            e1: mixed(k0, k2),
            e2: det2(k2),
        };
        Ok(cp)
    }

    /// Coefficients `[k0, k1, k2, k3, k4]` (`k[i]` multiplies `s^i`) at speed `v`.
    pub fn coeffs(&self, v: f64) -> [f64; 5] {
        let g = self.g;
        let u = v * v;
        [
            g * (g * self.e0) + u * (g * self.e1 + u * self.e2),
            v * (g * self.d0 + u * self.d2),
            g * self.b0 + u * self.b2,
            v * self.a3,
            self.k4,
        ]
    }

    /// Derivatives `d k_i / d v` at speed `v`.
    pub fn dcoeffs(&self, v: f64) -> [f64; 5] {
        let g = self.g;
        let u = v * v;
        [
            2.0 * v * (g * self.e1 + 2.0 * u * self.e2),
            g * self.d0 + 3.0 * u * self.d2,
            2.0 * v * self.b2,
            self.a3,
            0.0,
        ]
    }

    /// Roots at speed `v`, sorted by descending real part then imaginary part.
    pub fn roots(&self, v: f64) -> Result<[Complex<f64>; 4], EigenError> {
        if !v.is_finite() {
            return Err(EigenError::NonFinite {
                what: format!("speed {v}"),
            });
        }
        let va = v.abs();
        let mut z = quartic_roots(&self.coeffs(va)).ok_or_else(|| EigenError::NoConvergence {
            what: format!(
                "quartic roots at v = {} m/s",
                crate::number_text::format_significant(v, 10)
            ),
        })?;
        if v < 0.0 {
            for x in z.iter_mut() {
                *x = neg(*x);
            }
            sort_desc(&mut z);
        }
        Ok(z)
    }
}

/// A family of characteristic quartics over speed: what the mode tracking
/// and the critical-speed search need. [`CharPoly`] (the canonical form,
/// coefficients polynomial in the speed) and the general roll-steer
/// equations of any model (`general.rs`) implement it.
pub(crate) trait Spectrum {
    /// Coefficients `[k0, k1, k2, k3, k4]` at speed `v`.
    fn coefficients(&self, v: f64) -> Result<[f64; 5], EigenError>;
    /// Their derivatives in the speed.
    fn coefficient_rates(&self, v: f64) -> Result<[f64; 5], EigenError>;
    /// Roots at speed `v`, sorted by descending real then imaginary part.
    fn roots_at(&self, v: f64) -> Result<[C64; 4], EigenError>;
    /// A speed scale of the bicycle (m/s), where gravity and speed terms
    /// balance; it places the anchor of the mode labels.
    fn scale(&self) -> f64;
    /// Whether `roots(-v) = -roots(v)` (true for the canonical form, whose
    /// equations are even in `v` up to the sign of time).
    fn mirror_symmetric(&self) -> bool;
    /// The discriminant at speed `v` (zero where roots collide) and the
    /// number of real roots, if the family has them (the quartic's): where
    /// roots merge can then be bracketed without solving and labelling at
    /// every speed of a grid. `None`: not available (a spectrum chosen from
    /// a larger one).
    fn discriminant(&self, _v: f64) -> Option<(f64, Option<u8>)> {
        None
    }
}

impl Spectrum for CharPoly {
    fn coefficients(&self, v: f64) -> Result<[f64; 5], EigenError> {
        Ok(self.coeffs(v))
    }
    fn coefficient_rates(&self, v: f64) -> Result<[f64; 5], EigenError> {
        Ok(self.dcoeffs(v))
    }
    fn roots_at(&self, v: f64) -> Result<[C64; 4], EigenError> {
        self.roots(v)
    }
    fn scale(&self) -> f64 {
        speed_scale(self)
    }
    fn mirror_symmetric(&self) -> bool {
        true
    }
    fn discriminant(&self, v: f64) -> Option<(f64, Option<u8>)> {
        quartic::discriminant(&self.coeffs(v))
    }
}

/// `-z` without producing `-0.0` imaginary parts for real roots.
fn neg(z: C64) -> C64 {
    C64::new(-z.re, if z.im == 0.0 { 0.0 } else { -z.im })
}

/// The four eigenvalues at speed `v` (fast path, no vectors, no labels). Sorted by
/// descending real part, ties by descending imaginary part.
pub fn eigenvalues(c: &CanonicalMatrices, v: f64) -> Result<[Complex<f64>; 4], EigenError> {
    CharPoly::new(c)?.roots(v)
}

// ---------------------------------------------------------------------------
// Eigenvectors

/// Eigenvector of eigenvalue `s` at speed `v`: `u` spans the null space of
/// `P(s) = M0 s^2 + v C1 s + g K0 + v^2 K2`; `x = [u, s u]`, unit 2-norm, phase fixed so
/// that the larger-modulus component of `u` is real and positive.
pub fn eigenvector(c: &CanonicalMatrices, v: f64, s: Complex<f64>) -> [Complex<f64>; 4] {
    eigenvector_of(
        &SpeedMatrices {
            mass: c.m0,
            damping: c.damping(v),
            stiffness: c.stiffness(v),
        },
        s,
    )
}

/// [`eigenvector`] of the equations `M q'' + C q' + K q = 0` at one speed.
pub fn eigenvector_of(m: &SpeedMatrices, s: Complex<f64>) -> [Complex<f64>; 4] {
    let s2 = s * s;
    let p = |i: usize, j: usize| s2 * m.mass[(i, j)] + s * m.damping[(i, j)] + C64::new(m.stiffness[(i, j)], 0.0);
    let (p11, p12, p21, p22) = (p(0, 0), p(0, 1), p(1, 0), p(1, 1));
    let n1 = p11.norm_sqr() + p12.norm_sqr();
    let n2 = p21.norm_sqr() + p22.norm_sqr();
    let mut u = if n1 >= n2 && n1 > 0.0 {
        [-p12, p11]
    } else if n2 > 0.0 {
        [p22, -p21]
    } else {
        [C64::new(1.0, 0.0), C64::new(0.0, 0.0)]
    };
    // phase: larger component real positive
    let k = if u[0].norm() >= u[1].norm() { 0 } else { 1 };
    let uk = u[k];
    let nk = uk.norm();
    if nk > 0.0 && nk.is_finite() {
        let ph = uk.conj() / nk;
        u = [u[0] * ph, u[1] * ph];
        u[k] = C64::new(u[k].re, 0.0);
    }
    let x = [u[0], u[1], s * u[0], s * u[1]];
    let nrm = x.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt();
    if !(nrm > 0.0 && nrm.is_finite()) {
        return [C64::new(1.0, 0.0), C64::new(0.0, 0.0), s, C64::new(0.0, 0.0)];
    }
    [x[0] / nrm, x[1] / nrm, x[2] / nrm, x[3] / nrm]
}

/// Eigen-analysis at each speed in `speeds` (any order, negative speeds allowed), with
/// labels tracked continuously (see the module docs for the rule).
pub fn eigen_sweep(c: &CanonicalMatrices, speeds: &[f64]) -> Result<EigenSweep, EigenError> {
    let cp = CharPoly::new(c)?;
    let tracked = track(&cp, speeds)?;
    let points = speeds
        .iter()
        .zip(tracked)
        .map(|(&v, l)| {
            let mut vecs = [[C64::new(0.0, 0.0); 4]; 4];
            for k in 0..4 {
                // conjugate pairs get exactly conjugate vectors
                let s = l.roots[k];
                vecs[k] = if s.im < 0.0 {
                    let v_up = eigenvector(c, v, s.conj());
                    [v_up[0].conj(), v_up[1].conj(), v_up[2].conj(), v_up[3].conj()]
                } else {
                    eigenvector(c, v, s)
                };
            }
            EigenPoint {
                v,
                eigenvalues: l.roots,
                modes: l.labels,
                eigenvectors: vecs,
                extra_eigenvalues: Vec::new(),
            }
        })
        .collect();
    Ok(EigenSweep { points })
}
