//! The Whipple bicycle of any geometry (front-assembly mass centre anywhere,
//! as in Meijaard et al. 2007) with every effect of the library, driven
//! speed. Each effect's parameters default to the value at which it is
//! absent, so with a plain bicycle this model is the Whipple model; with
//! `d4 = 0` it is the thesis geometry. The linear analysis of a bicycle with
//! effect parameters (damping, a steer controller, ...) runs through it.

use super::thesis_whipple::Speed;
use super::whipple_offset::declare;
use crate::effects;
use crate::model::{Model, ModelError};

/// Every effect on the benchmark-compatible geometry, driven speed.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare("extended", crate::model::SourceFile::new("modeler/src/models/extended.rs", include_str!("extended.rs")), Speed::Driven);
    m.set_doc("Whipple bicycle of any geometry (front mass centre offset d4) with driven speed and every effect of the library, each absent at its default");
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    // The dictionary discovery searches beyond the library (the models
    // identification fits through carry it; every term zero by default).
    effects::apply(&mut m, &parts, &effects::generalized_forces::effect());
    m.build()
}
