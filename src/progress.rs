//! Progress of the long pipelines (fit, identify, synth), reported through a
//! callback so the library never draws on a terminal: the command line
//! renders it (a bar on a terminal), other callers may log or ignore it.

/// One step of a long computation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress<'a> {
    /// What was just done: `"runs"` for measured runs processed by `fit`, or
    /// a stage of `identify` in words (`"fitted steer_damping"`,
    /// `"score test of 30 candidates"`, `"cross-validated steer_damping"`).
    pub step: &'a str,
    /// Steps done so far (1 after the first).
    pub done: usize,
    /// Steps in all, when known in advance (`fit`: the runs and logs found).
    pub total: Option<usize>,
}

/// The progress callback the pipelines take. It may be called from several
/// threads at once (identification fits candidates in parallel).
pub type OnProgress<'a> = &'a (dyn Fn(Progress<'_>) + Sync);

/// A callback that ignores every report.
pub fn ignore(_: Progress<'_>) {}
