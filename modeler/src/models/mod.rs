//! The zoo of models. Each model is one file that declares it with the
//! [`crate::model`] API and exposes `pub fn model()`; `build.rs` derives and
//! emits every model listed here, and emits the registry the runtime and
//! the CLI use. Adding a model is writing its file and adding one name to
//! the list below.

use crate::model::{Model, ModelError};

macro_rules! models {
    ($($name:ident),* $(,)?) => {
        $(pub mod $name;)*
        /// Every model that `build.rs` generates code for, in registry order.
        pub fn all() -> Result<Vec<Model>, ModelError> {
            Ok(vec![$($name::model()?),*])
        }
    };
}

models!(
    thesis_whipple,
    whipple_offset,
    thesis_whipple_free,
    whipple_offset_free,
    extended,
    extended_free,
    tyre_free,
);
