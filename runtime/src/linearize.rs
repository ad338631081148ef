//! Reduced equations by generalized coordinate partitioning (thesis section
//! 3.8, eq. 40-47) and their exact linearization about upright straight
//! running (section 3.9, eq. 48-50).
//!
//! The reduced equations are `Ec = Mi q'' - Qi` in the independent coordinates
//! `q` (roll theta, steer gamma). The linearization differentiates `Ec` with
//! dual numbers seeded on `q` and `q'`: the derivatives flow exactly through
//! the constraint solution, the dependent velocities, `E`, `F`, `M` and the
//! forces. A central-difference version (the thesis's method) exists only to
//! cross-check it.

use crate::canonical::CanonicalMatrices;
use crate::constraints::{constraint_matrices, dependent_velocities, solve_configuration, NewtonOptions};
use crate::eigen::{EigenError, LateralStates, LinearBicycle, SpeedMatrices, StateSpaceBicycle};
use crate::linalg::{lu_factor, lu_solve, lu_solve_dual, lu_solve_dual_narrow, solve_in_place, Scratch};
use crate::model::{CoordinateRole, MultibodyModel};
// The types the `MultibodyModel` trait names live below it; their public
// paths stay here.
use crate::linear_types::ConstraintError;
pub use crate::linear_types::{Linearization, LinearizeError, StateMatrix, WithRest};
use crate::scalar::{Dual, Scalar};
use nalgebra::{DMatrix, Matrix2};

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

/// Exact linearization (dual numbers) about upright straight running of a
/// driven-speed model, at `param` (which fixes the speed): `M`, `C`, `K` in
/// the two independent coordinates (roll, steer).
pub fn linearize<M: MultibodyModel>(param: &[f64]) -> Result<Linearization, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    if ni != 2 {
        return Err(LinearizeError::NotRollSteer { model: M::NAME, n: ni });
    }
    M::linearize_with_rest_exact(param, &[0.0; 2]).map(|(l, _)| l)
}

/// The exact linearization about upright straight running (independent
/// rates `dq0`) and, from the same evaluation, the stiffness at rest, with
/// dual numbers of width `N = 2 H`, `H` the number of independent
/// coordinates. Each generated model calls it with its own widths
/// ([`MultibodyModel::linearize_with_rest_exact`]), so only they are
/// compiled per model.
///
/// It computes what [`linearize_with_rest_general`] computes (equal to
/// rounding) but evaluates only what the upright linearization needs, in the
/// narrowest duals that carry it:
/// * the configuration by Newton in `f64`, and the dependent coordinates'
///   derivatives in `q` from one real solve (implicit function theorem);
/// * everything that depends on the configuration only (`D`, `d`, `M`,
///   `Qgrav`, the partitioning `E`) in `H`-wide duals along `q`: their
///   derivatives along `q'` vanish;
/// * one real LU factorization of `D_dep` for both eliminations, with dual
///   right-hand sides ([`lu_solve_dual`]);
/// * the velocity terms (`Qv + Qext`, `gamma`) in `f64` with their
///   symbolic Jacobian ([`MultibodyModel::upright_velocity_terms_jacobian`]), then
///   `N`-wide duals (along `q` and `q'`) by the chain rule through the
///   solved coordinates and velocities;
/// * the reduced mass matrix `E^T M E` in `f64` (only its value is used).
pub fn linearize_with_rest<M: MultibodyModel, const H: usize, const N: usize>(
    param: &[f64],
    dq0: &[f64],
) -> Result<(Linearization, DMatrix<f64>), LinearizeError> {
    let u = upright_linearization::<M, H, N>(param, dq0)?;
    let m = |x: &[[f64; H]; H]| DMatrix::from_fn(H, H, |i, j| x[i][j]);
    Ok((
        Linearization {
            mass: m(&u.mass),
            damping: m(&u.damping),
            stiffness: m(&u.stiffness),
        },
        m(&u.rest),
    ))
}

/// [`linearize_with_rest`] in fixed-size matrices: `M`, `C`, `K` and the
/// stiffness at rest, `H x H` (row-major arrays).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UprightLinearization<const H: usize> {
    pub mass: [[f64; H]; H],
    pub damping: [[f64; H]; H],
    pub stiffness: [[f64; H]; H],
    pub rest: [[f64; H]; H],
}

/// Sizes the upright linearization keeps on the stack (larger models use
/// the heap, see [`Scratch`]): coordinates, constraints, parameters.
const CAP_Q: usize = 12;
const CAP_C: usize = 12;
const CAP_P: usize = 64;

/// The computation of [`linearize_with_rest`], allocating nothing for models
/// of up to 12 coordinates, 12 constraints and 64 parameters.
pub fn upright_linearization<M: MultibodyModel, const H: usize, const N: usize>(
    param: &[f64],
    dq0: &[f64],
) -> Result<UprightLinearization<H>, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    assert!(
        ni == H && 2 * H == N,
        "dual widths are the independent coordinates and twice that"
    );
    let nq = M::nq();
    let ind = M::INDEPENDENT;
    let dep = M::DEPENDENT;
    let nh = M::HOLONOMIC.len();
    let nc = nh + M::NONHOLONOMIC.len();
    // Configuration in f64, from the closed-form upright guess.
    let mut pf = Scratch::<f64, CAP_Q>::new(nq, 0.0);
    let pf = &mut *pf;
    M::upright_configuration(param, M::INITIAL_GUESS, pf);
    if let Some(j) = pf.iter().position(|x| !x.is_finite()) {
        return Err(ConstraintError::NoUprightConfiguration {
            coordinate: M::COORDINATES[j],
        }
        .into());
    }
    for &j in ind {
        pf[j] = 0.0;
    }
    // The closed-form guess usually satisfies the constraints already: then
    // Newton has nothing to do.
    let newton = NewtonOptions::default();
    let mut res = Scratch::<f64, CAP_C>::new(nh, 0.0);
    M::holonomic_residuals(param, 0.0, pf, &mut res);
    if !(param.iter().all(|x| x.is_finite()) && res.iter().all(|r| r.abs() <= newton.tol)) {
        solve_configuration::<M, f64>(param, 0.0, pf, &newton)?;
    }
    let singular = |what: &'static str| {
        move |s: crate::linalg::Singular| ConstraintError::SingularJacobian {
            what,
            column: s.column,
            pivot: s.pivot,
            scale: s.scale,
        }
    };
    // Dependent coordinates' derivatives in q: -Cq_dep^-1 Cq_ind.
    let mut cq = Scratch::<f64, { CAP_C * CAP_Q }>::new(nh * nq, 0.0);
    let cq = &mut *cq;
    M::holonomic_jacobian(param, 0.0, pf, cq);
    let mut jd = Scratch::<f64, { CAP_C * CAP_C }>::new(nh * nh, 0.0);
    let jd = &mut *jd;
    for (r, x) in jd.iter_mut().enumerate() {
        *x = cq[(r / nh) * nq + dep[r % nh]];
    }
    let nd = nq - ni;
    let mut perm = Scratch::<usize, CAP_Q>::new(nd.max(nh), 0);
    let perm = &mut *perm;
    lu_factor(jd, nh, &mut perm[..nh]).map_err(singular("holonomic constraints"))?;
    let mut p = Scratch::<Dual<H>, CAP_Q>::new(nq, Dual::zero());
    let p = &mut *p;
    for (x, &v) in p.iter_mut().zip(pf.iter()) {
        *x = Dual::cst(v);
    }
    let mut col = Scratch::<f64, CAP_C>::new(nh, 0.0);
    let col = &mut *col;
    for (k, &j) in ind.iter().enumerate() {
        p[j] = Dual::variable(0.0, k);
        for (i, c) in col.iter_mut().enumerate() {
            *c = -cq[i * nq + j];
        }
        lu_solve(jd, nh, &perm[..nh], col, 1);
        for (r, &jj) in dep.iter().enumerate() {
            p[jj].eps[k] = col[r];
        }
    }
    let mut ph = Scratch::<Dual<H>, CAP_P>::new(param.len(), Dual::zero());
    let ph = &mut *ph;
    for (x, &v) in ph.iter_mut().zip(param) {
        *x = Dual::cst(v);
    }
    let th = Dual::<H>::zero();
    // Coordinate partitioning (eq. 40-45) with one real factorization:
    // D = [Cq; B] and d = [-Ct; 0] (see `constraint_matrices`).
    let mut d = Scratch::<Dual<H>, { CAP_C * CAP_Q }>::new(nc * nq, Dual::zero());
    let d = &mut *d;
    M::holonomic_jacobian(ph, th, p, &mut d[..nh * nq]);
    M::nonholonomic_matrix(ph, th, p, &mut d[nh * nq..]);
    let mut ct = Scratch::<Dual<H>, CAP_C>::new(nh, Dual::zero());
    M::holonomic_time_derivative(ph, th, p, &mut ct);
    let mut depv = Scratch::<usize, CAP_Q>::new(nd, 0);
    let depv = &mut *depv;
    for (slot, j) in depv.iter_mut().zip((0..nq).filter(|j| !ind.contains(j))) {
        *slot = j;
    }
    let w = ni + 1;
    let mut a = Scratch::<Dual<H>, { CAP_C * CAP_C }>::new(nd * nd, Dual::zero());
    let a = &mut *a;
    let mut rhs = Scratch::<Dual<H>, { CAP_C * 4 }>::new(nd * w, Dual::zero());
    let rhs = &mut *rhs;
    for i in 0..nc {
        for (k, &j) in depv.iter().enumerate() {
            a[i * nd + k] = d[i * nq + j];
        }
        for (k, &j) in ind.iter().enumerate() {
            rhs[i * w + k] = d[i * nq + j];
        }
        rhs[i * w + ni] = if i < nh { -ct[i] } else { Dual::zero() };
    }
    let mut lu = Scratch::<f64, { CAP_C * CAP_C }>::new(nd * nd, 0.0);
    let lu = &mut *lu;
    for (l, x) in lu.iter_mut().zip(a.iter()) {
        *l = x.re;
    }
    lu_factor(lu, nd, &mut perm[..nd]).map_err(singular("coordinate partitioning"))?;
    // Checked where the general path checks it: after the partitioning.
    check_physical_branch::<M>(param, pf)?;
    let perm = &perm[..nd];
    lu_solve_dual(lu, nd, perm, a, rhs, w);
    // E = [I; -Ddep^-1 Dind] (configuration only).
    let mut e = Scratch::<Dual<H>, { CAP_Q * 3 }>::new(nq * ni, Dual::zero());
    let e = &mut *e;
    for (k, &j) in ind.iter().enumerate() {
        e[j * ni + k] = Dual::one();
    }
    for (r, &j) in depv.iter().enumerate() {
        for k in 0..ni {
            e[j * ni + k] = -rhs[r * w + k];
        }
    }
    // Velocities, now along q and q'.
    let mut dp = Scratch::<Dual<N>, CAP_Q>::new(nq, Dual::zero());
    let dp = &mut *dp;
    for (k, &j) in ind.iter().enumerate() {
        dp[j] = Dual::variable(dq0[k], ni + k);
    }
    for (r, &j) in depv.iter().enumerate() {
        let mut v = widen(rhs[r * w + ni]);
        for k in 0..ni {
            v -= widen(rhs[r * w + k]) * dp[ind[k]];
        }
        dp[j] = v;
    }
    // The velocity terms (Qv + Qext, then gamma) from their symbolic
    // Jacobian in f64, by the chain rule along the derivatives of the
    // coordinates (independent and dependent: the others stay put) and of
    // every velocity: far cheaper than evaluating them in N-wide duals.
    let nm = ind.len() + dep.len();
    let cols = 1 + nm + nq;
    let mut dpf = Scratch::<f64, CAP_Q>::new(nq, 0.0);
    let dpf = &mut *dpf;
    for (x, v) in dpf.iter_mut().zip(dp.iter()) {
        *x = v.re;
    }
    let mut jac = Scratch::<f64, { (CAP_Q + CAP_C) * (1 + 2 * CAP_Q) }>::new((nq + nc) * cols, 0.0);
    let jac = &mut *jac;
    M::upright_velocity_terms_jacobian(param, 0.0, pf, dpf, jac);
    let mut terms = Scratch::<Dual<N>, { CAP_Q + CAP_C }>::new(nq + nc, Dual::zero());
    let terms = &mut *terms;
    for (v, row) in terms.iter_mut().zip(jac.chunks_exact(cols)) {
        v.re = row[0];
        // (Most entries vanish: skipping them changes no value.)
        for (&c, &j) in row[1..=nm].iter().zip(ind.iter().chain(dep)) {
            if c != 0.0 {
                for k in 0..H {
                    v.eps[k] += c * p[j].eps[k];
                }
            }
        }
        for (&c, dpj) in row[1 + nm..].iter().zip(dp.iter()) {
            if c != 0.0 {
                for k in 0..N {
                    v.eps[k] += c * dpj.eps[k];
                }
            }
        }
    }
    let (forces, gamma) = terms.split_at_mut(nq);
    // F = [0; -Ddep^-1 gamma].
    lu_solve_dual_narrow(lu, nd, perm, a, gamma, 1);
    let mut f = Scratch::<Dual<N>, CAP_Q>::new(nq, Dual::zero());
    let f = &mut *f;
    for (r, &j) in depv.iter().enumerate() {
        f[j] = -gamma[r];
    }
    let mut mass = Scratch::<Dual<H>, { CAP_Q * CAP_Q }>::new(nq * nq, Dual::zero());
    let mass = &mut *mass;
    M::mass_matrix(ph, p, mass);
    let mut qg = Scratch::<Dual<H>, CAP_Q>::new(nq, Dual::zero());
    let qg = &mut *qg;
    M::gravity_forces(ph, p, qg);
    // Forces at rest (every velocity zero), for the stiffness at rest:
    // along q only.
    let mut qe_rest = Scratch::<Dual<H>, CAP_Q>::new(nq, Dual::zero());
    let qe_rest = &mut *qe_rest;
    let rest_rates = Scratch::<Dual<H>, CAP_Q>::new(nq, Dual::zero());
    M::applied_forces(ph, th, p, &rest_rates, qe_rest);
    // Qi = E^T (Qv + Qgrav + Qext - M F) (eq. 46-47); Ec = Mi q'' - Qi at
    // q'' = 0, so its derivatives are -Qi's.
    let mut qi = [Dual::<N>::zero(); H];
    let mut qi_rest = [Dual::<H>::zero(); H];
    for r in 0..nq {
        let mut s = forces[r] + widen(qg[r]);
        // F vanishes on the independent rows.
        for &c in depv.iter() {
            s -= widen(mass[r * nq + c]) * f[c];
        }
        let s_rest = qg[r] + qe_rest[r];
        for k in 0..ni {
            qi[k] += widen(e[r * ni + k]) * s;
            qi_rest[k] += e[r * ni + k] * s_rest;
        }
    }
    let mut u = UprightLinearization {
        mass: [[0.0; H]; H],
        damping: [[0.0; H]; H],
        stiffness: [[0.0; H]; H],
        rest: [[0.0; H]; H],
    };
    // Mi = E^T M E, its value only.
    for k in 0..ni {
        for b in 0..ni {
            let mut m = 0.0;
            for r in 0..nq {
                let mut me = 0.0;
                for c in 0..nq {
                    me += mass[r * nq + c].re * e[c * ni + b].re;
                }
                m += e[r * ni + k].re * me;
            }
            u.mass[k][b] = m;
        }
        for b in 0..ni {
            u.stiffness[k][b] = -qi[k].eps[b];
            u.damping[k][b] = -qi[k].eps[ni + b];
            u.rest[k][b] = -qi_rest[k].eps[b];
        }
    }
    Ok(u)
}

/// A dual along `H` directions as one along `N >= H` (the first `H`).
#[inline(always)]
fn widen<const H: usize, const N: usize>(x: Dual<H>) -> Dual<N> {
    let mut eps = [0.0; N];
    eps[..H].copy_from_slice(&x.eps);
    Dual { re: x.re, eps }
}

/// The general path of [`linearize_with_rest`]: the whole of
/// [`reduced_system`] in dual numbers (Newton's last step, both eliminations
/// and every generated function). Kept as the reference the fast path is
/// tested against.
pub fn linearize_with_rest_general<M: MultibodyModel, const N: usize>(
    param: &[f64],
    dq0: &[f64],
) -> Result<(Linearization, DMatrix<f64>), LinearizeError> {
    let ni = M::INDEPENDENT.len();
    assert_eq!(2 * ni, N, "dual width is twice the independent coordinates");
    let pd: Vec<Dual<N>> = param.iter().map(|&x| Dual::cst(x)).collect();
    let q: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(0.0, k)).collect();
    let dq: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(dq0[k], ni + k)).collect();
    let ddq = vec![Dual::<N>::zero(); ni];
    let sys = reduced_system::<M, Dual<N>>(&pd, Dual::zero(), &q, &dq, &ddq)?;
    check_physical_branch::<M>(param, &sys.p.iter().map(|x| x.re).collect::<Vec<_>>())?;
    let (ec, mi) = (sys.ec, sys.mi);
    Ok((
        Linearization {
            mass: DMatrix::from_fn(ni, ni, |i, j| mi[i * ni + j].re),
            stiffness: DMatrix::from_fn(ni, ni, |i, j| ec[i].eps[j]),
            damping: DMatrix::from_fn(ni, ni, |i, j| ec[i].eps[ni + j]),
        },
        DMatrix::from_fn(ni, ni, |i, j| sys.ec_rest[i].eps[j]),
    ))
}

/// Check that a solved upright configuration is the physical one: every
/// dependent coordinate equals the model's closed-form upright value
/// ([`MultibodyModel::upright_configuration`]) to 1e-8 rad. Another root of
/// the constraints (a flipped frame, the top of the rim) gives the matrices
/// of another mechanism, so it is refused.
pub fn check_physical_branch<M: MultibodyModel>(param: &[f64], p: &[f64]) -> Result<(), LinearizeError> {
    let mut up = Scratch::<f64, CAP_Q>::new(M::nq(), 0.0);
    M::upright_configuration(param, p, &mut up);
    for &j in M::DEPENDENT {
        let d = (p[j] - up[j] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
        if up[j].is_finite() && !(d.abs() <= 1e-8) {
            return Err(LinearizeError::OffBranch {
                coordinate: M::COORDINATES[j],
                value: p[j],
                expected: up[j],
                what: "the model's closed-form upright configuration",
            });
        }
    }
    Ok(())
}

/// Positions, within the independent coordinates, of roll and steer: all
/// independent coordinates except the one that carries the forward speed.
pub fn lateral_indices<M: MultibodyModel>() -> Vec<usize> {
    (0..M::INDEPENDENT.len())
        .filter(|&k| Some(M::INDEPENDENT[k]) != M::SPEED_COORDINATE)
        .collect()
}

/// Exact linearization about upright straight running at forward speed
/// `speed` (m/s), over all independent coordinates, for any model: a driven
/// model gets the speed through its speed parameter, a free-speed model
/// through the rate of its speed coordinate (found from the model's own
/// forward-speed expression). `param` is the full parameter vector (a driven
/// model's speed entry is overwritten).
pub fn linearize_at_speed<M: MultibodyModel>(param: &[f64], speed: f64) -> Result<Linearization, LinearizeError> {
    if !M::STATES.is_empty() {
        return Err(LinearizeError::HasStates { model: M::NAME });
    }
    let (param, dq0) = speed_setup::<M>(param, speed)?;
    M::linearize_with_rest_exact(&param, &dq0).map(|(l, _)| l)
}

/// A linear state-space model `x' = A x` about upright straight running.
#[derive(Clone, Debug)]
pub struct StateSpace {
    /// State names: the independent coordinates, their rates (`d` + name),
    /// then the model's extra states.
    pub names: Vec<String>,
    pub a: DMatrix<f64>,
}

/// Exact linearization of a model with extra first-order states (or any
/// model) at forward speed `speed`: `x = [q, q', z]` with `q` the
/// independent coordinates and `z` the extra states (at zero, their steady
/// value in straight running). `q''` comes from the reduced equations, `z'`
/// from the model's state rates evaluated with the full velocities.
pub fn state_space_at_speed<M: MultibodyModel>(param: &[f64], speed: f64) -> Result<StateSpace, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let nz = M::STATES.len();
    let (param, dq0) = speed_setup::<M>(param, speed)?;
    let _ = (ni, nz);
    let a = M::state_space_exact(&param, &dq0)?;
    let mut names: Vec<String> = M::INDEPENDENT.iter().map(|&j| M::COORDINATES[j].to_string()).collect();
    names.extend(M::INDEPENDENT.iter().map(|&j| format!("d{}", M::COORDINATES[j])));
    names.extend(M::STATES.iter().map(|s| s.to_string()));
    Ok(StateSpace { names, a })
}

/// The state matrix of [`state_space_at_speed`] with dual numbers of width
/// `N = 2 x` independent coordinates `+` extra states (called by each
/// generated model with its own `N`).
pub fn state_space_dual<M: MultibodyModel, const N: usize>(
    param: &[f64],
    dq0: &[f64],
) -> Result<DMatrix<f64>, LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let nz = M::STATES.len();
    let np = M::PARAMETERS.len();
    let mut pd: Vec<Dual<N>> = param.iter().map(|&x| Dual::cst(x)).collect();
    for k in 0..nz {
        pd[np + k] = Dual::variable(param[np + k], 2 * ni + k);
    }
    let q: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(0.0, k)).collect();
    let dq: Vec<Dual<N>> = (0..ni).map(|k| Dual::variable(dq0[k], ni + k)).collect();
    let sys = reduced_system::<M, Dual<N>>(&pd, Dual::zero(), &q, &dq, &vec![Dual::zero(); ni])?;
    // q'' = Mi^-1 Qi = -Mi^-1 Ec(q'' = 0).
    let mut mi = sys.mi.clone();
    let mut rhs: Vec<Dual<N>> = sys.ec.iter().map(|&e| -e).collect();
    solve_in_place(&mut mi, ni, &mut rhs, 1).map_err(|_| LinearizeError::SingularMass)?;
    let mut zdot = vec![Dual::<N>::zero(); nz];
    M::state_rates(&pd, Dual::zero(), &sys.p, &sys.dp, &mut zdot);
    let n = 2 * ni + nz;
    let mut a = DMatrix::zeros(n, n);
    for k in 0..ni {
        a[(k, ni + k)] = 1.0;
    }
    for r in 0..ni {
        for c in 0..n {
            a[(ni + r, c)] = rhs[r].eps[c];
        }
    }
    for r in 0..nz {
        for c in 0..n {
            a[(2 * ni + r, c)] = zdot[r].eps[c];
        }
    }
    Ok(a)
}

/// The parameter vector and independent rates for steady running at `speed`.
fn speed_setup<M: MultibodyModel>(param: &[f64], speed: f64) -> Result<(Vec<f64>, Vec<f64>), LinearizeError> {
    let mut param = param.to_vec();
    let mut dq0 = vec![0.0; M::INDEPENDENT.len()];
    speed_rates::<M>(&mut param, speed, &mut dq0)?;
    Ok((param, dq0))
}

/// Set `param` and the independent rates `dq0` (one per independent
/// coordinate, zero on entry) for steady running at `speed`.
fn speed_rates<M: MultibodyModel>(param: &mut [f64], speed: f64, dq0: &mut [f64]) -> Result<(), LinearizeError> {
    if let Some(k) = M::FORWARD_SPEED_PARAMETER {
        param[k] = speed;
    } else if let Some(c) = M::SPEED_COORDINATE {
        // Forward speed is linear in the rates: its slope in the speed
        // coordinate's rate, at the upright configuration.
        let mut p: Vec<f64> = M::INITIAL_GUESS.to_vec();
        for &j in M::INDEPENDENT {
            p[j] = 0.0;
        }
        solve_configuration::<M, f64>(param, 0.0, &mut p, &NewtonOptions::default())?;
        let mut unit = vec![0.0; M::nq()];
        unit[c] = 1.0;
        let slope = M::forward_speed(param, &p, &unit);
        if !(slope.abs() > 0.0) || !slope.is_finite() {
            return Err(LinearizeError::NoForwardSpeed { model: M::NAME });
        }
        let k = M::INDEPENDENT
            .iter()
            .position(|&j| j == c)
            .expect("the speed coordinate is independent");
        dq0[k] = speed / slope;
    } else if speed != 0.0 {
        return Err(LinearizeError::NoForwardSpeed { model: M::NAME });
    }
    Ok(())
}

/// The roll-steer block of a linearization (see [`lateral_indices`]).
pub fn lateral_block<M: MultibodyModel>(lin: &Linearization) -> Linearization {
    let idx = lateral_indices::<M>();
    let n = idx.len();
    let pick = |m: &DMatrix<f64>| DMatrix::from_fn(n, n, |i, j| m[(idx[i], idx[j])]);
    Linearization {
        mass: pick(&lin.mass),
        damping: pick(&lin.damping),
        stiffness: pick(&lin.stiffness),
    }
}

/// The thesis's finite-difference linearization (forward differences, step
/// `h`, `CalculaMatricesMCK.m`), kept to cross-check [`linearize`].
pub fn linearize_finite_difference<M: MultibodyModel>(param: &[f64], h: f64) -> Result<Linearization, LinearizeError> {
    let eval =
        |q: [f64; 2], dq: [f64; 2], ddq: [f64; 2]| reduced_equations::<M, f64>(param, 0.0, &q, &dq, &ddq).map(|r| r.0);
    let e0 = eval([0.0; 2], [0.0; 2], [0.0; 2])?;
    let mut lin = Linearization {
        mass: DMatrix::zeros(2, 2),
        damping: DMatrix::zeros(2, 2),
        stiffness: DMatrix::zeros(2, 2),
    };
    for j in 0..2 {
        let mut u = [0.0; 2];
        u[j] = h;
        let ek = eval(u, [0.0; 2], [0.0; 2])?;
        let ec = eval([0.0; 2], u, [0.0; 2])?;
        let em = eval([0.0; 2], [0.0; 2], u)?;
        for i in 0..2 {
            lin.stiffness[(i, j)] = (ek[i] - e0[i]) / h;
            lin.damping[(i, j)] = (ec[i] - e0[i]) / h;
            lin.mass[(i, j)] = (em[i] - e0[i]) / h;
        }
    }
    Ok(lin)
}

/// Fill a model's parameter vector by name from `lookup`; the forward-speed
/// parameter of a driven model gets `speed`, and a parameter `lookup` does
/// not know takes the model's default (effect parameters: absent). A model
/// with extra states gets them appended, at zero (see
/// [`MultibodyModel::STATES`]).
pub fn parameter_vector<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
    speed: f64,
) -> Result<Vec<f64>, LinearizeError> {
    let mut v: Vec<f64> = M::PARAMETER_INFO
        .iter()
        .enumerate()
        .map(|(i, info)| {
            if Some(i) == M::FORWARD_SPEED_PARAMETER {
                Some(speed)
            } else {
                lookup(info.name).or(info.default)
            }
            .ok_or(LinearizeError::NoValue {
                model: M::NAME,
                name: info.name,
                doc: info.doc,
            })
        })
        .collect::<Result<_, _>>()?;
    v.extend(M::STATES.iter().map(|_| 0.0));
    Ok(v)
}

/// Canonical matrices of Meijaard et al. (2007) from a generated model:
/// `M0 = M`, `C1 = C(v=1)`, `K0 = K(v=0)/g`, `K2 = K(v=1) - K(v=0)`, exact
/// because the reduced equations are quadratic in the forward speed. The
/// thesis's steer angle gamma is minus the benchmark's delta, so the
/// off-diagonal entries change sign.
///
/// One dual-number linearization at speed 1 gives `M`, `C(1)`, `K(1)` and,
/// from the same evaluation, `K(0)` (gravity and forces at rest: every
/// velocity vanishes at zero speed). Works for driven and free-speed models
/// alike (the roll-steer block); the gravity parameter is the one the model
/// declares.
pub fn canonical_matrices<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
) -> Result<CanonicalMatrices, LinearizeError> {
    canonical_matrices_by::<M>(lookup, M::linearize_with_rest_exact)
}

/// [`canonical_matrices`] through the general path
/// ([`linearize_with_rest_general`] with dual width `N`), the method before
/// the fast upright path; kept for the bench's comparison.
pub fn canonical_matrices_general<M: MultibodyModel, const N: usize>(
    lookup: impl Fn(&str) -> Option<f64>,
) -> Result<CanonicalMatrices, LinearizeError> {
    canonical_matrices_by::<M>(lookup, linearize_with_rest_general::<M, N>)
}

fn canonical_matrices_by<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
    linearize: impl Fn(&[f64], &[f64]) -> Result<WithRest, LinearizeError>,
) -> Result<CanonicalMatrices, LinearizeError> {
    // At speed 1 directly (a driven model's speed parameter).
    let mut param = parameter_vector::<M>(&lookup, 1.0)?;
    let g = M::GRAVITY_PARAMETER
        .map(|k| param[k])
        .ok_or(LinearizeError::MissingParameter {
            model: M::NAME,
            name: "gravity".into(),
        })?;
    if !M::STATES.is_empty() {
        return Err(LinearizeError::HasStates { model: M::NAME });
    }
    let mut dq1 = Scratch::<f64, 8>::new(M::INDEPENDENT.len(), 0.0);
    speed_rates::<M>(&mut param, 1.0, &mut dq1)?;
    let (l1, rest) = linearize(&param, &dq1)?;
    // Roll and steer (see `lateral_indices`), without allocating.
    let mut idx = [0; 2];
    let mut n = 0;
    for k in (0..M::INDEPENDENT.len()).filter(|&k| Some(M::INDEPENDENT[k]) != M::SPEED_COORDINATE) {
        if n < 2 {
            idx[n] = k;
        }
        n += 1;
    }
    if n != 2 {
        return Err(LinearizeError::NotRollSteer { model: M::NAME, n });
    }
    let pick = |m: &DMatrix<f64>| Matrix2::from_fn(|i, j| m[(idx[i], idx[j])]);
    let flip = |m: Matrix2<f64>| Matrix2::new(m[(0, 0)], -m[(0, 1)], -m[(1, 0)], m[(1, 1)]);
    let k0 = pick(&rest);
    Ok(CanonicalMatrices {
        m0: flip(pick(&l1.mass)),
        c1: flip(pick(&l1.damping)),
        k0: flip(k0) / g,
        k2: flip(pick(&l1.stiffness) - k0),
        g,
    })
}

/// Stiffness of the roll-steer linearization at zero forward speed, where
/// only gravity and forces at rest act (every velocity vanishes): the
/// derivative of `-E^T (Qgrav + Qext(p, 0))` in roll and steer.
pub fn static_stiffness<M: MultibodyModel>(param: &[f64]) -> Result<DMatrix<f64>, LinearizeError> {
    let (p0, dq0) = speed_setup::<M>(param, 0.0)?;
    let (_, rest) = M::linearize_with_rest_exact(&p0, &dq0)?;
    let idx = lateral_indices::<M>();
    Ok(DMatrix::from_fn(2, 2, |i, j| rest[(idx[i], idx[j])]))
}

/// Canonical matrices by two full linearizations (at `V = 0` and `V = 1`),
/// the method used before issue 10, point 10; kept for the bench's
/// comparison and as a cross-check of [`canonical_matrices`].
///
/// Canonical matrices of Meijaard et al. (2007) from a generated model:
/// `M0 = M`, `C1 = C(v=1)`, `K0 = K(v=0)/g`, `K2 = K(v=1) - K(v=0)`, exact
/// because the reduced equations are quadratic in the forward speed. The
/// thesis's steer angle gamma is minus the benchmark's delta, so the
/// off-diagonal entries change sign.
///
/// Works for driven and free-speed models alike (the roll-steer block of
/// [`linearize_at_speed`]); the gravity parameter is the one the model
/// declares.
pub fn canonical_matrices_two_speeds<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
) -> Result<CanonicalMatrices, LinearizeError> {
    let param = parameter_vector::<M>(&lookup, 0.0)?;
    let g = M::GRAVITY_PARAMETER
        .map(|k| param[k])
        .ok_or(LinearizeError::MissingParameter {
            model: M::NAME,
            name: "gravity".into(),
        })?;
    let l0 = lateral_block::<M>(&linearize_at_speed::<M>(&param, 0.0)?);
    let l1 = lateral_block::<M>(&linearize_at_speed::<M>(&param, 1.0)?);
    let flip = |m: &DMatrix<f64>| Matrix2::new(m[(0, 0)], -m[(0, 1)], -m[(1, 0)], m[(1, 1)]);
    Ok(CanonicalMatrices {
        m0: flip(&l0.mass),
        c1: flip(&l1.damping),
        k0: flip(&l0.stiffness) / g,
        k2: flip(&(&l1.stiffness - &l0.stiffness)),
        g,
    })
}

/// A generated model with its parameters, as a [`LinearBicycle`]: its
/// roll-steer equations at each speed come from the exact linearization at
/// that speed ([`linearize_at_speed`]), in the benchmark's sign convention
/// (the steer angle of the thesis axes is minus the benchmark's, so the
/// off-diagonal entries change sign). Any effect enters: damping,
/// friction's describing function, a speed-scheduled controller.
///
/// A model with extra first-order states (tyre forces) has no second-order
/// roll-steer form: it gives its lateral first-order equations instead
/// ([`StateSpaceBicycle`], from [`state_space_at_speed`]), which the eigen
/// analyses use themselves.
pub struct LinearModel<M: MultibodyModel> {
    param: Vec<f64>,
    /// Positions of roll and steer within the independent coordinates.
    roll_steer: [usize; 2],
    /// For a model with extra states: which states of
    /// [`state_space_at_speed`] are lateral, and how many eigenvalues are
    /// neutral (see [`lateral_states_of`]).
    lateral: Option<(Vec<usize>, usize)>,
    _model: std::marker::PhantomData<M>,
}

impl<M: MultibodyModel> LinearModel<M> {
    /// The model with its parameters filled from `lookup` (missing ones:
    /// the model's defaults).
    pub fn new(lookup: impl Fn(&str) -> Option<f64>) -> Result<Self, LinearizeError> {
        let param = parameter_vector::<M>(&lookup, 0.0)?;
        let position = |role| -> Result<usize, LinearizeError> {
            let j = M::require_coordinate(role, "the linear roll-steer analysis")?;
            M::INDEPENDENT
                .iter()
                .position(|&i| i == j)
                .ok_or(LinearizeError::NotRollSteer {
                    model: M::NAME,
                    n: M::INDEPENDENT.len(),
                })
        };
        let roll_steer = [position(CoordinateRole::Roll)?, position(CoordinateRole::Steer)?];
        // A second-order roll-steer form exists only when roll and steer
        // are all the lateral freedom there is: extra states (tyre forces)
        // or an extra coordinate (a rider's lean) need the state space.
        let lateral = if M::STATES.is_empty() && extra_coordinates::<M>().is_empty() {
            None
        } else {
            Some(lateral_states_of::<M>(&param, roll_steer)?)
        };
        Ok(LinearModel {
            param,
            roll_steer,
            lateral,
            _model: std::marker::PhantomData,
        })
    }
}

/// Positions within the independent coordinates of those the rolling
/// bicycle lacks ([`crate::model::added_coordinates`]).
fn extra_coordinates<M: MultibodyModel>() -> Vec<usize> {
    crate::model::added_coordinates(M::INDEPENDENT, M::COORDINATE_ROLES)
}

/// The lateral states of a model with extra states: every state of
/// [`state_space_at_speed`] but the speed coordinate and its rate (the
/// longitudinal motion, uncoupled from the lateral at upright straight
/// running) and the coordinates nothing depends on (lateral position, yaw,
/// wheel rotations: their columns of `A` vanish, each adds a zero
/// eigenvalue, and dropping them leaves the other eigenvalues exact since
/// `A` is block triangular in them). A column is structurally zero when it
/// is exactly zero at two unrelated speeds; dropping a state can empty
/// another's column (yaw feeds only the lateral position), hence the loop.
///
/// Also the number of neutral eigenvalues that remain (the heading when the
/// yaw stays, as with tyre slip: a zero eigenvalue at every speed), counted
/// as those below `1e-10 max |A_ij|` at both probe speeds (their rounding is
/// about `1e-16 max |A_ij|`).
fn lateral_states_of<M: MultibodyModel>(
    param: &[f64],
    roll_steer: [usize; 2],
) -> Result<(Vec<usize>, usize), LinearizeError> {
    let ni = M::INDEPENDENT.len();
    let probes = [
        state_space_at_speed::<M>(param, 1.3)?,
        state_space_at_speed::<M>(param, 4.7)?,
    ];
    let n = probes[0].a.nrows();
    // The speed coordinate's position and rate (states k and ni + k).
    let speed = M::SPEED_COORDINATE.and_then(|c| M::INDEPENDENT.iter().position(|&j| j == c));
    let mut keep: Vec<usize> = (0..n)
        .filter(|&i| speed.is_none_or(|k| i != k && i != ni + k))
        .collect();
    let essential = [roll_steer[0], roll_steer[1], ni + roll_steer[0], ni + roll_steer[1]];
    loop {
        let before = keep.len();
        let current = keep.clone();
        keep.retain(|&j| {
            essential.contains(&j)
                || probes
                    .iter()
                    .any(|p| current.iter().any(|&i| i != j && p.a[(i, j)] != 0.0) || p.a[(j, j)] != 0.0)
        });
        if keep.len() == before {
            break;
        }
    }
    let neutral = probes
        .iter()
        .map(|p| {
            let a = DMatrix::from_fn(keep.len(), keep.len(), |i, j| p.a[(keep[i], keep[j])]);
            let tol = 1e-10 * a.abs().max().max(1.0);
            a.complex_eigenvalues().iter().filter(|z| z.norm() <= tol).count()
        })
        .min()
        .unwrap_or(0);
    Ok((keep, neutral))
}

impl<M: MultibodyModel> StateSpaceBicycle for LinearModel<M> {
    fn lateral_states(&self, v: f64) -> Result<LateralStates, EigenError> {
        let (keep, neutral) = match &self.lateral {
            Some((k, n)) => (k.as_slice(), *n),
            None => (&[][..], 0),
        };
        let ss = state_space_at_speed::<M>(&self.param, v).map_err(|e| EigenError::Linearization {
            speed: v,
            what: e.to_string(),
        })?;
        let ni = M::INDEPENDENT.len();
        let at = |j: usize| keep.iter().position(|&k| k == j).unwrap_or(usize::MAX);
        let [r, s] = self.roll_steer;
        Ok(LateralStates {
            names: keep.iter().map(|&k| ss.names[k].clone()).collect(),
            a: DMatrix::from_fn(keep.len(), keep.len(), |i, j| ss.a[(keep[i], keep[j])]),
            roll_steer: [at(r), at(s), at(ni + r), at(ni + s)],
            // The generated models use the thesis's axes (see `at_speed`).
            steer_sign: -1.0,
            // Extra: the first-order states and the coordinates (and
            // their rates) the rolling bicycle lacks.
            extra: {
                let coords = extra_coordinates::<M>();
                (0..keep.len())
                    .filter(|&i| keep[i] >= 2 * ni || coords.iter().any(|&k| keep[i] == k || keep[i] == ni + k))
                    .collect()
            },
            neutral,
        })
    }
}

impl<M: MultibodyModel> LinearBicycle for LinearModel<M> {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        if self.lateral.is_some() {
            return Err(EigenError::Linearization {
                speed: v,
                what: LinearizeError::HasStates { model: M::NAME }.to_string(),
            });
        }
        let lin = linearize_at_speed::<M>(&self.param, v).map_err(|e| EigenError::Linearization {
            speed: v,
            what: e.to_string(),
        })?;
        let [r, s] = self.roll_steer;
        let pick = |m: &DMatrix<f64>| Matrix2::new(m[(r, r)], -m[(r, s)], -m[(s, r)], m[(s, s)]);
        Ok(SpeedMatrices {
            mass: pick(&lin.mass),
            damping: pick(&lin.damping),
            stiffness: pick(&lin.stiffness),
        })
    }
    fn first_order(&self) -> Option<&dyn StateSpaceBicycle> {
        self.lateral.is_some().then_some(self as &dyn StateSpaceBicycle)
    }
}
