//! Roll and steer angles from the two IMU orientations, and the estimate of
//! each sensor's mounting misalignment from the calibration run.
//!
//! Conventions (thesis, section 3 and eq. 87): the ideal frame sensor has
//! `R3 = Rz(yaw) Rx(roll) Ry(pitch)`, the ideal handlebar sensor
//! `R4 = R3 Rz(steer)`; a mounted sensor reads `R3 M_f` and `R4 M_h`, with the
//! misalignments `M_f`, `M_h` fixed rotations in the sensor frames.
//!
//! Two methods:
//! * [`AngleMethod::Direct`] (default): after removing the misalignments, roll
//!   is the frame's y axis against gravity (`sin roll = R3[2][1]`), steer is the
//!   angle of the relative rotation `R3^T R4` about the steer axis. Neither
//!   needs the frame pitch.
//! * [`AngleMethod::Thesis`]: eq. 88-93 on the raw third rows, with the sign of
//!   the frame pitch taken from a guess, then the calibration-run mean angles
//!   subtracted (section 6.5). Steer divides by `e^2 + d^2` (eq. 92 multiplied
//!   through by `e = sin roll`, so it stays finite at upright) and mixes the
//!   frame and handlebar noise with the roll error.

use super::read::{ImuRecord, ThesisRun};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};

/// How roll and steer are computed from the orientations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AngleMethod {
    /// Relative rotation for steer, gravity for roll (no pitch guess).
    #[default]
    Direct,
    /// Thesis eq. 87-93 with calibration offsets.
    Thesis,
}

/// Angles of one run on the IMU clock (rad).
#[derive(Clone, Debug, Default)]
pub struct Angles {
    /// Time (s, IMU clock).
    pub t: Vec<f64>,
    /// Roll `theta`, positive leaning right (thesis convention).
    pub roll: Vec<f64>,
    /// Steer `gamma`, positive turning left (thesis convention).
    pub steer: Vec<f64>,
    /// Frame pitch `beta`.
    pub pitch: Vec<f64>,
    /// Heading of the frame (arbitrary origin, unwrapped).
    pub yaw: Vec<f64>,
}

/// Mounting misalignments and noise levels from the calibration run.
#[derive(Clone, Debug)]
pub struct Calibration {
    /// Frame-sensor misalignment `M_f` (sensor reads `R3 M_f`).
    pub frame: Rotation3<f64>,
    /// Handlebar-sensor misalignment `M_h` (sensor reads `R4 M_h`).
    pub handlebar: Rotation3<f64>,
    /// Frame pitch at rest from the model (rad).
    pub frame_pitch: f64,
    /// IMU time from which the calibration record is settled (s).
    pub settled_from: f64,
    /// Thesis-method roll and steer at rest (rad), subtracted by that method.
    pub thesis_offsets: (f64, f64),
    /// Standard deviation of the direct roll and steer at rest (rad).
    pub noise: (f64, f64),
    /// Whether the misalignment about the vertical came from observed steer
    /// motion (see [`Calibration::with_steer_axis`]); otherwise it is zero.
    pub yaw_from_steer_axis: bool,
    /// The steer axis in frame-sensor coordinates, when observed.
    pub steer_axis: Option<Vector3<f64>>,
}

/// Motion of the bicycle during a calibration run ([`Calibration::motion`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationMotion {
    /// Range of the block-averaged roll (rad).
    pub roll_range: f64,
    /// Range of the block-averaged steer (rad).
    pub steer_range: f64,
    /// Largest roll rate between neighbouring blocks (rad/s).
    pub roll_rate: f64,
    /// Largest steer rate between neighbouring blocks (rad/s).
    pub steer_rate: f64,
}

impl CalibrationMotion {
    /// Whether the bicycle stayed at rest ([`Calibration::AT_REST_LIMIT`]).
    pub fn at_rest(&self) -> bool {
        self.roll_range <= Calibration::AT_REST_LIMIT && self.steer_range <= Calibration::AT_REST_LIMIT
    }
}

fn mat(q: &UnitQuaternion<f64>) -> Matrix3<f64> {
    *q.to_rotation_matrix().matrix()
}

/// Robust spread: 1.4826 x median absolute deviation.
pub fn robust_sigma(x: &[f64]) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    let m = median(x);
    let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
    1.4826 * median(&dev)
}

/// Median (NaN-free input).
pub fn median(x: &[f64]) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    let mut v = x.to_vec();
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Chordal mean of rotations (sign-aligned quaternion average).
fn mean_rotation(q: &[UnitQuaternion<f64>]) -> UnitQuaternion<f64> {
    let r = q[0];
    let mut s = nalgebra::Quaternion::new(0.0, 0.0, 0.0, 0.0);
    for x in q {
        let c = if x.coords.dot(&r.coords) < 0.0 {
            -x.into_inner()
        } else {
            x.into_inner()
        };
        s += c;
    }
    UnitQuaternion::from_quaternion(s)
}

/// First sample from which the record stays settled: the orientation stays
/// within 6 robust standard deviations of the mean of its second half. The
/// units need "a second or two" after the logger starts (thesis 6.5).
fn settled_index(rec: &ImuRecord) -> usize {
    let n = rec.q.len();
    let reference = mean_rotation(&rec.q[n / 2..]);
    let d: Vec<f64> = rec.q.iter().map(|q| q.angle_to(&reference)).collect();
    let tail = &d[n / 2..];
    let limit = median(tail) + 6.0 * robust_sigma(tail).max(1e-6);
    match d.iter().rposition(|&x| x > limit) {
        Some(k) if k + 1 < n / 2 => k + 1,
        Some(_) => n / 2,
        None => 0,
    }
}

/// Rotation taking unit vectors `a1 -> b1` exactly and `a2 -> b2` as well as
/// possible (TRIAD).
fn triad(a1: &Vector3<f64>, a2: &Vector3<f64>, b1: &Vector3<f64>, b2: &Vector3<f64>) -> Rotation3<f64> {
    let frame = |u: &Vector3<f64>, v: &Vector3<f64>| {
        let e1 = u.normalize();
        let e2 = u.cross(v).normalize();
        let e3 = e1.cross(&e2);
        Matrix3::from_columns(&[e1, e2, e3])
    };
    Rotation3::from_matrix_unchecked(frame(b1, b2) * frame(a1, a2).transpose())
}

impl Calibration {
    /// Estimate the misalignments from a calibration run (bicycle upright, at
    /// rest, handlebar straight) and the model's frame pitch at rest `beta0`
    /// (rad; about minus the steer-axis tilt).
    ///
    /// At rest `R_f = Rz(psi) Ry(beta0) M_f` with unknown heading `psi`: the
    /// gravity direction in the sensor fixes two of the three angles of `M_f`;
    /// the rotation about the vertical is indistinguishable from heading at
    /// rest. It is taken as zero here and found from steer motion by
    /// [`Calibration::with_steer_axis`]. `M_h = M_f R_f^T R_h` (steer zero).
    pub fn estimate(cal: &ThesisRun, beta0: f64) -> Calibration {
        let k0 = settled_index(&cal.frame).max(settled_index(&cal.handlebar));
        let rf = mean_rotation(&cal.frame.q[k0..]);
        let rh = mean_rotation(&cal.handlebar.q[k0..]);
        let g_sensor = rf.inverse() * Vector3::z();
        let vertical_body = Vector3::new(-beta0.sin(), 0.0, beta0.cos());
        // Yaw part zero: sensor z maps into the body's x-z plane.
        let z_sensor = Vector3::z();
        let frame = triad(&g_sensor, &z_sensor, &vertical_body, &Vector3::z());
        let rel = rf.inverse() * rh;
        let handlebar = frame * rel.to_rotation_matrix();
        let mut c = Calibration {
            frame,
            handlebar,
            frame_pitch: beta0,
            settled_from: cal.frame.t[k0],
            thesis_offsets: (0.0, 0.0),
            noise: (0.0, 0.0),
            yaw_from_steer_axis: false,
            steer_axis: None,
        };
        c.finish(cal, k0);
        c
    }

    /// How far the bicycle moved during the settled part of its
    /// calibration run: the range of the direct roll and steer angles
    /// averaged over blocks of [`Calibration::MOTION_BLOCK`] (rad), and the
    /// largest rate between neighbouring blocks (rad/s). Averaging first
    /// keeps the sensors' sample noise out; what remains is motion (or the
    /// sensors' slow wander). `None` when the settled part holds fewer than
    /// four blocks.
    pub fn motion(&self, cal: &ThesisRun) -> Option<CalibrationMotion> {
        let a = angles(cal, self, AngleMethod::Direct);
        let k0 = a.t.partition_point(|&t| t < self.settled_from);
        let t = &a.t[k0.min(a.t.len())..];
        if t.len() < 2 {
            return None;
        }
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        let m = ((Self::MOTION_BLOCK / dt).round() as usize).max(1);
        let blocks = t.len() / m;
        if blocks < 4 || !dt.is_finite() || dt <= 0.0 {
            return None;
        }
        let means = |x: &[f64]| -> Vec<f64> {
            x[k0..k0 + blocks * m]
                .chunks_exact(m)
                .map(|c| c.iter().sum::<f64>() / m as f64)
                .collect()
        };
        let spread = |x: &[f64]| {
            let (lo, hi) = x
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
            hi - lo
        };
        let rate = |x: &[f64]| {
            x.windows(2)
                .map(|w| (w[1] - w[0]).abs() / (m as f64 * dt))
                .fold(0.0, f64::max)
        };
        let (roll, steer) = (means(&a.roll), means(&a.steer));
        Some(CalibrationMotion {
            roll_range: spread(&roll),
            steer_range: spread(&steer),
            roll_rate: rate(&roll),
            steer_rate: rate(&steer),
        })
    }

    /// Block length of [`Calibration::motion`] (s): long against the
    /// sensors' sample noise, short against a hand's sway.
    pub const MOTION_BLOCK: f64 = 0.5;

    /// The largest motion of a calibration run at rest (rad): 2 deg of
    /// roll or steer between block means. The sensors' slow wander at rest
    /// is a few tenths of a degree; a bicycle that moved more than this
    /// while its mounting was being measured biases every angle by up to
    /// that much.
    pub const AT_REST_LIMIT: f64 = 2.0 * std::f64::consts::PI / 180.0;

    fn finish(&mut self, cal: &ThesisRun, k0: usize) {
        let direct = angles(cal, self, AngleMethod::Direct);
        self.noise = (robust_sigma(&direct.roll[k0..]), robust_sigma(&direct.steer[k0..]));
        let mut raw = self.clone();
        raw.thesis_offsets = (0.0, 0.0);
        let th = angles(cal, &raw, AngleMethod::Thesis);
        self.thesis_offsets = (median(&th.roll[k0..]), median(&th.steer[k0..]));
    }

    /// The steer axis in frame-sensor coordinates, from the relative rotations
    /// of runs with steer motion: `R_f^T R_h M_h^T M_f = M_f^T Rz(steer) M_f`,
    /// a rotation about `M_f^T z`. The units drift in heading independently,
    /// which adds a slow relative rotation about the vertical; so the axis is
    /// the principal direction of the rotation *increments* over a tenth of a
    /// second (steer moves fast during a response, drift does not). `None`
    /// without enough steer motion.
    pub fn steer_axis(&self, runs: &[&ThesisRun]) -> Option<Vector3<f64>> {
        let c = self.handlebar.inverse() * self.frame;
        let mut incs: Vec<Vector3<f64>> = Vec::new();
        for run in runs {
            let n = run.frame.q.len();
            let k0 = run.frame.t.partition_point(|&t| t < self.settled_from);
            if n < k0 + 10 {
                continue;
            }
            let rel: Vec<UnitQuaternion<f64>> = (k0..n)
                .map(|k| run.frame.q[k].inverse() * run.handlebar.q[k] * UnitQuaternion::from_rotation_matrix(&c))
                .collect();
            // Relative to the run's mean: full steer amplitudes (much larger
            // than the noise), while the drift stays small within a run.
            let reference = mean_rotation(&rel);
            for q in &rel {
                incs.push((reference.inverse() * q).scaled_axis());
            }
        }
        // Most increments are sensor noise; keep those well above it (three
        // median increment sizes).
        let sizes: Vec<f64> = incs.iter().map(|r| r.norm()).collect();
        let noise = median(&sizes);
        let mut s = Matrix3::zeros();
        let mut count = 0usize;
        for r in &incs {
            if r.norm() > 3.0 * noise {
                s += r * r.transpose();
                count += 1;
            }
        }
        if count < 5 {
            return None;
        }
        let eig = s.symmetric_eigen();
        let k = eig.eigenvalues.imax();
        let mut a: Vector3<f64> = eig.eigenvectors.column(k).into();
        if a.z < 0.0 {
            a = -a;
        }
        Some(a)
    }

    /// Complete the frame misalignment with the rotation about the vertical
    /// from the observed steer axis `axis` (frame-sensor coordinates): the
    /// body's steer axis (z) and vertical fix `M_f` fully (TRIAD).
    pub fn with_steer_axis(&self, cal: &ThesisRun, axis: &Vector3<f64>) -> Calibration {
        let k0 = settled_index(&cal.frame).max(settled_index(&cal.handlebar));
        let rf = mean_rotation(&cal.frame.q[k0..]);
        let rh = mean_rotation(&cal.handlebar.q[k0..]);
        let g_sensor = rf.inverse() * Vector3::z();
        let b = self.frame_pitch;
        let vertical_body = Vector3::new(-b.sin(), 0.0, b.cos());
        let frame = triad(&g_sensor, axis, &vertical_body, &Vector3::z());
        let handlebar = frame * (rf.inverse() * rh).to_rotation_matrix();
        let mut c = Calibration {
            frame,
            handlebar,
            yaw_from_steer_axis: true,
            steer_axis: Some(*axis),
            ..self.clone()
        };
        c.finish(cal, k0);
        c
    }

    /// Misalignment angles (roll about x, pitch about y, yaw about z; rad) of
    /// the frame and the handlebar sensors.
    pub fn misalignment_angles(&self) -> ([f64; 3], [f64; 3]) {
        let e = |r: &Rotation3<f64>| {
            let (a, b, c) = r.euler_angles();
            [a, b, c]
        };
        (e(&self.frame), e(&self.handlebar))
    }
}

fn unwrap(x: &mut [f64]) {
    for k in 1..x.len() {
        let d = x[k] - x[k - 1];
        let turns = (d / std::f64::consts::TAU).round();
        if turns != 0.0 {
            for v in x[k..].iter_mut() {
                *v -= turns * std::f64::consts::TAU;
            }
        }
    }
}

/// Roll, steer, pitch and yaw of a run by the chosen method.
pub fn angles(run: &ThesisRun, cal: &Calibration, method: AngleMethod) -> Angles {
    let n = run.frame.q.len();
    let mut out = Angles {
        t: run.frame.t.clone(),
        roll: Vec::with_capacity(n),
        steer: Vec::with_capacity(n),
        pitch: Vec::with_capacity(n),
        yaw: Vec::with_capacity(n),
    };
    let mf_t = cal.frame.inverse();
    let mh_t = cal.handlebar.inverse();
    for k in 0..n {
        let raw3 = mat(&run.frame.q[k]);
        let raw4 = mat(&run.handlebar.q[k]);
        let r3 = raw3 * mf_t.matrix();
        let r4 = raw4 * mh_t.matrix();
        let yaw = (-r3[(0, 1)]).atan2(r3[(1, 1)]);
        match method {
            AngleMethod::Direct => {
                let roll = r3[(2, 1)].atan2((r3[(2, 0)].powi(2) + r3[(2, 2)].powi(2)).sqrt());
                let pitch = (-r3[(2, 0)]).atan2(r3[(2, 2)]);
                let rel = r3.transpose() * r4;
                let steer = (rel[(1, 0)] - rel[(0, 1)]).atan2(rel[(0, 0)] + rel[(1, 1)]);
                out.roll.push(roll);
                out.steer.push(steer);
                out.pitch.push(pitch);
            }
            AngleMethod::Thesis => {
                // Eq. 88: beta from the raw third row; its sign is known from
                // the mass distribution (the guess).
                let mut beta = -(raw3[(2, 0)] / raw3[(2, 2)]).atan();
                if beta.signum() != cal.frame_pitch.signum() {
                    beta = -beta;
                }
                // Eq. 89-90.
                let s_th = raw3[(2, 1)];
                let c_th = -raw3[(2, 0)] / beta.sin();
                let roll = s_th.atan2(c_th);
                // Eq. 91-93, multiplied through by e.
                let d = beta.sin() * roll.cos();
                let e = roll.sin();
                let (a1, a2) = (raw4[(2, 0)], raw4[(2, 1)]);
                let den = e * e + d * d;
                let s_g = (e * a1 + d * a2) / den;
                let c_g = (e * a2 - d * a1) / den;
                let steer = s_g.atan2(c_g);
                out.roll.push(roll - cal.thesis_offsets.0);
                out.steer.push(steer - cal.thesis_offsets.1);
                out.pitch.push(beta);
            }
        }
        out.yaw.push(yaw);
    }
    unwrap(&mut out.yaw);
    out
}
