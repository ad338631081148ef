//! Conversion between the thesis form and the benchmark form.
//!
//! Geometry, upright with zero steer. Thesis global axes: X forward, Y left,
//! Z up, origin at the rear contact point. Benchmark axes: x forward, y right,
//! z down, same origin; `P = diag(1, -1, -1)` maps one to the other.
//!
//! - Rear wheel centre `C2 = (0, 0, Rt)`.
//! - Frame axes are the global axes pitched by `beta` about Y:
//!   `A(beta) = [[cos b, 0, sin b], [0, 1, 0], [-sin b, 0, cos b]]`
//!   (global = `A` * local). The frame x axis is `(cos b, 0, -sin b)`, the
//!   steer axis `A (0, 0, 1) = (sin b, 0, cos b)`. The benchmark steer tilt is
//!   `lam = -beta`.
//! - Rear-frame mass centre `C2 + A [x3, 0, z3]`; steer-axis point
//!   `S = C2 + A [x4, 0, z4]`; handlebar/fork mass centre `S + A [d4, 0, 0]`;
//!   front wheel centre `C5 = S + A [x5, 0, z5]`, with `Z(C5) = Rd` (the
//!   front contact is straight below `C5`).
//! - Tensors: `I_bench = P A I_thesis A^T P` for the rear frame (`I3`) and the
//!   handlebar/fork (`I4`, fork axes = frame axes at zero steer); wheels are
//!   `diag(Ix, Iy, Ix)` in both forms.

use nalgebra::{Matrix3, Vector3};

use super::{BenchmarkParameters, ParameterError, ThesisParameters};
use crate::scalar::Scalar;

/// `A(beta)`: rotation about Y by the frame pitch.
fn pitch(beta: f64) -> Matrix3<f64> {
    let (s, c) = beta.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

/// `P = diag(1, -1, -1)`: thesis global axes (Y left, Z up) to benchmark axes
/// (y right, z down). It is its own inverse.
fn flip() -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
}

/// Symmetric tensor `[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]`.
fn xz_tensor(xx: f64, yy: f64, zz: f64, xz: f64) -> Matrix3<f64> {
    Matrix3::new(xx, 0.0, xz, 0.0, yy, 0.0, xz, 0.0, zz)
}

/// A point in the xz plane of either axis set.
fn point(x: f64, z: f64) -> Vector3<f64> {
    Vector3::new(x, 0.0, z)
}

fn check_finite(symbols: &[&'static str], get: impl Fn(&str) -> Option<f64>) -> Result<(), ParameterError> {
    for &field in symbols {
        let value = get(field).unwrap_or(f64::NAN);
        if !value.is_finite() {
            return Err(ParameterError::NotFinite {
                field: field.to_string(),
                value,
                origin: Default::default(),
            });
        }
    }
    Ok(())
}

impl ThesisParameters {
    /// The frame pitch `beta` (rad) that puts the upright front wheel on the
    /// ground: the root of `Z(C5) = Rd`, i.e.
    /// `Rt - sin(b) (x4 + x5) + cos(b) (z4 + z5) = Rd`, with `C5` ahead of the
    /// rear wheel centre and `cos(beta) > 0`. For the thesis bicycle
    /// `beta ~ -0.315` rad. The steer-axis tilt from vertical is `-beta`.
    ///
    /// With `p = x4 + x5`, `q = z4 + z5`, `R = hypot(p, q)`: `R cos(b + phi) =
    /// Rd - Rt` with `phi = atan2(p, q)`, and `X(C5) = R sin(b + phi)`; the
    /// front wheel is ahead only for `b = acos((Rd - Rt) / R) - phi`, so the
    /// root is unique.
    ///
    /// Errors: [`ParameterError::NoGroundContact`] when `|Rd - Rt| >= R`;
    /// [`ParameterError::SteerAxisNotUpright`] when the root has
    /// `cos(beta) <= 0`; [`ParameterError::NotFinite`] for NaN or infinite
    /// geometry.
    pub fn frame_pitch(&self) -> Result<f64, ParameterError> {
        check_finite(&["Rt", "Rd", "x4", "z4", "x5", "z5"], |k| self.get(k))?;
        let p = self.steer_point_x + self.front_wheel_x;
        let q = self.steer_point_z + self.front_wheel_z;
        let d = self.front_wheel_radius - self.rear_wheel_radius;
        let reach = p.hypot(q);
        if reach <= d.abs() {
            return Err(ParameterError::NoGroundContact {
                height_difference: d,
                reach,
                detail: "|Rd - Rt| must be less than the reach, else the front wheel cannot \
                         touch the ground ahead of the rear wheel",
            });
        }
        let mut beta = (d / reach).acos() - p.atan2(q);
        if beta > std::f64::consts::PI {
            beta -= std::f64::consts::TAU;
        } else if beta <= -std::f64::consts::PI {
            beta += std::f64::consts::TAU;
        }
        if beta.cos() <= 0.0 {
            return Err(ParameterError::SteerAxisNotUpright { tilt: -beta });
        }
        Ok(beta)
    }

    /// Convert to the benchmark form (Meijaard et al. 2007), upright with zero
    /// steer.
    ///
    /// Geometry. Thesis global axes: X forward, Y left, Z up, origin at the
    /// rear contact point. Benchmark axes: x forward, y right, z down, same
    /// origin; `P = diag(1, -1, -1)` maps one to the other. Rear wheel centre
    /// `C2 = (0, 0, Rt)`. Frame axes are the global axes pitched by `beta`
    /// about Y: `A(beta) = [[cos b, 0, sin b], [0, 1, 0], [-sin b, 0, cos b]]`
    /// (global = `A` * local), so the frame x axis is `(cos b, 0, -sin b)` and
    /// the steer axis `(sin b, 0, cos b)`. Rear-frame mass centre
    /// `C2 + A [x3, 0, z3]`; steer-axis point `S = C2 + A [x4, 0, z4]`;
    /// handlebar/fork mass centre `S + A [d4, 0, 0]`; front wheel centre
    /// `C5 = S + A [x5, 0, z5]`, straight above the front contact.
    ///
    /// Result: `beta` from [`frame_pitch`](Self::frame_pitch); `w = X(C5)`; the steer
    /// axis meets the ground at `X_g` and `c = X_g - w`; `lam = -beta`; `xB,
    /// zB` from the rear-frame mass centre and `xH, zH` from the handlebar/fork
    /// mass centre (`z` down: `zB = -Z`); `rR = Rt`, `rF = Rd`; masses and
    /// wheel moments copied; frame tensors `P A I A^T P`, which flips the sign
    /// of the xz entry.
    pub fn to_benchmark(&self) -> Result<BenchmarkParameters, ParameterError> {
        check_finite(&Self::SYMBOLS, |k| self.get(k))?;
        let beta = self.frame_pitch()?;
        let a = pitch(beta);
        let (sb, cb) = beta.sin_cos();
        let c2 = point(0.0, self.rear_wheel_radius);
        let s = c2 + a * point(self.steer_point_x, self.steer_point_z);
        let c5 = s + a * point(self.front_wheel_x, self.front_wheel_z);
        let frame_com = c2 + a * point(self.frame_com_x, self.frame_com_z);
        let fork_com = s + a * point(self.fork_com_offset, 0.0);
        // The steer axis S + t (sin b, 0, cos b) meets Z = 0 at t = -Z(S)/cos b.
        let ground_x = s.x - s.z * sb / cb;
        let wheelbase = c5.x;
        let p = flip();
        let frame_i =
            p * a * xz_tensor(self.frame_ixx, self.frame_iyy, self.frame_izz, self.frame_ixz) * a.transpose() * p;
        let fork_i = p * a * xz_tensor(self.fork_ixx, self.fork_iyy, self.fork_izz, self.fork_ixz) * a.transpose() * p;
        Ok(BenchmarkParameters {
            wheelbase,
            trail: ground_x - wheelbase,
            steer_axis_tilt: -beta,
            g: self.g,
            rear_wheel_radius: self.rear_wheel_radius,
            rear_wheel_mass: self.rear_wheel_mass,
            rear_wheel_ixx: self.rear_wheel_i_diametral,
            rear_wheel_iyy: self.rear_wheel_i_axial,
            rear_frame_com_x: frame_com.x,
            rear_frame_com_z: -frame_com.z,
            rear_frame_mass: self.frame_mass,
            rear_frame_ixx: frame_i[(0, 0)],
            rear_frame_iyy: frame_i[(1, 1)],
            rear_frame_izz: frame_i[(2, 2)],
            rear_frame_ixz: frame_i[(0, 2)],
            front_frame_com_x: fork_com.x,
            front_frame_com_z: -fork_com.z,
            front_frame_mass: self.fork_mass,
            front_frame_ixx: fork_i[(0, 0)],
            front_frame_iyy: fork_i[(1, 1)],
            front_frame_izz: fork_i[(2, 2)],
            front_frame_ixz: fork_i[(0, 2)],
            front_wheel_radius: self.front_wheel_radius,
            front_wheel_mass: self.front_wheel_mass,
            front_wheel_ixx: self.front_wheel_i_diametral,
            front_wheel_iyy: self.front_wheel_i_axial,
        })
    }
}

impl BenchmarkParameters {
    /// Convert to the thesis form, upright with zero steer (the inverse of
    /// [`ThesisParameters::to_benchmark`], whose docs give the geometry).
    ///
    /// `beta = -lam`. The steer axis passes through `(w + c, 0, 0)` with
    /// direction `(sin b, 0, cos b)`; the steer-axis point `S` is the foot of
    /// the perpendicular from the front-frame mass centre `H` onto it, so
    /// `d4` (the signed distance of `H` from the axis along the frame x axis)
    /// is in general non-zero. `[x4, z4] = A^T (S - C2)`,
    /// `[x5, z5] = A^T (C5 - S)` with `C5 = (w, 0, rF)`,
    /// `[x3, z3] = A^T (B - C2)`; tensors `A^T P I P A`.
    ///
    /// Errors: [`ParameterError::NotFinite`] for NaN or infinite values,
    /// [`ParameterError::NonPositive`] for `w <= 0`,
    /// [`ParameterError::TiltOutOfRange`] for `|lam| >= pi/2`.
    pub fn to_thesis(&self) -> Result<ThesisParameters, ParameterError> {
        check_finite(&Self::SYMBOLS, |k| self.get(k))?;
        if self.wheelbase <= 0.0 {
            return Err(ParameterError::NonPositive {
                field: "w".to_string(),
                value: self.wheelbase,
                origin: Default::default(),
            });
        }
        if !(self.steer_axis_tilt.abs() < std::f64::consts::FRAC_PI_2) {
            return Err(ParameterError::TiltOutOfRange {
                field: "lam".to_string(),
                value: self.steer_axis_tilt,
                origin: Default::default(),
            });
        }
        let beta = -self.steer_axis_tilt;
        let a = pitch(beta);
        let at = a.transpose();
        let ex: Vector3<f64> = a.column(0).into();
        let axis: Vector3<f64> = a.column(2).into();
        // Benchmark z is down: a point (x, z_bench) is (x, 0, -z_bench) here.
        let c2 = point(0.0, self.rear_wheel_radius);
        let c5 = point(self.wheelbase, self.front_wheel_radius);
        let ground = point(self.wheelbase + self.trail, 0.0);
        let fork_com = point(self.front_frame_com_x, -self.front_frame_com_z);
        let frame_com = point(self.rear_frame_com_x, -self.rear_frame_com_z);
        let s = ground + axis * (fork_com - ground).dot(&axis);
        let steer_point = at * (s - c2);
        let front_wheel = at * (c5 - s);
        let frame_point = at * (frame_com - c2);
        let p = flip();
        let frame_i = at
            * p
            * xz_tensor(
                self.rear_frame_ixx,
                self.rear_frame_iyy,
                self.rear_frame_izz,
                self.rear_frame_ixz,
            )
            * p
            * a;
        let fork_i = at
            * p
            * xz_tensor(
                self.front_frame_ixx,
                self.front_frame_iyy,
                self.front_frame_izz,
                self.front_frame_ixz,
            )
            * p
            * a;
        Ok(ThesisParameters {
            rear_wheel_radius: self.rear_wheel_radius,
            front_wheel_radius: self.front_wheel_radius,
            frame_com_x: frame_point.x,
            frame_com_z: frame_point.z,
            steer_point_x: steer_point.x,
            steer_point_z: steer_point.z,
            front_wheel_x: front_wheel.x,
            front_wheel_z: front_wheel.z,
            fork_com_offset: (fork_com - s).dot(&ex),
            rear_wheel_mass: self.rear_wheel_mass,
            frame_mass: self.rear_frame_mass,
            fork_mass: self.front_frame_mass,
            front_wheel_mass: self.front_wheel_mass,
            rear_wheel_i_diametral: self.rear_wheel_ixx,
            rear_wheel_i_axial: self.rear_wheel_iyy,
            frame_ixx: frame_i[(0, 0)],
            frame_iyy: frame_i[(1, 1)],
            frame_izz: frame_i[(2, 2)],
            frame_ixz: frame_i[(0, 2)],
            fork_ixx: fork_i[(0, 0)],
            fork_iyy: fork_i[(1, 1)],
            fork_izz: fork_i[(2, 2)],
            fork_ixz: fork_i[(0, 2)],
            front_wheel_i_diametral: self.front_wheel_ixx,
            front_wheel_i_axial: self.front_wheel_iyy,
            g: self.g,
        })
    }
}

/// [`ThesisParameters::to_benchmark`] over any [`Scalar`]: thesis values in
/// the order of [`ThesisParameters::SYMBOLS`] to benchmark values in the
/// order of [`BenchmarkParameters::SYMBOLS`]. With dual numbers seeded on
/// the thesis values it gives the exact Jacobian of the conversion (the
/// sensitivities in thesis symbols are the benchmark ones through it).
/// `beta` is the frame pitch [`ThesisParameters::frame_pitch`] found for the
/// real parts (it picks the root's branch; the derivatives follow from the
/// ground-contact condition `Rt - sin(b) (x4 + x5) + cos(b) (z4 + z5) = Rd`
/// at that root).
pub fn thesis_to_benchmark_in<T: Scalar>(t: &[T; 26], beta: f64) -> [T; 26] {
    let [rt, rd, x3, z3, x4, z4, x5, z5, d4, m2, m3, m4, m5, i2x, i2y, i3x, i3y, i3z, i3zx, i4x, i4y, i4z, i4xz, i5x, i5y, g] =
        *t;
    // beta = acos(d / R) - atan2(p, q); atan2 differs from atan(p / q) or
    // pi/2 - atan(q / p) by a constant, so either carries its derivatives
    // (the one whose argument is at most 1 in size, away from a pole).
    let p = x4 + x5;
    let q = z4 + z5;
    let d = rd - rt;
    let reach = (p * p + q * q).sqrt();
    let angle = if q.re().abs() >= p.re().abs() {
        (p / q).atan()
    } else {
        T::cst(std::f64::consts::FRAC_PI_2) - (q / p).atan()
    };
    let b = (d / reach).acos() - angle;
    let b = b + T::cst(beta - b.re());
    let (sb, cb) = b.sin_cos();
    // Points (x, Z up) of the thesis axes.
    let sx = cb * x4 + sb * z4;
    let sz = rt - sb * x4 + cb * z4;
    let wheelbase = sx + cb * x5 + sb * z5;
    let ground_x = sx - sz * sb / cb;
    let frame_x = cb * x3 + sb * z3;
    let frame_z = rt - sb * x3 + cb * z3;
    let fork_x = sx + cb * d4;
    let fork_z = sz - sb * d4;
    // P A I A^T P for I = [[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]: the xz
    // block rotated by beta, its xz entry's sign flipped by P.
    let two = T::cst(2.0);
    let tensor = |xx: T, zz: T, xz: T| {
        (
            cb * cb * xx + two * cb * sb * xz + sb * sb * zz,
            sb * sb * xx - two * sb * cb * xz + cb * cb * zz,
            -(-cb * sb * xx + (cb * cb - sb * sb) * xz + sb * cb * zz),
        )
    };
    let (ibxx, ibzz, ibxz) = tensor(i3x, i3z, i3zx);
    let (ihxx, ihzz, ihxz) = tensor(i4x, i4z, i4xz);
    [
        wheelbase,
        ground_x - wheelbase,
        -b,
        g,
        rt,
        m2,
        i2x,
        i2y,
        frame_x,
        -frame_z,
        m3,
        ibxx,
        i3y,
        ibzz,
        ibxz,
        fork_x,
        -fork_z,
        m4,
        ihxx,
        i4y,
        ihzz,
        ihxz,
        rd,
        m5,
        i5x,
        i5y,
    ]
}

#[cfg(test)]
mod generic_tests {
    use super::*;

    /// The generic conversion gives `to_benchmark`'s values, for the
    /// thesis bicycle and for the benchmark's thesis form (offset fork).
    #[test]
    fn generic_conversion_matches_to_benchmark() {
        for t in [
            ThesisParameters::thesis_bicycle(),
            BenchmarkParameters::benchmark_bicycle().to_thesis().unwrap(),
        ] {
            let b = t.to_benchmark().unwrap();
            let x = thesis_to_benchmark_in(&t.values(), t.frame_pitch().unwrap());
            for (k, sym) in BenchmarkParameters::SYMBOLS.iter().enumerate() {
                let want = b.get(sym).unwrap();
                assert!(
                    (x[k] - want).abs() <= 1e-13 * want.abs().max(1.0),
                    "{sym}: {} vs {want}",
                    x[k]
                );
            }
        }
    }
}
