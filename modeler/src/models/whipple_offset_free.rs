//! The benchmark-compatible model (fork mass-centre offset `d4`) with free
//! forward speed; used for the Basu-Mandal et al. (2007) nonlinear check.

use super::thesis_whipple::Speed;
use super::whipple_offset::declare;
use crate::model::{Model, ModelError};

/// The free-speed offset model.
pub fn model() -> Result<Model, ModelError> {
    declare("whipple_offset_free", crate::model::SourceFile::new("modeler/src/models/whipple_offset_free.rs", include_str!("whipple_offset_free.rs")), Speed::Free).0.build()
}
