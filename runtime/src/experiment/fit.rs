//! Least-squares fits of a free response (Levenberg-Marquardt, crate
//! `levenberg-marquardt`, by variable projection: the linear parameters are
//! solved exactly for each trial eigenvalue), standard errors from the full
//! Jacobian at the optimum, r^2, AIC/BIC.
//!
//! Forms (`tau = t - t0`, `t0` the window start):
//! * [`FitForm::RollAngle`], thesis eq. 94: `A e^(a tau) cos(b tau + phi) + c`;
//!   eigenvalue `a + i b`.
//! * [`FitForm::RollRate`], Kooijman et al. (2008):
//!   `c1 + e^(sigma tau) (c2 cos(omega tau) + c3 sin(omega tau))`.
//! * [`FitForm::SpeedVarying`] on either signal: the eigenvalue varies
//!   linearly with speed, `s(v) = s0 + s1 (v - v_mean)`, so the phase and the
//!   log-envelope are `omega0 tau + omega1 I(tau)` and `sigma0 tau +
//!   sigma1 I(tau)` with `I(tau) = int_0^tau (v - v_mean)`. Reported
//!   eigenvalue: `sigma0 + i omega0` at the window's mean speed.
//!
//! Residuals of a measured response are correlated in time (unmodelled
//! dynamics, filtering), so the Jacobian standard errors are inflated by
//! `sqrt(n / n_eff)` with `n_eff = n (1 - rho) / (1 + rho)` from the lag-one
//! autocorrelation `rho` of the residuals.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

/// Which function was fitted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitForm {
    /// Thesis eq. 94 on roll angle.
    RollAngle,
    /// Kooijman form on roll rate.
    RollRate,
    /// Eigenvalue linear in speed, on roll angle.
    SpeedVaryingRollAngle,
    /// Eigenvalue linear in speed, on roll rate.
    SpeedVaryingRollRate,
}

impl FitForm {
    /// Name used in JSON and tables.
    pub fn name(self) -> &'static str {
        match self {
            FitForm::RollAngle => "eq94_roll_angle",
            FitForm::RollRate => "kooijman_roll_rate",
            FitForm::SpeedVaryingRollAngle => "speed_varying_roll_angle",
            FitForm::SpeedVaryingRollRate => "speed_varying_roll_rate",
        }
    }
    /// Whether the eigenvalue of this form varies with the speed.
    pub fn speed_varying(self) -> bool {
        matches!(self, FitForm::SpeedVaryingRollAngle | FitForm::SpeedVaryingRollRate)
    }
}

/// Result of one fit.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FitResult {
    /// Form.
    pub form: FitForm,
    /// Eigenvalue `[real, imag]` (1/s, rad/s), imag > 0.
    pub eigenvalue: [f64; 2],
    /// Its standard errors.
    pub eigenvalue_stderr: [f64; 2],
    /// d(eigenvalue)/d(speed) `[real, imag]` (1/m) for speed-varying forms.
    pub slope: Option<[f64; 2]>,
    /// Standard errors of the slope.
    pub slope_stderr: Option<[f64; 2]>,
    /// Coefficient of determination.
    pub r2: f64,
    /// Residual root mean square (signal units).
    pub rms: f64,
    /// Akaike information criterion (Gaussian likelihood).
    pub aic: f64,
    /// Bayesian information criterion.
    pub bic: f64,
    /// Number of samples.
    pub n: usize,
    /// All parameters (form order; see the module docs).
    pub params: Vec<f64>,
    /// Window start `t0` (s) the fit's `tau` is measured from.
    pub t0: f64,
    /// Lag-one autocorrelation of the residuals.
    pub residual_autocorrelation: f64,
    /// The speed over the window as the speed-varying forms saw it: its
    /// straight line `v(tau) = v0 + slope tau` and the window mean `vm`,
    /// `[v0, slope, vm]` (m/s, m/s^2, m/s). The eigenvalue varies with
    /// `I(tau) = int_0^tau (v - vm)`, so [`FitResult::evaluate`] needs it to
    /// draw the fitted curve (`None` for the constant forms).
    #[serde(skip)]
    pub speed_line: Option<[f64; 3]>,
}

/// `I(tau) = int_0^tau (v0 + slope s - vm) ds` of a speed line `[v0, slope, vm]`.
fn line_integral(line: [f64; 3], tau: f64) -> f64 {
    let [v0, slope, vm] = line;
    (v0 - vm) * tau + 0.5 * slope * tau * tau
}

impl FitResult {
    /// Fitted curve at times `t` (same clock as the data), the speed-varying
    /// forms with the speed line they were fitted with.
    pub fn evaluate(&self, t: &[f64]) -> Vec<f64> {
        let tau: Vec<f64> = t.iter().map(|x| x - self.t0).collect();
        let integral = self
            .speed_line
            .filter(|_| self.form.speed_varying())
            .map(|line| tau.iter().map(|&x| line_integral(line, x)).collect());
        let p = Problem {
            tau,
            y: vec![0.0; t.len()],
            integral,
            eq94: matches!(self.form, FitForm::RollAngle),
            p: DVector::from_vec(self.params.clone()),
        };
        p.model()
    }
}

/// Why a fit failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error, serde::Serialize)]
pub enum FitError {
    /// Too few samples for the parameters.
    #[error("{n} samples are too few for {k} parameters")]
    TooFewSamples {
        /// Samples.
        n: usize,
        /// Parameters.
        k: usize,
    },
    /// The data show no oscillation.
    #[error("no oscillation in the window")]
    NoOscillation,
    /// LM did not converge or gave a degenerate solution.
    #[error("the fit did not converge ({reason})")]
    NotConverged {
        /// Termination reason.
        reason: String,
    },
}

/// The least-squares problem for every form. Parameters:
/// eq. 94: `[A, a, b, phi, c]`; Kooijman: `[c, sigma, omega, p, q]`;
/// speed-varying: `[c, sigma0, omega0, p, q, sigma1, omega1]`.
struct Problem {
    tau: Vec<f64>,
    y: Vec<f64>,
    integral: Option<Vec<f64>>,
    eq94: bool,
    p: DVector<f64>,
}

impl Problem {
    fn phases(&self, k: usize) -> (f64, f64) {
        let p = &self.p;
        let tau = self.tau[k];
        let (mut s, mut w) = (p[1] * tau, p[2] * tau);
        if let Some(i) = &self.integral {
            s += p[5] * i[k];
            w += p[6] * i[k];
        }
        (s, w)
    }
    fn model(&self) -> Vec<f64> {
        let p = &self.p;
        (0..self.tau.len())
            .map(|k| {
                let (s, w) = self.phases(k);
                let e = s.exp();
                if self.eq94 {
                    p[0] * e * (w + p[3]).cos() + p[4]
                } else {
                    p[0] + e * (p[3] * w.cos() + p[4] * w.sin())
                }
            })
            .collect()
    }

    /// Model minus data at the parameters.
    fn residuals(&self) -> Option<DVector<f64>> {
        let m = self.model();
        let r = DVector::from_iterator(m.len(), m.iter().zip(&self.y).map(|(a, b)| a - b));
        r.iter().all(|x| x.is_finite()).then_some(r)
    }
    /// Jacobian of the residuals in the parameters (analytic).
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let n = self.tau.len();
        let k = self.p.len();
        let p = &self.p;
        let mut j = DMatrix::zeros(n, k);
        for i in 0..n {
            let (s, w) = self.phases(i);
            let e = s.exp();
            let tau = self.tau[i];
            // d/ds and d/dw of the oscillating part.
            let (d_ds, d_dw);
            if self.eq94 {
                let (sn, cs) = (w + p[3]).sin_cos();
                j[(i, 0)] = e * cs;
                j[(i, 3)] = -p[0] * e * sn;
                j[(i, 4)] = 1.0;
                d_ds = p[0] * e * cs;
                d_dw = -p[0] * e * sn;
            } else {
                let (sn, cs) = w.sin_cos();
                j[(i, 0)] = 1.0;
                j[(i, 3)] = e * cs;
                j[(i, 4)] = e * sn;
                d_ds = e * (p[3] * cs + p[4] * sn);
                d_dw = e * (-p[3] * sn + p[4] * cs);
            }
            j[(i, 1)] = d_ds * tau;
            j[(i, 2)] = d_dw * tau;
            if let Some(int) = &self.integral {
                j[(i, 5)] = d_ds * int[i];
                j[(i, 6)] = d_dw * int[i];
            }
        }
        j.iter().all(|x| x.is_finite()).then_some(j)
    }
}

/// The variable-projection problem: nonlinear parameters `[s, w]` or
/// `[s0, w0, s1, w1]`; residuals with the linear ones (`c, p, q`) solved
/// exactly; Jacobian by Kaufman's approximation (the model's derivative at
/// fixed linear parameters, projected off the span of the basis), which
/// costs one pass over the samples.
struct Projected<'a> {
    tau: &'a [f64],
    y: &'a [f64],
    integral: Option<&'a [f64]>,
    theta: DVector<f64>,
}

/// Basis `e^s cos w`, `e^s sin w` at every sample, the normal matrix of
/// `[1, e^s cos w, e^s sin w]` and the linear parameters.
struct Basis {
    ec_es: Vec<(f64, f64)>,
    normal: nalgebra::Cholesky<f64, nalgebra::U3>,
    linear: nalgebra::Vector3<f64>,
}

impl Projected<'_> {
    fn basis(&self) -> Option<Basis> {
        let th = self.theta.as_slice();
        let ec_es: Vec<(f64, f64)> = match self.integral {
            None => exp_basis(self.tau, th[0], th[1]).collect(),
            Some(int) => self
                .tau
                .iter()
                .zip(int)
                .map(|(&t, &i)| complex_exp(th[0] * t + th[2] * i, th[1] * t + th[3] * i))
                .collect(),
        };
        let mut a = nalgebra::Matrix3::zeros();
        let mut b = nalgebra::Vector3::zeros();
        for (&(ec, es), &y) in ec_es.iter().zip(self.y) {
            let x = nalgebra::Vector3::new(1.0, ec, es);
            a += x * x.transpose();
            b += x * y;
        }
        let normal = a.cholesky()?;
        let linear = normal.solve(&b);
        linear
            .iter()
            .all(|x| x.is_finite())
            .then_some(Basis { ec_es, normal, linear })
    }
    /// The full parameter vector (form order) at the current `theta`.
    fn full_parameters(&self, eq94: bool) -> Option<Vec<f64>> {
        let th = self.theta.as_slice();
        let l = self.basis()?.linear;
        let (c, p, q) = (l[0], l[1], l[2]);
        let mut full = if eq94 {
            vec![p.hypot(q), th[0], th[1], (-q).atan2(p), c]
        } else {
            vec![c, th[0], th[1], p, q]
        };
        full.extend_from_slice(&th[2..]);
        Some(full)
    }
}

/// `e^(s + i w)` as `(re, im)`.
fn complex_exp(s: f64, w: f64) -> (f64, f64) {
    let e = s.exp();
    let (sn, cs) = w.sin_cos();
    (e * cs, e * sn)
}

/// Whether the samples are uniformly spaced (to rounding).
fn uniform(tau: &[f64]) -> bool {
    let n = tau.len();
    n > 1 && {
        let dt = tau[1] - tau[0];
        (tau[n - 1] - tau[0] - dt * (n - 1) as f64).abs() < 1e-9 * (1.0 + tau[n - 1].abs())
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Projected<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;
    fn set_params(&mut self, x: &DVector<f64>) {
        self.theta.copy_from(x);
    }
    fn params(&self) -> DVector<f64> {
        self.theta.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        let b = self.basis()?;
        let l = &b.linear;
        let r = DVector::from_iterator(
            self.y.len(),
            b.ec_es
                .iter()
                .zip(self.y)
                .map(|(&(ec, es), &y)| l[0] + l[1] * ec + l[2] * es - y),
        );
        r.iter().all(|x| x.is_finite()).then_some(r)
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let b = self.basis()?;
        let (p, q) = (b.linear[1], b.linear[2]);
        let k = self.theta.len();
        let n = self.tau.len();
        let mut j = DMatrix::zeros(n, k);
        // Projections of each column onto the basis: accumulate Phi^T col.
        let mut phit = vec![nalgebra::Vector3::zeros(); k];
        for (i, &(ec, es)) in b.ec_es.iter().enumerate() {
            let d_ds = p * ec + q * es;
            let d_dw = -p * es + q * ec;
            let t = self.tau[i];
            let cols = [d_ds * t, d_dw * t];
            for (c, v) in cols.iter().enumerate() {
                j[(i, c)] = *v;
            }
            if k > 2 {
                let int = self.integral.map_or(0.0, |x| x[i]);
                j[(i, 2)] = d_ds * int;
                j[(i, 3)] = d_dw * int;
            }
            let x = nalgebra::Vector3::new(1.0, ec, es);
            for (c, acc) in phit.iter_mut().enumerate() {
                *acc += x * j[(i, c)];
            }
        }
        let coef: Vec<nalgebra::Vector3<f64>> = phit.iter().map(|v| b.normal.solve(v)).collect();
        for (i, &(ec, es)) in b.ec_es.iter().enumerate() {
            let x = nalgebra::Vector3::new(1.0, ec, es);
            for (c, cf) in coef.iter().enumerate() {
                j[(i, c)] -= x.dot(cf);
            }
        }
        j.iter().all(|x| x.is_finite()).then_some(j)
    }
}

/// `e^((s + i w) tau_k)` at every sample as `(re, im)`: by recurrence on
/// uniformly sampled windows (one complex product per sample; the grid calls
/// this hundreds of times per signal), exactly otherwise.
fn exp_basis(tau: &[f64], s: f64, w: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
    let uniform = uniform(tau);
    let dt = if tau.len() > 1 { tau[1] - tau[0] } else { 0.0 };
    let step = complex_exp(s * dt, w * dt);
    let mut z = complex_exp(
        s * tau.first().copied().unwrap_or(0.0),
        w * tau.first().copied().unwrap_or(0.0),
    );
    tau.iter().map(move |&t| {
        if uniform {
            let out = z;
            z = (z.0 * step.0 - z.1 * step.1, z.0 * step.1 + z.1 * step.0);
            out
        } else {
            complex_exp(s * t, w * t)
        }
    })
}

/// Residual sum of squares of `y ~ c + e^(s tau) (p cos w tau + q sin w tau)`,
/// linear in `c, p, q`, on one cell of the start grid,
/// from the decay `e^(s tau)` and the row's `cos w tau`, `sin w tau`
/// (`yy`, `b0`: the sums of `y^2` and `y`). No recurrence inside, so the
/// sums vectorize.
fn grid_ssr(decay: &[f64], cs: &[f64], sn: &[f64], y: &[f64], yy: f64, b0: f64) -> Option<f64> {
    let (mut s1, mut s2, mut s11, mut s12, mut s22, mut b1, mut b2) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..y.len().min(decay.len()).min(cs.len()).min(sn.len()) {
        let (ec, es) = (decay[k] * cs[k], decay[k] * sn[k]);
        s1 += ec;
        s2 += es;
        s11 += ec * ec;
        s12 += ec * es;
        s22 += es * es;
        b1 += ec * y[k];
        b2 += es * y[k];
    }
    let a = nalgebra::Matrix3::new(y.len() as f64, s1, s2, s1, s11, s12, s2, s12, s22);
    let b = nalgebra::Vector3::new(b0, b1, b2);
    let sol = a.cholesky()?.solve(&b);
    Some(yy - sol.dot(&b))
}

/// Dominant angular frequency from the mean spacing of zero crossings of the
/// detrended signal (rad/s). A crossing counts only once the signal has
/// passed a band of a quarter of its standard deviation on the other side
/// (hysteresis), so sample noise on a roll rate does not add crossings; a
/// heavily damped response may pass the band too few times, and then every
/// crossing counts.
fn crossing_frequency(tau: &[f64], y: &[f64]) -> Option<f64> {
    let n = y.len() as f64;
    let m = y.iter().sum::<f64>() / n;
    let sd = (y.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt();
    [0.25 * sd, 0.0].into_iter().find_map(|band| {
        let mut crossings = Vec::new();
        // Side of the band the signal was last on (+1 above, -1 below).
        let mut side = 0.0;
        let mut last_zero = None;
        for k in 0..y.len() {
            let a = y[k] - m;
            if k > 0 {
                let b = y[k - 1] - m;
                if a == 0.0 || a.signum() != b.signum() {
                    let f = if a == b { 0.0 } else { b / (b - a) };
                    last_zero = Some(tau[k - 1] + f * (tau[k] - tau[k - 1]));
                }
            }
            if a.abs() > band && a.signum() != side {
                if side != 0.0 {
                    crossings.extend(last_zero);
                }
                side = a.signum();
            }
        }
        if crossings.len() < 2 {
            return None;
        }
        let half = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        (half > 0.0).then(|| std::f64::consts::PI / half)
    })
}

fn lag1_autocorrelation(r: &[f64]) -> f64 {
    let n = r.len();
    let m = r.iter().sum::<f64>() / n as f64;
    let c0: f64 = r.iter().map(|x| (x - m).powi(2)).sum();
    let c1: f64 = (1..n).map(|k| (r[k] - m) * (r[k - 1] - m)).sum();
    if c0 > 0.0 {
        c1 / c0
    } else {
        0.0
    }
}

/// What the fits of one signal share: the zero-crossing frequency, the
/// starts (local minima of the grid, best first) and the constant-eigenvalue
/// optimum, if one converged to an oscillation. The constant and the
/// speed-varying forms on the same signal use one [`Prepared`].
#[derive(Clone, Debug)]
pub struct Prepared {
    w_hat: f64,
    starts: Vec<[f64; 2]>,
    constant: Option<[f64; 2]>,
}

/// MINPACK's limit on evaluations is patience x (parameters + 1); a
/// projected fit that has not converged in 150-250 has left the valley.
const PATIENCE: usize = 50;
/// A fitted frequency above this multiple of the zero-crossing rate fits
/// noise, not the window's oscillation.
const MAX_FREQUENCY: f64 = 4.0;

/// Converged, at least half a cycle in the window, and not above the band.
fn oscillates(th: &[f64], span: f64, w_hat: f64) -> bool {
    th[1].is_finite() && th[1].abs() * span >= std::f64::consts::PI && th[1].abs() <= MAX_FREQUENCY * w_hat
}

/// Grid, starts and the constant-eigenvalue fit of samples `(t, y)`.
pub fn prepare(t: &[f64], y: &[f64]) -> Result<Prepared, FitError> {
    let n = t.len();
    if n < 15 {
        return Err(FitError::TooFewSamples { n, k: 5 });
    }
    let t0 = t[0];
    let tau: Vec<f64> = t.iter().map(|x| x - t0).collect();
    let w_hat = crossing_frequency(&tau, y).ok_or(FitError::NoOscillation)?;
    // Coarse grid on (sigma, omega) with the linear parameters solved
    // exactly, for a start only: on at most GRID_SAMPLES samples (every
    // `stride`-th; at least 4 per period of the top grid frequency, 1.6 w_hat).
    const GRID_SAMPLES: usize = 100;
    let dt = tau[n - 1] / (n - 1) as f64;
    let max_stride = ((std::f64::consts::PI / (2.0 * 1.6 * w_hat * dt)).floor() as usize).max(1);
    let stride = n.div_ceil(GRID_SAMPLES).clamp(1, max_stride);
    let (tau_g, y_g): (Vec<f64>, Vec<f64>) = tau.iter().zip(y).step_by(stride).map(|(a, b)| (*a, *b)).unzip();
    const NW: usize = 21;
    const NS: usize = 25;
    let mut grid = [[f64::INFINITY; NS]; NW];
    let grid_w = |i: usize| w_hat * (0.6 + 0.05 * i as f64);
    let grid_s = |j: usize| w_hat * (-1.2 + 0.075 * j as f64);
    // The oscillation of a grid row is shared by its cells: cos and sin
    // once per row, the decay per cell (this grid is most of the time of a
    // log's many short kicks).
    let yy: f64 = y_g.iter().map(|v| v * v).sum();
    let b0: f64 = y_g.iter().sum();
    let uniform_g = uniform(&tau_g);
    let mut decay: Vec<f64> = Vec::with_capacity(tau_g.len());
    for (i, row) in grid.iter_mut().enumerate() {
        let w = grid_w(i);
        let (sn, cs): (Vec<f64>, Vec<f64>) = tau_g.iter().map(|&t| (w * t).sin_cos()).unzip();
        for (j, cell) in row.iter_mut().enumerate() {
            let s = grid_s(j);
            decay.clear();
            if uniform_g {
                let r = (s * (tau_g[1] - tau_g[0])).exp();
                let mut e = (s * tau_g[0]).exp();
                decay.extend(tau_g.iter().map(|_| {
                    let out = e;
                    e *= r;
                    out
                }));
            } else {
                decay.extend(tau_g.iter().map(|&t| (s * t).exp()));
            }
            if let Some(ssr) = grid_ssr(&decay, &cs, &sn, &y_g, yy, b0) {
                *cell = ssr;
            }
        }
    }
    // Starts: the grid's local minima (no smaller neighbour), best first, at
    // most MAX_STARTS. A growing or fast-decaying response has minima on
    // both sides of a non-oscillating valley; one start can end in it.
    const MAX_STARTS: usize = 4;
    let mut minima: Vec<(f64, usize, usize)> = Vec::new();
    for i in 0..NW {
        for j in 0..NS {
            let v = grid[i][j];
            let is_min = v.is_finite()
                && (i.saturating_sub(1)..=(i + 1).min(NW - 1))
                    .all(|a| (j.saturating_sub(1)..=(j + 1).min(NS - 1)).all(|b| grid[a][b] >= v));
            if is_min {
                minima.push((v, i, j));
            }
        }
    }
    minima.sort_by(|a, b| a.0.total_cmp(&b.0));
    minima.truncate(MAX_STARTS);
    if minima.is_empty() {
        return Err(FitError::NoOscillation);
    }
    // Variable projection (Golub and Pereyra 1973): the linear parameters
    // `c, p, q` are solved exactly for given phases, so Levenberg-Marquardt
    // sees only the 2 (or 4) nonlinear ones. The full problem is badly
    // conditioned where a slow drift sits under a fast decay (eq. 94's
    // amplitude and phase trade against the constant); the projected one is
    // not, and converges in a few steps, so several starts are affordable.
    let span = tau[n - 1];
    // Starts in the order of the grid's residual; the first that converges
    // to an oscillation is taken (not the smallest residual over all starts:
    // a far start can end on the slow capsize drift, another mode).
    let starts: Vec<[f64; 2]> = minima.iter().map(|&(_, i, j)| [grid_s(j), grid_w(i)]).collect();
    let mut constant = None;
    for th in &starts {
        let start = Projected {
            tau: &tau,
            y,
            integral: None,
            theta: DVector::from_vec(th.to_vec()),
        };
        let (pr, report) = LevenbergMarquardt::new().with_patience(PATIENCE).minimize(start);
        if report.termination.was_successful() && oscillates(pr.theta.as_slice(), span, w_hat) {
            constant = Some([pr.theta[0], pr.theta[1]]);
            break;
        }
    }
    Ok(Prepared {
        w_hat,
        starts,
        constant,
    })
}

/// Fit `form` to samples `(t, y)`. For speed-varying forms `speed` gives the
/// speed (m/s) at each sample.
pub fn fit(form: FitForm, t: &[f64], y: &[f64], speed: Option<&[f64]>) -> Result<FitResult, FitError> {
    fit_prepared(form, t, y, speed, &prepare(t, y)?)
}

/// [`fit`] with the signal's shared part already computed ([`prepare`] on
/// the same `t`, `y`).
pub fn fit_prepared(
    form: FitForm,
    t: &[f64],
    y: &[f64],
    speed: Option<&[f64]>,
    prep: &Prepared,
) -> Result<FitResult, FitError> {
    let n = t.len();
    let k = if form.speed_varying() { 7 } else { 5 };
    if n < 3 * k {
        return Err(FitError::TooFewSamples { n, k });
    }
    let t0 = t[0];
    let tau: Vec<f64> = t.iter().map(|x| x - t0).collect();
    let w_hat = prep.w_hat;
    let span = tau[n - 1];
    let eq94 = matches!(form, FitForm::RollAngle);
    // The speed enters through its straight line over the window (the
    // pipeline passes its linear trend): kept in the result, so that the
    // curve can be drawn again at any time.
    let speed_line = if form.speed_varying() {
        let v = speed.expect("speed-varying fit needs the speed");
        let vm = v.iter().sum::<f64>() / n as f64;
        let tm = tau.iter().sum::<f64>() / n as f64;
        let stt: f64 = tau.iter().map(|x| (x - tm).powi(2)).sum();
        let stv: f64 = tau.iter().zip(v).map(|(x, y)| (x - tm) * (y - vm)).sum();
        let slope = if stt > 0.0 { stv / stt } else { 0.0 };
        Some([vm - slope * tm, slope, vm])
    } else {
        None
    };
    let integral: Option<Vec<f64>> = speed_line.map(|line| tau.iter().map(|&x| line_integral(line, x)).collect());
    let mut best: Option<Projected> = None;
    if form.speed_varying() {
        // The speed-varying form nests the constant one (zero slopes): start
        // it from the constant optimum, so it fits at least as well and is
        // not led off by the slopes' first steps. Where the constant form
        // fits no oscillation (a growing response under a capsize drift),
        // the speed-varying one may: start it from the grid's minima then.
        let starts: Vec<[f64; 2]> = match prep.constant {
            Some(c) => vec![c],
            None => prep.starts.clone(),
        };
        for th in starts {
            let start = Projected {
                tau: &tau,
                y,
                integral: integral.as_deref(),
                theta: DVector::from_vec(vec![th[0], th[1], 0.0, 0.0]),
            };
            let (pr, report) = LevenbergMarquardt::new().with_patience(PATIENCE).minimize(start);
            if report.termination.was_successful() && oscillates(pr.theta.as_slice(), span, w_hat) {
                best = Some(pr);
                break;
            }
        }
    } else if let Some(c) = prep.constant {
        best = Some(Projected {
            tau: &tau,
            y,
            integral: None,
            theta: DVector::from_vec(c.to_vec()),
        });
    }
    let p_full = best.and_then(|pr| pr.full_parameters(eq94));
    let problem = Problem {
        tau: tau.clone(),
        y: y.to_vec(),
        integral: integral.clone(),
        eq94,
        p: DVector::from_vec(p_full.ok_or(FitError::NotConverged {
            reason: format!("no start of {} converged to an oscillation", prep.starts.len()),
        })?),
    };
    let r = problem.residuals().ok_or(FitError::NotConverged {
        reason: "non-finite residuals".into(),
    })?;
    let jac = problem.jacobian().ok_or(FitError::NotConverged {
        reason: "non-finite Jacobian".into(),
    })?;
    let ssr = r.norm_squared();
    let ym = y.iter().sum::<f64>() / n as f64;
    let sst: f64 = y.iter().map(|v| (v - ym).powi(2)).sum();
    let rho = lag1_autocorrelation(r.as_slice());
    let inflation = if rho > 0.0 { (1.0 + rho) / (1.0 - rho) } else { 1.0 };
    let s2 = ssr / (n - k) as f64;
    let cov = (jac.transpose() * &jac).try_inverse().ok_or(FitError::NotConverged {
        reason: "singular normal matrix".into(),
    })? * (s2 * inflation);
    let se = |i: usize| cov[(i, i)].max(0.0).sqrt();
    let pr = &problem.p;
    let mut omega = pr[2];
    let sigma = pr[1];
    // At least half a cycle in the window was checked on the start
    // ([`oscillates`]); the full parameters are the projected optimum's.
    if !(omega.is_finite() && sigma.is_finite()) {
        return Err(FitError::NoOscillation);
    }
    let mut params: Vec<f64> = pr.iter().copied().collect();
    // Report imag > 0: flip the sign of omega (and the sine/phase terms).
    if omega < 0.0 {
        omega = -omega;
        params[2] = omega;
        if eq94 {
            params[3] = -params[3];
        } else {
            params[4] = -params[4];
        }
        if form.speed_varying() {
            params[6] = -params[6];
        }
    }
    let ln = (ssr / n as f64).max(1e-300).ln();
    Ok(FitResult {
        form,
        eigenvalue: [sigma, omega],
        eigenvalue_stderr: [se(1), se(2)],
        slope: form.speed_varying().then(|| [params[5], params[6]]),
        slope_stderr: form.speed_varying().then(|| [se(5), se(6)]),
        r2: 1.0 - ssr / sst,
        rms: (ssr / n as f64).sqrt(),
        aic: n as f64 * ln + 2.0 * k as f64,
        bic: n as f64 * ln + k as f64 * (n as f64).ln(),
        n,
        params,
        t0,
        residual_autocorrelation: rho,
        speed_line,
    })
}
