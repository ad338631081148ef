//! Full-state feedback on the roll and steer torques, as an experiment ran
//! it: `u = [T_phi, T_delta] = -K(v) x` with `x = [phi, delta, phi',
//! delta']` in the benchmark's signs (roll positive to the right, steer
//! positive to the right), the form and the gain names of bicycleparameters'
//! `Meijaard2007WithFeedbackModel`. With it the linear equations
//! `M q'' + C q' + K q = u` become `M q'' + (C + K_d(v)) q' + (K + K_p(v)) q
//! = 0`, `K(v) = [K_p(v) K_d(v)]`: in state space `x' = (A - B K(v)) x`.
//!
//! The gains may follow a schedule over the forward speed: their values at
//! increasing knot speeds, linear between knots and held beyond the first
//! and the last. A piecewise-linear law is such a table (the balance-assist
//! bicycle's `k(v) = -kappa (4.7 - v)` on the roll rate between 1.5 and
//! 4.7 m/s, a ramp from zero below 1.5 m/s and zero above 4.7 m/s is the
//! knots 0, 1.5 and 4.7 m/s).

use crate::eigen::{EigenError, LinearBicycle, SpeedMatrices};
use crate::scalar::Scalar;
use nalgebra::{Matrix2, Matrix2x4};

/// The gain names, row by row of `K` (bicycleparameters' names): the roll
/// torque's gains on roll, steer, roll rate and steer rate, then the steer
/// torque's. Units: N m/rad on angles, N m s/rad on rates.
pub const GAIN_NAMES: [&str; 8] = [
    "kTphi_phi",
    "kTphi_del",
    "kTphi_phid",
    "kTphi_deld",
    "kTdel_phi",
    "kTdel_del",
    "kTdel_phid",
    "kTdel_deld",
];

/// A gain matrix `K(v)` known at knot speeds, linear between them and held
/// beyond the ends. One knot is a constant gain.
#[derive(Clone, Debug, PartialEq)]
pub struct GainSchedule {
    speeds: Vec<f64>,
    gains: Vec<Matrix2x4<f64>>,
}

/// Why a schedule cannot be built.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ScheduleError {
    #[error("a schedule needs at least one knot")]
    Empty,
    #[error("{speeds} knot speeds but {gains} gain matrices")]
    Lengths { speeds: usize, gains: usize },
    #[error("the knot speeds must be finite and increasing (knot {index}: {value})")]
    Speeds { index: usize, value: f64 },
    #[error("gain `{name}` at knot {index} is not a finite number ({value})")]
    Gain {
        name: &'static str,
        index: usize,
        value: f64,
    },
}

impl GainSchedule {
    /// Gains `gains[i]` at speeds `speeds[i]` (m/s, strictly increasing).
    pub fn new(speeds: Vec<f64>, gains: Vec<Matrix2x4<f64>>) -> Result<GainSchedule, ScheduleError> {
        if speeds.is_empty() {
            return Err(ScheduleError::Empty);
        }
        if speeds.len() != gains.len() {
            return Err(ScheduleError::Lengths {
                speeds: speeds.len(),
                gains: gains.len(),
            });
        }
        for (i, &v) in speeds.iter().enumerate() {
            if !v.is_finite() || (i > 0 && v <= speeds[i - 1]) {
                return Err(ScheduleError::Speeds { index: i, value: v });
            }
        }
        for (i, k) in gains.iter().enumerate() {
            if let Some(j) = (0..8).find(|&j| !k[(j / 4, j % 4)].is_finite()) {
                return Err(ScheduleError::Gain {
                    name: GAIN_NAMES[j],
                    index: i,
                    value: k[(j / 4, j % 4)],
                });
            }
        }
        Ok(GainSchedule { speeds, gains })
    }

    /// The same gain at every speed.
    pub fn constant(k: Matrix2x4<f64>) -> Result<GainSchedule, ScheduleError> {
        GainSchedule::new(vec![0.0], vec![k])
    }

    /// The knot speeds (m/s).
    pub fn speeds(&self) -> &[f64] {
        &self.speeds
    }

    /// The gain matrices at the knots.
    pub fn gains(&self) -> &[Matrix2x4<f64>] {
        &self.gains
    }

    /// What the feedback adds at speed `v` to the stiffness and to the
    /// damping matrix of `M q'' + C q' + K q = u` (benchmark signs): the
    /// gains on the angles and those on the rates.
    pub fn stiffness_and_damping(&self, v: f64) -> (Matrix2<f64>, Matrix2<f64>) {
        let k = self.at(v);
        (
            k.fixed_columns::<2>(0).into_owned(),
            k.fixed_columns::<2>(2).into_owned(),
        )
    }

    /// The torques `u = [T_phi, T_delta] = -K(v) x` (N m, benchmark signs)
    /// for the state `x = [phi, delta, phi', delta']` (rad, rad/s) at the
    /// forward speed `v` (m/s), in any scalar: what the nonlinear
    /// simulation applies. `K` is taken at `v`'s value and carried to first
    /// order along `v`'s derivatives (the schedule's slope there), so the
    /// forward sensitivities of a simulation are exact wherever the
    /// schedule is smooth (not at a knot, where it has a kink).
    pub fn torques<T: Scalar>(&self, v: T, x: [T; 4]) -> [T; 2] {
        let v0 = v.re();
        let (k, slope) = (self.at(v0), self.slope(v0));
        let dv = v - T::cst(v0);
        let mut u = [T::zero(); 2];
        for (i, ui) in u.iter_mut().enumerate() {
            for (j, &xj) in x.iter().enumerate() {
                *ui -= (T::cst(k[(i, j)]) + T::cst(slope[(i, j)]) * dv) * xj;
            }
        }
        u
    }

    /// `dK/dv` at `v` ((N m per rad or rad/s) per m/s): the slope of the
    /// knot interval that holds `v` (the one to the right at a knot, as
    /// [`GainSchedule::at`] interpolates there), zero beyond the ends.
    fn slope(&self, v: f64) -> Matrix2x4<f64> {
        let n = self.speeds.len();
        if n < 2 || !(v >= self.speeds[0] && v < self.speeds[n - 1]) {
            return Matrix2x4::zeros();
        }
        let i = self.speeds.partition_point(|&s| s <= v) - 1;
        (self.gains[i + 1] - self.gains[i]) / (self.speeds[i + 1] - self.speeds[i])
    }

    /// `K(v)`: linear between the knots, held beyond the ends.
    pub fn at(&self, v: f64) -> Matrix2x4<f64> {
        let n = self.speeds.len();
        if v <= self.speeds[0] {
            return self.gains[0];
        }
        if v >= self.speeds[n - 1] {
            return self.gains[n - 1];
        }
        let i = self.speeds.partition_point(|&s| s <= v) - 1;
        let t = (v - self.speeds[i]) / (self.speeds[i + 1] - self.speeds[i]);
        self.gains[i] * (1.0 - t) + self.gains[i + 1] * t
    }
}

/// A bicycle's linear equations with full-state feedback closed around them.
pub struct WithFeedback<B> {
    /// The open-loop bicycle.
    pub bicycle: B,
    /// The controller.
    pub schedule: GainSchedule,
}

impl<B: LinearBicycle> LinearBicycle for WithFeedback<B> {
    fn at_speed(&self, v: f64) -> Result<SpeedMatrices, EigenError> {
        let mut s = self.bicycle.at_speed(v)?;
        let (kp, kd) = self.schedule.stiffness_and_damping(v);
        s.stiffness += kp;
        s.damping += kd;
        Ok(s)
    }
    // No canonical form: the gains need not be linear or quadratic in the
    // speed, so the analyses take the general path. No first-order form:
    // a model with extra states has no `M, C, K` to close the loop on.
}

#[cfg(test)]
mod tests {
    use super::*;

    fn k(roll_rate_to_steer: f64) -> Matrix2x4<f64> {
        let mut m = Matrix2x4::zeros();
        m[(1, 2)] = roll_rate_to_steer;
        m
    }

    #[test]
    fn a_schedule_is_linear_between_knots_and_held_beyond_them() {
        let s = GainSchedule::new(vec![0.0, 1.5, 4.7], vec![k(0.0), k(-12.48), k(0.0)]).unwrap();
        assert_eq!(s.at(-1.0)[(1, 2)], 0.0);
        assert!((s.at(0.75)[(1, 2)] + 6.24).abs() < 1e-12);
        assert_eq!(s.at(1.5)[(1, 2)], -12.48);
        assert!((s.at(3.1)[(1, 2)] + 6.24).abs() < 1e-12);
        assert_eq!(s.at(4.7)[(1, 2)], 0.0);
        assert_eq!(s.at(9.0)[(1, 2)], 0.0);
        assert_eq!(GainSchedule::constant(k(2.0)).unwrap().at(123.0)[(1, 2)], 2.0);
    }

    /// The torques are `-K(v) x` at the speed's value, and a dual
    /// number's derivative along the speed is the schedule's slope times
    /// the state (between knots; zero beyond the ends).
    #[test]
    fn the_torques_are_minus_k_x_with_the_schedules_slope_along_the_speed() {
        use crate::scalar::Dual;
        let s = GainSchedule::new(vec![0.0, 1.5, 4.7], vec![k(0.0), k(-12.48), k(0.0)]).unwrap();
        let x = [0.1, -0.2, 0.3, 0.4];
        for (v, slope) in [(1.0, -12.48 / 1.5), (3.0, 12.48 / 3.2), (6.0, 0.0)] {
            let u = s.torques(v, x);
            assert_eq!(u[0], 0.0);
            assert!((u[1] + s.at(v)[(1, 2)] * 0.3).abs() < 1e-15, "v = {v}: {u:?}");
            let vd = Dual::<1> { re: v, eps: [1.0] };
            let xd = x.map(|c| Dual::<1> { re: c, eps: [0.0] });
            let ud = s.torques(vd, xd);
            assert!((ud[1].re - u[1]).abs() < 1e-15);
            assert!((ud[1].eps[0] + slope * 0.3).abs() < 1e-12, "v = {v}: {:?}", ud[1]);
        }
    }

    #[test]
    fn a_schedule_refuses_unordered_speeds_mismatched_lengths_and_non_finite_gains() {
        assert_eq!(
            GainSchedule::new(vec![1.0, 1.0], vec![k(0.0), k(0.0)]),
            Err(ScheduleError::Speeds { index: 1, value: 1.0 })
        );
        assert_eq!(
            GainSchedule::new(vec![1.0], vec![k(0.0), k(0.0)]),
            Err(ScheduleError::Lengths { speeds: 1, gains: 2 })
        );
        assert!(matches!(
            GainSchedule::new(vec![1.0], vec![k(f64::NAN)]),
            Err(ScheduleError::Gain {
                name: "kTdel_phid",
                index: 0,
                ..
            })
        ));
        assert_eq!(GainSchedule::new(vec![], vec![]), Err(ScheduleError::Empty));
    }

    #[test]
    fn feedback_adds_its_angle_gains_to_the_stiffness_and_its_rate_gains_to_the_damping() {
        let plant = crate::canonical::CanonicalMatrices {
            m0: Matrix2::new(80.0, 2.0, 2.0, 0.3),
            c1: Matrix2::new(0.0, 33.0, -0.8, 1.7),
            k0: Matrix2::new(-80.0, -2.6, -2.6, -0.8),
            k2: Matrix2::new(0.0, 76.0, 0.0, 2.7),
            g: 9.81,
        };
        let gain = Matrix2x4::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0);
        let closed = WithFeedback {
            bicycle: plant,
            schedule: GainSchedule::constant(gain).unwrap(),
        };
        let (open, with) = (plant.at_speed(4.0).unwrap(), closed.at_speed(4.0).unwrap());
        assert_eq!(with.mass, open.mass);
        assert_eq!(with.stiffness - open.stiffness, Matrix2::new(1.0, 2.0, 5.0, 6.0));
        assert_eq!(with.damping - open.damping, Matrix2::new(3.0, 4.0, 7.0, 8.0));
        assert!(closed.canonical().is_none());
    }
}
