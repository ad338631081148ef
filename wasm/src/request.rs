//! The requests the module answers, and their answers: each job's options
//! as JSON fields (SI units, the command line's defaults), each result the
//! library's typed result serialized.

use crate::bicycle_answer::bicycle_answer;
use crate::explore::{explore, ExploreError};
use bikedyn::bicycle::{Bicycle, BicycleError};
use bikedyn::canonical::{canonical, CanonicalOptions};
use bikedyn::eigen::{eigen_sweep, EigenJob, EigenOptions, Speeds};
use bikedyn::runtime::simulate::{InitialConditions, Inputs, SimOptions};
use bikedyn::simulate::{simulate, SimulateRequest};
use bikedyn::stability::{stability, StabilityOptions};
use bikedyn::sweep::{stability_map_row, sweep, SweepOptions, SweptParameter};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The answer to a request: the result's JSON, or an error's.
#[derive(Clone, Debug, PartialEq)]
pub enum Answer {
    /// The job's result.
    Result(String),
    /// `{"kind": ..., "message": ...}`: `request` (the request is not
    /// valid JSON or lacks a field), `bicycle` (the bicycle or a
    /// parameter, with the command line's message) or `job` (the job
    /// failed).
    Error(String),
}

/// Which bicycle, as the command line's `--bike` and Python's `Bicycle`
/// take it, then parameters changed in order.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct BicycleSpec {
    /// `benchmark` or `thesis`.
    #[serde(default)]
    builtin: Option<String>,
    /// A parameter file's text (TOML in either form, or the text form of
    /// bicycleparameters and HumanControl) and its file name.
    #[serde(default)]
    file: Option<FileText>,
    /// Named values, every benchmark or every thesis symbol (SI units).
    #[serde(default)]
    values: Option<BTreeMap<String, f64>>,
    /// `[symbol, value]` pairs set in order (thesis, benchmark or effect
    /// symbols).
    #[serde(default)]
    set: Vec<(String, f64)>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FileText {
    name: String,
    text: String,
}

/// The speeds of `eig`: a list, or `count` speeds from `start` by `step`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum SpeedsSpec {
    List(Vec<f64>),
    Range { start: f64, step: f64, count: usize },
}

impl From<SpeedsSpec> for Speeds {
    fn from(s: SpeedsSpec) -> Speeds {
        match s {
            SpeedsSpec::List(v) => Speeds::List(v),
            SpeedsSpec::Range { start, step, count } => Speeds::Range { start, step, count },
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Swept {
    symbol: String,
    values: Vec<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(tag = "job", rename_all = "snake_case", deny_unknown_fields)]
enum Request {
    /// The generated models (`bikedyn models --json`).
    Models,
    /// The bicycle's parameters in both forms, its derived geometry, its
    /// model and its TOML.
    Bicycle {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
    },
    /// `bikedyn eig --format json`, with the model and the critical speeds.
    Eig {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        speeds: SpeedsSpec,
        #[serde(default)]
        critical_speeds: bool,
        #[serde(default = "yes")]
        standard_deviations: bool,
        /// Also give the table as `bikedyn eig --format csv` writes it.
        #[serde(default)]
        csv: bool,
        /// Give each speed's mode shapes (default: yes). The explorer's
        /// diagram over speed asks without them: it draws eigenvalues and
        /// modes only, and the mode shapes were two thirds of its answer's
        /// JSON (the speed slider asks for its one speed with them).
        #[serde(default = "yes")]
        mode_shapes: bool,
        /// Give the eigenvalues and modes as columns of `f64` (no mode
        /// shapes or standard deviations; see `arrays.rs`): the explorer's
        /// diagram over speed.
        #[serde(default)]
        arrays: bool,
    },
    /// Everything the explorer's page shows of one bicycle, in one answer
    /// (`explore.rs`): the bicycle, its eigenvalues and modes over `speeds`
    /// as arrays, its self-stable speeds between `speed_min` and
    /// `speed_max`, and its eigenvalues and mode shapes at `speed`.
    Explore {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        speeds: SpeedsSpec,
        speed_min: f64,
        speed_max: f64,
        speed: f64,
    },
    /// `bikedyn stability --json`.
    Stability {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        #[serde(default)]
        speed_min: Option<f64>,
        #[serde(default)]
        speed_max: Option<f64>,
    },
    /// `bikedyn canonical --json`.
    Canonical {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        #[serde(default)]
        speeds: Vec<f64>,
    },
    /// `bikedyn sweep --format json`: one parameter, or a map over two.
    Sweep {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        parameter: Swept,
        #[serde(default)]
        second: Option<Swept>,
        #[serde(default)]
        speed_max: Option<f64>,
        #[serde(default)]
        at_speed: Option<f64>,
    },
    /// Row `row` of a stability map (a map drawn row by row, with progress).
    MapRow {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        parameter: Swept,
        second: Swept,
        row: usize,
        #[serde(default)]
        speed_max: Option<f64>,
        #[serde(default)]
        at_speed: Option<f64>,
    },
    /// A nonlinear simulation (thesis signs, SI units, as the library's
    /// `SimulateRequest`); the answer has the summary and the samples.
    Simulate {
        bicycle: BicycleSpec,
        #[serde(default)]
        model: Option<String>,
        #[serde(default)]
        free_speed: bool,
        initial: InitialConditions,
        #[serde(default)]
        inputs: Inputs,
        duration: f64,
        #[serde(default)]
        output_interval: Option<f64>,
    },
}

fn yes() -> bool {
    true
}

#[derive(Serialize)]
struct ErrorAnswer<'a> {
    kind: &'a str,
    message: String,
}

fn error(kind: &str, message: impl ToString) -> Answer {
    Answer::Error(
        serde_json::to_string(&ErrorAnswer {
            kind,
            message: message.to_string(),
        })
        .unwrap_or_default(),
    )
}

fn result(v: &impl Serialize) -> Answer {
    match serde_json::to_string(v) {
        Ok(t) => Answer::Result(t),
        Err(e) => error("job", format!("the result could not be written as JSON: {e}")),
    }
}

fn bicycle(spec: &BicycleSpec) -> Result<Bicycle, BicycleError> {
    let given = [spec.builtin.is_some(), spec.file.is_some(), spec.values.is_some()];
    if given.iter().filter(|g| **g).count() != 1 {
        return Err(BicycleError::NotFound {
            spec: "a bicycle request needs exactly one of `builtin`, `file` and `values`".into(),
        });
    }
    let mut b = if let Some(name) = &spec.builtin {
        // Only the built-in names: a module in a page has no files.
        if !matches!(name.as_str(), "benchmark" | "thesis") {
            return Err(BicycleError::NotFound { spec: name.clone() });
        }
        Bicycle::resolve(name)?
    } else if let Some(f) = &spec.file {
        Bicycle::from_file_text_in(&f.name, &f.text)?
    } else {
        let values: Vec<(String, f64, Option<f64>)> = spec
            .values
            .iter()
            .flatten()
            .map(|(k, v)| (k.clone(), *v, None))
            .collect();
        Bicycle::from_values("bicycle", &values)?
    };
    for (symbol, value) in &spec.set {
        b = b.with_parameter(symbol, *value)?;
    }
    Ok(b)
}

/// The answer to the UTF-8 JSON request `bytes` (an answer's arrays, if it
/// has any, are left out: see [`reply`]).
pub fn answer(bytes: &[u8]) -> Answer {
    reply(bytes).answer
}

/// The answer to a request, with the `f64` buffer that its `arrays` field
/// points into (empty unless the request asks for arrays).
pub struct Reply {
    /// The answer's JSON.
    pub answer: Answer,
    /// The numbers of its arrays.
    pub arrays: Vec<f64>,
}

/// The answer to the UTF-8 JSON request `bytes`, with its arrays.
pub fn reply(bytes: &[u8]) -> Reply {
    let mut arrays = Vec::new();
    let answer = answer_into(bytes, &mut arrays);
    Reply { answer, arrays }
}

fn answer_into(bytes: &[u8], arrays: &mut Vec<f64>) -> Answer {
    let request: Request = match serde_json::from_slice(bytes) {
        Ok(r) => r,
        Err(e) => return error("request", format!("the request is not one this module answers: {e}")),
    };
    match request {
        Request::Models => {
            let v: Vec<bikedyn::models::ModelRecord> = bikedyn::models::models()
                .iter()
                .map(bikedyn::models::ModelRecord::of)
                .collect();
            result(&v)
        }
        Request::Bicycle { bicycle, model } => on(&bicycle, "bicycle", |b| bicycle_answer(b, model.as_deref())),
        Request::Eig {
            bicycle,
            model,
            speeds,
            critical_speeds,
            standard_deviations,
            csv,
            mode_shapes,
            arrays: as_arrays,
        } => {
            let opts = EigenOptions {
                model,
                speeds: speeds.into(),
                standard_deviations,
                critical_speeds,
            };
            if as_arrays {
                if csv {
                    return error(
                        "request",
                        "`arrays` gives the eigenvalues and modes only: ask for `csv` without it",
                    );
                }
                // Neither standard deviations nor mode shapes go in arrays.
                let opts = EigenOptions {
                    standard_deviations: false,
                    ..opts
                };
                return on(&bicycle, "job", |b| {
                    EigenJob::new(b, &opts).and_then(|job| crate::arrays::eig_arrays(&job, arrays))
                });
            }
            on(&bicycle, "job", |b| {
                eigen_sweep(b, &opts).map(|r| EigAnswer {
                    model: r.model.clone(),
                    weave_speed: r.critical.as_ref().and_then(|c| c.weave_speed),
                    capsize_speed: r.critical.as_ref().and_then(|c| c.capsize_speed),
                    weave_real_pair_merge_speed: r.critical.as_ref().and_then(|c| c.weave_real_pair_merge),
                    csv: csv.then(|| eigen_csv(&r)),
                    points: if mode_shapes {
                        EigPoints::Full(r)
                    } else {
                        EigPoints::WithoutModeShapes(r.points.iter().map(PointWithoutModeShapes::of).collect())
                    },
                })
            })
        }
        Request::Explore {
            bicycle: spec,
            model,
            speeds,
            speed_min,
            speed_max,
            speed,
        } => match bicycle(&spec) {
            Err(e) => error("bicycle", e),
            Ok(b) => match explore(&b, model, speeds.into(), (speed_min, speed_max), speed, arrays) {
                Ok(r) => result(&r),
                Err(ExploreError::Bicycle(e)) => error("bicycle", e),
                Err(ExploreError::Eig(e)) => error("job", e),
            },
        },
        Request::Stability {
            bicycle,
            model,
            speed_min,
            speed_max,
        } => {
            let d = StabilityOptions::default();
            let opts = StabilityOptions {
                model,
                speed_min: speed_min.unwrap_or(d.speed_min),
                speed_max: speed_max.unwrap_or(d.speed_max),
                ..d
            };
            on(&bicycle, "job", |b| stability(b, &opts))
        }
        Request::Canonical { bicycle, model, speeds } => {
            on(&bicycle, "job", |b| canonical(b, &CanonicalOptions { model, speeds }))
        }
        Request::Sweep {
            bicycle,
            model,
            parameter,
            second,
            speed_max,
            at_speed,
        } => {
            let opts = sweep_options(model, parameter, second, speed_max, at_speed);
            on(&bicycle, "job", |b| {
                sweep(b, &opts, &bikedyn::runtime::sweep::no_progress)
            })
        }
        Request::MapRow {
            bicycle,
            model,
            parameter,
            second,
            row,
            speed_max,
            at_speed,
        } => {
            let opts = sweep_options(model, parameter, Some(second), speed_max, at_speed);
            on(&bicycle, "job", |b| {
                stability_map_row(b, &opts, row, &bikedyn::runtime::sweep::no_progress)
            })
        }
        Request::Simulate {
            bicycle,
            model,
            free_speed,
            initial,
            inputs,
            duration,
            output_interval,
        } => {
            let mut options = SimOptions::default();
            if let Some(dt) = output_interval {
                options.output_interval = dt;
            }
            let request = SimulateRequest {
                model,
                free_speed,
                initial,
                inputs,
                duration,
                options,
            };
            on(&bicycle, "job", |b| {
                simulate(b, &request).map(|o| SimulateAnswer {
                    summary: o.summary(),
                    roles: o
                        .simulation
                        .roles
                        .iter()
                        .map(|(role, i)| (role.describe().replace(' ', "_"), o.simulation.coordinates[*i]))
                        .collect(),
                    simulation: o.simulation,
                })
            })
        }
    }
}

/// `job` on the bicycle of `spec`: its result, or the error of the bicycle
/// (kind `bicycle`) or of the job (kind `kind`).
fn on<T: Serialize, E: std::fmt::Display>(
    spec: &BicycleSpec,
    kind: &str,
    job: impl FnOnce(&Bicycle) -> Result<T, E>,
) -> Answer {
    match bicycle(spec) {
        Err(e) => error("bicycle", e),
        Ok(b) => match job(&b) {
            Ok(r) => result(&r),
            Err(e) => error(kind, e),
        },
    }
}

fn sweep_options(
    model: Option<String>,
    parameter: Swept,
    second: Option<Swept>,
    speed_max: Option<f64>,
    at_speed: Option<f64>,
) -> SweepOptions {
    let mut o = SweepOptions::new(parameter.symbol, parameter.values);
    o.model = model;
    o.second = second.map(|s| SweptParameter::new(s.symbol, s.values));
    if let Some(v) = speed_max {
        o.speed_max = v;
    }
    o.at_speed = at_speed;
    o
}

#[derive(Serialize)]
struct EigAnswer {
    model: String,
    /// `bikedyn eig --format json`: one entry per speed (without
    /// `mode_shapes` when the request says `mode_shapes: false`).
    points: EigPoints,
    /// With `critical_speeds`: `v_w`, `v_c` and `v_d` in the speeds' range
    /// (m/s).
    weave_speed: Option<f64>,
    capsize_speed: Option<f64>,
    weave_real_pair_merge_speed: Option<f64>,
    /// With `csv`: the table of `bikedyn eig --format csv`.
    #[serde(skip_serializing_if = "Option::is_none")]
    csv: Option<String>,
}

/// The points of an `eig` answer.
#[derive(Serialize)]
#[serde(untagged)]
enum EigPoints {
    /// As `bikedyn eig --format json` writes them.
    Full(bikedyn::eigen::EigenSweepReport),
    /// The same without their mode shapes.
    WithoutModeShapes(Vec<PointWithoutModeShapes>),
}

/// An [`bikedyn::eigen::EigenAtSpeed`] without its mode shapes (the same
/// fields, names and order otherwise).
#[derive(Serialize)]
struct PointWithoutModeShapes {
    eigenvalues: [[f64; 2]; 4],
    #[serde(skip_serializing_if = "Vec::is_empty")]
    extra_eigenvalues: Vec<[f64; 2]>,
    modes: [&'static str; 4],
    #[serde(skip_serializing_if = "Option::is_none")]
    standard_deviations: Option<Vec<[f64; 2]>>,
    v: f64,
}

impl PointWithoutModeShapes {
    fn of(p: &bikedyn::eigen::EigenAtSpeed) -> Self {
        PointWithoutModeShapes {
            eigenvalues: p.eigenvalues,
            extra_eigenvalues: p.extra_eigenvalues.clone(),
            modes: p.modes,
            standard_deviations: p.standard_deviations.clone(),
            v: p.v,
        }
    }
}

/// The rows `bikedyn eig --format csv` writes, from the report's own
/// header and row functions.
fn eigen_csv(r: &bikedyn::eigen::EigenSweepReport) -> String {
    use bikedyn::report::output::{eigen_csv_header, eigen_point_csv_row_with};
    let first = r.points.first();
    let header = eigen_csv_header(
        first.map_or(0, |p| p.extra_eigenvalues.len()),
        first.is_some_and(|p| p.standard_deviations.is_some()),
    );
    let mut text = header.join(",") + "\n";
    for p in &r.points {
        text += &eigen_point_csv_row_with(&p.point, p.standard_deviations.as_deref()).join(",");
        text.push('\n');
    }
    text
}

#[derive(Serialize)]
struct SimulateAnswer {
    summary: bikedyn::simulate::SimulationSummary,
    /// The coordinate of each role (`roll`, `steer`, ...).
    roles: BTreeMap<String, &'static str>,
    simulation: bikedyn::runtime::simulate::Simulation,
}
