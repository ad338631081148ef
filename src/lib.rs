//! bikedyn: symbolic multibody bicycle models turned into fast generated
//! Rust, and the numerics that use them (linearization, stability sweeps,
//! verification). See README.md and ARCHITECTURE.md.

pub use bikedyn_runtime as runtime;

#[path = "../generated/mod.rs"]
pub mod generated;

pub use generated::{ThesisWhipple, WhippleOffset};

pub mod bench;
pub mod bench_simulate;
pub mod bicycle;
pub mod models;
