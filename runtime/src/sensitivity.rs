//! Exact sensitivities of the eigenvalues and of the weave and capsize
//! speeds to the bicycle's parameters (issue 36, item 2).
//!
//! # Method
//! The roll-steer equations `M0 q'' + v C1 q' + (g K0 + v^2 K2) q = 0` have
//! the eigenvalues `s` where `P(s) = s^2 M0 + s v C1 + g K0 + v^2 K2` is
//! singular. For a simple eigenvalue with right null vector `u` (`P u = 0`)
//! and left null vector `y` (`y^T P = 0`), differentiating `P(s(p), p) u = 0`
//! and multiplying by `y^T` gives
//!
//! ```text
//! ds/dp = - y^T (dP/dp) u / y^T (dP/ds) u,     dP/ds = 2 s M0 + v C1,
//! ```
//!
//! the left/right eigenvector formula `dλ = w^H (dA) v / w^H v` written for
//! the quadratic form (the state matrix `A = [[0, I], [-M0^-1 K, -M0^-1 C]]`
//! has right eigenvector `[u; s u]` and left eigenvector `[y^T (s M0 + v C1),
//! y^T M0]`; their product is `y^T (2 s M0 + v C1) u`). `dP/dp = s^2 dM0 + s v
//! dC1 + dg K0 + g dK0 + v^2 dK2`, and `dP/dv = s C1 + 2 v K2`.
//!
//! A critical speed `v*(p)` is where an eigenvalue's real part is zero: the
//! weave pair at `v_w`, the capsize root (a real root through zero) at
//! `v_c`. The implicit function theorem on `Re s(v*, p) = 0` gives
//! `dv*/dp = -Re(ds/dp) / Re(ds/dv)`.
//!
//! # The parameter derivatives
//! `dM0/dp, dC1/dp, dK0/dp, dK2/dp` are exact: the closed-form canonical
//! matrices of Meijaard et al. (2007), appendix A
//! ([`crate::closed_form::meijaard_canonical_in`]), evaluated in dual
//! numbers seeded on the 26 benchmark parameters, or on the 26 thesis
//! parameters through the conversion to the benchmark form
//! ([`crate::parameters::thesis_to_benchmark_in`]). The generated code carries
//! first derivatives only (its duals are seeded on the coordinates to
//! linearize), so it cannot give these mixed second derivatives; the closed
//! form holds for the Whipple bicycle, which is what the canonical form
//! describes. The caller checks that the closed form's matrices agree with
//! the generated model's ([`CanonicalJacobian::departure`]) before using its
//! derivatives.

use crate::canonical::CanonicalMatrices;
use crate::closed_form::meijaard_canonical_in;
use crate::eigen::{eigenvalues, CriticalSpeeds, EigenError, Mode};
use crate::parameters::{thesis_to_benchmark_in, BenchmarkParameters, ParameterError, ThesisParameters};
use crate::scalar::{Dual, Scalar};
use nalgebra::{Complex, Matrix2};
use serde::Serialize;

/// Number of benchmark parameters (Meijaard et al. 2007, Table 1).
pub const NP: usize = 26;

type C64 = Complex<f64>;

/// The derivatives of the canonical matrices with respect to one parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanonicalDerivative {
    pub m0: Matrix2<f64>,
    pub c1: Matrix2<f64>,
    pub k0: Matrix2<f64>,
    pub k2: Matrix2<f64>,
    /// `dg/dp` (1 for `g` itself).
    pub g: f64,
}

/// The canonical matrices of the closed form and their derivatives with
/// respect to each parameter of one form: the benchmark parameters (order
/// of [`BenchmarkParameters::SYMBOLS`]) or the thesis parameters (order of
/// [`ThesisParameters::SYMBOLS`], through the conversion to the benchmark
/// form, itself in dual numbers).
#[derive(Clone, Debug, PartialEq)]
pub struct CanonicalJacobian {
    /// The closed form's own values.
    pub value: CanonicalMatrices,
    /// The parameters' symbols.
    pub symbols: &'static [&'static str; NP],
    /// The parameter values.
    pub parameters: [f64; NP],
    /// `d/dp_k` of every matrix.
    pub d: Vec<CanonicalDerivative>,
}

impl CanonicalJacobian {
    /// Exact derivatives of the canonical matrices of `p` with respect to
    /// the benchmark parameters (dual numbers through the closed form).
    pub fn of(p: &BenchmarkParameters) -> Self {
        let values: [f64; NP] = BenchmarkParameters::SYMBOLS.map(|k| p.get(k).expect("a benchmark symbol"));
        let mut x = [Dual::<NP>::cst(0.0); NP];
        for k in 0..NP {
            x[k] = Dual::variable(values[k], k);
        }
        Self::from_duals(&x, &BenchmarkParameters::SYMBOLS, values)
    }

    /// Exact derivatives of the canonical matrices of `t` with respect to
    /// the thesis parameters (dual numbers through the conversion to the
    /// benchmark form and the closed form).
    pub fn of_thesis(t: &ThesisParameters) -> Result<Self, ParameterError> {
        let beta = t.frame_pitch()?;
        let values = t.values();
        let mut x = [Dual::<NP>::cst(0.0); NP];
        for k in 0..NP {
            x[k] = Dual::variable(values[k], k);
        }
        let b = thesis_to_benchmark_in(&x, beta);
        Ok(Self::from_duals(&b, &ThesisParameters::SYMBOLS, values))
    }

    fn from_duals(b: &[Dual<NP>; NP], symbols: &'static [&'static str; NP], values: [f64; NP]) -> Self {
        let m = meijaard_canonical_in(b);
        let re = |a: &[[Dual<NP>; 2]; 2]| Matrix2::from_fn(|i, j| a[i][j].re);
        let de = |a: &[[Dual<NP>; 2]; 2], k: usize| Matrix2::from_fn(|i, j| a[i][j].eps[k]);
        CanonicalJacobian {
            value: CanonicalMatrices {
                m0: re(&m.m0),
                c1: re(&m.c1),
                k0: re(&m.k0),
                k2: re(&m.k2),
                g: m.g.re,
            },
            symbols,
            parameters: values,
            d: (0..NP)
                .map(|k| CanonicalDerivative {
                    m0: de(&m.m0, k),
                    c1: de(&m.c1, k),
                    k0: de(&m.k0, k),
                    k2: de(&m.k2, k),
                    g: m.g.eps[k],
                })
                .collect(),
        }
    }

    /// Largest difference between the closed form's matrices and `c`,
    /// relative to the largest entry of each matrix (0 when they agree).
    pub fn departure(&self, c: &CanonicalMatrices) -> f64 {
        let v = &self.value;
        let rel = |a: &Matrix2<f64>, b: &Matrix2<f64>| (a - b).amax() / a.amax().max(b.amax()).max(f64::MIN_POSITIVE);
        rel(&v.m0, &c.m0)
            .max(rel(&v.c1, &c.c1))
            .max(rel(&v.k0, &c.k0))
            .max(rel(&v.k2, &c.k2))
            .max((v.g - c.g).abs() / v.g.abs().max(f64::MIN_POSITIVE))
    }
}

/// Errors of the sensitivity analysis.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SensitivityError {
    /// The eigenvalue is (numerically) double: its derivative does not
    /// exist (e.g. at the speed where the two real weave roots merge).
    #[error("the {mode} eigenvalue {re} {sign} {im}i at {speed} m/s is double (|y^T P'(s) u| = {denominator:.3e} relative to its terms): its derivative does not exist there (the roots merge); choose another speed")]
    DoubleEigenvalue {
        mode: &'static str,
        speed: f64,
        re: f64,
        sign: char,
        im: f64,
        denominator: f64,
    },
    /// The real part is tangent to zero at the crossing: the critical speed
    /// is not a differentiable function of the parameters there.
    #[error("the {what} crossing at {speed} m/s is tangent (d Re s / dv = {slope:e}): the critical speed does not move smoothly with the parameters")]
    TangentCrossing { what: &'static str, speed: f64, slope: f64 },
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

/// One parameter's derivative of a critical speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SpeedDerivative {
    /// Parameter symbol (benchmark or thesis form).
    pub parameter: &'static str,
    /// Its value (SI).
    pub value: f64,
    /// `dv*/dp` (m/s per unit of the parameter).
    pub derivative: f64,
    /// `(p / v*) dv*/dp`: per cent of speed per per cent of the parameter.
    pub elasticity: f64,
}

/// The sensitivity of one critical speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CriticalSensitivity {
    /// The critical speed (m/s).
    pub speed: f64,
    /// The eigenvalue crossing there, `[re, im]` (1/s; `re` is 0 up to rounding).
    pub eigenvalue: [f64; 2],
    /// `d Re s / dv` at the crossing (1/s per m/s).
    pub real_part_slope: f64,
    /// Per parameter, ranked by the size of the elasticity (largest first).
    pub derivatives: Vec<SpeedDerivative>,
}

/// One parameter's derivative of an eigenvalue.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EigenvalueDerivative {
    /// Parameter symbol (benchmark or thesis form).
    pub parameter: &'static str,
    /// Its value (SI).
    pub value: f64,
    /// `ds/dp`, `[re, im]` (1/s per unit of the parameter).
    pub derivative: [f64; 2],
    /// `p ds/dp`, `[re, im]` (1/s): the change for a 100 % change of the
    /// parameter, to first order; comparable across parameters.
    pub scaled: [f64; 2],
}

/// The derivatives of one eigenvalue at a speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModeSensitivity {
    /// Mode name (weave, capsize, castering, a merged pair).
    pub mode: &'static str,
    /// The eigenvalue `[re, im]` (1/s).
    pub eigenvalue: [f64; 2],
    /// `ds/dv`, `[re, im]` (1/s per m/s).
    pub speed_derivative: [f64; 2],
    /// Per parameter, ranked by `|p ds/dp|` (largest first).
    pub derivatives: Vec<EigenvalueDerivative>,
}

/// `P(s)` of the canonical matrices at speed `v`.
fn quadratic(c: &CanonicalMatrices, v: f64, s: C64) -> [[C64; 2]; 2] {
    let k = c.stiffness(v);
    let d = c.damping(v);
    let mut p = [[C64::new(0.0, 0.0); 2]; 2];
    for i in 0..2 {
        for j in 0..2 {
            p[i][j] = s * s * c.m0[(i, j)] + s * d[(i, j)] + k[(i, j)];
        }
    }
    p
}

/// `y^T B u` for a complex 2x2 `B`.
fn bilinear(y: &[C64; 2], b: &[[C64; 2]; 2], u: &[C64; 2]) -> C64 {
    let mut acc = C64::new(0.0, 0.0);
    for i in 0..2 {
        for j in 0..2 {
            acc += y[i] * b[i][j] * u[j];
        }
    }
    acc
}

fn real_matrix(m: &Matrix2<f64>, f: C64) -> [[C64; 2]; 2] {
    [[f * m[(0, 0)], f * m[(0, 1)]], [f * m[(1, 0)], f * m[(1, 1)]]]
}

fn add(a: [[C64; 2]; 2], b: [[C64; 2]; 2]) -> [[C64; 2]; 2] {
    [
        [a[0][0] + b[0][0], a[0][1] + b[0][1]],
        [a[1][0] + b[1][0], a[1][1] + b[1][1]],
    ]
}

/// The derivatives of the simple eigenvalue `s` at speed `v`: `(ds/dv,
/// ds/dp_k for each parameter)`. `c` gives the matrices (the generated
/// model's), `jac` their parameter derivatives.
pub fn eigenvalue_derivatives(
    c: &CanonicalMatrices,
    jac: &CanonicalJacobian,
    v: f64,
    s: C64,
    mode: Mode,
) -> Result<(C64, Vec<C64>), SensitivityError> {
    let p = quadratic(c, v, s);
    // Right null vector from the row of larger norm, left from the column.
    let row = |i: usize| p[i][0].norm_sqr() + p[i][1].norm_sqr();
    let col = |j: usize| p[0][j].norm_sqr() + p[1][j].norm_sqr();
    let u = if row(0) >= row(1) {
        [-p[0][1], p[0][0]]
    } else {
        [p[1][1], -p[1][0]]
    };
    let y = if col(0) >= col(1) {
        [-p[1][0], p[0][0]]
    } else {
        [p[1][1], -p[0][1]]
    };
    let norm = |z: &[C64; 2]| (z[0].norm_sqr() + z[1].norm_sqr()).sqrt();
    let ds = add(real_matrix(&c.m0, 2.0 * s), real_matrix(&c.c1, C64::new(v, 0.0)));
    let den = bilinear(&y, &ds, &u);
    let scale = norm(&y) * norm(&u) * (2.0 * s.norm() * c.m0.amax() + v.abs() * c.c1.amax());
    let (nu, ny) = (norm(&u), norm(&y));
    if !(nu > 0.0 && ny > 0.0 && den.norm() > 1e-7 * scale) {
        return Err(SensitivityError::DoubleEigenvalue {
            mode: mode.name(),
            speed: v,
            re: s.re,
            sign: if s.im < 0.0 { '-' } else { '+' },
            im: s.im.abs(),
            denominator: den.norm() / scale.max(f64::MIN_POSITIVE),
        });
    }
    let dv = add(real_matrix(&c.c1, s), real_matrix(&c.k2, C64::new(2.0 * v, 0.0)));
    let ds_dv = -bilinear(&y, &dv, &u) / den;
    let s2 = s * s;
    let ds_dp = jac
        .d
        .iter()
        .map(|d| {
            let dp = add(
                add(real_matrix(&d.m0, s2), real_matrix(&d.c1, s * v)),
                add(
                    real_matrix(&(d.k0 * c.g + c.k0 * d.g), C64::new(1.0, 0.0)),
                    real_matrix(&d.k2, C64::new(v * v, 0.0)),
                ),
            );
            -bilinear(&y, &dp, &u) / den
        })
        .collect();
    Ok((ds_dv, ds_dp))
}

/// The sensitivity of a critical speed `speed` where the eigenvalue nearest
/// `i frequency` (upper half plane) crosses the imaginary axis.
fn critical(
    c: &CanonicalMatrices,
    jac: &CanonicalJacobian,
    speed: f64,
    frequency: f64,
    mode: Mode,
    what: &'static str,
) -> Result<CriticalSensitivity, SensitivityError> {
    let roots = eigenvalues(c, speed)?;
    let target = C64::new(0.0, frequency);
    let s = roots
        .iter()
        .copied()
        .filter(|z| z.im >= 0.0)
        .min_by(|a, b| (a - target).norm().total_cmp(&(b - target).norm()))
        .expect("a root in the closed upper half plane");
    // A real root exactly: its imaginary part is rounding.
    let s = if frequency == 0.0 { C64::new(s.re, 0.0) } else { s };
    let (ds_dv, ds_dp) = eigenvalue_derivatives(c, jac, speed, s, mode)?;
    let slope = ds_dv.re;
    if !(slope.abs() > 1e-9 * ds_dv.norm().max(1e-300)) || !slope.is_finite() {
        return Err(SensitivityError::TangentCrossing { what, speed, slope });
    }
    let mut derivatives: Vec<SpeedDerivative> = ds_dp
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let derivative = -d.re / slope;
            let value = jac.parameters[k];
            SpeedDerivative {
                parameter: jac.symbols[k],
                value,
                derivative,
                elasticity: value / speed * derivative,
            }
        })
        .collect();
    derivatives.sort_by(|a, b| b.elasticity.abs().total_cmp(&a.elasticity.abs()));
    Ok(CriticalSensitivity {
        speed,
        eigenvalue: [s.re, s.im],
        real_part_slope: slope,
        derivatives,
    })
}

/// The sensitivities of the weave and capsize speeds of `crit` (found on
/// the matrices `c`); `None` where that speed is not in `crit`.
pub fn critical_speed_sensitivities(
    c: &CanonicalMatrices,
    jac: &CanonicalJacobian,
    crit: &CriticalSpeeds,
) -> Result<(Option<CriticalSensitivity>, Option<CriticalSensitivity>), SensitivityError> {
    let crossing_at = |v: f64| crit.crossings.iter().find(|x| x.speed == v);
    let weave = match crit.weave_speed {
        Some(v) => {
            let f = crossing_at(v).map_or(0.0, |x| x.frequency);
            Some(critical(c, jac, v, f, Mode::Weave, "weave")?)
        }
        None => None,
    };
    let capsize = match crit.capsize_speed {
        Some(v) => Some(critical(c, jac, v, 0.0, Mode::Capsize, "capsize")?),
        None => None,
    };
    Ok((weave, capsize))
}

/// The derivatives of every eigenvalue at speed `v`, in mode order (weave,
/// capsize, castering, ...; one entry per conjugate pair, its upper root).
pub fn eigenvalue_sensitivities(
    c: &CanonicalMatrices,
    jac: &CanonicalJacobian,
    v: f64,
) -> Result<Vec<ModeSensitivity>, SensitivityError> {
    let sweep = crate::eigen::eigen_sweep(c, &[v])?;
    let point = &sweep.points[0];
    let mut out = Vec::new();
    let mut order = [0, 1, 2, 3];
    order.sort_by_key(|&k| point.modes[k].rank());
    for k in order {
        let s = point.eigenvalues[k];
        if s.im < 0.0 {
            continue;
        }
        let mode = point.modes[k];
        let (ds_dv, ds_dp) = eigenvalue_derivatives(c, jac, v, s, mode)?;
        let mut derivatives: Vec<EigenvalueDerivative> = ds_dp
            .iter()
            .enumerate()
            .map(|(i, d)| {
                let value = jac.parameters[i];
                EigenvalueDerivative {
                    parameter: jac.symbols[i],
                    value,
                    derivative: [d.re, d.im],
                    scaled: [value * d.re, value * d.im],
                }
            })
            .collect();
        derivatives.sort_by(|a, b| {
            let n = |x: &EigenvalueDerivative| x.scaled[0].hypot(x.scaled[1]);
            n(b).total_cmp(&n(a))
        });
        out.push(ModeSensitivity {
            mode: mode.name(),
            eigenvalue: [s.re, s.im],
            speed_derivative: [ds_dv.re, ds_dv.im],
            derivatives,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_form::meijaard_canonical;

    fn benchmark() -> (CanonicalMatrices, CanonicalJacobian) {
        let p = BenchmarkParameters::benchmark_bicycle();
        (meijaard_canonical(&p), CanonicalJacobian::of(&p))
    }

    /// The dual closed form has the f64 closed form's values (to rounding), and each
    /// derivative matches a central difference of the f64 closed form.
    #[test]
    fn closed_form_derivatives_match_central_differences() {
        let p = BenchmarkParameters::benchmark_bicycle();
        let (c, jac) = benchmark();
        assert!(jac.departure(&c) < 1e-14, "{}", jac.departure(&c));
        for (k, sym) in BenchmarkParameters::SYMBOLS.iter().enumerate() {
            let x = p.get(sym).unwrap();
            let h = 1e-6 * x.abs().max(1e-3);
            let at = |x: f64| {
                let mut v = serde_json::to_value(p).unwrap();
                v[*sym] = x.into();
                meijaard_canonical(&serde_json::from_value(v).unwrap())
            };
            assert_central_difference(sym, &jac.d[k], &at(x + h), &at(x - h), h);
        }
    }

    /// Each matrix's derivative `d` against the central difference of the
    /// closed form at `p + h` (`a`) and `p - h` (`b`).
    fn assert_central_difference(
        sym: &str,
        d: &CanonicalDerivative,
        a: &CanonicalMatrices,
        b: &CanonicalMatrices,
        h: f64,
    ) {
        for (fd, d) in [
            ((a.m0 - b.m0) / (2.0 * h), d.m0),
            ((a.c1 - b.c1) / (2.0 * h), d.c1),
            ((a.k0 - b.k0) / (2.0 * h), d.k0),
            ((a.k2 - b.k2) / (2.0 * h), d.k2),
        ] {
            assert!((fd - d).amax() <= 1e-6 * (1.0 + d.amax()), "{sym}: {fd} vs {d}");
        }
    }

    /// The thesis-form derivatives are the benchmark ones through the
    /// conversion: against central differences of the f64 conversion and
    /// closed form.
    #[test]
    fn thesis_form_derivatives_match_central_differences() {
        let t = ThesisParameters::thesis_bicycle();
        let jac = CanonicalJacobian::of_thesis(&t).unwrap();
        assert!(jac.departure(&meijaard_canonical(&t.to_benchmark().unwrap())) < 1e-13);
        for (k, sym) in ThesisParameters::SYMBOLS.iter().enumerate() {
            let x = t.get(sym).unwrap();
            let h = 1e-6 * x.abs().max(1e-2);
            let at = |x: f64| {
                let mut v = serde_json::to_value(t).unwrap();
                v[*sym] = x.into();
                let t: ThesisParameters = serde_json::from_value(v).unwrap();
                meijaard_canonical(&t.to_benchmark().unwrap())
            };
            assert_central_difference(sym, &jac.d[k], &at(x + h), &at(x - h), h);
        }
    }

    /// `ds/dv` from the eigenvector formula against the roots' central
    /// difference in speed.
    #[test]
    fn eigenvalue_speed_derivative_matches_the_roots() {
        let (c, jac) = benchmark();
        let v = 5.0;
        let h = 1e-5;
        let modes = eigenvalue_sensitivities(&c, &jac, v).unwrap();
        let near = |roots: [C64; 4], s: C64| {
            roots
                .into_iter()
                .min_by(|a, b| (a - s).norm().total_cmp(&(b - s).norm()))
                .unwrap()
        };
        for m in &modes {
            let s = C64::new(m.eigenvalue[0], m.eigenvalue[1]);
            let fd = (near(eigenvalues(&c, v + h).unwrap(), s) - near(eigenvalues(&c, v - h).unwrap(), s)) / (2.0 * h);
            let d = C64::new(m.speed_derivative[0], m.speed_derivative[1]);
            assert!((fd - d).norm() < 1e-6 * (1.0 + d.norm()), "{}: {fd} vs {d}", m.mode);
        }
    }
}
