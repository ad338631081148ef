//! Why identification could not run or report.

use crate::bicycle::BicycleError;
use crate::fit::FitError;
use bikedyn_report::output::OutputError;
use bikedyn_report::plot::PlotError;
use bikedyn_runtime::linearize::LinearizeError;
use std::path::PathBuf;
use thiserror::Error;

/// Errors of `identify`'s pipeline and report.
#[derive(Debug, Error)]
pub enum IdentifyError {
    /// The bicycle could not be resolved, or lacks a parameter.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// No free-speed model of the registry has every parameter the bicycle sets.
    #[error("no free-speed model in the registry can represent `{bicycle}`")]
    NoFreeSpeedModel { bicycle: String },
    /// The free-speed model has no driven-speed twin (same effects).
    #[error("no driven-speed model with the effects of `{model}`")]
    NoDrivenTwin { model: &'static str },
    /// An effect asked for is not a candidate of the identification models.
    #[error("--effects: `{effect}` is not a candidate effect of the identification models ({})", known.join(", "))]
    NotACandidate { effect: String, known: Vec<&'static str> },
    /// An effect asked for is not something to find in these runs: the
    /// bicycle file declares it, or the logs' speed is imposed.
    #[error("--effects: `{effect}` is not a candidate here: {reason}")]
    ExcludedCandidate { effect: String, reason: String },
    /// An effect asked for cannot be tried from an eigenvalue table.
    #[error(
        "--effects: `{effect}` cannot be tried from an eigenvalue table ({reason}); effects that can: {}",
        if triable.is_empty() { "none".to_string() } else { triable.join(", ") }
    )]
    NotTriableFromTable {
        effect: String,
        reason: String,
        triable: Vec<String>,
    },
    /// Nothing to test: a conclusion ("no effect warranted") would mean nothing.
    #[error(
        "no candidate effect for `{bicycle}` through model `{model}` (effects: {}): identification would conclude without testing anything",
        if effects.is_empty() { "none".to_string() } else { effects.join(", ") }
    )]
    NoCandidates {
        bicycle: String,
        model: &'static str,
        effects: Vec<&'static str>,
    },
    /// Thesis-style runs and TU Delft logs in one identification: their
    /// channels differ (roll angle or roll rate; free or imposed speed).
    #[error("identify: {} mixes thesis-style runs and TU Delft logs; identify them separately", inputs.join(", "))]
    MixedInputs { inputs: Vec<String> },
    /// An input path is neither a run, a set nor a log.
    #[error(transparent)]
    Input(#[from] crate::runs::InputError),
    /// A measured eigenvalue table could not be read.
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    EigenTable {
        path: PathBuf,
        line: usize,
        message: String,
    },
    /// Fewer than two kicks with a free-response window.
    #[error(
        "identification needs at least two kicks with a free-response window; found {found}{}",
        if skipped.is_empty() { String::new() } else { format!(" ({})", skipped.join("; ")) }
    )]
    TooFewKicks { found: usize, skipped: Vec<String> },
    /// The measured-run pipeline failed as a whole.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The parameter vector of a model could not be formed from the bicycle.
    #[error(transparent)]
    Linearize(#[from] LinearizeError),
    /// The fits themselves (simulation setup, no data).
    #[error(transparent)]
    Fitting(#[from] bikedyn_runtime::identify::IdentifyError),
    /// The report folder could not be created.
    #[error("creating {}", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// A report file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A report plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The typical run of the residual plot failed to simulate.
    #[error("the typical run could not be simulated for the plot")]
    TypicalRunNotSimulated,
}
