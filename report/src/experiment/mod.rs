//! Output of measured runs: plots of the responses and of the measured
//! continuation ([`plot`]), the residual table ([`compare`]) and the files
//! of synthetic runs ([`synth`]).

pub mod compare;
pub mod plot;
pub mod synth;
