//! Small dense linear algebra generic over [`Scalar`], so that dual numbers
//! pass through constraint solves and the coordinate partitioning.
//!
//! One LU kernel ([`lu_factor`], [`lu_solve`]; [`solve_in_place`] is both)
//! does every small dense solve of bikedyn: the constraint Newton steps, the
//! coordinate partitioning of the linearization and of the simulation's
//! right-hand side, the reduced mass matrix, the Bairstow step of the quartic
//! solver. It is our own code rather than nalgebra's `lu()` because it is
//! generic over [`Scalar`] (dual numbers flow through it and give exact
//! derivatives of the solution), it works in the caller's buffers (stack
//! [`Scratch`] in the linearization, the simulation's workspace), so the hot
//! paths allocate nothing, and its singularity test is relative to the
//! matrix scale and reports where it failed ([`Singular`]). Plain `f64`
//! `DMatrix` solves off the hot paths use nalgebra.

use crate::scalar::{Dual, Scalar};

/// The matrix was singular to working precision (pivot below `tiny`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Singular {
    /// Column where elimination found no usable pivot.
    pub column: usize,
    /// Largest available pivot magnitude.
    pub pivot: f64,
    /// Largest entry magnitude of the matrix; a pivot is usable when it
    /// exceeds `1e-14 * scale`.
    pub scale: f64,
}

/// Solve `A X = B` in place by LU factorization with partial pivoting (on
/// the real parts): [`lu_factor`] then [`lu_solve`]. `a` is `n x n`
/// row-major and receives the factors, `b` is `n x nrhs` row-major and
/// receives `X`.
pub fn solve_in_place<T: Scalar>(a: &mut [T], n: usize, b: &mut [T], nrhs: usize) -> Result<(), Singular> {
    assert_eq!(b.len(), n * nrhs, "right-hand side size");
    let mut perm = Scratch::<usize, 32>::new(n, 0);
    lu_factor(a, n, &mut perm)?;
    lu_solve(a, n, &perm, b, nrhs);
    Ok(())
}

/// LU factorization with partial pivoting of an `n x n` matrix (row-major,
/// in place): `P A = L U` with unit lower `L` below the diagonal and `U` on
/// and above it. Pivots are chosen on the real parts; a pivot below `1e-14`
/// times the largest entry is [`Singular`]. `perm[k]` is the row swapped
/// with row `k` at step `k` (whole rows, multipliers included). With
/// real factors, dual-number systems are solved by [`lu_solve_dual`].
pub fn lu_factor<T: Scalar>(a: &mut [T], n: usize, perm: &mut [usize]) -> Result<(), Singular> {
    assert_eq!(a.len(), n * n, "matrix size");
    assert_eq!(perm.len(), n, "permutation size");
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.re().abs())).max(f64::MIN_POSITIVE);
    for k in 0..n {
        let (mut piv, mut best) = (k, a[k * n + k].re().abs());
        for i in k + 1..n {
            let v = a[i * n + k].re().abs();
            if v > best {
                piv = i;
                best = v;
            }
        }
        if !(best > scale * 1e-14) {
            return Err(Singular {
                column: k,
                pivot: best,
                scale,
            });
        }
        perm[k] = piv;
        if piv != k {
            for j in 0..n {
                a.swap(k * n + j, piv * n + j);
            }
        }
        let inv = T::one() / a[k * n + k];
        for i in k + 1..n {
            let f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if is_zero(f) {
                continue;
            }
            for j in k + 1..n {
                let u = a[k * n + j];
                a[i * n + j] -= f * u;
            }
        }
    }
    Ok(())
}

/// Exactly zero, derivatives included: a product by it changes nothing, so
/// the kernel skips it (the constraint matrices are sparse).
#[inline(always)]
fn is_zero<T: Scalar>(x: T) -> bool {
    x.re() == 0.0 && x == T::zero()
}

/// Solve `A X = B` in place with the factors of [`lu_factor`], for `m`
/// right-hand sides at once (`b` is `n x m`, row-major): the inner loops run
/// along the rows of `b`.
pub fn lu_solve<T: Scalar>(lu: &[T], n: usize, perm: &[usize], b: &mut [T], m: usize) {
    assert_eq!(lu.len(), n * n, "matrix size");
    assert_eq!(b.len(), n * m, "right-hand side size");
    // The widths of the linearization's solves as constants, so that the
    // compiler unrolls the rows of each (the same kernel, specialised).
    match m {
        1 => substitute(lu, n, perm, b, 1),
        2 => substitute(lu, n, perm, b, 2),
        3 => substitute(lu, n, perm, b, 3),
        4 => substitute(lu, n, perm, b, 4),
        6 => substitute(lu, n, perm, b, 6),
        8 => substitute(lu, n, perm, b, 8),
        9 => substitute(lu, n, perm, b, 9),
        12 => substitute(lu, n, perm, b, 12),
        _ => substitute(lu, n, perm, b, m),
    }
}

/// The substitutions of [`lu_solve`]: the row interchanges, `L y = P b`
/// forward, `U x = y` backward (times the reciprocal of each pivot).
#[inline(always)]
fn substitute<T: Scalar>(lu: &[T], n: usize, perm: &[usize], b: &mut [T], m: usize) {
    for k in 0..n {
        if perm[k] != k {
            for c in 0..m {
                b.swap(k * m + c, perm[k] * m + c);
            }
        }
    }
    for i in 0..n {
        let (done, rest) = b.split_at_mut(i * m);
        let row = &mut rest[..m];
        for j in 0..i {
            let l = lu[i * n + j];
            if !is_zero(l) {
                for (x, &y) in row.iter_mut().zip(&done[j * m..(j + 1) * m]) {
                    *x -= l * y;
                }
            }
        }
    }
    for i in (0..n).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * m);
        let row = &mut head[i * m..];
        for j in i + 1..n {
            let u = lu[i * n + j];
            if !is_zero(u) {
                for (x, &y) in row.iter_mut().zip(&tail[(j - i - 1) * m..(j - i) * m]) {
                    *x -= u * y;
                }
            }
        }
        let inv = T::one() / lu[i * n + i];
        for x in row.iter_mut() {
            *x *= inv;
        }
    }
}

/// Solve `A X = B` for dual-number `A` (`n x n`) and `B` (`n x nrhs`, both
/// row-major) given the factors of `A`'s real part: `X = A0^-1 B0` and, along
/// each direction, `X' = A0^-1 (B' - A' X)`. One real factorization replaces
/// the elimination in dual arithmetic (the derivative of the inverse is
/// exact, as with [`solve_in_place`] on duals). `B` receives `X`.
pub fn lu_solve_dual<const N: usize>(
    lu: &[f64],
    n: usize,
    perm: &[usize],
    a: &[Dual<N>],
    b: &mut [Dual<N>],
    nrhs: usize,
) {
    lu_solve_dual_narrow(lu, n, perm, a, b, nrhs)
}

/// [`lu_solve_dual`] for a matrix `A` whose derivatives are along the first
/// `HA <= N` directions only (the others vanish): e.g. a matrix of the
/// configuration alone and a right-hand side along the configuration and the
/// velocities. Equal to widening `A` to `N` directions, without the products
/// by zero. Allocates nothing for systems of up to 16 values.
pub fn lu_solve_dual_narrow<const HA: usize, const N: usize>(
    lu: &[f64],
    n: usize,
    perm: &[usize],
    a: &[Dual<HA>],
    b: &mut [Dual<N>],
    nrhs: usize,
) {
    assert!(HA <= N, "the matrix has at most the right-hand side's directions");
    assert_eq!(a.len(), n * n, "matrix size");
    assert_eq!(b.len(), n * nrhs, "right-hand side size");
    let mut x = Scratch::<f64, 64>::new(n * nrhs, 0.0);
    let x = &mut *x;
    for (xi, bi) in x.iter_mut().zip(b.iter()) {
        *xi = bi.re;
    }
    lu_solve(lu, n, perm, x, nrhs);
    // Columns (c, k): direction k of right-hand side c.
    let m = nrhs * N;
    let mut r = Scratch::<f64, 256>::new(n * m, 0.0);
    let r = &mut *r;
    for i in 0..n {
        let ri = &mut r[i * m..(i + 1) * m];
        for c in 0..nrhs {
            ri[c * N..(c + 1) * N].copy_from_slice(&b[i * nrhs + c].eps);
        }
        for j in 0..n {
            let aij = &a[i * n + j].eps;
            for c in 0..nrhs {
                let xj = x[j * nrhs + c];
                let rc = &mut ri[c * N..c * N + HA];
                for k in 0..HA {
                    rc[k] -= aij[k] * xj;
                }
            }
        }
    }
    lu_solve(lu, n, perm, r, m);
    for i in 0..n {
        for c in 0..nrhs {
            let v = &mut b[i * nrhs + c];
            v.re = x[i * nrhs + c];
            v.eps.copy_from_slice(&r[i * m + c * N..i * m + (c + 1) * N]);
        }
    }
}

/// A scratch buffer of `len` values, all `fill`: on the stack when
/// `len <= CAP`, on the heap otherwise, so hot paths sized for the bicycle
/// models allocate nothing and larger models stay correct. Dereferences to
/// the slice of its `len` values.
pub enum Scratch<T, const CAP: usize> {
    Stack([T; CAP], usize),
    Heap(Vec<T>),
}

impl<T: Copy, const CAP: usize> Scratch<T, CAP> {
    #[inline(always)]
    pub fn new(len: usize, fill: T) -> Self {
        if len <= CAP {
            Scratch::Stack([fill; CAP], len)
        } else {
            Scratch::Heap(vec![fill; len])
        }
    }
}

impl<T, const CAP: usize> std::ops::Deref for Scratch<T, CAP> {
    type Target = [T];
    #[inline(always)]
    fn deref(&self) -> &[T] {
        match self {
            Scratch::Stack(a, n) => &a[..*n],
            Scratch::Heap(v) => v,
        }
    }
}

impl<T, const CAP: usize> std::ops::DerefMut for Scratch<T, CAP> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        match self {
            Scratch::Stack(a, n) => &mut a[..*n],
            Scratch::Heap(v) => v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_pivoting_system() {
        let mut a = vec![0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let x = [1.0, -2.0, 0.5];
        let mut b: Vec<f64> = (0..3).map(|i| (0..3).map(|j| a[i * 3 + j] * x[j]).sum()).collect();
        solve_in_place(&mut a, 3, &mut b, 1).unwrap();
        for i in 0..3 {
            assert!((b[i] - x[i]).abs() < 1e-15);
        }
    }

    #[test]
    fn dual_solve_with_a_real_factorization_matches_dual_elimination() {
        let re = [0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let a: Vec<Dual<2>> = re
            .iter()
            .enumerate()
            .map(|(i, &x)| Dual {
                re: x,
                eps: [0.1 * i as f64, (i as f64).sin()],
            })
            .collect();
        let b: Vec<Dual<2>> = (0..6)
            .map(|i| Dual {
                re: 1.0 + i as f64,
                eps: [(i as f64).cos(), -0.3 * i as f64],
            })
            .collect();
        let (mut a1, mut b1) = (a.clone(), b.clone());
        solve_in_place(&mut a1, 3, &mut b1, 2).unwrap();
        let mut lu = re;
        let mut perm = [0; 3];
        lu_factor(&mut lu, 3, &mut perm).unwrap();
        let mut b2 = b.clone();
        lu_solve_dual(&lu, 3, &perm, &a, &mut b2, 2);
        for (x, y) in b1.iter().zip(&b2) {
            assert!((x.re - y.re).abs() < 1e-14);
            for k in 0..2 {
                assert!((x.eps[k] - y.eps[k]).abs() < 1e-13);
            }
        }
    }

    /// Every width of right-hand sides, the specialised ones (1, 2, 3, 4,
    /// 6, 8, 9, 12) and the others, gives bit for bit what solving column by
    /// column gives (the same operations in the same order), and solves
    /// `A X = B` to `n eps |A| |X|`. The zero leading entry forces a row
    /// interchange.
    #[test]
    fn every_width_of_right_hand_sides_is_the_same_kernel() {
        let n = 5;
        let a: Vec<f64> = (0..n * n)
            .map(|k| {
                if k == 0 {
                    0.0
                } else {
                    ((k * 7 + 3) % 11) as f64 - 5.0 + 0.1 * k as f64
                }
            })
            .collect();
        let mut lu = a.clone();
        let mut perm = [0; 5];
        lu_factor(&mut lu, n, &mut perm).unwrap();
        assert_ne!(perm[0], 0, "the zero pivot is interchanged");
        let norm_a = a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for m in 1..=13 {
            let b: Vec<f64> = (0..n * m).map(|k| (0.37 * k as f64).sin()).collect();
            let mut x = b.clone();
            lu_solve(&lu, n, &perm, &mut x, m);
            for c in 0..m {
                let mut col: Vec<f64> = (0..n).map(|i| b[i * m + c]).collect();
                lu_solve(&lu, n, &perm, &mut col, 1);
                let norm_x = col.iter().fold(0.0f64, |s, x| s.max(x.abs()));
                for i in 0..n {
                    assert_eq!(
                        x[i * m + c].to_bits(),
                        col[i].to_bits(),
                        "width {m}, column {c}, row {i}"
                    );
                    let r: f64 = (0..n).map(|j| a[i * n + j] * col[j]).sum::<f64>() - b[i * m + c];
                    assert!(
                        r.abs() <= 8.0 * n as f64 * f64::EPSILON * norm_a * norm_x,
                        "residual {r:e}"
                    );
                }
            }
        }
    }

    /// Dual numbers through the kernel give the derivative of the solution:
    /// `A(s) x(s) = b(s)` with `A' = A1`, `b' = b1` has `x' = A^-1 (b1 - A1 x)`.
    #[test]
    fn dual_numbers_through_the_kernel_give_the_derivative() {
        let re = [0.0, 2.0, 1.0, 1.0, 1.0, 0.0, 3.0, 0.0, 1.0];
        let a1 = [0.5, -1.0, 0.0, 0.25, 0.0, 2.0, -0.75, 1.0, 0.0];
        let (b0, b1) = ([1.0, -2.0, 0.5], [0.3, 0.0, -1.0]);
        let mut a: Vec<Dual<1>> = (0..9)
            .map(|k| Dual {
                re: re[k],
                eps: [a1[k]],
            })
            .collect();
        let mut b: Vec<Dual<1>> = (0..3)
            .map(|k| Dual {
                re: b0[k],
                eps: [b1[k]],
            })
            .collect();
        solve_in_place(&mut a, 3, &mut b, 1).unwrap();
        let x: Vec<f64> = b.iter().map(|v| v.re).collect();
        let mut want: Vec<f64> = (0..3)
            .map(|i| b1[i] - (0..3).map(|j| a1[i * 3 + j] * x[j]).sum::<f64>())
            .collect();
        let mut m = re;
        solve_in_place(&mut m, 3, &mut want, 1).unwrap();
        for i in 0..3 {
            assert!((b[i].eps[0] - want[i]).abs() < 1e-14, "{} vs {}", b[i].eps[0], want[i]);
        }
    }

    #[test]
    fn reports_singular_matrices() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        let mut b = vec![1.0, 1.0];
        assert!(solve_in_place(&mut a, 2, &mut b, 1).is_err());
    }
}
