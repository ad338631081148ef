//! `bikedyn models`: the generated models, as text or JSON.

use super::text::models_text;
use anyhow::Result;

/// Run `bikedyn models`.
pub fn run(json: bool) -> Result<bool> {
    let ms = bikedyn::models::models();
    if json {
        let v: Vec<_> = ms.iter().map(bikedyn::models::ModelRecord::of).collect();
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        out!("{}", models_text(ms));
    }
    Ok(true)
}
