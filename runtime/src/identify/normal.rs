//! The normal equations of a fit, solved on their block-arrow structure.
//! Each kick depends only on the shared effect parameters and its own
//! nuisances, so each kick's block is eliminated (a Schur complement) and a
//! k x k system of the shared parameters remains: an iteration costs
//! linearly in the number of kicks. The same reduced matrix gives the
//! standard errors, the score test's predictions and the confounding
//! measure.

use nalgebra::{DMatrix, DVector};

/// The Jacobian of one segment: the columns of the free shared (effect)
/// parameters `a` (rows x k, or no column) and of its own free initial
/// state `b` (rows x NUISANCE, or no column). A segment depends on nothing
/// else, so the whole Jacobian is these blocks and zeros.
pub(super) struct SegmentJacobian {
    pub(super) a: DMatrix<f64>,
    pub(super) b: DMatrix<f64>,
}

/// The normal equations of the block-arrow least-squares problem, reduced
/// to the shared parameters. With `J = [A_i B_i]` per segment, `J^T J` has a
/// shared block `sum A_i^T A_i` (plus the priors), a 6x6 block `B_i^T B_i` (10x10 with the tyre model)
/// per segment, and couplings `A_i^T B_i`; eliminating each segment's block
/// (Schur complement) leaves a k x k system. Its cost grows linearly with
/// the number of kicks, where a dense QR of `J` grows with their cube (a
/// hundred kicks of the TU Delft logs: 600 columns, minutes per iteration).
pub(super) struct Normal {
    /// Reduced shared matrix `S` and right-hand side.
    pub(super) s: DMatrix<f64>,
    rhs: DVector<f64>,
    /// Per segment: the damped `C_i^-1`, `E_i = A_i^T B_i` and `-B_i^T r_i`.
    segs: Vec<(DMatrix<f64>, DMatrix<f64>, DVector<f64>)>,
}

impl Normal {
    /// Build for damping `lambda` (Marquardt: the diagonal scaled by
    /// `1 + lambda`). `prior` holds `(column, sd, residual)` of the priors.
    pub(super) fn new(
        blocks: &[SegmentJacobian],
        res: &[Vec<f64>],
        prior: &[(usize, f64, f64)],
        k: usize,
        lambda: f64,
    ) -> Option<Normal> {
        Normal::damped(blocks, res, prior, k, lambda, lambda)
    }

    /// [`Normal::new`] with the shared block damped by `lambda` and each
    /// segment's block by `lambda_segment`: a segment's block left (almost)
    /// undamped is eliminated exactly, which is the step of the shared
    /// parameters on the profile where every segment's initial state is
    /// at its own optimum (Kaufman's variable-projection step).
    pub(super) fn damped(
        blocks: &[SegmentJacobian],
        res: &[Vec<f64>],
        prior: &[(usize, f64, f64)],
        k: usize,
        lambda: f64,
        lambda_segment: f64,
    ) -> Option<Normal> {
        let mut hgg = DMatrix::<f64>::zeros(k, k);
        let mut bg = DVector::<f64>::zeros(k);
        for (blk, r) in blocks.iter().zip(res) {
            let r = DVector::from_column_slice(r);
            if k > 0 {
                hgg += blk.a.tr_mul(&blk.a);
                bg -= blk.a.tr_mul(&r);
            }
        }
        for &(j, sd, pr) in prior {
            hgg[(j, j)] += 1.0 / (sd * sd);
            bg[j] -= pr / sd;
        }
        let damp = |m: &mut DMatrix<f64>, lambda: f64| {
            for j in 0..m.nrows() {
                let d = m[(j, j)];
                m[(j, j)] = d + lambda * d.max(1e-12);
            }
        };
        damp(&mut hgg, lambda);
        let mut s = hgg;
        let mut rhs = bg;
        let mut segs = Vec::with_capacity(blocks.len());
        for (blk, r) in blocks.iter().zip(res) {
            let r = DVector::from_column_slice(r);
            let mut c = blk.b.tr_mul(&blk.b);
            damp(&mut c, lambda_segment);
            let c_inv = if c.nrows() == 0 { c } else { c.try_inverse()? };
            let e = blk.a.tr_mul(&blk.b);
            let bi = -blk.b.tr_mul(&r);
            if k > 0 && c_inv.nrows() > 0 {
                let ec = &e * &c_inv;
                s -= &ec * e.transpose();
                rhs -= &ec * &bi;
            }
            segs.push((c_inv, e, bi));
        }
        Some(Normal { s, rhs, segs })
    }

    /// The step in packed order (shared parameters, then each segment's
    /// initial state).
    pub(super) fn step(&self) -> Option<Vec<f64>> {
        let dg = if self.s.nrows() > 0 {
            self.s.clone().lu().solve(&self.rhs)?
        } else {
            DVector::zeros(0)
        };
        let mut out: Vec<f64> = dg.iter().copied().collect();
        for (c_inv, e, bi) in &self.segs {
            if c_inv.nrows() == 0 {
                continue;
            }
            let di = if dg.nrows() > 0 {
                c_inv * (bi - e.tr_mul(&dg))
            } else {
                c_inv * bi
            };
            out.extend(di.iter());
        }
        Some(out)
    }
}
