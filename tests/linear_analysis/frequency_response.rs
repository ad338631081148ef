//! Frequency responses (`bikedyn bode`): `C (i omega I - A)^-1 B` from the
//! state-space LU solve against the inverse of the dynamic stiffness
//! `-omega^2 M + i omega C + K` formed in closed form (an independent
//! evaluation), and against the limits at low and high frequency.

use bikedyn::bicycle::Bicycle;
use bikedyn::frequency::{frequency_response, FrequencyOptions};
use bikedyn::runtime::eigen::{LinearBicycle, SpeedMatrices};
use nalgebra::{Complex, Matrix2};

type C64 = Complex<f64>;

/// `(-omega^2 M + i omega C + K)^-1` by the 2x2 adjugate.
fn inverse_dynamic_stiffness(m: &SpeedMatrices, omega: f64) -> Matrix2<C64> {
    let s = C64::new(0.0, omega);
    let p = Matrix2::from_fn(|i, j| s * s * m.mass[(i, j)] + s * m.damping[(i, j)] + m.stiffness[(i, j)]);
    let det = p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)];
    Matrix2::new(p[(1, 1)], -p[(0, 1)], -p[(1, 0)], p[(0, 0)]) / det
}

fn response_at(bike: &Bicycle, speed: f64, omega: &[f64]) -> Vec<Matrix2<C64>> {
    let r = frequency_response(
        bike,
        &FrequencyOptions {
            speed,
            omega_min: omega[0],
            omega_max: omega[1],
            points: 2,
            ..FrequencyOptions::default()
        },
    )
    .unwrap();
    assert_eq!(r.response.responses.len(), 4);
    (0..2)
        .map(|k| {
            let g = |i: usize| {
                let x = &r.response.responses[i];
                C64::new(x.re[k], x.im[k])
            };
            // Responses are ordered input-major: (roll torque: roll, steer),
            // (steer torque: roll, steer); rows outputs, columns inputs.
            Matrix2::new(g(0), g(2), g(1), g(3))
        })
        .collect()
}

fn relative(a: &Matrix2<C64>, b: &Matrix2<C64>) -> f64 {
    let scale = b.iter().map(|z| z.norm()).fold(0.0, f64::max);
    a.iter().zip(b.iter()).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
}

#[test]
fn transfer_functions_equal_the_inverse_dynamic_stiffness() {
    // The benchmark, and the same bicycle with steer damping (no canonical
    // form: the model linearized at the speed), stable and unstable speeds.
    let bench = Bicycle::resolve("benchmark").unwrap();
    let damped = bench.with_parameter("c_steer", 0.3).unwrap();
    for (bike, speed) in [(&bench, 5.0), (&bench, 2.0), (&damped, 4.0)] {
        let m = bike.linear_with(None).unwrap().at_speed(speed).unwrap();
        for pair in [[0.3, 4.4], [1.0, 25.0]] {
            let g = response_at(bike, speed, &pair);
            for (k, &omega) in pair.iter().enumerate() {
                let d = relative(&g[k], &inverse_dynamic_stiffness(&m, omega));
                assert!(
                    d < 1e-10,
                    "{} at {speed} m/s, omega {omega}: relative difference {d:e}",
                    bike.name
                );
            }
        }
    }
}

#[test]
fn the_response_tends_to_the_static_gain_and_to_the_inertia() {
    let bike = Bicycle::resolve("benchmark").unwrap();
    let speed = 5.0;
    let m = bike.linear_with(None).unwrap().at_speed(speed).unwrap();
    let r = frequency_response(
        &bike,
        &FrequencyOptions {
            speed,
            omega_min: 1e-6,
            omega_max: 1e4,
            points: 2,
            ..FrequencyOptions::default()
        },
    )
    .unwrap()
    .response;
    // -C A^-1 B = K^-1 (static deflection under a constant torque).
    let k_inv = m.stiffness.try_inverse().unwrap();
    let m_inv = m.mass.try_inverse().unwrap();
    for (n, g) in r.responses.iter().enumerate() {
        let (i, j) = (n % 2, n / 2);
        let dc = g.static_gain.unwrap();
        assert!(
            (dc - k_inv[(i, j)]).abs() < 1e-12 * k_inv.amax(),
            "{} to {}",
            g.input,
            g.output
        );
        // At 1e-6 rad/s the response is G(0) to first order in omega.
        assert!((g.re[0] - dc).abs() < 1e-5 * k_inv.amax() && g.im[0].abs() < 1e-5 * k_inv.amax());
        // At 1e4 rad/s, omega^2 G -> -M^-1.
        let w2 = 1e8;
        assert!(
            (w2 * g.re[1] + m_inv[(i, j)]).abs() < 1e-3 * m_inv.amax(),
            "{} to {}: {} vs {}",
            g.input,
            g.output,
            w2 * g.re[1],
            -m_inv[(i, j)]
        );
    }
}
