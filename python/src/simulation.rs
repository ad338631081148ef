//! `simulate`: the nonlinear simulation.

use super::*;

/// A simulation's output: `(model, column names, columns bytes (columns,
/// samples), samples, stop reason, statistics JSON)`, the columns those of
/// `bikedyn simulate --out`'s CSV.
pub(crate) type SimulationOut<'py> = (
    String,
    Vec<String>,
    Bound<'py, PyBytes>,
    usize,
    String,
    String,
    Vec<(&'static str, String)>,
);

/// Nonlinear simulation (SI units: rad, rad/s, m/s, N m, N s).
#[pyfunction]
#[pyo3(signature = (bike, duration, initial, kicks, pulses, model=None, free_speed=false, rtol=1e-8, atol=1e-10, method="dop853".to_string(), dt=0.01, roll_limit=None, steer_limit=None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn simulate<'py>(
    py: Python<'py>,
    bike: &PyBicycle,
    duration: f64,
    initial: (f64, f64, f64, f64, f64, f64),
    kicks: Vec<(f64, f64, Option<f64>, Option<f64>)>,
    pulses: Vec<(String, f64, f64, f64, String)>,
    model: Option<String>,
    free_speed: bool,
    rtol: f64,
    atol: f64,
    method: String,
    dt: f64,
    roll_limit: Option<f64>,
    steer_limit: Option<f64>,
) -> PyResult<SimulationOut<'py>> {
    let b = &bike.inner;
    let (model, header, columns, samples, stop, stats, roles) = detached(py, move || {
        let (roll, steer, roll_rate, steer_rate, speed, yaw) = initial;
        for (name, x) in [
            ("roll", roll),
            ("steer", steer),
            ("roll_rate", roll_rate),
            ("steer_rate", steer_rate),
            ("speed", speed),
            ("yaw", yaw),
            ("duration", duration),
            ("dt", dt),
            ("rtol", rtol),
            ("atol", atol),
        ] {
            if !x.is_finite() {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("{name} = {x} is not a finite number"),
                ));
            }
        }
        let mut kick_list = Vec::new();
        for (k, &(time, impulse, ahead, height)) in kicks.iter().enumerate() {
            let mut kick = Kick::at_saddle(time, impulse);
            if let (Some(a), Some(h)) = (ahead, height) {
                kick.ahead = a;
                kick.height = h;
            }
            if ![kick.time, kick.impulse, kick.ahead, kick.height]
                .iter()
                .all(|x| x.is_finite())
            {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("kicks[{k}]: every number must be finite"),
                ));
            }
            kick_list.push(kick);
        }
        let mut pulse_list = Vec::new();
        for (k, (target, start, length, amplitude, shape)) in pulses.iter().enumerate() {
            let target = match target.as_str() {
                "roll" => PulseTarget::Roll,
                "steer" => PulseTarget::Steer,
                other => {
                    return Err(Failure::new(
                        "InvalidArgumentError",
                        format!("pulses[{k}]: target `{other}` is neither roll nor steer"),
                    ))
                }
            };
            let shape = match shape.as_str() {
                "rect" | "rectangular" => PulseShape::Rectangular,
                "halfsine" | "half-sine" => PulseShape::HalfSine,
                other => {
                    return Err(Failure::new(
                        "InvalidArgumentError",
                        format!("pulses[{k}]: shape `{other}` is neither rect nor halfsine"),
                    ))
                }
            };
            if !(length.is_finite() && *length > 0.0 && start.is_finite() && amplitude.is_finite()) {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("pulses[{k}]: start and amplitude must be finite and the duration positive"),
                ));
            }
            pulse_list.push(TorquePulse {
                target,
                shape,
                start: *start,
                duration: *length,
                amplitude: *amplitude,
            });
        }
        let method = method.parse().map_err(|e| Failure::new("InvalidArgumentError", e))?;
        let opts = SimOptions {
            rtol,
            atol,
            method,
            output_interval: dt,
            events: Events {
                roll_limit,
                steer_limit,
            },
        };
        let request = bikedyn::simulate::SimulateRequest {
            model,
            free_speed,
            initial: InitialConditions {
                roll,
                steer,
                roll_rate,
                steer_rate,
                speed,
                yaw,
                ..InitialConditions::default()
            },
            inputs: Inputs {
                kicks: kick_list,
                pulses: pulse_list,
                feedback: None,
            },
            duration,
            options: opts,
        };
        let outcome = bikedyn::simulate::simulate(b, &request).map_err(sim_failure)?;
        let sim = &outcome.simulation;
        let header = bikedyn::report::simulate::simulation_csv_header(&sim);
        let n = sim.t.len();
        let mut columns: Vec<f64> = Vec::with_capacity(header.len() * n);
        columns.extend(&sim.t);
        for j in 0..sim.coordinates.len() {
            columns.extend(sim.p.iter().map(|row| row[j]));
        }
        for j in 0..sim.coordinates.len() {
            columns.extend(sim.dp.iter().map(|row| row[j]));
        }
        for c in [
            &sim.speed,
            &sim.kinetic_energy,
            &sim.potential_energy,
            &sim.constraint_residual,
        ] {
            columns.extend(c.iter());
        }
        for j in 0..sim.states.len() {
            columns.extend(sim.z.iter().map(|row| row[j]));
        }
        if columns.len() != header.len() * n {
            return Err(Failure::new(
                "InternalError",
                "simulation columns do not match the CSV header",
            ));
        }
        let stats =
            serde_json::to_string(&outcome.summary()).map_err(|e| Failure::new("InternalError", e.to_string()))?;
        let roles = sim
            .roles
            .iter()
            .map(|&(role, i)| (role_name(role), sim.coordinates[i].to_string()))
            .collect();
        Ok((
            sim.model.to_string(),
            header,
            columns,
            n,
            sim.stop.to_string(),
            stats,
            roles,
        ))
    })?;
    Ok((
        model,
        header,
        PyBytes::new(py, &bytes_of(&columns)),
        samples,
        stop,
        stats,
        roles,
    ))
}

/// The snake-case name of a coordinate's role (what `Simulation.roles` maps
/// to the model's own coordinate names).
pub(crate) fn role_name(role: bikedyn::runtime::model::CoordinateRole) -> &'static str {
    use bikedyn::runtime::model::CoordinateRole as R;
    match role {
        R::RearContactX => "rear_contact_x",
        R::RearContactY => "rear_contact_y",
        R::Yaw => "yaw",
        R::Roll => "roll",
        R::Pitch => "pitch",
        R::Steer => "steer",
        R::RearWheelRotation => "rear_wheel_rotation",
        R::FrontWheelRotation => "front_wheel_rotation",
        R::FrontContactRimAngle => "front_contact_rim_angle",
    }
}

pub(crate) fn sim_failure(e: bikedyn::simulate::SimulationError) -> Failure {
    use bikedyn::simulate::SimulationError as E;
    match e {
        E::Bicycle(b) => bicycle_failure(b),
        E::NoFreeSpeedVariant { .. } => Failure::new("ModelError", e),
        E::Linearize(_) => Failure::new("ParameterError", e),
        E::Simulate(_) => Failure::new("ComputationError", e),
    }
}
