//! The linear-analysis jobs as library calls (`canonical`, `stability`):
//! the typed results the command line prints and Python converts.

use bikedyn::bicycle::Bicycle;
use bikedyn::canonical::{canonical, state_space, CanonicalOptions, CanonicalReport};
use bikedyn::runtime::eigen::LinearBicycle;
use bikedyn::stability::{stability, StabilityError, StabilityOptions};

/// The benchmark bicycle has the canonical form; its structural zero
/// `C1[0][0]` is written as 0, and the file-free built-in has no standard
/// deviations.
#[test]
fn the_canonical_job_gives_the_benchmark_matrices_with_structural_zeros_as_zero() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let CanonicalReport::Canonical(c) = canonical(&b, &CanonicalOptions::default()).unwrap() else {
        panic!("the benchmark bicycle has a canonical form");
    };
    assert_eq!(c.matrices.c1[0][0], 0.0);
    assert_eq!(c.matrices.m0[0][0], c.exact.m0[(0, 0)]);
    assert!(c.standard_deviations.is_none());
    let json = serde_json::to_value(CanonicalReport::Canonical(c)).unwrap();
    for key in ["M0", "C1", "K0", "K2", "g", "model"] {
        assert!(json.get(key).is_some(), "{key} in {json}");
    }
}

/// A bicycle with a feedback controller has no canonical form: the job says
/// why and gives A(v) and B(v) = [0; M(v)^-1], which reproduce the linear
/// equations at each speed (A's lower rows are -M^-1 [K, C]).
#[test]
fn without_a_canonical_form_the_job_gives_state_space_matrices_that_reproduce_the_equations() {
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/balance_assist_gain_8.toml");
    let b = Bicycle::resolve(file).unwrap();
    let speeds = vec![0.5, 3.0, 6.0];
    let report = canonical(
        &b,
        &CanonicalOptions {
            model: None,
            speeds: speeds.clone(),
        },
    )
    .unwrap();
    let CanonicalReport::StateSpace(n) = &report else {
        panic!("a controller removes the canonical form");
    };
    assert!(n.why.contains("controller"), "{}", n.why);
    let ss = &n.state_space;
    assert_eq!(ss.states, ["roll", "steer", "roll_rate", "steer_rate"]);
    assert_eq!(ss.inputs, ["roll_torque", "steer_torque"]);
    let lin = b.linear_with(None).unwrap();
    for (at, &v) in ss.at.iter().zip(&speeds) {
        assert_eq!(at.speed, v);
        let m = lin.at_speed(v).unwrap();
        let minv = m.mass.try_inverse().unwrap();
        let bm = at.b.as_ref().unwrap();
        for i in 0..2 {
            assert_eq!(bm[i], [0.0, 0.0]);
            for j in 0..2 {
                assert_eq!(bm[i + 2][j], minv[(i, j)]);
                // Position rows: the rates.
                assert_eq!(at.a[i][j + 2], if i == j { 1.0 } else { 0.0 });
            }
        }
        // Acceleration rows: A[2.., ..2] M = -K and A[2.., 2..] M = -C.
        let a = nalgebra::Matrix4::from_fn(|i, j| at.a[i][j]);
        let k = -m.mass * a.fixed_view::<2, 2>(2, 0);
        let c = -m.mass * a.fixed_view::<2, 2>(2, 2);
        assert!((k - m.stiffness).amax() <= 1e-12 * m.stiffness.amax(), "K at {v} m/s");
        assert!(
            (c - m.damping).amax() <= 1e-12 * m.damping.amax().max(1.0),
            "C at {v} m/s"
        );
    }
    // The same matrices from the state-space call alone.
    let direct = state_space(&b, None, &speeds).unwrap();
    assert_eq!(direct.at.len(), 3);
    assert_eq!(direct.at[1].a, ss.at[1].a);
}

/// A model with extra first-order states (tyre forces) gives its own
/// lateral states, no inputs, and says which states are extra.
#[test]
fn a_model_with_extra_states_gives_its_own_lateral_states() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let ss = state_space(&b, Some("tyre_free"), &[4.0]).unwrap();
    assert!(ss.model_coordinates);
    assert!(ss.inputs.is_empty());
    assert_eq!(ss.extra_states, ["Fy_rear", "Fy_front"]);
    let n = ss.states.len();
    assert_eq!(ss.at[0].a.len(), n);
    assert!(ss.at[0].b.is_none());
    assert!(state_space(&b, None, &[f64::NAN]).is_err());
}

/// The benchmark bicycle's weave and capsize speeds from the stability job
/// are Meijaard et al. (2007)'s (v_w = 4.2923825363 m/s, v_c = 6.0242620154 m/s), its
/// self-stable interval lies between them, and a built-in bicycle without
/// `+/-` values has no standard deviations and refuses a Monte Carlo check.
#[test]
fn the_stability_job_gives_the_benchmark_speeds_and_refuses_draws_without_spreads() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let r = stability(&b, &StabilityOptions::default()).unwrap();
    assert!(
        (r.weave_speed.unwrap() - 4.292_382_536_341_11).abs() < 1e-10,
        "{:?}",
        r.weave_speed
    );
    assert!(
        (r.capsize_speed.unwrap() - 6.024_262_015_388_37).abs() < 1e-10,
        "{:?}",
        r.capsize_speed
    );
    assert_eq!(r.stable_intervals.len(), 1);
    assert!(r
        .crossings
        .iter()
        .any(|c| c.mode == "weave" && c.direction == "stabilizing" && c.kind == "complex_pair"));
    assert!(r.uncertainty.is_none() && r.weave_speed_sd.is_none());
    let json = serde_json::to_value(&r).unwrap();
    assert!(json.get("weave_speed_sd").is_none(), "{json}");
    assert_eq!(
        json["weave_real_pair_merge_speed"],
        serde_json::json!(r.weave_real_pair_merge)
    );
    let draws = StabilityOptions {
        monte_carlo: Some((20, 1)),
        ..StabilityOptions::default()
    };
    assert!(matches!(stability(&b, &draws), Err(StabilityError::NoUncertainties(_))));
    let backwards = StabilityOptions {
        speed_min: 5.0,
        speed_max: 2.0,
        ..StabilityOptions::default()
    };
    assert!(matches!(stability(&b, &backwards), Err(StabilityError::SpeedRange(..))));
}
