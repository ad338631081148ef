//! One result schema for identification from runs and from an eigenvalue
//! table: the JSON of both is the serialization of the same types
//! (`src/identify/result.rs`), its shape is committed in
//! `tests/data/identify_schema.json`, and the parts they share have the
//! same keys.
//!
//! The shape is every path of the JSON (object keys joined by `.`, array
//! elements as `[]`, the symbols of `parameters` as `*`) with the JSON
//! types seen there (`null|number`: a value that may be absent); a tagged
//! enum's keys depend on its variant and are left out. A change of the schema fails here until the committed
//! shape is rewritten: `BIKEDYN_BLESS=1 cargo test --release --test
//! behaviour -- result_schema`, and the diff of that file is the schema's
//! change for review.

use crate::common::*;
use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, BTreeSet};

type Shape = BTreeMap<String, BTreeSet<&'static str>>;

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "boolean",
        Value::Number(_) => "number",
        Value::String(_) => "string",
        Value::Array(_) => "array",
        Value::Object(_) => "object",
    }
}

/// Objects whose keys are data (symbols), not schema.
const MAPS: [&str; 1] = ["parameters"];

/// Tagged enums (a verdict's `kind`, a discovery's `status`): their keys
/// depend on which variant the data gave, so only their type is part of
/// the shape (the variants are the types' own, in `Verdict` and
/// `DiscoveryOutcome`).
const VARIANTS: [&str; 4] = [
    "candidates[].outcome",
    "final_check[].outcome",
    "discovery",
    "time_series_discovery",
];

fn shape_into(v: &Value, path: &str, out: &mut Shape) {
    out.entry(path.to_string()).or_default().insert(kind(v));
    if VARIANTS.contains(&path) {
        return;
    }
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if MAPS.contains(&path) { "*" } else { k.as_str() };
                let p = if path.is_empty() {
                    key.to_string()
                } else {
                    format!("{path}.{key}")
                };
                shape_into(x, &p, out);
            }
        }
        Value::Array(a) => {
            for x in a {
                shape_into(x, &format!("{path}[]"), out);
            }
        }
        _ => {}
    }
}

fn shape(v: &Value) -> Shape {
    let mut s = Shape::new();
    shape_into(v, "", &mut s);
    s.remove("");
    s
}

/// The keys of the object at `path` (objects of an array merged).
fn keys_at(s: &Shape, path: &str) -> BTreeSet<String> {
    let prefix = format!("{path}.");
    s.keys()
        .filter_map(|k| k.strip_prefix(&prefix))
        .map(|k| k.split(['.', '[']).next().unwrap().to_string())
        .collect()
}

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

fn as_json(s: &Shape) -> Value {
    Value::Object(
        s.iter()
            .map(|(k, t)| (k.clone(), json!(t.iter().copied().collect::<Vec<_>>().join("|"))))
            .collect::<Map<_, _>>(),
    )
}

#[test]
fn runs_and_tables_are_identified_into_one_committed_schema() {
    let runs = runs_result();
    let table = table_result();
    assert_eq!(runs["source"], "runs");
    assert_eq!(table["source"], "eigenvalue_table");
    let (r, t) = (shape(&runs), shape(&table));
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
    let committed_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/identify_schema.json");
    let observed = json!({ "runs": as_json(&r), "eigenvalue_table": as_json(&t) });
    if std::env::var_os("BIKEDYN_BLESS").is_some() {
        std::fs::write(&committed_path, serde_json::to_string_pretty(&observed).unwrap() + "\n").unwrap();
        return;
    }
    let committed: Value = serde_json::from_str(&std::fs::read_to_string(&committed_path).unwrap()).unwrap();
    for source in ["runs", "eigenvalue_table"] {
        let (want, got) = (&committed[source], &observed[source]);
        let want = want.as_object().unwrap();
        let got = got.as_object().unwrap();
        let missing: Vec<&String> = want.keys().filter(|k| !got.contains_key(*k)).collect();
        let added: Vec<&String> = got.keys().filter(|k| !want.contains_key(*k)).collect();
        let retyped: Vec<String> = want
            .iter()
            .filter_map(|(k, w)| got.get(k).filter(|g| *g != w).map(|g| format!("{k}: {w} -> {g}")))
            .collect();
        assert!(
            missing.is_empty() && added.is_empty() && retyped.is_empty(),
            "{source}: the JSON's shape differs from tests/data/identify_schema.json (rewrite it with BIKEDYN_BLESS=1 if the change is meant)\nmissing: {missing:?}\nadded: {added:?}\nretyped: {retyped:?}"
        );
    }
}
