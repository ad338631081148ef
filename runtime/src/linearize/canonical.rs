//! The canonical matrices `M0`, `C1`, `K0`, `K2` of Meijaard et al. (2007)
//! from a generated model: by one dual-number linearization at speed 1
//! (with the stiffness at rest from the same evaluation), by the general
//! path, or by two full linearizations (the earlier method, kept for the
//! bench and as a cross-check); and the stiffness at zero speed.
//!
//! Apart because this is the bridge from a generated model to the
//! benchmark's form ([`CanonicalMatrices`]), with its sign convention.

use super::at_speed::{lateral_block, lateral_indices, linearize_at_speed, parameter_vector, speed_rates, speed_setup};
use super::upright::linearize_with_rest_general;
use crate::canonical::CanonicalMatrices;
use crate::linalg::Scratch;
use crate::linear_types::{LinearizeError, WithRest};
use crate::model::MultibodyModel;
use nalgebra::{DMatrix, Matrix2};

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
    let g = gravity::<M>(&param)?;
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
    let g = gravity::<M>(&param)?;
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

/// The model's gravity from its parameter vector (an error naming the
/// model when it declares none: the canonical form separates the terms in g).
fn gravity<M: MultibodyModel>(param: &[f64]) -> Result<f64, LinearizeError> {
    M::GRAVITY_PARAMETER
        .map(|k| param[k])
        .ok_or(LinearizeError::MissingParameter {
            model: M::NAME,
            name: "gravity".into(),
        })
}
