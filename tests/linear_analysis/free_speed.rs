//! Free forward speed: the free-speed variant of each base
//! model, linearized about upright straight running at a speed, reproduces
//! the driven model's canonical matrices, and the forward-speed equation
//! decouples from roll and steer at first order.

use bikedyn::generated::{ThesisWhipple, ThesisWhippleFree, WhippleOffset, WhippleOffsetFree};
use bikedyn::models::default_bicycle;
use bikedyn::registry::ModelInfo;
use bikedyn_runtime::linearize::{canonical_matrices, lateral_indices, linearize_at_speed, parameter_vector};
use bikedyn_runtime::MultibodyModel;
use nalgebra::Matrix2;

fn max_rel(a: &Matrix2<f64>, b: &Matrix2<f64>) -> f64 {
    let scale = a.abs().max().max(b.abs().max()).max(1e-300);
    (a - b).abs().max() / scale
}

fn same_canonical<D: MultibodyModel, F: MultibodyModel>() {
    let p = default_bicycle(&ModelInfo::of::<D>());
    let driven = canonical_matrices::<D>(|s| p.get(s)).unwrap();
    let free = canonical_matrices::<F>(|s| p.get(s)).unwrap();
    for (name, a, b) in [
        ("M0", driven.m0, free.m0),
        ("C1", driven.c1, free.c1),
        ("K0", driven.k0, free.k0),
        ("K2", driven.k2, free.k2),
    ] {
        let e = max_rel(&a, &b);
        println!("{} vs {}: {name} max relative difference {e:.2e}", D::NAME, F::NAME);
        assert!(e < 1e-12, "{name}: driven {a} free {b}");
    }
}

#[test]
fn free_speed_thesis_model_reproduces_the_driven_canonical_matrices() {
    same_canonical::<ThesisWhipple, ThesisWhippleFree>();
}

#[test]
fn free_speed_offset_model_reproduces_the_driven_canonical_matrices() {
    same_canonical::<WhippleOffset, WhippleOffsetFree>();
}

/// At every speed the linear equations in (roll, rear wheel rotation, steer)
/// are block diagonal: roll and steer do not enter the speed equation, the
/// speed does not enter roll and steer, and the rear wheel's own stiffness
/// and damping vanish (no dissipation, level ground).
fn speed_decouples<F: MultibodyModel>() {
    let p = default_bicycle(&ModelInfo::of::<F>());
    let param = parameter_vector::<F>(|s| p.get(s), 0.0).unwrap();
    let c = F::SPEED_COORDINATE.expect("free-speed model");
    let k = F::INDEPENDENT.iter().position(|&j| j == c).unwrap();
    let lateral = lateral_indices::<F>();
    assert_eq!(lateral.len(), 2);
    for v in [0.5, 3.0, 4.5, 8.0] {
        let lin = linearize_at_speed::<F>(&param, v).unwrap();
        let scale = lin.mass.abs().max();
        for &i in &lateral {
            for (what, m) in [
                ("mass", &lin.mass),
                ("damping", &lin.damping),
                ("stiffness", &lin.stiffness),
            ] {
                assert!(
                    m[(k, i)].abs() <= 1e-12 * scale * v.max(1.0).powi(2),
                    "{what}[speed, {i}] = {} at {v} m/s",
                    m[(k, i)]
                );
                assert!(
                    m[(i, k)].abs() <= 1e-12 * scale * v.max(1.0).powi(2),
                    "{what}[{i}, speed] = {} at {v} m/s",
                    m[(i, k)]
                );
            }
        }
        assert!(lin.mass[(k, k)] > 0.0, "the rear wheel's rotation has inertia");
        assert!(lin.damping[(k, k)].abs() <= 1e-12 * scale);
        assert!(lin.stiffness[(k, k)].abs() <= 1e-12 * scale);
    }
}

#[test]
fn forward_speed_decouples_at_first_order() {
    speed_decouples::<ThesisWhippleFree>();
    speed_decouples::<WhippleOffsetFree>();
}

#[test]
fn the_linearization_at_a_speed_matches_the_canonical_form_at_that_speed() {
    let p = default_bicycle(&ModelInfo::of::<ThesisWhippleFree>());
    let c = canonical_matrices::<ThesisWhipple>(|s| p.get(s)).unwrap();
    let param = parameter_vector::<ThesisWhippleFree>(|s| p.get(s), 0.0).unwrap();
    let v = 5.3;
    let lin = linearize_at_speed::<ThesisWhippleFree>(&param, v).unwrap();
    let lat = lateral_indices::<ThesisWhippleFree>();
    // Thesis steer gamma = -delta: off-diagonal signs flip.
    let flip = |m: &nalgebra::DMatrix<f64>| {
        Matrix2::new(
            m[(lat[0], lat[0])],
            -m[(lat[0], lat[1])],
            -m[(lat[1], lat[0])],
            m[(lat[1], lat[1])],
        )
    };
    assert!(max_rel(&flip(&lin.damping), &c.damping(v)) < 1e-12);
    assert!(max_rel(&flip(&lin.stiffness), &c.stiffness(v)) < 1e-12);
}
