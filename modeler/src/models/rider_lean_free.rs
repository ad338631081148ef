//! The leaning-rider bicycle with free forward speed (simulation and
//! identification of runs whose speed changes).

use super::rider_lean::declare;
use super::thesis_whipple::Speed;
use crate::model::{Model, ModelError, SourceFile};

/// The free-speed leaning-rider bicycle.
pub fn model() -> Result<Model, ModelError> {
    declare(
        "rider_lean_free",
        SourceFile::new("modeler/src/models/rider_lean_free.rs", include_str!("rider_lean_free.rs")),
        Speed::Free,
    )
    .0
    .build()
}
