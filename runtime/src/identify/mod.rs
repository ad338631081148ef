//! Closing the loop (issue 9): from the residual between a model and measured
//! free responses to the effect the model lacks, its fitted parameters, and
//! the error before and after.
//!
//! # Method
//!
//! * **Data** (`segment.rs`). Each kick of a measured set gives a [`Segment`]:
//!   roll and steer (rad) on the IMU clock and the reed-switch speed (m/s) over
//!   the kick's free-response window (found by `experiment`, never by hand).
//! * **Time-series residuals** (`residuals.rs`). A candidate model is the
//!   free-speed model `M` (every effect of the library, each absent unless
//!   fitted) with some effect parameters free (`candidate.rs`). Each segment is
//!   simulated with the full nonlinear equations from its own initial state
//!   (roll, steer, their rates and the speed at the window start). The residual
//!   is measured minus simulated roll, steer and speed at the measurement
//!   times, each channel divided by its noise scale ([`Weights`]).
//! * **Fitting** (`fit.rs`). Effect parameters are shared by all segments; the
//!   initial states are per-segment nuisance parameters (`nuisance.rs`). Both
//!   are fitted together by Levenberg-Marquardt (`levenberg_marquardt.rs`:
//!   joint steps while they are accepted, then steps over the shared
//!   parameters' profile with each segment refitted on its own; a base fit
//!   fits each segment alone, also from its measured speed) on the block-arrow structure of
//!   the problem (`normal.rs`: a segment depends only on the shared parameters
//!   and its own initial state): the normal equations are reduced to the shared
//!   parameters by eliminating each segment's 6x6 block (10x10 with the tyre model), so an iteration costs
//!   linearly in the number of kicks (a dense solver's QR grows with their
//!   cube, and a hundred kicks of the TU Delft logs took minutes per iteration;
//!   the `levenberg-marquardt` crate has no sparse path). The Jacobian comes
//!   from forward sensitivities (`simulate::sensitivity`): each segment is
//!   simulated once in dual numbers carrying the derivatives along its initial
//!   state and the effect parameters (in passes of `WIDTH` directions of
//!   `residuals.rs`), exact to the integration tolerance (rtol 1e-8); forward
//!   differences of whole simulations (a column per simulation) remain only
//!   where the explicit integrator fails (a stiff candidate, simulated with
//!   Radau5). Residuals alone take the lean path of the same module (channel
//!   samples only). Segments run in parallel.
//! * **Roll channel and speed.** Thesis-style runs measure the roll angle
//!   and leave the speed free after the release; a log of a gyro-equipped
//!   bicycle whose motor holds the speed (the TU Delft logs) measures the
//!   roll rate ([`RollChannel`]), and its segments are simulated with the
//!   driven-speed model, the speed nuisance pinned by the measured speed.
//! * **Uncertainty.** Standard errors come from `(J^T J)^-1 s^2`, with `s^2`
//!   the residual variance, inflated by `(1 + rho) / (1 - rho)` for the lag-1
//!   autocorrelation `rho` of the residuals: 120 Hz samples of a smooth
//!   model error are not independent.
//! * **Selection** ([`selection`]). Forward stepwise: a candidate is added only
//!   if it lowers the Bayesian information criterion computed with the
//!   effective sample size (`n (1 - rho) / (1 + rho)` per channel, from the
//!   base model's residuals) *and* lowers the cross-validated error over
//!   held-out runs (k-fold by run or log, the effect fitted on the other runs
//!   and only the held-out run's initial state fitted to it:
//!   `cross_validation.rs`), *and* its dissipative parameters are positive (a
//!   negative damper is not physics). The score test ([`screen`]: one
//!   simulation per kick in dual numbers linearises every candidate at once)
//!   orders the candidates and skips those that cannot lower the criterion;
//!   when the best fails, the next is tried, and pairs when no single candidate
//!   passes. After the forward search, every candidate followed by a later
//!   addition is tested again against the final model without it
//!   (`selection/elimination.rs`). Sensor nuisances (mounting misalignment, clock offset) are
//!   estimated per set by the measured-run pipeline before, and are never
//!   candidates.

mod candidate;
pub mod confounding;
mod criterion;
mod cross_validation;
pub mod discovery;
mod encompassing;
mod fit;
mod fitted;
pub mod least_squares;
mod levenberg_marquardt;
mod normal;
mod nuisance;
mod problem;
pub mod remaining;
mod residuals;
mod rivals;
mod screen;
mod search_order;
mod segment;
pub mod selection;
pub mod state_correlation;
mod verdict;
pub use candidate::{Bound, Candidate, EffectParameter};
pub use confounding::{Confounding, Design, HeldOutGain, CONFOUNDED};
pub use cross_validation::{cross_validate, folds_by_run, paired_gain};
pub use fit::fit_candidate;
pub use fitted::{pooled_rms, CandidateFit, IdentifyOptions, SegmentError};
pub use nuisance::{at_rest, EXTRA_STATES, INITIAL_MOTION, NUISANCE, STEER_BIAS};
pub use residuals::{Factory, ModelFactory, Setup, Sim};
pub use segment::{RollChannel, Segment, Weights};
pub use selection::{bic, identify, Identification, MemberCheck, Step, Trial, Verdict, PLAUSIBLE_PRIOR_SDS};

/// Errors of identification.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    #[error("model `{model}` has no parameter `{symbol}`")]
    UnknownParameter { model: &'static str, symbol: String },
    #[error("no segment to fit (no kick with a usable free-response window)")]
    NoData,
    #[error("the simulation of {run} failed at the initial state: {message}")]
    Simulation { run: String, message: String },
    #[error("model `{model}` has {states} extra first-order states; identification fits at most {EXTRA_STATES} at each window start")]
    TooManyStates { model: &'static str, states: usize },
}
