//! `bikedyn synth`: synthetic field runs (issue 7, point 6), the physical
//! side. Each run is a hand-held launch, release, saddle kick and free
//! response of the chosen model ([`trajectory_for_run`]); this command writes
//! per run the orientation history (`<run>_trajectory.csv`: t, yaw, roll,
//! pitch, steer, rear_wheel_angle in rad, speed in m/s, thesis conventions)
//! and a truth file (`<run>_truth.json`: run plan, parameters, state at
//! release, stop reason, frozen-speed eigenvalues at the mean speed after
//! release).
//!
//! The sensor side is `experiment::synth::write_run`: every run becomes a
//! run folder in the measured-run format of `../shared/data/FORMAT.md`
//! (IMU quaternions, reed switch, run.toml) with sensor effects, beside a
//! `calibration/` folder (the bicycle at rest). The truth (physical and
//! sensor) goes to `truth/`, outside the set, so `bikedyn fit OUT` reads the
//! set as it would a measured one.

use anyhow::{bail, Context, Result};
use bikedyn::bicycle::{canonical_of, Bicycle};
use bikedyn::registry::{with_model, ModelVisitor};
use bikedyn::runtime::eigen::eigenvalues;
use bikedyn::runtime::experiment::synth::{rest_trajectory, write_run, RunKind, SensorModel};
use bikedyn::runtime::linearize::parameter_vector;
use bikedyn::runtime::model::CoordinateRole;
use bikedyn::runtime::output::{save_json, write_atomic};
use bikedyn::runtime::random::SplitMix64;
use bikedyn::runtime::simulate::trajectory::{trajectory_for_run, RunPlan, Trajectory};
use bikedyn::runtime::simulate::{SimOptions, Simulation};
use bikedyn::runtime::MultibodyModel;
use clap::Args;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Arguments of `bikedyn synth`.
#[derive(Args)]
pub struct SynthArgs {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long, default_value = "thesis")]
    bike: String,
    /// Generated model (default: the free-speed variant of the smallest
    /// model with every parameter the bicycle and `--effects` set, so that
    /// speed evolves physically after the release).
    #[arg(long)]
    model: Option<String>,
    /// Hidden effects: comma-separated `SYMBOL=VALUE` (e.g.
    /// `c_steer=0.3` or `Crr_rear=0.008,Crr_front=0.008`), on top of the
    /// bicycle's own effect parameters.
    #[arg(long, value_delimiter = ',')]
    effects: Vec<String>,
    /// Release speeds are drawn uniformly from LO:HI (m/s).
    #[arg(long, default_value = "3:7")]
    speeds: String,
    /// Number of runs.
    #[arg(long, default_value_t = 3)]
    runs: usize,
    /// Seed of the run plans (run k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
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
    let rest = |v: &[f64]| -> Vec<f64> {
        let first = v.first().copied().unwrap_or(0.0);
        std::iter::repeat_n(first, n_rest).chain(v.iter().copied()).collect()
    };
    Trajectory {
        t: (0..n_rest)
            .map(|k| k as f64 * dt)
            .chain(tr.t.iter().map(|t| t - tr.t[0] + n_rest as f64 * dt))
            .collect(),
        yaw: rest(&tr.yaw),
        roll: rest(&tr.roll),
        pitch: rest(&tr.pitch),
        steer: rest(&tr.steer),
        rear_wheel_angle: rest(&tr.rear_wheel_angle),
        speed: rest(&tr.speed),
    }
}

fn write_physical_run(dir: &Path, name: &str, tr: &Trajectory, truth: &serde_json::Value) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
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
) -> Result<(Trajectory, Simulation, Vec<f64>)> {
    let param = parameter_vector::<M>(lookup, plan.speed)?;
    let (tr, sim) = trajectory_for_run::<M>(&param, plan, &SimOptions::default())?;
    Ok((tr, sim, param))
}

struct OneRun<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
    plan: &'a RunPlan,
}
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for OneRun<'_, F> {
    #[allow(clippy::type_complexity)]
    type Output = Result<(Trajectory, Simulation, Vec<f64>, &'static [&'static str])>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let (t, s, pv) = one_run::<M>(self.lookup, self.plan)?;
        Ok((t, s, pv, M::PARAMETERS))
    }
}

/// Run `bikedyn synth`.
pub fn run(a: SynthArgs) -> Result<bool> {
    if a.runs == 0 || a.runs > 1000 {
        bail!("--runs must be between 1 and 1000");
    }
    let mut bike = Bicycle::resolve(&a.bike)?;
    for e in &a.effects {
        let (sym, val) = e
            .split_once('=')
            .with_context(|| format!("--effects `{e}`: expected SYMBOL=VALUE"))?;
        let val: f64 = val
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .with_context(|| format!("--effects `{e}`: `{}` is not a finite number", val.trim()))?;
        bike = bike.with_parameter(sym.trim(), val)?;
    }
    let (lo, hi) = a
        .speeds
        .split_once(':')
        .and_then(|(l, h)| Some((l.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?)))
        .filter(|(l, h)| l.is_finite() && h.is_finite() && *l > 0.0 && h >= l)
        .with_context(|| format!("--speeds `{}`: expected LO:HI with 0 < LO <= HI (m/s)", a.speeds))?;
    let p = bike.thesis()?;
    let canonical = canonical_of(&p)?;
    let info = match a.model.as_deref() {
        Some(name) => bike.model(Some(name))?,
        None => {
            let driven = bike.model(None)?;
            bikedyn::models::free_speed_variant(driven).with_context(|| {
                format!(
                    "model `{}` has no free-speed variant; name one with --model",
                    driven.name
                )
            })?
        }
    };
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let lookup = bike.lookup()?;
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
        let (tr, sim, param, names) = with_model(
            info.name,
            OneRun {
                lookup: &lookup,
                plan: &plan,
            },
        )
        .expect("registered model")?;
        let release = tr.t.iter().position(|&t| t >= plan.launch_duration).unwrap_or(0);
        let mean_speed = tr.speed[release..].iter().sum::<f64>() / (tr.speed.len() - release).max(1) as f64;
        let ev = eigenvalues(&canonical, mean_speed)?;
        let name = format!("run{:02}", k + 1);
        let truth = serde_json::json!({
            "model": sim.model,
            "bike": a.bike,
            "plan": plan,
            "parameters": names.iter().zip(&param).map(|(n, v)| (n.to_string(), serde_json::Value::from(*v))).collect::<serde_json::Map<_, _>>(),
            "release": {
                "time": plan.launch_duration,
                "roll": tr.roll[release], "steer": tr.steer[release], "yaw": tr.yaw[release],
                "roll_rate": sim.rate_of(CoordinateRole::Roll).map(|r| r[0]), "steer_rate": sim.rate_of(CoordinateRole::Steer).map(|r| r[0]),
                "speed": plan.speed,
            },
            "kick_time": plan.launch_duration + plan.kick_delay,
            "kick_time_on_imu_clock": REST_BEFORE_LAUNCH + plan.launch_duration + plan.kick_delay,
            "stop": sim.stop.to_string(),
            "max_constraint_residual": sim.max_constraint_residual(),
            "mean_speed_after_release": mean_speed,
            "frozen_speed_eigenvalues": ev.iter().map(|z| [z.re, z.im]).collect::<Vec<_>>(),
        });
        if k == 0 {
            // The calibration run: the bicycle held at rest, upright, at the
            // pitch of the model's upright configuration.
            let pitch = tr.pitch.first().copied().unwrap_or(0.0);
            let cal = rest_trajectory(10.0, pitch, 0.0);
            let mut sensors = sensors.clone();
            sensors.clock_offset = clock_offset(sensors.nominal_offset, a.seed);
            write_run(
                &a.out.join("calibration"),
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
            &a.out.join(&name),
            &name,
            RunKind::Run,
            &sensor_trajectory(&tr),
            &sensors,
            a.seed.wrapping_add(1 + k as u64),
        )?;
        let mut truth = truth;
        truth["sensors"] = serde_json::to_value(&sensor_truth)?;
        write_physical_run(&a.out.join("truth"), &name, &tr, &truth)?;
        println!(
            "{name}: release at {:.2} s, {:.2} m/s, kick {:+.2} N s at {:.2} s, {}",
            plan.launch_duration,
            plan.speed,
            plan.kick_impulse,
            plan.launch_duration + plan.kick_delay,
            sim.stop
        );
    }
    println!("wrote {} runs to {}", a.runs, a.out.display());
    Ok(true)
}

/// A synthetic set of the thesis bicycle at 4-6.5 m/s with `effects` hidden
/// (for the identification bench).
pub fn thesis_set(out: &Path, runs: usize, seed: u64, effects: &[&str]) -> Result<bool> {
    run(SynthArgs {
        bike: "thesis".into(),
        model: None,
        effects: effects.iter().map(|s| s.to_string()).collect(),
        speeds: "4:6.5".into(),
        runs,
        seed,
        out: out.to_path_buf(),
    })
}
