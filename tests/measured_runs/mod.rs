//! Measured runs: reading run folders and logs, `fit` on measured-style,
//! synthetic and TU Delft runs, and which fitted eigenvalues it accepts as
//! measured ones.

mod acceptance;
mod calibration_and_sensors;
mod fit_command;
mod kick_detection;
mod pipeline;
mod reading;
mod result_schema;
mod synthetic_runs;
