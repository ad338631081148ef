//! Scalars that flow through generated code.
//!
//! The emitted model functions are generic over [`Scalar`], so the same code
//! evaluates plain `f64` values (fast path, monomorphised) and forward-mode
//! [`Dual`] numbers, which carry exact first derivatives. We chose dual numbers
//! over emitting separate derivative code: the linearization needs derivatives
//! *through* the constraint solution and the coordinate partitioning
//! (E = -D_dep^-1 D_ind, F, ...), which no single emitted function covers, and
//! duals give them exactly (to rounding) with no extra generated code.

use std::fmt::Debug;
use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// Arithmetic needed by generated model code and the runtime's linear algebra.
pub trait Scalar:
    Copy
    + Debug
    + PartialEq
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
{
    /// A constant (zero derivative).
    fn cst(x: f64) -> Self;
    /// The real (primal) part.
    fn re(self) -> f64;
    fn sin(self) -> Self;
    fn cos(self) -> Self;
    fn sqrt(self) -> Self;
    fn exp(self) -> Self;
    fn acos(self) -> Self;
    fn atan(self) -> Self;
    fn powi(self, n: i32) -> Self;
    /// `(sin, cos)` in one call (generated code pairs them).
    fn sin_cos(self) -> (Self, Self);
    #[inline]
    fn zero() -> Self {
        Self::cst(0.0)
    }
    #[inline]
    fn one() -> Self {
        Self::cst(1.0)
    }
}

impl Scalar for f64 {
    #[inline]
    fn cst(x: f64) -> Self {
        x
    }
    #[inline]
    fn re(self) -> f64 {
        self
    }
    #[inline]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline]
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    #[inline]
    fn exp(self) -> Self {
        f64::exp(self)
    }
    #[inline]
    fn acos(self) -> Self {
        f64::acos(self)
    }
    #[inline]
    fn atan(self) -> Self {
        f64::atan(self)
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        f64::powi(self, n)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
    }
}

/// Forward-mode dual number with `N` derivative directions:
/// `re + sum_k eps[k] * e_k`, with `e_j e_k = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const N: usize> {
    /// Value.
    pub re: f64,
    /// Partial derivatives along the `N` seeded directions.
    pub eps: [f64; N],
}

impl<const N: usize> Dual<N> {
    /// A variable seeded along direction `k`.
    pub fn variable(re: f64, k: usize) -> Self {
        let mut eps = [0.0; N];
        eps[k] = 1.0;
        Dual { re, eps }
    }
    #[inline]
    fn chain(self, f: f64, df: f64) -> Self {
        Dual {
            re: f,
            eps: lanes::scale(&self.eps, df),
        }
    }
}

/// The derivative parts two directions at a time.
///
/// Without LLVM's SLP vectorizer (the root package is built at opt-level 2,
/// see `Cargo.toml`), nothing would pair the unrolled per-direction
/// operations into SSE2 instructions, so the pairing is written out here:
/// each operation loads two directions as one `__m128d`, and an odd `N` does
/// its last direction in scalar. Every direction gets the same IEEE
/// operations in the same order as the scalar loop of the portable version,
/// so the results are identical bit for bit.
#[cfg(target_arch = "x86_64")]
mod lanes {
    use core::arch::x86_64::{__m128d, _mm_add_pd, _mm_loadu_pd, _mm_mul_pd, _mm_set1_pd, _mm_storeu_pd, _mm_sub_pd};

    /// `out[k] = f2(a[2k..2k+2])` per pair of directions, `f1(k)` for the
    /// last one of an odd `N`.
    #[inline(always)]
    fn pairs<const N: usize>(f2: impl Fn(usize) -> __m128d, f1: impl Fn(usize) -> f64) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N / 2 {
            // SAFETY: SSE2 is part of the x86_64 baseline; `2 k + 1 < N`.
            unsafe { _mm_storeu_pd(out.as_mut_ptr().add(2 * k), f2(k)) };
        }
        if N % 2 == 1 {
            out[N - 1] = f1(N - 1);
        }
        out
    }

    #[inline(always)]
    fn ld<const N: usize>(a: &[f64; N], k: usize) -> __m128d {
        debug_assert!(2 * k + 1 < N);
        // SAFETY: SSE2 is part of the x86_64 baseline; callers pass `2 k + 1 < N`.
        unsafe { _mm_loadu_pd(a.as_ptr().add(2 * k)) }
    }

    /// `a + b`.
    #[inline]
    pub(super) fn add<const N: usize>(a: &[f64; N], b: &[f64; N]) -> [f64; N] {
        // SAFETY (all intrinsics below): SSE2 is part of the x86_64 baseline.
        pairs(|k| unsafe { _mm_add_pd(ld(a, k), ld(b, k)) }, |k| a[k] + b[k])
    }
    /// `a - b`.
    #[inline]
    pub(super) fn sub<const N: usize>(a: &[f64; N], b: &[f64; N]) -> [f64; N] {
        pairs(|k| unsafe { _mm_sub_pd(ld(a, k), ld(b, k)) }, |k| a[k] - b[k])
    }
    /// `a s`.
    #[inline]
    pub(super) fn scale<const N: usize>(a: &[f64; N], s: f64) -> [f64; N] {
        let sv = unsafe { _mm_set1_pd(s) };
        pairs(|k| unsafe { _mm_mul_pd(ld(a, k), sv) }, |k| a[k] * s)
    }
    /// `a sb + sa b`, the product rule.
    #[inline]
    pub(super) fn product<const N: usize>(a: &[f64; N], sb: f64, sa: f64, b: &[f64; N]) -> [f64; N] {
        let (sbv, sav) = unsafe { (_mm_set1_pd(sb), _mm_set1_pd(sa)) };
        pairs(
            |k| unsafe { _mm_add_pd(_mm_mul_pd(ld(a, k), sbv), _mm_mul_pd(sav, ld(b, k))) },
            |k| a[k] * sb + sa * b[k],
        )
    }
    /// `(a - q b) inv`, the quotient rule with `q` the quotient and `inv`
    /// the divisor's reciprocal.
    #[inline]
    pub(super) fn quotient<const N: usize>(a: &[f64; N], q: f64, b: &[f64; N], inv: f64) -> [f64; N] {
        let (qv, iv) = unsafe { (_mm_set1_pd(q), _mm_set1_pd(inv)) };
        pairs(
            |k| unsafe { _mm_mul_pd(_mm_sub_pd(ld(a, k), _mm_mul_pd(qv, ld(b, k))), iv) },
            |k| (a[k] - q * b[k]) * inv,
        )
    }
}

/// The derivative parts one direction at a time: the lanes of other
/// architectures, and the reference the `x86_64` lanes are tested against.
#[cfg(not(target_arch = "x86_64"))]
use portable as lanes;

// Written as loops over an array filled in place rather than with
// `std::array::from_fn`: the browser's build compiles the crate that
// instantiates them for size (`wasm/build.sh`), where `from_fn` stayed a
// call per direction through its closure machinery (with the operations'
// own calls, a fifth of the browser's stability map in a profile,
// 2026-12-02). The same operations in the same order, so the same numbers.
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
mod portable {
    #[inline]
    pub(super) fn add<const N: usize>(a: &[f64; N], b: &[f64; N]) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N {
            out[k] = a[k] + b[k];
        }
        out
    }
    #[inline]
    pub(super) fn sub<const N: usize>(a: &[f64; N], b: &[f64; N]) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N {
            out[k] = a[k] - b[k];
        }
        out
    }
    #[inline]
    pub(super) fn scale<const N: usize>(a: &[f64; N], s: f64) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N {
            out[k] = a[k] * s;
        }
        out
    }
    #[inline]
    pub(super) fn product<const N: usize>(a: &[f64; N], sb: f64, sa: f64, b: &[f64; N]) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N {
            out[k] = a[k] * sb + sa * b[k];
        }
        out
    }
    #[inline]
    pub(super) fn quotient<const N: usize>(a: &[f64; N], q: f64, b: &[f64; N], inv: f64) -> [f64; N] {
        let mut out = [0.0; N];
        for k in 0..N {
            out[k] = (a[k] - q * b[k]) * inv;
        }
        out
    }
}

// The operations are `#[inline]`, not `#[inline(always)]`: LLVM's
// always-inliner runs before each callee is simplified, so forced inlining
// pasted the per-direction loops, not yet unrolled, into the generated
// functions (tens of thousands of tiny loops in one function, which the loop
// passes then took minutes over). Plain `#[inline]` lets the callee be
// unrolled first; the generated code then inlines it all the same.
impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Dual {
            re: self.re + o.re,
            eps: lanes::add(&self.eps, &o.eps),
        }
    }
}
impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Dual {
            re: self.re - o.re,
            eps: lanes::sub(&self.eps, &o.eps),
        }
    }
}
impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Dual {
            re: self.re * o.re,
            eps: lanes::product(&self.eps, o.re, self.re, &o.eps),
        }
    }
}
impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.re;
        let re = self.re * inv;
        Dual {
            re,
            eps: lanes::quotient(&self.eps, re, &o.eps, inv),
        }
    }
}
impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.chain(-self.re, -1.0)
    }
}
impl<const N: usize> AddAssign for Dual<N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<const N: usize> SubAssign for Dual<N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<const N: usize> MulAssign for Dual<N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}

impl<const N: usize> Scalar for Dual<N> {
    #[inline]
    fn cst(x: f64) -> Self {
        Dual { re: x, eps: [0.0; N] }
    }
    #[inline]
    fn re(self) -> f64 {
        self.re
    }
    #[inline]
    fn sin(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(s, c)
    }
    #[inline]
    fn cos(self) -> Self {
        let (s, c) = self.re.sin_cos();
        self.chain(c, -s)
    }
    #[inline]
    fn sqrt(self) -> Self {
        let r = self.re.sqrt();
        self.chain(r, 0.5 / r)
    }
    #[inline]
    fn exp(self) -> Self {
        let e = self.re.exp();
        self.chain(e, e)
    }
    #[inline]
    fn acos(self) -> Self {
        self.chain(self.re.acos(), -1.0 / (1.0 - self.re * self.re).sqrt())
    }
    #[inline]
    fn atan(self) -> Self {
        self.chain(self.re.atan(), 1.0 / (1.0 + self.re * self.re))
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        let p = self.re.powi(n - 1);
        self.chain(p * self.re, n as f64 * p)
    }
    #[inline]
    fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.re.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The paired lanes give the portable loop's results bit for bit, odd
    /// widths (a last direction alone) included.
    #[test]
    fn paired_lanes_equal_the_portable_loop_bit_for_bit() {
        fn check<const N: usize>() {
            let mut state = 0x2545_f491_4f6c_dd1d_u64;
            let mut next = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 * 4.0 - 2.0
            };
            for _ in 0..200 {
                let a: [f64; N] = std::array::from_fn(|_| next());
                let b: [f64; N] = std::array::from_fn(|_| next());
                let (s, t) = (next(), next());
                let bits = |x: [f64; N]| x.map(f64::to_bits);
                assert_eq!(bits(lanes::add(&a, &b)), bits(portable::add(&a, &b)));
                assert_eq!(bits(lanes::sub(&a, &b)), bits(portable::sub(&a, &b)));
                assert_eq!(bits(lanes::scale(&a, s)), bits(portable::scale(&a, s)));
                assert_eq!(
                    bits(lanes::product(&a, s, t, &b)),
                    bits(portable::product(&a, s, t, &b))
                );
                assert_eq!(
                    bits(lanes::quotient(&a, s, &b, t)),
                    bits(portable::quotient(&a, s, &b, t))
                );
            }
        }
        check::<1>();
        check::<2>();
        check::<3>();
        check::<5>();
        check::<6>();
        check::<12>();
    }

    #[test]
    fn dual_derivatives_match_calculus() {
        let x = Dual::<2>::variable(0.7, 0);
        let y = Dual::<2>::variable(-1.3, 1);
        // f = sin(x) * y^3 / (x + 2) + sqrt(x) cos(y)
        let f = x.sin() * y.powi(3) / (x + Dual::cst(2.0)) + x.sqrt() * y.cos();
        let (xv, yv) = (0.7f64, -1.3f64);
        let dfdx = (xv.cos() * yv.powi(3) * (xv + 2.0) - xv.sin() * yv.powi(3)) / (xv + 2.0).powi(2)
            + 0.5 / xv.sqrt() * yv.cos();
        let dfdy = xv.sin() * 3.0 * yv.powi(2) / (xv + 2.0) - xv.sqrt() * yv.sin();
        assert!((f.eps[0] - dfdx).abs() < 1e-14);
        assert!((f.eps[1] - dfdy).abs() < 1e-14);
    }
}

/// An `f64` that counts the floating-point operations done on it (per
/// thread), to report flop counts beside timings. Transcendental calls count
/// as one operation each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Counted(pub f64);

thread_local! {
    static FLOPS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

impl Counted {
    /// Operations counted on this thread since the last reset.
    pub fn count() -> u64 {
        FLOPS.with(|c| c.get())
    }
    /// Reset this thread's counter.
    pub fn reset() {
        FLOPS.with(|c| c.set(0));
    }
    #[inline]
    fn tick(n: u64) {
        FLOPS.with(|c| c.set(c.get() + n));
    }
}

macro_rules! counted_binop {
    ($tr:ident, $m:ident, $atr:ident, $am:ident, $op:tt) => {
        impl $tr for Counted {
            type Output = Counted;
            #[inline]
            fn $m(self, o: Counted) -> Counted {
                Counted::tick(1);
                Counted(self.0 $op o.0)
            }
        }
        impl $atr for Counted {
            #[inline]
            fn $am(&mut self, o: Counted) {
                *self = *self $op o;
            }
        }
    };
}
counted_binop!(Add, add, AddAssign, add_assign, +);
counted_binop!(Sub, sub, SubAssign, sub_assign, -);
counted_binop!(Mul, mul, MulAssign, mul_assign, *);
impl Div for Counted {
    type Output = Counted;
    #[inline]
    fn div(self, o: Counted) -> Counted {
        Counted::tick(1);
        Counted(self.0 / o.0)
    }
}
impl Neg for Counted {
    type Output = Counted;
    #[inline]
    fn neg(self) -> Counted {
        Counted::tick(1);
        Counted(-self.0)
    }
}
impl Scalar for Counted {
    fn cst(x: f64) -> Self {
        Counted(x)
    }
    fn re(self) -> f64 {
        self.0
    }
    fn sin(self) -> Self {
        Counted::tick(1);
        Counted(self.0.sin())
    }
    fn cos(self) -> Self {
        Counted::tick(1);
        Counted(self.0.cos())
    }
    fn sqrt(self) -> Self {
        Counted::tick(1);
        Counted(self.0.sqrt())
    }
    fn exp(self) -> Self {
        Counted::tick(1);
        Counted(self.0.exp())
    }
    fn acos(self) -> Self {
        Counted::tick(1);
        Counted(self.0.acos())
    }
    fn atan(self) -> Self {
        Counted::tick(1);
        Counted(self.0.atan())
    }
    fn powi(self, n: i32) -> Self {
        Counted::tick(1);
        Counted(self.0.powi(n))
    }
    fn sin_cos(self) -> (Self, Self) {
        Counted::tick(2);
        (Counted(self.0.sin()), Counted(self.0.cos()))
    }
}
