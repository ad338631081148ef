//! bikedyn report: the output layer above the numerics of
//! `bikedyn-runtime`. Plots (plotters), terminal tables, CSV and JSON text
//! and the atomic writing of every output file. The runtime computes and
//! returns data; this crate only presents it, and the runtime never depends
//! on it.
//!
//! The modules follow the runtime's: [`output`] (atomic writes, eigenvalue
//! and sweep formats, tables), [`plot`] (continuation diagram, stability
//! map, fonts), [`simulate`] (time-history CSV and plot), [`identify`]
//! (identification plots), [`experiment`] (measured-run plots, the residual
//! table, the synthetic sensor files), [`staged`] (output folders written
//! as a whole and recognised as bikedyn's), [`temporaries`] (cleanup of
//! killed runs' temporaries).
// The same allowances as the runtime, whose code this was: index loops over
// grid cells read more plainly than zipped iterators.
#![allow(clippy::needless_range_loop)]
// `!(x <= tol)` is deliberate throughout: it treats NaN as a failure.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod experiment;
pub mod frequency;
pub mod identify;
pub mod output;
pub mod plot;
pub mod sensitivity;
pub mod simulate;
pub mod staged;
pub mod temporaries;
