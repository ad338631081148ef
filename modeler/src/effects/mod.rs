//! The effect library: physics the rigid Whipple model lacks, each effect in
//! its own file, applicable to any bicycle model that exposes
//! [`BicycleParts`] (both base models, driven or free speed).
//!
//! An effect adds parameters (each with a meaning, a unit and a default at
//! which the effect is absent) and applied forces, or moves mass centres.
//! Applying effects to a model is part of its declaration (see
//! `models/extended.rs`), so the derivation treats them like any
//! other force: exact derivatives, verified by `bikedyn verify`, including
//! the power identity and the sign of each dissipative force's power.
//!
//! Adding an effect is writing one file here with `pub fn effect() ->
//! Effect` and adding its name to the list at the bottom.
//!
//! Corrections of uncertain inertial parameters (frame roll inertia `I3x`,
//! mass-centre height `z3`, ...) need no effect: they are parameters of
//! every model already, and the identification frees them by name.

use crate::expr::Expr;
pub use crate::identification::{Candidate, Fitted, Identification, LinearEquivalent, Signature};
use crate::model::{BodyId, FrameId, ModelBuilder, PointId, SourceFile};

/// The parts of a bicycle model an effect may refer to.
#[derive(Clone, Debug)]
pub struct BicycleParts {
    pub rear_wheel: BodyId,
    pub rear_frame: BodyId,
    /// Handlebar + fork.
    pub fork: BodyId,
    pub front_wheel: BodyId,
    /// Rear frame axes: x forward perpendicular to the steer axis, z along it.
    pub rear_frame_axes: FrameId,
    /// Fork axes: the rear frame axes turned by the steer angle.
    pub fork_axes: FrameId,
    pub rear_wheel_axes: FrameId,
    pub front_wheel_axes: FrameId,
    /// Wheel centres.
    pub rear_hub: PointId,
    pub front_hub: PointId,
    /// The point of the steer axis where the thesis puts the fork's mass centre.
    pub steer_point: PointId,
    pub rear_frame_mass_centre: PointId,
    /// Geometric contact points (lowest points of the rims).
    pub rear_contact: PointId,
    pub front_contact: PointId,
    /// Coordinate names.
    pub rear_contact_lateral: String,
    pub yaw: String,
    pub roll: String,
    pub steer: String,
    pub rear_wheel_rotation: String,
    pub front_wheel_rotation: String,
    pub rear_wheel_radius: Expr,
    pub front_wheel_radius: Expr,
    /// Gravitational acceleration (parameter).
    pub gravity: Expr,
}

/// Quasi-static normal loads `(rear, front)` of the wheels from the current
/// geometry: the weight of the whole bicycle shared between the contacts by
/// moments about the rear contact, along the ground-plane line joining the
/// contacts. Dynamic load transfer is neglected (exact on level ground at
/// constant speed).
pub fn static_normal_loads(m: &ModelBuilder, parts: &BicycleParts) -> (Expr, Expr) {
    use crate::expr::{dot3, num, position, Vec3};
    let (rc, fc) = (position(parts.rear_contact), position(parts.front_contact));
    let d: Vec3 = [fc[0].clone() - rc[0].clone(), fc[1].clone() - rc[1].clone(), num(0)];
    let dd = dot3(&d, &d);
    let mut weight = num(0);
    let mut moment = num(0);
    for b in &m.model().bodies {
        let g = position(b.mass_centre);
        let r: Vec3 = std::array::from_fn(|k| g[k].clone() - rc[k].clone());
        weight = weight + b.mass.clone();
        moment = moment + b.mass.clone() * dot3(&r, &d);
    }
    let g = parts.gravity.clone();
    let front = g.clone() * moment / dd;
    (g * weight - front.clone(), front)
}

/// One effect of the library.
#[derive(Clone, Copy)]
pub struct Effect {
    /// Name, as listed by `bikedyn models` and used by `--effects`.
    pub name: &'static str,
    /// One line: what the effect models.
    pub doc: &'static str,
    /// Declares the effect's parameters and forces on a bicycle model.
    pub apply: fn(&mut ModelBuilder, &BicycleParts),
    /// How identification tests the effect, or why it never does: a
    /// required field, so an effect cannot be added without saying.
    pub identification: Identification,
}

/// Apply `effect` to the model being declared.
pub fn apply(m: &mut ModelBuilder, parts: &BicycleParts, effect: &Effect) {
    if let Some(file) = library_file(effect.name) {
        m.add_source(file);
    }
    m.begin_effect(effect.name, effect.doc);
    m.declare_identification(effect.identification);
    (effect.apply)(m, parts);
    m.end_effect();
}

macro_rules! effects {
    ($($name:ident),* $(,)?) => {
        $(pub mod $name;)*
        /// Every effect of the library that is absent at its defaults, in
        /// order (the extended models apply all of them).
        pub fn all() -> Vec<Effect> {
            vec![$($name::effect()),*]
        }

        /// The file that declares the library effect `name`, with its text
        /// (part of the inputs of the committed code of every model that
        /// applies it); `None` for an effect declared outside the library.
        pub fn library_file(name: &str) -> Option<SourceFile> {
            match name {
                $(stringify!($name) => Some(SourceFile::new(
                    concat!("modeler/src/effects/", stringify!($name), ".rs"),
                    include_str!(concat!(stringify!($name), ".rs")),
                )),)*
                "tyre_relaxation" => Some(SourceFile::new(
                    "modeler/src/effects/tyre_relaxation.rs",
                    include_str!("tyre_relaxation.rs"),
                )),
                "generalized_forces" => Some(SourceFile::new(
                    "modeler/src/effects/generalized_forces.rs",
                    include_str!("generalized_forces.rs"),
                )),
                _ => None,
            }
        }
    };
}

/// Tyre lateral slip with relaxation: it changes the degrees of freedom (the
/// wheels may slide sideways), so it is never "absent" and is applied by its
/// own models, not by the extended ones.
pub mod generalized_forces;
pub mod tyre_relaxation;

effects!(
    steer_damping,
    steer_friction,
    rolling_resistance,
    aero_drag,
    lateral_mass_offset,
    steer_controller,
);
