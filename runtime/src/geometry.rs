//! Derived geometry of a bicycle (issue 10, point 9): the quantities a
//! researcher reads next to the parameters, in the benchmark's axes (x
//! forward, z down, origin at the rear contact point), from the auxiliary
//! quantities of Meijaard et al. (2007), appendix A (eqs. A 1 - A 17).

use crate::parameters::BenchmarkParameters;
use serde::Serialize;

/// Derived geometry and mass distribution of an upright bicycle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DerivedGeometry {
    /// Wheelbase `w` (m).
    pub wheelbase: f64,
    /// Trail `c` (m).
    pub trail: f64,
    /// Steer-axis tilt from vertical `lam` (rad).
    pub steer_axis_tilt: f64,
    /// Steer-axis tilt in degrees.
    pub steer_axis_tilt_deg: f64,
    /// Total mass `mT` (kg, eq. A 1).
    pub total_mass: f64,
    /// Total mass centre ahead of the rear contact `xT` (m, eq. A 2).
    pub total_com_x: f64,
    /// Total mass centre height above the ground `-zT` (m, eq. A 3).
    pub total_com_height: f64,
    /// Front assembly (handlebar, fork and front wheel) mass `mA` (kg, eq. A 8).
    pub front_mass: f64,
    /// Distance of the front assembly's mass centre ahead of the steer axis
    /// `uA` (m, eq. A 14).
    pub front_com_offset: f64,
    /// Front assembly moment of inertia about the steer axis `IAll`
    /// (kg m^2, eq. A 15).
    pub front_steer_inertia: f64,
    /// Front assembly product of inertia about the steer axis and x, `IAlx`
    /// (kg m^2, eq. A 16).
    pub front_steer_x_product: f64,
    /// Front assembly product of inertia about the steer axis and z, `IAlz`
    /// (kg m^2, eq. A 17).
    pub front_steer_z_product: f64,
    /// Total yaw inertia about the rear contact `ITzz` (kg m^2, eq. A 6).
    pub total_izz: f64,
    /// Trail ratio `mu = (c / w) cos(lam)` (eq. A 18).
    pub trail_ratio: f64,
}

impl DerivedGeometry {
    /// Derived geometry of a benchmark-form set.
    pub fn of(p: &BenchmarkParameters) -> Self {
        let w = p.wheelbase;
        let c = p.trail;
        let lam = p.steer_axis_tilt;
        let (rr, mr) = (p.rear_wheel_radius, p.rear_wheel_mass);
        let (xb, zb, mb) = (p.rear_frame_com_x, p.rear_frame_com_z, p.rear_frame_mass);
        let (xh, zh, mh) = (p.front_frame_com_x, p.front_frame_com_z, p.front_frame_mass);
        let (rf, mf) = (p.front_wheel_radius, p.front_wheel_mass);
        let mt = mr + mb + mh + mf;
        let xt = (xb * mb + xh * mh + w * mf) / mt;
        let zt = (-rr * mr + zb * mb + zh * mh - rf * mf) / mt;
        let itzz = p.rear_wheel_ixx
            + p.rear_frame_izz
            + p.front_frame_izz
            + p.front_wheel_ixx
            + mb * xb * xb
            + mh * xh * xh
            + mf * w * w;
        let ma = mh + mf;
        // A front assembly without mass has its "mass centre" at the front
        // wheel centre (all terms below then vanish with ma).
        let (xa, za) = if ma > 0.0 {
            ((xh * mh + w * mf) / ma, (zh * mh - rf * mf) / ma)
        } else {
            (w, -rf)
        };
        let iaxx = p.front_frame_ixx + p.front_wheel_ixx + mh * (zh - za).powi(2) + mf * (rf + za).powi(2);
        let iaxz = p.front_frame_ixz - mh * (xh - xa) * (zh - za) + mf * (w - xa) * (rf + za);
        let iazz = p.front_frame_izz + p.front_wheel_ixx + mh * (xh - xa).powi(2) + mf * (w - xa).powi(2);
        let (sl, cl) = lam.sin_cos();
        let ua = (xa - w - c) * cl - za * sl;
        DerivedGeometry {
            wheelbase: w,
            trail: c,
            steer_axis_tilt: lam,
            steer_axis_tilt_deg: lam.to_degrees(),
            total_mass: mt,
            total_com_x: xt,
            total_com_height: -zt,
            front_mass: ma,
            front_com_offset: ua,
            front_steer_inertia: ma * ua * ua + iaxx * sl * sl + 2.0 * iaxz * sl * cl + iazz * cl * cl,
            front_steer_x_product: -ma * ua * za + iaxx * sl + iaxz * cl,
            front_steer_z_product: ma * ua * xa + iaxz * sl + iazz * cl,
            total_izz: itzz,
            trail_ratio: c / w * cl,
        }
    }

    /// `(symbol, value, unit, description)` rows for printing.
    pub fn rows(&self) -> Vec<(&'static str, f64, &'static str, &'static str)> {
        vec![
            ("w", self.wheelbase, "m", "wheelbase"),
            ("c", self.trail, "m", "trail"),
            ("lam", self.steer_axis_tilt, "rad", "steer-axis tilt from vertical"),
            (
                "lam_deg",
                self.steer_axis_tilt_deg,
                "deg",
                "steer-axis tilt from vertical",
            ),
            ("mT", self.total_mass, "kg", "total mass"),
            (
                "xT",
                self.total_com_x,
                "m",
                "total mass centre ahead of the rear contact",
            ),
            (
                "hT",
                self.total_com_height,
                "m",
                "total mass centre height above the ground",
            ),
            (
                "mA",
                self.front_mass,
                "kg",
                "front assembly (handlebar, fork, front wheel) mass",
            ),
            (
                "uA",
                self.front_com_offset,
                "m",
                "front assembly mass centre ahead of the steer axis",
            ),
            (
                "IAll",
                self.front_steer_inertia,
                "kg m^2",
                "front assembly inertia about the steer axis",
            ),
            (
                "IAlx",
                self.front_steer_x_product,
                "kg m^2",
                "front assembly product of inertia, steer axis and x",
            ),
            (
                "IAlz",
                self.front_steer_z_product,
                "kg m^2",
                "front assembly product of inertia, steer axis and z",
            ),
            (
                "ITzz",
                self.total_izz,
                "kg m^2",
                "total yaw inertia about the rear contact",
            ),
            ("mu", self.trail_ratio, "", "trail ratio (c/w) cos(lam)"),
        ]
    }
}
