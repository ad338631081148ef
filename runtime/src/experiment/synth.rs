//! Synthetic measured runs: the sensor model that turns a sampled motion of
//! the bicycle into the readings of `shared/data/FORMAT.md` (orientations of
//! the two IMUs and the reed-switch voltage), with the sensors'
//! imperfections, and a simple launch-kick-response motion for tests. The
//! report layer writes the readings as a run's files (its
//! `experiment::synth::write_run`).

pub use super::records::RunKind;
use crate::random::SplitMix64;
use crate::simulate::trajectory::Trajectory;
use crate::CanonicalMatrices;
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use serde::Serialize;

/// Sensor imperfections. `Default` = values like `shared/data/dev`.
#[derive(Clone, Debug, Serialize)]
pub struct SensorModel {
    /// Frame-sensor misalignment: rotations about x, y, z (rad), composed as
    /// `Rotation3::from_euler_angles`; the sensor reads `R_frame * M`.
    pub frame_misalignment: [f64; 3],
    /// Handlebar-sensor misalignment (as above).
    pub handlebar_misalignment: [f64; 3],
    /// White orientation noise, standard deviation per axis (rad).
    pub orientation_noise: f64,
    /// Heading drift rate (rad/s, about global Z).
    pub heading_drift: f64,
    /// Start-up settling: initial orientation error (rad), decaying with
    /// `settling_time`.
    pub settling_error: f64,
    /// Time constant of the settling (s).
    pub settling_time: f64,
    /// IMU rate (Hz).
    pub imu_rate_hz: f64,
    /// DAQ rate (Hz).
    pub daq_rate_hz: f64,
    /// True clock offset `t_imu - t_daq` (s).
    pub clock_offset: f64,
    /// Nominal offset written to run.toml (s).
    pub nominal_offset: f64,
    /// Magnets on the rear wheel.
    pub magnets: usize,
    /// Rear-wheel circumference (m).
    pub wheel_circumference: f64,
    /// Standard deviation of each magnet's position error along the rim (m).
    pub magnet_spacing_error: f64,
    /// Switch closes within this distance of a magnet (m).
    pub closing_distance: f64,
    /// Supply voltage (V).
    pub supply_v: f64,
    /// Voltage noise (V).
    pub switch_noise_v: f64,
    /// Probability that the switch bounces open for one sample after closing.
    pub bounce_probability: f64,
}

impl Default for SensorModel {
    fn default() -> Self {
        SensorModel {
            frame_misalignment: [0.05, -0.03, 0.04],
            handlebar_misalignment: [-0.04, 0.06, 0.17],
            orientation_noise: 0.003,
            heading_drift: 0.002,
            settling_error: 0.05,
            settling_time: 0.6,
            imu_rate_hz: 120.0,
            daq_rate_hz: 1000.0,
            clock_offset: 1.42,
            nominal_offset: 1.30,
            magnets: 9,
            wheel_circumference: 2.010,
            magnet_spacing_error: 0.003,
            closing_distance: 0.015,
            supply_v: 9.0,
            switch_noise_v: 0.02,
            bounce_probability: 0.3,
        }
    }
}

/// What the pipeline should recover.
#[derive(Clone, Debug, Serialize)]
pub struct SynthTruth {
    /// Run name.
    pub name: String,
    /// Run or calibration.
    pub kind: RunKind,
    /// Frame misalignment (x, y, z Euler angles, rad).
    pub frame_misalignment: [f64; 3],
    /// Handlebar misalignment.
    pub handlebar_misalignment: [f64; 3],
    /// True clock offset (s).
    pub clock_offset: f64,
    /// Physical time of the IMU clock's zero (s).
    pub imu_clock_origin: f64,
    /// Magnet positions along the rim from the first (m).
    pub magnet_positions: Vec<f64>,
    /// Kick time on the IMU clock, if the caller knows it.
    pub kick_time: Option<f64>,
    /// Weave eigenvalue, if the caller knows it.
    pub weave: Option<[f64; 2]>,
}

/// Why a run cannot be recorded.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// The trajectory is not usable.
    #[error("trajectory: {0}")]
    Trajectory(&'static str),
}

/// One reading of an IMU: time on the IMU clock (s) and the orientation it
/// reports.
#[derive(Clone, Copy, Debug)]
pub struct ImuSample {
    /// Time on the IMU clock (s).
    pub time: f64,
    /// Orientation, sign-continuous with the previous reading.
    pub orientation: UnitQuaternion<f64>,
}

/// One reading of the reed switch: time on the DAQ clock (s) and voltage.
#[derive(Clone, Copy, Debug)]
pub struct SwitchSample {
    /// Time on the DAQ clock (s).
    pub time: f64,
    /// Voltage across the switch (V).
    pub volts: f64,
}

/// The sensor readings of one synthetic run, with what the pipeline should
/// recover from them.
#[derive(Clone, Debug)]
pub struct SensorRecording {
    /// Frame IMU at its rate.
    pub frame: Vec<ImuSample>,
    /// Handlebar IMU at its rate.
    pub handlebar: Vec<ImuSample>,
    /// Reed switch at the DAQ rate.
    pub speed_switch: Vec<SwitchSample>,
    /// The truth behind the readings.
    pub truth: SynthTruth,
}

/// Stream of a run's sensor errors: the seed mixed with a constant, so it
/// differs from the streams that start from the seed itself (the hand
/// disturbances and clock offsets of `bikedyn synth`).
const SENSOR_STREAM: u64 = SplitMix64::GAMMA;

fn interp(t: &[f64], x: &[f64], s: f64) -> f64 {
    let k = t.partition_point(|&v| v <= s);
    if k == 0 {
        return x[0];
    }
    if k >= t.len() {
        return x[t.len() - 1];
    }
    let w = (s - t[k - 1]) / (t[k] - t[k - 1]);
    x[k - 1] + w * (x[k] - x[k - 1])
}

/// The readings of the two IMUs and the reed switch of one run, from the
/// angles of `traj` (the reed switch follows its wheel rotation; its speed
/// series is not read), with the sensors' imperfections drawn from `seed`.
pub fn record_run(
    name: &str,
    kind: RunKind,
    traj: &Trajectory,
    sensors: &SensorModel,
    seed: u64,
) -> Result<SensorRecording, SynthError> {
    let n = traj.t.len();
    if n < 2
        || [&traj.yaw, &traj.roll, &traj.pitch, &traj.steer, &traj.rear_wheel_angle]
            .iter()
            .any(|v| v.len() != n)
    {
        return Err(SynthError::Trajectory("all series need the length of t (at least 2)"));
    }
    if traj.t.windows(2).any(|w| !(w[1] > w[0])) {
        return Err(SynthError::Trajectory("t must increase"));
    }
    let mut rng = SplitMix64::new(seed ^ SENSOR_STREAM);
    let e = |a: [f64; 3]| Rotation3::from_euler_angles(a[0], a[1], a[2]);
    let mf = e(sensors.frame_misalignment);
    let mh = e(sensors.handlebar_misalignment);
    let t0 = traj.t[0];
    let t_end = traj.t[n - 1];
    // Settling error axes, fixed per run.
    let mut axis = || Vector3::new(rng.normal(), rng.normal(), rng.normal()).normalize();
    let (ax_f, ax_h) = (axis(), axis());
    let mut frame = Vec::new();
    let mut handlebar = Vec::new();
    let (mut last_f, mut last_h): (Option<UnitQuaternion<f64>>, Option<UnitQuaternion<f64>>) = (None, None);
    let dt_imu = 1.0 / sensors.imu_rate_hz;
    let n_imu = ((t_end - t0) / dt_imu).floor() as usize + 1;
    for k in 0..n_imu {
        let ti = k as f64 * dt_imu;
        let s = t0 + ti;
        let (yaw, roll, pitch, steer) = (
            interp(&traj.t, &traj.yaw, s),
            interp(&traj.t, &traj.roll, s),
            interp(&traj.t, &traj.pitch, s),
            interp(&traj.t, &traj.steer, s),
        );
        let drift = Rotation3::from_axis_angle(&Vector3::z_axis(), sensors.heading_drift * ti);
        let ideal = drift
            * Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), roll)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch);
        let settle = sensors.settling_error * (-ti / sensors.settling_time.max(1e-9)).exp();
        let mut noise = |ax: &Vector3<f64>| {
            let v = Vector3::new(rng.normal(), rng.normal(), rng.normal()) * sensors.orientation_noise + ax * settle;
            Rotation3::new(v)
        };
        let rf = ideal * mf * noise(&ax_f);
        let rh = ideal * Rotation3::from_axis_angle(&Vector3::z_axis(), steer) * mh * noise(&ax_h);
        for (r, last, readings) in [(rf, &mut last_f, &mut frame), (rh, &mut last_h, &mut handlebar)] {
            let mut q = UnitQuaternion::from_rotation_matrix(&r);
            if let Some(l) = last {
                if q.coords.dot(&l.coords) < 0.0 {
                    q = UnitQuaternion::new_unchecked(-q.into_inner());
                }
            }
            *last = Some(q);
            readings.push(ImuSample {
                time: ti,
                orientation: q,
            });
        }
    }
    // Reed switch.
    let r_wheel = sensors.wheel_circumference / std::f64::consts::TAU;
    let nm = sensors.magnets.max(1);
    let spacing = sensors.wheel_circumference / nm as f64;
    let magnets: Vec<f64> = (0..nm)
        .map(|k| {
            k as f64 * spacing
                + if k == 0 {
                    0.0
                } else {
                    sensors.magnet_spacing_error * rng.normal()
                }
        })
        .collect();
    let c = sensors.wheel_circumference;
    let mut speed_switch = Vec::new();
    let dt_daq = 1.0 / sensors.daq_rate_hz;
    let mut k = 0usize;
    let mut was_closed = false;
    let mut bounce_next = false;
    loop {
        let td = k as f64 * dt_daq;
        let ti = td + sensors.clock_offset;
        let s = t0 + ti;
        if s > t_end {
            break;
        }
        if s >= t0 {
            let x = r_wheel * interp(&traj.t, &traj.rear_wheel_angle, s);
            let pos = x.rem_euclid(c);
            let closed = magnets.iter().any(|m| {
                let d = (pos - m).rem_euclid(c);
                d.min(c - d) < sensors.closing_distance
            });
            let mut out = closed;
            if closed && !was_closed {
                bounce_next = rng.next_f64() < sensors.bounce_probability;
            } else if closed && bounce_next {
                out = false;
                bounce_next = false;
            }
            was_closed = closed;
            let v = if out { sensors.supply_v } else { 0.0 } + sensors.switch_noise_v * rng.normal();
            speed_switch.push(SwitchSample { time: td, volts: v });
        }
        k += 1;
    }
    let truth = SynthTruth {
        name: name.to_string(),
        kind,
        frame_misalignment: sensors.frame_misalignment,
        handlebar_misalignment: sensors.handlebar_misalignment,
        clock_offset: sensors.clock_offset,
        imu_clock_origin: t0,
        magnet_positions: magnets,
        kick_time: None,
        weave: None,
    };
    Ok(SensorRecording {
        frame,
        handlebar,
        speed_switch,
        truth,
    })
}

/// A launch, a kick and a free response with a known weave eigenvalue, for
/// testing the pipeline (not a simulation of the bicycle: the response is a
/// prescribed damped oscillation plus a slow capsize drift, and the yaw
/// follows the rolling kinematics `yaw' = (v steer + c steer') cos(l) / w`).
#[derive(Clone, Debug, Serialize)]
pub struct ResponseSpec {
    /// At rest before the launch (s).
    pub rest: f64,
    /// Duration of the push (s).
    pub launch: f64,
    /// Speed at release (m/s).
    pub launch_speed: f64,
    /// Deceleration after release (m/s^2).
    pub deceleration: f64,
    /// Kick after release (s).
    pub kick_delay: f64,
    /// Record after the kick (s).
    pub after_kick: f64,
    /// Weave eigenvalue `[real, imag]`.
    pub weave: [f64; 2],
    /// Change of the eigenvalue per m/s of speed `[real, imag]` (0 = constant).
    pub weave_slope: [f64; 2],
    /// Roll-rate jump of the kick (rad/s).
    pub roll_rate_jump: f64,
    /// Steer amplitude relative to roll, and its phase lead (rad).
    pub steer_ratio: (f64, f64),
    /// Capsize drift: growth rate (1/s) and initial amplitude (rad).
    pub capsize: (f64, f64),
    /// Frame pitch (rad).
    pub frame_pitch: f64,
    /// Wheelbase (m), trail (m), steer-axis tilt (rad) for the yaw.
    pub geometry: (f64, f64, f64),
    /// Sample rate of the trajectory (Hz).
    pub rate_hz: f64,
}

impl Default for ResponseSpec {
    fn default() -> Self {
        ResponseSpec {
            rest: 3.0,
            launch: 2.5,
            launch_speed: 5.0,
            deceleration: 0.15,
            kick_delay: 1.0,
            after_kick: 4.0,
            weave: [-1.5, 6.0],
            weave_slope: [0.0, 0.0],
            roll_rate_jump: 0.6,
            steer_ratio: (0.8, 0.6),
            capsize: (0.1, 0.002),
            frame_pitch: -0.3154,
            geometry: (1.02, 0.076, 0.3154),
            rate_hz: 1000.0,
        }
    }
}

impl ResponseSpec {
    /// Physical time of the kick (s; the trajectory starts at 0).
    pub fn kick_time(&self) -> f64 {
        self.rest + self.launch + self.kick_delay
    }

    /// Speed at physical time `t` (m/s).
    pub fn speed(&self, t: f64) -> f64 {
        let release = self.rest + self.launch;
        if t <= self.rest {
            0.0
        } else if t <= release {
            let u = (t - self.rest) / self.launch;
            self.launch_speed * 0.5 * (1.0 - (std::f64::consts::PI * u).cos())
        } else {
            (self.launch_speed - self.deceleration * (t - release)).max(0.0)
        }
    }

    /// The trajectory.
    pub fn trajectory(&self) -> Trajectory {
        let end = self.kick_time() + self.after_kick;
        let n = (end * self.rate_hz).round() as usize + 1;
        let dt = 1.0 / self.rate_hz;
        let tk = self.kick_time();
        let vk = self.speed(tk);
        let (w, c, lam) = self.geometry;
        let r_wheel = 2.010 / std::f64::consts::TAU;
        let mut tr = Trajectory::default();
        let (mut yaw, mut psi, mut phase, mut logenv) = (0.0, 0.0, 0.0, 0.0);
        let mut prev_steer = 0.0;
        for k in 0..n {
            let t = k as f64 * dt;
            let v = self.speed(t);
            let (roll, steer) = if t >= tk {
                let tau = t - tk;
                let s = self.weave[0] + self.weave_slope[0] * (v - vk);
                let om = self.weave[1] + self.weave_slope[1] * (v - vk);
                if k > 0 && t - dt >= tk {
                    logenv += s * dt;
                    phase += om * dt;
                }
                let amp = self.roll_rate_jump / self.weave[1] * logenv.exp();
                let drift = self.capsize.1 * ((self.capsize.0 * tau).exp() - 1.0);
                (
                    amp * phase.sin() + drift,
                    self.steer_ratio.0 * amp * (phase + self.steer_ratio.1).sin(),
                )
            } else {
                (0.0, 0.0)
            };
            let steer_rate = if k > 0 { (steer - prev_steer) / dt } else { 0.0 };
            prev_steer = steer;
            yaw += (v * steer + c * steer_rate) * lam.cos() / w * dt;
            psi += v / r_wheel * dt;
            tr.t.push(t);
            tr.yaw.push(yaw + 1.0);
            tr.roll.push(roll);
            tr.pitch.push(self.frame_pitch);
            tr.steer.push(steer);
            tr.rear_wheel_angle.push(psi);
            tr.speed.push(v);
        }
        tr
    }
}

/// A calibration trajectory: upright, at rest, steer zero, for `duration` s.
pub fn rest_trajectory(duration: f64, frame_pitch: f64, yaw: f64) -> Trajectory {
    let n = (duration * 1000.0) as usize + 1;
    Trajectory {
        t: (0..n).map(|k| k as f64 * 1e-3).collect(),
        yaw: vec![yaw; n],
        roll: vec![0.0; n],
        pitch: vec![frame_pitch; n],
        steer: vec![0.0; n],
        rear_wheel_angle: vec![0.0; n],
        speed: vec![0.0; n],
    }
}

/// The response of the linearized bicycle to a kick, with the launch and
/// the speed of `spec` (its `weave`, `steer_ratio` and `capsize` are not
/// used): `M0 q'' + v C1 q' + (g K0 + v^2 K2) q = 0` with `q = [roll,
/// delta]` (Meijaard et al. 2007; thesis steer `gamma = -delta`) integrated
/// by fourth-order Runge-Kutta at the instantaneous speed, from upright with
/// the roll rate `spec.roll_rate_jump` at the kick. All modes (weave,
/// capsize, castering) are in it, as in a measured run; the yaw follows the
/// rolling kinematics. `None` if the mass matrix is singular.
pub fn linear_model_trajectory(c: &CanonicalMatrices, spec: &ResponseSpec) -> Option<Trajectory> {
    let end = spec.kick_time() + spec.after_kick;
    let n = (end * spec.rate_hz).round() as usize + 1;
    let dt = 1.0 / spec.rate_hz;
    let tk = spec.kick_time();
    let (w, trail, lam) = spec.geometry;
    let r_wheel = 2.010 / std::f64::consts::TAU;
    let mut x = nalgebra::Vector4::zeros();
    let mut kicked = false;
    let mut tr = Trajectory::default();
    let (mut yaw, mut psi) = (1.0, 0.0);
    for k in 0..n {
        let t = k as f64 * dt;
        let v = spec.speed(t);
        if !kicked && t >= tk {
            x[2] = spec.roll_rate_jump;
            kicked = true;
        }
        let (roll, delta, delta_rate) = (x[0], x[1], x[3]);
        tr.t.push(t);
        tr.yaw.push(yaw);
        tr.roll.push(roll);
        tr.pitch.push(spec.frame_pitch);
        tr.steer.push(-delta);
        tr.rear_wheel_angle.push(psi);
        tr.speed.push(v);
        // Steer gamma = -delta: turning left raises the yaw.
        yaw += (v * (-delta) + trail * (-delta_rate)) * lam.cos() / w * dt;
        psi += v / r_wheel * dt;
        if kicked {
            let a = |s: f64| c.state_matrix(spec.speed(s));
            let (a0, a1, a2) = (a(t)?, a(t + 0.5 * dt)?, a(t + dt)?);
            let k1 = a0 * x;
            let k2 = a1 * (x + 0.5 * dt * k1);
            let k3 = a1 * (x + 0.5 * dt * k2);
            let k4 = a2 * (x + dt * k3);
            x += dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
    }
    Some(tr)
}
