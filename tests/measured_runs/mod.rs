//! Measured runs: `fit` on measured-style, synthetic and TU Delft runs.

mod fit_command;
mod synthetic_runs;
