//! Issue 10, point 10: the fast upright linearization that every generated
//! model uses (`linearize_with_rest`: Newton in f64, one real factorization
//! with dual right-hand sides, one shared `all_quantities` evaluation) equals
//! the general path (`linearize_with_rest_general`: the whole reduced system
//! in dual numbers) to 1e-12 on random designs, and fails exactly when it
//! fails.

use bikedyn::generated::{Extended, ExtendedFree, ThesisWhipple, ThesisWhippleFree, WhippleOffset};
use bikedyn::runtime::linearize::{linearize_with_rest_general, parameter_vector, WithRest};
use bikedyn::runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn::runtime::random::SplitMix64;
use bikedyn::runtime::MultibodyModel;
use nalgebra::DMatrix;

/// A random design around the benchmark or thesis bicycle: geometry, radii,
/// masses and inertias scaled, mass centres moved, gravity changed.
fn random_design(rng: &mut SplitMix64) -> ThesisParameters {
    let mut d = if rng.next_f64() < 0.5 {
        BenchmarkParameters::benchmark_bicycle()
    } else {
        ThesisParameters::thesis_bicycle().to_benchmark().unwrap()
    };
    d.wheelbase *= rng.uniform(0.7, 1.4);
    d.trail = rng.uniform(-0.1, 0.3);
    d.steer_axis_tilt = rng.uniform(-0.5, 0.8);
    d.rear_wheel_radius *= rng.uniform(0.5, 2.0);
    d.front_wheel_radius *= rng.uniform(0.5, 2.0);
    for (m, ixx, iyy) in [
        (&mut d.rear_wheel_mass, &mut d.rear_wheel_ixx, &mut d.rear_wheel_iyy),
        (&mut d.front_wheel_mass, &mut d.front_wheel_ixx, &mut d.front_wheel_iyy),
    ] {
        let s = rng.uniform(0.3, 3.0);
        *m *= s;
        *ixx *= s;
        *iyy *= s;
    }
    let s = rng.uniform(0.3, 3.0);
    d.rear_frame_mass *= s;
    d.rear_frame_ixx *= s;
    d.rear_frame_iyy *= s;
    d.rear_frame_izz *= s;
    d.rear_frame_ixz *= s;
    let s = rng.uniform(0.3, 3.0);
    d.front_frame_mass *= s;
    d.front_frame_ixx *= s;
    d.front_frame_iyy *= s;
    d.front_frame_izz *= s;
    d.front_frame_ixz *= s;
    let q = 0.3 * d.wheelbase;
    d.rear_frame_com_x += rng.uniform(-q, q);
    d.rear_frame_com_z += rng.uniform(-q, q);
    d.front_frame_com_x += rng.uniform(-q, q);
    d.front_frame_com_z += rng.uniform(-q, q);
    d.g = rng.uniform(1.0, 25.0);
    d.to_thesis().unwrap()
}

/// Largest entry difference of two matrices relative to the larger entry of
/// either (a structurally zero entry is compared at the matrix's scale).
fn relative(a: &DMatrix<f64>, b: &DMatrix<f64>) -> f64 {
    let scale = a.amax().max(b.amax()).max(f64::MIN_POSITIVE);
    (a - b).amax() / scale
}

/// Compare the two paths for model `M` at `param` and independent rates
/// `dq0`; returns whether they computed (both) or failed (both).
fn compare<M: MultibodyModel, const N: usize>(param: &[f64], dq0: &[f64], case: &str) -> bool {
    let fast = M::linearize_with_rest_exact(param, dq0);
    let general = linearize_with_rest_general::<M, N>(param, dq0);
    match (fast, general) {
        (Ok((lf, rf)), Ok((lg, rg))) => {
            let pairs: [(&str, &DMatrix<f64>, &DMatrix<f64>); 4] = [
                ("mass", &lf.mass, &lg.mass),
                ("damping", &lf.damping, &lg.damping),
                ("stiffness", &lf.stiffness, &lg.stiffness),
                ("stiffness at rest", &rf, &rg),
            ];
            for (what, f, g) in pairs {
                let d = relative(f, g);
                assert!(
                    d < 1e-12,
                    "{} {case}: {what} differs by {d:e}\nfast {f}\ngeneral {g}",
                    M::NAME
                );
            }
            true
        }
        (Err(a), Err(b)) => {
            assert_eq!(
                std::mem::discriminant(&a),
                std::mem::discriminant(&b),
                "{} {case}: {a} / {b}",
                M::NAME
            );
            false
        }
        (a, b) => panic!(
            "{} {case}: fast {:?}, general {:?}",
            M::NAME,
            a.map(|_: WithRest| ()),
            b.map(|_| ())
        ),
    }
}

/// Parameters of model `M` for design `t` at forward speed `v`, with every
/// effect parameter moved from its default (absent) by up to `effects`.
fn param_of<M: MultibodyModel>(t: &ThesisParameters, v: f64, effects: f64, rng: &mut SplitMix64) -> Vec<f64> {
    let mut p = parameter_vector::<M>(|s| t.get(s), v).unwrap();
    for (i, info) in M::PARAMETER_INFO.iter().enumerate() {
        if info.effect.is_some() {
            p[i] += effects * rng.next_f64();
        }
    }
    p
}

#[test]
fn fast_upright_linearization_equals_general_path_on_random_designs() {
    let mut rng = SplitMix64::new(1010);
    let mut computed = 0;
    let cases = 300;
    for case in 0..cases {
        let t = random_design(&mut rng);
        let v = rng.uniform(0.0, 10.0);
        let label = format!("case {case} (V = {v})");
        let p = param_of::<ThesisWhipple>(&t, v, 0.0, &mut rng);
        computed += compare::<ThesisWhipple, 4>(&p, &[0.0; 2], &label) as usize;
        // The fork mass centre off the steer axis.
        let mut t4 = t;
        t4.fork_com_offset = rng.uniform(-0.05, 0.05);
        let p = param_of::<WhippleOffset>(&t4, v, 0.0, &mut rng);
        compare::<WhippleOffset, 4>(&p, &[0.0; 2], &label);
        // Every effect present (applied forces at speed and at rest).
        let p = param_of::<Extended>(&t, v, 0.05, &mut rng);
        compare::<Extended, 4>(&p, &[0.0; 2], &label);
        // Free speed: three independent coordinates, the speed in a rate.
        let p = param_of::<ThesisWhippleFree>(&t, v, 0.0, &mut rng);
        let k = ThesisWhippleFree::INDEPENDENT
            .iter()
            .position(|&j| Some(j) == ThesisWhippleFree::SPEED_COORDINATE)
            .unwrap();
        let mut dq0 = [0.0; 3];
        dq0[k] = v / t.rear_wheel_radius;
        compare::<ThesisWhippleFree, 6>(&p, &dq0, &label);
        // Free speed with every effect (speed-dependent applied forces).
        let p = param_of::<ExtendedFree>(&t, v, 0.05, &mut rng);
        compare::<ExtendedFree, 6>(&p, &dq0, &label);
    }
    assert!(computed > cases * 9 / 10, "only {computed} of {cases} designs computed");
}
