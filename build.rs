//! Writes every model of the modeler's zoo (`bikedyn_modeler::models::all`)
//! and the model registry into OUT_DIR (pulled in by `generated/mod.rs`).
//! Without the `derive` feature the committed files of `generated/snapshots/`
//! are used when their inputs hash matches the model files (no Symbolica in
//! the build); a changed model stops the build with the command that
//! re-derives it. With `--features derive` the models are derived here with
//! Symbolica. Set BIKEDYN_CODEGEN_REPORT=1 to see derivation times and
//! operation counts as cargo warnings.

use std::env;
use std::path::{Path, PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=modeler/src");
    println!("cargo:rerun-if-changed=generated/snapshots");
    println!("cargo:rerun-if-env-changed=BIKEDYN_CODEGEN_REPORT");
    let out_dir = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let snapshots = Path::new(env!("CARGO_MANIFEST_DIR")).join("generated/snapshots");
    let report = env::var("BIKEDYN_CODEGEN_REPORT").is_ok_and(|v| !v.is_empty() && v != "0");
    let models = bikedyn_modeler::models::all().unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    let r = bikedyn_modeler::codegen::build(&models, &snapshots, &out_dir).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1)
    });
    let Some(r) = r.filter(|_| report) else {
        return;
    };
    println!(
        "cargo:warning=code generation: {} models in {:.2} s (budget 30 s)",
        r.models.len(),
        r.total.as_secs_f64()
    );
    for m in &r.models {
        println!(
            "cargo:warning=model {}: derivation {:.2} s, derivation + emission {:.2} s, operations {} before / {} after optimisation",
            m.model,
            m.derivation.as_secs_f64(),
            m.total.as_secs_f64(),
            m.operations_before,
            m.operations_after
        );
        for (name, before, after, tr) in &m.functions {
            println!("cargo:warning=  {name:<28} {before:>9} -> {after:>6} operations ({tr} sin/cos/sqrt/exp)");
        }
    }
}
