//! The main job on embedded defaults (`bikedyn report`): every built-in
//! model verified against finite differences, the canonical matrices,
//! self-stable speeds, eigenvalue tables and diagrams of the built-in
//! bicycles, and identification of the committed example set, written to
//! one folder. The command line prints what this returns.

use crate::bicycle::{Bicycle, BicycleError, BUILT_IN};
use crate::identify::{report as identify_report, IdentifyError, IdentifyRequest, Outcome, EXAMPLE_SET};
use crate::progress::OnProgress;
use bikedyn_report::output::{self, OutputError};
use bikedyn_report::plot::{plot_continuation, subject, PlotError, PlotOptions};
use bikedyn_report::staged::{FolderKind, StagedDir};
use bikedyn_runtime::eigen::{critical_speeds, eigen_sweep, CriticalSpeeds, EigenError};
use bikedyn_runtime::verify::VerifyOptions;
use bikedyn_runtime::CanonicalMatrices;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// What the main job computes and where it writes.
#[derive(Clone, Debug)]
pub struct MainReportOptions {
    /// The folder written (new, empty, or an earlier report, replaced whole).
    pub out: PathBuf,
    /// The speeds of the eigenvalue tables and diagrams (m/s; default 0 to
    /// 10 in steps of 0.01).
    pub speeds: Vec<f64>,
    /// The range searched for the weave and capsize speeds (m/s; default 0
    /// to 10).
    pub speed_range: (f64, f64),
    /// Identify the committed example set (default true).
    pub identify: bool,
}

impl MainReportOptions {
    /// The defaults, writing to `out`.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self {
            out: out.into(),
            speeds: (0..=1000).map(|i| f64::from(i) * 0.01).collect(),
            speed_range: (0.0, 10.0),
            identify: true,
        }
    }
}

/// One built-in bicycle's linear figures and the files written for it.
#[derive(Clone, Debug)]
pub struct BicycleFigures {
    /// The built-in name.
    pub name: &'static str,
    /// Its canonical matrices (benchmark form).
    pub canonical: CanonicalMatrices,
    /// Its weave and capsize speeds in the searched range.
    pub critical: CriticalSpeeds,
    /// The files written: eigenvalue table (CSV, JSON), diagrams (SVG,
    /// PNG), stability (JSON).
    pub files: Vec<PathBuf>,
}

/// The identification of the example set in the main job.
pub struct ExampleIdentification {
    /// The request run (the committed example set, defaults otherwise).
    pub request: IdentifyRequest,
    /// What identification found.
    pub outcome: Outcome,
    /// Its report folder (`identify/` in the job's folder).
    pub folder: PathBuf,
}

/// What the main job found and wrote.
pub struct MainReport {
    /// Each built-in model's verification against finite differences:
    /// `(model, passed)`.
    pub verified: Vec<(String, bool)>,
    /// The built-in bicycles' figures.
    pub bicycles: Vec<BicycleFigures>,
    /// The example set's identification (`None` when not asked).
    pub identification: Option<ExampleIdentification>,
    /// The folder written.
    pub folder: PathBuf,
}

impl MainReport {
    /// Whether every model passed its verification.
    pub fn verified(&self) -> bool {
        self.verified.iter().all(|(_, passed)| *passed)
    }
}

/// Why the main job stopped.
#[derive(Debug, Error)]
pub enum MainReportError {
    /// The output folder cannot be written, or a table could not.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
    /// A built-in bicycle could not be resolved.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// An eigenvalue computation failed.
    #[error("bicycle {bicycle}: {source}")]
    Eigen {
        bicycle: &'static str,
        #[source]
        source: EigenError,
    },
    /// A model of the registry could not be verified.
    #[error(transparent)]
    UnknownModel(#[from] crate::models::UnknownModel),
    /// The example set's identification failed.
    #[error(transparent)]
    Identify(#[from] IdentifyError),
}

/// Run the main job: the folder is written whole beside its place and
/// moved in at the end, so a failure leaves the earlier report or none.
pub fn main_report(options: &MainReportOptions, progress: OnProgress<'_>) -> Result<MainReport, MainReportError> {
    let staged = StagedDir::new(&options.out, FolderKind::Report)?;
    let out = staged.path().to_path_buf();
    let verified = crate::models::verify_models(None, &VerifyOptions::default())?
        .reports
        .into_iter()
        .map(|r| (r.model, r.passed))
        .collect();
    let mut bicycles = Vec::new();
    for &(name, _) in BUILT_IN {
        bicycles.push(bicycle_figures(name, options, &out)?);
    }
    // Close the loop on the committed example set (made by `bikedyn synth`
    // with steer damping hidden): measured eigenvalues on the continuation
    // diagram, the identified effect, before and after.
    let identification = if options.identify {
        let request = IdentifyRequest {
            inputs: vec![PathBuf::from(EXAMPLE_SET)],
            ..IdentifyRequest::default()
        };
        let outcome = crate::identify::run(&request, progress)?;
        identify_report::write_report(&outcome, &request, &out.join("identify"), &PlotOptions::default())?;
        Some((request, outcome))
    } else {
        None
    };
    staged.commit()?;
    // The staged paths now live under the target folder.
    let moved = |p: &Path| options.out.join(p.strip_prefix(&out).unwrap_or(p));
    for b in &mut bicycles {
        b.files = b.files.iter().map(|f| moved(f)).collect();
    }
    Ok(MainReport {
        verified,
        bicycles,
        identification: identification.map(|(request, outcome)| ExampleIdentification {
            request,
            outcome,
            folder: options.out.join("identify"),
        }),
        folder: options.out.clone(),
    })
}

/// One built-in bicycle's canonical matrices, critical speeds, eigenvalue
/// tables, diagrams and stability file, written into `out`.
fn bicycle_figures(
    name: &'static str,
    options: &MainReportOptions,
    out: &Path,
) -> Result<BicycleFigures, MainReportError> {
    let eigen = |source| MainReportError::Eigen { bicycle: name, source };
    let bike = Bicycle::resolve(name)?;
    let canonical = bike.canonical()?;
    let (v_min, v_max) = options.speed_range;
    let critical = critical_speeds(&canonical, v_min, v_max).map_err(eigen)?;
    let sweep = eigen_sweep(&canonical, &options.speeds).map_err(eigen)?;
    let mut files = Vec::new();
    let csv = out.join(format!("{name}_eigenvalues.csv"));
    output::save_eigen_sweep_csv(&csv, &sweep)?;
    let json = out.join(format!("{name}_eigenvalues.json"));
    output::save_eigen_sweep_json(&json, &sweep)?;
    files.extend([csv, json]);
    let opts = PlotOptions {
        y_range: Some((-10.0, 10.0)),
        subject: Some(subject(name, Some("canonical form"))),
        ..PlotOptions::default()
    };
    for ext in ["svg", "png"] {
        let path = out.join(format!("{name}_continuation.{ext}"));
        plot_continuation(&path, &sweep, Some(&critical), &opts)?;
        files.push(path);
    }
    let stability = out.join(format!("{name}_stability.json"));
    output::save_json(&stability, &output::stability_json(name, &critical))?;
    files.push(stability);
    Ok(BicycleFigures {
        name,
        canonical,
        critical,
        files,
    })
}
