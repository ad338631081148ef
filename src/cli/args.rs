//! The command line's arguments (clap). Every command's work is in the
//! library; these types only say how it is asked for.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "bikedyn",
    version,
    about = "Symbolic multibody bicycle models, generated code, linearization and stability"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Print every parameter-file warning in full (also those of the
    /// built-in bicycles, which are known and documented).
    #[arg(long, global = true)]
    pub verbose: bool,
    /// Accept parameter files with lengths that look like millimetres (over
    /// 10 m), which are otherwise refused.
    #[arg(long, global = true)]
    pub allow_units: bool,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum Format {
    Table,
    Csv,
    Json,
}

/// Quantity of a stability map.
#[derive(Clone, Copy, ValueEnum)]
pub enum MapArg {
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
pub enum FormName {
    Benchmark,
    Thesis,
}

/// Which bicycle to analyse, and through which model.
#[derive(Args)]
pub struct BikeArg {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long = "bike", default_value = "thesis")]
    pub spec: String,
    /// Generated model to run it through (see `bikedyn models`; default: the
    /// smallest driven-speed model with every parameter the bicycle sets).
    #[arg(long)]
    pub model: Option<String>,
}

/// Table/CSV/JSON output of a command.
#[derive(Args)]
pub struct OutputArgs {
    /// Output format [default: table].
    #[arg(long, value_enum)]
    pub format: Option<Format>,
    /// JSON output: the same as `--format json` (every command with
    /// structured output takes `--json`).
    #[arg(long, conflicts_with = "format")]
    pub json: bool,
    /// Write the table/CSV/JSON to this file instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

impl OutputArgs {
    /// The format asked for (a table unless `--format` or `--json` says
    /// otherwise).
    pub fn format(&self) -> Format {
        if self.json {
            Format::Json
        } else {
            self.format.unwrap_or(Format::Table)
        }
    }
    /// Whether the output was asked for by a flag (`--format`, `--json` or
    /// `--output`) rather than by default.
    pub fn asked_for(&self) -> bool {
        self.json || self.format.is_some() || self.output.is_some()
    }
}

/// Size, resolution and axis limits of the figures a command draws.
#[derive(Args, Clone, Debug, Default)]
pub struct PlotArgs {
    /// Figure size WIDTHxHEIGHT in inches (default 8x6 for one panel, taller
    /// for stacked panels and 9x6.2 for fit and identify figures; e.g.
    /// 3.5x2.6 for a journal column), or with a unit: 16x12cm, 800x600px
    /// (pixels at 100 dpi). A size given is kept, even 8x6.
    #[arg(long, value_name = "WxH")]
    pub plot_size: Option<String>,
    /// Resolution of PNG figures in dots per inch (default 100; 300 for
    /// print): more pixels, the same figure. SVG is resolution independent.
    #[arg(long, value_name = "DPI")]
    pub dpi: Option<f64>,
    /// Horizontal axis limits A:B (e.g. --xlim 0:8).
    #[arg(long, value_name = "A:B", allow_hyphen_values = true)]
    pub xlim: Option<String>,
    /// Vertical axis limits A:B (e.g. --ylim=-10:10).
    #[arg(long, value_name = "A:B", allow_hyphen_values = true)]
    pub ylim: Option<String>,
}

#[derive(Subcommand)]
pub enum Command {
    /// Measured weave eigenvalues from raw logs (thesis-style run sets, TU Delft kick logs).
    Fit(FitArgs),
    /// Close the loop: from the residual of measured runs to the missing effect, its fitted parameters, and the error before and after
    Identify(IdentifyArgs),
    /// The main job on embedded defaults: verify the generated models, print
    /// the canonical matrices and self-stable speeds of the built-in bicycles,
    /// and write eigenvalue tables and continuation diagrams to a folder.
    Report {
        /// Output folder.
        #[arg(long, default_value = "bikedyn-report")]
        out: PathBuf,
    },
    /// The stability explorer in the browser: serve wasm/explorer/ on this
    /// machine (127.0.0.1) and print its address. Build its module first
    /// with `bash wasm/build.sh`.
    Serve {
        /// The explorer folder.
        #[arg(long, default_value = "wasm/explorer")]
        dir: PathBuf,
        /// Port on 127.0.0.1 (0: a free one).
        #[arg(long, default_value_t = 8000)]
        port: u16,
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
        /// Number of random states (1 to 100000).
        #[arg(long, default_value_t = 20, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=100_000))]
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
        #[arg(long, default_value = "0:10:2", allow_hyphen_values = true)]
        speeds: String,
        #[arg(long)]
        json: bool,
    },
    /// Eigenvalues and modes over forward speed.
    Eig {
        #[command(flatten)]
        bike: BikeArg,
        /// Speeds START:STOP:STEP (m/s).
        #[arg(long, default_value = "0:10:0.5", allow_hyphen_values = true)]
        speeds: String,
        #[command(flatten)]
        out: OutputArgs,
        /// Continuation diagram (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
        /// Root locus (.svg or .png): the eigenvalues over --speeds in the
        /// complex plane, coloured by speed.
        #[arg(long, value_name = "FILE")]
        plot_root_locus: Option<PathBuf>,
        /// Mode shapes at --speed (.svg or .png): roll and steer amplitude and
        /// phase of each mode as phasors.
        #[arg(long, value_name = "FILE", requires = "speed")]
        plot_mode_shapes: Option<PathBuf>,
        /// Speed (m/s) of --plot-mode-shapes.
        #[arg(long, allow_hyphen_values = true)]
        speed: Option<f64>,
        #[command(flatten)]
        plot_args: PlotArgs,
    },
    /// Weave and capsize speeds and the self-stable speed interval(s).
    Stability {
        #[command(flatten)]
        bike: BikeArg,
        /// Upper end of the searched speed range (m/s).
        #[arg(long, default_value_t = 10.0)]
        speed_max: f64,
        /// JSON output.
        #[arg(long)]
        json: bool,
        /// Check the first-order standard deviations of the speeds with N
        /// bicycles drawn about the file's values with its +/- standard
        /// deviations (2 to 1000000; in parallel).
        #[arg(long, value_name = "N", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(2..=1_000_000))]
        monte_carlo: Option<usize>,
        /// Seed of the --monte-carlo draws.
        #[arg(long, default_value_t = 1, requires = "monte_carlo")]
        seed: u64,
    },
    /// Stability over one parameter, or over a grid of two (a stability map).
    Sweep(SweepArgs),
    /// Exact derivatives of the weave and capsize speeds (and of the
    /// eigenvalues at --speed) with respect to every parameter: a ranked
    /// table of elasticities (% per %), CSV or JSON, and a bar chart.
    Sensitivity {
        #[command(flatten)]
        bike: BikeArg,
        /// The parameters to differentiate with respect to: benchmark or
        /// thesis symbols (default: the form the bicycle is given in).
        #[arg(long, value_enum)]
        form: Option<FormName>,
        /// Speed (m/s) at which the eigenvalues are differentiated too.
        #[arg(long, allow_hyphen_values = true)]
        speed: Option<f64>,
        /// Upper end of the speeds searched for v_w and v_c (m/s).
        #[arg(long, default_value_t = 10.0)]
        speed_max: f64,
        #[command(flatten)]
        out: OutputArgs,
        /// Bar chart of the elasticities (.svg or .png).
        #[arg(long)]
        plot: Option<PathBuf>,
        #[command(flatten)]
        plot_args: PlotArgs,
    },
    /// Frequency response at a speed: roll and steer torque to roll and
    /// steer angle, G(i omega) = C (i omega I - A)^-1 B on a log-spaced
    /// grid, as a table, CSV or JSON, and a Bode plot.
    Bode {
        #[command(flatten)]
        bike: BikeArg,
        /// Forward speed (m/s).
        #[arg(long, allow_hyphen_values = true)]
        speed: f64,
        /// Angular frequencies MIN:MAX (rad/s), log-spaced.
        #[arg(long, default_value = "0.1:100", allow_hyphen_values = true)]
        omega: String,
        /// Number of frequencies.
        #[arg(long, default_value_t = 200)]
        points: usize,
        #[command(flatten)]
        out: OutputArgs,
        /// Bode plot (.svg or .png): magnitude (dB) and phase (deg) against
        /// omega; --xlim in rad/s, --ylim the magnitude's range in dB.
        #[arg(long)]
        plot: Option<PathBuf>,
        #[command(flatten)]
        plot_args: PlotArgs,
    },
    /// Parameter sets: show or convert between thesis and benchmark forms.
    Params {
        #[command(subcommand)]
        command: ParamsCommand,
    },
    /// Nonlinear simulation (time histories to CSV and a plot).
    Simulate(SimulateArgs),
    /// Synthetic field runs: launch, release, kick, free response (trajectories and truth).
    Synth(SynthArgs),
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
pub enum ParamsCommand {
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

/// Arguments of `bikedyn fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// Set folders (all runs), run folders, TU Delft log files, or folders of logs.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Bicycle (built-in name or parameter file): the frame pitch at rest,
    /// the predicted weave and the model the fitted eigenvalues are judged
    /// against. Default: the built-in thesis bicycle for thesis-format runs;
    /// TU Delft logs need their own.
    #[arg(long)]
    pub bike: Option<String>,
    /// JSON output (one entry per kick).
    #[arg(long)]
    pub json: bool,
    /// Write plots (responses with speed, continuation diagram; SVG and PNG)
    /// to this folder.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Size and resolution of the plots; the limits apply to the
    /// continuation diagram.
    #[command(flatten)]
    pub plot_args: PlotArgs,
    /// Angle method: direct (default) or thesis (eq. 87-93).
    #[arg(long, default_value = "direct")]
    pub angles: String,
    /// Keep the nominal clock offset instead of estimating it.
    #[arg(long)]
    pub nominal_clock: bool,
}

/// Arguments of `bikedyn identify`.
#[derive(Args, Debug, Clone)]
pub struct IdentifyArgs {
    /// Set folders (all runs), run folders, or TU Delft logs (files or a
    /// folder of them).
    #[arg(required_unless_present = "eigenvalues")]
    pub inputs: Vec<PathBuf>,
    /// Instead of runs: a table of measured weave eigenvalues (CSV; columns
    /// speed m/s, real 1/s, imaginary rad/s, optionally their two standard
    /// errors; a header row in any words).
    #[arg(long, conflicts_with = "inputs")]
    pub eigenvalues: Option<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Bicycle (built-in name or parameter file); its effect parameters, if
    /// any, are part of the model before identification. Default: the
    /// built-in thesis bicycle for thesis-format runs; TU Delft logs and an
    /// eigenvalue table need their own.
    #[arg(long)]
    pub bike: Option<String>,
    /// Candidate effects to consider (comma-separated; default: every
    /// effect of the library that identification supports).
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Report folder (report.md, report.json, plots, fitted parameter file).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Print the JSON summary instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// Folds of the cross-validation over runs (2 to 1000; at most one per
    /// run or log: more are reduced to that, and the console says so).
    #[arg(long, default_value_t = 4, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(2..=1000))]
    pub folds: usize,
    /// Largest number of parameter corrections (of the parameters whose
    /// model declares an uncertainty) tried beside the effects, those that
    /// could explain most of the weave misfit first; 0: none (default:
    /// every one that could explain some of it)
    #[arg(long)]
    pub corrections: Option<usize>,
    /// Skip the search, after the library, of a dictionary of generalized
    /// forces on the roll and steer equations (what no library effect
    /// names), on the table or on the kicks' weave eigenvalues.
    #[arg(long)]
    pub no_discover: bool,
    /// Most candidates one step of the library's search fits beyond its
    /// contenders, best predicted first (a compute budget for large sets;
    /// the report lists what a step left unfitted). Default: no budget, a
    /// step that adds nothing has fitted every candidate predicted to gain.
    #[arg(long, conflicts_with = "eigenvalues", value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..))]
    pub max_fits_per_step: Option<usize>,
    /// Raise each step's bar of a consistent held-out gain with the
    /// candidates the step has fitted (a Bonferroni bar over them; the
    /// speed-decay laws keep two standard errors), against chance entries
    /// among many tries. Default: two standard errors for every candidate.
    #[arg(long, conflicts_with = "eigenvalues")]
    pub family_wise_bar: bool,
    /// Size and resolution of the report's plots; the limits apply to the
    /// continuation diagram.
    #[command(flatten)]
    pub plot_args: PlotArgs,
}

/// Arguments of `bikedyn simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long, default_value = "thesis")]
    pub bike: String,
    /// Generated model (default: the smallest model with every parameter
    /// the bicycle sets: thesis_whipple, whipple_offset when the fork mass
    /// centre is off the steer axis, rider_lean with a leaning rider, ...).
    #[arg(long)]
    pub model: Option<String>,
    /// Free forward speed (no driving constraint): needs a free-speed model.
    #[arg(long)]
    pub free_speed: bool,
    /// Forward speed of the rear contact point (m/s); imposed by a driven
    /// model, initial for a free-speed one.
    #[arg(long)]
    pub speed: f64,
    /// Initial roll (deg, positive leaning right).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub roll: f64,
    /// Initial steer (deg, positive turning left).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub steer: f64,
    /// Initial roll rate (deg/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub roll_rate: f64,
    /// Initial steer rate (deg/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub steer_rate: f64,
    /// Initial yaw (deg).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub yaw: f64,
    /// Lateral kick TIME:IMPULSE[:AHEAD:HEIGHT] (s, N s positive toward the
    /// rider's right, point m ahead of the rear contact and m above ground;
    /// default point: a saddle 0.25 m ahead, 0.95 m high). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pub kick: Vec<String>,
    /// Torque pulse roll|steer:START:DURATION:AMPLITUDE[:rect|halfsine]
    /// (s, s, N m). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pub pulse: Vec<String>,
    /// Simulated time (s).
    #[arg(long)]
    pub duration: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-8)]
    pub rtol: f64,
    /// Absolute tolerance of the integrator.
    #[arg(long, default_value_t = 1e-10)]
    pub atol: f64,
    /// Integration method: dop853 (explicit, default) or radau5 (implicit,
    /// for stiff effects such as very short tyre relaxation lengths).
    #[arg(long, default_value = "dop853")]
    pub method: String,
    /// Output sample interval (s).
    #[arg(long, default_value_t = 0.01)]
    pub dt: f64,
    /// Stop when |roll| reaches this angle (deg; 0 disables).
    #[arg(long, default_value_t = 1.0f64.to_degrees())]
    pub roll_limit: f64,
    /// Stop when |steer| reaches this angle (deg; 0 disables).
    #[arg(long, default_value_t = 1.4f64.to_degrees())]
    pub steer_limit: f64,
    /// CSV output (columns: t, coordinates, rates, speed, energies, residual).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Plot of roll, steer and speed against time (.svg or .png), with the
    /// kicks and pulses marked.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Size and resolution of the plot; --xlim is the time range, --ylim
    /// the range of the roll and steer panels.
    #[command(flatten)]
    pub plot_args: PlotArgs,
}

/// Arguments of `bikedyn synth`.
#[derive(Args)]
pub struct SynthArgs {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long, default_value = "thesis")]
    pub bike: String,
    /// Generated model (default: the free-speed variant of the smallest
    /// model with every parameter the bicycle and `--effects` set, so that
    /// speed evolves physically after the release).
    #[arg(long)]
    pub model: Option<String>,
    /// Hidden effects: comma-separated `SYMBOL=VALUE` (e.g.
    /// `c_steer=0.3` or `Crr_rear=0.008,Crr_front=0.008`), on top of the
    /// bicycle's own effect parameters.
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Release speeds are drawn uniformly from LO:HI (m/s).
    #[arg(long, default_value = "3:7")]
    pub speeds: String,
    /// Number of runs.
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Seed of the run plans (run k uses seed + k).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output folder (new or empty; the set appears there only when it is
    /// complete).
    #[arg(long)]
    pub out: PathBuf,
    /// Replace a set that `bikedyn synth` wrote in the output folder (a
    /// folder without its marker, or with files it did not write, is
    /// refused).
    #[arg(long)]
    pub force: bool,
}

/// `bikedyn sweep`: stability over one or two parameters.
#[derive(Args)]
pub struct SweepArgs {
    #[command(flatten)]
    pub bike: BikeArg,
    /// Parameter symbol (thesis: Rt, x4, d4, ...; benchmark: c, lam, w, ...).
    #[arg(long)]
    pub param: String,
    /// Values START:STOP:STEP.
    #[arg(long, allow_hyphen_values = true)]
    pub values: String,
    /// Second parameter for a two-parameter stability map.
    #[arg(long)]
    pub param2: Option<String>,
    /// Values of the second parameter START:STOP:STEP.
    #[arg(long, allow_hyphen_values = true)]
    pub values2: Option<String>,
    /// Upper end of the searched speed range (m/s).
    #[arg(long, default_value_t = 10.0)]
    pub speed_max: f64,
    #[command(flatten)]
    pub out: OutputArgs,
    /// Plot (.svg or .png): a two-parameter sweep's stability map, or a
    /// one-parameter sweep's --map quantity against the parameter.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub plot_args: PlotArgs,
    /// Quantity drawn by --plot: the self-stable range width, the weave
    /// or capsize speed, or the real part of the least stable eigenvalue
    /// at --at-speed. Cells whose stable range reaches --speed-max are
    /// marked (the range is cut there).
    #[arg(long, value_enum, default_value_t = MapArg::Width)]
    pub map: MapArg,
    /// Speed (m/s) of --map least-stable; its value is also written to the
    /// JSON of every cell.
    #[arg(long)]
    pub at_speed: Option<f64>,
}
