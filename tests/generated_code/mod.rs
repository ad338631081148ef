//! The generated code: every derivative against finite differences, and the
//! committed copies in `generated/` against what the build emits.

mod finite_differences;
mod snapshots;
