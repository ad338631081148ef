//! The committed copies in `generated/snapshots/` must equal what build.rs
//! writes, so that a model change shows up as a readable diff in review.
//! Without the `derive` feature build.rs takes them as they are (when their
//! inputs hash matches); with `--features derive` this compares them with
//! fresh derivations. `bikedyn-derive --check` (CI) does the same without
//! building bikedyn; `bikedyn-derive` or `UPDATE_SNAPSHOTS=1 cargo test
//! --features derive --test behaviour snapshots` refreshes them.

use std::path::Path;

#[test]
fn generated_snapshots_are_fresh() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("generated/snapshots");
    let update = std::env::var("UPDATE_SNAPSHOTS").is_ok_and(|v| v == "1");
    let mut stale = Vec::new();
    for (name, emitted) in bikedyn::generated::SOURCES {
        let path = dir.join(format!("{name}.rs"));
        if update {
            std::fs::create_dir_all(&dir).unwrap();
            std::fs::write(&path, emitted).unwrap();
            continue;
        }
        match std::fs::read_to_string(&path) {
            Ok(committed) if committed == *emitted => {}
            Ok(committed) => {
                let line = committed
                    .lines()
                    .zip(emitted.lines())
                    .position(|(a, b)| a != b)
                    .map(|i| i + 1);
                stale.push(format!(
                    "{} differs from the emitted code (first difference at line {:?})",
                    path.display(),
                    line
                ));
            }
            Err(e) => stale.push(format!("{} cannot be read: {e}", path.display())),
        }
    }
    // A snapshot of a model that is no longer generated is stale too.
    if let Ok(entries) = std::fs::read_dir(&dir) {
        for e in entries.flatten() {
            let name = e.file_name().to_string_lossy().trim_end_matches(".rs").to_string();
            if !bikedyn::generated::SOURCES.iter().any(|(n, _)| *n == name) {
                if update {
                    std::fs::remove_file(e.path()).unwrap();
                } else {
                    stale.push(format!("{} has no generated model", e.path().display()));
                }
            }
        }
    }
    assert!(
        stale.is_empty(),
        "stale generated snapshots:\n  {}\nrun `UPDATE_SNAPSHOTS=1 cargo test --test behaviour snapshots` and review the diff",
        stale.join("\n  ")
    );
}

#[test]
fn snapshots_have_a_header_naming_model_sources_and_hash() {
    for (name, emitted) in bikedyn::generated::SOURCES {
        let first = emitted.lines().next().unwrap();
        assert!(first.starts_with("// @generated"), "{name}: {first}");
        assert!(first.contains(&format!("model \"{name}\"")), "{name}: {first}");
        assert!(first.contains("modeler/src/models/"), "{name}: {first}");
        assert!(first.contains("model hash"), "{name}: {first}");
        assert!(first.contains("inputs hash"), "{name}: {first}");
    }
}
