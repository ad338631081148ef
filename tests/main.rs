//! bikedyn's behaviour, in one test binary grouped by capability.
//!
//! One harness rather than one binary per file: every test binary links all
//! the generated models, so sixteen binaries cost sixteen links. Helpers
//! shared by the groups live in `common`.
//!
//! - `linear_analysis`: published figures (Meijaard benchmark, Basu-Mandal),
//!   closed-form oracles on real and random designs, constraint solving, the
//!   fast upright path, free speed.
//! - `generated_code`: finite-difference verification and committed copies.
//! - `simulation`: the nonlinear motion against the linear solution, events,
//!   energy, the stiff integrator.
//! - `parameter_files`: bicycle parameter files of every format, read,
//!   validated, converted and written back.
//! - `effects`: the effect library in parameter files and the equations.
//! - `any_bicycle`: real bicycles with effect parameters through every job.
//! - `measured_runs`: `fit` on measured-style and synthetic runs.
//! - `identification`: closing the loop on sets with a hidden effect.
//! - `command_line`: the commands, their outputs and their errors.

mod common;

mod any_bicycle;
mod command_line;
mod effects;
mod generated_code;
mod identification;
mod linear_analysis;
mod measured_runs;
mod parameter_files;
mod simulation;
