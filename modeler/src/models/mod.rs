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
        /// Each is checked for the coordinate roles the runtime's jobs need
        /// ([`crate::model::BICYCLE_JOBS`]).
        pub fn all() -> Result<Vec<Model>, ModelError> {
            let models = vec![$($name::model()?),*];
            for m in &models {
                m.check_roles(crate::model::BICYCLE_JOBS)?;
            }
            Ok(models)
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
    rider_lean,
    rider_lean_free,
);
