//! The user's model runs through bikedyn's runtime: verification against
//! finite differences, and the linearization against the textbook small
//! oscillations of a double pendulum.

use bikedyn_runtime::linearize::{linearize_at_speed, parameter_vector};
use bikedyn_runtime::verify::{verify, VerifyOptions};
use double_pendulum::DoublePendulum;

fn params() -> Vec<f64> {
    parameter_vector::<DoublePendulum>(
        |s| match s {
            "l1" | "l2" => Some(0.8),
            "m1" | "m2" => Some(1.5),
            "g" => Some(9.81),
            _ => None,
        },
        0.0,
    )
    .unwrap()
}

#[test]
fn generated_code_verifies() {
    let r = verify::<DoublePendulum>(&params(), &VerifyOptions::default());
    for q in &r.quantities {
        println!("{:<60} {:.2e}", q.name, q.max_rel_error);
    }
    assert!(r.passed);
    assert_eq!(double_pendulum::MODELS.len(), 1);
    assert_eq!(double_pendulum::MODELS[0].name, "double_pendulum");
}

/// Equal masses m and lengths l: omega^2 = (2 -+ sqrt 2) g / l.
#[test]
fn small_oscillations_match_the_textbook() {
    let lin = linearize_at_speed::<DoublePendulum>(&params(), 0.0).unwrap();
    let a = lin.mass.clone().try_inverse().unwrap() * &lin.stiffness;
    let mut w2: Vec<f64> = a.complex_eigenvalues().iter().map(|z| z.re).collect();
    w2.sort_by(f64::total_cmp);
    let (g, l) = (9.81, 0.8);
    let want = [(2.0 - 2f64.sqrt()) * g / l, (2.0 + 2f64.sqrt()) * g / l];
    for (got, want) in w2.iter().zip(want) {
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
    }
}
