//! Generated model code. `build.rs` writes it into OUT_DIR; this module pulls
//! it in. `generated/snapshots/` holds committed, formatted copies, kept fresh
//! by `tests/codegen_snapshots.rs` (refresh with `UPDATE_SNAPSHOTS=1 cargo test`).

/// The thesis's Whipple model (fork mass centre on the steer axis).
pub mod thesis_whipple {
    include!(concat!(env!("OUT_DIR"), "/thesis_whipple.rs"));
}

/// The benchmark-compatible variant (fork mass centre offset `d4`).
pub mod whipple_offset {
    include!(concat!(env!("OUT_DIR"), "/whipple_offset.rs"));
}

pub use thesis_whipple::ThesisWhipple;
pub use whipple_offset::WhippleOffset;

/// Emitted sources by model name, as build.rs wrote them.
pub const SOURCES: &[(&str, &str)] = &[
    (
        "thesis_whipple",
        include_str!(concat!(env!("OUT_DIR"), "/thesis_whipple.rs")),
    ),
    (
        "whipple_offset",
        include_str!(concat!(env!("OUT_DIR"), "/whipple_offset.rs")),
    ),
];

/// Derivation time and operation counts of the last code generation (JSON).
pub const CODEGEN_REPORT: &str = include_str!(concat!(env!("OUT_DIR"), "/codegen_report.json"));
