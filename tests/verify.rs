//! Generated derivatives against finite differences of generated primal
//! quantities (issue: verified generated code), through the library and the CLI.

use bikedyn::runtime::verify::VerifyOptions;
use std::process::Command;

#[test]
fn every_generated_derivative_of_every_model_matches_finite_differences() {
    for m in bikedyn::models::MODELS {
        let r = bikedyn::models::verify_model(
            m,
            &VerifyOptions {
                states: 10,
                seed: 7,
                ..Default::default()
            },
        )
        .unwrap();
        for q in &r.quantities {
            println!("{m}: {:<40} {:.3e} (tol {:.0e})", q.name, q.max_rel_error, q.tolerance);
        }
        assert!(
            r.passed,
            "{m} failed verification: {:#?}",
            r.quantities.iter().filter(|q| !q.passed).collect::<Vec<_>>()
        );
        assert_eq!(r.quantities.len(), 13);
    }
}

#[test]
fn cli_verify_json_reports_every_quantity() {
    let out = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args([
            "verify",
            "--model",
            "thesis_whipple",
            "--states",
            "5",
            "--seed",
            "3",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["passed"], true);
    let q = v["quantities"].as_array().unwrap();
    let names: Vec<&str> = q.iter().map(|x| x["name"].as_str().unwrap()).collect();
    for want in [
        "Cq",
        "Ct",
        "dCqdp",
        "B",
        "dBdp",
        "Qv",
        "M symmetric",
        "M positive semi-definite",
    ] {
        assert!(names.contains(&want), "missing {want} in {names:?}");
    }
    for x in q {
        assert!(x["max_rel_error"].as_f64().unwrap() <= x["tolerance"].as_f64().unwrap());
    }
}

#[test]
fn cli_verify_rejects_an_unknown_model() {
    let out = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args(["verify", "--model", "tricycle"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown model `tricycle`"));
}
