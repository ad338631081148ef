//! `bikedyn fit`: measured weave eigenvalues from raw logs (thesis-style run
//! sets and TU Delft kick logs), with the model's prediction when a bicycle
//! is given.

use crate::bicycle::{Bicycle, BicycleError, Linear};
use crate::progress::{OnProgress, Progress};
use crate::registry::BuiltIn;
use bikedyn_report::plot::PlotError;
use bikedyn_runtime::eigen::LinearBicycle;
use bikedyn_runtime::experiment::{
    self,
    angles::{AngleMethod, Calibration},
    compare, read, Input, KickFit, PipelineOptions, RunError, RunReport,
};
use bikedyn_runtime::parameters::ParameterError;
use bikedyn_runtime::registry::ModelRegistry;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use thiserror::Error;

/// What `fit` processes and how.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    /// Set folders (all runs), run folders, TU Delft log files, or folders of logs.
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    pub calibration: Option<PathBuf>,
    /// Bicycle for the prediction and the frame pitch at rest (built-in name
    /// or parameter file). Without it the thesis bicycle's frame pitch is used
    /// and no prediction is made.
    pub bike: Option<String>,
    /// How roll and steer are computed from the orientations (default: direct).
    pub angles: AngleMethod,
    /// Keep the nominal clock offset instead of estimating it.
    pub nominal_clock: bool,
}

/// Why `fit` could not run. A run that cannot be processed is not an error
/// of the whole: it is listed in [`FitOutcome::errors`].
#[derive(Debug, Error)]
pub enum FitError {
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
    /// A folder of plots could not be created.
    #[error("creating {}", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
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
            std::fs::read(&f).ok()?.hash(&mut h);
        }
    } else {
        std::fs::read(&canonical).ok()?.hash(&mut h);
    }
    Some((canonical, h.finish()))
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
    /// The bicycle's linear equations through its model (any effects), for
    /// the predicted weave, when a bicycle is given.
    pub linear: Option<Linear>,
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
    let bike = opts.bike.as_deref().map(Bicycle::<R>::resolve_in).transpose()?;
    // The prediction runs through the bicycle's own model, effects (damping,
    // an assist controller) included.
    let linear = bike.as_ref().map(|b| b.linear_with(None)).transpose()?;
    let pitch_bike = match &bike {
        Some(b) => b.clone(),
        None => Bicycle::<R>::resolve_in("thesis")?,
    };
    let frame_pitch = pitch_bike
        .thesis()?
        .frame_pitch()
        .map_err(|source| FitError::FramePitch {
            bicycle: pitch_bike.name.clone(),
            source,
        })?;
    let opt = PipelineOptions {
        angle_method: opts.angles,
        frame_pitch,
        refine_clock: !opts.nominal_clock,
        ..PipelineOptions::default()
    };
    let mut inputs = Vec::new();
    let mut errors = Vec::new();
    for p in &opts.inputs {
        match experiment::classify(p) {
            Ok(i) => inputs.extend(i),
            Err(e) => errors.push(e.to_string()),
        }
    }
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
                match read::read_tudelft(&path) {
                    Ok(log) => reports.push(experiment::process_tudelft(&log, &opt)),
                    Err(e) => errors.push(e.to_string()),
                }
                tick();
            }
            Input::Set { runs, calibration } => {
                if runs.is_empty() {
                    if let Some(c) = calibration.filter(|c| !calibrating.contains(c)) {
                        errors.push(format!(
                            "{}: skipped: a calibration run (the bicycle at rest, kind = \"calibration\" in its run.toml), with no kick to fit",
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
                            RunError::NoCalibration {
                                run: r.clone(),
                                expected: expected.clone(),
                            }
                            .to_string(),
                        );
                    }
                    continue;
                };
                match experiment::process_set(&runs, &cal, &opt, &tick) {
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
    // A kick without a speed is fitted but cannot be compared with any
    // model: say so (and the exit status says something was left out).
    for r in &reports {
        for k in r.kicks.iter().filter(|k| !k.mean_speed.is_finite()) {
            errors.push(format!("{} kick at {:.2} s: {NO_SPEED}", k.run.display(), k.kick_time));
        }
    }
    Ok(FitOutcome {
        reports,
        errors,
        linear,
        calibrations,
    })
}

/// Why a kick has no predicted weave although it was fitted.
const NO_SPEED: &str = "no usable speed record in the fit window (the wheel sensor gave no speed there), so no speed to predict the weave at";

fn pair(x: [f64; 2]) -> Value {
    json!([x[0], x[1]])
}

/// JSON entry of one kick (schema in README, "Measured runs").
pub fn kick_json(k: &KickFit, linear: Option<&dyn LinearBicycle>) -> Value {
    let mut v = json!({
        "run": k.run.display().to_string(),
        "kick_time": k.kick_time,
        "window": pair(k.window),
        "window_end": k.window_end,
        "speed_interval": pair(k.speed_interval),
        "mean_speed": k.mean_speed,
        "fits": k.fits.iter().map(|f| json!({
            "form": f.form.name(),
            "eigenvalue": pair(f.eigenvalue),
            "stderr": pair(f.eigenvalue_stderr),
            "slope_per_mps": f.slope.map(pair),
            "slope_stderr": f.slope_stderr.map(pair),
            "r2": f.r2, "rms": f.rms, "aic": f.aic, "bic": f.bic, "n": f.n,
        })).collect::<Vec<_>>(),
        "failed_fits": k.failed.iter().map(|(f, e)| json!({"form": f.name(), "error": e})).collect::<Vec<_>>(),
    });
    if let Some(f) = k.chosen_fit() {
        v["weave"] = pair(f.eigenvalue);
        v["weave_stderr"] = pair(f.eigenvalue_stderr);
        v["r2"] = json!(f.r2);
        v["form"] = json!(f.form.name());
    } else {
        v["weave"] = Value::Null;
        v["weave_stderr"] = Value::Null;
        v["r2"] = Value::Null;
        v["form"] = Value::Null;
    }
    if let Some(o) = k.clock_offset {
        v["clock_offset"] = json!({"value": o.value, "stderr": o.stderr, "from_data": o.from_data});
    }
    if !k.mean_speed.is_finite() {
        v["predicted_weave"] = Value::Null;
        v["no_prediction"] = json!(NO_SPEED);
    } else if let Some(c) = linear {
        let [lo, hi] = k.speed_interval;
        v["predicted_weave"] = match compare::predict(c, k.mean_speed, lo, hi) {
            Some(p) => json!({
                "at_mean_speed": pair(p.at_mean_speed),
                "real_range": pair(p.real_range),
                "imag_range": pair(p.imag_range),
            }),
            None => Value::Null,
        };
    }
    v
}

/// Residual rows (measured against predicted at the mean speed).
pub fn residuals(out: &FitOutcome) -> Vec<compare::Residual> {
    let Some(c) = &out.linear else { return Vec::new() };
    let mut rows = Vec::new();
    for r in &out.reports {
        for k in &r.kicks {
            if !k.mean_speed.is_finite() {
                continue;
            }
            let (Some(f), Some(p)) = (k.chosen_fit(), compare::predicted_weave(c, k.mean_speed)) else {
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

/// Text table of the kicks.
pub fn kicks_table(out: &FitOutcome) -> String {
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
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let mut rows = Vec::new();
    for r in &out.reports {
        for k in &r.kicks {
            let (ev, se, r2, form) = match k.chosen_fit() {
                Some(f) => (
                    format!("{:.3}{:+.3}i", f.eigenvalue[0], f.eigenvalue[1]),
                    format!("{:.3}, {:.3}", f.eigenvalue_stderr[0], f.eigenvalue_stderr[1]),
                    format!("{:.3}", f.r2),
                    f.form.name().to_string(),
                ),
                None => ("-".into(), "-".into(), "-".into(), "no fit".into()),
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
            ]);
        }
    }
    bikedyn_report::output::format_table(&header, &rows)
}

/// Response plots (one per kick) and, with a bicycle, the continuation
/// diagram with the measured eigenvalues, in `dir` (created), each as SVG
/// and PNG. The axis limits of `opts` apply to the continuation diagram
/// only; its subject gets the model's name there.
pub fn plots(out: &FitOutcome, dir: &Path, opts: &bikedyn_report::plot::PlotOptions) -> Result<(), FitError> {
    use bikedyn_report::experiment::plot as xplot;
    use bikedyn_report::plot::PlotOptions;
    std::fs::create_dir_all(dir).map_err(|source| FitError::CreateDir {
        path: dir.to_path_buf(),
        source,
    })?;
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
    if let Some(c) = &out.linear {
        let o = PlotOptions {
            subject: opts.subject.as_ref().map(|s| format!("{s}, model {}", c.model)),
            ..opts.clone()
        };
        for ext in ["svg", "png"] {
            xplot::plot_measured_continuation(&dir.join(format!("continuation_measured.{ext}")), c, &kicks, &o)?;
        }
    }
    Ok(())
}
