//! The exact linearization about upright straight running (thesis section
//! 3.9, eq. 48-50): `M`, `C`, `K` in the independent coordinates and the
//! stiffness at rest, by the allocation-free fast path each generated model
//! calls ([`linearize_with_rest`], [`upright_linearization`]) and by the
//! general path through the whole reduced system in dual numbers
//! ([`linearize_with_rest_general`]), kept as its reference; and the check
//! that the solved configuration is the physical one.
//!
//! Apart because the fast path is the longest and most delicate computation
//! of the linearization (stack scratch sizes, dual widths, the chain rule
//! through the solved coordinates); the linearization at a speed and the
//! canonical matrices reach it through the model
//! (`MultibodyModel::linearize_with_rest_exact`).

use super::reduced::reduced_system;
use crate::constraints::{solve_configuration, NewtonOptions};
use crate::linalg::{lu_factor, lu_solve, lu_solve_dual, lu_solve_dual_narrow, Scratch};
use crate::linear_types::{ConstraintError, Linearization, LinearizeError};
use crate::model::MultibodyModel;
use crate::scalar::{Dual, Scalar};
use nalgebra::DMatrix;

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
