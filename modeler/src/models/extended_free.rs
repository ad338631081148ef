//! The Whipple bicycle of any geometry with every effect of the library and
//! free forward speed: the model for simulated runs with speed decay
//! (rolling resistance, drag) and for identification on measured runs, on
//! every bicycle (`d4 = 0` is the thesis geometry).

use super::thesis_whipple::Speed;
use super::whipple_offset::declare;
use crate::effects;
use crate::model::{Model, ModelError};

/// Every effect on the benchmark-compatible geometry, free speed.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare("extended_free", crate::model::SourceFile::new("modeler/src/models/extended_free.rs", include_str!("extended_free.rs")), Speed::Free);
    m.set_doc("Whipple bicycle of any geometry (front mass centre offset d4) with free forward speed and every effect of the library, each absent at its default");
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    // The dictionary discovery searches beyond the library (the models
    // identification fits through carry it; every term zero by default).
    effects::apply(&mut m, &parts, &effects::generalized_forces::effect());
    m.build()
}
