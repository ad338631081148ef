//! Lateral offsets of the mass centres of the rear frame (`y3`, the
//! instrument box of the thesis, section 4.3) and of the front assembly
//! (`y4`), along each body's y axis (to the left, thesis axes). The Whipple
//! model assumes both bodies symmetric about their x-z planes; an offset
//! makes the bicycle lean steadily to one side in straight running.

use super::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use crate::expr::{num, vec3};
use crate::model::ModelBuilder;

fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let y3 = m.parameter_with_default("y3", "rear-frame mass centre offset to the left, frame y (m)", 0.0);
    let y4 = m.parameter_with_default("y4", "front-assembly mass centre offset to the left, fork y (m)", 0.0);
    for (body, axes, y, name) in [
        (parts.rear_frame, parts.rear_frame_axes, y3, "G3_lateral"),
        (parts.fork, parts.fork_axes, y4, "G4_lateral"),
    ] {
        let centre = m.model().bodies[body.0].mass_centre;
        let moved = m.point(name, Some(centre), vec![(axes, vec3(num(0), y, num(0)))]);
        m.move_mass_centre(body, moved);
    }
}

/// The parameters identification fits for this effect.
const FITTED: &[Fitted] = &[Fitted::plain("y3", 0.01, false)];

/// The effect.
pub fn effect() -> Effect {
    Effect {
        name: "lateral_mass_offset",
        doc: "lateral offsets y3 (rear frame) and y4 (front assembly) of the mass centres",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::SteadyLean],
            reason: "a steady lean and steer bias after the kick: a mass centre off the plane of symmetry (electronics, battery)",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
