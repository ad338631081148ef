//! The reduced equations `Ec = Mi q'' - Qi` by generalized coordinate
//! partitioning (thesis section 3.8, eq. 40-47), in any scalar type: the
//! dependent coordinates and velocities solved from the constraints, then
//! the equations in the independent coordinates alone.
//!
//! Apart from the linearizations because they are the equations
//! themselves: the general path and the state space differentiate them in
//! dual numbers, the thesis's cross-check by finite differences (the fast
//! upright path evaluates only the parts it needs, itself).

use crate::constraints::{constraint_matrices, dependent_velocities, solve_configuration, NewtonOptions};
use crate::linalg::{lu_factor, lu_solve};
use crate::linear_types::ConstraintError;
use crate::model::MultibodyModel;
use crate::scalar::Scalar;

/// Evaluate the reduced equations `Ec = Mi q'' - Qi` (thesis `EcMov.m`) at
/// independent coordinates `q`, rates `dq`, accelerations `ddq`, with the
/// ignorable coordinates at their initial guesses and time `t`. Returns
/// `(Ec, Mi)` (`Mi` row-major `nind x nind`).
pub fn reduced_equations<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    q: &[T],
    dq: &[T],
    ddq: &[T],
) -> Result<(Vec<T>, Vec<T>), ConstraintError> {
    reduced_system::<M, T>(param, t, q, dq, ddq).map(|s| (s.ec, s.mi))
}

/// The reduced equations with the full configuration and velocities they
/// were evaluated at.
pub struct ReducedSystem<T> {
    /// `Ec = Mi q'' - Qi`.
    pub ec: Vec<T>,
    /// `Mi`, row-major `nind x nind`.
    pub mi: Vec<T>,
    /// All coordinates (dependent ones solved).
    pub p: Vec<T>,
    /// All velocities (dependent ones solved).
    pub dp: Vec<T>,
    /// `Ec` at rest (all velocities zero, no acceleration):
    /// `-E^T (Qgrav + Qext(p, 0))`; its derivative in `q` is the stiffness
    /// at zero forward speed, from the same evaluation.
    pub ec_rest: Vec<T>,
}

/// [`reduced_equations`], also returning `p` and `p'`.
pub fn reduced_system<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    q: &[T],
    dq: &[T],
    ddq: &[T],
) -> Result<ReducedSystem<T>, ConstraintError> {
    let nq = M::nq();
    let ind = M::INDEPENDENT;
    let ni = ind.len();
    // Start from the model's physical upright configuration (closed-form
    // frame pitch and rim angle), so Newton lands on the physical branch.
    let paramf: Vec<f64> = param.iter().map(|x| x.re()).collect();
    let mut guess = vec![0.0; nq];
    M::upright_configuration(&paramf, M::INITIAL_GUESS, &mut guess);
    if let Some(j) = guess.iter().position(|x| !x.is_finite()) {
        return Err(ConstraintError::NoUprightConfiguration {
            coordinate: M::COORDINATES[j],
        });
    }
    let mut p: Vec<T> = guess.iter().map(|&x| T::cst(x)).collect();
    for (k, &j) in ind.iter().enumerate() {
        p[j] = q[k];
    }
    solve_configuration::<M, T>(param, t, &mut p, &NewtonOptions::default())?;
    // One factorization of D_dep gives E = [I; -Ddep^-1 Dind] and the
    // dependent velocities (eq. 40-45) and, after gamma, F = [0; -Ddep^-1
    // gamma].
    let nc = M::HOLONOMIC.len() + M::NONHOLONOMIC.len();
    let cm = constraint_matrices::<M, T>(param, t, &p);
    let depv = dependent_velocities::<M>();
    let nd = depv.len();
    let singular = |s: crate::linalg::Singular| ConstraintError::SingularJacobian {
        what: "coordinate partitioning",
        column: s.column,
        pivot: s.pivot,
        scale: s.scale,
    };
    let mut a = vec![T::zero(); nd * nd];
    // Right-hand sides: columns [Dind (ni columns) | d].
    let mut rhs = vec![T::zero(); nd * (ni + 1)];
    for i in 0..nc {
        for (k, &j) in depv.iter().enumerate() {
            a[i * nd + k] = cm.d[i * nq + j];
        }
        for (k, &j) in ind.iter().enumerate() {
            rhs[i * (ni + 1) + k] = cm.d[i * nq + j];
        }
        rhs[i * (ni + 1) + ni] = cm.d_rhs[i];
    }
    let mut perm = vec![0; nd];
    lu_factor(&mut a, nd, &mut perm).map_err(singular)?;
    lu_solve(&a, nd, &perm, &mut rhs, ni + 1);
    let mut dp = vec![T::zero(); nq];
    for (k, &j) in ind.iter().enumerate() {
        dp[j] = dq[k];
    }
    for (r, &j) in depv.iter().enumerate() {
        let mut v = rhs[r * (ni + 1) + ni];
        for k in 0..ni {
            v -= rhs[r * (ni + 1) + k] * dq[k];
        }
        dp[j] = v;
    }
    let nh = M::HOLONOMIC.len();
    let mut gamma = vec![T::zero(); nc];
    M::holonomic_convective(param, t, &p, &dp, &mut gamma[..nh]);
    M::nonholonomic_convective(param, t, &p, &dp, &mut gamma[nh..]);
    lu_solve(&a, nd, &perm, &mut gamma, 1);
    let mut e = vec![T::zero(); nq * ni];
    let mut f = vec![T::zero(); nq];
    for (k, &j) in ind.iter().enumerate() {
        e[j * ni + k] = T::one();
    }
    for (r, &j) in depv.iter().enumerate() {
        for k in 0..ni {
            e[j * ni + k] = -rhs[r * (ni + 1) + k];
        }
        f[j] = -gamma[r];
    }

    let mut mass = vec![T::zero(); nq * nq];
    M::mass_matrix(param, &p, &mut mass);
    let mut qv = vec![T::zero(); nq];
    M::quadratic_velocity_forces(param, &p, &dp, &mut qv);
    let mut qg = vec![T::zero(); nq];
    M::gravity_forces(param, &p, &mut qg);
    let mut qe = vec![T::zero(); nq];
    M::applied_forces(param, t, &p, &dp, &mut qe);
    // Q = Qv + Qgrav + Qext - M F; Mi = E^T M E; Qi = E^T Q (eq. 46-47).
    let mut qtot = vec![T::zero(); nq];
    for r in 0..nq {
        let mut s = qv[r] + qg[r] + qe[r];
        for c in 0..nq {
            s -= mass[r * nq + c] * f[c];
        }
        qtot[r] = s;
    }
    let mut me = vec![T::zero(); nq * ni];
    for r in 0..nq {
        for k in 0..ni {
            let mut s = T::zero();
            for c in 0..nq {
                s += mass[r * nq + c] * e[c * ni + k];
            }
            me[r * ni + k] = s;
        }
    }
    let mut mi = vec![T::zero(); ni * ni];
    let mut ec = vec![T::zero(); ni];
    for a_ in 0..ni {
        let mut qi = T::zero();
        for r in 0..nq {
            qi += e[r * ni + a_] * qtot[r];
        }
        let mut s = -qi;
        for b in 0..ni {
            let mut m = T::zero();
            for r in 0..nq {
                m += e[r * ni + a_] * me[r * ni + b];
            }
            mi[a_ * ni + b] = m;
            s += m * ddq[b];
        }
        ec[a_] = s;
    }
    let mut qe_rest = vec![T::zero(); nq];
    M::applied_forces(param, t, &p, &vec![T::zero(); nq], &mut qe_rest);
    let ec_rest: Vec<T> = (0..ni)
        .map(|a_| {
            let mut qi = T::zero();
            for r in 0..nq {
                qi += e[r * ni + a_] * (qg[r] + qe_rest[r]);
            }
            -qi
        })
        .collect();
    Ok(ReducedSystem { ec, mi, p, dp, ec_rest })
}
