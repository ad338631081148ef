//! The effect library through parameters, models and the CLI: effect
//! parameters in parameter files, model selection,
//! `bikedyn models`, `bikedyn params show`, and the physics of an effect in
//! the linearization.

use crate::common::*;
use bikedyn::bicycle::files::ParameterFile;
use bikedyn::bicycle::{Bicycle, BicycleError};
use bikedyn::generated::{Extended, ThesisWhipple, WhippleOffset};
use bikedyn::models::{default_bicycle, model_names};
use bikedyn::registry::ModelInfo;
use bikedyn_runtime::linearize::{canonical_matrices, lateral_block, linearize_at_speed, parameter_vector};
use bikedyn_runtime::parameters::ThesisParameters;

fn thesis_file_with(extra: &str, name: &str) -> std::path::PathBuf {
    let dir = scratch("effects");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    let text = format!("{}{extra}", ThesisParameters::thesis_bicycle().to_toml_string());
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn built_in_bicycles_have_every_effect_absent() {
    for name in ["thesis", "benchmark"] {
        let b = Bicycle::resolve(name).unwrap();
        let nonzero = b.nonzero_parameters().unwrap();
        for info in bikedyn::models::effect_parameters() {
            assert!(!nonzero.iter().any(|(s, _)| *s == info.name), "{name}: {}", info.name);
            assert_eq!(b.value(info.name), info.default, "{name}: {}", info.name);
        }
    }
    assert_eq!(
        Bicycle::resolve("thesis").unwrap().model(None).unwrap().name,
        "thesis_whipple"
    );
    assert_eq!(
        Bicycle::resolve("benchmark").unwrap().model(None).unwrap().name,
        "whipple_offset"
    );
}

#[test]
fn a_parameter_file_carries_effect_parameters() {
    let path = thesis_file_with("c_steer = 0.25\nCrr_rear = 0.008\n", "damped.toml");
    let b = Bicycle::resolve(path.to_str().unwrap()).unwrap();
    assert_eq!(b.effects.get("c_steer"), Some(&0.25));
    assert_eq!(b.value("Crr_rear"), Some(0.008));
    // The smallest model with those parameters: the thesis model with effects.
    assert_eq!(b.model(None).unwrap().name, "extended");
    // Through a model without them: refused, naming the parameter.
    let err = b.model(Some("thesis_whipple")).unwrap_err();
    assert!(err.to_string().contains("c_steer"), "{err}");
    // The canonical form does not hold with steer damping.
    assert!(matches!(b.canonical(), Err(BicycleError::NotCanonical { .. })));
}

#[test]
fn an_unknown_symbol_names_the_file_and_line() {
    let path = thesis_file_with("c_stear = 0.25\n", "typo.toml");
    let err = Bicycle::resolve(path.to_str().unwrap()).unwrap_err().to_string();
    let line = ThesisParameters::thesis_bicycle().to_toml_string().lines().count() + 1;
    assert!(err.contains("typo.toml"), "{err}");
    assert!(err.contains(&format!("{line}")), "{err}");
    assert!(err.contains("c_stear"), "{err}");
}

/// Steer damping adds `c` to the steer-steer entry of the damping matrix,
/// at every speed, and nothing else.
#[test]
fn steer_damping_adds_its_coefficient_to_the_steer_damping() {
    let p = ThesisParameters::thesis_bicycle();
    let c = canonical_matrices::<ThesisWhipple>(|s| p.get(s)).unwrap();
    let coefficient = 0.37;
    let param =
        parameter_vector::<Extended>(|s| if s == "c_steer" { Some(coefficient) } else { p.get(s) }, 0.0).unwrap();
    for v in [1.0, 4.0, 7.5] {
        let lin = lateral_block::<Extended>(&linearize_at_speed::<Extended>(&param, v).unwrap());
        let want = c.damping(v);
        assert!((lin.damping[(0, 0)] - want[(0, 0)]).abs() < 1e-12);
        assert!(
            (lin.damping[(0, 1)] + want[(0, 1)]).abs() < 1e-12,
            "thesis steer is -delta"
        );
        assert!((lin.damping[(1, 1)] - want[(1, 1)] - coefficient).abs() < 1e-12);
        assert!((lin.stiffness[(1, 1)] - c.stiffness(v)[(1, 1)]).abs() < 1e-10);
    }
}

#[test]
fn with_every_effect_absent_the_extended_model_is_the_whipple_model() {
    // The extended model is the offset geometry: with d4 = 0 (the thesis
    // bicycle) it is the thesis model, with the benchmark's d4 the offset one.
    let thesis = ThesisParameters::thesis_bicycle();
    let bench = default_bicycle(&ModelInfo::of::<Extended>());
    assert!(bench.get("d4").unwrap() != 0.0);
    for (p, a) in [
        (thesis, canonical_matrices::<ThesisWhipple>(|s| thesis.get(s)).unwrap()),
        (bench, canonical_matrices::<WhippleOffset>(|s| bench.get(s)).unwrap()),
    ] {
        let b = canonical_matrices::<Extended>(|s| p.get(s)).unwrap();
        assert!((a.m0 - b.m0).abs().max() < 1e-12);
        assert!((a.c1 - b.c1).abs().max() < 1e-9, "{} {}", a.c1, b.c1);
        assert!((a.k0 - b.k0).abs().max() < 1e-12);
        assert!((a.k2 - b.k2).abs().max() < 1e-9);
    }
}

#[test]
fn models_json_lists_every_registered_model() {
    let out = bikedyn(&["models", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let names: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["name"].as_str().unwrap())
        .collect();
    assert_eq!(names, model_names());
    for m in v.as_array().unwrap() {
        for key in [
            "name",
            "doc",
            "base",
            "free_speed",
            "effects",
            "coordinates",
            "parameters",
            "states",
        ] {
            assert!(!m[key].is_null(), "{key} missing in {m}");
        }
    }
    let ext = v
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "extended_free")
        .unwrap();
    assert_eq!(ext["free_speed"], true);
    assert!(ext["effects"].as_array().unwrap().iter().any(|e| e == "steer_damping"));
}

#[test]
fn params_show_lists_effect_parameters_with_units() {
    let path = thesis_file_with("c_steer = 0.25\n", "show.toml");
    let out = bikedyn(&["params", "show", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("Rt = 0.3199"), "{text}");
    assert!(text.contains("(m)"), "{text}");
    let line = text
        .lines()
        .find(|l| l.starts_with("c_steer = 0.25"))
        .expect("c_steer listed");
    assert!(line.contains("N m s/rad"), "{line}");
    assert!(text.lines().any(|l| l.starts_with("Crr_rear = 0.0")), "{text}");
}

#[test]
fn commands_take_a_model() {
    let out = bikedyn(&[
        "stability",
        "--bike",
        "thesis",
        "--model",
        "thesis_whipple_free",
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let free: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let out = bikedyn(&["stability", "--bike", "thesis", "--json"]);
    let driven: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let (a, b) = (
        free["weave_speed"].as_f64().unwrap(),
        driven["weave_speed"].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    let out = bikedyn(&["canonical", "--bike", "benchmark", "--model", "thesis_whipple"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("d4"));
    let out = bikedyn(&["canonical", "--model", "no_such_model"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("thesis_whipple_free"));
}

/// Tyre slip with relaxation: as the tyres stiffen (cornering stiffness up,
/// relaxation length down) the weave eigenvalue of the tyre model tends to
/// the no-slip model's. A physical check of the effect, its extra states and
/// the state-space linearization.
#[test]
fn stiff_tyres_recover_the_rolling_without_slip_weave() {
    use bikedyn::generated::{ThesisWhippleFree, TyreFree};
    use bikedyn_runtime::linearize::state_space_at_speed;
    use bikedyn_runtime::MultibodyModel;
    let p = ThesisParameters::thesis_bicycle();
    let v = 5.0;
    let c = canonical_matrices::<ThesisWhippleFree>(|s| p.get(s)).unwrap();
    let weave = bikedyn_runtime::eigen::eigenvalues(&c, v)
        .unwrap()
        .into_iter()
        .filter(|z| z.im > 0.0)
        .max_by(|a, b| a.im.total_cmp(&b.im))
        .unwrap();
    assert_eq!(TyreFree::STATES.len(), 2);
    let mut last_err = f64::INFINITY;
    for (ca, sigma) in [(14.0, 0.2), (200.0, 0.02), (3000.0, 0.002)] {
        let param = parameter_vector::<TyreFree>(
            |s| match s {
                "Ca_rear" | "Ca_front" => Some(ca),
                "sigma_rear" | "sigma_front" => Some(sigma),
                _ => p.get(s),
            },
            0.0,
        )
        .unwrap();
        let ss = state_space_at_speed::<TyreFree>(&param, v).unwrap();
        assert_eq!(ss.a.nrows(), 12);
        let schur = nalgebra::linalg::Schur::try_new(ss.a.clone(), 1e-14, 10_000).expect("Schur converges");
        let eig = schur.complex_eigenvalues();
        let near = eig
            .iter()
            .filter(|z| z.im > 0.5)
            .min_by(|a, b| (*a - weave).norm().total_cmp(&(*b - weave).norm()))
            .copied()
            .unwrap();
        let err = (near - weave).norm() / weave.norm();
        println!("C_alpha {ca:>6} /rad, sigma {sigma} m: weave {near:.4} (no slip {weave:.4}), relative difference {err:.2e}");
        assert!(
            err < last_err,
            "the weave approaches the no-slip weave as tyres stiffen"
        );
        last_err = err;
    }
    assert!(
        last_err < 0.02,
        "stiff tyres: weave within 2 % of rolling without slip ({last_err:.3})"
    );
}

/// Each effect file declares what identification needs:
/// an effect without a declaration is never silently skipped, and what a
/// declaration names exists in the models that carry the effect.
#[test]
fn every_effect_declares_its_identification() {
    use bikedyn_runtime::model::EffectIdentification;
    let mut seen = std::collections::BTreeSet::new();
    for m in bikedyn::registry::MODELS {
        assert_eq!(m.effects.len(), m.effect_declarations.len(), "{}", m.name);
        for e in m.effect_declarations {
            seen.insert(e.name);
            let id = e
                .identification
                .unwrap_or_else(|| panic!("{}: effect `{}` declares no identification", m.name, e.name));
            let c = match id {
                EffectIdentification::Candidate(c) => c,
                EffectIdentification::OptOut(why) => {
                    assert!(why.len() > 10, "{}: `{}` opts out without a reason", m.name, e.name);
                    continue;
                }
            };
            assert!(!c.fitted.is_empty() && !c.signatures.is_empty() && !c.reason.is_empty());
            let of_effect = |sym: &str| {
                let p = m
                    .parameter(sym)
                    .unwrap_or_else(|| panic!("{}: `{sym}` of `{}` missing", m.name, e.name));
                assert_eq!(p.effect, Some(e.name), "{}: `{sym}` belongs to another effect", m.name);
            };
            for f in c.fitted {
                of_effect(f.symbol);
                f.tied.iter().for_each(|t| of_effect(t));
                assert!(f.scale > 0.0);
            }
            c.held.iter().for_each(|h| of_effect(h));
        }
    }
    // The whole library is in the registry.
    for name in [
        "steer_damping",
        "steer_friction",
        "rolling_resistance",
        "aero_drag",
        "lateral_mass_offset",
        "steer_controller",
        "tyre_relaxation",
    ] {
        assert!(seen.contains(name), "{name}");
    }
}

/// Effect parameters are physical or refused, naming the file and the
/// field: not a number, negative damping, a zero relaxation length (which
/// would otherwise divide by zero in the tyre law).
#[test]
fn non_physical_effect_parameters_are_refused() {
    for (line, field, why) in [
        ("c_steer = nan\n", "c_steer", "finite"),
        ("c_steer = -0.1\n", "c_steer", "at least 0"),
        ("CdA = -0.3\n", "CdA", "at least 0"),
        ("sigma_rear = 0.0\n", "sigma_rear", "greater than 0"),
        ("w_steer = 0.0\n", "w_steer", "greater than 0"),
    ] {
        let path = thesis_file_with(line, &format!("bad_{field}.toml"));
        let err = Bicycle::resolve(path.to_str().unwrap()).unwrap_err().to_string();
        assert!(
            err.contains(path.to_str().unwrap()) && err.contains(field) && err.contains(why),
            "{line}: {err}"
        );
    }
    // A sweep into non-physical values is refused the same way.
    let b = Bicycle::resolve("thesis").unwrap();
    let err = b.with_parameter("c_steer", -1.0).unwrap_err().to_string();
    assert!(err.contains("c_steer") && err.contains("at least 0"), "{err}");
    assert!(b.with_parameter("c_steer", 0.3).is_ok());
}

/// The linear analysis of a model with extra states:
/// the tyre model's weave and capsize speeds tend to the rolling-without-slip
/// bicycle's as the tyres stiffen, its four roll-steer modes are labelled as
/// every model's, and with the extra modes they make up the whole lateral
/// spectrum but the neutral heading.
#[test]
fn the_tyre_model_has_weave_and_capsize_speeds_that_tend_to_rolling_without_slip() {
    use bikedyn::generated::{ThesisWhippleFree, TyreFree};
    use bikedyn_runtime::eigen::{critical_speeds, critical_speeds_of, eigen_sweep_of, Mode, StateSpaceBicycle};
    use bikedyn_runtime::linearize::LinearModel;
    let p = ThesisParameters::thesis_bicycle();
    let c = canonical_matrices::<ThesisWhippleFree>(|s| p.get(s)).unwrap();
    let no_slip = critical_speeds(&c, 0.0, 10.0).unwrap();
    let (vw0, vc0) = (no_slip.weave_speed.unwrap(), no_slip.capsize_speed.unwrap());
    let mut last = f64::INFINITY;
    for (ca, sigma) in [(14.0, 0.2), (200.0, 0.02), (3000.0, 0.002)] {
        let m = LinearModel::<TyreFree>::new(|s| match s {
            "Ca_rear" | "Ca_front" => Some(ca),
            "sigma_rear" | "sigma_front" => Some(sigma),
            _ => p.get(s),
        })
        .unwrap();
        let r = critical_speeds_of(&m, 0.0, 10.0).unwrap();
        let (vw, vc) = (r.weave_speed.unwrap(), r.capsize_speed.unwrap());
        println!("C_alpha {ca:>6} /rad, sigma {sigma} m: weave speed {vw:.6} (no slip {vw0:.6}), capsize speed {vc:.6} (no slip {vc0:.6})");
        let err = ((vw - vw0) / vw0).abs().max(((vc - vc0) / vc0).abs());
        assert!(
            err < last,
            "the critical speeds approach rolling without slip as tyres stiffen"
        );
        last = err;
        // Labels and the whole spectrum at a speed between the two.
        let sweep = eigen_sweep_of(&m, &[5.0]).unwrap();
        let pt = &sweep.points[0];
        assert_eq!(pt.modes, [Mode::Weave, Mode::Weave, Mode::Capsize, Mode::Castering]);
        let ls = m.lateral_states(5.0).unwrap();
        assert_eq!(ls.neutral, 1, "the heading");
        let mut all: Vec<_> = ls.a.complex_eigenvalues().iter().copied().collect();
        let ours: Vec<_> = pt.eigenvalues.iter().chain(&pt.extra_eigenvalues).copied().collect();
        assert_eq!(ours.len(), all.len() - 1);
        for z in &ours {
            let k = (0..all.len())
                .min_by(|&i, &j| (all[i] - z).norm().total_cmp(&(all[j] - z).norm()))
                .unwrap();
            assert!(
                (all[k] - z).norm() <= 1e-9 * z.norm().max(1.0),
                "{z} is an eigenvalue of A"
            );
            all.remove(k);
        }
        // Zero up to the rounding of the Schur form, about 1e-16 max |A_ij|.
        let rounding = 1e-10 * ls.a.abs().max();
        assert!(
            all[0].norm() < rounding,
            "what is left is the neutral heading, {}",
            all[0]
        );
        // The weave and capsize at 5 m/s: stable, and the castering fast.
        assert!(pt.is_stable(), "{:?}", pt.eigenvalues);
    }
    assert!(
        last < 1e-3,
        "stiff tyres: critical speeds within 0.1 % of rolling without slip ({last:.2e})"
    );
}
