//! Re-derive bikedyn's models with Symbolica and refresh their committed
//! generated files (`generated/snapshots/`), or check them (`--check`: exit
//! 1 when any committed file differs from what derivation gives; CI runs
//! it, so the committed code can never drift from the model files).
//!
//! Usage: `bikedyn-derive [--check] [--dir DIR]` (default dir: the
//! repository's `generated/snapshots`). Needs the `derive` feature:
//! `cargo run --release -p bikedyn-modeler --features derive --bin bikedyn-derive`.

use bikedyn_modeler::emit::emit;
use bikedyn_modeler::{codegen, derive, models};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut check = false;
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut dir = manifest.parent().unwrap_or(manifest).join("generated/snapshots");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--check" => check = true,
            "--dir" => match args.next() {
                Some(d) => dir = PathBuf::from(d),
                None => return fail("--dir needs a folder"),
            },
            "-h" | "--help" => {
                println!("bikedyn-derive [--check] [--dir DIR]: re-derive the models into DIR (default generated/snapshots), or check that DIR holds what derivation gives");
                return ExitCode::SUCCESS;
            }
            other => {
                return fail(&format!(
                    "unknown argument `{other}` (bikedyn-derive [--check] [--dir DIR])"
                ))
            }
        }
    }
    let models = match models::all() {
        Ok(m) => m,
        Err(e) => return fail(&e.to_string()),
    };
    let _one_symbolica = codegen::symbolica_guard();
    let mut differ = Vec::new();
    for m in &models {
        let emitted = match emit(&derive::derive(m)) {
            Ok(e) => e.source,
            Err(e) => return fail(&format!("model `{}`: {e}", m.name)),
        };
        let path = dir.join(format!("{}.rs", m.name));
        let committed = std::fs::read_to_string(&path).ok();
        if committed.as_deref() == Some(emitted.as_str()) {
            println!("{}: unchanged", path.display());
            continue;
        }
        if check {
            differ.push(path.display().to_string());
            continue;
        }
        if let Err(e) = std::fs::create_dir_all(&dir).and_then(|_| write_atomic(&path, &emitted)) {
            return fail(&format!("{}: {e}", path.display()));
        }
        println!("{}: re-derived", path.display());
    }
    // A committed file of a model that no longer exists is stale too.
    if let Ok(entries) = std::fs::read_dir(&dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().trim_end_matches(".rs").to_string();
            if !models.iter().any(|m| m.name == name) {
                if check {
                    differ.push(format!("{} (no such model)", e.path().display()));
                } else if let Err(err) = std::fs::remove_file(e.path()) {
                    return fail(&format!("{}: {err}", e.path().display()));
                }
            }
        }
    }
    if !differ.is_empty() {
        return fail(&format!(
            "committed generated code differs from derivation:\n  {}\nrun `{}` and commit the diff",
            differ.join("\n  "),
            bikedyn_modeler::snapshot::DERIVE_COMMAND
        ));
    }
    ExitCode::SUCCESS
}

fn write_atomic(path: &std::path::Path, text: &str) -> std::io::Result<()> {
    let tmp = path.with_extension("rs.tmp");
    std::fs::write(&tmp, text)?;
    std::fs::rename(&tmp, path)
}

fn fail(msg: &str) -> ExitCode {
    eprintln!("bikedyn-derive: {msg}");
    ExitCode::FAILURE
}
