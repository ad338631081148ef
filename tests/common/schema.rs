//! The shape of a JSON result, and its check against a committed file (the
//! result schema tests of `identify` and `fit`).
//!
//! The shape is every path of the JSON (object keys joined by `.`, array
//! elements as `[]`, the keys of an object whose keys are data as `*`)
//! with the JSON types seen there (`null|number`: a value that may be
//! absent). A tagged enum's keys depend on its variant, so at its path
//! only the type is kept. A change of a schema fails its test until the
//! committed shape is rewritten: `BIKEDYN_BLESS=1 cargo test --release
//! --test behaviour -- result_schema`, and the diff of that file is the
//! schema's change for review.

use serde_json::{json, Map, Value};
use std::collections::{BTreeMap, BTreeSet};

/// Each path of a JSON value and the JSON types seen there.
pub type Shape = BTreeMap<String, BTreeSet<&'static str>>;

/// Where a result's keys are not its schema.
pub struct Paths {
    /// Objects whose keys are data (symbols), not schema.
    pub maps: &'static [&'static str],
    /// Tagged enums: their keys depend on the variant the data gave.
    pub variants: &'static [&'static str],
}

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

fn shape_into(v: &Value, path: &str, paths: &Paths, out: &mut Shape) {
    out.entry(path.to_string()).or_default().insert(kind(v));
    if paths.variants.contains(&path) {
        return;
    }
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let key = if paths.maps.contains(&path) { "*" } else { k.as_str() };
                let p = if path.is_empty() {
                    key.to_string()
                } else {
                    format!("{path}.{key}")
                };
                shape_into(x, &p, paths, out);
            }
        }
        Value::Array(a) => {
            for x in a {
                shape_into(x, &format!("{path}[]"), paths, out);
            }
        }
        _ => {}
    }
}

/// The shape of `v`.
pub fn shape(v: &Value, paths: &Paths) -> Shape {
    let mut s = Shape::new();
    shape_into(v, "", paths, &mut s);
    s.remove("");
    s
}

/// The keys of the object at `path` (objects of an array merged).
pub fn keys_at(s: &Shape, path: &str) -> BTreeSet<String> {
    let prefix = format!("{path}.");
    s.keys()
        .filter_map(|k| k.strip_prefix(&prefix))
        .map(|k| k.split(['.', '[']).next().unwrap().to_string())
        .collect()
}

fn as_json(s: &Shape) -> Value {
    Value::Object(
        s.iter()
            .map(|(k, t)| (k.clone(), json!(t.iter().copied().collect::<Vec<_>>().join("|"))))
            .collect::<Map<_, _>>(),
    )
}

/// Compare the shapes of `sources` (name, shape) with the committed file
/// `tests/data/<file>` (one object per source), or rewrite it with
/// `BIKEDYN_BLESS` set.
pub fn check_committed(file: &str, sources: &[(&str, &Shape)]) {
    let committed_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(file);
    let observed = Value::Object(
        sources
            .iter()
            .map(|(name, s)| (name.to_string(), as_json(s)))
            .collect::<Map<_, _>>(),
    );
    if std::env::var_os("BIKEDYN_BLESS").is_some() {
        std::fs::write(&committed_path, serde_json::to_string_pretty(&observed).unwrap() + "\n").unwrap();
        return;
    }
    let committed: Value = serde_json::from_str(&std::fs::read_to_string(&committed_path).unwrap()).unwrap();
    for (source, _) in sources {
        let (want, got) = (&committed[*source], &observed[*source]);
        let want = want
            .as_object()
            .unwrap_or_else(|| panic!("tests/data/{file} has no `{source}`"));
        let got = got.as_object().unwrap();
        let missing: Vec<&String> = want.keys().filter(|k| !got.contains_key(*k)).collect();
        let added: Vec<&String> = got.keys().filter(|k| !want.contains_key(*k)).collect();
        let retyped: Vec<String> = want
            .iter()
            .filter_map(|(k, w)| got.get(k).filter(|g| *g != w).map(|g| format!("{k}: {w} -> {g}")))
            .collect();
        assert!(
            missing.is_empty() && added.is_empty() && retyped.is_empty(),
            "{source}: the JSON's shape differs from tests/data/{file} (rewrite it with BIKEDYN_BLESS=1 if the change is meant)\nmissing: {missing:?}\nadded: {added:?}\nretyped: {retyped:?}"
        );
    }
}
