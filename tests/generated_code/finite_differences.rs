//! Generated derivatives against finite differences of generated primal
//! quantities, through the library and the CLI.

use crate::common::*;
use bikedyn::runtime::verify::VerifyOptions;

#[test]
fn every_generated_derivative_of_every_model_matches_finite_differences() {
    // Walks the registry: a new model is verified without touching this test.
    for m in bikedyn::models::model_names() {
        let r = bikedyn::models::verify_model(
            m,
            &VerifyOptions {
                states: 10,
                seed: 7,
                ..Default::default()
            },
        )
        .unwrap();
        for q in &r.quantities {
            println!("{m}: {:<40} {:.3e} (tol {:.0e})", q.name, q.max_rel_error, q.tolerance);
        }
        assert!(
            r.passed,
            "{m} failed verification: {:#?}",
            r.quantities.iter().filter(|q| !q.passed).collect::<Vec<_>>()
        );
        assert_eq!(r.quantities.len(), 16);
        assert!(r.quantities.iter().any(|q| q.name.starts_with("energy balance")));
    }
}

/// `verify --json` of the thesis model at five states, seed 3.
const VERIFY_JSON_ARGS: &[&str] = &[
    "verify",
    "--model",
    "thesis_whipple",
    "--states",
    "5",
    "--seed",
    "3",
    "--json",
];

#[test]
fn cli_verify_json_reports_every_quantity() {
    let out = bikedyn(VERIFY_JSON_ARGS);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["passed"], true);
    let q = v["quantities"].as_array().unwrap();
    let names: Vec<&str> = q.iter().map(|x| x["name"].as_str().unwrap()).collect();
    for want in [
        "Cq",
        "Ct",
        "dCqdp",
        "B",
        "dBdp",
        "Qv",
        "M symmetric",
        "M positive semi-definite",
    ] {
        assert!(names.contains(&want), "missing {want} in {names:?}");
    }
    for x in q {
        assert!(x["max_rel_error"].as_f64().unwrap() <= x["tolerance"].as_f64().unwrap());
    }
}

#[test]
fn cli_verify_rejects_an_unknown_model() {
    let out = bikedyn(&["verify", "--model", "tricycle"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown model `tricycle`"));
}

/// The thesis model with a deliberately wrong `Cq` (one entry off by 1e-4
/// relative) and a wrong `dBdp`: the checker must catch both and nothing else.
struct Broken;

mod broken_impl {
    use super::Broken;
    use bikedyn::generated::ThesisWhipple as W;
    use bikedyn::runtime::{MultibodyModel, Scalar};

    impl MultibodyModel for Broken {
        const NAME: &'static str = "broken";
        const DOC: &'static str = "thesis model with deliberately broken derivatives";
        const BASE: &'static str = W::BASE;
        const FREE_SPEED: bool = W::FREE_SPEED;
        const EFFECTS: &'static [&'static str] = W::EFFECTS;
        const PARAMETER_INFO: &'static [bikedyn::runtime::model::ParameterInfo] = W::PARAMETER_INFO;
        const FORCES: &'static [bikedyn::runtime::model::ForceInfo] = W::FORCES;
        const FORWARD_SPEED_PARAMETER: Option<usize> = W::FORWARD_SPEED_PARAMETER;
        const SPEED_COORDINATE: Option<usize> = W::SPEED_COORDINATE;
        const GRAVITY_PARAMETER: Option<usize> = W::GRAVITY_PARAMETER;
        const STATES: &'static [&'static str] = W::STATES;
        const STATE_DOCS: &'static [&'static str] = W::STATE_DOCS;
        fn state_rates<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::state_rates(a, t, p, dp, o)
        }
        fn upright_configuration<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::upright_configuration(a, p, o)
        }
        fn upright_velocity_terms_jacobian(a: &[f64], t: f64, p: &[f64], dp: &[f64], o: &mut [f64]) {
            W::upright_velocity_terms_jacobian(a, t, p, dp, o)
        }
        fn linearize_with_rest_exact(
            param: &[f64],
            dq0: &[f64],
        ) -> Result<bikedyn::runtime::linearize::WithRest, bikedyn::runtime::linearize::LinearizeError> {
            W::linearize_with_rest_exact(param, dq0)
        }
        fn state_space_exact(
            param: &[f64],
            dq0: &[f64],
        ) -> Result<bikedyn::runtime::linearize::StateMatrix, bikedyn::runtime::linearize::LinearizeError> {
            W::state_space_exact(param, dq0)
        }
        fn applied_force_terms<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::applied_force_terms(a, t, p, dp, o)
        }
        fn forward_speed<T: Scalar>(a: &[T], p: &[T], dp: &[T]) -> T {
            W::forward_speed(a, p, dp)
        }
        const COORDINATES: &'static [&'static str] = W::COORDINATES;
        const PARAMETERS: &'static [&'static str] = W::PARAMETERS;
        const HOLONOMIC: &'static [&'static str] = W::HOLONOMIC;
        const NONHOLONOMIC: &'static [&'static str] = W::NONHOLONOMIC;
        const POINTS: &'static [&'static str] = W::POINTS;
        const INDEPENDENT: &'static [usize] = W::INDEPENDENT;
        const DEPENDENT: &'static [usize] = W::DEPENDENT;
        const INITIAL_GUESS: &'static [f64] = W::INITIAL_GUESS;
        const ALL_QUANTITIES_LAYOUT: &'static [(&'static str, usize, usize)] = W::ALL_QUANTITIES_LAYOUT;
        const FLOPS: &'static [(&'static str, usize)] = W::FLOPS;
        fn mass_matrix<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::mass_matrix(a, p, o)
        }
        fn quadratic_velocity_forces<T: Scalar>(a: &[T], p: &[T], dp: &[T], o: &mut [T]) {
            W::quadratic_velocity_forces(a, p, dp, o)
        }
        fn gravity_forces<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::gravity_forces(a, p, o)
        }
        fn applied_forces<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::applied_forces(a, t, p, dp, o)
        }
        fn holonomic_residuals<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_residuals(a, t, p, o)
        }
        fn holonomic_jacobian<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_jacobian(a, t, p, o);
            o[3] *= T::cst(1.0 + 1e-4);
        }
        fn holonomic_time_derivative<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_time_derivative(a, t, p, o)
        }
        fn holonomic_convective<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::holonomic_convective(a, t, p, dp, o)
        }
        fn nonholonomic_velocities<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::nonholonomic_velocities(a, t, p, dp, o)
        }
        fn nonholonomic_matrix<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::nonholonomic_matrix(a, t, p, o)
        }
        fn nonholonomic_convective<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::nonholonomic_convective(a, t, p, dp, o);
            o[0] += T::cst(1e-3);
        }
        fn kinetic_energy<T: Scalar>(a: &[T], p: &[T], dp: &[T]) -> T {
            W::kinetic_energy(a, p, dp)
        }
        fn potential_energy<T: Scalar>(a: &[T], p: &[T]) -> T {
            W::potential_energy(a, p)
        }
        fn point_positions<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::point_positions(a, p, o)
        }
        fn all_quantities<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::all_quantities(a, t, p, dp, o)
        }
    }
}

#[test]
fn verification_catches_wrong_derivatives() {
    use bikedyn::runtime::verify::verify;
    let param = bikedyn::models::default_parameters::<bikedyn::generated::ThesisWhipple>();
    let r = verify::<Broken>(
        &param,
        &VerifyOptions {
            states: 5,
            seed: 11,
            ..Default::default()
        },
    );
    assert!(!r.passed);
    let failed: Vec<&str> = r
        .quantities
        .iter()
        .filter(|q| !q.passed)
        .map(|q| q.name.as_str())
        .collect();
    assert!(failed.contains(&"Cq"), "{failed:?}");
    assert!(failed.contains(&"dBdp"), "{failed:?}");
    // all_quantities still agrees with the unmodified functions it was compared to,
    // except where the broken ones differ.
    assert!(!failed.contains(&"Qv") && !failed.contains(&"B"), "{failed:?}");
}

/// The steer damper of the effect library with its sign flipped: a force
/// that feeds energy in although it is declared dissipative.
struct PumpingDamper;

mod pumping_impl {
    use super::PumpingDamper;
    use bikedyn::generated::ExtendedFree as W;
    use bikedyn::runtime::{MultibodyModel, Scalar};

    fn flip<T: Scalar>(o: &mut [T]) {
        for x in o.iter_mut() {
            *x = -*x;
        }
    }

    impl MultibodyModel for PumpingDamper {
        const NAME: &'static str = "pumping_damper";
        const DOC: &'static str = W::DOC;
        const BASE: &'static str = W::BASE;
        const FREE_SPEED: bool = W::FREE_SPEED;
        const EFFECTS: &'static [&'static str] = W::EFFECTS;
        const PARAMETER_INFO: &'static [bikedyn::runtime::model::ParameterInfo] = W::PARAMETER_INFO;
        const FORCES: &'static [bikedyn::runtime::model::ForceInfo] = W::FORCES;
        const FORWARD_SPEED_PARAMETER: Option<usize> = W::FORWARD_SPEED_PARAMETER;
        const SPEED_COORDINATE: Option<usize> = W::SPEED_COORDINATE;
        const GRAVITY_PARAMETER: Option<usize> = W::GRAVITY_PARAMETER;
        const STATES: &'static [&'static str] = W::STATES;
        const STATE_DOCS: &'static [&'static str] = W::STATE_DOCS;
        fn state_rates<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::state_rates(a, t, p, dp, o)
        }
        fn upright_configuration<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::upright_configuration(a, p, o)
        }
        fn upright_velocity_terms_jacobian(a: &[f64], t: f64, p: &[f64], dp: &[f64], o: &mut [f64]) {
            W::upright_velocity_terms_jacobian(a, t, p, dp, o)
        }
        fn linearize_with_rest_exact(
            param: &[f64],
            dq0: &[f64],
        ) -> Result<bikedyn::runtime::linearize::WithRest, bikedyn::runtime::linearize::LinearizeError> {
            W::linearize_with_rest_exact(param, dq0)
        }
        fn state_space_exact(
            param: &[f64],
            dq0: &[f64],
        ) -> Result<bikedyn::runtime::linearize::StateMatrix, bikedyn::runtime::linearize::LinearizeError> {
            W::state_space_exact(param, dq0)
        }
        const COORDINATES: &'static [&'static str] = W::COORDINATES;
        const PARAMETERS: &'static [&'static str] = W::PARAMETERS;
        const HOLONOMIC: &'static [&'static str] = W::HOLONOMIC;
        const NONHOLONOMIC: &'static [&'static str] = W::NONHOLONOMIC;
        const POINTS: &'static [&'static str] = W::POINTS;
        const INDEPENDENT: &'static [usize] = W::INDEPENDENT;
        const DEPENDENT: &'static [usize] = W::DEPENDENT;
        const INITIAL_GUESS: &'static [f64] = W::INITIAL_GUESS;
        const ALL_QUANTITIES_LAYOUT: &'static [(&'static str, usize, usize)] = W::ALL_QUANTITIES_LAYOUT;
        const FLOPS: &'static [(&'static str, usize)] = W::FLOPS;
        fn mass_matrix<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::mass_matrix(a, p, o)
        }
        fn quadratic_velocity_forces<T: Scalar>(a: &[T], p: &[T], dp: &[T], o: &mut [T]) {
            W::quadratic_velocity_forces(a, p, dp, o)
        }
        fn gravity_forces<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::gravity_forces(a, p, o)
        }
        fn applied_forces<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::applied_forces(a, t, p, dp, o);
            flip(o)
        }
        fn applied_force_terms<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::applied_force_terms(a, t, p, dp, o);
            flip(o)
        }
        fn forward_speed<T: Scalar>(a: &[T], p: &[T], dp: &[T]) -> T {
            W::forward_speed(a, p, dp)
        }
        fn holonomic_residuals<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_residuals(a, t, p, o)
        }
        fn holonomic_jacobian<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_jacobian(a, t, p, o)
        }
        fn holonomic_time_derivative<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::holonomic_time_derivative(a, t, p, o)
        }
        fn holonomic_convective<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::holonomic_convective(a, t, p, dp, o)
        }
        fn nonholonomic_velocities<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::nonholonomic_velocities(a, t, p, dp, o)
        }
        fn nonholonomic_matrix<T: Scalar>(a: &[T], t: T, p: &[T], o: &mut [T]) {
            W::nonholonomic_matrix(a, t, p, o)
        }
        fn nonholonomic_convective<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::nonholonomic_convective(a, t, p, dp, o)
        }
        fn kinetic_energy<T: Scalar>(a: &[T], p: &[T], dp: &[T]) -> T {
            W::kinetic_energy(a, p, dp)
        }
        fn potential_energy<T: Scalar>(a: &[T], p: &[T]) -> T {
            W::potential_energy(a, p)
        }
        fn point_positions<T: Scalar>(a: &[T], p: &[T], o: &mut [T]) {
            W::point_positions(a, p, o)
        }
        fn all_quantities<T: Scalar>(a: &[T], t: T, p: &[T], dp: &[T], o: &mut [T]) {
            W::all_quantities(a, t, p, dp, o)
        }
    }
}

#[test]
fn verification_catches_a_dissipative_force_that_pumps_energy() {
    use bikedyn::generated::ExtendedFree as W;
    use bikedyn::runtime::verify::{verify, with_effects_switched_on};
    let param = with_effects_switched_on::<W>(&bikedyn::models::default_parameters::<W>());
    let opts = VerifyOptions {
        states: 5,
        seed: 3,
        ..Default::default()
    };
    let good = verify::<W>(&param, &opts);
    assert!(good.passed, "{:#?}", good.quantities);
    let r = verify::<PumpingDamper>(&param, &opts);
    let failed: Vec<&str> = r
        .quantities
        .iter()
        .filter(|q| !q.passed)
        .map(|q| q.name.as_str())
        .collect();
    assert!(failed.iter().any(|n| n.starts_with("dissipative")), "{failed:?}");
}

/// Issue 17, point 5: the forward sensitivities of a simulation (dual
/// numbers through the generated code, the constraint solve and the
/// integrator) against central differences of whole simulations, for a
/// driven model (the speed moves a parameter), a free-speed model with
/// effects, and a model with extra first-order states (tyre forces).
#[test]
fn forward_sensitivities_match_central_differences_of_simulations() {
    use bikedyn::generated::{ExtendedFree, ThesisWhipple, TyreFree};
    use bikedyn::runtime::linearize::parameter_vector;
    use bikedyn::runtime::parameters::ThesisParameters;
    use bikedyn::runtime::scalar::Dual;
    use bikedyn::runtime::simulate::sensitivity::{response, Directions, Response};
    use bikedyn::runtime::simulate::{simulate, Inputs};
    use bikedyn::runtime::MultibodyModel;

    // Up to six directions: the dual width identification uses.
    fn check<M: MultibodyModel>(set: &[(&str, f64)], free: &[&str], initial: &[usize]) {
        let thesis = ThesisParameters::thesis_bicycle();
        let mut param = parameter_vector::<M>(|s| thesis.get(s), 5.0).unwrap();
        for (s, v) in set {
            param[M::parameter_index(s).unwrap()] = *v;
        }
        let (mut ic, opts) = kick_and_tight_options();
        // A model with extra states (the lagged tyre forces) starts with
        // them changing, as just after a kick.
        if !M::STATES.is_empty() {
            ic.state_rates = [150.0, -80.0];
        }
        let k = free.len();
        let mut dirs = Directions {
            parameters: free
                .iter()
                .enumerate()
                .map(|(d, s)| (M::parameter_index(s).unwrap(), d, 1.0))
                .collect(),
            ..Directions::default()
        };
        // 0-4: roll, steer, their rates, speed; 5, 6: the extra states'
        // initial rates.
        for (d, &which) in initial.iter().enumerate() {
            if which < 5 {
                dirs.initial[which] = Some(k + d);
            } else {
                dirs.state_rates[which - 5] = Some(k + d);
            }
        }
        let nd = k + initial.len();
        assert!(nd <= 6);
        let duration = 2.0;
        let speed_at = wheel_sensor_times(duration);
        let exact: Response<Dual<6>> = response::<M, Dual<6>>(&param, &ic, &dirs, duration, &opts, &speed_at).unwrap();
        let plain: Response<f64> = response::<M, f64>(&param, &ic, &dirs, duration, &opts, &speed_at).unwrap();
        // The lean response is the simulation's.
        let sim = simulate::<M>(&param, &ic, &Inputs::default(), duration, &opts).unwrap();
        let roll = sim.coordinate("theta").unwrap();
        assert_eq!(plain.t.len(), sim.t.len());
        for (i, (a, b)) in plain.roll.iter().zip(&roll).enumerate() {
            assert!(
                (a - b).abs() < 1e-10,
                "{}: sample {i}: lean roll {a} against simulate {b}",
                M::NAME
            );
            assert!((a - exact.roll[i].re).abs() < 1e-9);
        }
        // The speed, from the velocities alone at the samples around each
        // time asked for, is the simulation's (a full evaluation at every
        // sample), interpolated alike.
        assert_eq!(plain.speed.len(), speed_at.len());
        for (&t, (a, e)) in speed_at.iter().zip(plain.speed.iter().zip(&exact.speed)) {
            let k = sim.t.partition_point(|&x| x <= t).clamp(1, sim.t.len() - 1);
            let w = ((t - sim.t[k - 1]) / (sim.t[k] - sim.t[k - 1])).min(1.0);
            let b = sim.speed[k - 1] + (sim.speed[k] - sim.speed[k - 1]) * w;
            assert!(
                (a - b).abs() < 1e-10 && (a - e.re).abs() < 1e-9,
                "{}: speed at {t} s: lean {a}, dual {}, simulate {b}",
                M::NAME,
                e.re
            );
        }
        let moved = |d: usize, h: f64| -> Response<f64> {
            let mut p = param.clone();
            let mut c = ic;
            if d < k {
                p[M::parameter_index(free[d]).unwrap()] += h;
            } else {
                match initial[d - k] {
                    0 => c.roll += h,
                    1 => c.steer += h,
                    2 => c.roll_rate += h,
                    3 => c.steer_rate += h,
                    4 => c.speed += h,
                    j => c.state_rates[j - 5] += h,
                }
            }
            response::<M, f64>(&p, &c, &Directions::default(), duration, &opts, &speed_at).unwrap()
        };
        for d in 0..nd {
            let size = if d < k {
                param[M::parameter_index(free[d]).unwrap()].abs().max(0.1)
            } else if initial[d - k] >= 5 {
                100.0 // N/s
            } else {
                0.1
            };
            let h = 1e-5 * size;
            let (a, b) = (moved(d, h), moved(d, -h));
            let channels: [(&str, &Vec<Dual<6>>, &Vec<f64>, &Vec<f64>); 4] = [
                ("roll", &exact.roll, &a.roll, &b.roll),
                ("roll rate", &exact.roll_rate, &a.roll_rate, &b.roll_rate),
                ("steer", &exact.steer, &a.steer, &b.steer),
                ("speed", &exact.speed, &a.speed, &b.speed),
            ];
            for (name, e, a, b) in channels {
                let (worst, scale) = misfit_against_central(e, a, b, h, d);
                println!(
                    "{}: d {name} / d direction {d}: max |exact - central| = {worst:.2e} of {scale:.2e}",
                    M::NAME
                );
                assert!(
                    worst <= 1e-5 * scale,
                    "{}: d {name} / d direction {d}: exact and central differences differ by {worst:.3e} (scale {scale:.3e})",
                    M::NAME
                );
            }
        }
    }
    let all = [0, 1, 2, 3, 4];
    check::<ThesisWhipple>(&[], &["I3x"], &all);
    let effects = [("c_steer", 0.3), ("CdA", 0.4), ("Crr_rear", 0.01)];
    check::<ExtendedFree>(&effects, &["c_steer"], &all);
    check::<ExtendedFree>(&effects, &["CdA", "I3x", "T_steer"], &[2, 4]);
    check::<TyreFree>(&[("c_steer", 0.2)], &["c_steer", "sigma_front"], &[0, 3, 4]);
    check::<TyreFree>(&[("c_steer", 0.2)], &["sigma_rear"], &[2, 4, 5, 6]);
}

/// A sensitivity direction that moves several parameters with weights (a
/// correction of the front assembly's mass-centre height moves the
/// steer-axis point, the wheel centre from it and the offset from the axis
/// together) equals the central difference of simulations moved along that
/// combination.
#[test]
fn a_weighted_combination_of_parameters_is_one_sensitivity_direction() {
    use bikedyn::generated::ExtendedFree;
    use bikedyn::runtime::linearize::parameter_vector;
    use bikedyn::runtime::parameters::ThesisParameters;
    use bikedyn::runtime::scalar::Dual;
    use bikedyn::runtime::simulate::sensitivity::{response, Directions, Response};
    use bikedyn::runtime::MultibodyModel;
    type M = ExtendedFree;

    let thesis = ThesisParameters::thesis_bicycle();
    let param = parameter_vector::<M>(|s| thesis.get(s), 5.0).unwrap();
    let weights = [("z4", 0.95), ("z5", -0.95), ("d4", 0.31)];
    let dirs = Directions {
        parameters: weights
            .iter()
            .map(|(s, w)| (M::parameter_index(s).unwrap(), 0, *w))
            .collect(),
        ..Directions::default()
    };
    let (ic, opts) = kick_and_tight_options();
    let speed_at = wheel_sensor_times(2.0);
    let exact: Response<Dual<6>> = response::<M, Dual<6>>(&param, &ic, &dirs, 2.0, &opts, &speed_at).unwrap();
    let moved = |h: f64| -> Response<f64> {
        let mut p = param.clone();
        for (s, w) in weights {
            p[M::parameter_index(s).unwrap()] += w * h;
        }
        response::<M, f64>(&p, &ic, &Directions::default(), 2.0, &opts, &speed_at).unwrap()
    };
    let h = 1e-5;
    let (a, b) = (moved(h), moved(-h));
    for (name, e, a, b) in [
        ("roll", &exact.roll, &a.roll, &b.roll),
        ("steer", &exact.steer, &a.steer, &b.steer),
        ("speed", &exact.speed, &a.speed, &b.speed),
    ] {
        let (worst, scale) = misfit_against_central(e, a, b, h, 0);
        assert!(
            worst <= 1e-5 * scale,
            "d {name} along the combination: exact and central differences differ by {worst:.3e} (scale {scale:.3e})"
        );
    }
}

/// With a controller closed around the equations (a `[feedback]` gain
/// schedule, every gain non-zero and changing with speed), the forward
/// sensitivities still match central differences of whole simulations,
/// along the initial speed too (the gains' slope over speed enters there),
/// and the lean response is the full simulation's with the same controller.
#[test]
fn forward_sensitivities_with_a_controller_match_central_differences() {
    use bikedyn::generated::ExtendedFree;
    use bikedyn::runtime::feedback::GainSchedule;
    use bikedyn::runtime::linearize::parameter_vector;
    use bikedyn::runtime::parameters::ThesisParameters;
    use bikedyn::runtime::scalar::Dual;
    use bikedyn::runtime::simulate::sensitivity::{response_with, Directions, Response};
    use bikedyn::runtime::simulate::{simulate, Inputs};
    use bikedyn::runtime::MultibodyModel;
    use nalgebra::Matrix2x4;
    type M = ExtendedFree;

    let schedule = GainSchedule::new(
        vec![0.0, 10.0],
        vec![
            Matrix2x4::new(0.5, 0.2, 0.1, 0.05, -0.3, 0.4, -8.0, 0.1),
            Matrix2x4::new(1.0, -0.2, 0.3, 0.0, 0.2, 0.8, -2.0, 0.3),
        ],
    )
    .unwrap();
    let feedback = Some(&schedule);
    let thesis = ThesisParameters::thesis_bicycle();
    let mut param = parameter_vector::<M>(|s| thesis.get(s), 5.0).unwrap();
    param[M::parameter_index("c_steer").unwrap()] = 0.2;
    let mut dirs = Directions {
        parameters: vec![(M::parameter_index("c_steer").unwrap(), 0, 1.0)],
        ..Directions::default()
    };
    dirs.initial[2] = Some(1); // roll rate
    dirs.initial[4] = Some(2); // speed
    let (ic, opts) = kick_and_tight_options();
    let duration = 2.0;
    let speed_at = wheel_sensor_times(duration);
    let exact: Response<Dual<6>> =
        response_with::<M, Dual<6>>(&param, &ic, &dirs, duration, &opts, &speed_at, feedback).unwrap();
    let plain: Response<f64> = response_with::<M, f64>(
        &param,
        &ic,
        &Directions::default(),
        duration,
        &opts,
        &speed_at,
        feedback,
    )
    .unwrap();
    let inputs = Inputs {
        feedback: Some(schedule.clone()),
        ..Inputs::default()
    };
    let sim = simulate::<M>(&param, &ic, &inputs, duration, &opts).unwrap();
    let roll = sim.coordinate("theta").unwrap();
    let open = simulate::<M>(&param, &ic, &Inputs::default(), duration, &opts).unwrap();
    let open_roll = open.coordinate("theta").unwrap();
    let apart = roll
        .iter()
        .zip(&open_roll)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(apart > 1e-3, "the controller changes the response ({apart} rad)");
    for (i, (a, b)) in plain.roll.iter().zip(&roll).enumerate() {
        assert!((a - b).abs() < 1e-10, "sample {i}: lean roll {a} against simulate {b}");
        assert!((a - exact.roll[i].re).abs() < 1e-9);
    }
    let moved = |d: usize, h: f64| -> Response<f64> {
        let (mut p, mut c) = (param.clone(), ic);
        match d {
            0 => p[M::parameter_index("c_steer").unwrap()] += h,
            1 => c.roll_rate += h,
            _ => c.speed += h,
        }
        response_with::<M, f64>(&p, &c, &Directions::default(), duration, &opts, &speed_at, feedback).unwrap()
    };
    for d in 0..3 {
        let h = 1e-6;
        let (a, b) = (moved(d, h), moved(d, -h));
        for (name, e, a, b) in [
            ("roll", &exact.roll, &a.roll, &b.roll),
            ("steer", &exact.steer, &a.steer, &b.steer),
            ("speed", &exact.speed, &a.speed, &b.speed),
        ] {
            let (worst, scale) = misfit_against_central(e, a, b, h, d);
            assert!(
                worst <= 1e-5 * scale,
                "d {name} / d direction {d}: exact and central differences differ by {worst:.3e} (scale {scale:.3e})"
            );
        }
    }
}

/// The state just after a kick at 5 m/s, and integration tolerances far
/// below the differences' step, for the sensitivity checks.
/// The largest difference between a sampled channel's exact derivative
/// along direction `d` and the central difference of the channel moved by
/// `+h` (`up`) and `-h` (`down`), and the scale it is judged against (the
/// differences' largest size, at least 1e-3).
fn misfit_against_central<T: bikedyn::runtime::simulate::sensitivity::Carried>(
    exact: &[T],
    up: &[f64],
    down: &[f64],
    h: f64,
    d: usize,
) -> (f64, f64) {
    let fd: Vec<f64> = up.iter().zip(down).map(|(x, y)| (x - y) / (2.0 * h)).collect();
    let scale = fd.iter().fold(1e-3f64, |m, x| m.max(x.abs()));
    let worst = exact
        .iter()
        .zip(&fd)
        .map(|(x, f)| (x.derivative(d) - f).abs())
        .fold(0.0f64, f64::max);
    (worst, scale)
}

/// Times at which the speed is asked for, as a wheel sensor gives them:
/// off the output grid, from the start to past the end (held there).
fn wheel_sensor_times(duration: f64) -> Vec<f64> {
    (0..)
        .map(|i| 0.037 * i as f64)
        .take_while(|&t| t < duration + 0.1)
        .collect()
}

/// The verification job is one library call: its typed result is what
/// `verify --json` prints (the JSON comes from the type), and an unknown
/// model is a typed error that lists the known ones.
#[test]
fn the_verification_job_gives_the_command_lines_json() {
    use bikedyn::runtime::verify::VerifyOptions;
    let opts = VerifyOptions {
        states: 5,
        seed: 3,
        ..VerifyOptions::default()
    };
    let v = bikedyn::models::verify_models(Some("thesis_whipple"), &opts).unwrap();
    assert!(v.passed);
    assert_eq!(v.reports.len(), 1);
    let out = bikedyn(VERIFY_JSON_ARGS);
    // The same text (parsing would round the last digit of some numbers).
    assert_eq!(
        String::from_utf8_lossy(&out.stdout).trim_end(),
        serde_json::to_string_pretty(&v.to_json()).unwrap()
    );
    let e = bikedyn::models::verify_models(Some("tricycle"), &opts).unwrap_err();
    assert_eq!(e.model, "tricycle");
    assert!(e.known.contains("thesis_whipple"), "{}", e.known);
}
