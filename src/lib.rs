//! bikedyn: symbolic multibody bicycle models turned into fast generated
//! Rust, and the numerics that use them (linearization, stability sweeps,
//! verification). See README.md, ARCHITECTURE.md and docs/.

pub use bikedyn_report as report;
pub use bikedyn_runtime as runtime;

#[path = "../generated/mod.rs"]
pub mod generated;

pub use generated::{ThesisWhipple, WhippleOffset};

/// The registry of generated models: `MODELS`, `SOURCES`, `with_model`, the
/// built-in registry as a type ([`registry::BuiltIn`]), and the runtime's
/// `ModelInfo`, `ModelVisitor` and `ModelRegistry`.
///
/// The pipelines run on the built-in registry by default; their `_in`
/// forms (`Bicycle::resolve_in`, `synth::synth_in`, `identify::run_in`, ...)
/// take another one, such as the `Registry` a user's build script generated
/// with `bikedyn_modeler::codegen::generate` (`examples/steering_spring`).
pub mod registry {
    pub use crate::generated::{with_model, MODELS, SOURCES};
    pub use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
    /// The models bikedyn's own build generates (`bikedyn models`).
    pub type BuiltIn = crate::generated::Registry;
}

/// `bikedyn bench` (not in the WebAssembly build: its clock and temporary
/// folder are not there).
#[cfg(not(target_arch = "wasm32"))]
pub mod bench;
pub mod bicycle;
pub mod canonical;
pub mod capped;
pub mod eigen;
pub mod fit;
pub mod frequency;
pub mod identify;
pub mod main_report;
pub mod models;
pub mod monte_carlo;
pub mod progress;
pub mod runs;
pub mod sensitivity;
/// `bikedyn serve` (not in the WebAssembly build: no sockets there).
#[cfg(not(target_arch = "wasm32"))]
pub mod serve;
pub mod simulate;
pub mod stability;
pub mod sweep;
pub mod synth;
