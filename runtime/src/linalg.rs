//! Small dense linear algebra generic over [`Scalar`], so that dual numbers
//! pass through constraint solves and the coordinate partitioning.

use crate::scalar::Scalar;

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
    fn reports_singular_matrices() {
        let mut a = vec![1.0, 2.0, 2.0, 4.0];
        let mut b = vec![1.0, 1.0];
        assert!(solve_in_place(&mut a, 2, &mut b, 1).is_err());
    }
}
