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
use crate::constraints::{
    constraint_matrices, dependent_velocities, solve_configuration, ConstraintError, NewtonOptions,
};
use crate::linalg::solve_in_place;
use crate::model::MultibodyModel;
use crate::scalar::{Dual, Scalar};
use nalgebra::{DMatrix, Matrix2};
use thiserror::Error;

/// Linearization failures.
#[derive(Clone, Debug, Error, PartialEq)]
pub enum LinearizeError {
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
    #[error("model `{model}` has no parameter `{name}`")]
    MissingParameter { model: &'static str, name: String },
    #[error("the canonical form needs exactly 2 independent coordinates (roll, steer), model `{model}` has {n}")]
    NotRollSteer { model: &'static str, n: usize },
    #[error("the reduced mass matrix is singular")]
    SingularMass,
    /// The constraint solver converged to a root that is not the physical
    /// upright configuration (issue 10, point 1): refusing is better than
    /// returning the matrices of another bicycle.
    #[error("the constraint solution is not the physical upright bicycle: {coordinate} = {value:.6} rad, but the geometry gives {expected:.6} rad ({what}); refusing rather than returning the matrices of another root")]
    OffBranch {
        coordinate: &'static str,
        value: f64,
        expected: f64,
        what: &'static str,
    },
    /// A wheel of zero radius (a skate) that has a spin inertia: its spin
    /// rate, and so its gyroscopic moment, would be infinite.
    #[error("the {wheel} has zero radius ({radius_symbol} = 0) but a non-zero spin inertia ({inertia_symbol} = {inertia}): a skate wheel must have zero spin inertia")]
    SkateWithSpinInertia {
        wheel: &'static str,
        radius_symbol: &'static str,
        inertia_symbol: &'static str,
        inertia: f64,
    },
    /// The parameters could not be converted for a derived computation.
    #[error("{0}")]
    Parameters(String),
    /// The zero-radius limit could not be taken reliably (the matrices are
    /// not the quadratic polynomial in the radius that the closed form says).
    #[error("the zero-radius limit is not reliable here (departure from a quadratic in the radius: {departure:.3e}, relative to {scale:.3e})")]
    ZeroRadiusLimit { departure: f64, scale: f64 },
}

/// Evaluate the reduced equations `Ec = Mi q'' - Qi` (thesis `EcMov.m`) at
/// independent coordinates `q`, rates `dq`, accelerations `ddq`, with the
/// ignorable coordinates at their initial guesses and time `t`. Returns
/// `(Ec, Mi)` (`Mi` row-major `nind x nind`).
///
/// The constraint solver starts from the physical upright configuration
/// ([`upright_guess`]), so the solution is the root with the front contact at
/// the lowest point of the rim and the front wheel ahead of the rear one.
pub fn reduced_equations<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    q: &[T],
    dq: &[T],
    ddq: &[T],
) -> Result<(Vec<T>, Vec<T>), ConstraintError> {
    let paramf: Vec<f64> = param.iter().map(|x| x.re()).collect();
    let guess = upright_guess::<M>(&paramf)?;
    reduced_equations_from::<M, T>(param, t, &guess, q, dq, ddq).map(|r| (r.ec, r.mi))
}

/// Physical upright configuration of a bicycle model with the thesis's
/// coordinates (frame pitch `beta`, rim angle `xi` of the front contact) and
/// parameters (`Rt`, `Rd`, `x4`, `z4`, `x5`, `z5`): every coordinate at
/// [`MultibodyModel::INITIAL_GUESS`] except
///
/// * `beta`, the root of `Rt - sin(b) (x4 + x5) + cos(b) (z4 + z5) = Rd` with
///   the front wheel centre ahead of the rear one (the same root as
///   `ThesisParameters::frame_pitch`): with `P = x4 + x5`, `Q = z4 + z5`,
///   `R = hypot(P, Q)`, `beta = acos((Rd - Rt) / R) - atan2(P, Q)`;
/// * `xi = pi/2 - beta - eps`, which puts the front contact at the lowest
///   point of the rim (its height along the rim is `-Rd sin(xi + beta + eps)`
///   relative to the wheel centre).
///
/// Models without these names get their initial guess unchanged. Error
/// [`ConstraintError::NoGroundContact`] when `|Rd - Rt| >= R`.
pub fn upright_guess<M: MultibodyModel>(param: &[f64]) -> Result<Vec<f64>, ConstraintError> {
    let mut p = M::INITIAL_GUESS.to_vec();
    if let Some((beta, xi)) = upright_pitch_and_rim_angle::<M>(param, &p)? {
        p[M::coordinate_index("beta").expect("checked")] = beta;
        p[M::coordinate_index("xi").expect("checked")] = xi;
    }
    Ok(p)
}

/// `(beta, xi)` of the physical upright configuration, `None` for a model
/// without the thesis's names.
fn upright_pitch_and_rim_angle<M: MultibodyModel>(
    param: &[f64],
    p: &[f64],
) -> Result<Option<(f64, f64)>, ConstraintError> {
    let get = |n: &str| M::parameter_index(n).and_then(|i| param.get(i).copied());
    let (Some(rt), Some(rd), Some(x4), Some(z4), Some(x5), Some(z5)) =
        (get("Rt"), get("Rd"), get("x4"), get("z4"), get("x5"), get("z5"))
    else {
        return Ok(None);
    };
    if M::coordinate_index("beta").is_none() || M::coordinate_index("xi").is_none() {
        return Ok(None);
    }
    let eps = M::coordinate_index("eps").map_or(0.0, |i| p[i]);
    let (pp, qq) = (x4 + x5, z4 + z5);
    let reach = pp.hypot(qq);
    let d = rd - rt;
    if !(reach > d.abs()) {
        return Err(ConstraintError::NoGroundContact {
            height_difference: d,
            reach,
        });
    }
    let beta = wrap_angle((d / reach).acos() - pp.atan2(qq));
    let xi = wrap_angle(std::f64::consts::FRAC_PI_2 - beta - eps);
    Ok(Some((beta, xi)))
}

/// An angle in `(-pi, pi]`.
fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let r = a.rem_euclid(TAU);
    if r > PI {
        r - TAU
    } else {
        r
    }
}

/// Check that a solved upright configuration `p` is the physical root: the
/// frame pitch equals the geometric one (front wheel centre ahead of the
/// rear one) and the front contact is the lowest point of the rim, to
/// `1e-8` rad.
fn check_physical_branch<M: MultibodyModel>(param: &[f64], p: &[f64]) -> Result<(), LinearizeError> {
    let Some((beta, xi)) = upright_pitch_and_rim_angle::<M>(param, p)? else {
        return Ok(());
    };
    let tol = 1e-8;
    let ib = M::coordinate_index("beta").expect("checked");
    let ix = M::coordinate_index("xi").expect("checked");
    if !(wrap_angle(p[ib] - beta).abs() <= tol) {
        return Err(LinearizeError::OffBranch {
            coordinate: "beta",
            value: p[ib],
            expected: beta,
            what: "frame pitch with the front wheel ahead of the rear wheel",
        });
    }
    let rd = M::parameter_index("Rd").map_or(0.0, |i| param[i]);
    if rd > 0.0 && !(wrap_angle(p[ix] - xi).abs() <= tol) {
        return Err(LinearizeError::OffBranch {
            coordinate: "xi",
            value: p[ix],
            expected: xi,
            what: "front contact at the lowest point of the rim",
        });
    }
    Ok(())
}

/// What [`reduced_equations_from`] returns.
struct Reduced<T> {
    /// `Ec = Mi q'' - Qi`.
    ec: Vec<T>,
    /// `Mi`, row-major.
    mi: Vec<T>,
    /// `-E^T (Qgrav + Qext(p, 0, t))`: the reduced equations at rest (zero
    /// velocities), at the same configuration.
    ec_rest: Vec<T>,
    /// Solved coordinates (real parts).
    solved: Vec<f64>,
}

/// [`reduced_equations`] from the configuration guess `guess` (all
/// coordinates; the independent ones are replaced by `q`).
fn reduced_equations_from<M: MultibodyModel, T: Scalar>(
    param: &[T],
    t: T,
    guess: &[f64],
    q: &[T],
    dq: &[T],
    ddq: &[T],
) -> Result<Reduced<T>, ConstraintError> {
    let nq = M::nq();
    let ind = M::INDEPENDENT;
    let ni = ind.len();
    let mut p: Vec<T> = guess.iter().map(|&x| T::cst(x)).collect();
    for (k, &j) in ind.iter().enumerate() {
        p[j] = q[k];
    }
    solve_configuration::<M, T>(param, t, &mut p, &NewtonOptions::default())?;
    // One elimination on D_dep gives E = [I; -Ddep^-1 Dind] and the
    // dependent velocities (eq. 40-45); a second, after gamma, gives
    // F = [0; -Ddep^-1 gamma].
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
    let a_dep = a.clone();
    solve_in_place(&mut a, nd, &mut rhs, ni + 1).map_err(singular)?;
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
    let mut a = a_dep;
    solve_in_place(&mut a, nd, &mut gamma, 1).map_err(singular)?;
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
    let mut qe_rest = vec![T::zero(); nq];
    M::applied_forces(param, t, &p, &vec![T::zero(); nq], &mut qe_rest);
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
    let mut ec_rest = vec![T::zero(); ni];
    for a_ in 0..ni {
        let mut qi = T::zero();
        let mut qi_rest = T::zero();
        for r in 0..nq {
            qi += e[r * ni + a_] * qtot[r];
            qi_rest += e[r * ni + a_] * (qg[r] + qe_rest[r]);
        }
        ec_rest[a_] = -qi_rest;
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
    let solved = p.iter().map(|x| x.re()).collect();
    Ok(Reduced {
        ec,
        mi,
        ec_rest,
        solved,
    })
}

/// `M`, `C`, `K` of `M q'' + C q' + K q = 0` (thesis eq. 48-50) about
/// upright straight running, in the model's independent coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct Linearization {
    pub mass: DMatrix<f64>,
    pub damping: DMatrix<f64>,
    pub stiffness: DMatrix<f64>,
}

/// Exact linearization (dual numbers) at `param` (which fixes the speed).
pub fn linearize<M: MultibodyModel>(param: &[f64]) -> Result<Linearization, LinearizeError> {
    linearize_with_rest::<M>(param).map(|(l, _)| l)
}

/// [`linearize`] and, from the same dual evaluation, the stiffness at rest
/// (`V = 0`): `K(0) = d/dq [-E^T (Qgrav + Qext(p, 0))]`, because the
/// configuration and `E` do not depend on the speed and every velocity
/// term vanishes at rest (see [`static_stiffness`]).
fn linearize_with_rest<M: MultibodyModel>(param: &[f64]) -> Result<(Linearization, DMatrix<f64>), LinearizeError> {
    const N: usize = 4;
    let ni = M::INDEPENDENT.len();
    if ni != 2 {
        return Err(LinearizeError::NotRollSteer { model: M::NAME, n: ni });
    }
    let pd: Vec<Dual<N>> = param.iter().map(|&x| Dual::cst(x)).collect();
    let q = [Dual::<N>::variable(0.0, 0), Dual::variable(0.0, 1)];
    let dq = [Dual::<N>::variable(0.0, 2), Dual::variable(0.0, 3)];
    let ddq = [Dual::<N>::zero(); 2];
    let guess = upright_guess::<M>(param)?;
    let r = reduced_equations_from::<M, Dual<N>>(&pd, Dual::zero(), &guess, &q, &dq, &ddq)?;
    check_physical_branch::<M>(param, &r.solved)?;
    let mass = DMatrix::from_fn(2, 2, |i, j| r.mi[i * 2 + j].re);
    let stiffness = DMatrix::from_fn(2, 2, |i, j| r.ec[i].eps[j]);
    let damping = DMatrix::from_fn(2, 2, |i, j| r.ec[i].eps[2 + j]);
    let rest = DMatrix::from_fn(2, 2, |i, j| r.ec_rest[i].eps[j]);
    Ok((
        Linearization {
            mass,
            damping,
            stiffness,
        },
        rest,
    ))
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

/// Fill a model's parameter vector by name from `lookup`, with the forward
/// speed `V`.
pub fn parameter_vector<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
    speed: f64,
) -> Result<Vec<f64>, LinearizeError> {
    M::PARAMETERS
        .iter()
        .map(|&n| {
            if n == "V" { Some(speed) } else { lookup(n) }.ok_or_else(|| LinearizeError::MissingParameter {
                model: M::NAME,
                name: n.to_string(),
            })
        })
        .collect()
}

/// Stiffness `K` of the linearization at zero forward speed, where only
/// gravity (and applied forces at rest) act: with `V = 0` and `q' = 0` every
/// velocity vanishes (the driving constraint's `Ct` is `-V/Rt`), so `Qv`, the
/// convective terms and `F` are zero and `Ec = -E^T (Qgrav + Qext)`. This
/// needs only the configuration, `E` and the gravity forces with 2-direction
/// dual numbers, a fraction of a full [`linearize`].
pub fn static_stiffness<M: MultibodyModel>(param: &[f64]) -> Result<DMatrix<f64>, LinearizeError> {
    const N: usize = 2;
    let ni = M::INDEPENDENT.len();
    if ni != 2 {
        return Err(LinearizeError::NotRollSteer { model: M::NAME, n: ni });
    }
    let nq = M::nq();
    let ind = M::INDEPENDENT;
    let pd: Vec<Dual<N>> = param.iter().map(|&x| Dual::cst(x)).collect();
    let guess = upright_guess::<M>(param)?;
    let mut p: Vec<Dual<N>> = guess.iter().map(|&x| Dual::cst(x)).collect();
    for (k, &j) in ind.iter().enumerate() {
        p[j] = Dual::variable(0.0, k);
    }
    let t = Dual::<N>::zero();
    solve_configuration::<M, Dual<N>>(&pd, t, &mut p, &NewtonOptions::default())?;
    let solved: Vec<f64> = p.iter().map(|x| x.re).collect();
    check_physical_branch::<M>(param, &solved)?;
    let cm = constraint_matrices::<M, Dual<N>>(&pd, t, &p);
    let depv = dependent_velocities::<M>();
    let nd = depv.len();
    let nc = cm.d_rhs.len();
    let mut a = vec![Dual::<N>::zero(); nd * nd];
    let mut rhs = vec![Dual::<N>::zero(); nd * ni];
    for i in 0..nc {
        for (k, &j) in depv.iter().enumerate() {
            a[i * nd + k] = cm.d[i * nq + j];
        }
        for (k, &j) in ind.iter().enumerate() {
            rhs[i * ni + k] = cm.d[i * nq + j];
        }
    }
    solve_in_place(&mut a, nd, &mut rhs, ni).map_err(|s| ConstraintError::SingularJacobian {
        what: "coordinate partitioning",
        column: s.column,
        pivot: s.pivot,
        scale: s.scale,
    })?;
    // Q = Qgrav + Qext at rest; Qi_k = sum_r E[r][k] Q[r].
    let mut qg = vec![Dual::<N>::zero(); nq];
    M::gravity_forces(&pd, &p, &mut qg);
    let mut qe = vec![Dual::<N>::zero(); nq];
    let dp = vec![Dual::<N>::zero(); nq];
    M::applied_forces(&pd, t, &p, &dp, &mut qe);
    let mut k = DMatrix::zeros(2, 2);
    for a_ in 0..ni {
        let mut qi = qg[ind[a_]] + qe[ind[a_]];
        for (r, &j) in depv.iter().enumerate() {
            qi -= rhs[r * ni + a_] * (qg[j] + qe[j]);
        }
        for b in 0..ni {
            k[(a_, b)] = -qi.eps[b];
        }
    }
    Ok(k)
}

/// Canonical matrices by two full linearizations (at `V = 0` and `V = 1`),
/// the method [`canonical_matrices`] used before issue 10, point 10; kept for
/// the bench's comparison and as a cross-check.
pub fn canonical_matrices_two_speeds<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
) -> Result<CanonicalMatrices, LinearizeError> {
    let g = lookup("g").ok_or_else(|| LinearizeError::MissingParameter {
        model: M::NAME,
        name: "g".into(),
    })?;
    let l0 = linearize::<M>(&parameter_vector::<M>(&lookup, 0.0)?)?;
    let l1 = linearize::<M>(&parameter_vector::<M>(&lookup, 1.0)?)?;
    let flip = |m: &DMatrix<f64>| Matrix2::new(m[(0, 0)], -m[(0, 1)], -m[(1, 0)], m[(1, 1)]);
    Ok(CanonicalMatrices {
        m0: flip(&l0.mass),
        c1: flip(&l1.damping),
        k0: flip(&l0.stiffness) / g,
        k2: flip(&(&l1.stiffness - &l0.stiffness)),
        g,
    })
}

/// Canonical matrices of Meijaard et al. (2007) from a generated model:
/// `M0 = M`, `C1 = C(v=1)`, `K0 = K(v=0)/g`, `K2 = K(v=1) - K(v=0)`, exact
/// because the reduced equations are quadratic in the forward speed. The
/// thesis's steer angle gamma is minus the benchmark's delta, so the
/// off-diagonal entries change sign.
///
/// One dual-number linearization at `V = 1` gives `M`, `C(1)`, `K(1)` and,
/// from the same evaluation, `K(0)` (the gravity and rest terms alone; see
/// [`static_stiffness`] for the standalone computation).
pub fn canonical_matrices<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
) -> Result<CanonicalMatrices, LinearizeError> {
    let g = lookup("g").ok_or_else(|| LinearizeError::MissingParameter {
        model: M::NAME,
        name: "g".into(),
    })?;
    let (l1, k_rest) = linearize_with_rest::<M>(&parameter_vector::<M>(&lookup, 1.0)?)?;
    let flip = |m: &DMatrix<f64>| Matrix2::new(m[(0, 0)], -m[(0, 1)], -m[(1, 0)], m[(1, 1)]);
    Ok(CanonicalMatrices {
        m0: flip(&l1.mass),
        c1: flip(&l1.damping),
        k0: flip(&k_rest) / g,
        k2: flip(&(&l1.stiffness - &k_rest)),
        g,
    })
}
