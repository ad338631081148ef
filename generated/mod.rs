//! Generated model code. `build.rs` writes every model and the registry into
//! OUT_DIR; this module pulls the registry in (it lists the models, so no
//! model name is written by hand here). `generated/snapshots/` holds the
//! committed, formatted code of each model, which the build uses when its
//! inputs hash matches the model files (refresh with `cargo run --release
//! -p bikedyn-modeler --features derive --bin bikedyn-derive`; CI checks
//! it with `--check`).

include!(concat!(env!("OUT_DIR"), "/models.rs"));

/// Derivation time and operation counts of the last code generation (JSON).
pub const CODEGEN_REPORT: &str = include_str!(concat!(env!("OUT_DIR"), "/codegen_report.json"));
