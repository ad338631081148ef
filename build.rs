//! Derives every model of the modeler's zoo with Symbolica and writes the
//! emitted Rust into OUT_DIR (pulled in by `generated/mod.rs` with `include!`).
//! Set BIKEDYN_CODEGEN_REPORT=1 to see derivation times and operation counts
//! as cargo warnings.

use std::env;
use std::fs;
use std::path::PathBuf;
use std::time::Instant;

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=modeler/src");
    println!("cargo:rerun-if-env-changed=BIKEDYN_CODEGEN_REPORT");
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let report = env::var("BIKEDYN_CODEGEN_REPORT").is_ok_and(|v| !v.is_empty() && v != "0");

    let models = match bikedyn_modeler::models::all() {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(1);
        }
    };
    let mut json = Vec::new();
    for model in &models {
        let start = Instant::now();
        let derived = bikedyn_modeler::derive::derive(model);
        let emitted = match bikedyn_modeler::emit::emit(&derived) {
            Ok(e) => e,
            Err(e) => {
                eprintln!("model `{}`: {e}", model.name);
                std::process::exit(1);
            }
        };
        let total = start.elapsed();
        let path = out_dir.join(format!("{}.rs", model.name));
        fs::write(&path, &emitted.source).unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
        // Totals over the individual functions (all_quantities repeats them).
        let singles = || emitted.reports.iter().filter(|r| r.name != "all_quantities");
        let before: usize = singles().map(|r| r.before.total()).sum();
        let after: usize = singles().map(|r| r.after.total()).sum();
        if report {
            println!(
                "cargo:warning=model {}: derivation {:.2} s, derivation + emission {:.2} s, operations {} before / {} after optimisation",
                model.name,
                derived.elapsed.as_secs_f64(),
                total.as_secs_f64(),
                before,
                after
            );
            for r in &emitted.reports {
                println!(
                    "cargo:warning=  {:<28} {:>9} -> {:>6} operations ({} sin/cos/sqrt)",
                    r.name,
                    r.before.total(),
                    r.after.total(),
                    r.after.transcendental
                );
            }
        }
        let functions: Vec<String> = emitted
            .reports
            .iter()
            .map(|r| {
                format!(
                    "{{\"name\":\"{}\",\"operations_before\":{},\"operations_after\":{}}}",
                    r.name,
                    r.before.total(),
                    r.after.total()
                )
            })
            .collect();
        json.push(format!(
            "{{\"model\":\"{}\",\"derivation_s\":{},\"derivation_and_emission_s\":{},\"operations_before\":{},\"operations_after\":{},\"functions\":[{}]}}",
            model.name,
            derived.elapsed.as_secs_f64(),
            total.as_secs_f64(),
            before,
            after,
            functions.join(",")
        ));
    }
    let path = out_dir.join("codegen_report.json");
    fs::write(&path, format!("[{}]\n", json.join(","))).unwrap_or_else(|e| panic!("writing {}: {e}", path.display()));
}
