//! Adding an effect is writing one file: this fixture is such a file (an
//! effect declared outside the library, a front-hub brake), applied to every
//! bicycle model of the zoo through the same API the library's effects use,
//! then derived and emitted. It is one test function because Symbolica's
//! non-commercial licence allows one Symbolica thread at a time.

use bikedyn_modeler::codegen::generate;
use bikedyn_modeler::effects::{self, BicycleParts, Candidate, Effect, Fitted, Identification, Signature};
use bikedyn_modeler::expr::rate;
use bikedyn_modeler::model::{Force, ModelBuilder};
use bikedyn_modeler::models::thesis_whipple::{self, Speed};
use bikedyn_modeler::models::whipple_offset;

// ---- the whole effect file ----------------------------------------------
fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {
    let c = m.parameter_with_default("c_brake", "front hub brake drag coefficient (N m s/rad)", 0.0);
    m.dissipative_force(Force::Generalized {
        name: "front_brake".into(),
        coordinate: parts.front_wheel_rotation.clone(),
        expr: -(c * rate(&parts.front_wheel_rotation)),
    });
}
const BRAKE_FITTED: &[Fitted] = &[Fitted::plain("c_brake", 0.05, true)];
fn front_brake() -> Effect {
    Effect {
        name: "front_brake",
        doc: "viscous front hub brake, torque -c_brake eps'",
        apply,
        identification: Identification::Candidate(Candidate {
            fitted: BRAKE_FITTED,
            held: &[],
            speed_decay: true,
            signatures: &[Signature::SpeedDecay],
            reason: "the speed falls during the response: a dragging front brake",
            linear_equivalent: None,
            own_model: false,
        }),
    }
}
// --------------------------------------------------------------------------

/// A base model's `declare` with a plain path as its model file.
type Declare = fn(&str, &'static str, Speed) -> (ModelBuilder, BicycleParts);

#[test]
fn a_new_effect_applies_to_every_base_model_and_speed_variant() {
    let mut models = Vec::new();
    for speed in [Speed::Driven, Speed::Free] {
        for (base, declare) in [
            (
                "thesis_whipple",
                (|n, f, s| thesis_whipple::declare(n, f, s)) as Declare,
            ),
            ("whipple_offset", |n, f, s| whipple_offset::declare(n, f, s)),
        ] {
            let name = format!("{base}_{speed:?}_brake").to_lowercase();
            let (mut m, parts) = declare(&name, "modeler/tests/new_effect.rs", speed);
            effects::apply(&mut m, &parts, &front_brake());
            // The library's effects compose with it.
            for e in effects::all() {
                effects::apply(&mut m, &parts, &e);
            }
            let model = m.build().unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(model.free_speed, speed == Speed::Free);
            let brake = model.parameters.iter().find(|p| p.name == "c_brake").unwrap();
            assert_eq!(brake.default, Some(0.0));
            assert_eq!(brake.effect.as_deref(), Some("front_brake"));
            assert!(model.forces.iter().any(|f| f.name() == "front_brake" && f.dissipative));
            assert_eq!(model.effects[0].name, "front_brake");
            models.push(model);
        }
    }
    let out = std::env::temp_dir().join(format!("bikedyn-new-effect-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let report = generate(&models, &out).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(report.models.len(), 4);
    let registry = std::fs::read_to_string(out.join("models.rs")).unwrap();
    for m in &models {
        assert!(
            registry.contains(&format!("\"{}\"", m.name)),
            "registry lists {}",
            m.name
        );
        let src = std::fs::read_to_string(out.join(format!("{}.rs", m.name))).unwrap();
        assert!(src.contains("p_c_brake"), "{} uses the brake parameter", m.name);
        assert!(
            src.contains("name: \"front_brake\""),
            "{} lists the brake force",
            m.name
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
