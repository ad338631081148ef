//! The hash of the generated files' headers (a model's and its sources'
//! fingerprint), shared by the model, the emitter and the snapshot check.

/// FNV-1a, for the header's model hash (stable across platforms and runs).
pub fn fnv1a(data: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf29ce484222325;
    for b in data {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    h
}
