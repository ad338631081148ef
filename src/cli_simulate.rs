//! `bikedyn simulate`: nonlinear simulation of a generated model from the
//! command line (issue 7). Angles on the command line are in degrees, rates
//! in deg/s; the CSV uses the model's units (rad, rad/s, m, m/s, J).

use anyhow::{bail, Context, Result};
use bikedyn::bicycle::Bicycle;
use bikedyn::registry::{with_model, ModelVisitor};
use bikedyn::runtime::linearize::parameter_vector;
use bikedyn::runtime::plot::PlotOptions;
use bikedyn::runtime::simulate::plot::plot_simulation;
use bikedyn::runtime::simulate::{
    simulate, Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, SimOptions, Simulation, TorquePulse,
};
use bikedyn::runtime::MultibodyModel;
use clap::Args;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `bikedyn simulate`.
#[derive(Args)]
pub struct SimulateArgs {
    /// Built-in bicycle (thesis, benchmark) or parameter file.
    #[arg(long, default_value = "thesis")]
    bike: String,
    /// Generated model (default: thesis_whipple, or whipple_offset when the
    /// fork mass centre is off the steer axis).
    #[arg(long)]
    model: Option<String>,
    /// Free forward speed (no driving constraint): needs a free-speed model.
    #[arg(long)]
    free_speed: bool,
    /// Forward speed of the rear contact point (m/s); imposed by a driven
    /// model, initial for a free-speed one.
    #[arg(long)]
    speed: f64,
    /// Initial roll (deg, positive leaning right).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    roll: f64,
    /// Initial steer (deg, positive turning left).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    steer: f64,
    /// Initial roll rate (deg/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    roll_rate: f64,
    /// Initial steer rate (deg/s).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    steer_rate: f64,
    /// Initial yaw (deg).
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    yaw: f64,
    /// Lateral kick TIME:IMPULSE[:AHEAD:HEIGHT] (s, N s positive toward the
    /// rider's right, point m ahead of the rear contact and m above ground;
    /// default point: a saddle 0.25 m ahead, 0.95 m high). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    kick: Vec<String>,
    /// Torque pulse roll|steer:START:DURATION:AMPLITUDE[:rect|halfsine]
    /// (s, s, N m). Repeatable.
    #[arg(long, allow_hyphen_values = true)]
    pulse: Vec<String>,
    /// Simulated time (s).
    #[arg(long)]
    duration: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-8)]
    rtol: f64,
    /// Absolute tolerance of the integrator.
    #[arg(long, default_value_t = 1e-10)]
    atol: f64,
    /// Integration method: dop853 (explicit, default) or radau5 (implicit,
    /// for stiff effects such as very short tyre relaxation lengths).
    #[arg(long, default_value = "dop853")]
    method: String,
    /// Output sample interval (s).
    #[arg(long, default_value_t = 0.01)]
    dt: f64,
    /// Stop when |roll| reaches this angle (deg; 0 disables).
    #[arg(long, default_value_t = 1.0f64.to_degrees())]
    roll_limit: f64,
    /// Stop when |steer| reaches this angle (deg; 0 disables).
    #[arg(long, default_value_t = 1.4f64.to_degrees())]
    steer_limit: f64,
    /// CSV output (columns: t, coordinates, rates, speed, energies, residual).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Plot of roll, steer and speed against time (.svg or .png).
    #[arg(long)]
    plot: Option<PathBuf>,
}

fn numbers(spec: &str, what: &str) -> Result<Vec<f64>> {
    spec.split(':')
        .map(|p| {
            let x: f64 = p
                .trim()
                .parse()
                .with_context(|| format!("{what} `{spec}`: `{p}` is not a number"))?;
            if !x.is_finite() {
                bail!("{what} `{spec}`: `{p}` is not finite");
            }
            Ok(x)
        })
        .collect()
}

/// Parse `TIME:IMPULSE[:AHEAD:HEIGHT]`.
pub fn parse_kick(spec: &str) -> Result<Kick> {
    match numbers(spec, "--kick")?.as_slice() {
        [t, j] => Ok(Kick::at_saddle(*t, *j)),
        [t, j, a, h] => Ok(Kick {
            time: *t,
            impulse: *j,
            ahead: *a,
            height: *h,
        }),
        _ => bail!("--kick `{spec}`: expected TIME:IMPULSE or TIME:IMPULSE:AHEAD:HEIGHT"),
    }
}

/// Parse `roll|steer:START:DURATION:AMPLITUDE[:rect|halfsine]`.
pub fn parse_pulse(spec: &str) -> Result<TorquePulse> {
    let parts: Vec<&str> = spec.split(':').collect();
    if parts.len() != 4 && parts.len() != 5 {
        bail!("--pulse `{spec}`: expected roll|steer:START:DURATION:AMPLITUDE[:rect|halfsine]");
    }
    let target = match parts[0] {
        "roll" => PulseTarget::Roll,
        "steer" => PulseTarget::Steer,
        other => bail!("--pulse `{spec}`: target `{other}` is neither roll nor steer"),
    };
    let shape = match parts.get(4).copied().unwrap_or("rect") {
        "rect" | "rectangular" => PulseShape::Rectangular,
        "halfsine" | "half-sine" => PulseShape::HalfSine,
        other => bail!("--pulse `{spec}`: shape `{other}` is neither rect nor halfsine"),
    };
    let x = numbers(&parts[1..4].join(":"), "--pulse")?;
    if x[1] <= 0.0 {
        bail!("--pulse `{spec}`: duration must be positive");
    }
    Ok(TorquePulse {
        target,
        shape,
        start: x[0],
        duration: x[1],
        amplitude: x[2],
    })
}

fn run_model<M: MultibodyModel>(
    lookup: impl Fn(&str) -> Option<f64>,
    ic: &InitialConditions,
    inputs: &Inputs,
    duration: f64,
    opts: &SimOptions,
) -> Result<Simulation> {
    let param = parameter_vector::<M>(lookup, ic.speed)?;
    Ok(simulate::<M>(&param, ic, inputs, duration, opts)?)
}

struct RunSimulation<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
    ic: &'a InitialConditions,
    inputs: &'a Inputs,
    duration: f64,
    opts: &'a SimOptions,
}
impl<F: Fn(&str) -> Option<f64>> ModelVisitor for RunSimulation<'_, F> {
    type Output = Result<Simulation>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        run_model::<M>(self.lookup, self.ic, self.inputs, self.duration, self.opts)
    }
}

/// Run `bikedyn simulate`.
pub fn run(a: SimulateArgs) -> Result<bool> {
    if let Some(p) = &a.plot {
        bikedyn::runtime::plot::ImageFormat::from_path(p)?;
    }
    let bike = Bicycle::resolve(&a.bike)?;
    for w in &bike.warnings {
        eprintln!("warning ({}): {w}", bike.name);
    }
    let mut info = bike.model(a.model.as_deref())?;
    if a.free_speed {
        info = bikedyn::models::free_speed_variant(info)
            .with_context(|| format!("model `{}` has no free-speed variant (see `bikedyn models`)", info.name))?;
    }
    if !(a.speed.is_finite()) {
        bail!("--speed must be a finite number");
    }
    let ic = InitialConditions {
        roll: a.roll.to_radians(),
        steer: a.steer.to_radians(),
        roll_rate: a.roll_rate.to_radians(),
        steer_rate: a.steer_rate.to_radians(),
        speed: a.speed,
        yaw: a.yaw.to_radians(),
    };
    let inputs = Inputs {
        kicks: a.kick.iter().map(|k| parse_kick(k)).collect::<Result<_>>()?,
        pulses: a.pulse.iter().map(|k| parse_pulse(k)).collect::<Result<_>>()?,
    };
    let limit = |deg: f64| (deg > 0.0).then(|| deg.to_radians());
    let opts = SimOptions {
        rtol: a.rtol,
        atol: a.atol,
        method: a.method.parse()?,
        output_interval: a.dt,
        events: Events {
            roll_limit: limit(a.roll_limit),
            steer_limit: limit(a.steer_limit),
        },
    };
    let lookup = bike.lookup()?;
    let start = Instant::now();
    let sim = with_model(
        info.name,
        RunSimulation {
            lookup: &lookup,
            ic: &ic,
            inputs: &inputs,
            duration: a.duration,
            opts: &opts,
        },
    )
    .expect("registered model")?;
    let wall = start.elapsed().as_secs_f64();
    let simulated = sim.t.last().copied().unwrap_or(0.0);
    println!(
        "model {} ({}), bicycle {}",
        sim.model,
        if info.free_speed { "free speed" } else { "driven speed" },
        a.bike
    );
    println!("  stop: {}", sim.stop);
    println!(
        "  {}: simulated {simulated:.3} s in {:.3} ms ({:.0}x real time), {} right-hand-side evaluations, {} steps ({} rejected)",
        opts.method.name(),
        wall * 1e3,
        simulated / wall.max(1e-12),
        sim.stats.rhs_evaluations,
        sim.stats.accepted_steps,
        sim.stats.rejected_steps
    );
    println!(
        "  max holonomic constraint residual {:.2e}, max velocity-constraint residual {:.2e}, relative energy change {:.2e}",
        sim.max_constraint_residual(),
        sim.max_velocity_residual(),
        sim.relative_energy_drift()
    );
    if let Some(out) = &a.out {
        sim.save_csv(out)?;
        eprintln!("wrote {}", out.display());
    }
    if let Some(plot) = &a.plot {
        plot_simulation(plot, &sim, &PlotOptions::default())?;
        eprintln!("wrote {}", plot.display());
    }
    Ok(true)
}
