//! Verification of generated code against central finite differences of the
//! generated primal quantities, at random states (a user-facing check: run it
//! after changing a model).

use crate::constraints::{constraint_matrices, solve_configuration, solve_velocities, NewtonOptions};
use crate::linalg::solve_in_place;
use crate::model::MultibodyModel;
use crate::random::SplitMix64;
use nalgebra::{DMatrix, SymmetricEigen};
use serde::Serialize;

/// Result of one check.
#[derive(Clone, Debug, Serialize)]
pub struct QuantityCheck {
    pub name: String,
    /// Largest error over all states, relative to the largest magnitude of
    /// the reference of that state (so tiny entries do not dominate).
    pub max_rel_error: f64,
    pub tolerance: f64,
    pub passed: bool,
}

/// All checks of one model.
#[derive(Clone, Debug, Serialize)]
pub struct VerifyReport {
    pub model: String,
    pub states: usize,
    pub seed: u64,
    pub passed: bool,
    pub quantities: Vec<QuantityCheck>,
}

/// Options.
#[derive(Clone, Copy, Debug)]
pub struct VerifyOptions {
    /// Number of random states (default 20).
    pub states: usize,
    /// Seed of the state generator (default 1).
    pub seed: u64,
    /// Tolerance of finite-difference comparisons (default 1e-6; central
    /// differences with step ~1e-5 are accurate to ~1e-9 on these smooth
    /// trigonometric expressions, so a real error shows up orders above it).
    pub fd_tolerance: f64,
}
impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            states: 20,
            seed: 1,
            fd_tolerance: 1e-6,
        }
    }
}

struct Acc {
    name: &'static str,
    tol: f64,
    worst: f64,
}
impl Acc {
    fn new(name: &'static str, tol: f64) -> Self {
        Acc { name, tol, worst: 0.0 }
    }
    fn compare(&mut self, got: &[f64], want: &[f64]) {
        let scale = want
            .iter()
            .chain(got.iter())
            .fold(0.0f64, |m, x| m.max(x.abs()))
            .max(1e-12);
        for (g, w) in got.iter().zip(want) {
            let e = (g - w).abs() / scale;
            if !(e <= self.worst) {
                self.worst = if e.is_nan() { f64::INFINITY } else { e.max(self.worst) };
            }
        }
    }
    /// Record an error already made relative.
    fn record(&mut self, e: f64) {
        if !(e <= self.worst) {
            self.worst = if e.is_nan() { f64::INFINITY } else { e };
        }
    }
    fn done(self) -> QuantityCheck {
        QuantityCheck {
            name: self.name.into(),
            max_rel_error: self.worst,
            tolerance: self.tol,
            passed: self.worst <= self.tol,
        }
    }
}

/// Central difference of a vector function along a scalar variable.
fn central(h: f64, mut f: impl FnMut(f64) -> Vec<f64>) -> Vec<f64> {
    let a = f(h);
    let b = f(-h);
    a.iter().zip(&b).map(|(x, y)| (x - y) / (2.0 * h)).collect()
}

/// Run every check on `M` at `opts.states` random states with parameters
/// `param` (the model's parameter vector).
pub fn verify<M: MultibodyModel>(param: &[f64], opts: &VerifyOptions) -> VerifyReport {
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let nnh = M::NONHOLONOMIC.len();
    let mut rng = SplitMix64::new(opts.seed);
    let tol = opts.fd_tolerance;
    let (mut a_cq, mut a_ct, mut a_dcq) = (Acc::new("Cq", tol), Acc::new("Ct", tol), Acc::new("dCqdp", tol));
    let (mut a_b, mut a_dbdp) = (Acc::new("B", tol), Acc::new("dBdp", tol));
    let mut a_qv = Acc::new("Qv", tol);
    let mut a_qg = Acc::new("Qgrav", tol);
    let mut a_sym = Acc::new("M symmetric", 1e-14);
    let mut a_psd = Acc::new("M positive semi-definite", 1e-12);
    let mut a_pow_v = Acc::new("power p'^T Qv = -1/2 p'^T dM/dt p'", tol);
    let mut a_pow_g = Acc::new("power p'^T Qgrav = -dV/dt", tol);
    let mut a_t = Acc::new("T = 1/2 p'^T M p'", 1e-13);
    let mut a_all = Acc::new("all_quantities = individual functions", 1e-12);
    for _ in 0..opts.states {
        let p: Vec<f64> = (0..nq).map(|j| M::INITIAL_GUESS[j] + rng.uniform(-0.6, 0.6)).collect();
        let dp: Vec<f64> = (0..nq).map(|_| rng.uniform(-3.0, 3.0)).collect();
        let t = rng.uniform(0.0, 2.0);
        let h = 1e-5;
        let shifted = |j: Option<usize>, s: f64, dir: Option<&[f64]>| -> Vec<f64> {
            let mut q = p.clone();
            if let Some(j) = j {
                q[j] += s;
            }
            if let Some(d) = dir {
                for k in 0..nq {
                    q[k] += s * d[k];
                }
            }
            q
        };
        // Cq vs FD of Res; Ct vs FD in time.
        let mut cq = vec![0.0; nh * nq];
        M::holonomic_jacobian(param, t, &p, &mut cq);
        let mut fd = vec![0.0; nh * nq];
        for j in 0..nq {
            let col = central(h, |s| {
                let mut r = vec![0.0; nh];
                M::holonomic_residuals(param, t, &shifted(Some(j), s, None), &mut r);
                r
            });
            for i in 0..nh {
                fd[i * nq + j] = col[i];
            }
        }
        a_cq.compare(&cq, &fd);
        let mut ct = vec![0.0; nh];
        M::holonomic_time_derivative(param, t, &p, &mut ct);
        a_ct.compare(
            &ct,
            &central(h, |s| {
                let mut r = vec![0.0; nh];
                M::holonomic_residuals(param, t + s, &p, &mut r);
                r
            }),
        );
        // dCqdp vs directional FD of Cq p' along p'.
        let cq_dp = |q: &[f64]| {
            let mut c = vec![0.0; nh * nq];
            M::holonomic_jacobian(param, t, q, &mut c);
            (0..nh)
                .map(|i| (0..nq).map(|k| c[i * nq + k] * dp[k]).sum())
                .collect::<Vec<f64>>()
        };
        let mut dcq = vec![0.0; nh];
        M::holonomic_convective(param, t, &p, &dp, &mut dcq);
        a_dcq.compare(&dcq, &central(h, |s| cq_dp(&shifted(None, s, Some(&dp)))));
        // B vs FD of the contact-point velocities in p'; dBdp vs FD of B p'.
        let mut b = vec![0.0; nnh * nq];
        M::nonholonomic_matrix(param, t, &p, &mut b);
        let mut fdb = vec![0.0; nnh * nq];
        for j in 0..nq {
            let col = central(h, |s| {
                let mut v = dp.clone();
                v[j] += s;
                let mut r = vec![0.0; nnh];
                M::nonholonomic_velocities(param, t, &p, &v, &mut r);
                r
            });
            for i in 0..nnh {
                fdb[i * nq + j] = col[i];
            }
        }
        a_b.compare(&b, &fdb);
        let b_dp = |q: &[f64]| {
            let mut c = vec![0.0; nnh * nq];
            M::nonholonomic_matrix(param, t, q, &mut c);
            (0..nnh)
                .map(|i| (0..nq).map(|k| c[i * nq + k] * dp[k]).sum())
                .collect::<Vec<f64>>()
        };
        let mut dbdp = vec![0.0; nnh];
        M::nonholonomic_convective(param, t, &p, &dp, &mut dbdp);
        a_dbdp.compare(&dbdp, &central(h, |s| b_dp(&shifted(None, s, Some(&dp)))));
        // Qv vs -d(M p')/dt + dT/dp.
        let mass_at = |q: &[f64]| {
            let mut m = vec![0.0; nq * nq];
            M::mass_matrix(param, q, &mut m);
            m
        };
        let m0 = mass_at(&p);
        let mdot = central(h, |s| mass_at(&shifted(None, s, Some(&dp))));
        let mut qv = vec![0.0; nq];
        M::quadratic_velocity_forces(param, &p, &dp, &mut qv);
        let dtdq: Vec<f64> = (0..nq)
            .map(|j| central(h, |s| vec![M::kinetic_energy(param, &shifted(Some(j), s, None), &dp)])[0])
            .collect();
        let want: Vec<f64> = (0..nq)
            .map(|a| -(0..nq).map(|c| mdot[a * nq + c] * dp[c]).sum::<f64>() + dtdq[a])
            .collect();
        a_qv.compare(&qv, &want);
        // Qgrav vs -dV/dp.
        let mut qg = vec![0.0; nq];
        M::gravity_forces(param, &p, &mut qg);
        let dvdq: Vec<f64> = (0..nq)
            .map(|j| -central(h, |s| vec![M::potential_energy(param, &shifted(Some(j), s, None))])[0])
            .collect();
        a_qg.compare(&qg, &dvdq);
        // M symmetric and positive semi-definite.
        let asym: Vec<f64> = (0..nq * nq).map(|k| m0[(k % nq) * nq + k / nq]).collect();
        a_sym.compare(&m0, &asym);
        let mm = DMatrix::from_row_slice(nq, nq, &m0);
        let ev = SymmetricEigen::new(mm.clone()).eigenvalues;
        let scale = ev.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let neg = ev.iter().fold(0.0f64, |m, x| m.max(-x)) / scale;
        a_psd.worst = a_psd.worst.max(neg);
        // T = 1/2 p'^T M p'.
        let tt = 0.5
            * (0..nq)
                .map(|a| (0..nq).map(|c| dp[a] * m0[a * nq + c] * dp[c]).sum::<f64>())
                .sum::<f64>();
        a_t.compare(&[M::kinetic_energy(param, &p, &dp)], &[tt]);
        // all_quantities must reproduce every individual function.
        let total: usize = M::ALL_QUANTITIES_LAYOUT.iter().map(|x| x.2).sum();
        let mut all = vec![0.0; total];
        M::all_quantities(param, t, &p, &dp, &mut all);
        for &(name, off, len) in M::ALL_QUANTITIES_LAYOUT {
            let mut one = vec![0.0; len];
            match name {
                "mass_matrix" => M::mass_matrix(param, &p, &mut one),
                "quadratic_velocity_forces" => M::quadratic_velocity_forces(param, &p, &dp, &mut one),
                "gravity_forces" => M::gravity_forces(param, &p, &mut one),
                "applied_forces" => M::applied_forces(param, t, &p, &dp, &mut one),
                "holonomic_residuals" => M::holonomic_residuals(param, t, &p, &mut one),
                "holonomic_jacobian" => M::holonomic_jacobian(param, t, &p, &mut one),
                "holonomic_time_derivative" => M::holonomic_time_derivative(param, t, &p, &mut one),
                "holonomic_convective" => M::holonomic_convective(param, t, &p, &dp, &mut one),
                "nonholonomic_velocities" => M::nonholonomic_velocities(param, t, &p, &dp, &mut one),
                "nonholonomic_matrix" => M::nonholonomic_matrix(param, t, &p, &mut one),
                "nonholonomic_convective" => M::nonholonomic_convective(param, t, &p, &dp, &mut one),
                "point_positions" => M::point_positions(param, &p, &mut one),
                _ => one.copy_from_slice(&all[off..off + len]),
            }
            a_all.compare(&all[off..off + len], &one);
        }
        // Power identities.
        let pq: f64 = (0..nq).map(|a| dp[a] * qv[a]).sum();
        let pm: f64 = -0.5
            * (0..nq)
                .map(|a| (0..nq).map(|c| dp[a] * mdot[a * nq + c] * dp[c]).sum::<f64>())
                .sum::<f64>();
        let ke = tt.abs().max(1e-12);
        a_pow_v.compare(&[pq / ke], &[pm / ke]);
        let pg: f64 = (0..nq).map(|a| dp[a] * qg[a]).sum();
        let dvdt = central(h, |s| vec![M::potential_energy(param, &shifted(None, s, Some(&dp)))])[0];
        let vs = (0..nq).map(|a| (dp[a] * qg[a]).abs()).sum::<f64>().max(1e-12);
        a_pow_g.compare(&[pg / vs], &[-dvdt / vs]);
    }
    let (a_energy, a_dissipative, a_terms) = power_checks::<M>(param, opts, &mut rng);
    let quantities: Vec<QuantityCheck> = [
        a_cq,
        a_ct,
        a_dcq,
        a_b,
        a_dbdp,
        a_qv,
        a_qg,
        a_sym,
        a_psd,
        a_t,
        a_pow_v,
        a_pow_g,
        a_all,
        a_terms,
        a_energy,
        a_dissipative,
    ]
    .into_iter()
    .map(Acc::done)
    .collect();
    VerifyReport {
        model: M::NAME.into(),
        states: opts.states,
        seed: opts.seed,
        // No state checked is no verification, not a pass.
        passed: opts.states > 0 && quantities.iter().all(|q| q.passed),
        quantities,
    }
}

/// The parameter vector `verify` uses for a model: `base` with every effect
/// parameter that defaults to 0 (effect absent) set to a test value, so that
/// the effects' forces are exercised. Test values are moderate multiples of
/// typical magnitudes; the identities hold for any value.
pub fn with_effects_switched_on<M: MultibodyModel>(base: &[f64]) -> Vec<f64> {
    let np = M::PARAMETER_INFO.len();
    M::PARAMETER_INFO
        .iter()
        .zip(base)
        .map(|(info, &x)| match (info.effect, info.default) {
            (Some(_), Some(d)) if d == 0.0 && x == 0.0 => 0.1,
            _ => x,
        })
        .chain(base[np..].iter().copied())
        .collect()
}

/// Power checks along motions that satisfy the constraints: the energy
/// balance `d(T + V)/dt = p'^T Qext + (power of the constraint forces)` by a
/// central difference in time, each dissipative force's power `p'^T Q_f <= 0`,
/// and `applied_forces` = the sum of `applied_force_terms`.
fn power_checks<M: MultibodyModel>(param: &[f64], opts: &VerifyOptions, rng: &mut SplitMix64) -> (Acc, Acc, Acc) {
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let nc = nh + M::NONHOLONOMIC.len();
    let nf = M::FORCES.len();
    let np = M::PARAMETERS.len();
    let mut param = param.to_vec();
    let mut a_energy = Acc::new("energy balance d(T+V)/dt = p'^T Qext + constraint power", 1e-5);
    let mut a_dis = Acc::new("dissipative forces: power p'^T Q_f <= 0", 1e-12);
    let mut a_terms = Acc::new("applied_forces = sum of applied_force_terms", 1e-12);
    for _ in 0..opts.states {
        // A configuration on the constraint manifold near upright running.
        let mut p: Vec<f64> = vec![0.0; nq];
        M::upright_configuration(&param, M::INITIAL_GUESS, &mut p);
        for &j in M::INDEPENDENT {
            p[j] = rng.uniform(-0.4, 0.4);
        }
        let t = rng.uniform(0.0, 2.0);
        // Extra states (e.g. tyre forces) at random values, so that the
        // forces that depend on them do work.
        for z in param[np..].iter_mut() {
            *z = rng.uniform(-20.0, 20.0);
        }
        let param = &param[..];
        for (j, x) in p.iter_mut().enumerate() {
            if !M::INDEPENDENT.contains(&j) && !M::DEPENDENT.contains(&j) {
                *x += rng.uniform(-0.5, 0.5);
            }
        }
        let mut dp = vec![0.0; nq];
        for &j in M::INDEPENDENT {
            dp[j] = rng.uniform(-3.0, 3.0);
        }
        if solve_configuration::<M, f64>(param, t, &mut p, &NewtonOptions::default()).is_err()
            || solve_velocities::<M, f64>(param, t, &p, &mut dp).is_err()
        {
            continue;
        }
        // Accelerations and multipliers: [M D^T; D 0] [p''; lambda] = [Q; -gamma].
        let mut mass = vec![0.0; nq * nq];
        M::mass_matrix(param, &p, &mut mass);
        let (mut qv, mut qg, mut qe) = (vec![0.0; nq], vec![0.0; nq], vec![0.0; nq]);
        M::quadratic_velocity_forces(param, &p, &dp, &mut qv);
        M::gravity_forces(param, &p, &mut qg);
        M::applied_forces(param, t, &p, &dp, &mut qe);
        let mut terms = vec![0.0; nf * nq];
        M::applied_force_terms(param, t, &p, &dp, &mut terms);
        let summed: Vec<f64> = (0..nq).map(|a| (0..nf).map(|f| terms[f * nq + a]).sum()).collect();
        a_terms.compare(&summed, &qe);
        let cm = constraint_matrices::<M, f64>(param, t, &p);
        let mut gamma = vec![0.0; nc];
        M::holonomic_convective(param, t, &p, &dp, &mut gamma[..nh]);
        M::nonholonomic_convective(param, t, &p, &dp, &mut gamma[nh..]);
        let n = nq + nc;
        let mut a = vec![0.0; n * n];
        let mut b = vec![0.0; n];
        for r in 0..nq {
            for c in 0..nq {
                a[r * n + c] = mass[r * nq + c];
            }
            for i in 0..nc {
                a[r * n + nq + i] = cm.d[i * nq + r];
                a[(nq + i) * n + r] = cm.d[i * nq + r];
            }
            b[r] = qv[r] + qg[r] + qe[r];
        }
        for i in 0..nc {
            b[nq + i] = -gamma[i];
        }
        if solve_in_place(&mut a, n, &mut b, 1).is_err() {
            continue;
        }
        let (ddp, lambda) = b.split_at(nq);
        // T and V along the motion to second order, p(s) = p + s p' + s^2/2 p'';
        // the central difference of T + V is then exact to O(h^2).
        let energies = |s: f64| {
            let q: Vec<f64> = (0..nq).map(|j| p[j] + s * dp[j] + 0.5 * s * s * ddp[j]).collect();
            let v: Vec<f64> = (0..nq).map(|j| dp[j] + s * ddp[j]).collect();
            (M::kinetic_energy(param, &q, &v), M::potential_energy(param, &q))
        };
        let h = 2e-5;
        let ((t1, v1), (t0, v0)) = (energies(h), energies(-h));
        let (dt_dt, dv_dt) = ((t1 - t0) / (2.0 * h), (v1 - v0) / (2.0 * h));
        let de_dt = dt_dt + dv_dt;
        let p_ext: f64 = (0..nq).map(|j| dp[j] * qe[j]).sum();
        // Constraint forces -D^T lambda do work only where D p' != 0 (the
        // driving constraint): power -(D p') . lambda = -d . lambda.
        let p_con: f64 = -(0..nc).map(|i| cm.d_rhs[i] * lambda[i]).sum::<f64>();
        let scale = p_ext.abs() + p_con.abs() + dt_dt.abs() + dv_dt.abs() + 1e-9;
        a_energy.record((de_dt - p_ext - p_con).abs() / scale);
        for (f, info) in M::FORCES.iter().enumerate() {
            if info.dissipative {
                let pw: f64 = (0..nq).map(|j| dp[j] * terms[f * nq + j]).sum();
                a_dis.record(pw.max(0.0) / scale);
            }
        }
    }
    (a_energy, a_dis, a_terms)
}
