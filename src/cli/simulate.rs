//! `bikedyn simulate`: nonlinear simulation of a generated model from the
//! command line (issue 7). Angles on the command line are in degrees, rates
//! in deg/s; the CSV uses the model's units (rad, rad/s, m, m/s, J).

use super::args::SimulateArgs;
use anyhow::{bail, Context, Result};
use bikedyn::bicycle::Bicycle;
use bikedyn::report::simulate::plot::plot_simulation;
use bikedyn::report::simulate::save_simulation_csv;
use bikedyn::simulate::{
    self, Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, SimOptions, SimulateRequest, TorquePulse,
    MIN_RTOL,
};

/// The numbers of a colon-separated spec; `format` is the expected form,
/// shown when a part is not a number (`--kick 1,3` names TIME:IMPULSE).
fn numbers(spec: &str, what: &str, format: &str) -> Result<Vec<f64>> {
    spec.split(':')
        .map(|p| {
            let x: f64 = p.trim().parse().ok().with_context(|| {
                format!("{what} `{spec}`: `{p}` is not a number (expected {format}, parts separated by colons)")
            })?;
            if !x.is_finite() {
                bail!("{what} `{spec}`: `{p}` is not finite");
            }
            Ok(x)
        })
        .collect()
}

/// Parse `TIME:IMPULSE[:AHEAD:HEIGHT]`.
pub fn parse_kick(spec: &str) -> Result<Kick> {
    const FORMAT: &str = "TIME:IMPULSE or TIME:IMPULSE:AHEAD:HEIGHT, e.g. 1.0:3";
    match numbers(spec, "--kick", FORMAT)?.as_slice() {
        [t, j] => Ok(Kick::at_saddle(*t, *j)),
        // A point below the ground is no place to kick a bicycle (a sign
        // slip: heights are up from the ground).
        [_, _, _, h] if *h < 0.0 => bail!("--kick `{spec}`: HEIGHT {h} m is below the ground; the point's height above the ground is positive, e.g. 0.95 for a saddle"),
        [t, j, a, h] => Ok(Kick {
            time: *t,
            impulse: *j,
            ahead: *a,
            height: *h,
        }),
        _ => bail!("--kick `{spec}`: expected {FORMAT}"),
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
    let x = numbers(
        &parts[1..4].join(":"),
        "--pulse",
        "roll|steer:START:DURATION:AMPLITUDE[:rect|halfsine]",
    )?;
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

/// Run `bikedyn simulate`.
pub fn run(a: SimulateArgs) -> Result<bool> {
    let mut plot_opts = super::plot_options(&a.plot_args, None)?;
    super::Paths::new()
        .bike("--bike", Some(&a.bike))
        .file("--out", a.out.as_deref())
        .file("--plot", a.plot.as_deref())
        .check()?;
    super::check_outputs(a.out.as_deref(), a.plot.as_deref())?;
    let bike = Bicycle::resolve(&a.bike)?;
    super::show_warnings(&bike);
    let request = SimulateRequest {
        model: a.model.clone(),
        free_speed: a.free_speed,
        ..SimulateRequest::default()
    };
    let info = simulate::choose_model(&bike, request.model.as_deref(), request.free_speed)?;
    if let Some(m) = a.model.as_deref().filter(|m| *m != info.name) {
        // The named model is not the one run: say which is.
        eprintln!(
            "note: --free-speed runs {}, the free-speed variant of --model {m}",
            info.name
        );
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
        ..InitialConditions::default()
    };
    let inputs = Inputs {
        kicks: a.kick.iter().map(|k| parse_kick(k)).collect::<Result<_>>()?,
        pulses: a.pulse.iter().map(|k| parse_pulse(k)).collect::<Result<_>>()?,
        feedback: None,
    };
    // 0 disables a stop; a negative or non-finite angle is no angle (NaN
    // would silently disable it too).
    for (flag, deg) in [("--roll-limit", a.roll_limit), ("--steer-limit", a.steer_limit)] {
        if !(deg.is_finite() && deg >= 0.0) {
            bail!("{flag} {deg}: an angle in degrees, at least 0 (0 disables the stop)");
        }
    }
    let limit = |deg: f64| (deg > 0.0).then(|| deg.to_radians());
    // Refused rather than clamped: the run would be less accurate than asked.
    if !(a.rtol >= MIN_RTOL && a.rtol < 1.0) {
        bail!(
            "--rtol {:?}: a relative tolerance from {MIN_RTOL:.1e} (ten units of rounding, the integrators' floor) to below 1",
            a.rtol
        );
    }
    if !(a.atol > 0.0 && a.atol.is_finite()) {
        bail!("--atol {:?}: a positive, finite absolute tolerance", a.atol);
    }
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
    let request = SimulateRequest {
        initial: ic,
        inputs,
        duration: a.duration,
        options: opts,
        ..request
    };
    let outcome = simulate::simulate(&bike, &request)?;
    let summary = outcome.summary();
    let sim = &outcome.simulation;
    let inputs = &request.inputs;
    outln!(
        "model {} ({}), bicycle {}",
        summary.model,
        if summary.free_speed {
            "free speed"
        } else {
            "driven speed"
        },
        a.bike
    );
    outln!("  stop: {}", summary.stop);
    outln!(
        "  {}: simulated {:.3} s in {:.3} ms ({:.0}x real time), {} right-hand-side evaluations, {} steps ({} rejected)",
        request.options.method.name(),
        summary.simulated_seconds,
        summary.wall_seconds * 1e3,
        summary.simulated_seconds / summary.wall_seconds.max(1e-12),
        summary.rhs_evaluations,
        summary.accepted_steps,
        summary.rejected_steps
    );
    outln!(
        "  max holonomic constraint residual {:.2e}, max velocity-constraint residual {:.2e}, relative energy change {:.2e}",
        summary.max_constraint_residual,
        summary.max_velocity_residual,
        summary.relative_energy_change
    );
    if let Some(out) = &a.out {
        save_simulation_csv(out, sim)?;
        eprintln!("wrote {}", out.display());
    }
    if let Some(plot) = &a.plot {
        plot_opts.subject = Some(bikedyn::report::plot::subject(&a.bike, Some(&sim.model)));
        plot_simulation(plot, sim, inputs, &plot_opts)?;
        eprintln!("wrote {}", plot.display());
    }
    Ok(true)
}
