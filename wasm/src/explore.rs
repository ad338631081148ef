//! The `explore` job: everything the explorer's page shows of one bicycle,
//! in one answer: the bicycle (as the `bicycle` job gives it), its
//! eigenvalues and modes over speed as arrays (as `eig` with `arrays`),
//! its self-stable speeds, and its eigenvalues and mode shapes at one speed
//! (the page's slider).
//!
//! Why one job: the page asked four times after every change (`bicycle`,
//! `eig`, `stability`, `eig` at one speed), and each request sent the
//! bicycle again (an imported file's whole text), which the module parsed,
//! built and linearized again: a quarter of the page's redraw after a
//! parameter change (2026-11-30). The numbers are those of the four jobs:
//! the same library calls on the same bicycle.

use crate::arrays::{eig_arrays, EigArrays};
use crate::bicycle_answer::{bicycle_answer, BicycleAnswer};
use bikedyn::bicycle::{Bicycle, BicycleError};
use bikedyn::eigen::{EigenAtSpeed, EigenJob, EigenOptions, EigenSweepError, Speeds};
use bikedyn::runtime::eigen::critical_speeds_of;
use serde::Serialize;

/// The answer: the `eig` answer with `arrays` (its fields at the top, so
/// that `arrays` is where the loader looks for it) and three more.
#[derive(Serialize)]
pub struct ExploreAnswer {
    /// The bicycle, as the `bicycle` job answers.
    pub bicycle: BicycleAnswer,
    #[serde(flatten)]
    pub eig: EigArrays,
    /// The speed ranges between `speed_min` and `speed_max` where every
    /// eigenvalue's real part is negative, as `stability` gives them
    /// (`stable_intervals`); none when they cannot be found (the page draws
    /// no band then, as it did when `stability` failed).
    pub stable_intervals: Option<Vec<[f64; 2]>>,
    /// The eigenvalues, modes and mode shapes at `speed`, as one point of
    /// `eig --format json` without standard deviations (the page shows
    /// none); none when they cannot be computed.
    pub at_speed: Option<EigenAtSpeed>,
}

/// Where the job fails: the bicycle (kind `bicycle`, as the `bicycle`
/// job's) or the eigenvalues over speed (kind `job`, as `eig`'s).
pub enum ExploreError {
    Bicycle(BicycleError),
    Eig(EigenSweepError),
}

/// The job on the bicycle `b`: `speeds` are the diagram's, `band` the
/// range of the self-stable speeds and `speed` the slider's; the arrays'
/// numbers go to `arrays`.
pub fn explore(
    b: &Bicycle,
    model: Option<String>,
    speeds: Speeds,
    band: (f64, f64),
    speed: f64,
    arrays: &mut Vec<f64>,
) -> Result<ExploreAnswer, ExploreError> {
    let bicycle = bicycle_answer(b, model.as_deref()).map_err(ExploreError::Bicycle)?;
    let opts = EigenOptions {
        model,
        speeds,
        standard_deviations: false,
        critical_speeds: true,
    };
    let job = EigenJob::new(b, &opts).map_err(ExploreError::Eig)?;
    let eig = eig_arrays(&job, arrays).map_err(ExploreError::Eig)?;
    // As `stability` checks its range and finds them (its standard
    // deviations of the speeds, which the page does not show, are left
    // out). The diagram's critical speeds were found by the same search on
    // the speeds' range (`EigenJob::new`): on the same range, its answer.
    let (lo, hi) = band;
    let searched = match &opts.speeds {
        Speeds::Range { count, .. } => {
            let first = opts.speeds.at(0);
            (first, opts.speeds.at(count - 1).max(first + 1e-9)) == (lo, hi)
        }
        Speeds::List(_) => false,
    };
    let stable_intervals = if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
        None
    } else if searched {
        job.critical.as_ref().map(|c| c.stable_intervals.clone())
    } else {
        b.linear_with(opts.model.as_deref())
            .ok()
            .and_then(|lin| critical_speeds_of(&lin, lo, hi).ok())
            .map(|c| c.stable_intervals)
    };
    // The slider's speed with the diagram's job: the numbers of `eig` at
    // that speed alone, without a second linearization and labelling of
    // the diagram's first speed.
    let at_speed = job.point_at(speed).ok();
    Ok(ExploreAnswer {
        bicycle,
        eig,
        stable_intervals,
        at_speed,
    })
}
