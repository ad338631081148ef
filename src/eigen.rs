//! The `eig` job: a bicycle's eigenvalues over forward speed, each labelled
//! with its mode (weave, capsize, castering, ...) and its mode shape (roll
//! and steer amplitude and phase), with the standard deviations that the
//! parameter file's `+/-` values imply (first order, exact derivatives).
//!
//! The command line and Python call [`eigen_sweep`], or [`EigenJob`] to
//! have the speeds' points one block at a time (memory flat in the number
//! of speeds), and print or convert the typed result; the JSON of
//! `bikedyn eig --format json` is the serialization of
//! [`EigenSweepReport`], one [`EigenAtSpeed`] per speed.

use crate::bicycle::{Bicycle, BicycleError, Linear};
use crate::registry::ModelRegistry;
use crate::sensitivity::EigenvalueSpread;
use bikedyn_report::output::{mode_shape, ordered_indices, output_order, ModeShape};
use bikedyn_runtime::eigen::{
    critical_speeds_of, eigen_sweep_of, eigenvalue_sweep_of, eigenvalues_of, CriticalSpeeds, EigenError, EigenPoint,
    EigenSweep, LabelledEigenvalues, LinearBicycle,
};
use nalgebra::Complex;
use rayon::prelude::*;
use serde::Serialize;

/// The speeds of the `eig` job (m/s).
#[derive(Clone, Debug, PartialEq)]
pub enum Speeds {
    /// `count` evenly spaced speeds `start + k * step`, `k = 0 .. count`
    /// (the step is not used for one speed):
    /// a long range (the command line streams up to 10^9 speeds) is never
    /// held as a list.
    Range {
        /// First speed (m/s).
        start: f64,
        /// Spacing (m/s), positive when `count > 1`.
        step: f64,
        /// Number of speeds, at least 1.
        count: usize,
    },
    /// These speeds, in this order.
    List(Vec<f64>),
}

impl Default for Speeds {
    /// 0 to 10 m/s in steps of 0.5 m/s (21 speeds), `bikedyn eig`'s
    /// default `--speeds 0:10:0.5`.
    fn default() -> Self {
        Speeds::Range {
            start: 0.0,
            step: 0.5,
            count: 21,
        }
    }
}

impl Speeds {
    /// Number of speeds.
    pub fn len(&self) -> usize {
        match self {
            Speeds::Range { count, .. } => *count,
            Speeds::List(v) => v.len(),
        }
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Speed `k` (m/s), `k < len()`.
    pub fn at(&self, k: usize) -> f64 {
        match self {
            Speeds::Range { start, step, .. } => start + k as f64 * step,
            Speeds::List(v) => v[k],
        }
    }

    /// The lowest and highest speed (m/s).
    fn bounds(&self) -> (f64, f64) {
        match self {
            Speeds::Range { count, .. } => (self.at(0), self.at(count - 1)),
            Speeds::List(v) => v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x))),
        }
    }

    fn check(&self) -> Result<(), EigenSweepError> {
        match self {
            Speeds::Range { step, count, .. } => {
                if *count == 0 {
                    return Err(EigenSweepError::NoSpeeds);
                }
                // One speed needs no step (the command line gives it 0).
                if *count > 1 && !(step.is_finite() && *step > 0.0) {
                    return Err(EigenSweepError::Step(*step));
                }
                for index in [0, count - 1] {
                    let value = self.at(index);
                    if !value.is_finite() {
                        return Err(EigenSweepError::Speed { index, value });
                    }
                }
            }
            Speeds::List(v) => {
                if v.is_empty() {
                    return Err(EigenSweepError::NoSpeeds);
                }
                if let Some(index) = v.iter().position(|x| !x.is_finite()) {
                    return Err(EigenSweepError::Speed { index, value: v[index] });
                }
            }
        }
        Ok(())
    }
}

/// What the `eig` job computes.
#[derive(Clone, Debug)]
pub struct EigenOptions {
    /// The model (default: the bicycle's default model).
    pub model: Option<String>,
    /// The speeds (default: 0 to 10 m/s in steps of 0.5 m/s).
    pub speeds: Speeds,
    /// Whether to give each eigenvalue's standard deviation from the
    /// file's `+/-` values (default: yes; nothing is computed for a
    /// bicycle without them).
    pub standard_deviations: bool,
    /// Whether to find the weave and capsize speeds between the lowest and
    /// the highest speed (default: no).
    pub critical_speeds: bool,
}

impl Default for EigenOptions {
    fn default() -> Self {
        Self {
            model: None,
            speeds: Speeds::default(),
            standard_deviations: true,
            critical_speeds: false,
        }
    }
}

/// The eigenvalues at one speed, in the stable output order: by mode
/// (weave, capsize, castering, merged pairs, other), then descending
/// imaginary part, then descending real part. Fields are in alphabetical
/// order, as `bikedyn eig --format json` has always written them.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EigenAtSpeed {
    /// The four roll-steer eigenvalues `[re, im]` (1/s).
    pub eigenvalues: [[f64; 2]; 4],
    /// The eigenvalues `[re, im]` (1/s) of a model's extra first-order
    /// states (tyre forces), by descending real part; absent for others.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extra_eigenvalues: Vec<[f64; 2]>,
    /// Each eigenvalue's mode shape: roll and steer amplitude and phase
    /// (rad), relative to roll (or to steer for a mode without roll).
    pub mode_shapes: [ModeShape; 4],
    /// Each eigenvalue's mode: `weave`, `capsize`, `castering`, a merged
    /// pair's name or `other`.
    pub modes: [&'static str; 4],
    /// Each eigenvalue's standard deviation `[re, im]` (1/s) from the
    /// file's `+/-` values, when asked and the file gives them; NaN
    /// (`null` in JSON) where an eigenvalue is double and has no
    /// derivative.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub standard_deviations: Option<Vec<[f64; 2]>>,
    /// Forward speed (m/s).
    pub v: f64,
    /// The point as computed (eigenvalues in the solver's order, with the
    /// eigenvectors), for tables, figures and Python's arrays.
    #[serde(skip)]
    pub point: EigenPoint,
}

/// The result of the `eig` job.
#[derive(Clone, Debug, Serialize)]
#[serde(transparent)]
pub struct EigenSweepReport {
    /// The generated model (not serialized: the JSON is the list of
    /// speeds, and the command line names the model on standard error).
    #[serde(skip)]
    pub model: String,
    /// One entry per speed, in the order given.
    pub points: Vec<EigenAtSpeed>,
    /// Why the standard deviations could not be computed although the file
    /// gives `+/-` values (a note for the reader; not serialized).
    #[serde(skip)]
    pub standard_deviations_missing: Option<String>,
    /// The weave and capsize speeds between the lowest and the highest
    /// speed, when asked and found.
    #[serde(skip)]
    pub critical: Option<CriticalSpeeds>,
}

impl EigenSweepReport {
    /// The points as computed, for tables and figures.
    pub fn sweep(&self) -> EigenSweep {
        EigenSweep {
            points: self.points.iter().map(|p| p.point.clone()).collect(),
        }
    }
}

/// Errors of the job.
#[derive(Debug, thiserror::Error)]
pub enum EigenSweepError {
    /// The bicycle or model.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The eigenvalues at a speed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// `speeds` holds no speed.
    #[error("speeds: no speeds given")]
    NoSpeeds,
    /// `speeds` holds a speed that is not a finite number.
    #[error("speeds[{index}] = {value} is not a finite speed (m/s)")]
    Speed {
        /// Its index.
        index: usize,
        /// The value (m/s).
        value: f64,
    },
    /// `speeds`' step is not positive and finite.
    #[error("speeds: step {0} m/s must be positive and finite")]
    Step(f64),
}

/// Speeds computed at a time by [`EigenPoints`]: memory stays flat however
/// many speeds are asked, and each speed's labels do not depend on the
/// others (every speed is labelled by continuation from the bicycle's
/// anchor speed), so blocks give what one sweep over all would.
const BLOCK: usize = 4096;

/// The `eig` job, prepared: the model linearized, the standard deviations'
/// derivatives formed and the first speed's eigenvalues computed, so that
/// nothing is written before a bicycle without an eigen analysis fails.
pub struct EigenJob {
    /// The generated model.
    pub model: &'static str,
    /// Number of extra eigenvalues per speed (a model with extra states).
    pub extra_eigenvalues: usize,
    /// Why the standard deviations could not be computed although the file
    /// gives `+/-` values.
    pub standard_deviations_missing: Option<String>,
    /// The weave and capsize speeds between the lowest and the highest
    /// speed, when asked and found (a figure is drawn without them
    /// otherwise, so a failed search is no error).
    pub critical: Option<CriticalSpeeds>,
    lin: Linear,
    speeds: Speeds,
    spread: Option<EigenvalueSpread>,
}

impl EigenJob {
    /// Prepare the job.
    pub fn new<R: ModelRegistry>(bike: &Bicycle<R>, opts: &EigenOptions) -> Result<Self, EigenSweepError> {
        opts.speeds.check()?;
        let lin = bike.linear_with(opts.model.as_deref())?;
        let (spread, standard_deviations_missing) = if opts.standard_deviations {
            match EigenvalueSpread::of(bike, opts.model.as_deref()) {
                Ok(s) => (s, None),
                Err(e) => (None, Some(e.to_string())),
            }
        } else {
            (None, None)
        };
        let extra_eigenvalues = eigen_sweep_of(&lin, &[opts.speeds.at(0)])?.points[0]
            .extra_eigenvalues
            .len();
        let critical = if opts.critical_speeds {
            let (lo, hi) = opts.speeds.bounds();
            // One speed: the search needs a range, however short.
            critical_speeds_of(&lin, lo, hi.max(lo + 1e-9)).ok()
        } else {
            None
        };
        Ok(EigenJob {
            model: lin.model,
            extra_eigenvalues,
            standard_deviations_missing,
            critical,
            lin,
            speeds: opts.speeds.clone(),
            spread,
        })
    }

    /// The point at one more speed `v` (m/s) with this job's bicycle,
    /// model and standard deviations: what a job of `v` alone gives, without
    /// linearizing and labelling the first speed again (the explorer asks
    /// for the slider's speed after every edit beside the diagram's).
    pub fn point_at(&self, v: f64) -> Result<EigenAtSpeed, EigenSweepError> {
        Speeds::List(vec![v]).check()?;
        let mut s = eigen_sweep_of(&self.lin, &[v])?;
        Ok(self.at_speed(s.points.remove(0)))
    }

    /// Whether the points carry standard deviations.
    pub fn standard_deviations(&self) -> bool {
        self.spread.is_some()
    }

    /// The points, speed by speed, computed a block at a time.
    pub fn points(&self) -> EigenPoints<'_> {
        EigenPoints {
            job: self,
            next: 0,
            block: Vec::new().into_iter(),
            failed: false,
        }
    }

    /// All points at once.
    pub fn report(self) -> Result<EigenSweepReport, EigenSweepError> {
        let points = self.points().collect::<Result<Vec<_>, _>>()?;
        Ok(EigenSweepReport {
            model: self.model.to_string(),
            points,
            standard_deviations_missing: self.standard_deviations_missing,
            critical: self.critical,
        })
    }

    fn at_speed(&self, p: EigenPoint) -> EigenAtSpeed {
        let idx = ordered_indices(&p);
        let EigenvaluesAtSpeed {
            v,
            eigenvalues,
            modes,
            extra_eigenvalues,
        } = EigenvaluesAtSpeed::of(&LabelledEigenvalues::from(&p), &idx);
        let standard_deviations = self.spread.as_ref().map(|s| s.of_eigenvalues(p.v, &eigenvalues));
        EigenAtSpeed {
            eigenvalues,
            extra_eigenvalues,
            mode_shapes: idx.map(|k| mode_shape(&p.eigenvectors[k])),
            modes,
            standard_deviations,
            v,
            point: p,
        }
    }

    /// Every speed's eigenvalues and modes alone, in the order and with the
    /// values of [`EigenJob::points`], without mode shapes or standard
    /// deviations: a diagram over speed draws no more (the browser's, where
    /// the mode shapes were a sixth of its time, 2026-11-29, and the
    /// eigenvectors they come from a tenth of what was left, 2026-11-30).
    pub fn eigenvalues_and_modes(&self) -> Result<Vec<EigenvaluesAtSpeed>, EigenSweepError> {
        Ok(self
            .labelled_eigenvalues()?
            .iter()
            .map(|p| EigenvaluesAtSpeed::of(p, &output_order(&p.modes, &p.eigenvalues)))
            .collect())
    }

    /// Every speed's eigenvalues and mode labels as the eigen analysis
    /// gives them (in its order: [`output_order`] gives the output order),
    /// the numbers of [`EigenJob::eigenvalues_and_modes`] without a copy
    /// of each speed's: the browser's diagram writes them straight into
    /// its arrays (the copies, with their modes' names compared as text,
    /// were a tenth of its request, 2026-12-02).
    pub fn labelled_eigenvalues(&self) -> Result<Vec<LabelledEigenvalues>, EigenSweepError> {
        let n = self.speeds.len();
        let speeds_of =
            |start: usize| -> Vec<f64> { (start..(start + BLOCK).min(n)).map(|k| self.speeds.at(k)).collect() };
        if n <= BLOCK {
            return Ok(eigenvalue_sweep_of(&self.lin, &speeds_of(0))?);
        }
        let mut out = Vec::with_capacity(n);
        for start in (0..n).step_by(BLOCK) {
            out.extend(eigenvalue_sweep_of(&self.lin, &speeds_of(start))?);
        }
        Ok(out)
    }
}

/// A speed's eigenvalues and modes, as in [`EigenAtSpeed`] (the same order).
#[derive(Clone, Debug, PartialEq)]
pub struct EigenvaluesAtSpeed {
    /// Forward speed (m/s).
    pub v: f64,
    /// The four roll-steer eigenvalues `[re, im]` (1/s).
    pub eigenvalues: [[f64; 2]; 4],
    /// Each eigenvalue's mode.
    pub modes: [&'static str; 4],
    /// The eigenvalues `[re, im]` (1/s) of a model's extra first-order
    /// states; empty for others.
    pub extra_eigenvalues: Vec<[f64; 2]>,
}

impl EigenvaluesAtSpeed {
    /// A speed's, in the output order `idx` ([`output_order`]).
    fn of(p: &LabelledEigenvalues, idx: &[usize; 4]) -> Self {
        EigenvaluesAtSpeed {
            v: p.v,
            eigenvalues: idx.map(|k| [p.eigenvalues[k].re, p.eigenvalues[k].im]),
            modes: idx.map(|k| p.modes[k].name()),
            extra_eigenvalues: p.extra_eigenvalues.iter().map(|z| [z.re, z.im]).collect(),
        }
    }
}

/// The points of an [`EigenJob`], in the order of its speeds; after an
/// error, none.
pub struct EigenPoints<'a> {
    job: &'a EigenJob,
    next: usize,
    block: std::vec::IntoIter<EigenAtSpeed>,
    failed: bool,
}

impl Iterator for EigenPoints<'_> {
    type Item = Result<EigenAtSpeed, EigenSweepError>;

    fn next(&mut self) -> Option<Self::Item> {
        if let Some(p) = self.block.next() {
            return Some(Ok(p));
        }
        let n = self.job.speeds.len();
        if self.failed || self.next >= n {
            return None;
        }
        let end = (self.next + BLOCK).min(n);
        let speeds: Vec<f64> = (self.next..end).map(|k| self.job.speeds.at(k)).collect();
        self.next = end;
        match eigen_sweep_of(&self.job.lin, &speeds) {
            Ok(s) => {
                let block: Vec<EigenAtSpeed> = s.points.into_iter().map(|p| self.job.at_speed(p)).collect();
                self.block = block.into_iter();
                self.block.next().map(Ok)
            }
            Err(e) => {
                self.failed = true;
                Some(Err(e.into()))
            }
        }
    }
}

/// The `eig` job: `bike`'s eigenvalues, modes and mode shapes at every
/// speed of `opts`.
pub fn eigen_sweep<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &EigenOptions,
) -> Result<EigenSweepReport, EigenSweepError> {
    EigenJob::new(bike, opts)?.report()
}

/// Eigenvalues alone at many speeds: the fast path for large speed grids.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Eigenvalues {
    /// The generated model.
    pub model: String,
    /// Eigenvalues per speed: 4, or more for a model with extra states.
    pub per_speed: usize,
    /// `per_speed` eigenvalues `[re, im]` (1/s) per speed, speed by speed,
    /// each speed's by descending real part, then imaginary part; NaN
    /// where a speed has fewer.
    pub values: Vec<[f64; 2]>,
}

/// The eigenvalues of `bike` through `model` at `speeds` (m/s), without
/// mode labels or vectors, in parallel over the speeds.
pub fn eigenvalues<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: Option<&str>,
    speeds: &[f64],
) -> Result<Eigenvalues, EigenSweepError> {
    Speeds::List(speeds.to_vec()).check()?;
    let lin = bike.linear_with(model)?;
    let sort = |z: &mut Vec<Complex<f64>>| {
        z.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
    };
    if lin.first_order().is_some() {
        // Extra states: the sweep's spectrum, which includes them.
        let sweep = eigen_sweep_of(&lin, speeds)?;
        let k = 4 + sweep
            .points
            .iter()
            .map(|p| p.extra_eigenvalues.len())
            .max()
            .unwrap_or(0);
        let mut values = Vec::with_capacity(k * speeds.len());
        for p in &sweep.points {
            let mut z: Vec<_> = p.eigenvalues.iter().chain(&p.extra_eigenvalues).copied().collect();
            sort(&mut z);
            z.resize(k, Complex::new(f64::NAN, f64::NAN));
            values.extend(z.iter().map(|z| [z.re, z.im]));
        }
        return Ok(Eigenvalues {
            model: lin.model.to_string(),
            per_speed: k,
            values,
        });
    }
    // Chunks of speeds per task: enough work per task to outweigh the
    // scheduling.
    const CHUNK: usize = 1024;
    let rows: Vec<Result<Vec<[f64; 2]>, EigenError>> = speeds
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut out = Vec::with_capacity(4 * chunk.len());
            for &v in chunk {
                let mut z = eigenvalues_of(&lin, v)?.to_vec();
                sort(&mut z);
                out.extend(z.iter().map(|z| [z.re, z.im]));
            }
            Ok(out)
        })
        .collect();
    let mut values = Vec::with_capacity(4 * speeds.len());
    for r in rows {
        values.extend(r?);
    }
    Ok(Eigenvalues {
        model: lin.model.to_string(),
        per_speed: 4,
        values,
    })
}
