//! bikedyn: symbolic multibody bicycle models turned into fast generated
//! Rust, and the numerics that use them (linearization, stability sweeps,
//! verification). See README.md and ARCHITECTURE.md.

pub use bikedyn_report as report;
pub use bikedyn_runtime as runtime;

#[path = "../generated/mod.rs"]
pub mod generated;

pub use generated::{ThesisWhipple, WhippleOffset};

/// The registry of generated models: `MODELS`, `SOURCES`, `with_model`, and
/// the runtime's `ModelInfo` and `ModelVisitor`.
pub mod registry {
    pub use crate::generated::{with_model, MODELS, SOURCES};
    pub use bikedyn_runtime::registry::{ModelInfo, ModelVisitor};
}

pub mod bicycle;
pub mod fit;
pub mod identify;
pub mod models;
pub mod progress;
pub mod simulate;
pub mod synth;
