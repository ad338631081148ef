//! Frequency responses of the linear roll-steer equations at one speed
//! (issue 36, item 3): the transfer functions from the roll and steer
//! torques to the roll and steer angles,
//!
//! ```text
//! G(s) = C (s I - A)^-1 B,   s = i omega,
//! A = [[0, I], [-M^-1 K, -M^-1 C]],  B = [0; M^-1],  C = [I, 0],
//! ```
//!
//! for `M q'' + C q' + K q = [T_phi, T_delta]` in the benchmark's signs
//! (roll positive to the right, steer positive turning right; Meijaard et
//! al. 2007). The inputs are the two generalized forces the canonical form
//! has; a lateral force at the saddle is not one of them (the model's input
//! matrix has the two torques only), so it is not offered.
//!
//! `G(i omega)` is evaluated by one complex LU solve of the 4x4 state-space
//! system per frequency. When the bicycle is unstable at the speed, `G(i
//! omega)` is still the transfer function on the imaginary axis (what a
//! stabilized loop would see), but it is not a measurable steady-state
//! response; [`FrequencyResponse::stable`] says which.

use crate::eigen::{LinearBicycle, SpeedMatrices};
use nalgebra::{Complex, Matrix2, Matrix4, SMatrix};
use serde::Serialize;

type C64 = Complex<f64>;

/// The inputs of [`frequency_response`].
pub const INPUTS: [&str; 2] = ["roll_torque", "steer_torque"];
/// The outputs of [`frequency_response`].
pub const OUTPUTS: [&str; 2] = ["roll", "steer"];

/// Errors of the frequency response.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum FrequencyError {
    #[error("the mass matrix is singular at {speed} m/s: there is no state-space form")]
    SingularMass { speed: f64 },
    #[error("omega = {omega} rad/s is a pole of the bicycle at {speed} m/s (i omega I - A is singular): the response is infinite there")]
    Pole { omega: f64, speed: f64 },
    #[error("frequencies: {what}")]
    BadFrequencies { what: String },
    #[error(transparent)]
    Eigen(#[from] crate::eigen::EigenError),
    #[error("{model}: the torque inputs are not formed for a model with extra first-order states (its lateral equations have no second-order form)")]
    FirstOrder { model: String },
}

/// The state-space matrices of `M q'' + C q' + K q = u`: `A` (4x4), `B`
/// (4x2), `C` (2x4), state `[phi, delta, phi', delta']`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateSpace {
    pub a: Matrix4<f64>,
    pub b: SMatrix<f64, 4, 2>,
    pub c: SMatrix<f64, 2, 4>,
}

impl StateSpace {
    /// The state-space form of the equations at one speed; `None` when the
    /// mass matrix is singular.
    pub fn of(m: &SpeedMatrices) -> Option<Self> {
        let a = m.state_matrix()?;
        let minv = m.mass.try_inverse()?;
        let mut b = SMatrix::<f64, 4, 2>::zeros();
        b.fixed_view_mut::<2, 2>(2, 0).copy_from(&minv);
        let mut c = SMatrix::<f64, 2, 4>::zeros();
        c[(0, 0)] = 1.0;
        c[(1, 1)] = 1.0;
        Some(StateSpace { a, b, c })
    }

    /// `C (s I - A)^-1 B` (rows: outputs, columns: inputs); `None` when `s`
    /// is an eigenvalue.
    pub fn transfer(&self, s: C64) -> Option<Matrix2<C64>> {
        let sia = Matrix4::<C64>::from_fn(|i, j| {
            let d = if i == j { s } else { C64::new(0.0, 0.0) };
            d - C64::new(self.a[(i, j)], 0.0)
        });
        let b = self.b.map(|x| C64::new(x, 0.0));
        let x = sia.lu().solve(&b)?;
        if x.iter().any(|z| !(z.re.is_finite() && z.im.is_finite())) {
            return None;
        }
        let c = self.c.map(|x| C64::new(x, 0.0));
        Some(c * x)
    }

    /// `-C A^-1 B`, the response to a constant input; `None` when `A` is
    /// singular (a zero eigenvalue: the capsize speed).
    pub fn static_gain(&self) -> Option<Matrix2<f64>> {
        let x = self.a.lu().solve(&self.b)?;
        let g = -(self.c * x);
        g.iter().all(|v| v.is_finite()).then_some(g)
    }
}

/// One input-output pair over the frequencies.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Response {
    /// `roll_torque` or `steer_torque`.
    pub input: &'static str,
    /// `roll` or `steer`.
    pub output: &'static str,
    /// Real part of `G(i omega)` (rad/(N m)).
    pub re: Vec<f64>,
    /// Imaginary part (rad/(N m)).
    pub im: Vec<f64>,
    /// `20 log10 |G|` (dB re 1 rad/(N m)).
    pub magnitude_db: Vec<f64>,
    /// Phase of `G` (degrees), unwrapped along the frequencies from its
    /// principal value at the first one.
    pub phase_deg: Vec<f64>,
    /// `G(0) = -C A^-1 B` (rad/(N m)); `None` at a zero eigenvalue.
    pub static_gain: Option<f64>,
}

/// The frequency response of a bicycle at one speed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrequencyResponse {
    /// Forward speed (m/s).
    pub speed: f64,
    /// Whether every eigenvalue has a negative real part at the speed.
    pub stable: bool,
    /// Angular frequencies (rad/s).
    pub omega: Vec<f64>,
    /// One per input-output pair: roll torque to roll, to steer, steer
    /// torque to roll, to steer.
    pub responses: Vec<Response>,
}

/// `n` frequencies from `lo` to `hi` (rad/s), evenly spaced in logarithm.
pub fn log_grid(lo: f64, hi: f64, n: usize) -> Result<Vec<f64>, FrequencyError> {
    let bad = |what: String| Err(FrequencyError::BadFrequencies { what });
    if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && hi > lo) {
        return bad(format!(
            "{lo}:{hi} must be two positive finite angular frequencies (rad/s), the first below the second"
        ));
    }
    if n < 2 {
        return bad(format!("{n} points: at least 2 are needed"));
    }
    let (a, b) = (lo.ln(), hi.ln());
    Ok((0..n)
        .map(|k| {
            if k == 0 {
                lo
            } else if k + 1 == n {
                hi
            } else {
                (a + (b - a) * k as f64 / (n - 1) as f64).exp()
            }
        })
        .collect())
}

/// The frequency response of `bike` at `speed` over `omega` (rad/s).
pub fn frequency_response(
    bike: &dyn LinearBicycle,
    speed: f64,
    omega: &[f64],
) -> Result<FrequencyResponse, FrequencyError> {
    if omega.is_empty() || omega.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
        return Err(FrequencyError::BadFrequencies {
            what: "every frequency must be finite and non-negative, and there must be at least one".into(),
        });
    }
    let m = bike.at_speed(speed)?;
    let ss = StateSpace::of(&m).ok_or(FrequencyError::SingularMass { speed })?;
    let stable = ss.a.complex_eigenvalues().iter().all(|z| z.re < 0.0);
    let g: Vec<Matrix2<C64>> = omega
        .iter()
        .map(|&w| {
            ss.transfer(C64::new(0.0, w))
                .ok_or(FrequencyError::Pole { omega: w, speed })
        })
        .collect::<Result<_, _>>()?;
    let dc = ss.static_gain();
    let mut responses = Vec::new();
    for (j, input) in INPUTS.iter().enumerate() {
        for (i, output) in OUTPUTS.iter().enumerate() {
            let z: Vec<C64> = g.iter().map(|m| m[(i, j)]).collect();
            responses.push(Response {
                input,
                output,
                re: z.iter().map(|z| z.re).collect(),
                im: z.iter().map(|z| z.im).collect(),
                magnitude_db: z.iter().map(|z| 20.0 * z.norm().log10()).collect(),
                phase_deg: unwrap_degrees(z.iter().map(|z| z.arg().to_degrees())),
                static_gain: dc.map(|d| d[(i, j)]),
            });
        }
    }
    Ok(FrequencyResponse {
        speed,
        stable,
        omega: omega.to_vec(),
        responses,
    })
}

/// Phases (degrees) with the jumps of 360 between neighbours removed.
fn unwrap_degrees(p: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for x in p {
        let y = match out.last() {
            Some(&prev) => x + 360.0 * ((prev - x) / 360.0).round(),
            None => x,
        };
        out.push(y);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_are_unwrapped() {
        let p = unwrap_degrees([170.0, -175.0, -160.0, 179.0].into_iter());
        assert_eq!(p, vec![170.0, 185.0, 200.0, 179.0]);
    }

    #[test]
    fn the_grid_is_logarithmic_and_ends_exactly() {
        let g = log_grid(0.1, 100.0, 4).unwrap();
        assert_eq!(g.len(), 4);
        assert_eq!((g[0], g[3]), (0.1, 100.0));
        assert!((g[1] - 1.0).abs() < 1e-12 && (g[2] - 10.0).abs() < 1e-12, "{g:?}");
        assert!(log_grid(0.0, 1.0, 10).is_err());
        assert!(log_grid(1.0, 1.0, 10).is_err());
        assert!(log_grid(1.0, 10.0, 1).is_err());
    }
}
