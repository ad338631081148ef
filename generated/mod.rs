//! Generated model code. `build.rs` writes every model and the registry into
//! OUT_DIR; this module pulls the registry in (it lists the models, so no
//! model name is written by hand here). `generated/snapshots/` holds
//! committed, formatted copies, kept fresh by `tests/generated_code/snapshots.rs`
//! (refresh with `UPDATE_SNAPSHOTS=1 cargo test --test behaviour snapshots`).

include!(concat!(env!("OUT_DIR"), "/models.rs"));

/// Derivation time and operation counts of the last code generation (JSON).
pub const CODEGEN_REPORT: &str = include_str!(concat!(env!("OUT_DIR"), "/codegen_report.json"));
