//! Holonomic constraint solution (Newton's method with the generated
//! Jacobian) and dependent velocities, for any generated model.

use crate::linalg::{solve_in_place, Singular};
pub use crate::linear_types::ConstraintError;
use crate::model::MultibodyModel;
use crate::scalar::Scalar;

/// Options of the Newton solver, with documented defaults.
#[derive(Clone, Copy, Debug)]
pub struct NewtonOptions {
    /// Convergence tolerance on the max-norm of the residuals (default 1e-14).
    pub tol: f64,
    /// Iteration cap (default 50).
    pub max_iterations: usize,
}
impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tol: 1e-14,
            max_iterations: 50,
        }
    }
}

/// Diagnostics of a converged solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonInfo {
    pub iterations: usize,
    /// Max-norm of the residuals at the solution.
    pub residual: f64,
}

fn singular(what: &'static str) -> impl Fn(Singular) -> ConstraintError {
    move |s| ConstraintError::SingularJacobian {
        what,
        column: s.column,
        pivot: s.pivot,
        scale: s.scale,
    }
}

/// Solve the holonomic constraints for the dependent coordinates
/// (`M::DEPENDENT`), keeping all other coordinates of `p` fixed. Newton runs
/// on the real parts; with dual numbers, one final Newton step in `T` carries
/// the exact derivatives of the solution (implicit function theorem).
pub fn solve_configuration<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    p: &mut [T],
    opts: &NewtonOptions,
) -> Result<NewtonInfo, ConstraintError> {
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let dep = M::DEPENDENT;
    assert_eq!(p.len(), nq, "coordinate vector length");
    if param.iter().chain(p.iter()).any(|x| !x.re().is_finite()) || !t.re().is_finite() {
        return Err(ConstraintError::NotFinite {
            what: "parameters or coordinates",
        });
    }
    let paramf: Vec<f64> = param.iter().map(|x| x.re()).collect();
    let mut pf: Vec<f64> = p.iter().map(|x| x.re()).collect();
    let tf = t.re();
    let mut res = vec![0.0; nh];
    let mut cq = vec![0.0; nh * nq];
    let mut jac = vec![0.0; nh * nh];
    let mut iterations = 0;
    let norm = |r: &[f64]| r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    M::holonomic_residuals(&paramf, tf, &pf, &mut res);
    let mut rnorm = norm(&res);
    while !(rnorm <= opts.tol) || iterations == 0 {
        if iterations >= opts.max_iterations || !rnorm.is_finite() {
            let worst = (0..nh)
                .max_by(|&a, &b| res[a].abs().total_cmp(&res[b].abs()))
                .unwrap_or(0);
            return Err(ConstraintError::NotSatisfiable {
                constraint: M::HOLONOMIC.get(worst).copied().unwrap_or("?"),
                residual: rnorm,
                iterations,
            });
        }
        M::holonomic_jacobian(&paramf, tf, &pf, &mut cq);
        for i in 0..nh {
            for (k, &j) in dep.iter().enumerate() {
                jac[i * nh + k] = cq[i * nq + j];
            }
        }
        let mut step = res.clone();
        solve_in_place(&mut jac, nh, &mut step, 1).map_err(singular("holonomic constraints"))?;
        // Damped step: halve until the residual decreases (guards against
        // overshooting into another branch from a poor guess).
        let mut lambda = 1.0;
        let base = pf.clone();
        loop {
            for (k, &j) in dep.iter().enumerate() {
                pf[j] = base[j] - lambda * step[k];
            }
            M::holonomic_residuals(&paramf, tf, &pf, &mut res);
            let n = norm(&res);
            if n < rnorm || lambda < 1e-3 || n <= opts.tol {
                rnorm = n;
                break;
            }
            lambda *= 0.5;
        }
        iterations += 1;
        if rnorm <= opts.tol {
            break;
        }
    }
    // Final step in T: exact first derivatives of the solution.
    for (j, x) in p.iter_mut().enumerate() {
        if dep.contains(&j) {
            *x = T::cst(pf[j]);
        }
    }
    let mut res_t = vec![T::zero(); nh];
    let mut cq_t = vec![T::zero(); nh * nq];
    M::holonomic_residuals(param, t, p, &mut res_t);
    M::holonomic_jacobian(param, t, p, &mut cq_t);
    let mut jac_t = vec![T::zero(); nh * nh];
    for i in 0..nh {
        for (k, &j) in dep.iter().enumerate() {
            jac_t[i * nh + k] = cq_t[i * nq + j];
        }
    }
    solve_in_place(&mut jac_t, nh, &mut res_t, 1).map_err(singular("holonomic constraints"))?;
    for (k, &j) in dep.iter().enumerate() {
        p[j] -= res_t[k];
    }
    Ok(NewtonInfo {
        iterations,
        residual: rnorm,
    })
}

/// The constraint matrix `D = [Cq; B]` and right-hand sides at velocity level
/// (`D p' = d`, `d = [-Ct; 0]`) and acceleration level (`D p'' = -gamma`,
/// `gamma = [dCqdp; dBdp]`).
pub struct ConstraintMatrices<T> {
    /// `(nh + nnh) x nq`, row-major.
    pub d: Vec<T>,
    /// Velocity-level right-hand side.
    pub d_rhs: Vec<T>,
}

/// Assemble `D` and `d` at `(p, t)`.
pub fn constraint_matrices<M: MultibodyModel, T: Scalar>(param: &[T], t: T, p: &[T]) -> ConstraintMatrices<T> {
    let nq = M::nq();
    let nh = M::HOLONOMIC.len();
    let nnh = M::NONHOLONOMIC.len();
    let mut d = vec![T::zero(); (nh + nnh) * nq];
    M::holonomic_jacobian(param, t, p, &mut d[..nh * nq]);
    M::nonholonomic_matrix(param, t, p, &mut d[nh * nq..]);
    let mut ct = vec![T::zero(); nh];
    M::holonomic_time_derivative(param, t, p, &mut ct);
    let mut d_rhs = vec![T::zero(); nh + nnh];
    for i in 0..nh {
        d_rhs[i] = -ct[i];
    }
    ConstraintMatrices { d, d_rhs }
}

/// Indices of the coordinates whose velocities are dependent (all but the
/// independent ones).
pub fn dependent_velocities<M: MultibodyModel>() -> Vec<usize> {
    (0..M::nq()).filter(|j| !M::INDEPENDENT.contains(j)).collect()
}

/// Solve the velocity constraints for the dependent velocities, given the
/// independent ones already in `dp` (thesis eq. 40-41).
pub fn solve_velocities<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    p: &[T],
    dp: &mut [T],
) -> Result<(), ConstraintError> {
    let nq = M::nq();
    let cm = constraint_matrices::<M, T>(param, t, p);
    let depv = dependent_velocities::<M>();
    let nd = depv.len();
    let nc = cm.d_rhs.len();
    assert_eq!(
        nc, nd,
        "a validated model has as many constraints as dependent velocities"
    );
    let mut a = vec![T::zero(); nd * nd];
    let mut rhs = cm.d_rhs.clone();
    for i in 0..nc {
        for (k, &j) in depv.iter().enumerate() {
            a[i * nd + k] = cm.d[i * nq + j];
        }
        for &j in M::INDEPENDENT {
            rhs[i] -= cm.d[i * nq + j] * dp[j];
        }
    }
    solve_in_place(&mut a, nd, &mut rhs, 1).map_err(singular("velocity constraints"))?;
    for (k, &j) in depv.iter().enumerate() {
        dp[j] = rhs[k];
    }
    Ok(())
}
