//! The measured data identification fits: one [`Segment`] per kick (the
//! free response after it, on the IMU clock), what its roll channel
//! measures, and the noise scales that weight its channels. A segment's
//! initial state is estimated from its first samples: the starting point of
//! its nuisances in a fit.

use super::{at_rest, NUISANCE};
use crate::feedback::GainSchedule;
use serde::Serialize;

/// What the roll channel of a segment measures: the roll angle (the
/// thesis's IMU orientation) or the roll rate (a gyro, as on the TU Delft
/// steer-by-wire bicycle, whose roll angle is a filter's estimate).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RollChannel {
    /// Roll angle (rad).
    Angle,
    /// Roll rate (rad/s).
    Rate,
}

impl RollChannel {
    /// Name of the channel in reports.
    pub fn describe(self) -> &'static str {
        match self {
            RollChannel::Angle => "roll",
            RollChannel::Rate => "roll rate",
        }
    }
    /// Unit of the channel in reports (degrees).
    pub fn unit_deg(self) -> &'static str {
        match self {
            RollChannel::Angle => "deg",
            RollChannel::Rate => "deg/s",
        }
    }
}

/// One measured free response.
#[derive(Clone, Debug, Serialize)]
pub struct Segment {
    /// Run (path) the kick belongs to.
    pub run: String,
    /// Time of the window start on the IMU clock (s).
    pub t0: f64,
    /// Sample times from the window start (s).
    pub t: Vec<f64>,
    /// Measured roll channel, positive leaning right: the roll angle (rad)
    /// or, for [`RollChannel::Rate`], the roll rate (rad/s).
    pub roll: Vec<f64>,
    /// What `roll` measures.
    pub roll_channel: RollChannel,
    /// Measured steer (rad, positive turning left).
    pub steer: Vec<f64>,
    /// Speed sample times from the window start (s).
    pub speed_t: Vec<f64>,
    /// Measured forward speed (m/s).
    pub speed: Vec<f64>,
    /// Initial state estimated from the data: roll, steer (rad), their rates
    /// (rad/s), speed (m/s).
    pub initial: [f64; NUISANCE],
    /// Mean speed over the window (m/s) and its range.
    pub mean_speed: f64,
    pub speed_interval: [f64; 2],
    /// Measured weave eigenvalue and its standard error (1/s), when fitted.
    pub weave: Option<([f64; 2], [f64; 2])>,
    /// Coefficient of determination of that eigenvalue fit.
    pub weave_r2: Option<f64>,
    /// The steer angle comes from two orientation sensors (frame and
    /// handlebar), whose heading references differ run by run: its bias
    /// over the window is a nuisance of the kick ([`super::STEER_BIAS`]).
    /// An encoder's steer (the TU Delft logs) has none.
    pub steer_bias: bool,
    /// The controller the experiment ran (a bicycle file's `[feedback]`
    /// table), closed around every simulation of the kick.
    #[serde(skip)]
    pub feedback: Option<GainSchedule>,
}

impl Segment {
    /// Build a segment from measured series on one clock; `t0` is the window
    /// start. The initial roll, steer and rates come from a least-squares
    /// line through the first `SLOPE_SPAN` seconds (a slope over a tenth of a
    /// weave period averages the 120 Hz noise without bending the response).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        run: String,
        t0: f64,
        t: Vec<f64>,
        roll: Vec<f64>,
        steer: Vec<f64>,
        speed_t: Vec<f64>,
        speed: Vec<f64>,
        weave: Option<([f64; 2], [f64; 2])>,
    ) -> Option<Segment> {
        const SLOPE_SPAN: f64 = 0.06;
        if t.len() < 12 || speed.is_empty() {
            return None;
        }
        let line = |x: &[f64]| {
            let k = t.iter().take_while(|&&s| s <= SLOPE_SPAN).count().max(4).min(t.len());
            let (n, st, sx) = (k as f64, t[..k].iter().sum::<f64>(), x[..k].iter().sum::<f64>());
            let stt: f64 = t[..k].iter().map(|a| a * a).sum();
            let stx: f64 = t[..k].iter().zip(&x[..k]).map(|(a, b)| a * b).sum();
            let slope = (n * stx - st * sx) / (n * stt - st * st);
            ((sx - slope * st) / n, slope)
        };
        let (r0, dr0) = line(&roll);
        let (s0, ds0) = line(&steer);
        let v0 = speed[0];
        let mean_speed = speed.iter().sum::<f64>() / speed.len() as f64;
        let lo = speed.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = speed.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let initial = at_rest([r0, s0, dr0, ds0, v0]);
        if initial.iter().any(|x| !x.is_finite()) || !(v0 > 0.0) {
            return None;
        }
        Some(Segment {
            run,
            t0,
            t,
            roll,
            roll_channel: RollChannel::Angle,
            steer,
            speed_t,
            speed,
            initial,
            mean_speed,
            speed_interval: [lo, hi],
            weave,
            weave_r2: None,
            steer_bias: false,
            feedback: None,
        })
    }

    /// A segment whose roll channel is a gyro's roll rate (rad/s): the
    /// initial roll comes from `roll_angle` (a filter's estimate, used only
    /// as the starting value of that nuisance), the initial roll rate from
    /// the rate itself.
    #[allow(clippy::too_many_arguments)]
    pub fn with_roll_rate(
        run: String,
        t0: f64,
        t: Vec<f64>,
        roll_angle: Vec<f64>,
        roll_rate: Vec<f64>,
        steer: Vec<f64>,
        speed_t: Vec<f64>,
        speed: Vec<f64>,
        weave: Option<([f64; 2], [f64; 2])>,
    ) -> Option<Segment> {
        let mut s = Segment::new(run, t0, t, roll_angle, steer, speed_t, speed, weave)?;
        if roll_rate.len() != s.t.len() || roll_rate.iter().any(|x| !x.is_finite()) {
            return None;
        }
        let k = s.t.iter().take_while(|&&x| x <= 0.06).count().clamp(1, s.t.len());
        s.initial[2] = roll_rate[..k].iter().sum::<f64>() / k as f64;
        s.roll = roll_rate;
        s.roll_channel = RollChannel::Rate;
        Some(s)
    }

    /// The same segment with its steer's bias fitted per kick (a steer
    /// angle from two orientation sensors).
    pub fn with_steer_bias(mut self) -> Segment {
        self.steer_bias = true;
        self
    }

    /// The same segment simulated with the experiment's controller.
    pub fn with_feedback(mut self, feedback: Option<GainSchedule>) -> Segment {
        self.feedback = feedback;
        self
    }

    /// Window length (s).
    pub fn duration(&self) -> f64 {
        self.t
            .last()
            .copied()
            .unwrap_or(0.0)
            .max(self.speed_t.last().copied().unwrap_or(0.0))
    }

    pub(super) fn len(&self) -> usize {
        2 * self.t.len() + self.speed.len()
    }
}

/// Noise scales of the three channels.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Weights {
    /// Roll (rad).
    pub roll: f64,
    /// Steer (rad).
    pub steer: f64,
    /// Speed (m/s).
    pub speed: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_initial_state_from_a_line_through_the_first_samples() {
        let t: Vec<f64> = (0..120).map(|k| k as f64 / 120.0).collect();
        let roll: Vec<f64> = t.iter().map(|&x| 0.02 + 0.3 * x).collect();
        let steer: Vec<f64> = t.iter().map(|&x| -0.01 - 0.5 * x).collect();
        let s = Segment::new(
            "r".into(),
            0.0,
            t.clone(),
            roll,
            steer,
            vec![0.0, 0.5],
            vec![5.0, 4.9],
            None,
        )
        .unwrap();
        assert!((s.initial[0] - 0.02).abs() < 1e-12 && (s.initial[2] - 0.3).abs() < 1e-9);
        assert!((s.initial[1] + 0.01).abs() < 1e-12 && (s.initial[3] + 0.5).abs() < 1e-9);
        assert_eq!(s.initial[4], 5.0);
        assert_eq!(s.speed_interval, [4.9, 5.0]);
    }
}
