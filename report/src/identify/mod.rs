//! Output of an identification: its plots ([`plot`]).

pub mod plot;
