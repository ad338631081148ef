//! A user's build script: declare a model with bikedyn's modeler and let it
//! generate the code (as prost-build does for protobuf).

use bikedyn_modeler::expr::{inertia_wheel, num, vec3};
use bikedyn_modeler::model::{Axis, Model, ModelError, Role, GROUND};
use std::path::PathBuf;

/// A planar double pendulum of two point masses on massless rods, swinging
/// about the global y axis (z up).
fn double_pendulum() -> Result<Model, ModelError> {
    let mut m = Model::builder("double_pendulum")
        .doc("planar double pendulum of point masses (example of a user's model)")
        .source("examples/double_pendulum/build.rs");
    let th1 = m.coordinate(
        "theta1",
        Role::Independent,
        0.0,
        "upper rod angle from the downward vertical (rad)",
    );
    let th2 = m.coordinate(
        "theta2",
        Role::Independent,
        0.0,
        "lower rod angle, relative to the upper rod (rad)",
    );
    let l1 = m.parameter("l1", "upper rod length (m)");
    let l2 = m.parameter("l2", "lower rod length (m)");
    let m1 = m.parameter("m1", "upper mass (kg)");
    let m2 = m.parameter("m2", "lower mass (kg)");
    m.parameter("g", "gravitational acceleration (m/s^2)");
    m.gravity("g", Axis::Z);
    let upper = m.frame("upper", GROUND, vec![(Axis::Y, th1)]);
    let lower = m.frame("lower", upper, vec![(Axis::Y, th2)]);
    let bob1 = m.point("bob1", None, vec![(upper, vec3(num(0), num(0), -l1))]);
    let bob2 = m.point("bob2", Some(bob1), vec![(lower, vec3(num(0), num(0), -l2))]);
    m.body("upper_mass", upper, m1, inertia_wheel(num(0), num(0)), bob1);
    m.body("lower_mass", lower, m2, inertia_wheel(num(0), num(0)), bob2);
    m.point_of_interest(bob2);
    m.build()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let model = double_pendulum().unwrap_or_else(|e| panic!("{e}"));
    bikedyn_modeler::codegen::generate(&[model], &out).unwrap_or_else(|e| panic!("{e}"));
}
