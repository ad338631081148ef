//! Measured runs: `fit` on measured-style, synthetic and TU Delft runs, and
//! which fitted eigenvalues it accepts as measured ones.

mod acceptance;
mod fit_command;
mod synthetic_runs;
