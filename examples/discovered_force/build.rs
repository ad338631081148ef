//! Derive the offset-geometry bicycle with the effect `identify` wrote
//! (`effects/discovered.rs`, as written: its parameters, forces and
//! identification block), driven and free speed, as a user would after a
//! discovery: copy the file, apply it, generate.

use bikedyn_modeler::effects;
use bikedyn_modeler::model::{Model, ModelError};
use bikedyn_modeler::models::thesis_whipple::Speed;
use bikedyn_modeler::models::whipple_offset;
use std::path::PathBuf;

#[path = "effects/discovered.rs"]
mod discovered;
#[path = "effects/discovered_lag.rs"]
mod discovered_lag;
#[path = "effects/discovered_runs.rs"]
mod discovered_runs;

const SOURCE: &str = "examples/discovered_force/build.rs";

fn bicycle(name: &str, speed: Speed, effect: effects::Effect) -> Result<Model, ModelError> {
    let (mut m, parts) = whipple_offset::declare(name, SOURCE, speed);
    m.set_doc(match speed {
        Speed::Driven => "Whipple bicycle of any geometry with a force identify discovered, driven speed",
        Speed::Free => "Whipple bicycle of any geometry with a force identify discovered, free forward speed",
    });
    effects::apply(&mut m, &parts, &effect);
    m.build()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=effects/discovered.rs");
    println!("cargo:rerun-if-changed=effects/discovered_lag.rs");
    println!("cargo:rerun-if-changed=effects/discovered_runs.rs");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    // The steer torque from the roll angle (refitted in the tests), and a
    // lagged steer torque from the roll rate (a first-order state), and
    // what the search in the time series found in measured-style runs.
    let models = [
        bicycle("discovered_bicycle", Speed::Driven, discovered::effect()),
        bicycle("discovered_bicycle_free", Speed::Free, discovered::effect()),
        bicycle("discovered_lag_bicycle", Speed::Driven, discovered_lag::effect()),
        bicycle("discovered_lag_bicycle_free", Speed::Free, discovered_lag::effect()),
        bicycle("discovered_runs_bicycle", Speed::Driven, discovered_runs::effect()),
        bicycle("discovered_runs_bicycle_free", Speed::Free, discovered_runs::effect()),
    ]
    .into_iter()
    .collect::<Result<Vec<Model>, ModelError>>()
    .unwrap_or_else(|e| panic!("{e}"));
    for m in &models {
        m.check_roles(bikedyn_modeler::model::BICYCLE_JOBS)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    bikedyn_modeler::codegen::generate(&models, &out).unwrap_or_else(|e| panic!("{e}"));
}
