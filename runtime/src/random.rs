//! The one seeded random generator of bikedyn: SplitMix64 (Steele, Lea and
//! Flood 2014, with the constants of Vigna's reference `splitmix64.c`).
//!
//! Every seeded draw goes through it: run plans and hand disturbances of
//! `bikedyn synth`, sensor errors and clock offsets of synthetic runs, the
//! random states of `bikedyn verify`, the random designs of the tests. A
//! seed therefore fixes every output, and the committed example set
//! (`examples/data/hidden_steer_damping`) is made again byte for byte from
//! its seed. Own code rather than `rand`: a dozen lines, and the sequence is
//! fixed here (`rand`'s `StdRng` does not promise a stable algorithm across
//! versions).

/// SplitMix64: a 64-bit state advanced by the golden-ratio increment and
/// mixed into each output. Not for cryptography; enough for reproducible
/// test cases and synthetic noise.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// The state increment, `2^64 / phi` rounded to odd.
    pub const GAMMA: u64 = 0x9E37_79B9_7F4A_7C15;

    /// A generator whose state is `state` (the seed, used as is: the first
    /// output is the mix of `state + GAMMA`).
    pub fn new(state: u64) -> Self {
        SplitMix64 { state }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(Self::GAMMA);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 53 bits of [`Self::next_u64`] over `2^53`
    /// (every value a multiple of `2^-53`, exactly representable).
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi): `lo + (hi - lo) u` with `u` from
    /// [`Self::next_f64`].
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }

    /// Standard normal deviate by Box-Muller (the cosine branch; two
    /// uniforms per deviate, the first kept away from 0 so its log is
    /// finite).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.next_f64().max(1e-300);
        let u2 = self.next_f64();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first outputs from state 0 are those of Vigna's reference
    /// `splitmix64.c` (seeded with `x = 0`), so the sequence every seeded
    /// output in the repository was made with stays the same.
    #[test]
    fn matches_the_reference_sequence() {
        let mut g = SplitMix64::new(0);
        let want = [
            0xE220_A839_7B1D_CDAF,
            0x6E78_9E6A_A1B9_65F4,
            0x06C4_5D18_8009_454F,
            0xF88B_B8A8_724C_81EC,
        ];
        for w in want {
            assert_eq!(g.next_u64(), w);
        }
    }

    /// `next_f64` keeps the top 53 bits: 0xE220A8397B1DCDAF >> 11 over 2^53.
    #[test]
    fn maps_the_top_53_bits_to_the_unit_interval() {
        let mut g = SplitMix64::new(0);
        assert_eq!(
            g.next_f64(),
            (0xE220_A839_7B1D_CDAFu64 >> 11) as f64 / 9_007_199_254_740_992.0
        );
        assert_eq!(g.next_f64(), 0.43152799704850997);
        let mut h = SplitMix64::new(0);
        h.next_u64();
        h.next_u64();
        assert_eq!(
            h.uniform(-1.0, 3.0),
            -1.0 + 4.0 * (0x06C4_5D18_8009_454Fu64 >> 11) as f64 / 9_007_199_254_740_992.0
        );
    }

    /// A normal deviate uses two uniforms, and over many draws has mean 0 and
    /// variance 1 (to 4 standard errors: 4 / sqrt(n) for the mean, about
    /// 4 sqrt(2 / n) for the variance).
    #[test]
    fn normal_deviates_are_standard() {
        let mut g = SplitMix64::new(7);
        let mut h = g.clone();
        let x = g.normal();
        let (u1, u2) = (h.next_f64(), h.next_f64());
        assert_eq!(x, (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos());
        assert_eq!(g, h);
        let n = 100_000;
        let v: Vec<f64> = (0..n).map(|_| g.normal()).collect();
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!(mean.abs() < 4.0 / (n as f64).sqrt(), "mean {mean}");
        assert!((var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(), "variance {var}");
    }
}
