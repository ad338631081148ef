//! Constraint solution and coordinate partitioning on the generated thesis model.

use bikedyn::generated::ThesisWhipple as W;
use bikedyn::models::default_parameters;
use bikedyn::runtime::constraints::{solve_configuration, solve_velocities, ConstraintError, NewtonOptions};
use bikedyn::runtime::linearize::{canonical_matrices, LinearizeError};
use bikedyn::runtime::parameters::ThesisParameters;
use bikedyn::runtime::MultibodyModel;

#[test]
fn newton_solves_the_holonomic_constraints_to_1e14_at_any_roll_and_steer() {
    let param = default_parameters::<W>();
    for (roll, steer) in [(0.0, 0.0), (0.3, -0.4), (-0.5, 0.8), (0.1, 1.2)] {
        let mut p = W::INITIAL_GUESS.to_vec();
        p[3] = roll;
        p[6] = steer;
        let info = solve_configuration::<W, f64>(&param, 0.7, &mut p, &NewtonOptions::default()).unwrap();
        let mut res = vec![0.0; 3];
        W::holonomic_residuals(&param, 0.7, &p, &mut res);
        assert!(
            res.iter().all(|r| r.abs() <= 1e-14),
            "roll {roll} steer {steer}: residuals {res:?} ({info:?})"
        );
        // Upright, the frame pitch is minus the steer-axis tilt of the thesis
        // bicycle (~18 degrees) and the contact is at the bottom of the rim:
        // xi is measured in the front-wheel axes, pitched by beta.
        if roll == 0.0 && steer == 0.0 {
            let lam = ThesisParameters::thesis_bicycle().frame_pitch().unwrap();
            assert!((p[5] - lam).abs() < 1e-12, "beta {} vs {lam}", p[5]);
            assert!(
                (p[8] - (std::f64::consts::FRAC_PI_2 - p[5])).abs() < 1e-12,
                "xi {}",
                p[8]
            );
        }
    }
}

#[test]
fn velocities_satisfy_every_constraint() {
    let param = default_parameters::<W>();
    let mut p = W::INITIAL_GUESS.to_vec();
    p[3] = 0.2;
    p[6] = 0.3;
    solve_configuration::<W, f64>(&param, 0.0, &mut p, &NewtonOptions::default()).unwrap();
    let mut dp = vec![0.0; 9];
    dp[3] = 0.5;
    dp[6] = -1.0;
    solve_velocities::<W, f64>(&param, 0.0, &p, &mut dp).unwrap();
    let (mut cq, mut ct, mut b) = (vec![0.0; 27], vec![0.0; 3], vec![0.0; 36]);
    W::holonomic_jacobian(&param, 0.0, &p, &mut cq);
    W::holonomic_time_derivative(&param, 0.0, &p, &mut ct);
    W::nonholonomic_matrix(&param, 0.0, &p, &mut b);
    for i in 0..3 {
        let r: f64 = (0..9).map(|j| cq[i * 9 + j] * dp[j]).sum::<f64>() + ct[i];
        assert!(r.abs() < 1e-12, "holonomic velocity row {i}: {r}");
    }
    for i in 0..4 {
        let r: f64 = (0..9).map(|j| b[i * 9 + j] * dp[j]).sum();
        assert!(r.abs() < 1e-12, "rolling row {i}: {r}");
    }
}

#[test]
fn a_front_wheel_that_cannot_reach_the_ground_is_a_typed_error_not_nan() {
    let mut t = ThesisParameters::thesis_bicycle();
    t.front_wheel_radius = 3.0; // far larger than the wheelbase allows
    let err = canonical_matrices::<W>(|s| t.get(s)).unwrap_err();
    // Detected from the model's closed-form upright configuration before
    // Newton runs: the frame pitch has no real value.
    match err {
        LinearizeError::Constraint(ConstraintError::NoUprightConfiguration { coordinate }) => {
            assert_eq!(coordinate, "beta");
        }
        other => panic!("expected NoUprightConfiguration, got {other:?}"),
    }
    let msg = canonical_matrices::<W>(|s| t.get(s)).unwrap_err().to_string();
    assert!(msg.contains("cannot touch the ground"), "{msg}");
}

#[test]
fn nan_parameters_are_rejected_before_newton() {
    let mut param = default_parameters::<W>();
    param[1] = f64::NAN;
    let mut p = W::INITIAL_GUESS.to_vec();
    let err = solve_configuration::<W, f64>(&param, 0.0, &mut p, &NewtonOptions::default()).unwrap_err();
    assert!(matches!(err, ConstraintError::NotFinite { .. }), "{err:?}");
}
