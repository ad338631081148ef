//! Small dense linear algebra generic over [`Scalar`], so that dual numbers
//! pass through constraint solves and the coordinate partitioning.

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

/// Solve `A X = B` in place by Gaussian elimination with partial pivoting
/// (on the real parts). `a` is `n x n` row-major, `b` is `n x nrhs`
/// row-major and receives `X`.
pub fn solve_in_place<T: Scalar>(a: &mut [T], n: usize, b: &mut [T], nrhs: usize) -> Result<(), Singular> {
    assert_eq!(a.len(), n * n, "matrix size");
    assert_eq!(b.len(), n * nrhs, "right-hand side size");
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
        if piv != k {
            for j in 0..n {
                a.swap(k * n + j, piv * n + j);
            }
            for j in 0..nrhs {
                b.swap(k * nrhs + j, piv * nrhs + j);
            }
        }
        let inv = T::one() / a[k * n + k];
        for i in k + 1..n {
            let f = a[i * n + k] * inv;
            if f.re() == 0.0 && f == T::zero() {
                continue;
            }
            for j in k..n {
                let t = a[k * n + j];
                a[i * n + j] -= f * t;
            }
            for j in 0..nrhs {
                let t = b[k * nrhs + j];
                b[i * nrhs + j] -= f * t;
            }
        }
    }
    for k in (0..n).rev() {
        let inv = T::one() / a[k * n + k];
        for j in 0..nrhs {
            let mut s = b[k * nrhs + j];
            for i in k + 1..n {
                s -= a[k * n + i] * b[i * nrhs + j];
            }
            b[k * nrhs + j] = s * inv;
        }
    }
    Ok(())
}

/// LU factorization with partial pivoting of a real `n x n` matrix (row-major,
/// in place), with the same pivot rule and singularity test as
/// [`solve_in_place`]. `perm[k]` is the row swapped with row `k` at step `k`.
/// Used to solve dual-number systems with one real factorization (see
/// [`lu_solve_dual`]).
pub fn lu_factor(a: &mut [f64], n: usize, perm: &mut [usize]) -> Result<(), Singular> {
    assert_eq!(a.len(), n * n, "matrix size");
    assert_eq!(perm.len(), n, "permutation size");
    let scale = a.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(f64::MIN_POSITIVE);
    for k in 0..n {
        let (mut piv, mut best) = (k, a[k * n + k].abs());
        for i in k + 1..n {
            let v = a[i * n + k].abs();
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
        let inv = 1.0 / a[k * n + k];
        for i in k + 1..n {
            let f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if f == 0.0 {
                continue;
            }
            for j in k + 1..n {
                a[i * n + j] -= f * a[k * n + j];
            }
        }
    }
    Ok(())
}

/// Solve `A x = b` in place with the factors of [`lu_factor`].
pub fn lu_solve(lu: &[f64], n: usize, perm: &[usize], b: &mut [f64]) {
    for k in 0..n {
        b.swap(k, perm[k]);
    }
    for i in 0..n {
        let mut s = b[i];
        for j in 0..i {
            s -= lu[i * n + j] * b[j];
        }
        b[i] = s;
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for j in i + 1..n {
            s -= lu[i * n + j] * b[j];
        }
        b[i] = s / lu[i * n + i];
    }
}

/// Solve `A X = B` in place with the factors of [`lu_factor`], for `m`
/// right-hand sides at once (`b` is `n x m`, row-major): the inner loops run
/// along the rows of `b`.
pub fn lu_solve_many(lu: &[f64], n: usize, perm: &[usize], b: &mut [f64], m: usize) {
    assert_eq!(b.len(), n * m, "right-hand side size");
    // The widths of the dual-number solves: rows of fixed length, which the
    // compiler unrolls (the same operations in the same order).
    match m {
        1 => return lu_solve_rows::<1>(lu, n, perm, b.as_chunks_mut().0),
        2 => return lu_solve_rows::<2>(lu, n, perm, b.as_chunks_mut().0),
        3 => return lu_solve_rows::<3>(lu, n, perm, b.as_chunks_mut().0),
        4 => return lu_solve_rows::<4>(lu, n, perm, b.as_chunks_mut().0),
        6 => return lu_solve_rows::<6>(lu, n, perm, b.as_chunks_mut().0),
        8 => return lu_solve_rows::<8>(lu, n, perm, b.as_chunks_mut().0),
        9 => return lu_solve_rows::<9>(lu, n, perm, b.as_chunks_mut().0),
        12 => return lu_solve_rows::<12>(lu, n, perm, b.as_chunks_mut().0),
        _ => {}
    }
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
            if l != 0.0 {
                for (x, y) in row.iter_mut().zip(&done[j * m..(j + 1) * m]) {
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
            if u != 0.0 {
                for (x, y) in row.iter_mut().zip(&tail[(j - i - 1) * m..(j - i) * m]) {
                    *x -= u * y;
                }
            }
        }
        let inv = 1.0 / lu[i * n + i];
        for x in row.iter_mut() {
            *x *= inv;
        }
    }
}

/// [`lu_solve_many`] with rows of `W` values.
fn lu_solve_rows<const W: usize>(lu: &[f64], n: usize, perm: &[usize], b: &mut [[f64; W]]) {
    assert_eq!(b.len(), n, "right-hand side size");
    for k in 0..n {
        if perm[k] != k {
            b.swap(k, perm[k]);
        }
    }
    for i in 0..n {
        let mut row = b[i];
        for j in 0..i {
            let l = lu[i * n + j];
            if l != 0.0 {
                let y = &b[j];
                for c in 0..W {
                    row[c] -= l * y[c];
                }
            }
        }
        b[i] = row;
    }
    for i in (0..n).rev() {
        let mut row = b[i];
        for j in i + 1..n {
            let u = lu[i * n + j];
            if u != 0.0 {
                let y = &b[j];
                for c in 0..W {
                    row[c] -= u * y[c];
                }
            }
        }
        let inv = 1.0 / lu[i * n + i];
        for x in row.iter_mut() {
            *x *= inv;
        }
        b[i] = row;
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
    lu_solve_many(lu, n, perm, x, nrhs);
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
    lu_solve_many(lu, n, perm, r, m);
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

    #[test]
    fn reports_singular_matrices() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        let mut b = vec![1.0, 1.0];
        assert!(solve_in_place(&mut a, 2, &mut b, 1).is_err());
    }
}
