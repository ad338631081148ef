//! One result schema for identification from runs and from an eigenvalue
//! table: the JSON of both is the serialization of the same types
//! (`src/identify/result.rs`), its shape is committed in
//! `tests/data/identify_schema.json`, and the parts they share have the
//! same keys.
//!
//! The shape (`crate::common::schema`) is every path of the JSON with the
//! JSON types seen there, the symbols of `parameters` as `*`; a tagged
//! enum's keys depend on its variant and are left out. A change of the
//! schema fails here until the committed shape is rewritten:
//! `BIKEDYN_BLESS=1 cargo test --release --test behaviour --
//! result_schema`, and the diff of that file is the schema's change for
//! review.

use crate::common::schema::{check_committed, keys_at, shape, Paths, Shape};
use crate::common::*;
use serde_json::Value;
use std::collections::BTreeSet;

/// The identification result's paths whose keys are not schema.
const PATHS: Paths = Paths {
    // Objects whose keys are data (symbols), not schema.
    maps: &["parameters"],
    // Tagged enums (a verdict's `kind`, a discovery's `status`): their keys
    // depend on which variant the data gave, so only their type is part of
    // the shape (the variants are the types' own, in `Verdict` and
    // `DiscoveryOutcome`).
    variants: &[
        "candidates[].outcome",
        "final_check[].outcome",
        "discovery",
        "time_series_discovery",
    ],
};

fn runs_result() -> Value {
    let set = example_set();
    ok_json(&[
        "identify",
        set.to_str().unwrap(),
        "--effects",
        "steer_damping,aero_drag",
        "--corrections",
        "0",
        "--json",
    ])
}

fn table_result() -> Value {
    let path = super::eigenvalue_tables::weave_table("schema", Some(0.3), "3:7:0.5", "speed,re,im,sd_re,sd_im");
    ok_json(&[
        "identify",
        "--eigenvalues",
        path.to_str().unwrap(),
        "--bike",
        "thesis",
        "--json",
    ])
}

#[test]
fn runs_and_tables_are_identified_into_one_committed_schema() {
    let runs = runs_result();
    let table = table_result();
    assert_eq!(runs["source"], "runs");
    assert_eq!(table["source"], "eigenvalue_table");
    let (r, t) = (shape(&runs, &PATHS), shape(&table, &PATHS));
    // What both have, they have alike: the same keys in the selection's
    // parameters, the candidates and the errors at both stages.
    let shared = [
        "",
        "parameters.*",
        "candidates[]",
        "error_before",
        "error_after",
        "error_before.held_out",
        "error_after.held_out",
    ];
    let top = |s: &Shape| -> BTreeSet<String> {
        s.keys()
            .map(|k| k.split(['.', '[']).next().unwrap().to_string())
            .collect()
    };
    for path in shared {
        let (a, b) = if path.is_empty() {
            (top(&r), top(&t))
        } else {
            (keys_at(&r, path), keys_at(&t, path))
        };
        if path.is_empty() {
            let common = [
                "source",
                "selected_effects",
                "parameters",
                "candidates",
                "error_before",
                "error_after",
                "driven_model",
                "remaining",
                "discovery",
            ];
            for k in common {
                assert!(a.contains(k) && b.contains(k), "{k}: runs {a:?}, table {b:?}");
            }
        } else {
            assert!(!a.is_empty(), "runs have nothing at {path}");
            assert_eq!(a, b, "keys at {path}: runs against table");
        }
    }
    check_committed("identify_schema.json", &[("runs", &r), ("eigenvalue_table", &t)]);
}
