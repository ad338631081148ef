//! The thesis model with free forward speed: no driving constraint; the rear
//! wheel rotation is a degree of freedom, so speed can change (coasting,
//! rolling resistance, drag). Its linearization at a speed reproduces the
//! driven model's canonical matrices (`tests/linear_analysis/free_speed.rs`).

use super::thesis_whipple::{declare, Speed};
use crate::model::{Model, ModelError};

/// The free-speed thesis model.
pub fn model() -> Result<Model, ModelError> {
    declare("thesis_whipple_free", crate::model::SourceFile::new("modeler/src/models/thesis_whipple_free.rs", include_str!("thesis_whipple_free.rs")), Speed::Free).0.build()
}
