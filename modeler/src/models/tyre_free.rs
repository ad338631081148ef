//! The Whipple bicycle of any geometry with free forward speed, tyre
//! lateral slip with relaxation ([`crate::effects::tyre_relaxation`]) and
//! every other effect of the library: independent coordinates roll, rear
//! wheel rotation, steer, rear contact lateral position and yaw; two extra
//! states, the lagged lateral tyre forces.

use super::thesis_whipple::Speed;
use super::whipple_offset::declare;
use crate::effects;
use crate::model::{Model, ModelError};

/// Tyre slip and every effect on the benchmark-compatible geometry, free speed.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = declare("tyre_free", crate::model::SourceFile::new("modeler/src/models/tyre_free.rs", include_str!("tyre_free.rs")), Speed::Free);
    m.set_doc("Whipple bicycle of any geometry with free forward speed, tyre lateral slip with relaxation, and every effect of the library");
    effects::apply(&mut m, &parts, &effects::tyre_relaxation::effect());
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    m.build()
}
