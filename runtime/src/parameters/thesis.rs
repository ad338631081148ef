//! Thesis-form parameters (SI units). Axes of the thesis: X forward, Y left,
//! Z up. Body 2 rear wheel, 3 rear frame, 4 handlebar + fork, 5 front wheel.
//! Frame axes (body 3): z along the steer axis pointing up, x perpendicular to
//! it pointing forward; fork axes (body 4) are the frame axes turned by the
//! steer angle about z.

use serde::{Deserialize, Serialize};

/// Parameters of the thesis model, field names are physical, TOML keys are the
/// thesis symbols (`Rt`, `x3`, `I3zx`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThesisParameters {
    /// `Rt`: rear wheel radius (m).
    #[serde(rename = "Rt")]
    pub rear_wheel_radius: f64,
    /// `Rd`: front wheel radius (m).
    #[serde(rename = "Rd")]
    pub front_wheel_radius: f64,
    /// `x3`: rear-frame mass centre from the rear wheel centre, frame x (m).
    #[serde(rename = "x3")]
    pub frame_com_x: f64,
    /// `z3`: rear-frame mass centre from the rear wheel centre, frame z (m).
    #[serde(rename = "z3")]
    pub frame_com_z: f64,
    /// `x4`: steer-axis point (the fork mass centre in the thesis model) from
    /// the rear wheel centre, frame x (m).
    #[serde(rename = "x4")]
    pub steer_point_x: f64,
    /// `z4`: same point, frame z (m).
    #[serde(rename = "z4")]
    pub steer_point_z: f64,
    /// `x5`: front wheel centre from the steer-axis point, fork x (m).
    #[serde(rename = "x5")]
    pub front_wheel_x: f64,
    /// `z5`: front wheel centre from the steer-axis point, fork z (m).
    #[serde(rename = "z5")]
    pub front_wheel_z: f64,
    /// `d4`: handlebar/fork mass centre ahead of the steer axis, fork x (m).
    /// Zero in the thesis model (section 3.5.1.2); needed for the benchmark.
    #[serde(rename = "d4", default)]
    pub fork_com_offset: f64,
    /// `m2`: rear wheel mass (kg).
    #[serde(rename = "m2")]
    pub rear_wheel_mass: f64,
    /// `m3`: rear frame mass (kg).
    #[serde(rename = "m3")]
    pub frame_mass: f64,
    /// `m4`: handlebar + fork mass (kg).
    #[serde(rename = "m4")]
    pub fork_mass: f64,
    /// `m5`: front wheel mass (kg).
    #[serde(rename = "m5")]
    pub front_wheel_mass: f64,
    /// `I2x`: rear wheel moment about a diameter (kg m^2).
    #[serde(rename = "I2x")]
    pub rear_wheel_i_diametral: f64,
    /// `I2y`: rear wheel moment about its axle (kg m^2).
    #[serde(rename = "I2y")]
    pub rear_wheel_i_axial: f64,
    /// `I3x`: rear frame inertia, frame axes, xx (kg m^2).
    #[serde(rename = "I3x")]
    pub frame_ixx: f64,
    /// `I3y` (kg m^2).
    #[serde(rename = "I3y")]
    pub frame_iyy: f64,
    /// `I3z` (kg m^2).
    #[serde(rename = "I3z")]
    pub frame_izz: f64,
    /// `I3zx`: tensor entry xz = zx (kg m^2).
    #[serde(rename = "I3zx")]
    pub frame_ixz: f64,
    /// `I4x`: handlebar + fork inertia, fork axes, xx (kg m^2).
    #[serde(rename = "I4x")]
    pub fork_ixx: f64,
    /// `I4y` (kg m^2).
    #[serde(rename = "I4y")]
    pub fork_iyy: f64,
    /// `I4z` (kg m^2).
    #[serde(rename = "I4z")]
    pub fork_izz: f64,
    /// `I4xz`: tensor entry xz = zx (kg m^2).
    #[serde(rename = "I4xz")]
    pub fork_ixz: f64,
    /// `I5x`: front wheel moment about a diameter (kg m^2).
    #[serde(rename = "I5x")]
    pub front_wheel_i_diametral: f64,
    /// `I5y`: front wheel moment about its axle (kg m^2).
    #[serde(rename = "I5y")]
    pub front_wheel_i_axial: f64,
    /// `g`: gravitational acceleration (m/s^2).
    pub g: f64,
}

impl ThesisParameters {
    /// Thesis symbols, in a fixed order (the single name table).
    pub const SYMBOLS: [&'static str; 26] = [
        "Rt", "Rd", "x3", "z3", "x4", "z4", "x5", "z5", "d4", "m2", "m3", "m4", "m5", "I2x", "I2y", "I3x", "I3y",
        "I3z", "I3zx", "I4x", "I4y", "I4z", "I4xz", "I5x", "I5y", "g",
    ];

    /// Values in the order of [`Self::SYMBOLS`] (`values()[i]` is
    /// `get(SYMBOLS[i])`), without comparing names.
    pub fn values(&self) -> [f64; 26] {
        [
            self.rear_wheel_radius,
            self.front_wheel_radius,
            self.frame_com_x,
            self.frame_com_z,
            self.steer_point_x,
            self.steer_point_z,
            self.front_wheel_x,
            self.front_wheel_z,
            self.fork_com_offset,
            self.rear_wheel_mass,
            self.frame_mass,
            self.fork_mass,
            self.front_wheel_mass,
            self.rear_wheel_i_diametral,
            self.rear_wheel_i_axial,
            self.frame_ixx,
            self.frame_iyy,
            self.frame_izz,
            self.frame_ixz,
            self.fork_ixx,
            self.fork_iyy,
            self.fork_izz,
            self.fork_ixz,
            self.front_wheel_i_diametral,
            self.front_wheel_i_axial,
            self.g,
        ]
    }

    /// Value by thesis symbol (the names the generated models use).
    pub fn get(&self, symbol: &str) -> Option<f64> {
        Some(match symbol {
            "Rt" => self.rear_wheel_radius,
            "Rd" => self.front_wheel_radius,
            "x3" => self.frame_com_x,
            "z3" => self.frame_com_z,
            "x4" => self.steer_point_x,
            "z4" => self.steer_point_z,
            "x5" => self.front_wheel_x,
            "z5" => self.front_wheel_z,
            "d4" => self.fork_com_offset,
            "m2" => self.rear_wheel_mass,
            "m3" => self.frame_mass,
            "m4" => self.fork_mass,
            "m5" => self.front_wheel_mass,
            "I2x" => self.rear_wheel_i_diametral,
            "I2y" => self.rear_wheel_i_axial,
            "I3x" => self.frame_ixx,
            "I3y" => self.frame_iyy,
            "I3z" => self.frame_izz,
            "I3zx" => self.frame_ixz,
            "I4x" => self.fork_ixx,
            "I4y" => self.fork_iyy,
            "I4z" => self.fork_izz,
            "I4xz" => self.fork_ixz,
            "I5x" => self.front_wheel_i_diametral,
            "I5y" => self.front_wheel_i_axial,
            "g" => self.g,
            _ => return None,
        })
    }

    /// The field of `symbol`, to set it (`None` for an unknown symbol).
    pub fn get_mut(&mut self, symbol: &str) -> Option<&mut f64> {
        Some(match symbol {
            "Rt" => &mut self.rear_wheel_radius,
            "Rd" => &mut self.front_wheel_radius,
            "x3" => &mut self.frame_com_x,
            "z3" => &mut self.frame_com_z,
            "x4" => &mut self.steer_point_x,
            "z4" => &mut self.steer_point_z,
            "x5" => &mut self.front_wheel_x,
            "z5" => &mut self.front_wheel_z,
            "d4" => &mut self.fork_com_offset,
            "m2" => &mut self.rear_wheel_mass,
            "m3" => &mut self.frame_mass,
            "m4" => &mut self.fork_mass,
            "m5" => &mut self.front_wheel_mass,
            "I2x" => &mut self.rear_wheel_i_diametral,
            "I2y" => &mut self.rear_wheel_i_axial,
            "I3x" => &mut self.frame_ixx,
            "I3y" => &mut self.frame_iyy,
            "I3z" => &mut self.frame_izz,
            "I3zx" => &mut self.frame_ixz,
            "I4x" => &mut self.fork_ixx,
            "I4y" => &mut self.fork_iyy,
            "I4z" => &mut self.fork_izz,
            "I4xz" => &mut self.fork_ixz,
            "I5x" => &mut self.front_wheel_i_diametral,
            "I5y" => &mut self.front_wheel_i_axial,
            "g" => &mut self.g,
            _ => return None,
        })
    }
}

/// The thesis bicycle as TOML (`runtime/data/thesis_bicycle.toml`), embedded.
/// Loads to exactly [`ThesisParameters::thesis_bicycle`].
pub const THESIS_BICYCLE_TOML: &str = include_str!("../../data/thesis_bicycle.toml");

impl ThesisParameters {
    /// The instrumented bicycle of the thesis (section 4.4, eq. 72,
    /// `Parametros.m`).
    ///
    /// `x4, z4, x5, z5` are computed exactly as `Parametros.m` does: the
    /// measured points `(0.893746, 0.349845)` and `(0.129668, -0.349845)` are
    /// rotated by `betaf = 5.96817301822878` rad with
    /// `A23 = [[cos betaf, -sin betaf], [sin betaf, cos betaf]]`, giving about
    /// `x4 = 0.9582, z4 = 0.0557, x5 = 0.0149, z5 = -0.3728` m. `d4 = 0` (the
    /// thesis model puts the handlebar/fork mass centre on the steer axis).
    ///
    /// Its handlebar (I4) and front-wheel (I5) tensors violate the triangle
    /// inequality of principal moments; [`validate`](Self::validate) reports
    /// that as two warnings.
    pub fn thesis_bicycle() -> Self {
        let betaf: f64 = 5.96817301822878;
        let (s, c) = betaf.sin_cos();
        let rotate = |a: f64, b: f64| (c * a - s * b, s * a + c * b);
        let (x4, z4) = rotate(0.893746, 0.349845);
        let (x5, z5) = rotate(0.129668, -0.349845);
        ThesisParameters {
            rear_wheel_radius: 0.3199,
            front_wheel_radius: 0.3199,
            frame_com_x: 0.4633,
            frame_com_z: 0.0367,
            steer_point_x: x4,
            steer_point_z: z4,
            front_wheel_x: x5,
            front_wheel_z: z5,
            fork_com_offset: 0.0,
            rear_wheel_mass: 2.52,
            frame_mass: 6.862,
            fork_mass: 2.96,
            front_wheel_mass: 1.96,
            rear_wheel_i_diametral: 0.0884,
            rear_wheel_i_axial: 0.1357,
            frame_ixx: 0.3295,
            frame_iyy: 1.1843,
            frame_izz: 1.2506,
            frame_ixz: 0.0646,
            fork_ixx: 0.3056,
            fork_iyy: 0.158,
            fork_izz: 0.0385,
            fork_ixz: -0.0385,
            front_wheel_i_diametral: 0.0525,
            front_wheel_i_axial: 0.119,
            g: 9.81,
        }
    }

    /// Build a set by asking `value` for every symbol of [`Self::SYMBOLS`]
    /// (in that order); the first error is returned.
    pub fn from_lookup<E>(mut value: impl FnMut(&'static str) -> Result<f64, E>) -> Result<Self, E> {
        Ok(ThesisParameters {
            rear_wheel_radius: value("Rt")?,
            front_wheel_radius: value("Rd")?,
            frame_com_x: value("x3")?,
            frame_com_z: value("z3")?,
            steer_point_x: value("x4")?,
            steer_point_z: value("z4")?,
            front_wheel_x: value("x5")?,
            front_wheel_z: value("z5")?,
            fork_com_offset: value("d4")?,
            rear_wheel_mass: value("m2")?,
            frame_mass: value("m3")?,
            fork_mass: value("m4")?,
            front_wheel_mass: value("m5")?,
            rear_wheel_i_diametral: value("I2x")?,
            rear_wheel_i_axial: value("I2y")?,
            frame_ixx: value("I3x")?,
            frame_iyy: value("I3y")?,
            frame_izz: value("I3z")?,
            frame_ixz: value("I3zx")?,
            fork_ixx: value("I4x")?,
            fork_iyy: value("I4y")?,
            fork_izz: value("I4z")?,
            fork_ixz: value("I4xz")?,
            front_wheel_i_diametral: value("I5x")?,
            front_wheel_i_axial: value("I5y")?,
            g: value("g")?,
        })
    }

    /// One-line description and unit of each symbol (for comments in written
    /// TOML).
    pub fn describe(symbol: &str) -> Option<&'static str> {
        Some(match symbol {
            "Rt" => "rear wheel radius (m)",
            "Rd" => "front wheel radius (m)",
            "x3" => "rear-frame mass centre from the rear wheel centre, frame x (m)",
            "z3" => "rear-frame mass centre from the rear wheel centre, frame z (m)",
            "x4" => "steer-axis point from the rear wheel centre, frame x (m)",
            "z4" => "steer-axis point from the rear wheel centre, frame z (m)",
            "x5" => "front wheel centre from the steer-axis point, fork x (m)",
            "z5" => "front wheel centre from the steer-axis point, fork z (m)",
            "d4" => "handlebar/fork mass centre ahead of the steer axis, fork x (m)",
            "m2" => "rear wheel mass (kg)",
            "m3" => "rear frame mass (kg)",
            "m4" => "handlebar + fork mass (kg)",
            "m5" => "front wheel mass (kg)",
            "I2x" => "rear wheel moment about a diameter (kg m^2)",
            "I2y" => "rear wheel moment about its axle (kg m^2)",
            "I3x" => "rear frame inertia xx, frame axes (kg m^2)",
            "I3y" => "rear frame inertia yy, frame axes (kg m^2)",
            "I3z" => "rear frame inertia zz, frame axes (kg m^2)",
            "I3zx" => "rear frame inertia xz = zx, frame axes (kg m^2)",
            "I4x" => "handlebar + fork inertia xx, fork axes (kg m^2)",
            "I4y" => "handlebar + fork inertia yy, fork axes (kg m^2)",
            "I4z" => "handlebar + fork inertia zz, fork axes (kg m^2)",
            "I4xz" => "handlebar + fork inertia xz = zx, fork axes (kg m^2)",
            "I5x" => "front wheel moment about a diameter (kg m^2)",
            "I5y" => "front wheel moment about its axle (kg m^2)",
            "g" => "gravitational acceleration (m/s^2)",
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_follow_the_symbol_order() {
        let t = ThesisParameters::thesis_bicycle();
        let v = t.values();
        for (i, s) in ThesisParameters::SYMBOLS.iter().enumerate() {
            assert_eq!(Some(v[i]), t.get(s), "{s}");
        }
    }
}
