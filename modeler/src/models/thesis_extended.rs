//! The thesis model with every effect of the library (`crate::effects`),
//! driven speed. Each effect's parameters default to the value at which it
//! is absent, so with a plain bicycle this model is the thesis model; the
//! identification (issue 9) frees the parameters of the effects it tests.

use super::thesis_whipple::{declare, Speed};
use crate::effects;
use crate::model::{Model, ModelError};

/// The thesis model with all effects.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare("thesis_extended", "modeler/src/models/thesis_extended.rs", Speed::Driven);
    m.set_doc("Thesis Whipple bicycle (driven speed) with every effect of the library, each absent at its default");
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    m.build()
}
