//! `bikedyn synth`: synthetic field runs (issue 7, point 6), the physical
//! side. Each run is a hand-held launch, release, saddle kick and free
//! response of the chosen model ([`trajectory_for_run`]); this command writes
//! per run the orientation history (`<run>_trajectory.csv`: t, yaw, roll,
//! pitch, steer, rear_wheel_angle in rad, speed in m/s, thesis conventions)
//! and a truth file (`<run>_truth.json`: run plan, parameters, state at
//! release, stop reason, frozen-speed eigenvalues at the mean speed after
//! release).
//!
//! MERGE NOTE (issue 8): the sensor side (`experiment::synth::write_run`,
//! FORMAT.md files: IMU quaternions, reed switch, run.toml, calibration run,
//! sensor effects) takes the `Trajectory` built from [`RunTrajectory`]'s
//! fields; wire it in [`write_physical_run`] when that branch lands.

use anyhow::{bail, Context, Result};
use bikedyn::bicycle::{canonical_of, Bicycle};
use bikedyn::generated::{ThesisWhipple, WhippleOffset};
use bikedyn::runtime::eigen::eigenvalues;
use bikedyn::runtime::linearize::parameter_vector;
use bikedyn::runtime::output::{save_json, write_atomic};
use bikedyn::runtime::simulate::trajectory::{trajectory_for_run, RunPlan, RunTrajectory};
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
    /// Generated model (default: thesis_whipple, or whipple_offset when the
    /// fork mass centre is off the steer axis).
    #[arg(long)]
    model: Option<String>,
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

fn write_physical_run(dir: &Path, name: &str, tr: &RunTrajectory, truth: &serde_json::Value) -> Result<()> {
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
) -> Result<(RunTrajectory, Simulation, Vec<f64>)> {
    let param = parameter_vector::<M>(lookup, plan.speed)?;
    let (tr, sim) = trajectory_for_run::<M>(&param, plan, &SimOptions::default())?;
    Ok((tr, sim, param))
}

/// Run `bikedyn synth`.
pub fn run(a: SynthArgs) -> Result<bool> {
    if a.runs == 0 || a.runs > 1000 {
        bail!("--runs must be between 1 and 1000");
    }
    let bike = Bicycle::resolve(&a.bike)?;
    let p = bike.thesis()?;
    let canonical = canonical_of(&p)?;
    let model = a.model.clone().unwrap_or_else(|| {
        if p.fork_com_offset == 0.0 {
            ThesisWhipple::NAME.to_string()
        } else {
            WhippleOffset::NAME.to_string()
        }
    });
    std::fs::create_dir_all(&a.out).with_context(|| format!("creating {}", a.out.display()))?;
    let lookup = |s: &str| p.get(s);
    for k in 0..a.runs {
        let plan = RunPlan::random(a.seed.wrapping_add(k as u64));
        let (tr, sim, param, names): (_, _, _, &[&str]) = match model.as_str() {
            "thesis_whipple" if p.fork_com_offset == 0.0 => {
                let (t, s, pv) = one_run::<ThesisWhipple>(&lookup, &plan)?;
                (t, s, pv, ThesisWhipple::PARAMETERS)
            }
            "thesis_whipple" => bail!(
                "bicycle `{}` needs --model whipple_offset (fork mass centre off the steer axis)",
                a.bike
            ),
            "whipple_offset" => {
                let (t, s, pv) = one_run::<WhippleOffset>(&lookup, &plan)?;
                (t, s, pv, WhippleOffset::PARAMETERS)
            }
            other => bail!("unknown model `{other}` (models: thesis_whipple, whipple_offset)"),
        };
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
                "roll_rate": sim.rate("theta").map(|r| r[0]), "steer_rate": sim.rate("gamma").map(|r| r[0]),
                "speed": plan.speed,
            },
            "kick_time": plan.launch_duration + plan.kick_delay,
            "stop": sim.stop.to_string(),
            "max_constraint_residual": sim.max_constraint_residual(),
            "mean_speed_after_release": mean_speed,
            "frozen_speed_eigenvalues": ev.iter().map(|z| [z.re, z.im]).collect::<Vec<_>>(),
        });
        write_physical_run(&a.out, &name, &tr, &truth)?;
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
