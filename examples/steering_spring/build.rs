//! A user's build script: a bicycle effect bikedyn's library lacks, a
//! steering return spring (the self-centring torsional spring sold as a
//! "steering stabilizer"), declared with bikedyn's public modeler API and
//! applied to the library's offset-geometry bicycle beside the library's
//! steer damping, so that identification has to tell the two apart.

use bikedyn_modeler::effects::{self, BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use bikedyn_modeler::expr::coord;
use bikedyn_modeler::model::{Force, Model, ModelBuilder, ModelError};
use bikedyn_modeler::models::thesis_whipple::Speed;
use bikedyn_modeler::models::whipple_offset;
use std::path::PathBuf;

const SOURCE: &str = "examples/steering_spring/build.rs";

/// The spring's torque `-k_spring gamma` acts on the steer coordinate: a
/// generalized force on the relative angle between fork and frame is a
/// torque on the fork about the steer axis with its reaction on the frame.
fn apply_steering_spring(m: &mut ModelBuilder, parts: &BicycleParts) {
    let k = m.parameter_with_default(
        "k_spring",
        "steering return spring stiffness about the steer axis (N m/rad)",
        0.0,
    );
    // A return spring pulls the handlebar back to centre; a negative
    // stiffness would push it away, which no such spring does.
    m.lower_bound("k_spring", 0.0, false);
    m.force(Force::Generalized {
        name: "steering_spring".into(),
        coordinate: parts.steer.clone(),
        expr: -(k * coord(&parts.steer)),
    });
}

/// What identification fits for the spring: its stiffness, around 1 N m/rad
/// (a stabilizer spring adds a few N m/rad, beside the bicycle's own
/// speed-dependent steer stiffness of tens of N m/rad at riding speeds).
const FITTED: &[Fitted] = &[Fitted::plain("k_spring", 1.0, false)];

/// The steering return spring as an effect with its identification
/// declaration.
fn steering_spring() -> Effect {
    Effect {
        name: "steering_spring",
        doc: "steering return spring between fork and frame, torque -k_spring gamma",
        apply: apply_steering_spring,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::FrequencyShiftWithSpeed],
            reason: "a weave frequency error that changes with speed: a constant steer stiffness matters most at low speed, where the bicycle's own speed-dependent steer stiffness is small",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}

/// The offset-geometry bicycle (any geometry; `d4 = 0` is the thesis
/// geometry) with the library's steer damping and the user's spring.
fn spring_bicycle(name: &str, speed: Speed) -> Result<Model, ModelError> {
    let (mut m, parts) = whipple_offset::declare(name, SOURCE, speed);
    m.set_doc(match speed {
        Speed::Driven => {
            "Whipple bicycle of any geometry with steer damping and a steering return spring, driven speed"
        }
        Speed::Free => {
            "Whipple bicycle of any geometry with steer damping and a steering return spring, free forward speed"
        }
    });
    let library = effects::steer_damping::effect();
    effects::apply(&mut m, &parts, &library);
    effects::apply(&mut m, &parts, &steering_spring());
    m.build()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    // Driven speed for the linear (weave) predictions, free speed for the
    // synthetic runs and the fits: identification needs both twins.
    let models = [
        spring_bicycle("spring_bicycle", Speed::Driven),
        spring_bicycle("spring_bicycle_free", Speed::Free),
    ]
    .into_iter()
    .collect::<Result<Vec<Model>, ModelError>>()
    .unwrap_or_else(|e| panic!("{e}"));
    // The coordinate roles bikedyn's jobs (linear analysis, simulation,
    // identification) look up: a missing one stops the build here.
    for m in &models {
        m.check_roles(bikedyn_modeler::model::BICYCLE_JOBS)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    bikedyn_modeler::codegen::generate(&models, &out).unwrap_or_else(|e| panic!("{e}"));
}
