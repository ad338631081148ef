//! bikedyn runtime: numerics on generated multibody models (nalgebra only; no
//! Symbolica at run time).
#![allow(clippy::needless_range_loop)]
// `!(x <= tol)` is deliberate throughout: it treats NaN as a failure.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod canonical;
pub mod closed_form;
pub mod constraints;
pub mod eigen;
pub mod experiment;
pub mod feedback;
pub mod frequency;
pub mod geometry;
pub mod identify;
pub mod linalg;
pub mod linear_types;
pub mod linearize;
pub mod model;
pub mod number_text;
pub mod parameters;
pub mod random;
pub mod registry;
pub mod scalar;
pub mod sensitivity;
pub mod simulate;
pub mod small_sort;
pub mod sweep;
pub mod verify;

pub use canonical::CanonicalMatrices;
pub use model::MultibodyModel;
pub use scalar::{Dual, Scalar};
