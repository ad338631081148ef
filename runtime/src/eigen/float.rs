//! Floating-point operations of the eigen analysis's inner loops that
//! WebAssembly has no instruction for, written so that there they compile
//! to instructions rather than calls; natively they are the standard
//! library's. [`max`] and [`min`] give the standard library's results on
//! every target; in the browser build [`mul_add`] and [`cbrt`] come within
//! a few units in the last place of them (the browser's numbers stay within
//! 1e-12 of the native build's, `wasm/tests/agreement.mjs`).
//!
//! [`mul_add`]: `a * b + c` with one rounding, as the quartic's accurate
//! steps need it (Kahan's 2x2 determinant, the Ferrari factorisation's
//! residuals). Natively this is `f64::mul_add`: the FMA instruction where
//! the CPU has one, else the C library's correctly rounded `fma`.
//! WebAssembly has no fused multiply-add instruction, so there `mul_add` is
//! a call to the compiler's software `fma` (128-bit integer arithmetic):
//! 11-15 % of the browser's diagram and stability map in a profile
//! (2026-12-01). There the value comes from error-free transformations in
//! plain `f64` arithmetic instead: Dekker's product (`a b = p + e` exactly,
//! Veltkamp's split) and Knuth's sum (`p + c = s + t` exactly), then
//! `s + (t + e)`: the exact `a b + c` rounded twice, at most one unit in the
//! last place from the fused result, and equal to it whenever `t + e` is
//! exact (e.g. the rounding error of a product, as Kahan's determinant asks
//! for). Factors beyond `1e290` (where the split would overflow; far
//! beyond a bicycle's coefficients) are multiplied and added plainly.

/// The larger of `a` and `b`, as `f64::max`: a NaN argument gives the
/// other one, and `+0.0` is larger than `-0.0`. WebAssembly's `f64.max`
/// propagates a NaN, so `f64::max` is a call there (to `fmax`, as is
/// `f64::min` to `fmin`: together 4 % of the browser's stability map in a
/// profile, 2026-12-01); these comparisons are not.
#[inline]
pub(crate) fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else if b > a {
        b
    } else if a.is_nan() {
        b
    } else if b.is_nan() || a.is_sign_positive() {
        a
    } else {
        b
    }
}

/// The smaller of `a` and `b`, as `f64::min` (see [`max`]): a NaN argument
/// gives the other one, and `-0.0` is smaller than `+0.0`.
#[inline]
pub(crate) fn min(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else if b < a {
        b
    } else if a.is_nan() {
        b
    } else if b.is_nan() || a.is_sign_negative() {
        a
    } else {
        b
    }
}

/// `a * b + c`, fused (see the module's doc for WebAssembly).
#[inline]
pub(crate) fn mul_add(a: f64, b: f64, c: f64) -> f64 {
    #[cfg(not(target_arch = "wasm32"))]
    {
        a.mul_add(b, c)
    }
    #[cfg(target_arch = "wasm32")]
    {
        emulated(a, b, c)
    }
}

/// The real cube root of `x`. Natively `f64::cbrt`. In WebAssembly the
/// compiler's correctly rounded `cbrt` makes about twenty software `fma`
/// calls (5 % of the browser's stability map in a profile, 2026-12-01);
/// the resolvent's root it starts is polished by Newton's method on the
/// cubic afterwards, so there it is computed by Halley's iteration from an
/// exponent-third guess instead (within a few units in the last place).
#[inline]
pub(crate) fn cbrt(x: f64) -> f64 {
    #[cfg(not(target_arch = "wasm32"))]
    {
        x.cbrt()
    }
    #[cfg(target_arch = "wasm32")]
    {
        halley_cbrt(x)
    }
}

/// Cube root by three Halley steps, `t <- t (t^3 + 2 a) / (2 t^3 + a)`
/// (cubic convergence: a guess within 7 % is within 1e-15 after three),
/// from the guess that divides the exponent by three (the bit pattern's
/// third, offset so that 1 maps to 1). Signs, zeros, infinities and NaN as
/// `f64::cbrt`; subnormals scaled up by `2^54` and back by `2^-18` first.
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
fn halley_cbrt(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let (a, back) = if x.abs() < f64::MIN_POSITIVE {
        (x.abs() * 2f64.powi(54), 2f64.powi(-18))
    } else {
        (x.abs(), 1.0)
    };
    // 1.0's bit pattern less its third: the guess is exact at powers of 8.
    const OFFSET: u64 = 0x3ff0_0000_0000_0000 - 0x3ff0_0000_0000_0000 / 3;
    let mut t = f64::from_bits(a.to_bits() / 3 + OFFSET);
    for _ in 0..3 {
        let t3 = t * t * t;
        t *= (t3 + 2.0 * a) / (2.0 * t3 + a);
    }
    (t * back).copysign(x)
}

/// Veltkamp's split of `x` into a high part of 26 significant bits and the
/// rest, so that products of parts are exact.
#[inline]
fn split(x: f64) -> (f64, f64) {
    const FACTOR: f64 = 134_217_729.0; // 2^27 + 1
    let t = FACTOR * x;
    let hi = t - (t - x);
    (hi, x - hi)
}

/// `a * b + c` from Dekker's exact product and Knuth's exact sum.
#[inline]
#[cfg_attr(not(target_arch = "wasm32"), allow(dead_code))]
fn emulated(a: f64, b: f64, c: f64) -> f64 {
    let p = a * b;
    if !p.is_finite() || !(a.abs() < 1e290 && b.abs() < 1e290) {
        return p + c;
    }
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    // The product's rounding error: a b = p + e exactly.
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    // p + c = s + t exactly.
    let s = p + c;
    let z = s - p;
    let t = (p - (s - z)) + (c - z);
    s + (t + e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same as the standard library's, NaN and signed zeros included.
    #[test]
    fn max_and_min_are_the_standard_librarys() {
        let xs = [
            f64::NAN,
            -0.0,
            0.0,
            1.0,
            -1.0,
            2.5,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e-300,
        ];
        for &a in &xs {
            for &b in &xs {
                let same = |x: f64, y: f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
                assert!(
                    same(max(a, b), f64::max(a, b)) || (a == 0.0 && b == 0.0 && max(a, b) == 0.0),
                    "max {a} {b}"
                );
                assert!(
                    same(min(a, b), f64::min(a, b)) || (a == 0.0 && b == 0.0 && min(a, b) == 0.0),
                    "min {a} {b}"
                );
            }
        }
        assert!(max(-0.0, 0.0).is_sign_positive() && max(0.0, -0.0).is_sign_positive());
        assert!(min(-0.0, 0.0).is_sign_negative() && min(0.0, -0.0).is_sign_negative());
    }

    /// Within a few units in the last place of the correctly rounded root,
    /// over signs and magnitudes from subnormal to huge.
    #[test]
    fn halleys_cube_root_is_within_a_few_ulps() {
        let mut x: f64 = 3.0e-310;
        while x < 1.0e300 {
            for v in [x, -x, 1.000001 * x, 0.7 * x] {
                let (r, h) = (v.cbrt(), halley_cbrt(v));
                assert!((r - h).abs() <= 4.0 * f64::EPSILON * r.abs(), "{v}: {r} against {h}");
            }
            x *= 3.7;
        }
        for v in [0.0, -0.0, f64::INFINITY, f64::NEG_INFINITY, 8.0, -27.0, 1.0] {
            assert_eq!(halley_cbrt(v).to_bits(), v.cbrt().to_bits(), "{v}");
        }
        assert!(halley_cbrt(f64::NAN).is_nan());
    }

    /// Kahan's use: the rounding error of a product, exactly.
    #[test]
    fn the_emulation_gives_a_products_rounding_error_exactly() {
        let xs = [
            0.1,
            1.0 / 3.0,
            2.0f64.sqrt(),
            9.81,
            -0.3,
            1.0e-7,
            123456.789,
            0.0885,
            -7.5e3,
        ];
        for &a in &xs {
            for &b in &xs {
                let w = a * b;
                assert_eq!(emulated(-a, b, w), (-a).mul_add(b, w), "{a} {b}");
                assert_eq!(emulated(a, b, -w), a.mul_add(b, -w), "{a} {b}");
            }
        }
    }

    /// In general within one unit in the last place of the fused result,
    /// over a spread of magnitudes and signs (a deterministic sequence).
    #[test]
    fn the_emulation_is_within_one_ulp_of_the_fused_multiply_add() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let m = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            let e = ((state & 0x3f) as i32) - 32;
            m * 2f64.powi(e)
        };
        let mut exact = 0;
        for _ in 0..100_000 {
            let (a, b, c) = (next(), next(), next());
            let (f, g) = (a.mul_add(b, c), emulated(a, b, c));
            if f == g {
                exact += 1;
            } else {
                let ulp = f64::EPSILON * f.abs().max(f64::MIN_POSITIVE);
                assert!((f - g).abs() <= ulp, "{a} {b} {c}: {f} against {g}");
            }
        }
        assert!(exact > 99_000, "{exact} of 100000 exact");
    }
}
