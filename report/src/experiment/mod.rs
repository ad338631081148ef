//! Output of measured runs: plots of the responses and of the measured
//! continuation ([`plot`]), the residual table ([`compare`]), the
//! acceptance verdicts of measured eigenvalues in words ([`accept`]) and the
//! files of synthetic runs ([`synth`]).

pub mod accept;
pub mod compare;
pub mod plot;
pub mod synth;
