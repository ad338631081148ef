//! The `bikedyn` command line: parses arguments and calls the library.

use anyhow::{bail, Context, Result};
use bikedyn::bicycle::{Bicycle, BUILT_IN};
use bikedyn::runtime::eigen::{
    critical_speeds, critical_speeds_of, eigen_sweep, eigen_sweep_of, CriticalSpeeds, CrossingDirection, CrossingKind,
    LinearBicycle,
};
use bikedyn::runtime::output;
use bikedyn::runtime::plot::{plot_continuation, plot_stability_map, ImageFormat, PlotOptions};
use bikedyn::runtime::sweep::{parameter_sweep, stability_map, MapQuantity, ParamAxis, SweepOptions};
use bikedyn::runtime::verify::VerifyOptions;
use bikedyn::runtime::CanonicalMatrices;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;
use std::process::ExitCode;

mod cli_simulate;
mod cli_synth;

#[derive(Parser)]
#[command(
    name = "bikedyn",
    version,
    about = "Symbolic multibody bicycle models, generated code, linearization and stability"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Table,
    Csv,
    Json,
}

/// Quantity of a stability map.
#[derive(Clone, Copy, ValueEnum)]
enum MapArg {
    /// Width of the self-stable speed range (m/s).
    Width,
    /// Weave speed (m/s).
    Weave,
    /// Capsize speed (m/s).
    Capsize,
    /// Real part of the least stable eigenvalue at --at-speed (1/s).
    LeastStable,
}

#[derive(Clone, Copy, ValueEnum)]
enum FormName {
    Benchmark,
    Thesis,
}

/// Which bicycle to analyse, and through which model.
#[derive(Args)]
struct BikeArg {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long = "bike", default_value = "thesis")]
    spec: String,
    /// Generated model to run it through (see `bikedyn models`; default: the
    /// smallest driven-speed model with every parameter the bicycle sets).
    #[arg(long)]
    model: Option<String>,
}

/// Table/CSV/JSON output of a command.
#[derive(Args)]
struct OutputArgs {
    #[arg(long, value_enum, default_value_t = Format::Table)]
    format: Format,
    /// Write the table/CSV/JSON to this file instead of standard output.
    #[arg(long)]
    output: Option<PathBuf>,
}

#[derive(Subcommand)]
enum Command {
    /// Measured weave eigenvalues from raw logs (thesis-style run sets, TU Delft kick logs).
    Fit(bikedyn::fit::FitArgs),
    /// Close the loop: from the residual of measured runs to the missing effect, its fitted parameters, and the error before and after
    Identify(bikedyn::identify::IdentifyArgs),
    /// The main job on embedded defaults: verify the generated models, print
    /// the canonical matrices and self-stable speeds of the built-in bicycles,
    /// and write eigenvalue tables and continuation diagrams to a folder.
    Report {
        /// Output folder.
        #[arg(long, default_value = "bikedyn-report")]
        out: PathBuf,
    },
    /// List the generated models: coordinates, parameters and effects.
    Models {
        /// JSON output: a list of {name, doc, base, free_speed, effects, coordinates, parameters}.
        #[arg(long)]
        json: bool,
    },
    /// Check every generated derivative against finite differences.
    Verify {
        /// Model name (default: all models).
        #[arg(long)]
        model: Option<String>,
        /// Number of random states.
        #[arg(long, default_value_t = 20)]
        states: usize,
        /// Seed of the random states.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// JSON output.
        #[arg(long)]
        json: bool,
    },
    /// Canonical matrices M0, C1, K0, K2 (Meijaard et al. 2007 form).
    Canonical {
        #[command(flatten)]
        bike: BikeArg,
        /// Speeds START:STOP:STEP (m/s) at which to print the state-space
        /// matrices A(v), B(v) of a bicycle without canonical form.
        #[arg(long, default_value = "0:10:2")]
        speeds: String,
        #[arg(long)]
        json: bool,
    },
    /// Eigenvalues and modes over forward speed.
    Eig {
        #[command(flatten)]
        bike: BikeArg,
        /// Speeds START:STOP:STEP (m/s).
        #[arg(long, default_value = "0:10:0.5")]
        speeds: String,
        #[command(flatten)]
        out: OutputArgs,
        /// Continuation diagram (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
    },
    /// Weave and capsize speeds and the self-stable speed interval(s).
    Stability {
        #[command(flatten)]
        bike: BikeArg,
        /// Upper end of the searched speed range (m/s).
        #[arg(long, default_value_t = 10.0)]
        speed_max: f64,
        #[arg(long)]
        json: bool,
    },
    /// Stability over one parameter, or over a grid of two (a stability map).
    Sweep {
        #[command(flatten)]
        bike: BikeArg,
        /// Parameter symbol (thesis: Rt, x4, d4, ...; benchmark: c, lam, w, ...).
        #[arg(long)]
        param: String,
        /// Values START:STOP:STEP.
        #[arg(long)]
        values: String,
        /// Second parameter for a two-parameter stability map.
        #[arg(long)]
        param2: Option<String>,
        /// Values of the second parameter START:STOP:STEP.
        #[arg(long)]
        values2: Option<String>,
        /// Upper end of the searched speed range (m/s).
        #[arg(long, default_value_t = 10.0)]
        speed_max: f64,
        #[command(flatten)]
        out: OutputArgs,
        /// Stability map plot (.svg or .png), two-parameter sweeps only.
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Quantity mapped by --plot: the self-stable range width, the weave
        /// or capsize speed, or the real part of the least stable eigenvalue
        /// at --at-speed. Cells whose stable range reaches --speed-max are
        /// marked (the range is cut there).
        #[arg(long, value_enum, default_value_t = MapArg::Width)]
        map: MapArg,
        /// Speed (m/s) of --map least-stable; its value is also written to the
        /// JSON of every cell.
        #[arg(long)]
        at_speed: Option<f64>,
    },
    /// Parameter sets: show or convert between thesis and benchmark forms.
    Params {
        #[command(subcommand)]
        command: ParamsCommand,
    },
    /// Nonlinear simulation (time histories to CSV and a plot).
    Simulate(cli_simulate::SimulateArgs),
    /// Synthetic field runs: launch, release, kick, free response (trajectories and truth).
    Synth(cli_synth::SynthArgs),
    /// Print timing and operation-count figures of the generated code.
    Bench {
        /// Fewer repetitions (for a quick look).
        #[arg(long)]
        quick: bool,
        /// Instead: time a full `identify` on a 12-run synthetic set (steer
        /// damping hidden), made in a temporary folder.
        #[arg(long)]
        identify: bool,
    },
}

#[derive(Subcommand)]
enum ParamsCommand {
    /// Convert a parameter file (or built-in bicycle) to the other form (TOML on stdout).
    Convert {
        #[arg(long, value_enum)]
        to: FormName,
        /// Parameter file or built-in name.
        file: String,
        #[arg(long)]
        output: Option<PathBuf>,
    },
    /// Print a bicycle's parameters (TOML: geometry, inertia and the effect
    /// parameters of its model, each with its unit) and its validation warnings.
    Show {
        /// Built-in bicycle or parameter file (also accepted as `--bike`).
        #[arg(value_name = "FILE", conflicts_with = "bike")]
        file: Option<String>,
        #[arg(long, default_value = "thesis")]
        bike: String,
        /// Model whose effect parameters are listed (default: the one that fits).
        #[arg(long)]
        model: Option<String>,
    },
}

/// Most points a `START:STOP:STEP` range may have when all its results are
/// held in memory (sweeps, tables, plots).
const MAX_POINTS: usize = 10_000_000;
/// Most rows of a terminal table (`eig --format table`): the table is
/// aligned, so it is held in memory; CSV and JSON stream instead.
const MAX_TABLE_ROWS: usize = 100_000;
/// Most cells of a two-parameter stability map (each cell is one
/// linearization and one critical-speed search, held in memory).
const MAX_MAP_CELLS: usize = 10_000_000;
/// Most speeds of `eig` with CSV or JSON output, which streams its rows (memory
/// stays flat; the limit only bounds the run time, about 1 µs per speed).
const MAX_STREAMED_POINTS: usize = 1_000_000_000;

/// `START:STOP:STEP` (or one number) as `(start, step, count)`, with at most
/// `limit` points.
fn range_spec(s: &str, what: &str, limit: usize) -> Result<(f64, f64, usize)> {
    let parts: Vec<&str> = s.split(':').collect();
    let nums: Vec<f64> = parts
        .iter()
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .with_context(|| format!("{what}: `{p}` is not a number (expected START:STOP:STEP)"))
        })
        .collect::<Result<_>>()?;
    match nums.as_slice() {
        [x] if x.is_finite() => Ok((*x, 0.0, 1)),
        [a, b, h] if a.is_finite() && b.is_finite() && h.is_finite() && *h > 0.0 && b >= a => {
            // Count in floating point: `as usize` would saturate (and `+ 1`
            // wrap) for a tiny step such as 1e-300.
            let intervals = ((b - a) / h + 1e-9).floor();
            if intervals.is_nan() || intervals >= limit as f64 {
                bail!(
                    "{what}: `{s}` gives {} points, more than the limit of {limit} \
                     (use a larger STEP or a shorter range)",
                    output::format_significant(intervals + 1.0, 4)
                );
            }
            Ok((*a, *h, intervals as usize + 1))
        }
        _ => bail!("{what}: `{s}` must be START:STOP:STEP with STEP > 0 and STOP >= START"),
    }
}

fn parse_range(s: &str, what: &str) -> Result<Vec<f64>> {
    let (a, h, n) = range_spec(s, what, MAX_POINTS)?;
    Ok((0..n).map(|k| a + k as f64 * h).collect())
}

fn load(bike: &str) -> Result<Bicycle> {
    let b = Bicycle::resolve(bike)?;
    for w in &b.warnings {
        eprintln!("warning ({}): {w}", b.name);
    }
    Ok(b)
}

fn critical(c: &CanonicalMatrices, vmax: f64) -> Result<CriticalSpeeds> {
    Ok(critical_speeds(c, 0.0, vmax)?)
}

fn emit(text: &str, output: &Option<PathBuf>) -> Result<()> {
    match output {
        Some(p) => output::write_string_atomic(p, text)?,
        None => print!("{text}"),
    }
    Ok(())
}

fn stability_json(name: &str, c: &CriticalSpeeds) -> serde_json::Value {
    serde_json::json!({
        "bike": name,
        "weave_speed": c.weave_speed,
        "capsize_speed": c.capsize_speed,
        "weave_real_pair_merge_speed": c.weave_real_pair_merge,
        "stable_intervals": c.stable_intervals,
        "crossings": c.crossings.iter().map(|x| serde_json::json!({
            "speed": x.speed, "mode": x.mode.name(), "direction": format!("{:?}", x.direction).to_lowercase(),
            "kind": match x.kind { CrossingKind::RealRoot => "real_root", CrossingKind::ComplexPair => "complex_pair" },
            "frequency": x.frequency
        })).collect::<Vec<_>>(),
    })
}

fn stability_text(name: &str, c: &CriticalSpeeds) -> String {
    let f = |x: Option<f64>| {
        x.map(|v| format!("{v:.10} m/s"))
            .unwrap_or_else(|| "none in range".into())
    };
    let mut s = format!("bicycle: {name}\n");
    s += &format!("  weave speed v_w:   {}\n", f(c.weave_speed));
    s += &format!("  capsize speed v_c: {}\n", f(c.capsize_speed));
    s += &format!("  weave real-pair merge v_d: {}\n", f(c.weave_real_pair_merge));
    if c.stable_intervals.is_empty() {
        s += "  self-stable: never in the searched range\n";
    }
    for [lo, hi] in &c.stable_intervals {
        s += &format!("  self-stable from {lo:.4} to {hi:.4} m/s\n");
    }
    if !c.crossings.is_empty() {
        s += "  stability crossings (speed, mode, direction):\n";
    }
    for x in &c.crossings {
        let dir = match x.direction {
            CrossingDirection::Destabilizing => "becomes unstable",
            CrossingDirection::Stabilizing => "becomes stable",
        };
        let kind = match x.kind {
            CrossingKind::RealRoot => "real root through zero".to_string(),
            CrossingKind::ComplexPair => format!("oscillation, {:.4} rad/s", x.frequency),
        };
        s += &format!("    {:.10} m/s  {:<17}  {dir} ({kind})\n", x.speed, x.mode.name());
    }
    s
}

/// "c: trail (m)" from a parameter symbol, for plot axes.
fn axis_label(symbol: &str) -> String {
    use bikedyn::runtime::parameters::{BenchmarkParameters, ThesisParameters};
    match BenchmarkParameters::describe(symbol).or_else(|| ThesisParameters::describe(symbol)) {
        Some(d) => format!("{d} [{symbol}]"),
        None => symbol.to_string(),
    }
}

fn models_text(ms: &[bikedyn::registry::ModelInfo]) -> String {
    let mut s = String::new();
    for m in ms {
        s += &format!("{}\n  {}\n", m.name, m.doc);
        s += &format!(
            "  base {}, {} speed; effects: {}\n",
            m.base,
            if m.free_speed { "free" } else { "driven" },
            if m.effects.is_empty() {
                "none".to_string()
            } else {
                m.effects.join(", ")
            }
        );
        let coords: Vec<String> = m
            .coordinates
            .iter()
            .enumerate()
            .map(|(i, c)| {
                if m.independent.contains(&i) {
                    format!("{c}*")
                } else {
                    c.to_string()
                }
            })
            .collect();
        s += &format!("  coordinates (* independent): {}\n", coords.join(" "));
        let params: Vec<&str> = m.parameters.iter().map(|p| p.name).collect();
        s += &format!("  parameters: {}\n\n", params.join(" "));
    }
    s
}

/// A bicycle's parameters as TOML (its own form), followed by the effect
/// parameters of its model with their values, defaults and units.
fn params_show_text(b: &Bicycle, model: Option<&str>) -> Result<String> {
    let info = b.model(model)?;
    let mut s = b.parameters.to_toml_string();
    let effects: Vec<_> = info.parameters.iter().filter(|p| p.effect.is_some()).collect();
    s += &format!("# model: {} ({})\n", info.name, info.doc);
    if effects.is_empty() {
        s += "# this model has no effect parameters (see `bikedyn models`)\n";
    }
    for p in effects {
        let v = b.effects.get(p.name).copied().or(p.default).unwrap_or(f64::NAN);
        let line = format!("{} = {v:?}", p.name);
        s += &format!("{line:<32} # {} [effect {}]\n", p.doc, p.effect.unwrap_or(""));
    }
    Ok(s)
}

/// Canonical matrices for people: 12 significant digits relative to each
/// matrix's largest entry, no negative zero (the JSON keeps full precision).
fn canonical_text(c: &CanonicalMatrices) -> String {
    let m = |name: &str, x: &nalgebra::Matrix2<f64>| {
        let e = output::format_matrix_entries(&[x[(0, 0)], x[(0, 1)], x[(1, 0)], x[(1, 1)]], 12);
        let w = e.iter().map(String::len).max().unwrap_or(0);
        format!(
            "{name} = [[{:>w$}, {:>w$}],\n      [{:>w$}, {:>w$}]]\n",
            e[0], e[1], e[2], e[3]
        )
    };
    format!(
        "{}{}{}{}g = {}\n",
        m("M0", &c.m0),
        m("C1", &c.c1),
        m("K0", &c.k0),
        m("K2", &c.k2),
        c.g
    )
}

/// A sweep with failed cells is an error listing them (at most ten), never
/// a table with messages in it.
fn refuse_failed_cells<'a>(
    cells: impl Iterator<Item = (String, &'a bikedyn::runtime::sweep::CellResult)>,
) -> Result<()> {
    let failed: Vec<String> = cells
        .filter_map(|(at, c)| c.as_ref().err().map(|e| format!("  {at}: {}", e.message)))
        .collect();
    if failed.is_empty() {
        return Ok(());
    }
    let shown = failed.iter().take(10).cloned().collect::<Vec<_>>().join("\n");
    let more = if failed.len() > 10 {
        format!("\n  ... and {} more", failed.len() - 10)
    } else {
        String::new()
    };
    bail!(
        "{} of the sweep's designs failed, no table written:\n{shown}{more}",
        failed.len()
    )
}

/// Rows of `B = [0; M^-1]` (inputs roll and steer torque).
fn state_input_rows(minv: &nalgebra::Matrix2<f64>) -> Vec<[f64; 2]> {
    vec![
        [0.0, 0.0],
        [0.0, 0.0],
        [minv[(0, 0)], minv[(0, 1)]],
        [minv[(1, 0)], minv[(1, 1)]],
    ]
}

fn state_space_text(v: f64, a: &nalgebra::Matrix4<f64>, minv: &nalgebra::Matrix2<f64>) -> String {
    let mut s = format!("v = {v} m/s\n");
    let e: Vec<f64> = (0..4).flat_map(|i| (0..4).map(move |j| a[(i, j)])).collect();
    let e = output::format_matrix_entries(&e, 10);
    let w = e.iter().map(String::len).max().unwrap_or(0);
    for i in 0..4 {
        let open = if i == 0 { "A = [[" } else { "     [" };
        let close = if i == 3 { "]]" } else { "]," };
        s += &format!(
            "{open}{:>w$}, {:>w$}, {:>w$}, {:>w$}{close}\n",
            e[4 * i],
            e[4 * i + 1],
            e[4 * i + 2],
            e[4 * i + 3]
        );
    }
    let b: Vec<f64> = state_input_rows(minv).iter().flatten().copied().collect();
    let b = output::format_matrix_entries(&b, 10);
    let w = b.iter().map(String::len).max().unwrap_or(0);
    for i in 0..4 {
        let open = if i == 0 { "B = [[" } else { "     [" };
        let close = if i == 3 { "]]" } else { "]," };
        s += &format!("{open}{:>w$}, {:>w$}{close}\n", b[2 * i], b[2 * i + 1]);
    }
    s
}

fn canonical_json(c: &CanonicalMatrices) -> serde_json::Value {
    serde_json::json!({
        "M0": CanonicalMatrices::rows(&c.m0), "C1": CanonicalMatrices::rows(&c.c1),
        "K0": CanonicalMatrices::rows(&c.k0), "K2": CanonicalMatrices::rows(&c.k2), "g": c.g,
    })
}

fn run(cli: Cli) -> Result<bool> {
    match cli.command {
        Command::Report { out } => {
            std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
            let mut ok = true;
            for m in bikedyn::models::model_names() {
                let r = bikedyn::models::verify_model(m, &VerifyOptions::default()).expect("known model");
                println!("verify {m}: {}", if r.passed { "passed" } else { "FAILED" });
                ok &= r.passed;
            }
            let speeds = parse_range("0:10:0.01", "speeds")?;
            for (name, _) in BUILT_IN {
                let b = load(name)?;
                let c = b.canonical()?;
                let crit = critical(&c, 10.0)?;
                println!("\n{}", stability_text(name, &crit));
                println!("{}", canonical_text(&c));
                let sweep = eigen_sweep(&c, &speeds)?;
                output::save_eigen_sweep_csv(out.join(format!("{name}_eigenvalues.csv")), &sweep)?;
                output::save_eigen_sweep_json(out.join(format!("{name}_eigenvalues.json")), &sweep)?;
                let opts = PlotOptions {
                    y_range: Some((-10.0, 10.0)),
                    ..PlotOptions::default()
                };
                for ext in ["svg", "png"] {
                    plot_continuation(
                        out.join(format!("{name}_continuation.{ext}")),
                        &sweep,
                        Some(&crit),
                        &opts,
                    )?;
                }
                output::save_json(out.join(format!("{name}_stability.json")), &stability_json(name, &crit))?;
            }
            println!("wrote tables and plots to {}", out.display());
            // Close the loop on the committed example set (made by `bikedyn
            // synth` with steer damping hidden): measured eigenvalues on the
            // continuation diagram, the identified effect, before and after.
            let set = PathBuf::from(bikedyn::identify::EXAMPLE_SET);
            let args = bikedyn::identify::IdentifyArgs {
                inputs: vec![set.clone()],
                calibration: None,
                bike: "thesis".into(),
                effects: vec![],
                report: Some(out.join("identify")),
                json: false,
                folds: 4,
            };
            println!(
                "\nidentify {} (runs made by `bikedyn synth` with an effect hidden):",
                set.display()
            );
            let o = bikedyn::identify::run_identify(&args)?;
            let dir = out.join("identify");
            bikedyn::identify::write_report(&o, &args, &dir)?;
            println!("{}", bikedyn::identify::summary(&o));
            println!("report: {}", dir.join("report.md").display());
            Ok(ok)
        }
        Command::Verify {
            model,
            states,
            seed,
            json,
        } => {
            let names: Vec<&str> = match &model {
                Some(m) => vec![m.as_str()],
                None => bikedyn::models::model_names(),
            };
            let opts = VerifyOptions {
                states,
                seed,
                ..VerifyOptions::default()
            };
            let mut reports = Vec::new();
            for n in names {
                let r = bikedyn::models::verify_model(n, &opts).with_context(|| {
                    format!(
                        "unknown model `{n}` (models: {})",
                        bikedyn::models::model_names().join(", ")
                    )
                })?;
                reports.push(r);
            }
            let passed = reports.iter().all(|r| r.passed);
            if json {
                let quantities: Vec<_> = reports
                    .iter()
                    .flat_map(|r| r.quantities.iter().map(move |q| serde_json::json!({
                        "model": r.model, "name": q.name, "max_rel_error": q.max_rel_error, "tolerance": q.tolerance, "passed": q.passed
                    })))
                    .collect();
                println!(
                    "{}",
                    serde_json::to_string_pretty(&serde_json::json!({"passed": passed, "quantities": quantities}))?
                );
            } else {
                for r in &reports {
                    println!("model {} ({} random states, seed {}):", r.model, r.states, r.seed);
                    for q in &r.quantities {
                        println!(
                            "  {:<40} max rel error {:>10.3e}  tolerance {:>8.1e}  {}",
                            q.name,
                            q.max_rel_error,
                            q.tolerance,
                            if q.passed { "ok" } else { "FAIL" }
                        );
                    }
                }
                println!(
                    "{}",
                    if passed {
                        "verification passed"
                    } else {
                        "verification FAILED"
                    }
                );
            }
            Ok(passed)
        }
        Command::Models { json } => {
            let ms = bikedyn::models::models();
            if json {
                let v: Vec<_> = ms.iter().map(bikedyn::models::model_json).collect();
                println!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                print!("{}", models_text(ms));
            }
            Ok(true)
        }
        Command::Canonical {
            bike: BikeArg { spec: bike, model },
            speeds,
            json,
        } => {
            let b = load(&bike)?;
            let lin = b.linear_with(model.as_deref())?;
            match &lin.canonical {
                Some(c) => {
                    if json {
                        let mut v = canonical_json(c);
                        v["model"] = serde_json::json!(lin.model);
                        println!("{}", serde_json::to_string_pretty(&v)?);
                    } else {
                        println!("model: {}", lin.model);
                        print!("{}", canonical_text(c));
                    }
                }
                None => {
                    // Why there is no canonical form, then A(v), B(v).
                    let why = b
                        .canonical_with(model.as_deref())
                        .err()
                        .map(|e| e.to_string())
                        .unwrap_or_default();
                    let speeds = parse_range(&speeds, "--speeds")?;
                    let mut rows = Vec::new();
                    for &v in &speeds {
                        let m = lin.at_speed(v)?;
                        let a = m
                            .state_matrix()
                            .with_context(|| format!("singular mass matrix at {v} m/s"))?;
                        let minv = m.mass.try_inverse().context("singular mass matrix")?;
                        rows.push((v, a, minv));
                    }
                    if json {
                        let v: Vec<_> = rows
                            .iter()
                            .map(|(v, a, minv)| {
                                serde_json::json!({
                                    "speed": v,
                                    "A": (0..4).map(|i| (0..4).map(|j| a[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
                                    "B": state_input_rows(minv),
                                })
                            })
                            .collect();
                        let out = serde_json::json!({
                            "model": lin.model,
                            "canonical": null,
                            "why": why,
                            "state": ["roll", "steer", "roll_rate", "steer_rate"],
                            "inputs": ["roll_torque", "steer_torque"],
                            "state_space": v,
                        });
                        println!("{}", serde_json::to_string_pretty(&out)?);
                    } else {
                        println!("model: {}", lin.model);
                        println!("no canonical form: {why}");
                        println!("state-space form x' = A(v) x + B(v) u, x = [roll, steer, roll rate, steer rate] (rad, rad/s), u = [roll torque, steer torque] (N m), benchmark signs:");
                        for (v, a, minv) in &rows {
                            print!("{}", state_space_text(*v, a, minv));
                        }
                    }
                }
            }
            Ok(true)
        }
        Command::Eig {
            bike: BikeArg { spec: bike, model },
            speeds,
            out: OutputArgs { format, output: out },
            plot,
        } => {
            let b = load(&bike)?;
            // Every output is checked before any work (issue 10, point 4).
            if let Some(p) = &out {
                output::output_target(p)?;
            }
            if let Some(p) = &plot {
                ImageFormat::from_path(p)?;
                output::output_target(p)?;
            }
            let limit = match format {
                Format::Table => MAX_TABLE_ROWS,
                Format::Csv | Format::Json => MAX_STREAMED_POINTS,
            };
            let (start, step, n) = range_spec(&speeds, "--speeds", limit).map_err(|e| match format {
                Format::Table => {
                    anyhow::anyhow!(
                        "{e}; a table holds every row, --format csv or json streams up to {MAX_STREAMED_POINTS} points"
                    )
                }
                _ => e,
            })?;
            let lin = b.linear_with(model.as_deref())?;
            eprintln!("model: {}", lin.model);
            let c: &dyn LinearBicycle = &lin;
            let speed = |k: usize| start + k as f64 * step;
            let stream = |fmt: output::StreamFormat| -> Result<()> {
                match &out {
                    Some(p) => output::write_atomic(p, |w| output::stream_eigen_sweep(c, n, speed, fmt, w))?,
                    None => {
                        let mut w = std::io::BufWriter::new(std::io::stdout().lock());
                        output::stream_eigen_sweep(c, n, speed, fmt, &mut w).map_err(|e| anyhow::anyhow!(e))?;
                        std::io::Write::flush(&mut w)?;
                    }
                }
                Ok(())
            };
            match format {
                Format::Table => {
                    let speeds: Vec<f64> = (0..n).map(speed).collect();
                    emit(&output::format_eigen_table(&eigen_sweep_of(c, &speeds)?), &out)?;
                }
                Format::Csv => stream(output::StreamFormat::Csv)?,
                Format::Json => stream(output::StreamFormat::Json)?,
            }
            if let Some(p) = plot {
                // A diagram needs no more than 20,001 points: longer ranges are
                // plotted at evenly spaced speeds over the same interval.
                const PLOT_POINTS: usize = 20_001;
                let last = speed(n - 1);
                let speeds: Vec<f64> = if n <= PLOT_POINTS {
                    (0..n).map(speed).collect()
                } else {
                    (0..PLOT_POINTS)
                        .map(|k| start + (last - start) * k as f64 / (PLOT_POINTS - 1) as f64)
                        .collect()
                };
                let sweep = eigen_sweep_of(c, &speeds)?;
                let vmax = last.max(start + 1e-9);
                let crit = critical_speeds_of(c, start, vmax).ok();
                plot_continuation(&p, &sweep, crit.as_ref(), &PlotOptions::default())?;
                eprintln!("wrote {}", p.display());
            }
            Ok(true)
        }
        Command::Stability {
            bike: BikeArg { spec: bike, model },
            speed_max,
            json,
        } => {
            let b = load(&bike)?;
            let lin = b.linear_with(model.as_deref())?;
            let crit = critical_speeds_of(&lin, 0.0, speed_max)?;
            if json {
                let mut v = stability_json(&bike, &crit);
                v["model"] = serde_json::json!(lin.model);
                println!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                println!("model: {}", lin.model);
                print!("{}", stability_text(&bike, &crit));
            }
            Ok(true)
        }
        Command::Sweep {
            bike: BikeArg { spec: bike, model },
            param,
            values,
            param2,
            values2,
            speed_max,
            out: OutputArgs { format, output: out },
            plot,
            map,
            at_speed,
        } => {
            let b = load(&bike)?;
            // Every output is checked before any work (issue 10, point 4).
            if let Some(p) = &out {
                output::output_target(p)?;
            }
            if let Some(p) = &plot {
                ImageFormat::from_path(p)?;
                output::output_target(p)?;
            }
            let quantity = match map {
                MapArg::Width => MapQuantity::StableWidth,
                MapArg::Weave => MapQuantity::WeaveSpeed,
                MapArg::Capsize => MapQuantity::CapsizeSpeed,
                MapArg::LeastStable => MapQuantity::LeastStableRealPart,
            };
            if matches!(map, MapArg::LeastStable) && at_speed.is_none() {
                bail!("--map least-stable needs --at-speed V (m/s)");
            }
            if let Some(v) = at_speed {
                if !v.is_finite() {
                    bail!("--at-speed must be a finite speed, found {v:?}");
                }
            }
            let xs = parse_range(&values, "--values")?;
            // One model for every cell: the one that represents the design
            // with the swept parameters at their first non-zero values (a
            // sweep of c_steer from 0 runs wholly through the model with
            // steer damping), unless the user names it.
            let model: Option<String> = match model {
                Some(m) => Some(m),
                None => {
                    let pick = |b: &Bicycle, name: &str, vals: &[f64]| -> Result<Bicycle> {
                        let v = vals.iter().copied().find(|&v| v != 0.0).unwrap_or(vals[0]);
                        Ok(b.with_parameter(name, v)?)
                    };
                    let mut probe = pick(&b, &param, &xs)?;
                    if let (Some(p2), Some(v2)) = (&param2, &values2) {
                        probe = pick(&probe, p2, &parse_range(v2, "--values2")?)?;
                    }
                    Some(probe.model(None)?.name.to_string())
                }
            };
            eprintln!("model: {}", model.as_deref().unwrap_or_default());
            let opts = SweepOptions {
                probe_speed: at_speed,
                ..SweepOptions::with_speed_range(0.0, speed_max)
            };
            let text = match (param2, values2) {
                (Some(p2), Some(v2)) => {
                    let ys = parse_range(&v2, "--values2")?;
                    let cells = xs.len() as f64 * ys.len() as f64;
                    if cells > MAX_MAP_CELLS as f64 {
                        bail!(
                            "--values x --values2 gives {} x {} = {} cells, more than the limit of {MAX_MAP_CELLS} \
                             (use larger steps)",
                            xs.len(),
                            ys.len(),
                            output::format_significant(cells, 4)
                        );
                    }
                    b.with_parameter(&param, xs[0])?.with_parameter(&p2, ys[0])?;
                    let map = stability_map(
                        ParamAxis::new(param.clone(), xs),
                        ParamAxis::new(p2.clone(), ys),
                        |x, y| {
                            b.with_parameter(&param, x)
                                .and_then(|b| b.with_parameter(&p2, y))
                                .and_then(|b| b.linear_with(model.as_deref()))
                        },
                        &opts,
                    )?;
                    refuse_failed_cells(map.cells.iter().enumerate().map(|(k, c)| {
                        let (ny, x, y) = (map.y.values.len(), &map.x.values, &map.y.values);
                        (format!("{param} = {}, {p2} = {}", x[k / ny], y[k % ny]), c)
                    }))?;
                    if let Some(p) = &plot {
                        let opts = PlotOptions {
                            x_label: Some(axis_label(&param)),
                            y_label: Some(axis_label(&p2)),
                            ..PlotOptions::default()
                        };
                        plot_stability_map(p, &map, quantity, &opts)?;
                        eprintln!("wrote {}", p.display());
                    }
                    match format {
                        Format::Table => output::format_stability_map_table(&map),
                        Format::Json => serde_json::to_string_pretty(&output::stability_map_json(&map))? + "\n",
                        Format::Csv => {
                            let mut buf = Vec::new();
                            output::write_stability_map_csv(&mut buf, &map)?;
                            String::from_utf8(buf)?
                        }
                    }
                }
                (None, None) => {
                    b.with_parameter(&param, xs[0])?;
                    if plot.is_some() {
                        bail!("--plot draws a two-parameter stability map: give --param2 and --values2");
                    }
                    let s = parameter_sweep(
                        ParamAxis::new(param.clone(), xs),
                        |x| {
                            b.with_parameter(&param, x)
                                .and_then(|b| b.linear_with(model.as_deref()))
                        },
                        &opts,
                    )?;
                    refuse_failed_cells(
                        s.points
                            .iter()
                            .zip(&s.param.values)
                            .map(|(c, x)| (format!("{param} = {x}"), c)),
                    )?;
                    match format {
                        Format::Table => output::format_parameter_table(&s),
                        Format::Json => serde_json::to_string_pretty(&output::parameter_sweep_json(&s))? + "\n",
                        Format::Csv => {
                            let mut buf = Vec::new();
                            output::write_parameter_sweep_csv(&mut buf, &s)?;
                            String::from_utf8(buf)?
                        }
                    }
                }
                _ => bail!("--param2 and --values2 go together"),
            };
            emit(&text, &out)?;
            Ok(true)
        }
        Command::Params { command } => match command {
            ParamsCommand::Convert { to, file, output: out } => {
                let b = load(&file)?;
                let text = match to {
                    FormName::Benchmark => b.parameters.to_benchmark()?.to_toml_string(),
                    FormName::Thesis => b.thesis()?.to_toml_string(),
                };
                emit(&text, &out)?;
                Ok(true)
            }
            ParamsCommand::Show { file, bike, model } => {
                let b = load(file.as_deref().unwrap_or(&bike))?;
                print!("{}", params_show_text(&b, model.as_deref())?);
                // Derived geometry, whatever the form of the file (issue 10,
                // point 9), as TOML comments so the output still loads.
                let g = bikedyn::runtime::geometry::DerivedGeometry::of(&b.parameters.to_benchmark()?);
                println!("\n# Derived geometry (Meijaard et al. 2007, appendix A; benchmark axes):");
                for (sym, value, unit, what) in g.rows() {
                    println!(
                        "# {sym:<8} = {:>14} {unit:<7} {what}",
                        output::format_significant(value, 8)
                    );
                }
                Ok(true)
            }
        },
        Command::Fit(args) => bikedyn::fit::command(&args),
        Command::Identify(args) => bikedyn::identify::command(&args),
        Command::Simulate(args) => cli_simulate::run(args),
        Command::Synth(args) => cli_synth::run(args),
        Command::Bench { identify: true, .. } => {
            let dir = std::env::temp_dir().join(format!("bikedyn-bench-identify-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&dir);
            cli_synth::thesis_set(&dir, 12, 22, &["c_steer=0.25"])?;
            let args = bikedyn::identify::IdentifyArgs {
                inputs: vec![dir.clone()],
                calibration: None,
                bike: "thesis".into(),
                effects: vec![],
                report: None,
                json: false,
                folds: 4,
            };
            let t = std::time::Instant::now();
            let o = bikedyn::identify::run_identify(&args)?;
            let secs = t.elapsed().as_secs_f64();
            let _ = std::fs::remove_dir_all(&dir);
            println!("{}", bikedyn::identify::summary(&o));
            println!(
                "identify, 12-run set ({} kicks): {secs:.1} s wall clock on {} threads, {} simulations (target < 60 s on 2 cores)",
                o.segments.len(),
                rayon::current_num_threads(),
                o.identification.simulations
            );
            Ok(true)
        }
        Command::Bench { quick, .. } => {
            bikedyn::bench::run(quick)?;
            Ok(true)
        }
    }
}

/// The error and its causes, each cause once: a cause whose text the
/// message already contains (errors that print their source) is skipped.
/// Every part is cut to `MAX_PART` characters, so a junk input line is not
/// echoed whole.
fn error_message(e: &anyhow::Error) -> String {
    const MAX_PART: usize = 400;
    let mut msg = String::new();
    for cause in e.chain() {
        let mut part = cause.to_string();
        if msg.contains(&part) {
            continue;
        }
        let n = part.chars().count();
        if n > MAX_PART {
            part = part.chars().take(MAX_PART).collect::<String>() + &format!("... ({} more characters)", n - MAX_PART);
        }
        if !msg.is_empty() {
            msg += ": ";
        }
        msg += &part;
    }
    msg
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {}", error_message(&e));
            ExitCode::from(2)
        }
    }
}
