//! The generated double pendulum: its registry (`MODELS`, `with_model`) and
//! the type `DoublePendulum`, which implements `bikedyn_runtime::MultibodyModel`.

include!(concat!(env!("OUT_DIR"), "/models.rs"));
