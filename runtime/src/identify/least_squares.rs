//! Levenberg-Marquardt for a few parameters with a forward-difference
//! Jacobian, for fits whose residuals cost microseconds (eigenvalue
//! tables, the discovery's dictionary terms). The time-series fits have
//! their own block-arrow solver with exact sensitivities (`fit.rs`).

use nalgebra::{DMatrix, DVector};

/// The fitted values, their residuals and the Jacobian there.
pub struct LeastSquares {
    pub x: Vec<f64>,
    pub residuals: Vec<f64>,
    pub jacobian: DMatrix<f64>,
}

/// Minimize the sum of squares of `eval(x)` from `x0`. Column `j` of the
/// Jacobian steps `rel_step * max(scales[j], |x_j|)`. Iterates while a step
/// lowers the cost by more than 1e-10 of it, at most 100 times. An error of
/// `eval` ends the fit with it.
pub fn levenberg_marquardt<E>(
    x0: Vec<f64>,
    scales: &[f64],
    rel_step: f64,
    eval: &dyn Fn(&[f64]) -> Result<Vec<f64>, E>,
) -> Result<LeastSquares, E> {
    let k = x0.len();
    let cost = |r: &[f64]| r.iter().map(|a| a * a).sum::<f64>();
    let jac = |x: &[f64], r0: &[f64]| -> Result<DMatrix<f64>, E> {
        let mut j = DMatrix::zeros(r0.len(), k);
        for col in 0..k {
            let h = rel_step * scales[col].max(x[col].abs());
            let mut xp = x.to_vec();
            xp[col] += h;
            for (i, (a, b)) in eval(&xp)?.iter().zip(r0).enumerate() {
                j[(i, col)] = (a - b) / h;
            }
        }
        Ok(j)
    };
    let mut x = x0;
    let mut r = eval(&x)?;
    let mut c = cost(&r);
    let mut lambda = 1e-3;
    // Nothing free: the cost as it is.
    for _ in 0..if k == 0 { 0 } else { 100 } {
        let j = jac(&x, &r)?;
        let h = j.tr_mul(&j);
        let g = j.tr_mul(&DVector::from_column_slice(&r));
        let mut improved = false;
        while lambda < 1e12 {
            let mut a = h.clone();
            for d in 0..k {
                a[(d, d)] += lambda * h[(d, d)].max(1e-12);
            }
            let Some(dx) = a.lu().solve(&(-&g)) else {
                lambda *= 10.0;
                continue;
            };
            let xt: Vec<f64> = x.iter().zip(dx.iter()).map(|(a, b)| a + b).collect();
            let rt = eval(&xt)?;
            let ct = cost(&rt);
            if ct < c {
                let done = (c - ct) <= 1e-10 * c;
                (x, r, c) = (xt, rt, ct);
                lambda = (lambda / 3.0).max(1e-12);
                improved = !done;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    let jacobian = jac(&x, &r)?;
    Ok(LeastSquares {
        x,
        residuals: r,
        jacobian,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_through_points_is_fitted_to_rounding() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let y: Vec<f64> = t.iter().map(|t| 2.0 - 0.5 * t).collect();
        let eval =
            |x: &[f64]| -> Result<Vec<f64>, ()> { Ok(t.iter().zip(&y).map(|(t, y)| y - (x[0] + x[1] * t)).collect()) };
        let f = levenberg_marquardt(vec![0.0, 0.0], &[1.0, 1.0], 1e-7, &eval).unwrap();
        assert!((f.x[0] - 2.0).abs() < 1e-6 && (f.x[1] + 0.5).abs() < 1e-6, "{:?}", f.x);
        assert_eq!(f.jacobian.shape(), (4, 2));
    }
}
