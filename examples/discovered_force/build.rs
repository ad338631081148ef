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

const SOURCE: &str = "examples/discovered_force/build.rs";

fn bicycle(name: &str, speed: Speed) -> Result<Model, ModelError> {
    let (mut m, parts) = whipple_offset::declare(name, SOURCE, speed);
    m.set_doc(match speed {
        Speed::Driven => "Whipple bicycle of any geometry with the force identify discovered, driven speed",
        Speed::Free => "Whipple bicycle of any geometry with the force identify discovered, free forward speed",
    });
    effects::apply(&mut m, &parts, &discovered::effect());
    m.build()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=effects/discovered.rs");
    let out = PathBuf::from(std::env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let models = [
        bicycle("discovered_bicycle", Speed::Driven),
        bicycle("discovered_bicycle_free", Speed::Free),
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
