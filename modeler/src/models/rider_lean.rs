//! A bicycle with a leaning rider: the benchmark-compatible Whipple bicycle
//! (`whipple_offset`) with the rider's upper body as a body of its own (body
//! 6), hinged to the rear frame about a longitudinal axis through the saddle
//! and held by a passive spring and damper, as in Moore's (2012) rider-lean
//! model. The rear frame (body 3) then carries the rest of the rider (legs
//! and pelvis) with the frame. Every effect of the library is declared,
//! each absent at its default (as in `extended`), so a rider's bicycle
//! meets damping, friction or a controller, and identification's
//! candidates, like any other. Driven speed; `rider_lean_free` frees it.
//!
//! The lean axis is fixed in the rear frame and horizontal, pointing
//! forward, when the bicycle stands upright: the axes of the rider's
//! parameters (`xL`, `zL`, `x6`, `z6`, `I6*`) are those of the upright
//! bicycle, x forward and z up, as a rider split of HumanControl or
//! bicycleparameters gives them. The lean `lean` is the upper body's
//! rotation about that axis relative to the frame, positive to the right as
//! the roll.

use super::thesis_whipple::{self, Speed};
use super::whipple_offset;
use crate::effects::{self, BicycleParts};
use crate::expr::{coord, inertia_xz, num, param, rate, vec3, Expr};
use crate::model::{Axis, Force, Model, ModelBuilder, ModelError, Role, SourceFile, Uncertainty};

const SOURCE: SourceFile = SourceFile::new("modeler/src/models/rider_lean.rs", include_str!("rider_lean.rs"));

/// The rear frame's pitch when both wheels stand on the ground, by which
/// the lean axis is turned back to lie horizontal at upright.
fn upright_pitch() -> Expr {
    thesis_whipple::upright_pitch(
        param("x4") + param("x5"),
        param("z4") + param("z5"),
        param("Rt"),
        param("Rd"),
    )
}

/// Declare the leaning-rider bicycle under `name` (model file `source`).
pub fn declare(name: &str, source: impl Into<SourceFile>, speed: Speed) -> (ModelBuilder, BicycleParts) {
    let (mut m, parts) = whipple_offset::declare(name, source, speed);
    m.add_source(SOURCE);
    m.set_base("rider_lean");
    m.set_doc(match speed {
        Speed::Driven => "Whipple bicycle (front mass centre offset d4) with the rider's upper body leaning on the rear frame about a longitudinal axis through the saddle, passive spring k_lean and damper c_lean (Moore 2012), and every effect of the library, each absent at its default",
        Speed::Free => "Whipple bicycle (front mass centre offset d4) with the rider's upper body leaning on the rear frame (spring k_lean, damper c_lean; Moore 2012), every effect of the library, free forward speed",
    });
    let lean = m.coordinate(
        "lean",
        Role::Independent,
        0.0,
        "rider's upper-body lean relative to the rear frame, about the longitudinal axis through the saddle (rad), positive to the right",
    );
    let xl = m.parameter("xL", "lean axis point (saddle) from the rear wheel centre, forward, upright axes (m)");
    let zl = m.parameter("zL", "lean axis point (saddle) from the rear wheel centre, up, upright axes (m)");
    let x6 = m.parameter("x6", "upper-body mass centre from the lean axis point, forward, upright axes (m)");
    let z6 = m.parameter("z6", "upper-body mass centre from the lean axis point, up, upright axes (m)");
    let m6 = m.parameter("m6", "rider's upper-body mass (kg)");
    let i6x = m.parameter("I6x", "upper-body inertia xx about its mass centre, upright axes (kg m^2)");
    let i6y = m.parameter("I6y", "upper-body inertia yy (kg m^2)");
    let i6z = m.parameter("I6z", "upper-body inertia zz (kg m^2)");
    let i6xz = m.parameter("I6xz", "upper-body inertia xz (kg m^2)");
    // A rider's lean stiffness is a property of the person, not a
    // measured dimension: no default, the file says it.
    let k = m.parameter("k_lean", "lean stiffness of the rider's hips and trunk (N m/rad)");
    let c = m.parameter_with_default("c_lean", "lean damping of the rider's hips and trunk (N m s/rad)", 0.0);
    // Physical values only: a passive hip and trunk neither push the rider
    // over nor feed energy in; a body has positive mass and moments.
    m.lower_bound("c_lean", 0.0, false);
    m.lower_bound("k_lean", 0.0, false);
    for p in ["m6", "I6x", "I6y", "I6z"] {
        m.lower_bound(p, 0.0, true);
    }
    for (p, u) in [
        ("xL", Uncertainty::MASS_CENTRE),
        ("zL", Uncertainty::MASS_CENTRE),
        ("x6", Uncertainty::MASS_CENTRE),
        ("z6", Uncertainty::MASS_CENTRE),
        ("m6", Uncertainty::MASS),
        ("I6x", Uncertainty::INERTIA),
        ("I6y", Uncertainty::INERTIA),
        ("I6z", Uncertainty::INERTIA),
        ("I6xz", Uncertainty::INERTIA),
    ] {
        m.uncertainty(p, u);
    }

    // Upright axes fixed in the rear frame (the frame's axes turned back by
    // its upright pitch), then the lean about their x axis.
    let base = m.frame("A6u", parts.rear_frame_axes, vec![(Axis::Y, -upright_pitch())]);
    let upper_body_axes = m.frame("A6", base, vec![(Axis::X, lean)]);
    let lean_point = m.point("L", Some(parts.rear_hub), vec![(base, vec3(xl, num(0), zl))]);
    let g6 = m.point("G6", Some(lean_point), vec![(upper_body_axes, vec3(x6, num(0), z6))]);
    m.body("upper_body", upper_body_axes, m6, inertia_xz(i6x, i6y, i6z, i6xz), g6);
    m.force(Force::Generalized {
        name: "lean_spring".into(),
        coordinate: "lean".into(),
        expr: -(k * coord("lean")),
    });
    m.dissipative_force(Force::Generalized {
        name: "lean_damper".into(),
        coordinate: "lean".into(),
        expr: -(c * rate("lean")),
    });
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    (m, parts)
}

/// The leaning-rider bicycle, driven speed.
pub fn model() -> Result<Model, ModelError> {
    declare("rider_lean", SOURCE, Speed::Driven).0.build()
}
