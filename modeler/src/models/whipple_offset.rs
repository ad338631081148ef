//! Benchmark-compatible Whipple bicycle: the thesis model with the handlebar +
//! fork mass centre off the steer axis. The thesis puts it on the axis
//! (section 3.5.1.2 calls that an approximation); Meijaard et al. (2007) do
//! not, so representing their benchmark exactly needs the offset `d4`.
//! With `d4 = 0` this model is the thesis model.

use super::thesis_whipple::{self, Speed};
use crate::effects::BicycleParts;
use crate::expr::{num, vec3};
use crate::model::{Model, ModelBuilder, ModelError, SourceFile, Uncertainty};

const SOURCE: SourceFile = SourceFile::new("modeler/src/models/whipple_offset.rs", include_str!("whipple_offset.rs"));

/// Declare the offset variant under `name` (model file `source`).
pub fn declare(name: &str, source: impl Into<SourceFile>, speed: Speed) -> (ModelBuilder, BicycleParts) {
    let (mut m, parts) = thesis_whipple::declare(name, source, speed);
    m.add_source(SOURCE);
    m.set_base("whipple_offset");
    m.set_doc(match speed {
        Speed::Driven => "Whipple bicycle with the handlebar/fork mass centre a distance d4 ahead of the steer axis (benchmark-compatible)",
        Speed::Free => "Whipple bicycle with the handlebar/fork mass centre a distance d4 ahead of the steer axis (benchmark-compatible), free forward speed",
    });
    let d4 = m.parameter("d4", "handlebar/fork mass centre ahead of the steer axis, fork x (m)");
    m.uncertainty("d4", Uncertainty::MASS_CENTRE);
    let g4 = m.point(
        "G4_offset",
        Some(parts.steer_point),
        vec![(parts.fork_axes, vec3(d4, num(0), num(0)))],
    );
    m.move_mass_centre(parts.fork, g4);
    (m, parts)
}

/// The offset variant (driven speed).
pub fn model() -> Result<Model, ModelError> {
    declare("whipple_offset", SOURCE, Speed::Driven).0.build()
}
