//! `bikedyn fit`: measured weave eigenvalues from raw logs (thesis-style run
//! sets and TU Delft kick logs), with the bicycle model's prediction. The
//! paths given are walked and their runs read by [`crate::runs`], and
//! processed by the runtime's pipeline (`bikedyn_runtime::experiment`).
//! Which fitted eigenvalues are measured ones is judged against that model
//! (`bikedyn_runtime::experiment::accept`), once, here: `identify` uses
//! these verdicts.

use crate::bicycle::{Bicycle, BicycleError, Linear};
use crate::capped::MAX_DATA_FILE_BYTES;
use crate::progress::{OnProgress, Progress};
use crate::registry::BuiltIn;
use crate::runs::{self, Input, InputError};
use bikedyn_report::plot::PlotError;
use bikedyn_report::staged::{FolderKind, StagedDir};
use bikedyn_runtime::experiment::{self, accept, angles::Calibration, compare, KickFit, PipelineOptions, RunReport};
// Types of the options and results of a fit, named by front ends from here.
pub use bikedyn_runtime::eigen::LinearBicycle;
pub use bikedyn_runtime::experiment::angles::AngleMethod;
pub use bikedyn_runtime::experiment::STEER_AXIS_APART;
use bikedyn_runtime::parameters::ParameterError;
use bikedyn_runtime::registry::ModelRegistry;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

mod record;
pub use record::{FailedFit, FitRecord, FormFit, KickRecord, Refusal, RefusedFit};

/// What `fit` processes and how.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    /// Set folders (all runs), run folders, TU Delft log files, or folders of logs.
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    pub calibration: Option<PathBuf>,
    /// Bicycle (built-in name or parameter file): the frame pitch at rest,
    /// the predicted weave and the bounds of the acceptance tests. `None`:
    /// the built-in thesis bicycle for thesis-format runs; TU Delft logs
    /// need one ([`BikeRequired`]).
    pub bike: Option<String>,
    /// How roll and steer are computed from the orientations (default: direct).
    pub angles: AngleMethod,
    /// Keep the nominal clock offset instead of estimating it.
    pub nominal_clock: bool,
}

/// Inputs that are not thesis-format runs (TU Delft logs, an eigenvalue
/// table) and no bicycle: the built-in thesis bicycle is the default of
/// thesis-format runs only, since these came from another bicycle.
#[derive(Debug, Error)]
#[error(
    "give the bicycle with --bike FILE (Python: bike=): the built-in thesis bicycle is the default of thesis-format runs only, and these are not: {}",
    inputs.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
)]
pub struct BikeRequired {
    /// The inputs that need it.
    pub inputs: Vec<PathBuf>,
}

/// The bicycle of a fit or an identification on `inputs`: the one given,
/// else the built-in thesis bicycle when every input is a set of
/// thesis-format runs; TU Delft logs need one.
pub fn bicycle_for<'a>(bike: Option<&'a str>, inputs: &[Input]) -> Result<&'a str, BikeRequired> {
    if let Some(b) = bike {
        return Ok(b);
    }
    let logs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|i| match i {
            Input::Log(p) => Some(p.clone()),
            Input::Set { .. } => None,
        })
        .collect();
    if logs.is_empty() {
        Ok("thesis")
    } else {
        Err(BikeRequired { inputs: logs })
    }
}

/// Why `fit` could not run. A run that cannot be processed is not an error
/// of the whole: it is listed in [`FitOutcome::errors`].
#[derive(Debug, Error)]
pub enum FitError {
    /// Logs without a bicycle.
    #[error(transparent)]
    BikeRequired(#[from] BikeRequired),
    /// The bicycle could not be resolved or has no canonical form it should have.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The frame pitch at rest of the bicycle (from its geometry) failed.
    #[error("frame pitch of {bicycle}")]
    FramePitch {
        bicycle: String,
        #[source]
        source: ParameterError,
    },
    /// The folder of plots could not be written (see
    /// `bikedyn_report::staged`).
    #[error(transparent)]
    Output(#[from] bikedyn_report::output::OutputError),
    /// A plot could not be drawn or written.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// The same run or log was given twice (by path, or a copy with the
    /// same data files): it would be counted twice and, in identification,
    /// held out against itself.
    #[error("{} and {} are the same {what}{how}: give each run or log once", first.display(), second.display())]
    DuplicateInput {
        first: PathBuf,
        second: PathBuf,
        /// "run" or "log".
        what: &'static str,
        /// Empty for the same path, or why two paths are the same data.
        how: &'static str,
    },
}

/// A hash of the data of a run folder (every file but `run.toml`, whose
/// `kind` a copy may change) or of a log file, and the path's canonical
/// form; `None` when it cannot be read (the pipeline reports that).
fn identity(path: &Path) -> Option<(PathBuf, u64)> {
    use std::hash::{Hash, Hasher};
    let canonical = std::fs::canonicalize(path).ok()?;
    let mut h = std::hash::DefaultHasher::new();
    if canonical.is_dir() {
        let mut files: Vec<PathBuf> = std::fs::read_dir(&canonical)
            .ok()?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && p.file_name().is_some_and(|n| n != "run.toml"))
            .collect();
        files.sort();
        for f in files {
            f.file_name().hash(&mut h);
            hash_file(&f, &mut h)?;
        }
    } else {
        hash_file(&canonical, &mut h)?;
    }
    Some((canonical, h.finish()))
}

/// Hash a file's bytes a block at a time, so memory stays bounded; a file
/// above the readers' cap is hashed by its size alone (the reader refuses
/// it, from its size, before reading).
fn hash_file(path: &Path, h: &mut impl std::hash::Hasher) -> Option<()> {
    use std::io::Read;
    let mut file = std::fs::File::open(path).ok()?;
    let len = file.metadata().ok()?.len();
    h.write_u64(len);
    if len > MAX_DATA_FILE_BYTES {
        return Some(());
    }
    let mut buf = vec![0u8; 1 << 16];
    loop {
        match file.read(&mut buf) {
            Ok(0) => return Some(()),
            Ok(n) => h.write(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return None,
        }
    }
}

/// Refuse a run folder or log that the inputs name twice, by path or by
/// content (a copied run), and a calibration that is a copy of a run. One
/// calibration shared by several sets is no duplicate.
fn check_duplicates(inputs: &[Input], calibration: Option<&PathBuf>) -> Result<(), FitError> {
    let mut data: Vec<(&PathBuf, &'static str)> = Vec::new();
    let mut calibrations: Vec<&PathBuf> = calibration.into_iter().collect();
    for i in inputs {
        match i {
            Input::Set { runs, calibration } => {
                data.extend(runs.iter().map(|p| (p, "run")));
                calibrations.extend(calibration.iter());
            }
            Input::Log(p) => data.push((p, "log")),
        }
    }
    let mut seen: Vec<(&PathBuf, PathBuf, u64)> = Vec::new();
    for (path, what) in data {
        let Some((canonical, hash)) = identity(path) else {
            continue;
        };
        if let Some((first, first_canonical, _)) = seen.iter().find(|(_, c, h)| *c == canonical || *h == hash) {
            return Err(FitError::DuplicateInput {
                first: (*first).clone(),
                second: path.clone(),
                what,
                how: if *first_canonical == canonical {
                    ""
                } else {
                    " (the same data files: a copy)"
                },
            });
        }
        seen.push((path, canonical, hash));
    }
    for cal in calibrations {
        let Some((_, hash)) = identity(cal) else {
            continue;
        };
        if let Some((run, _, _)) = seen.iter().find(|(_, _, h)| *h == hash) {
            return Err(FitError::DuplicateInput {
                first: (*run).clone(),
                second: cal.clone(),
                what: "run",
                how: " (the same data files: the calibration is a copy of a run)",
            });
        }
    }
    Ok(())
}

/// Everything `fit` found: reports per run and errors per skipped run.
pub struct FitOutcome {
    /// Processed runs.
    pub reports: Vec<RunReport>,
    /// Skipped runs with the reason.
    pub errors: Vec<String>,
    /// Folders of a set that look like runs but have no `run.toml` (left
    /// out, said so; the exit status is unchanged, since a set may hold
    /// other folders).
    pub warnings: Vec<String>,
    /// The bicycle (as given, or `thesis`, the default for thesis-format runs).
    pub bike: String,
    /// The bicycle's linear equations through its model (any effects): the
    /// predicted weave, and the model the fitted eigenvalues are judged
    /// against.
    pub linear: Linear,
    /// Calibration of each set (folder and estimate).
    pub calibrations: Vec<(PathBuf, Calibration)>,
}

/// Run the pipeline on the inputs. `progress` is called after each run or
/// log (step `"runs"`, with the total found).
pub fn run_fit(opts: &FitOptions, progress: OnProgress<'_>) -> Result<FitOutcome, FitError> {
    run_fit_in::<BuiltIn>(opts, progress)
}

/// [`run_fit`] with the bicycle resolved against the models of registry `R`
/// (its prediction runs through one of them).
pub fn run_fit_in<R: ModelRegistry>(opts: &FitOptions, progress: OnProgress<'_>) -> Result<FitOutcome, FitError> {
    let mut inputs = Vec::new();
    let mut errors = Vec::new();
    let mut warnings = Vec::new();
    for p in &opts.inputs {
        match runs::classify_reporting(p) {
            Ok((i, left_out)) => {
                inputs.extend(i);
                warnings.extend(left_out.iter().map(|e| e.to_string()));
            }
            Err(e) => errors.push(e.to_string()),
        }
    }
    let spec = bicycle_for(opts.bike.as_deref(), &inputs)?;
    let bike = Bicycle::<R>::resolve_in(spec)?;
    // The prediction runs through the bicycle's own model, effects (damping,
    // an assist controller) included.
    let linear = bike.linear_with(None)?;
    let frame_pitch = bike.thesis()?.frame_pitch().map_err(|source| FitError::FramePitch {
        bicycle: bike.name.clone(),
        source,
    })?;
    let opt = PipelineOptions {
        angle_method: opts.angles,
        frame_pitch,
        refine_clock: !opts.nominal_clock,
        ..PipelineOptions::default()
    };
    check_duplicates(&inputs, opts.calibration.as_ref())?;
    let total: usize = inputs
        .iter()
        .map(|i| match i {
            Input::Set { runs, .. } => runs.len(),
            Input::Log(_) => 1,
        })
        .sum();
    // Runs of a set are processed in parallel: count with an atomic.
    let done = AtomicUsize::new(0);
    let tick = || {
        let done = done.fetch_add(1, Ordering::Relaxed) + 1;
        progress(Progress {
            step: "runs",
            done,
            total: Some(total),
        })
    };
    // Calibration runs that calibrate some runs given (a calibration given
    // alone is listed as skipped, not dropped silently).
    let calibrating: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|i| match i {
            Input::Set { runs, calibration } if !runs.is_empty() => calibration.clone(),
            _ => None,
        })
        .collect();
    let mut reports = Vec::new();
    let mut calibrations = Vec::new();
    for input in inputs {
        match input {
            Input::Log(path) => {
                match runs::read_tudelft(&path) {
                    Ok(log) => reports.push(experiment::process_tudelft(&log, &opt)),
                    Err(e) => errors.push(e.to_string()),
                }
                tick();
            }
            Input::Set { runs, calibration } => {
                if runs.is_empty() {
                    if let Some(c) = calibration.filter(|c| !calibrating.contains(c)) {
                        errors.push(format!(
                            "{}: a calibration run (the bicycle at rest, kind = \"calibration\" in its run.toml), with no kick to fit",
                            c.display()
                        ));
                    }
                    continue;
                }
                let cal = opts.calibration.clone().or(calibration);
                let Some(cal) = cal else {
                    let expected = runs[0].parent().unwrap_or(Path::new(".")).join("calibration");
                    for r in &runs {
                        errors.push(
                            InputError::NoCalibration {
                                run: r.clone(),
                                expected: expected.clone(),
                            }
                            .to_string(),
                        );
                    }
                    continue;
                };
                match runs::process_set(&runs, &cal, &opt, &tick) {
                    Ok((c, results)) => {
                        calibrations.push((cal.clone(), c));
                        for r in results {
                            match r {
                                Ok(rep) => reports.push(rep),
                                Err(e) => errors.push(e.to_string()),
                            }
                        }
                    }
                    Err(e) => errors.push(format!("calibration: {e}")),
                }
            }
        }
    }
    // A run or log in which no kick was found gave nothing: it is skipped
    // with the reason, so the exit status says something was left out (a
    // list of no kicks with exit 0 read as success).
    for r in &mut reports {
        if r.kicks.is_empty() {
            let note = r.notes.iter().position(|n| n.starts_with(experiment::NO_KICK));
            let why = note.map_or_else(|| experiment::NO_KICK.to_string(), |i| r.notes.remove(i));
            errors.push(format!("{}: {why}", r.run.display()));
        }
    }
    // A run whose steer axis lies apart from the set's was fitted with the
    // set's axis: say so, it may hold swapped or moved sensors.
    for r in &reports {
        for n in r.notes.iter().filter(|n| n.starts_with(experiment::STEER_AXIS_APART)) {
            warnings.push(format!("{}: {n}", r.run.display()));
        }
    }
    // Which fitted eigenvalues are measured weave eigenvalues, and which
    // form is reported, judged against the bicycle's model (the outlier
    // test over every kick of the inputs).
    accept::judge(reports.iter_mut().flat_map(|r| r.kicks.iter_mut()), Some(&linear));
    // A kick without a speed is fitted but cannot be compared with any
    // model: say so (and the exit status says something was left out).
    for r in &reports {
        for k in r.kicks.iter().filter(|k| !k.mean_speed.is_finite()) {
            errors.push(format!(
                "{} kick at {:.2} s: {}",
                k.run.display(),
                k.kick_time,
                no_speed_reason(r, k)
            ));
        }
    }
    Ok(FitOutcome {
        reports,
        errors,
        warnings,
        bike: spec.to_string(),
        linear,
        calibrations,
    })
}

/// The real cause of a kick without a speed: an empty window (the roll
/// beyond the fall angle from the start, as a lean column in degrees
/// gives), a speed record that the clock offset moves away from the IMU
/// record (a wrong `nominal_offset_s`), or the wheel sensor's silence.
fn no_speed_reason(r: &RunReport, k: &KickFit) -> String {
    use bikedyn_runtime::experiment::kicks::{KickOptions, WindowEnd};
    if k.samples.t.len() < 2 {
        let fall = KickOptions::default().fall_angle;
        // A log's lean column is read as given: in degrees it is beyond
        // the fall angle at once; a run's roll comes from the orientations.
        let hint = if r.log.is_some() {
            " (a lean column in degrees rather than radians?)"
        } else {
            " (the bicycle fell)"
        };
        return match k.window_end {
            WindowEnd::Fall => format!(
                "the free-response window is empty: the roll angle passes the fall angle ({fall} rad) at once after the kick{hint}"
            ),
            end => format!("the free-response window is empty (it ends at once: {end:?})"),
        };
    }
    if let (Some(sp), Some(off)) = (&r.speed, &r.clock_offset) {
        let (a, b) = (sp.t.first(), sp.t.last());
        if let (Some(&a), Some(&b)) = (a, b) {
            let (a, b) = (a + off.value, b + off.value);
            if b < k.window[0] || a > k.window[1] {
                return format!(
                    "the speed record, moved onto the IMU clock by the clock offset of {:.3} s, covers {a:.2} to {b:.2} s and misses the window {:.2} to {:.2} s: check [clocks] nominal_offset_s in run.toml",
                    off.value, k.window[0], k.window[1]
                );
            }
        }
    }
    NO_SPEED.to_string()
}

/// Why a kick has no predicted weave although it was fitted.
const NO_SPEED: &str = "no usable speed record in the fit window (the wheel sensor gave no speed there), so no speed to predict the weave at";

/// Residual rows (measured against predicted at the mean speed), of the
/// measured weave eigenvalues.
pub fn residuals(out: &FitOutcome) -> Vec<compare::Residual> {
    let c = &out.linear;
    let mut rows = Vec::new();
    for r in &out.reports {
        for k in &r.kicks {
            if !k.mean_speed.is_finite() {
                continue;
            }
            let (Some(f), Some(p)) = (k.measured_weave(), compare::predicted_weave(c, k.mean_speed)) else {
                continue;
            };
            rows.push(compare::Residual {
                run: k.run.display().to_string(),
                kick_time: k.kick_time,
                mean_speed: k.mean_speed,
                measured: f.eigenvalue,
                stderr: f.eigenvalue_stderr,
                predicted: p,
                z: [
                    (f.eigenvalue[0] - p[0]) / f.eigenvalue_stderr[0],
                    (f.eigenvalue[1] - p[1]) / f.eigenvalue_stderr[1],
                ],
            });
        }
    }
    rows
}

/// Misalignment and noise of each calibration, one line per sensor.
pub fn calibration_text(out: &FitOutcome) -> String {
    let mut s = String::new();
    for (dir, c) in &out.calibrations {
        let (f, h) = c.misalignment_angles();
        let d = |a: [f64; 3]| {
            format!(
                "{:+.2} {:+.2} {:+.2}",
                a[0].to_degrees(),
                a[1].to_degrees(),
                a[2].to_degrees()
            )
        };
        s += &format!(
            "calibration {}: settled from {:.2} s; misalignment (deg, about x y z): frame {}, handlebar {}{}; \
             noise at rest (deg): roll {:.3}, steer {:.3}\n",
            dir.display(),
            c.settled_from,
            d(f),
            d(h),
            if c.yaw_from_steer_axis {
                " (about the vertical from the observed steer axis)"
            } else {
                " (none about the vertical: no steer motion seen)"
            },
            c.noise.0.to_degrees(),
            c.noise.1.to_degrees()
        );
    }
    s
}

/// Text table of the kicks: the measured weave eigenvalues, and for the
/// others the test they failed ([`refused_text`] says why in full).
pub fn kicks_table(out: &FitOutcome) -> String {
    use bikedyn_report::experiment::accept::rejected_label;
    let header: Vec<String> = [
        "run",
        "kick t (s)",
        "window (s)",
        "v (m/s)",
        "weave",
        "stderr",
        "r2",
        "form",
        "clock offset (s)",
        "verdict",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut rows = Vec::new();
    for r in &out.reports {
        for k in &r.kicks {
            let (ev, se, r2, form) = match k.measured_weave() {
                Some(f) => (
                    format!("{:.3}{:+.3}i", f.eigenvalue[0], f.eigenvalue[1]),
                    format!("{:.3}, {:.3}", f.eigenvalue_stderr[0], f.eigenvalue_stderr[1]),
                    format!("{:.3}", f.r2),
                    f.form.name().to_string(),
                ),
                None => ("-".into(), "-".into(), "-".into(), "-".into()),
            };
            let verdict = match &k.rejected {
                None => "accepted".to_string(),
                Some(r) => format!("refused: {}", rejected_label(r)),
            };
            rows.push(vec![
                k.run
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                format!("{:.2}", k.kick_time),
                format!("{:.2}-{:.2}", k.window[0], k.window[1]),
                format!("{:.2}-{:.2}", k.speed_interval[0], k.speed_interval[1]),
                ev,
                se,
                r2,
                form,
                k.clock_offset
                    .map(|o| format!("{:.3} +- {:.3}", o.value, o.stderr))
                    .unwrap_or_default(),
                verdict,
            ]);
        }
    }
    bikedyn_report::output::format_table(&header, &rows)
}

/// One line per kick whose fitted eigenvalue is not a measured weave
/// eigenvalue, with the test it failed and its numbers.
pub fn refused_text(out: &FitOutcome) -> String {
    use bikedyn_report::experiment::accept::rejected_text;
    let mut s = String::new();
    for k in out.reports.iter().flat_map(|r| &r.kicks) {
        let Some(r) = &k.rejected else { continue };
        let fit = k
            .chosen_fit()
            .map(|f| format!(" (fit {:.3}{:+.3}i, r2 {:.3})", f.eigenvalue[0], f.eigenvalue[1], f.r2))
            .unwrap_or_default();
        s += &format!(
            "refused: {} kick at {:.2} s{fit}: {}\n",
            k.run.display(),
            k.kick_time,
            rejected_text(r)
        );
    }
    s
}

/// For how many kicks the speed-varying form is the chosen one, and how
/// many had a speed-varying fit that failed its tests, by test.
pub fn speed_form_text(out: &FitOutcome) -> String {
    use bikedyn_report::experiment::accept::speed_form_label;
    let kicks: Vec<&KickFit> = out.reports.iter().flat_map(|r| &r.kicks).collect();
    let kept = kicks
        .iter()
        .filter(|k| k.chosen_fit().is_some_and(|f| f.form.speed_varying()))
        .count();
    let mut by: Vec<(&str, usize)> = Vec::new();
    for r in kicks.iter().filter_map(|k| k.speed_form.as_ref()) {
        match by.iter_mut().find(|(l, _)| *l == speed_form_label(r)) {
            Some((_, n)) => *n += 1,
            None => by.push((speed_form_label(r), 1)),
        }
    }
    let refused: usize = by.iter().map(|(_, n)| n).sum();
    let mut s = format!("speed-varying form chosen for {kept} of {} kicks", kicks.len());
    if refused > 0 {
        let list: Vec<String> = by.iter().map(|(l, n)| format!("{l}: {n}")).collect();
        s += &format!(
            "; refused for {refused} ({}; reasons in --json, speed_varying_refused)",
            list.join(", ")
        );
    }
    s + "\n"
}

/// Response plots (one per kick) and the continuation diagram with the
/// measured eigenvalues, in the folder `dir`, each as SVG and PNG. The
/// folder is written whole beside its place and moved in (a kill leaves the
/// earlier plots or the new ones); it must be new, empty or earlier plots of
/// `fit` (`bikedyn_report::staged`). The axis limits of `opts` apply to the
/// continuation diagram only; its subject gets the model's name there.
pub fn plots(out: &FitOutcome, dir: &Path, opts: &bikedyn_report::plot::PlotOptions) -> Result<(), FitError> {
    let staged = StagedDir::new(dir, FolderKind::FitPlots)?;
    plots_into(out, staged.path(), opts)?;
    Ok(staged.commit()?)
}

/// [`plots`] into an existing folder `dir`, for a caller that stages the
/// folder itself (with more files in it).
pub fn plots_into(out: &FitOutcome, dir: &Path, opts: &bikedyn_report::plot::PlotOptions) -> Result<(), FitError> {
    use bikedyn_report::experiment::plot as xplot;
    use bikedyn_report::plot::PlotOptions;
    for r in &out.reports {
        let stem = r
            .run
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into());
        let response = PlotOptions {
            x_range: None,
            y_range: None,
            ..opts.clone()
        };
        for (i, k) in r.kicks.iter().enumerate() {
            for ext in ["svg", "png"] {
                let path = dir.join(format!("{stem}_kick{:02}.{ext}", i + 1));
                xplot::plot_response(&path, k, &response)?;
            }
        }
    }
    let kicks: Vec<&KickFit> = out.reports.iter().flat_map(|r| r.kicks.iter()).collect();
    let c = &out.linear;
    let o = PlotOptions {
        subject: opts.subject.as_ref().map(|s| format!("{s}, model {}", c.model)),
        ..opts.clone()
    };
    for ext in ["svg", "png"] {
        xplot::plot_measured_continuation(&dir.join(format!("continuation_measured.{ext}")), c, &kicks, &o)?;
    }
    Ok(())
}
