//! `bikedyn models`: the generated models, as text or JSON.

use super::text::models_text;
use anyhow::Result;

/// Run `bikedyn models`.
pub fn run(json: bool) -> Result<bool> {
    let ms = bikedyn::models::models();
    if json {
        let v: Vec<_> = ms.iter().map(bikedyn::models::model_json).collect();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print!("{}", models_text(ms));
    }
    Ok(true)
}
