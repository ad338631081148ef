//! Synthetic measured-style run sets (`bikedyn synth`): synthetic field runs (issue 7, point 6), the physical
//! side. Each run is a hand-held launch, release, saddle kick and free
//! response of the chosen model ([`trajectory_for_run`]); [`synth`] writes
//! per run the orientation history (`<run>_trajectory.csv`: t, yaw, roll,
//! pitch, steer, rear_wheel_angle in rad, speed in m/s, thesis conventions)
//! and a truth file (`<run>_truth.json`: run plan, parameters, state at
//! release, stop reason, frozen-speed eigenvalues at the mean speed after
//! release).
//!
//! The sensor side is `bikedyn_report::experiment::synth::write_run`: every run becomes a
//! run folder in the measured-run format of `../shared/data/FORMAT.md`
//! (IMU quaternions, reed switch, run.toml) with sensor effects, beside a
//! `calibration/` folder (the bicycle at rest). The truth (physical and
//! sensor) goes to `truth/`, outside the set, so `bikedyn fit OUT` reads the
//! set as it would a measured one.

use crate::bicycle::{canonical_of, Bicycle, BicycleError};
use crate::registry::BuiltIn;
/// The fastest run the measured-run reader accepts (m/s): a synthetic run is held to it.
pub use crate::runs::MAX_SPEED_M_S;
use bikedyn_report::experiment::synth::{write_run, WriteRunError};
use bikedyn_report::output::{save_json, write_atomic, OutputError};
use bikedyn_report::staged::{FolderKind, StagedDir};
use bikedyn_runtime::eigen::{eigenvalues_of, EigenError};
use bikedyn_runtime::experiment::synth::{rest_trajectory, RunKind, SensorModel, SynthTruth};
use bikedyn_runtime::feedback::GainSchedule;
use bikedyn_runtime::linearize::{parameter_vector, LinearizeError};
use bikedyn_runtime::model::CoordinateRole;
use bikedyn_runtime::parameters::ThesisParameters;
use bikedyn_runtime::random::SplitMix64;
use bikedyn_runtime::registry::{ModelRegistry, ModelVisitor};
use bikedyn_runtime::simulate::trajectory::{trajectory_for_run, RunPlan, Trajectory};
use bikedyn_runtime::simulate::{SimOptions, SimulateError, Simulation};
use bikedyn_runtime::MultibodyModel;
use serde::Serialize;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// What set to make.
#[derive(Clone, Debug)]
pub struct SynthOptions {
    /// Built-in bicycle (thesis, benchmark) or parameter file (default thesis).
    pub bike: String,
    /// Generated model (default: the free-speed variant of the smallest
    /// model with every parameter the bicycle and `effects` set, so that
    /// speed evolves physically after the release).
    pub model: Option<String>,
    /// Hidden effects `(symbol, value)` on top of the bicycle's own effect
    /// parameters (e.g. `("c_steer", 0.3)`, in the parameter's unit).
    pub effects: Vec<(String, f64)>,
    /// Release speeds are drawn uniformly from `[LO, HI]` (m/s, 0 < LO <= HI;
    /// default 3-7).
    pub speeds: [f64; 2],
    /// Number of runs, 1 to 1000 (default 3).
    pub runs: usize,
    /// Seed of the run plans (run k uses seed + k; default 1).
    pub seed: u64,
    /// Output folder: it must not exist or be empty, unless `force`.
    pub out: PathBuf,
    /// Replace a set that `synth` wrote in `out` (recognised by its marker,
    /// `bikedyn_report::staged::MARKER`; a folder without it, or with
    /// files the set does not list, is refused). The old set is removed
    /// once the new one is complete.
    pub force: bool,
}

impl Default for SynthOptions {
    fn default() -> Self {
        Self {
            bike: "thesis".into(),
            model: None,
            effects: Vec::new(),
            speeds: [3.0, 7.0],
            runs: 3,
            seed: 1,
            out: PathBuf::from("synth"),
            force: false,
        }
    }
}

/// One run written.
#[derive(Clone, Debug, Serialize)]
pub struct SynthRun {
    /// Run folder name (`run01`, ...).
    pub name: String,
    /// The run plan (launch, release speed, kick).
    pub plan: RunPlan,
    /// Why the simulation stopped.
    pub stop: String,
    /// The generated model that simulated it.
    pub model: &'static str,
}

/// What a synthetic run truly is, as `truth/<run>_truth.json` holds it
/// (the JSON is this type's derived serialization): what `fit` and
/// `identify` on the set should recover.
#[derive(Clone, Debug, Serialize)]
pub struct RunTruth {
    /// The generated model that simulated the run.
    pub model: &'static str,
    /// The bicycle, as given (built-in name or parameter file).
    pub bike: String,
    /// The run plan (launch, release speed, kick; s, rad, m/s, N s).
    pub plan: RunPlan,
    /// The model's parameter vector by symbol (each in its unit; the
    /// forward speed's entry is the release speed).
    pub parameters: BTreeMap<&'static str, f64>,
    /// The state at release.
    pub release: ReleaseState,
    /// Kick time on the simulation's clock (s from the launch).
    pub kick_time: f64,
    /// Kick time on the IMU clock of the run's files (s).
    pub kick_time_on_imu_clock: f64,
    /// Why the simulation stopped.
    pub stop: String,
    /// Largest holonomic-constraint residual over the run.
    pub max_constraint_residual: f64,
    /// Mean forward speed from the release to the end (m/s).
    pub mean_speed_after_release: f64,
    /// Eigenvalues `[real, imag]` (1/s, rad/s) of the model's linear
    /// equations frozen at `mean_speed_after_release`.
    pub frozen_speed_eigenvalues: Vec<[f64; 2]>,
    /// The sensors' truth: misalignments, clock offset, magnets.
    pub sensors: SynthTruth,
}

/// The state of a synthetic run at release (angles in rad, rates in rad/s).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct ReleaseState {
    /// Time of the release from the launch (s).
    pub time: f64,
    /// Roll angle.
    pub roll: f64,
    /// Steer angle.
    pub steer: f64,
    /// Yaw angle.
    pub yaw: f64,
    /// Roll rate, or `null` for a model that declares no roll.
    pub roll_rate: Option<f64>,
    /// Steer rate, or `null` for a model that declares no steer.
    pub steer_rate: Option<f64>,
    /// Forward speed at release (m/s).
    pub speed: f64,
}

/// Why a synthetic set could not be made.
#[derive(Debug, Error)]
pub enum SynthError {
    /// The output folder holds files already (a set must never be mixed
    /// with another's runs or overwrite measured data).
    #[error("{} is not empty: choose a new folder, or pass --force to replace a set that bikedyn synth wrote there", path.display())]
    OutputNotEmpty { path: PathBuf },
    /// The number of runs is outside 1 to 1000.
    #[error("--runs must be between 1 and 1000")]
    RunCount { runs: usize },
    /// The release speeds are not `0 < LO <= HI <= 30` m/s.
    #[error("release speeds must be 0 < LO <= HI <= {MAX_SPEED_M_S} (m/s), found {lo}:{hi}: no measured run is ridden faster, and `fit` refuses such speeds")]
    Speeds { lo: f64, hi: f64 },
    /// The bicycle could not be resolved, or an effect value set on it.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The model fitting the bicycle has no free-speed variant.
    #[error("model `{model}` has no free-speed variant; name one with --model")]
    NoFreeSpeedVariant { model: String },
    /// The output folder (or `truth/`) could not be created.
    #[error("creating {}", path.display())]
    CreateDir {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The parameter vector of the model could not be formed.
    #[error(transparent)]
    Linearize(#[from] LinearizeError),
    /// A run could not be simulated.
    #[error(transparent)]
    Simulate(#[from] SimulateError),
    /// The frozen-speed eigenvalues of the truth file failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// The sensor files of a run could not be written.
    #[error(transparent)]
    Sensors(#[from] WriteRunError),
    /// A trajectory or truth file could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Refuse a non-empty output folder without `force` (with it, the staged
/// set checks that the folder is a set bikedyn wrote).
fn check_empty(out: &Path, force: bool) -> Result<(), SynthError> {
    let non_empty = match std::fs::read_dir(out) {
        Ok(mut entries) => entries.next().is_some(),
        // Not a folder (a file): staging the set says so.
        Err(_) => false,
    };
    if non_empty && !force {
        return Err(SynthError::OutputNotEmpty {
            path: out.to_path_buf(),
        });
    }
    Ok(())
}

fn create_dir(dir: &Path) -> Result<(), SynthError> {
    std::fs::create_dir_all(dir).map_err(|source| SynthError::CreateDir {
        path: dir.to_path_buf(),
        source,
    })
}

/// A per-run clock offset: the nominal one plus up to +/- 0.3 s, as in
/// FORMAT.md (the first draw of the seed's generator, so runs are
/// reproducible).
fn clock_offset(nominal: f64, seed: u64) -> f64 {
    nominal + 0.6 * (SplitMix64::new(seed).next_f64() - 0.5)
}

/// Time the bicycle stands still, held upright, before the launch (s): the
/// loggers start during it and the IMUs settle (FORMAT.md, "What a run
/// contains", step 1).
const REST_BEFORE_LAUNCH: f64 = 2.5;

/// The sensor-side motion: the rest before the launch, then the simulated
/// run shifted by it.
fn sensor_trajectory(tr: &Trajectory) -> Trajectory {
    let dt = tr.t.get(1).map_or(0.01, |t1| t1 - tr.t[0]).max(1e-4);
    let n_rest = (REST_BEFORE_LAUNCH / dt).round() as usize;
    let first = |v: &[f64]| v.first().copied().unwrap_or(0.0);
    let mut out = Trajectory {
        t: (0..n_rest).map(|k| k as f64 * dt).collect(),
        yaw: vec![first(&tr.yaw); n_rest],
        roll: vec![first(&tr.roll); n_rest],
        pitch: vec![first(&tr.pitch); n_rest],
        steer: vec![first(&tr.steer); n_rest],
        rear_wheel_angle: vec![first(&tr.rear_wheel_angle); n_rest],
        speed: vec![first(&tr.speed); n_rest],
    };
    // Through `append`, which keeps the times strictly increasing: two
    // samples a rounding error apart (an event next to an output time)
    // can become equal once shifted.
    out.append(tr, n_rest as f64 * dt - tr.t.first().copied().unwrap_or(0.0));
    out
}

fn write_physical_run(dir: &Path, name: &str, tr: &Trajectory, truth: &RunTruth) -> Result<(), SynthError> {
    create_dir(dir)?;
    write_atomic(dir.join(format!("{name}_trajectory.csv")), |w: &mut dyn Write| {
        writeln!(w, "t,yaw,roll,pitch,steer,rear_wheel_angle,speed")?;
        for i in 0..tr.t.len() {
            writeln!(
                w,
                "{:.6},{:.12e},{:.12e},{:.12e},{:.12e},{:.12e},{:.9e}",
                tr.t[i], tr.yaw[i], tr.roll[i], tr.pitch[i], tr.steer[i], tr.rear_wheel_angle[i], tr.speed[i]
            )?;
        }
        Ok::<(), std::io::Error>(())
    })?;
    save_json(dir.join(format!("{name}_truth.json")), truth)?;
    Ok(())
}

fn one_run<M: MultibodyModel>(
    lookup: &dyn Fn(&str) -> Option<f64>,
    plan: &RunPlan,
    feedback: Option<&GainSchedule>,
) -> Result<(Trajectory, Simulation, Vec<f64>), SynthError> {
    let param = parameter_vector::<M>(lookup, plan.speed)?;
    let (tr, sim) = trajectory_for_run::<M>(&param, plan, feedback, &SimOptions::default())?;
    Ok((tr, sim, param))
}

struct OneRun<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
    plan: &'a RunPlan,
    /// The bicycle file's controller, acting from the release on.
    feedback: Option<&'a GainSchedule>,
}
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for OneRun<'_, F> {
    #[allow(clippy::type_complexity)]
    type Output = Result<(Trajectory, Simulation, Vec<f64>, &'static [&'static str]), SynthError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let (t, s, pv) = one_run::<M>(self.lookup, self.plan, self.feedback)?;
        Ok((t, s, pv, M::PARAMETERS))
    }
}

/// Make the set with the built-in models: `on_run` is called after each
/// run is written (into a hidden folder beside `out`: the set appears in
/// `out` only when it is complete).
pub fn synth(a: &SynthOptions, on_run: &mut dyn FnMut(&SynthRun)) -> Result<(), SynthError> {
    synth_in::<BuiltIn>(a, on_run)
}

/// [`synth`] with the models of registry `R`: the bicycle, the hidden
/// effects and the model are resolved among them (e.g. an effect declared
/// in a user's own build script).
pub fn synth_in<R: ModelRegistry>(a: &SynthOptions, on_run: &mut dyn FnMut(&SynthRun)) -> Result<(), SynthError> {
    if a.runs == 0 || a.runs > 1000 {
        return Err(SynthError::RunCount { runs: a.runs });
    }
    let mut bike = Bicycle::<R>::resolve_in(&a.bike)?;
    for (sym, val) in &a.effects {
        bike = bike.with_parameter(sym, *val)?;
    }
    let [lo, hi] = a.speeds;
    // A set no measurement could be (100 m/s) would only test the model
    // where no bicycle is ridden.
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi >= lo && hi <= MAX_SPEED_M_S) {
        return Err(SynthError::Speeds { lo, hi });
    }
    let p = bike.thesis()?;
    // The experimenter kicks a heavier bicycle harder: the plans draw the
    // thesis's 2-5 N s at the saddle, which is scaled here by this bicycle's
    // roll inertia about the rear contact line (M0[0][0], the bare bicycle's)
    // over the thesis bicycle's, so that every bicycle gets the roll-rate
    // jump of the thesis's kicks (impulse times height over roll inertia).
    // Unscaled, a 33 kg city bicycle's response to a thesis kick sits at the
    // noise level of the thesis's IMU and no kick is found.
    let info = match a.model.as_deref() {
        Some(name) => bike.model(Some(name))?,
        None => {
            let driven = bike.model(None)?;
            crate::models::free_speed_variant_in::<R>(driven).ok_or_else(|| SynthError::NoFreeSpeedVariant {
                model: driven.name.to_string(),
            })?
        }
    };
    let lookup = bike.lookup()?;
    // A model's added body (a leaning rider's upper body) rolls with the
    // bicycle too: its roll inertia is the model's own mass matrix entry
    // (the lean held), not the bare bicycle's.
    let roll_inertia = if info.added_coordinates().is_empty() {
        canonical_of(&p)?.m0[(0, 0)]
    } else {
        R::with_model(info.name, RollInertia(&lookup)).expect("registered model")?
    };
    let kick_scale = roll_inertia / canonical_of(&ThesisParameters::thesis_bicycle())?.m0[(0, 0)];
    // The truth's frozen-speed eigenvalues: the linear equations of the
    // model simulated, damping, controllers and tyre states included (not
    // the bare Whipple bicycle's).
    let linear = bike.linear_with(Some(info.name))?;
    check_empty(&a.out, a.force)?;
    let set = StagedDir::new(&a.out, FolderKind::SyntheticSet)?;
    let out = set.path().to_path_buf();
    // Sensors like the thesis's instrumentation (FORMAT.md), on this
    // bicycle's rear wheel.
    let sensors = SensorModel {
        wheel_circumference: 2.0 * std::f64::consts::PI * p.rear_wheel_radius,
        ..SensorModel::default()
    };
    for k in 0..a.runs {
        let mut plan = RunPlan::random(a.seed.wrapping_add(k as u64));
        // RunPlan::random draws 3-7 m/s; map that draw onto LO:HI.
        plan.speed = lo + (hi - lo) * (plan.speed - 3.0) / 4.0;
        plan.kick_impulse *= kick_scale;
        let (tr, sim, param, names) = R::with_model(
            info.name,
            OneRun {
                lookup: &lookup,
                plan: &plan,
                feedback: bike.feedback.as_ref(),
            },
        )
        .expect("registered model")?;
        let release = tr.t.iter().position(|&t| t >= plan.launch_duration).unwrap_or(0);
        let mean_speed = tr.speed[release..].iter().sum::<f64>() / (tr.speed.len() - release).max(1) as f64;
        let ev = eigenvalues_of(&linear, mean_speed)?;
        let name = format!("run{:02}", k + 1);
        if k == 0 {
            // The calibration run: the bicycle held at rest, upright, at the
            // pitch of the model's upright configuration.
            let pitch = tr.pitch.first().copied().unwrap_or(0.0);
            let cal = rest_trajectory(10.0, pitch, 0.0);
            let mut sensors = sensors.clone();
            sensors.clock_offset = clock_offset(sensors.nominal_offset, a.seed);
            write_run(
                &out.join("calibration"),
                "calibration",
                RunKind::Calibration,
                &cal,
                &sensors,
                a.seed,
            )?;
        }
        let mut sensors = sensors.clone();
        sensors.clock_offset = clock_offset(sensors.nominal_offset, a.seed.wrapping_add(1 + k as u64));
        let sensor_truth = write_run(
            &out.join(&name),
            &name,
            RunKind::Run,
            &sensor_trajectory(&tr),
            &sensors,
            a.seed.wrapping_add(1 + k as u64),
        )?;
        let truth = RunTruth {
            model: sim.model,
            bike: a.bike.clone(),
            plan,
            parameters: names.iter().copied().zip(param.iter().copied()).collect(),
            release: ReleaseState {
                time: plan.launch_duration,
                roll: tr.roll[release],
                steer: tr.steer[release],
                yaw: tr.yaw[release],
                roll_rate: sim.rate_of(CoordinateRole::Roll).map(|r| r[0]),
                steer_rate: sim.rate_of(CoordinateRole::Steer).map(|r| r[0]),
                speed: plan.speed,
            },
            kick_time: plan.launch_duration + plan.kick_delay,
            kick_time_on_imu_clock: REST_BEFORE_LAUNCH + plan.launch_duration + plan.kick_delay,
            stop: sim.stop.to_string(),
            max_constraint_residual: sim.max_constraint_residual(),
            mean_speed_after_release: mean_speed,
            frozen_speed_eigenvalues: ev.iter().map(|z| [z.re, z.im]).collect(),
            sensors: sensor_truth,
        };
        write_physical_run(&out.join("truth"), &name, &tr, &truth)?;
        on_run(&SynthRun {
            model: info.name,
            stop: sim.stop.to_string(),
            name,
            plan,
        });
    }
    Ok(set.commit()?)
}

/// The roll-roll entry of a model's mass matrix at upright straight running
/// (kg m^2): the roll inertia about the rear contact line with every other
/// independent coordinate held.
struct RollInertia<'a, F: Fn(&str) -> Option<f64>>(&'a F);
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for RollInertia<'_, F> {
    type Output = Result<f64, LinearizeError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let param = parameter_vector::<M>(self.0, 0.0)?;
        let lin = bikedyn_runtime::linearize::linearize_at_speed::<M>(&param, 1.0)?;
        let roll = M::require_coordinate(CoordinateRole::Roll, "a kick's size")?;
        let k = M::INDEPENDENT
            .iter()
            .position(|&j| j == roll)
            .expect("roll is independent");
        Ok(lin.mass[(k, k)])
    }
}
