//! Orientation histories of a simulated run, in the form the synthetic
//! measured-run writer of issue 8 takes (`experiment::synth::Trajectory`:
//! `t, yaw, roll, pitch, steer, rear_wheel_angle`, thesis conventions, rad, s).

use serde::Serialize;

use super::{SimulateError, Simulation};

/// Angles of a run against time (thesis conventions, rad, s): yaw phi, roll
/// theta (positive leaning right), frame pitch beta, steer gamma (positive
/// turning left) and rear wheel rotation psi.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RunTrajectory {
    pub t: Vec<f64>,
    pub yaw: Vec<f64>,
    pub roll: Vec<f64>,
    pub pitch: Vec<f64>,
    pub steer: Vec<f64>,
    pub rear_wheel_angle: Vec<f64>,
    /// Forward speed of the rear contact point (m/s), for the truth file.
    pub speed: Vec<f64>,
}

impl RunTrajectory {
    /// Extract the angles from a simulation. Duplicate samples at kick times
    /// (before and after the velocity jump) are merged: angles are continuous.
    pub fn from_simulation(sim: &Simulation) -> Result<Self, SimulateError> {
        let col = |name: &'static str| {
            sim.coordinate(name)
                .ok_or(SimulateError::MissingCoordinate { model: sim.model, name })
        };
        let (yaw, roll, pitch, steer, psi) = (col("phi")?, col("theta")?, col("beta")?, col("gamma")?, col("psi")?);
        let mut r = RunTrajectory::default();
        for i in 0..sim.t.len() {
            if i > 0 && sim.t[i] <= sim.t[i - 1] {
                continue;
            }
            r.t.push(sim.t[i]);
            r.yaw.push(yaw[i]);
            r.roll.push(roll[i]);
            r.pitch.push(pitch[i]);
            r.steer.push(steer[i]);
            r.rear_wheel_angle.push(psi[i]);
            r.speed.push(sim.speed[i]);
        }
        Ok(r)
    }

    /// Append another trajectory that starts where this one ends (its first
    /// sample is dropped if it repeats the last time), shifting its time by
    /// `offset`.
    pub fn append(&mut self, other: &RunTrajectory, offset: f64) {
        for i in 0..other.t.len() {
            let t = other.t[i] + offset;
            if let Some(&last) = self.t.last() {
                if t <= last {
                    continue;
                }
            }
            self.t.push(t);
            self.yaw.push(other.yaw[i]);
            self.roll.push(other.roll[i]);
            self.pitch.push(other.pitch[i]);
            self.steer.push(other.steer[i]);
            self.rear_wheel_angle.push(other.rear_wheel_angle[i]);
            self.speed.push(other.speed[i]);
        }
    }
}
