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
//!
//! # Layout
//!
//! * `reduced.rs`: the reduced equations themselves ([`reduced_equations`],
//!   [`reduced_system`]), in any scalar type;
//! * `upright.rs`: the exact linearization about upright straight running,
//!   its allocation-free fast path ([`linearize_with_rest`]) and the general
//!   path it is tested against ([`linearize_with_rest_general`]);
//! * `at_speed.rs`: steady running at a given forward speed, for any model
//!   ([`parameter_vector`], [`linearize_at_speed`], [`state_space_at_speed`]);
//! * `canonical.rs`: the canonical matrices of Meijaard et al.
//!   (2007) from a generated model ([`canonical_matrices`]);
//! * `linear_model.rs`: a generated model as a
//!   [`LinearBicycle`](crate::eigen::LinearBicycle) for the
//!   eigen analyses ([`LinearModel`]);
//! * here: the driven model's [`linearize`] and the thesis's
//!   finite-difference cross-check ([`linearize_finite_difference`]).

mod at_speed;
mod canonical;
mod linear_model;
mod reduced;
mod upright;

pub use at_speed::{
    lateral_block, lateral_indices, linearize_at_speed, parameter_vector, state_space_at_speed, state_space_dual,
    StateSpace,
};
pub use canonical::{canonical_matrices, canonical_matrices_general, canonical_matrices_two_speeds, static_stiffness};
pub use linear_model::LinearModel;
pub use reduced::{reduced_equations, reduced_system, ReducedSystem};
pub use upright::{
    check_physical_branch, linearize_with_rest, linearize_with_rest_general, upright_linearization,
    UprightLinearization,
};

use crate::model::MultibodyModel;
// The types the `MultibodyModel` trait names live below it; their public
// paths stay here.
pub use crate::linear_types::{Linearization, LinearizeError, StateMatrix, WithRest};
use nalgebra::DMatrix;

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
