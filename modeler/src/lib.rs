//! bikedyn's build-time modeler: declare a multibody model as data
//! ([`model`]), derive its equations symbolically with Symbolica
//! (`derive`), emit optimized Rust (`emit`), and write a crate's generated
//! models and registry ([`codegen::build`], for `build.rs`).
//!
//! Derivation and emission sit behind the `derive` feature, the only part
//! that uses Symbolica (whose own licence governs its use). Without it, a
//! build takes each model's committed generated file when the file's inputs
//! hash says it is what derivation would give ([`snapshot`]), and stops
//! with the command that re-derives a model that changed. The generated
//! code and the runtime never depend on Symbolica.

// Effect files name the modeler by its crate path, so that one file works
// in `modeler/src/effects/` and in a user's `build.rs` alike (identify
// writes discovered effects so).
extern crate self as bikedyn_modeler;

pub mod codegen;
#[cfg(feature = "derive")]
pub mod derive;
pub mod effects;
#[cfg(feature = "derive")]
pub mod emit;
pub mod expr;
pub mod hash;
pub mod identification;
pub mod model;
pub mod models;
pub mod registry;
pub mod snapshot;
