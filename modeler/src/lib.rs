//! bikedyn's build-time modeler: declare a multibody model as data
//! ([`model`]), derive its equations symbolically with Symbolica
//! ([`derive`]), emit optimized Rust ([`emit`]), and write a crate's
//! generated models and registry ([`codegen::generate`], for `build.rs`).
//!
//! Symbolica runs here only, at build time; the generated code and the
//! runtime do not depend on it. Symbolica's own licence governs its use.

pub mod codegen;
pub mod derive;
pub mod effects;
pub mod emit;
pub mod expr;
pub mod model;
pub mod models;
