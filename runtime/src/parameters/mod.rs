//! Bicycle parameter sets: the thesis form (Martin Recuero 2009, section 4.4)
//! and the benchmark form (Meijaard et al. 2007, Table 1), validation and
//! conversion between them. Their files (TOML of either form, the text files
//! of BicycleParameters and HumanControl) are the application's: read and
//! written by `bikedyn::bicycle::files`.
//!
//! - [`ThesisParameters`] / [`BenchmarkParameters`]: the two forms, with the
//!   reference bicycles [`ThesisParameters::thesis_bicycle`] and
//!   [`BenchmarkParameters::benchmark_bicycle`] (also embedded as TOML:
//!   [`THESIS_BICYCLE_TOML`], [`BENCHMARK_BICYCLE_TOML`]).
//! - [`ParameterSet`]: a set of either [`Form`].
//! - J. K. Moore's (2012) parameters with a leaning rider, as
//!   bicycleparameters names them (`MooreRiderLean2012ParameterSet`): told
//!   by their keys and converted to the benchmark form and the `rider_lean`
//!   model's rider ([`moore`]).
//! - `validate()`: errors ([`ParameterError`]) for non-finite values,
//!   non-positive masses/radii/inertias and non-positive-definite tensors;
//!   warnings ([`ParameterWarning`]) for principal moments that violate the
//!   triangle inequality and for degenerate bodies (skate wheels, point
//!   masses, as in the two-mass-skate bicycle).
//! - [`ThesisParameters::to_benchmark`] / [`BenchmarkParameters::to_thesis`]:
//!   exact conversions (geometry in [`ThesisParameters::to_benchmark`]).
//!
//! ```
//! use bikedyn_runtime::parameters::{ParameterWarning, ThesisParameters};
//! let thesis = ThesisParameters::thesis_bicycle();
//! let warnings = thesis.validate().unwrap();
//! assert!(matches!(warnings[0], ParameterWarning::TriangleInequality { body: "handlebar", .. }));
//! let bench = thesis.to_benchmark().unwrap();
//! assert!((bench.steer_axis_tilt - 0.315).abs() < 0.01);
//! ```

mod benchmark;
mod convert;
pub use convert::thesis_to_benchmark_in;
mod error;
pub mod moore;
mod set;
mod thesis;
mod validate;

pub use benchmark::{BenchmarkParameters, BENCHMARK_BICYCLE_TOML};
pub use error::{cut, Origin, ParameterError, ParameterWarning};
pub use set::{Form, ParameterSet};
pub use thesis::{ThesisParameters, THESIS_BICYCLE_TOML};
pub use validate::body;
