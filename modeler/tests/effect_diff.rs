//! Generated code diffs like the change: adding one effect to a model
//! changes the emitted file in proportion to what the effect adds. The
//! effect is the steering-spring example's (`examples/steering_spring`), a
//! 20-line file; the model is `extended`, the library's largest. Before
//! temporaries were named by content, this one effect renumbered nearly
//! every line of the file. One test function: Symbolica's non-commercial
//! licence allows one Symbolica thread at a time.

use bikedyn_modeler::codegen::generate;
use bikedyn_modeler::effects::{self, BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use bikedyn_modeler::expr::coord;
use bikedyn_modeler::model::{Force, Model, ModelBuilder};
use bikedyn_modeler::models::thesis_whipple::Speed;
use bikedyn_modeler::models::whipple_offset;
use similar::{ChangeTag, TextDiff};

// ---- the steering-spring example's effect ----------------------------------
fn apply_steering_spring(m: &mut ModelBuilder, parts: &BicycleParts) {
    let k = m.parameter_with_default(
        "k_spring",
        "steering return spring stiffness about the steer axis (N m/rad)",
        0.0,
    );
    m.lower_bound("k_spring", 0.0, false);
    m.force(Force::Generalized {
        name: "steering_spring".into(),
        coordinate: parts.steer.clone(),
        expr: -(k * coord(&parts.steer)),
    });
}
const FITTED: &[Fitted] = &[Fitted::plain("k_spring", 1.0, false)];
fn steering_spring() -> Effect {
    Effect {
        name: "steering_spring",
        doc: "steering return spring between fork and frame, torque -k_spring gamma",
        apply: apply_steering_spring,
        identification: Identification::Candidate(Candidate {
            fitted: FITTED,
            held: &[],
            speed_decay: false,
            signatures: &[Signature::FrequencyShiftWithSpeed],
            reason: "a weave frequency error that changes with speed",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
// -----------------------------------------------------------------------------

/// `extended` as its model file declares it (every library effect on the
/// offset geometry, driven speed), with the spring added last or not at all.
fn extended(with_spring: bool) -> Model {
    let (mut m, parts) = whipple_offset::declare("extended", "modeler/tests/effect_diff.rs", Speed::Driven);
    for e in effects::all() {
        effects::apply(&mut m, &parts, &e);
    }
    if with_spring {
        effects::apply(&mut m, &parts, &steering_spring());
    }
    m.build().unwrap_or_else(|e| panic!("{e}"))
}

fn emitted(model: Model, tag: &str) -> String {
    let out = std::env::temp_dir().join(format!("bikedyn-effect-diff-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    generate(&[model], &out).unwrap_or_else(|e| panic!("{e}"));
    let text = std::fs::read_to_string(out.join("extended.rs")).unwrap();
    std::fs::remove_dir_all(&out).ok();
    text
}

#[test]
fn adding_the_steering_spring_to_extended_changes_under_ten_percent_of_its_lines() {
    let before = emitted(extended(false), "before");
    let after = emitted(extended(true), "after");
    assert!(!before.contains("p_k_spring"));
    assert!(
        after.contains("let p_k_spring = param["),
        "the spring's stiffness is read"
    );
    let diff = TextDiff::from_lines(&before, &after);
    let (mut added, mut removed) = (0usize, 0usize);
    for change in diff.iter_all_changes() {
        match change.tag() {
            ChangeTag::Insert => added += 1,
            ChangeTag::Delete => removed += 1,
            ChangeTag::Equal => {}
        }
    }
    let lines = before.lines().count();
    let changed = (added + removed) as f64 / lines as f64;
    println!(
        "extended: {lines} lines; adding the steering spring adds {added} and removes {removed} ({:.2} % of the lines)",
        100.0 * changed
    );
    assert!(added > 0, "the spring's torque is emitted");
    assert!(changed < 0.10, "{:.1} % of the lines changed", 100.0 * changed);
}
