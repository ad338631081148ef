//! The dictionary's terms and the linear equations they enter: which
//! signal a term multiplies, on which equation, with what speed power and
//! lag, and the state matrix of a plant with terms (a lag adds a state).

use nalgebra::{Complex, DMatrix, Matrix2, Matrix2x4};
use serde::Serialize;

/// A coordinate of the lateral equations (benchmark signs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Coordinate {
    Roll,
    Steer,
}

impl Coordinate {
    fn index(self) -> usize {
        match self {
            Coordinate::Roll => 0,
            Coordinate::Steer => 1,
        }
    }
}

/// What a term multiplies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", content = "of", rename_all = "snake_case")]
pub enum Signal {
    /// An angle (rad).
    Angle(Coordinate),
    /// An angular rate (rad/s).
    Rate(Coordinate),
    /// An angular acceleration (rad/s^2): an added inertia.
    Acceleration(Coordinate),
    /// The declared controller's torque (N m), passed through a lag in
    /// place of acting at once.
    ControllerTorque,
    /// A constant torque (N m): a bias, such as a cable pulling the
    /// handlebar or a load off the plane of symmetry. It leaves the linear
    /// equations unchanged, so only the time series see it.
    Constant,
    /// A Coulomb-like torque opposing a rate, `-T tanh(w / w0)` with
    /// `w0` = [`COULOMB_SMOOTHING`] (T in N m): friction in a
    /// joint. Its linearization about upright is not useful (its describing
    /// function depends on the amplitude), so only the time series see it.
    Coulomb(Coordinate),
}

/// The rate (rad/s) below which a Coulomb-like term of the time-series
/// dictionary turns smoothly to zero (keeps exact derivatives at rest; a
/// measured weave's steer rate is of order 0.1-1 rad/s).
pub const COULOMB_SMOOTHING: f64 = 0.02;

/// One term of the dictionary: `Q_equation += theta v^speed_power signal`,
/// through a first-order lag when `lagged`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Term {
    pub equation: Coordinate,
    pub signal: Signal,
    pub speed_power: u8,
    pub lagged: bool,
}

impl Term {
    /// Every term the linear stage can fit. With `controller`, also the lag
    /// of the declared controller's torque.
    pub fn dictionary(controller: bool) -> Vec<Term> {
        use Coordinate::*;
        use Signal::*;
        let mut terms = Vec::new();
        for equation in [Roll, Steer] {
            for signal in [Angle(Roll), Angle(Steer), Rate(Roll), Rate(Steer)] {
                for lagged in [false, true] {
                    for speed_power in 0..=2 {
                        terms.push(Term {
                            equation,
                            signal,
                            speed_power,
                            lagged,
                        });
                    }
                }
            }
            for of in [Roll, Steer] {
                terms.push(Term {
                    equation,
                    signal: Acceleration(of),
                    speed_power: 0,
                    lagged: false,
                });
            }
        }
        if controller {
            terms.push(Term {
                equation: Steer,
                signal: Signal::ControllerTorque,
                speed_power: 0,
                lagged: true,
            });
        }
        terms
    }

    /// Every term the time-series search can fit through the nonlinear
    /// model: on each equation, each angle and rate times 1, v or v^2, a
    /// constant bias, and a Coulomb-like torque opposing its own rate. The
    /// lags and added inertias stay with the linear stage (a lag adds a
    /// state and an inertia a mass-matrix entry, which a generalized
    /// force of the derived model cannot carry).
    pub fn time_series_dictionary() -> Vec<Term> {
        use Coordinate::*;
        use Signal::*;
        let mut terms = Vec::new();
        for equation in [Roll, Steer] {
            for signal in [Angle(Roll), Angle(Steer), Rate(Roll), Rate(Steer)] {
                for speed_power in 0..=2 {
                    terms.push(Term {
                        equation,
                        signal,
                        speed_power,
                        lagged: false,
                    });
                }
            }
            for signal in [Constant, Coulomb(equation)] {
                terms.push(Term {
                    equation,
                    signal,
                    speed_power: 0,
                    lagged: false,
                });
            }
        }
        terms
    }

    /// The symbol of this term's coefficient in the derived models that
    /// carry the time-series dictionary (`modeler/src/effects/
    /// generalized_forces.rs`, the models' signs): `Q_` and [`Term::name`].
    pub fn model_symbol(&self) -> String {
        format!("Q_{}", self.name())
    }

    /// The factor from the benchmark's signs (roll and steer positive to
    /// the right) to the models' (the thesis's: steer positive to the
    /// left) of this term's coefficient: -1 when exactly one of the
    /// equation and the signal is the steer (a constant counts as its
    /// equation's coordinate; a Coulomb term opposes its own rate).
    pub fn model_sign(&self) -> f64 {
        let sign = |c: Coordinate| if c == Coordinate::Steer { -1.0 } else { 1.0 };
        let of = match self.signal {
            Signal::Angle(c) | Signal::Rate(c) | Signal::Acceleration(c) => sign(c),
            Signal::Constant => 1.0,
            Signal::Coulomb(_) | Signal::ControllerTorque => sign(self.equation),
        };
        sign(self.equation) * of
    }

    /// A name for reports and JSON: the equation's torque, the signal, the
    /// speed power and the lag, as `steer_torque_roll_rate_v2` or
    /// `steer_torque_controller_lagged`.
    pub fn name(&self) -> String {
        let coordinate = |c: Coordinate| match c {
            Coordinate::Roll => "roll",
            Coordinate::Steer => "steer",
        };
        let signal = match self.signal {
            Signal::Angle(c) => coordinate(c).to_string(),
            Signal::Rate(c) => format!("{}_rate", coordinate(c)),
            Signal::Acceleration(c) => format!("{}_acceleration", coordinate(c)),
            Signal::ControllerTorque => "controller".to_string(),
            Signal::Constant => "bias".to_string(),
            Signal::Coulomb(c) => format!("coulomb_{}_rate", coordinate(c)),
        };
        let power = match self.speed_power {
            0 => String::new(),
            1 => "_v".to_string(),
            p => format!("_v{p}"),
        };
        format!(
            "{}_torque_{signal}{power}{}",
            coordinate(self.equation),
            if self.lagged { "_lagged" } else { "" }
        )
    }

    /// Fitted values: the coefficient (absent for the controller's lag),
    /// then the time constant of a lag.
    pub fn parameter_count(&self) -> usize {
        usize::from(self.signal != Signal::ControllerTorque) + usize::from(self.lagged)
    }

    /// The coefficient's unit (SI).
    pub fn unit(&self) -> String {
        let base = match self.signal {
            Signal::Angle(_) => "N m/rad",
            Signal::Rate(_) => "N m s/rad",
            Signal::Acceleration(_) => "kg m^2",
            Signal::ControllerTorque => "",
            Signal::Constant | Signal::Coulomb(_) => "N m",
        };
        match self.speed_power {
            0 => base.to_string(),
            1 => format!("{base} per m/s"),
            p => format!("{base} per (m/s)^{p}"),
        }
    }
}

/// The linear equations at one speed with the declared controller apart:
/// `M q'' + C q' + K q = -K_fb x` (benchmark signs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantAt {
    pub mass: Matrix2<f64>,
    pub damping: Matrix2<f64>,
    pub stiffness: Matrix2<f64>,
    /// `K_fb`: the controller's gains on `[roll, steer, roll rate, steer
    /// rate]` for `[roll torque, steer torque]` (zero without one).
    pub feedback: Matrix2x4<f64>,
}

/// A lag's time constant is fitted as its logarithm (it stays positive).
pub(super) fn time_constant(log_tau: f64) -> f64 {
    log_tau.exp()
}

/// The state matrix of the plant with `terms` at values `theta` (each
/// term's coefficient then, for a lag, the logarithm of its time constant)
/// at speed `v`; `None` when the mass matrix with the added inertias is
/// singular.
pub fn state_matrix(plant: &PlantAt, terms: &[Term], theta: &[f64], v: f64) -> Option<DMatrix<f64>> {
    let (mut m, mut c, mut k) = (plant.mass, plant.damping, plant.stiffness);
    let controller_lagged = terms.iter().any(|t| t.signal == Signal::ControllerTorque);
    if !controller_lagged {
        k += plant.feedback.fixed_columns::<2>(0);
        c += plant.feedback.fixed_columns::<2>(2);
    }
    // Lags: (equation, signal column in x, coefficient, time constant).
    let mut lags: Vec<(usize, usize, f64, f64)> = Vec::new();
    let mut it = theta.iter();
    for t in terms {
        if t.signal == Signal::ControllerTorque {
            let tau = time_constant(*it.next()?);
            for e in 0..2 {
                // Each torque's lag state follows -K_fb x.
                lags.push((e, usize::MAX, 1.0, tau));
            }
            continue;
        }
        let coefficient = *it.next()? * v.powi(i32::from(t.speed_power));
        let (e, col) = match t.signal {
            Signal::Angle(s) => (t.equation.index(), s.index()),
            Signal::Rate(s) => (t.equation.index(), 2 + s.index()),
            Signal::Acceleration(s) => {
                m[(t.equation.index(), s.index())] -= coefficient;
                continue;
            }
            // No part in the linear equations about upright (only the
            // time-series search offers them).
            Signal::ControllerTorque | Signal::Constant | Signal::Coulomb(_) => continue,
        };
        if t.lagged {
            lags.push((e, col, coefficient, time_constant(*it.next()?)));
        } else if col < 2 {
            k[(e, col)] -= coefficient;
        } else {
            c[(e, col - 2)] -= coefficient;
        }
    }
    let mi = m.try_inverse()?;
    let n = 4 + lags.len();
    let mut a = DMatrix::zeros(n, n);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    let (mk, mc) = (-mi * k, -mi * c);
    for i in 0..2 {
        for j in 0..2 {
            a[(2 + i, j)] = mk[(i, j)];
            a[(2 + i, 2 + j)] = mc[(i, j)];
        }
    }
    for (j, &(e, col, coefficient, tau)) in lags.iter().enumerate() {
        let z = 4 + j;
        a[(z, z)] = -1.0 / tau;
        if col == usize::MAX {
            for s in 0..4 {
                a[(z, s)] = -plant.feedback[(e, s)] / tau;
            }
        } else {
            a[(z, col)] += coefficient / tau;
        }
        for i in 0..2 {
            a[(2 + i, z)] += mi[(i, e)];
        }
    }
    Some(a)
}

/// The eigenvalues of `a`; `None` when an entry is not finite or the
/// Schur iteration does not converge (a fit's trial step can make either;
/// nalgebra's unbounded iteration would not return).
pub(super) fn eigenvalues(a: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let n = a.nrows();
    let schur = nalgebra::linalg::Schur::try_new(a.clone(), f64::EPSILON, 100 * n * n)?;
    Some(schur.complex_eigenvalues().iter().copied().collect())
}

/// The complex eigenvalue of `a` with positive imaginary part nearest
/// `guide` (the weave a model without the terms predicts).
pub fn weave_near(a: &DMatrix<f64>, guide: Complex<f64>) -> Option<Complex<f64>> {
    eigenvalues(a)?
        .iter()
        .filter(|z| z.im > 1e-9)
        .min_by(|x, y| (*x - guide).norm().total_cmp(&(*y - guide).norm()))
        .copied()
}
