//! Inputs and perturbations: initial conditions, impulsive kicks, torque
//! pulses, and the events that stop a run.

use crate::feedback::GainSchedule;
use serde::{Deserialize, Serialize};

/// Initial conditions in the thesis's conventions (rad, rad/s, m/s): roll
/// positive leaning right, steer positive turning left.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct InitialConditions {
    /// Roll angle theta (rad).
    pub roll: f64,
    /// Steer angle gamma (rad).
    pub steer: f64,
    /// Roll rate (rad/s).
    pub roll_rate: f64,
    /// Steer rate (rad/s).
    pub steer_rate: f64,
    /// Forward speed of the rear contact point (m/s). For a driven-speed
    /// model this also sets the parameter `V`.
    pub speed: f64,
    /// Yaw angle phi (rad).
    pub yaw: f64,
    /// Rates of the model's extra first-order states at the start (`M::STATES`
    /// in order, at most [`MAX_STATE_RATES`]; a tyre model's lagged lateral
    /// forces, N/s). The states' values are in the parameter vector's tail;
    /// the free independent rates (with tyre slip, the lateral ones) are
    /// solved so that the states change at these rates. Zero (the default):
    /// the states at rest relative to the motion, as in steady running; a
    /// start just after a kick has forces lagging behind the slip.
    #[serde(default, skip_serializing_if = "all_zero")]
    pub state_rates: [f64; MAX_STATE_RATES],
}

/// Most extra states whose initial rates [`InitialConditions`] can set.
pub const MAX_STATE_RATES: usize = 2;

fn all_zero(x: &[f64; MAX_STATE_RATES]) -> bool {
    x.iter().all(|v| *v == 0.0)
}

impl Default for InitialConditions {
    /// Upright, straight ahead, 4.5 m/s.
    fn default() -> Self {
        InitialConditions {
            roll: 0.0,
            steer: 0.0,
            roll_rate: 0.0,
            steer_rate: 0.0,
            speed: 4.5,
            yaw: 0.0,
            state_rates: [0.0; MAX_STATE_RATES],
        }
    }
}

/// An impulsive lateral kick at a point of the rear frame (the thesis hits
/// the saddle, section 5). The velocity jump is consistent with all
/// constraints: `Mi dq' = E^T H_P^T J` (impulse-momentum of the constrained
/// system; positions do not change).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Kick {
    /// Time of the kick (s).
    pub time: f64,
    /// Lateral impulse (N s), horizontal, perpendicular to the heading,
    /// positive toward the rider's right (so that it rolls the bicycle to the
    /// right, positive theta).
    pub impulse: f64,
    /// Point of application: distance ahead of the rear contact point (m)
    /// and height above the ground (m) in the upright reference configuration;
    /// the point is fixed in the rear frame.
    pub ahead: f64,
    /// Height above the ground (m), upright.
    pub height: f64,
}

impl Kick {
    /// A kick at a typical saddle position (0.25 m ahead of the rear contact,
    /// 0.95 m high; the thesis gives no saddle coordinates).
    pub fn at_saddle(time: f64, impulse: f64) -> Self {
        Kick {
            time,
            impulse,
            ahead: 0.25,
            height: 0.95,
        }
    }
}

/// Which generalized force a torque pulse adds to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PulseTarget {
    /// A torque on the rear frame about the heading's horizontal x axis
    /// (its generalized force is on theta only), positive rolling right.
    Roll,
    /// A torque pair between frame and fork about the steer axis (the
    /// generalized force on gamma), positive turning left.
    Steer,
}

/// Time shape of a torque pulse.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum PulseShape {
    /// Constant amplitude over the duration.
    Rectangular,
    /// `amplitude * sin(pi (t - start) / duration)`.
    HalfSine,
}

/// A torque pulse (N m) of given shape.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TorquePulse {
    pub target: PulseTarget,
    pub shape: PulseShape,
    /// Start time (s).
    pub start: f64,
    /// Duration (s), > 0.
    pub duration: f64,
    /// Peak torque (N m).
    pub amplitude: f64,
}

impl TorquePulse {
    /// Torque at time `t`.
    pub fn value(&self, t: f64) -> f64 {
        let s = (t - self.start) / self.duration;
        if !(0.0..1.0).contains(&s) {
            return 0.0;
        }
        match self.shape {
            PulseShape::Rectangular => self.amplitude,
            PulseShape::HalfSine => self.amplitude * (std::f64::consts::PI * s).sin(),
        }
    }
}

/// All perturbations of a run, and a controller closed around it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Inputs {
    pub kicks: Vec<Kick>,
    pub pulses: Vec<TorquePulse>,
    /// Full-state feedback on the roll and steer torques (a bicycle
    /// file's `[feedback]` table), applied at every evaluation from the
    /// roll and steer angles and rates and the forward speed
    /// ([`GainSchedule::torques`], benchmark signs). Not read from a
    /// request: the application sets it from the bicycle.
    #[serde(skip)]
    pub feedback: Option<GainSchedule>,
}

impl Inputs {
    /// Roll and steer torques at `t` (sum of all pulses).
    pub fn torques(&self, t: f64) -> (f64, f64) {
        let mut r = (0.0, 0.0);
        for p in &self.pulses {
            match p.target {
                PulseTarget::Roll => r.0 += p.value(t),
                PulseTarget::Steer => r.1 += p.value(t),
            }
        }
        r
    }

    /// Times where the right-hand side is not smooth (kicks, pulse edges):
    /// the integration restarts there.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut b: Vec<f64> = self.kicks.iter().map(|k| k.time).collect();
        for p in &self.pulses {
            b.push(p.start);
            b.push(p.start + p.duration);
        }
        b.sort_by(f64::total_cmp);
        b.dedup();
        b
    }
}

/// Events that end a run early.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Events {
    /// Stop when |roll| reaches this angle (rad): the bicycle has fallen
    /// (default 1.0 rad, about 57 degrees; `None` to never stop).
    pub roll_limit: Option<f64>,
    /// Stop when |steer| reaches this angle (rad): the handlebar hits its
    /// stop (default 1.4 rad, about 80 degrees; `None` to never stop).
    pub steer_limit: Option<f64>,
}

impl Default for Events {
    fn default() -> Self {
        Events {
            roll_limit: Some(1.0),
            steer_limit: Some(1.4),
        }
    }
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum StopReason {
    /// The requested duration was reached.
    Completed,
    /// |roll| reached the limit (the bicycle fell) at `time`.
    Fell { time: f64, roll: f64 },
    /// |steer| reached the steer stop at `time`.
    SteerStop { time: f64, steer: f64 },
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Completed => write!(f, "completed"),
            StopReason::Fell { time, roll } => {
                write!(f, "fell: roll reached {:.2} deg at t = {time:.6} s", roll.to_degrees())
            }
            StopReason::SteerStop { time, steer } => write!(
                f,
                "steer stop: steer reached {:.2} deg at t = {time:.6} s",
                steer.to_degrees()
            ),
        }
    }
}
