//! The canonical linear form of Meijaard et al. (2007):
//! `M0 q'' + v C1 q' + (g K0 + v^2 K2) q = f`, with `q = [roll phi, steer delta]`
//! in the benchmark's sign convention (x forward, y right, z down; the thesis's
//! steer angle gamma is `-delta`).

use nalgebra::{Matrix2, Matrix4};

/// Canonical matrices of a bicycle linearized about upright straight running.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanonicalMatrices {
    /// Mass matrix `M0` (kg m^2).
    pub m0: Matrix2<f64>,
    /// Velocity-damping matrix per unit speed `C1` (kg m).
    pub c1: Matrix2<f64>,
    /// Gravity stiffness per unit g `K0` (kg m).
    pub k0: Matrix2<f64>,
    /// Velocity stiffness per unit speed squared `K2` (kg).
    pub k2: Matrix2<f64>,
    /// Gravitational acceleration (m/s^2).
    pub g: f64,
}

impl CanonicalMatrices {
    /// Rows of a 2x2 matrix, for JSON/TOML output (`[[m11, m12], [m21, m22]]`).
    pub fn rows(m: &Matrix2<f64>) -> [[f64; 2]; 2] {
        [[m[(0, 0)], m[(0, 1)]], [m[(1, 0)], m[(1, 1)]]]
    }

    /// Damping matrix `v C1` at forward speed `v` (m/s).
    pub fn damping(&self, v: f64) -> Matrix2<f64> {
        self.c1 * v
    }

    /// Stiffness matrix `g K0 + v^2 K2` at forward speed `v` (m/s).
    pub fn stiffness(&self, v: f64) -> Matrix2<f64> {
        self.k0 * self.g + self.k2 * (v * v)
    }

    /// State matrix `A` of `x' = A x`, `x = [phi, delta, phi', delta']`.
    /// Returns `None` when `M0` is singular.
    pub fn state_matrix(&self, v: f64) -> Option<Matrix4<f64>> {
        let minv = self.m0.try_inverse()?;
        let mk = -(minv * self.stiffness(v));
        let mc = -(minv * self.damping(v));
        let mut a = Matrix4::zeros();
        a[(0, 2)] = 1.0;
        a[(1, 3)] = 1.0;
        a.fixed_view_mut::<2, 2>(2, 0).copy_from(&mk);
        a.fixed_view_mut::<2, 2>(2, 2).copy_from(&mc);
        Some(a)
    }
}
