//! The sampled motion of the bicycle ([`Trajectory`]): what a simulated run
//! gives ([`trajectory_for_run`]) and what the synthetic sensor model takes
//! (`experiment::synth::record_run`, issue 8), with the test motions of
//! `experiment::synth`.

use serde::Serialize;

use super::{SimulateError, Simulation};
use crate::random::SplitMix64;

/// A sampled motion of the bicycle, thesis conventions: yaw phi, roll theta
/// (positive leaning right), frame pitch beta (the model coordinate; about
/// minus the steer-axis tilt when upright), steer gamma (positive turning
/// left), rear wheel rotation psi (increases when rolling forward), and the
/// forward speed. All series have the length of `t`, which increases; the
/// IMU logger of a synthetic run starts at `t[0]`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Trajectory {
    /// Time (s).
    pub t: Vec<f64>,
    /// Yaw (rad).
    pub yaw: Vec<f64>,
    /// Roll (rad).
    pub roll: Vec<f64>,
    /// Frame pitch (rad).
    pub pitch: Vec<f64>,
    /// Steer (rad).
    pub steer: Vec<f64>,
    /// Rear wheel rotation (rad).
    pub rear_wheel_angle: Vec<f64>,
    /// Forward speed of the rear contact point (m/s): for the truth files;
    /// the sensor writer reads the wheel rotation instead.
    pub speed: Vec<f64>,
}

impl Trajectory {
    /// Samples closer in time than this (s) are one sample: far below any
    /// sample interval, far above the rounding of a time near 10 s.
    pub const MIN_STEP: f64 = 1e-9;

    /// The angles and speed of a simulation. Duplicate samples at kick times
    /// (before and after the velocity jump) are merged: angles are continuous.
    /// So are samples within [`Trajectory::MIN_STEP`] of the one before (an
    /// event a rounding error from an output time).
    pub fn from_simulation(sim: &Simulation) -> Result<Self, SimulateError> {
        use crate::model::CoordinateRole as R;
        let col = |role| sim.require_coordinate(role, "the run's trajectory");
        let (yaw, roll, pitch, steer, psi) = (
            col(R::Yaw)?,
            col(R::Roll)?,
            col(R::Pitch)?,
            col(R::Steer)?,
            col(R::RearWheelRotation)?,
        );
        let mut r = Trajectory::default();
        for i in 0..sim.t.len() {
            if r.t.last().is_some_and(|&last| sim.t[i] <= last + Self::MIN_STEP) {
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
    pub fn append(&mut self, other: &Trajectory, offset: f64) {
        for i in 0..other.t.len() {
            let t = other.t[i] + offset;
            if let Some(&last) = self.t.last() {
                if t <= last + Self::MIN_STEP {
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

/// The physical side of a synthetic measured run (issue 7, point 6): the
/// bicycle is pushed by hand, upright, from rest to `speed` over
/// `launch_duration` with small hand disturbances of roll and steer, released,
/// kicked at the saddle `kick_delay` after release, and left to run for
/// `free_duration` after the kick (or until it falls). Times in s, angles in
/// rad, speed in m/s, impulse in N s.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RunPlan {
    pub launch_duration: f64,
    pub speed: f64,
    /// Amplitude of the hand's roll disturbance.
    pub hand_roll: f64,
    /// Amplitude of the hand's steer disturbance.
    pub hand_steer: f64,
    pub kick_delay: f64,
    pub kick_impulse: f64,
    pub free_duration: f64,
    /// Sample interval of the returned trajectory.
    pub sample_interval: f64,
    /// Seed of the hand disturbances.
    pub seed: u64,
}

/// Stream of a run plan's draws: the seed mixed with a constant, so it
/// differs from the hand disturbances' stream, which starts from the seed
/// itself.
const PLAN_STREAM: u64 = 0x0005_EED0_FB1C_7C1E;

impl RunPlan {
    /// A plan drawn like the thesis's field tests (section 5): launch 2-3 s
    /// to 3-7 m/s, hand disturbances up to 1 deg of roll and 2 deg of steer,
    /// kick 0.6-1.4 s after release with 2-5 N s toward either side, 4-6 s of
    /// free response, samples every 1 ms.
    pub fn random(seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed ^ PLAN_STREAM);
        let mut u = |lo: f64, hi: f64| rng.uniform(lo, hi);
        let side = if u(0.0, 1.0) < 0.5 { -1.0 } else { 1.0 };
        RunPlan {
            launch_duration: u(2.0, 3.0),
            speed: u(3.0, 7.0),
            hand_roll: u(0.2, 1.0).to_radians(),
            hand_steer: u(0.5, 2.0).to_radians(),
            kick_delay: u(0.6, 1.4),
            kick_impulse: side * u(2.0, 5.0),
            free_duration: u(4.0, 6.0),
            sample_interval: 0.001,
            seed,
        }
    }
}

/// Smooth hand disturbance: three sinusoids of 0.3-1.5 Hz with random phases,
/// faded in from rest; returns value and rate at `t`.
struct Hand {
    parts: [(f64, f64, f64); 3],
}

impl Hand {
    fn new(amplitude: f64, rng: &mut SplitMix64) -> Self {
        let mut part = || {
            let f = 0.3 + 1.2 * rng.next_f64();
            let ph = 2.0 * std::f64::consts::PI * rng.next_f64();
            (amplitude / 3.0, 2.0 * std::f64::consts::PI * f, ph)
        };
        Hand {
            parts: [part(), part(), part()],
        }
    }
    fn at(&self, t: f64, fade: f64) -> (f64, f64) {
        // w(t) = 1 - exp(-t / fade) fades the disturbance in from rest.
        let (w, dw) = ((1.0 - (-t / fade).exp()), (-t / fade).exp() / fade);
        let (mut x, mut dx) = (0.0, 0.0);
        for &(a, om, ph) in &self.parts {
            let s = (om * t + ph).sin() - ph.sin();
            x += a * s;
            dx += a * om * (om * t + ph).cos();
        }
        (w * x, dw * x + w * dx)
    }
}

/// Simulate a whole synthetic run of model `M`: the hand-held launch
/// (prescribed, kinematically consistent with the rolling constraints:
/// yaw follows from the steer and roll the hand imposes), the release, the
/// kick and the free response from the nonlinear equations. Returns the
/// orientation history (hand-over to the measured-run writer) and the
/// simulation of the free part (its time starts at the release). A
/// controller (`feedback`, a bicycle file's `[feedback]` table) acts from
/// the release on: the hand holds the bicycle before.
pub fn trajectory_for_run<M: crate::model::MultibodyModel>(
    param: &[f64],
    plan: &RunPlan,
    feedback: Option<&crate::feedback::GainSchedule>,
    opts: &super::SimOptions,
) -> Result<(Trajectory, Simulation), SimulateError> {
    use super::{initial_state, simulate, Evaluator, InitialConditions, Inputs, Kick};
    let bad = |m: &str| Err(SimulateError::InvalidInput(format!("run plan: {m} ({plan:?})")));
    if !(plan.launch_duration > 0.1 && plan.speed > 0.0 && plan.sample_interval > 0.0) {
        return bad("launch duration, speed and sample interval must be positive");
    }
    if !(plan.kick_delay >= 0.0 && plan.free_duration > 0.0) {
        return bad("kick delay must be >= 0 and free duration positive");
    }
    let mut rng = SplitMix64::new(plan.seed);
    let hand_roll = Hand::new(plan.hand_roll, &mut rng);
    let hand_steer = Hand::new(plan.hand_steer, &mut rng);
    let fade = 0.3 * plan.launch_duration;
    let tl = plan.launch_duration;
    let v_at = |t: f64| {
        let u = (t / tl).clamp(0.0, 1.0);
        plan.speed * u * u * (3.0 - 2.0 * u)
    };
    let dist_at = |t: f64| {
        let u = (t / tl).clamp(0.0, 1.0);
        plan.speed * tl * (u * u * u - 0.5 * u * u * u * u)
    };
    // Launch: configuration and yaw rate from the constraints at the
    // reference speed, scaled to the hand's speed (velocities are linear in
    // the independent rates and the driving speed).
    let ic_ref = InitialConditions {
        speed: plan.speed,
        ..Default::default()
    };
    let (y0, param_v) = initial_state::<M>(param, &ic_ref)?;
    let rt = super::rhs::rolling_radius::<M>(&param_v, &super::rhs::BicycleCoordinates::of::<M>()?)?;
    let inputs = Inputs::default();
    let eval = Evaluator::<M>::new(&param_v, &inputs)?;
    let c = eval.coords;
    let l = eval.layout.clone();
    let n = (tl / plan.sample_interval).round() as usize;
    let mut traj = Trajectory::default();
    let (mut yaw, mut last_rate) = (0.0, 0.0);
    let mut at_release = (0.0, 0.0, 0.0, 0.0);
    for k in 0..=n {
        let t = k as f64 * tl / n as f64;
        let (r, dr) = hand_roll.at(t, fade);
        let (s, ds) = hand_steer.at(t, fade);
        let mut y = y0.clone();
        y[c.roll_ind] = r;
        y[c.steer_ind] = s;
        y[l.time()] = 0.0;
        // Free-speed models: the reference state's rear wheel rate is the
        // speed; zero it for the homogeneous part.
        let (p_full, dp_full) = {
            y[l.rates() + c.roll_ind] = dr;
            y[l.rates() + c.steer_ind] = ds;
            eval.full_state(0.0, &y)?
        };
        y[l.rates() + c.roll_ind] = 0.0;
        y[l.rates() + c.steer_ind] = 0.0;
        let (_, dp_drive) = eval.full_state(0.0, &y)?;
        let v = v_at(t);
        let rate = (dp_full[c.yaw] - dp_drive[c.yaw]) + v / plan.speed * dp_drive[c.yaw];
        if k > 0 {
            yaw += 0.5 * (rate + last_rate) * tl / n as f64;
        }
        last_rate = rate;
        traj.t.push(t);
        traj.yaw.push(yaw);
        traj.roll.push(r);
        traj.pitch.push(p_full[c.pitch]);
        traj.steer.push(s);
        traj.rear_wheel_angle.push(dist_at(t) / rt);
        traj.speed.push(v);
        at_release = (r, s, dr, ds);
    }
    let ic = InitialConditions {
        roll: at_release.0,
        steer: at_release.1,
        roll_rate: at_release.2,
        steer_rate: at_release.3,
        speed: plan.speed,
        yaw,
        ..InitialConditions::default()
    };
    let inputs = Inputs {
        kicks: vec![Kick::at_saddle(plan.kick_delay, plan.kick_impulse)],
        pulses: vec![],
        feedback: feedback.cloned(),
    };
    let o = super::SimOptions {
        output_interval: plan.sample_interval,
        ..*opts
    };
    let sim = simulate::<M>(param, &ic, &inputs, plan.kick_delay + plan.free_duration, &o)?;
    let mut free = Trajectory::from_simulation(&sim)?;
    let psi0 = dist_at(tl) / rt;
    for x in &mut free.rear_wheel_angle {
        *x += psi0;
    }
    traj.append(&free, tl);
    Ok((traj, sim))
}
