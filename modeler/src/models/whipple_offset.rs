//! Benchmark-compatible Whipple bicycle: the thesis model with the handlebar +
//! fork mass centre off the steer axis. The thesis puts it on the axis
//! (section 3.5.1.2 calls that an approximation); Meijaard et al. (2007) do
//! not, so representing their benchmark exactly needs the offset `d4`.
//! With `d4 = 0` this model is the thesis model.

use crate::expr::{num, vec3};
use crate::model::{Model, ModelError};

/// The offset variant.
pub fn model() -> Result<Model, ModelError> {
    let (mut m, parts) = super::thesis_whipple::declare("whipple_offset", "modeler/src/models/whipple_offset.rs");
    m.set_doc("Whipple bicycle with the handlebar/fork mass centre a distance d4 ahead of the steer axis (benchmark-compatible)");
    let d4 = m.parameter("d4", "handlebar/fork mass centre ahead of the steer axis, fork x (m)");
    let g4 = m.point(
        "G4_offset",
        Some(parts.steer_point),
        vec![(parts.fork_frame, vec3(d4, num(0), num(0)))],
    );
    m.move_mass_centre(parts.fork, g4);
    m.build()
}
