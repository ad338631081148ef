//! The generated spring bicycles: their registry (`MODELS`, `with_model`,
//! and `Registry`, the type bikedyn's pipelines take) and the model types
//! `SpringBicycle` and `SpringBicycleFree`.

include!(concat!(env!("OUT_DIR"), "/models.rs"));
