//! The thesis model with free forward speed, tyre lateral slip with
//! relaxation ([`crate::effects::tyre_relaxation`]) and every other effect
//! of the library: independent coordinates roll, rear wheel rotation, steer,
//! rear contact lateral position and yaw; two extra states, the lagged
//! lateral tyre forces.

use super::thesis_whipple::{declare, Speed};
use crate::effects;
use crate::model::{Model, ModelError};

/// The free-speed thesis model with tyre slip.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare("thesis_tyre_free", "modeler/src/models/thesis_tyre_free.rs", Speed::Free);
    m.set_doc("Thesis Whipple bicycle with free forward speed, tyre lateral slip with relaxation, and every effect of the library");
    effects::apply(&mut m, &parts, &effects::tyre_relaxation::effect());
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    m.build()
}
