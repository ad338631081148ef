//! Benchmark-form parameters of Meijaard et al. (2007), Table 1. Benchmark
//! axes: x forward, y right, z down; lengths m, masses kg, inertias kg m^2
//! about each body's mass centre. B = rear frame (with rider, if any),
//! H = front frame (handlebar and fork), R/F = rear/front wheel.

use serde::{Deserialize, Serialize};

/// Benchmark parameters; TOML/text keys are the Meijaard symbols.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BenchmarkParameters {
    /// `w`: wheelbase (m).
    #[serde(rename = "w")]
    pub wheelbase: f64,
    /// `c`: trail (m).
    #[serde(rename = "c")]
    pub trail: f64,
    /// `lam`: steer-axis tilt from vertical (rad).
    #[serde(rename = "lam")]
    pub steer_axis_tilt: f64,
    /// `g` (m/s^2).
    pub g: f64,
    /// `rR` (m).
    #[serde(rename = "rR")]
    pub rear_wheel_radius: f64,
    /// `mR` (kg).
    #[serde(rename = "mR")]
    pub rear_wheel_mass: f64,
    /// `IRxx`: rear wheel moment about a diameter (kg m^2).
    #[serde(rename = "IRxx")]
    pub rear_wheel_ixx: f64,
    /// `IRyy`: rear wheel moment about its axle (kg m^2).
    #[serde(rename = "IRyy")]
    pub rear_wheel_iyy: f64,
    /// `xB` (m).
    #[serde(rename = "xB")]
    pub rear_frame_com_x: f64,
    /// `zB` (m, z down: negative above ground).
    #[serde(rename = "zB")]
    pub rear_frame_com_z: f64,
    /// `mB` (kg).
    #[serde(rename = "mB")]
    pub rear_frame_mass: f64,
    /// `IBxx` (kg m^2).
    #[serde(rename = "IBxx")]
    pub rear_frame_ixx: f64,
    /// `IByy` (kg m^2).
    #[serde(rename = "IByy")]
    pub rear_frame_iyy: f64,
    /// `IBzz` (kg m^2).
    #[serde(rename = "IBzz")]
    pub rear_frame_izz: f64,
    /// `IBxz` (kg m^2).
    #[serde(rename = "IBxz")]
    pub rear_frame_ixz: f64,
    /// `xH` (m).
    #[serde(rename = "xH")]
    pub front_frame_com_x: f64,
    /// `zH` (m).
    #[serde(rename = "zH")]
    pub front_frame_com_z: f64,
    /// `mH` (kg).
    #[serde(rename = "mH")]
    pub front_frame_mass: f64,
    /// `IHxx` (kg m^2).
    #[serde(rename = "IHxx")]
    pub front_frame_ixx: f64,
    /// `IHyy` (kg m^2).
    #[serde(rename = "IHyy")]
    pub front_frame_iyy: f64,
    /// `IHzz` (kg m^2).
    #[serde(rename = "IHzz")]
    pub front_frame_izz: f64,
    /// `IHxz` (kg m^2).
    #[serde(rename = "IHxz")]
    pub front_frame_ixz: f64,
    /// `rF` (m).
    #[serde(rename = "rF")]
    pub front_wheel_radius: f64,
    /// `mF` (kg).
    #[serde(rename = "mF")]
    pub front_wheel_mass: f64,
    /// `IFxx` (kg m^2).
    #[serde(rename = "IFxx")]
    pub front_wheel_ixx: f64,
    /// `IFyy` (kg m^2).
    #[serde(rename = "IFyy")]
    pub front_wheel_iyy: f64,
}

impl BenchmarkParameters {
    /// Meijaard symbols in Table 1 order (the single name table).
    pub const SYMBOLS: [&'static str; 26] = [
        "w", "c", "lam", "g", "rR", "mR", "IRxx", "IRyy", "xB", "zB", "mB", "IBxx", "IByy", "IBzz", "IBxz", "xH", "zH",
        "mH", "IHxx", "IHyy", "IHzz", "IHxz", "rF", "mF", "IFxx", "IFyy",
    ];

    /// Value by Meijaard symbol.
    pub fn get(&self, symbol: &str) -> Option<f64> {
        Some(match symbol {
            "w" => self.wheelbase,
            "c" => self.trail,
            "lam" => self.steer_axis_tilt,
            "g" => self.g,
            "rR" => self.rear_wheel_radius,
            "mR" => self.rear_wheel_mass,
            "IRxx" => self.rear_wheel_ixx,
            "IRyy" => self.rear_wheel_iyy,
            "xB" => self.rear_frame_com_x,
            "zB" => self.rear_frame_com_z,
            "mB" => self.rear_frame_mass,
            "IBxx" => self.rear_frame_ixx,
            "IByy" => self.rear_frame_iyy,
            "IBzz" => self.rear_frame_izz,
            "IBxz" => self.rear_frame_ixz,
            "xH" => self.front_frame_com_x,
            "zH" => self.front_frame_com_z,
            "mH" => self.front_frame_mass,
            "IHxx" => self.front_frame_ixx,
            "IHyy" => self.front_frame_iyy,
            "IHzz" => self.front_frame_izz,
            "IHxz" => self.front_frame_ixz,
            "rF" => self.front_wheel_radius,
            "mF" => self.front_wheel_mass,
            "IFxx" => self.front_wheel_ixx,
            "IFyy" => self.front_wheel_iyy,
            _ => return None,
        })
    }

    /// The field of `symbol`, to set it (`None` for an unknown symbol).
    pub fn get_mut(&mut self, symbol: &str) -> Option<&mut f64> {
        Some(match symbol {
            "w" => &mut self.wheelbase,
            "c" => &mut self.trail,
            "lam" => &mut self.steer_axis_tilt,
            "g" => &mut self.g,
            "rR" => &mut self.rear_wheel_radius,
            "mR" => &mut self.rear_wheel_mass,
            "IRxx" => &mut self.rear_wheel_ixx,
            "IRyy" => &mut self.rear_wheel_iyy,
            "xB" => &mut self.rear_frame_com_x,
            "zB" => &mut self.rear_frame_com_z,
            "mB" => &mut self.rear_frame_mass,
            "IBxx" => &mut self.rear_frame_ixx,
            "IByy" => &mut self.rear_frame_iyy,
            "IBzz" => &mut self.rear_frame_izz,
            "IBxz" => &mut self.rear_frame_ixz,
            "xH" => &mut self.front_frame_com_x,
            "zH" => &mut self.front_frame_com_z,
            "mH" => &mut self.front_frame_mass,
            "IHxx" => &mut self.front_frame_ixx,
            "IHyy" => &mut self.front_frame_iyy,
            "IHzz" => &mut self.front_frame_izz,
            "IHxz" => &mut self.front_frame_ixz,
            "rF" => &mut self.front_wheel_radius,
            "mF" => &mut self.front_wheel_mass,
            "IFxx" => &mut self.front_wheel_ixx,
            "IFyy" => &mut self.front_wheel_iyy,
            _ => return None,
        })
    }
}

/// The Meijaard et al. (2007) benchmark bicycle as TOML
/// (`runtime/data/benchmark_bicycle.toml`), embedded. Loads to exactly
/// [`BenchmarkParameters::benchmark_bicycle`].
pub const BENCHMARK_BICYCLE_TOML: &str = include_str!("../../data/benchmark_bicycle.toml");

impl BenchmarkParameters {
    /// The benchmark bicycle of Meijaard, Papadopoulos, Ruina & Schwab (2007),
    /// Table 1, with `lam = pi/10` exactly (as an `f64`).
    pub fn benchmark_bicycle() -> Self {
        BenchmarkParameters {
            wheelbase: 1.02,
            trail: 0.08,
            steer_axis_tilt: std::f64::consts::PI / 10.0,
            g: 9.81,
            rear_wheel_radius: 0.3,
            rear_wheel_mass: 2.0,
            rear_wheel_ixx: 0.0603,
            rear_wheel_iyy: 0.12,
            rear_frame_com_x: 0.3,
            rear_frame_com_z: -0.9,
            rear_frame_mass: 85.0,
            rear_frame_ixx: 9.2,
            rear_frame_iyy: 11.0,
            rear_frame_izz: 2.8,
            rear_frame_ixz: 2.4,
            front_frame_com_x: 0.9,
            front_frame_com_z: -0.7,
            front_frame_mass: 4.0,
            front_frame_ixx: 0.05892,
            front_frame_iyy: 0.06,
            front_frame_izz: 0.00708,
            front_frame_ixz: -0.00756,
            front_wheel_radius: 0.35,
            front_wheel_mass: 3.0,
            front_wheel_ixx: 0.1405,
            front_wheel_iyy: 0.28,
        }
    }

    /// Build a set by asking `value` for every symbol of [`Self::SYMBOLS`]
    /// (in that order); the first error is returned.
    pub fn from_lookup<E>(mut value: impl FnMut(&'static str) -> Result<f64, E>) -> Result<Self, E> {
        Ok(BenchmarkParameters {
            wheelbase: value("w")?,
            trail: value("c")?,
            steer_axis_tilt: value("lam")?,
            g: value("g")?,
            rear_wheel_radius: value("rR")?,
            rear_wheel_mass: value("mR")?,
            rear_wheel_ixx: value("IRxx")?,
            rear_wheel_iyy: value("IRyy")?,
            rear_frame_com_x: value("xB")?,
            rear_frame_com_z: value("zB")?,
            rear_frame_mass: value("mB")?,
            rear_frame_ixx: value("IBxx")?,
            rear_frame_iyy: value("IByy")?,
            rear_frame_izz: value("IBzz")?,
            rear_frame_ixz: value("IBxz")?,
            front_frame_com_x: value("xH")?,
            front_frame_com_z: value("zH")?,
            front_frame_mass: value("mH")?,
            front_frame_ixx: value("IHxx")?,
            front_frame_iyy: value("IHyy")?,
            front_frame_izz: value("IHzz")?,
            front_frame_ixz: value("IHxz")?,
            front_wheel_radius: value("rF")?,
            front_wheel_mass: value("mF")?,
            front_wheel_ixx: value("IFxx")?,
            front_wheel_iyy: value("IFyy")?,
        })
    }

    /// One-line description and unit of each symbol (for comments in written
    /// TOML).
    pub fn describe(symbol: &str) -> Option<&'static str> {
        Some(match symbol {
            "w" => "wheelbase (m)",
            "c" => "trail (m)",
            "lam" => "steer-axis tilt from vertical (rad)",
            "g" => "gravitational acceleration (m/s^2)",
            "rR" => "rear wheel radius (m)",
            "mR" => "rear wheel mass (kg)",
            "IRxx" => "rear wheel moment about a diameter (kg m^2)",
            "IRyy" => "rear wheel moment about its axle (kg m^2)",
            "xB" => "rear-frame mass centre x (m)",
            "zB" => "rear-frame mass centre z, down (m)",
            "mB" => "rear frame mass (kg)",
            "IBxx" => "rear frame inertia xx (kg m^2)",
            "IByy" => "rear frame inertia yy (kg m^2)",
            "IBzz" => "rear frame inertia zz (kg m^2)",
            "IBxz" => "rear frame inertia xz (kg m^2)",
            "xH" => "front-frame mass centre x (m)",
            "zH" => "front-frame mass centre z, down (m)",
            "mH" => "front frame (handlebar + fork) mass (kg)",
            "IHxx" => "front frame inertia xx (kg m^2)",
            "IHyy" => "front frame inertia yy (kg m^2)",
            "IHzz" => "front frame inertia zz (kg m^2)",
            "IHxz" => "front frame inertia xz (kg m^2)",
            "rF" => "front wheel radius (m)",
            "mF" => "front wheel mass (kg)",
            "IFxx" => "front wheel moment about a diameter (kg m^2)",
            "IFyy" => "front wheel moment about its axle (kg m^2)",
            _ => return None,
        })
    }
}
