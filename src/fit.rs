//! `bikedyn fit`: measured weave eigenvalues from raw logs (thesis-style run
//! sets and TU Delft kick logs), with the model's prediction when a bicycle
//! is given.

use crate::bicycle::Bicycle;
use anyhow::{Context, Result};
use bikedyn_runtime::experiment::{
    self,
    angles::{AngleMethod, Calibration},
    compare, read, Input, KickFit, PipelineOptions, RunError, RunReport,
};
use bikedyn_runtime::CanonicalMatrices;
use clap::Args;
use serde_json::{json, Value};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Arguments of `bikedyn fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// Set folders (all runs), run folders, TU Delft log files, or folders of logs.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Bicycle for the prediction and the frame pitch at rest (built-in name
    /// or parameter file). Without it the thesis bicycle's frame pitch is used
    /// and no prediction is made.
    #[arg(long)]
    pub bike: Option<String>,
    /// JSON output (one entry per kick).
    #[arg(long)]
    pub json: bool,
    /// Write plots (responses with speed, continuation diagram) to this folder.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Angle method: direct (default) or thesis (eq. 87-93).
    #[arg(long, default_value = "direct")]
    pub angles: String,
    /// Keep the nominal clock offset instead of estimating it.
    #[arg(long)]
    pub nominal_clock: bool,
}

/// Everything `fit` found: reports per run and errors per skipped run.
pub struct FitOutcome {
    /// Processed runs.
    pub reports: Vec<RunReport>,
    /// Skipped runs with the reason.
    pub errors: Vec<String>,
    /// Canonical matrices of the bicycle, when given.
    pub canonical: Option<CanonicalMatrices>,
    /// Calibration of each set (folder and estimate).
    pub calibrations: Vec<(PathBuf, Calibration)>,
}

/// Run the pipeline on the inputs.
pub fn run_fit(args: &FitArgs) -> Result<FitOutcome> {
    let bike = args.bike.as_deref().map(Bicycle::resolve).transpose()?;
    // A bicycle with effect parameters has no canonical form (identify
    // passes such bicycles for the frame pitch): no prediction then.
    let canonical = match bike.as_ref().map(|b| b.canonical()) {
        Some(Err(crate::bicycle::BicycleError::NotCanonical { .. })) | None => None,
        Some(r) => Some(r?),
    };
    let pitch_bike = match &bike {
        Some(b) => b.clone(),
        None => Bicycle::resolve("thesis")?,
    };
    let frame_pitch = pitch_bike
        .thesis()?
        .frame_pitch()
        .with_context(|| format!("frame pitch of {}", pitch_bike.name))?;
    let angle_method = match args.angles.as_str() {
        "direct" => AngleMethod::Direct,
        "thesis" => AngleMethod::Thesis,
        other => anyhow::bail!("--angles {other}: expected direct or thesis"),
    };
    let opt = PipelineOptions {
        angle_method,
        frame_pitch,
        refine_clock: !args.nominal_clock,
        ..PipelineOptions::default()
    };
    let mut inputs = Vec::new();
    let mut errors = Vec::new();
    for p in &args.inputs {
        match experiment::classify(p) {
            Ok(i) => inputs.extend(i),
            Err(e) => errors.push(e.to_string()),
        }
    }
    let total: usize = inputs
        .iter()
        .map(|i| match i {
            Input::Set { runs, .. } => runs.len(),
            Input::Log(_) => 1,
        })
        .sum();
    let bar = indicatif::ProgressBar::new(total as u64);
    if !(std::io::stderr().is_terminal() && total > 3) {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let tick = || bar.inc(1);
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
                    continue;
                }
                let cal = args.calibration.clone().or(calibration);
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
    bar.finish_and_clear();
    Ok(FitOutcome {
        reports,
        errors,
        canonical,
        calibrations,
    })
}

fn pair(x: [f64; 2]) -> Value {
    json!([x[0], x[1]])
}

/// JSON entry of one kick (schema in README, "Measured runs").
pub fn kick_json(k: &KickFit, canonical: Option<&CanonicalMatrices>) -> Value {
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
    if let Some(c) = canonical {
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
    let Some(c) = &out.canonical else { return Vec::new() };
    let mut rows = Vec::new();
    for r in &out.reports {
        for k in &r.kicks {
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
    bikedyn_runtime::output::format_table(&header, &rows)
}

/// The `fit` command: prints the table or JSON, writes plots; `Ok(false)`
/// when some run was skipped (its error is on stderr; the others are output).
pub fn command(args: &FitArgs) -> Result<bool> {
    let out = run_fit(args)?;
    for e in &out.errors {
        eprintln!("skipped: {e}");
    }
    for r in &out.reports {
        for n in &r.notes {
            eprintln!("{}: {n}", r.run.display());
        }
        for g in &r.gaps {
            eprintln!("{g}");
        }
        if r.renormalised.iter().any(|&n| n > 0) {
            eprintln!(
                "{}: normalised {} frame and {} handlebar quaternions",
                r.run.display(),
                r.renormalised[0],
                r.renormalised[1]
            );
        }
    }
    if args.json {
        eprint!("{}", calibration_text(&out));
        let list: Vec<Value> = out
            .reports
            .iter()
            .flat_map(|r| r.kicks.iter())
            .map(|k| kick_json(k, out.canonical.as_ref()))
            .collect();
        println!("{}", serde_json::to_string_pretty(&list)?);
    } else {
        print!("{}", calibration_text(&out));
        print!("{}", kicks_table(&out));
        let rows = residuals(&out);
        if !rows.is_empty() {
            println!("\nmeasured against predicted weave eigenvalue (z = difference / standard error)");
            print!("{}", compare::format_residuals(&rows));
        }
    }
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        crate::fit::plots(&out, dir)?;
    }
    Ok(out.errors.is_empty())
}

/// Response plots (one per kick) and, with a bicycle, the continuation
/// diagram with the measured eigenvalues.
pub fn plots(out: &FitOutcome, dir: &Path) -> Result<()> {
    use bikedyn_runtime::experiment::plot as xplot;
    for r in &out.reports {
        let stem = r
            .run
            .file_stem()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "run".into());
        for (i, k) in r.kicks.iter().enumerate() {
            let path = dir.join(format!("{stem}_kick{:02}.svg", i + 1));
            xplot::plot_response(&path, k)?;
        }
    }
    let kicks: Vec<&KickFit> = out.reports.iter().flat_map(|r| r.kicks.iter()).collect();
    if let Some(c) = &out.canonical {
        xplot::plot_measured_continuation(&dir.join("continuation_measured.svg"), c, &kicks)?;
    }
    Ok(())
}

/// `bikedyn bench` section: time to process one thesis-style run end to end
/// (read, angles, speed, clock, kick, fits) and one TU Delft log, on one
/// core. Uses `../shared` when present, else a synthetic run written to a
/// temporary folder (and no TU Delft figure).
pub fn bench_experiment(quick: bool) -> Result<()> {
    use bikedyn_runtime::experiment::angles::Calibration;
    use bikedyn_runtime::experiment::synth::{rest_trajectory, write_run, ResponseSpec, SensorModel};
    use std::time::Instant;
    let reps = if quick { 5 } else { 30 };
    println!("\n== measured runs (bikedyn fit), median of {reps}, one thread ==");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    let (run_dir, cal_dir, log) = if root.join("data/dev/run01").is_dir() {
        (
            root.join("data/dev/run01"),
            root.join("data/dev/calibration"),
            Some(root.join("realdata/tudelft_sbw_kicks/logs/eigen_normal_sil6.5n2_16.2kph.log")),
        )
    } else {
        let d = std::env::temp_dir().join(format!("bikedyn-bench-{}", std::process::id()));
        let spec = ResponseSpec::default();
        let s = SensorModel::default();
        write_run(
            &d.join("calibration"),
            "calibration",
            read::RunKind::Calibration,
            &rest_trajectory(10.0, spec.frame_pitch, 0.3),
            &s,
            1,
        )?;
        write_run(&d.join("run01"), "run01", read::RunKind::Run, &spec.trajectory(), &s, 2)?;
        (d.join("run01"), d.join("calibration"), None)
    };
    let opt = PipelineOptions::default();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let cal_run = read::read_run(&cal_dir)?;
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        std::hint::black_box(Calibration::estimate(&cal_run, opt.frame_pitch));
        times.push(t.elapsed().as_secs_f64());
    }
    println!(
        "calibration run (misalignment estimate, read excluded): {:>8.2} ms",
        1e3 * median(times)
    );
    let cal = Calibration::estimate(&cal_run, opt.frame_pitch);
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        let run = read::read_run(&run_dir)?;
        std::hint::black_box(experiment::process_thesis_run(&run, &cal, &opt));
        times.push(t.elapsed().as_secs_f64());
    }
    println!(
        "thesis-style run, end to end ({}): {:>8.2} ms",
        run_dir.display(),
        1e3 * median(times)
    );
    if let Some(log) = log.filter(|l| l.is_file()) {
        let mut times = Vec::new();
        let mut kicks = 0;
        for _ in 0..reps.min(10) {
            let t = Instant::now();
            let l = read::read_tudelft(&log)?;
            kicks = experiment::process_tudelft(&l, &opt).kicks.len();
            times.push(t.elapsed().as_secs_f64());
        }
        println!(
            "TU Delft log, end to end ({kicks} kicks, {}): {:>8.2} ms",
            log.display(),
            1e3 * median(times)
        );
    }
    Ok(())
}
