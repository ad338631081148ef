//! The thesis model with every effect of the library and free forward
//! speed: the model for simulated runs with speed decay (rolling
//! resistance, drag) and for identification on measured runs.

use super::thesis_whipple::{declare, Speed};
use crate::effects;
use crate::model::{Model, ModelError};

/// The free-speed thesis model with all effects.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare(
        "thesis_extended_free",
        "modeler/src/models/thesis_extended_free.rs",
        Speed::Free,
    );
    m.set_doc("Thesis Whipple bicycle with free forward speed and every effect of the library, each absent at its default");
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    m.build()
}
