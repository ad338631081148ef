//! Critical speeds (placeholder while implementing).
use super::*;

/// Critical speeds and all real-part zero crossings in `[v_min, v_max]`.
pub fn critical_speeds(
    c: &CanonicalMatrices,
    v_min: f64,
    v_max: f64,
) -> Result<CriticalSpeeds, EigenError> {
    let _ = (c, v_min, v_max);
    Err(EigenError::NoConvergence { what: "not implemented yet".into() })
}
