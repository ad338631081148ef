//! The zoo of models. Each model is one file that declares it with the
//! [`crate::model`] API; `build.rs` derives and emits every model in [`all`].

pub mod thesis_whipple;
pub mod whipple_offset;

use crate::model::{Model, ModelError};

/// Every model that `build.rs` generates code for.
pub fn all() -> Result<Vec<Model>, ModelError> {
    Ok(vec![thesis_whipple::model()?, whipple_offset::model()?])
}
