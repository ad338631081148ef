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

use super::records::{ImuRecord, ThesisRun};
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

/// Motion of the bicycle during a calibration run ([`Calibration::motion`]):
/// how far each sensor tilted against gravity. The calibration measures
/// each sensor's tilt against gravity; a tilt that changed while it was
/// measured biases the mounting by up to that much. Roll tilts both
/// sensors, steer the handlebar sensor (by the steer angle times the sine
/// of the steer axis's tilt, about 0.3). Heading, invisible at rest and
/// drifting in real units by degrees a minute, biases nothing and is not
/// counted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CalibrationMotion {
    /// Largest angle between the frame sensor's block-averaged gravity
    /// directions (rad).
    pub frame_tilt_range: f64,
    /// The same for the handlebar sensor (rad).
    pub handlebar_tilt_range: f64,
    /// Largest frame-sensor tilt rate between neighbouring blocks (rad/s).
    pub frame_tilt_rate: f64,
    /// The same for the handlebar sensor (rad/s).
    pub handlebar_tilt_rate: f64,
}

impl CalibrationMotion {
    /// Whether the bicycle stayed at rest ([`Calibration::AT_REST_LIMIT`]).
    pub fn at_rest(&self) -> bool {
        self.frame_tilt_range <= Calibration::AT_REST_LIMIT && self.handlebar_tilt_range <= Calibration::AT_REST_LIMIT
    }
}

/// Global up in a sensor's own axes (the third row of its orientation):
/// what gravity shows of the sensor's tilt, whatever its heading.
fn up_in_sensor(q: &UnitQuaternion<f64>) -> Vector3<f64> {
    q.inverse_transform_vector(&Vector3::z())
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
    /// calibration run: for each sensor, the largest angle between its
    /// gravity directions (global up in sensor coordinates, the third row
    /// of its orientation) averaged over blocks of
    /// [`Calibration::MOTION_BLOCK`], and the largest tilt rate between
    /// neighbouring blocks (rad/s). Averaging first keeps the sensors'
    /// sample noise out; what remains is motion or the sensors' slow wander
    /// in tilt. The sensors' heading drift (a relative one reads as a
    /// steer of degrees over a ten-second record) does not enter. `None`
    /// when the settled part holds fewer than four blocks.
    pub fn motion(&self, cal: &ThesisRun) -> Option<CalibrationMotion> {
        let n = cal.frame.q.len().min(cal.handlebar.q.len());
        let t = &cal.frame.t[..n.min(cal.frame.t.len())];
        let k0 = t.partition_point(|&x| x < self.settled_from);
        let t = &t[k0..];
        if t.len() < 2 {
            return None;
        }
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        if !dt.is_finite() || dt <= 0.0 {
            return None;
        }
        let m = ((Self::MOTION_BLOCK / dt).round() as usize).max(1);
        let blocks = t.len() / m;
        if blocks < 4 {
            return None;
        }
        let means = |q: &[UnitQuaternion<f64>]| -> Vec<Vector3<f64>> {
            q[k0..k0 + blocks * m]
                .chunks_exact(m)
                .map(|c| c.iter().map(up_in_sensor).sum::<Vector3<f64>>().normalize())
                .collect()
        };
        let range = |g: &[Vector3<f64>]| {
            let mut widest = 0.0f64;
            for (i, a) in g.iter().enumerate() {
                for b in &g[i + 1..] {
                    widest = widest.max(a.angle(b));
                }
            }
            widest
        };
        let rate = |g: &[Vector3<f64>]| {
            g.windows(2)
                .map(|w| w[0].angle(&w[1]) / (m as f64 * dt))
                .fold(0.0, f64::max)
        };
        let (frame, handlebar) = (means(&cal.frame.q), means(&cal.handlebar.q));
        Some(CalibrationMotion {
            frame_tilt_range: range(&frame),
            handlebar_tilt_range: range(&handlebar),
            frame_tilt_rate: rate(&frame),
            handlebar_tilt_rate: rate(&handlebar),
        })
    }

    /// Block length of [`Calibration::motion`] (s): long against the
    /// sensors' sample noise, short against a hand's sway.
    pub const MOTION_BLOCK: f64 = 0.5;

    /// The largest motion of a calibration run at rest (rad): 2 deg of
    /// either sensor's tilt between block means. The sensors' slow wander
    /// in tilt at rest is a few tenths of a degree (up to 0.9 deg over the
    /// oracle simulator's ten-second records); a bicycle that moved more
    /// than this while its mounting was being measured biases every angle
    /// by up to that much.
    pub const AT_REST_LIMIT: f64 = 2.0 * std::f64::consts::PI / 180.0;

    /// The share of a run's relative rotation that must be about one axis
    /// for the run to show the steer axis ([`Self::steer_axis_consensus`]).
    /// A steer motion puts nearly all of it about the steer axis; sensor
    /// noise spreads it evenly over three axes (a share of 1/3). Half lies
    /// well between: a run at one half has as much rotation off the axis as
    /// about it.
    pub const ONE_AXIS_SHARE: f64 = 0.5;

    /// The least angle (rad) between a run's steer axis and the set's that
    /// puts the run apart (left out of the set's axis; set aside if its
    /// files look swapped, else flagged): 5 deg. Both sensors are clamped
    /// to their bodies, so all runs of a set turn about one axis; runs with
    /// steer motion give it to a fraction of a degree. A sensor moved or
    /// turned on its mount, or the two sensors' files swapped, tilts it by
    /// the mounting's own misalignment, several degrees.
    pub const STEER_AXIS_TOLERANCE: f64 = 5.0 * std::f64::consts::PI / 180.0;

    /// How many times the set's median distance of run axes from the
    /// consensus a run's axis may lie before it is left out of the estimate
    /// and flagged: 5 (for a two-dimensional normal scatter, a probability
    /// of 3e-8). A good run's own axis, from few samples above the noise and
    /// with heading drift, scatters by degrees with heavier tails than that:
    /// a control set of the oracle simulator had one at 6.6 medians. Hence a
    /// run beyond is only left out of the pooled axis, where it would weigh
    /// with its scatter, and flagged for a look, never dropped.
    pub const STEER_AXIS_SCATTERS: f64 = 5.0;

    fn finish(&mut self, cal: &ThesisRun, k0: usize) {
        let direct = angles(cal, self, AngleMethod::Direct);
        self.noise = (robust_sigma(&direct.roll[k0..]), robust_sigma(&direct.steer[k0..]));
        let mut raw = self.clone();
        raw.thesis_offsets = (0.0, 0.0);
        let th = angles(cal, &raw, AngleMethod::Thesis);
        self.thesis_offsets = (median(&th.roll[k0..]), median(&th.steer[k0..]));
    }

    /// Each sensor's typical direction of global up in its own axes over a
    /// record from `from` (s) on: the component-wise median, normalised
    /// (a fall or a lean at the end moves it little). At rest and in
    /// upright running alike it is fixed by the sensor's mounting, up to
    /// the roll and the steer (times the sine of the steer axis's tilt) of
    /// the moment, so it tells a run's frame sensor from its handlebar
    /// sensor whenever the two are mounted a few degrees apart. `None`
    /// with fewer than ten samples.
    pub fn typical_up(frame: &ImuRecord, handlebar: &ImuRecord, from: f64) -> Option<(Vector3<f64>, Vector3<f64>)> {
        let n = frame.q.len().min(handlebar.q.len());
        let k0 = frame.t[..n.min(frame.t.len())].partition_point(|&t| t < from);
        if n < k0 + 10 {
            return None;
        }
        let up = |q: &[UnitQuaternion<f64>]| {
            let v: Vec<Vector3<f64>> = q[k0..n].iter().map(up_in_sensor).collect();
            let c = |i: usize| median(&v.iter().map(|v| v[i]).collect::<Vec<_>>());
            Vector3::new(c(0), c(1), c(2)).normalize()
        };
        Some((up(&frame.q), up(&handlebar.q)))
    }

    /// The rotations of the handlebar sensor relative to the frame sensor
    /// over a run's settled record (its `frame` and `handlebar` records), each relative to the run's mean
    /// (scaled axis, rad), in frame-sensor coordinates:
    /// `R_f^T R_h M_h^T M_f = M_f^T Rz(steer) M_f` is a rotation about
    /// `M_f^T z`. The units drift in heading independently, which adds a slow
    /// relative rotation about the vertical; relative to the run's mean the
    /// steer amplitudes are full (much larger than the noise) while the drift
    /// stays small within a run.
    pub fn relative_rotations(&self, frame: &ImuRecord, handlebar: &ImuRecord) -> Vec<Vector3<f64>> {
        let c = self.handlebar.inverse() * self.frame;
        let n = frame.q.len().min(handlebar.q.len());
        let k0 = frame.t.partition_point(|&t| t < self.settled_from);
        if n < k0 + 10 {
            return Vec::new();
        }
        let rel: Vec<UnitQuaternion<f64>> = (k0..n)
            .map(|k| frame.q[k].inverse() * handlebar.q[k] * UnitQuaternion::from_rotation_matrix(&c))
            .collect();
        let reference = mean_rotation(&rel);
        rel.iter().map(|q| (reference.inverse() * q).scaled_axis()).collect()
    }

    /// The principal direction of the rotations `incs` well above the noise
    /// (three times `noise`, the median rotation size: most samples are
    /// sensor noise), with the share of their squared size it carries.
    /// `None` with fewer than five such rotations.
    fn principal_axis(incs: &[Vector3<f64>], noise: f64) -> Option<RunSteerAxis> {
        let mut s = Matrix3::zeros();
        let mut count = 0usize;
        for r in incs {
            if r.norm() > 3.0 * noise {
                s += r * r.transpose();
                count += 1;
            }
        }
        if count < 5 || s.trace() <= 0.0 {
            return None;
        }
        let eig = s.symmetric_eigen();
        let k = eig.eigenvalues.imax();
        let mut a: Vector3<f64> = eig.eigenvectors.column(k).into();
        if a.z < 0.0 {
            a = -a;
        }
        Some(RunSteerAxis {
            axis: a,
            share: eig.eigenvalues[k] / s.trace(),
            samples: count,
        })
    }

    /// The steer axis in frame-sensor coordinates, from the relative
    /// rotations of runs with steer motion ([`Self::relative_rotations`] of
    /// each run), pooled. `None` without enough steer motion. A set's runs
    /// are first screened by [`Self::steer_axis_consensus`].
    pub fn steer_axis(runs: &[&[Vector3<f64>]]) -> Option<Vector3<f64>> {
        let incs: Vec<Vector3<f64>> = runs.iter().flat_map(|r| r.iter().copied()).collect();
        let sizes: Vec<f64> = incs.iter().map(|r| r.norm()).collect();
        Self::principal_axis(&incs, median(&sizes)).map(|a| a.axis)
    }

    /// One run's own steer axis ([`Self::steer_axis`] on that run's
    /// relative rotations alone), with how much of its relative rotation is
    /// about that axis.
    pub fn run_steer_axis(rotations: &[Vector3<f64>]) -> Option<RunSteerAxis> {
        let sizes: Vec<f64> = rotations.iter().map(|r| r.norm()).collect();
        Self::principal_axis(rotations, median(&sizes))
    }

    /// Which runs the set's steer axis is estimated from. The two sensors
    /// are fixed to the frame and the fork, so every run turns the handlebar
    /// sensor about one and the same axis relative to the frame sensor. A
    /// run whose relative rotation is not about one axis (noise, a frozen or
    /// foreign record) would turn a pooled estimate, and through it every
    /// run's angles: it is left out of the estimate. So is a run turning
    /// about an axis of its own (its sensors swapped or moved, or a good
    /// run's estimate far out), which the caller sets aside or flags. The
    /// consensus is the axis of the run closest to the others (the medoid: it stands while fewer than half the runs
    /// are bad); a run is inconsistent when its axis is further from it than
    /// [`Self::STEER_AXIS_TOLERANCE`] and than [`Self::STEER_AXIS_SCATTERS`]
    /// times the runs' median distance from it. The set's axis is pooled
    /// over the runs that agree.
    /// The test needs three runs with an axis of their own; with fewer, those
    /// runs are pooled untested.
    /// `runs` holds each run's [`Self::relative_rotations`].
    pub fn steer_axis_consensus(runs: &[&[Vector3<f64>]]) -> SteerAxisConsensus {
        let axes: Vec<Option<RunSteerAxis>> = runs.iter().map(|r| Self::run_steer_axis(r)).collect();
        let mut verdicts: Vec<RunAxisVerdict> = axes
            .iter()
            .map(|a| match a {
                Some(a) if a.share >= Self::ONE_AXIS_SHARE => RunAxisVerdict::Used,
                Some(a) => RunAxisVerdict::NotAboutOneAxis { share: a.share },
                None => RunAxisVerdict::NoSteerMotion,
            })
            .collect();
        let with_axis: Vec<usize> = (0..runs.len())
            .filter(|&i| verdicts[i] == RunAxisVerdict::Used)
            .collect();
        let angle = |i: usize, j: usize| {
            let (a, b) = (
                axes[i].as_ref().expect("has an axis").axis,
                axes[j].as_ref().expect("has an axis").axis,
            );
            a.dot(&b).abs().min(1.0).acos()
        };
        let mut consensus = None;
        if with_axis.len() >= 3 {
            let medoid = *with_axis
                .iter()
                .min_by(|&&i, &&j| {
                    let mi = median(&with_axis.iter().map(|&k| angle(i, k)).collect::<Vec<_>>());
                    let mj = median(&with_axis.iter().map(|&k| angle(j, k)).collect::<Vec<_>>());
                    mi.total_cmp(&mj)
                })
                .expect("three runs");
            let distances: Vec<f64> = with_axis.iter().map(|&k| angle(medoid, k)).collect();
            let limit = Self::STEER_AXIS_TOLERANCE.max(Self::STEER_AXIS_SCATTERS * median(&distances));
            for (&k, &d) in with_axis.iter().zip(&distances) {
                if d > limit {
                    verdicts[k] = RunAxisVerdict::Inconsistent { angle: d, limit };
                }
            }
            consensus = axes[medoid].as_ref().map(|a| a.axis);
        }
        // The runs that show the axis, pooled; a run without an axis of its
        // own would add only its noise, and a noise record can outweigh the
        // rest. Without any such run, every run is pooled: together they
        // may show what none shows alone.
        let used: Vec<&[Vector3<f64>]> = runs
            .iter()
            .zip(&verdicts)
            .filter(|(_, v)| matches!(v, RunAxisVerdict::Used))
            .map(|(r, _)| *r)
            .collect();
        let pooled = if used.is_empty() { runs.to_vec() } else { used };
        SteerAxisConsensus {
            axis: Self::steer_axis(&pooled),
            medoid: consensus,
            runs: verdicts,
        }
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

/// One run's steer axis ([`Calibration::run_steer_axis`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSteerAxis {
    /// The axis in frame-sensor coordinates (unit, z up).
    pub axis: Vector3<f64>,
    /// Share of the run's relative rotation (squared, above the noise)
    /// about that axis: 1 for a pure steer motion, about 1/3 for noise.
    pub share: f64,
    /// Samples above the noise.
    pub samples: usize,
}

/// What a run gives the set's steer axis ([`Calibration::steer_axis_consensus`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RunAxisVerdict {
    /// Its axis agrees with the others and enters the estimate.
    Used,
    /// Too little steer motion above its noise for an axis of its own (a
    /// straight run, or a record of noise): left out of the estimate.
    NoSteerMotion,
    /// Its relative rotation is not about one axis: left out of the
    /// estimate.
    NotAboutOneAxis {
        /// Share about its principal axis.
        share: f64,
    },
    /// It turns about an axis of its own: left out of the estimate (and
    /// flagged by the caller).
    Inconsistent {
        /// Its axis's angle from the consensus (rad).
        angle: f64,
        /// The largest angle accepted (rad).
        limit: f64,
    },
}

/// The set's steer axis with each run's part in it.
#[derive(Clone, Debug, PartialEq)]
pub struct SteerAxisConsensus {
    /// The axis pooled over the runs used (`None` without steer motion).
    pub axis: Option<Vector3<f64>>,
    /// The consensus run axis the others were judged against (with three
    /// runs or more with an axis).
    pub medoid: Option<Vector3<f64>>,
    /// One verdict per run, in order.
    pub runs: Vec<RunAxisVerdict>,
}
