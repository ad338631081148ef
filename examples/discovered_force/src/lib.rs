//! The bicycle with the discovered force: its registry (`MODELS`,
//! `with_model`, and `Registry`, the type bikedyn's pipelines take) and the
//! model types `DiscoveredBicycle` and `DiscoveredBicycleFree`.

include!(concat!(env!("OUT_DIR"), "/models.rs"));
