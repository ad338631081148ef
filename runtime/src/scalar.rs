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
        let mut eps = self.eps;
        for e in eps.iter_mut() {
            *e *= df;
        }
        Dual { re: f, eps }
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
    fn add(mut self, o: Self) -> Self {
        self.re += o.re;
        for k in 0..N {
            self.eps[k] += o.eps[k];
        }
        self
    }
}
impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.re -= o.re;
        for k in 0..N {
            self.eps[k] -= o.eps[k];
        }
        self
    }
}
impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut eps = [0.0; N];
        for k in 0..N {
            eps[k] = self.eps[k] * o.re + self.re * o.eps[k];
        }
        Dual {
            re: self.re * o.re,
            eps,
        }
    }
}
impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let inv = 1.0 / o.re;
        let re = self.re * inv;
        let mut eps = [0.0; N];
        for k in 0..N {
            eps[k] = (self.eps[k] - re * o.eps[k]) * inv;
        }
        Dual { re, eps }
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
