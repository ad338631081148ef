//! Physical validation of both parameter forms.
//!
//! Errors: any value NaN or infinite ([`ParameterError::NotFinite`]); a
//! wheelbase, `g`, rear-frame mass, radius, mass or diagonal inertia that is
//! not > 0 ([`ParameterError::NonPositive`]); an inertia tensor that is not
//! positive definite ([`ParameterError::NonPhysicalInertia`]). Warning:
//! principal moments that violate the triangle inequality
//! ([`ParameterWarning::TriangleInequality`]).
//!
//! Degenerate bodies are the one exception to "> 0", because measured sets
//! use them (the two-mass-skate bicycle, Kooijman et al. 2011,
//! `TmsBenchmark.txt`): a wheel radius may be 0 (a skate); a body's whole
//! inertia tensor may be 0 (a point mass); a wheel or the front frame may
//! have mass 0 together with a zero tensor (no body). Each such case is
//! reported as [`ParameterWarning::Degenerate`]. Zero mass with a non-zero
//! tensor, or a zero diagonal in a non-zero tensor, is still an error.
//!
//! Every body tensor of both forms has the symmetric "xz-coupled" shape
//! `[[xx, 0, xz], [0, yy, 0], [xz, 0, zz]]` (wheels: `xz = 0`, `zz = xx`), so
//! the principal moments are `yy` and the two eigenvalues of the 2x2 xz block,
//! computed in closed form.

use super::{BenchmarkParameters, ParameterError, ParameterWarning, ThesisParameters};

/// Body names used in errors and warnings of both forms.
pub mod body {
    /// Rear wheel (thesis body 2, benchmark R).
    pub const REAR_WHEEL: &str = "rear wheel";
    /// Rear frame, with the rider if any (thesis body 3, benchmark B).
    pub const REAR_FRAME: &str = "rear frame";
    /// Handlebar and fork (thesis body 4, benchmark H).
    pub const HANDLEBAR: &str = "handlebar";
    /// Front wheel (thesis body 5, benchmark F).
    pub const FRONT_WHEEL: &str = "front wheel";
}

/// A (symbol, value) pair.
type Field = (&'static str, f64);

/// One body: mass, optional wheel radius, and its tensor in the xz-coupled
/// shape (`zz` is the symbol of `xx` for wheels, `xz` is 0 for them).
struct Body {
    name: &'static str,
    mass: Field,
    radius: Option<Field>,
    /// Whether the mass may be zero (with a zero tensor): not for the rear frame.
    may_vanish: bool,
    xx: Field,
    yy: Field,
    zz: Field,
    xz: f64,
}

fn non_positive((field, value): Field) -> ParameterError {
    ParameterError::NonPositive {
        field: field.to_string(),
        value,
        origin: Default::default(),
    }
}

impl Body {
    /// Principal moments, largest first.
    fn principal(&self) -> [f64; 3] {
        let (xx, yy, zz) = (self.xx.1, self.yy.1, self.zz.1);
        let mean = 0.5 * (xx + zz);
        let radius = (0.5 * (xx - zz)).hypot(self.xz);
        let mut p = [mean + radius, yy, mean - radius];
        p.sort_by(|a, b| b.total_cmp(a));
        p
    }

    fn check(&self, warnings: &mut Vec<ParameterWarning>) -> Result<(), ParameterError> {
        let degenerate = |what| ParameterWarning::Degenerate { body: self.name, what };
        if let Some(r) = self.radius {
            if r.1 < 0.0 {
                return Err(non_positive(r));
            }
            if r.1 == 0.0 {
                warnings.push(degenerate("zero radius (a skate)"));
            }
        }
        let diagonal = [self.xx, self.yy, self.zz];
        for d in diagonal {
            if d.1 < 0.0 {
                return Err(non_positive(d));
            }
        }
        let mass = self.mass;
        if mass.1 < 0.0 || (mass.1 == 0.0 && !self.may_vanish) {
            return Err(non_positive(mass));
        }
        let zero_tensor = diagonal.iter().all(|d| d.1 == 0.0) && self.xz == 0.0;
        if zero_tensor {
            warnings.push(degenerate(if mass.1 == 0.0 {
                "no mass and no inertia"
            } else {
                "point mass (zero inertia tensor)"
            }));
            return Ok(());
        }
        if mass.1 == 0.0 {
            // Inertia without mass.
            return Err(non_positive(mass));
        }
        if let Some(&d) = diagonal.iter().find(|d| d.1 == 0.0) {
            return Err(non_positive(d));
        }
        // Diagonals > 0: the tensor is positive definite iff the xz block's
        // determinant is > 0.
        let (xx, zz) = (self.xx.1, self.zz.1);
        let det = xx * zz - self.xz * self.xz;
        if det <= 0.0 {
            return Err(ParameterError::NonPhysicalInertia {
                body: self.name,
                ixx: xx,
                izz: zz,
                ixz: self.xz,
                det,
                origin: Default::default(),
            });
        }
        let p = self.principal();
        let excess = p[0] - p[1] - p[2];
        // A tolerance of a few ulps of the trace keeps a thin disc (Iyy = 2 Ixx
        // exactly, excess 0 up to rounding) from warning.
        let tol = 8.0 * f64::EPSILON * (p[0] + p[1] + p[2]);
        if excess > tol {
            warnings.push(ParameterWarning::TriangleInequality {
                body: self.name,
                principal: p,
                excess,
            });
        }
        Ok(())
    }
}

/// Shared checks: `values` are all (symbol, value) pairs, `positive` the
/// fields that must be > 0, `bodies` the four bodies.
fn validate_common(
    values: impl Iterator<Item = Field>,
    positive: &[Field],
    bodies: &[Body],
) -> Result<Vec<ParameterWarning>, ParameterError> {
    // The canonical matrices multiply up to four parameters per entry and the
    // characteristic quartic up to four entries: 1e20^12 stays finite.
    const LIMIT: f64 = 1e20;
    for (field, value) in values {
        if !value.is_finite() {
            return Err(ParameterError::NotFinite {
                field: field.to_string(),
                value,
                origin: Default::default(),
            });
        }
        if value.abs() > LIMIT {
            return Err(ParameterError::TooLarge {
                field: field.to_string(),
                value,
                limit: LIMIT,
                origin: Default::default(),
            });
        }
    }
    if let Some(&f) = positive.iter().find(|f| f.1 <= 0.0) {
        return Err(non_positive(f));
    }
    let mut warnings = Vec::new();
    for b in bodies {
        b.check(&mut warnings)?;
    }
    Ok(warnings)
}

/// Plausibility warnings shared by both forms: lengths over 10 m (probably
/// millimetres) and mass centres below the ground.
fn plausibility(lengths: &[Field], bench: Option<&BenchmarkParameters>, warnings: &mut Vec<ParameterWarning>) {
    for &(field, value) in lengths {
        if value.abs() > 10.0 {
            warnings.push(ParameterWarning::LooksLikeMillimetres { field, value });
        }
    }
    if let Some(b) = bench {
        // Benchmark z is down: a mass centre below the ground has z > 0.
        for (body, z) in [
            (body::REAR_FRAME, b.rear_frame_com_z),
            (body::HANDLEBAR, b.front_frame_com_z),
        ] {
            if z > 0.0 {
                warnings.push(ParameterWarning::MassCentreBelowGround { body, height: -z });
            }
        }
    }
}

impl ThesisParameters {
    /// Check the set: every value finite; `g` and the rear-frame mass > 0;
    /// radii, masses and diagonal inertias > 0 except for degenerate bodies;
    /// every non-zero body tensor positive definite.
    ///
    /// Degenerate bodies are allowed because measured sets use them (the
    /// two-mass-skate bicycle, `TmsBenchmark.txt`): a wheel radius may be 0 (a
    /// skate), a body's whole tensor may be 0 (a point mass), a wheel or the
    /// handlebar may have mass 0 with a zero tensor (no body); each is
    /// reported as [`ParameterWarning::Degenerate`]. Zero mass with a non-zero
    /// tensor, or a zero diagonal in a non-zero tensor, is an error.
    ///
    /// Returns the warnings (e.g. [`ParameterWarning::TriangleInequality`];
    /// [`ThesisParameters::thesis_bicycle`] has two, for the handlebar and the
    /// front wheel). The first problem found is the error; errors carry no
    /// file name here (loaders add it).
    ///
    /// The geometry must be an upright bicycle's
    /// ([`ParameterError::ImpossibleGeometry`]: no frame pitch puts the
    /// front wheel on the ground ahead with the steer axis within 90 degrees
    /// of vertical).
    ///
    /// Plausibility warnings: a length over 10 m
    /// ([`ParameterWarning::LooksLikeMillimetres`]) and a frame or handlebar
    /// mass centre below the ground ([`ParameterWarning::MassCentreBelowGround`]).
    pub fn validate(&self) -> Result<Vec<ParameterWarning>, ParameterError> {
        let mut warnings = self.validate_bodies()?;
        self.check_geometry()?;
        let s = self;
        let lengths = [
            ("Rt", s.rear_wheel_radius),
            ("Rd", s.front_wheel_radius),
            ("x3", s.frame_com_x),
            ("z3", s.frame_com_z),
            ("x4", s.steer_point_x),
            ("z4", s.steer_point_z),
            ("x5", s.front_wheel_x),
            ("z5", s.front_wheel_z),
            ("d4", s.fork_com_offset),
        ];
        plausibility(&lengths, self.to_benchmark().ok().as_ref(), &mut warnings);
        Ok(warnings)
    }

    /// The geometry is an upright bicycle's: a frame pitch puts the front
    /// wheel on the ground ahead of the rear one with the steer axis less
    /// than 90 degrees from vertical (the benchmark form's tilt range).
    /// Every command and the Python package validate through here, so a
    /// set such as `x4 = -1` (a tilt of 2.83 rad) is refused by all of
    /// them, naming the field.
    fn check_geometry(&self) -> Result<(), ParameterError> {
        let s = self;
        let (problem, radius) = match self.frame_pitch() {
            Ok(_) => return Ok(()),
            Err(ParameterError::SteerAxisNotUpright { tilt }) => (
                format!(
                    "gives a steer-axis tilt of {} rad ({} deg), outside (-pi/2, pi/2) rad",
                    crate::number_text::format_significant(tilt, 3),
                    crate::number_text::format_significant(tilt.to_degrees(), 3)
                ),
                None,
            ),
            // The larger wheel cannot reach the ground: name its radius.
            Err(e @ ParameterError::NoGroundContact { .. }) => (
                format!("gives {e}"),
                Some(if s.front_wheel_radius > s.rear_wheel_radius {
                    ("Rd", s.front_wheel_radius)
                } else {
                    ("Rt", s.rear_wheel_radius)
                }),
            ),
            Err(e) => return Err(e),
        };
        let (field, value) = if let Some(r) = radius {
            r
        } else if s.steer_point_x <= 0.0 {
            ("x4", s.steer_point_x)
        } else if s.front_wheel_z >= 0.0 {
            ("z5", s.front_wheel_z)
        } else {
            ("x4", s.steer_point_x)
        };
        Err(ParameterError::ImpossibleGeometry {
            field: field.to_string(),
            value,
            problem,
            origin: Default::default(),
        })
    }

    fn validate_bodies(&self) -> Result<Vec<ParameterWarning>, ParameterError> {
        let s = self;
        validate_common(
            Self::SYMBOLS.iter().map(|&k| (k, s.get(k).unwrap_or(f64::NAN))),
            &[("g", s.g)],
            &[
                Body {
                    name: body::REAR_WHEEL,
                    mass: ("m2", s.rear_wheel_mass),
                    radius: Some(("Rt", s.rear_wheel_radius)),
                    may_vanish: true,
                    xx: ("I2x", s.rear_wheel_i_diametral),
                    yy: ("I2y", s.rear_wheel_i_axial),
                    zz: ("I2x", s.rear_wheel_i_diametral),
                    xz: 0.0,
                },
                Body {
                    name: body::REAR_FRAME,
                    mass: ("m3", s.frame_mass),
                    radius: None,
                    may_vanish: false,
                    xx: ("I3x", s.frame_ixx),
                    yy: ("I3y", s.frame_iyy),
                    zz: ("I3z", s.frame_izz),
                    xz: s.frame_ixz,
                },
                Body {
                    name: body::HANDLEBAR,
                    mass: ("m4", s.fork_mass),
                    radius: None,
                    may_vanish: true,
                    xx: ("I4x", s.fork_ixx),
                    yy: ("I4y", s.fork_iyy),
                    zz: ("I4z", s.fork_izz),
                    xz: s.fork_ixz,
                },
                Body {
                    name: body::FRONT_WHEEL,
                    mass: ("m5", s.front_wheel_mass),
                    radius: Some(("Rd", s.front_wheel_radius)),
                    may_vanish: true,
                    xx: ("I5x", s.front_wheel_i_diametral),
                    yy: ("I5y", s.front_wheel_i_axial),
                    zz: ("I5x", s.front_wheel_i_diametral),
                    xz: 0.0,
                },
            ],
        )
    }
}

impl BenchmarkParameters {
    /// Check the set: every value finite; `w`, `g` and `mB` > 0; radii,
    /// masses and diagonal inertias > 0 except for degenerate bodies (zero
    /// radius, zero tensor, no body: see [`ThesisParameters::validate`]), each
    /// reported as [`ParameterWarning::Degenerate`]; every non-zero body
    /// tensor positive definite.
    ///
    /// Returns the warnings (e.g. [`ParameterWarning::TriangleInequality`]).
    /// The first problem found is the error; errors carry no file name here
    /// (loaders add it).
    ///
    /// The steer-axis tilt must be within `(-pi/2, pi/2)` rad
    /// ([`ParameterError::TiltOutOfRange`], whose message suggests the value in
    /// radians when it looks like degrees). Plausibility warnings: a length
    /// over 10 m ([`ParameterWarning::LooksLikeMillimetres`]) and a frame or
    /// handlebar mass centre below the ground
    /// ([`ParameterWarning::MassCentreBelowGround`]).
    pub fn validate(&self) -> Result<Vec<ParameterWarning>, ParameterError> {
        let mut warnings = self.validate_bodies()?;
        let s = self;
        if !(s.steer_axis_tilt.abs() < std::f64::consts::FRAC_PI_2) {
            return Err(ParameterError::TiltOutOfRange {
                field: "lam".to_string(),
                value: s.steer_axis_tilt,
                origin: Default::default(),
            });
        }
        let lengths = [
            ("w", s.wheelbase),
            ("c", s.trail),
            ("rR", s.rear_wheel_radius),
            ("rF", s.front_wheel_radius),
            ("xB", s.rear_frame_com_x),
            ("zB", s.rear_frame_com_z),
            ("xH", s.front_frame_com_x),
            ("zH", s.front_frame_com_z),
        ];
        plausibility(&lengths, Some(self), &mut warnings);
        Ok(warnings)
    }

    fn validate_bodies(&self) -> Result<Vec<ParameterWarning>, ParameterError> {
        let s = self;
        validate_common(
            Self::SYMBOLS.iter().map(|&k| (k, s.get(k).unwrap_or(f64::NAN))),
            &[("w", s.wheelbase), ("g", s.g)],
            &[
                Body {
                    name: body::REAR_WHEEL,
                    mass: ("mR", s.rear_wheel_mass),
                    radius: Some(("rR", s.rear_wheel_radius)),
                    may_vanish: true,
                    xx: ("IRxx", s.rear_wheel_ixx),
                    yy: ("IRyy", s.rear_wheel_iyy),
                    zz: ("IRxx", s.rear_wheel_ixx),
                    xz: 0.0,
                },
                Body {
                    name: body::REAR_FRAME,
                    mass: ("mB", s.rear_frame_mass),
                    radius: None,
                    may_vanish: false,
                    xx: ("IBxx", s.rear_frame_ixx),
                    yy: ("IByy", s.rear_frame_iyy),
                    zz: ("IBzz", s.rear_frame_izz),
                    xz: s.rear_frame_ixz,
                },
                Body {
                    name: body::HANDLEBAR,
                    mass: ("mH", s.front_frame_mass),
                    radius: None,
                    may_vanish: true,
                    xx: ("IHxx", s.front_frame_ixx),
                    yy: ("IHyy", s.front_frame_iyy),
                    zz: ("IHzz", s.front_frame_izz),
                    xz: s.front_frame_ixz,
                },
                Body {
                    name: body::FRONT_WHEEL,
                    mass: ("mF", s.front_wheel_mass),
                    radius: Some(("rF", s.front_wheel_radius)),
                    may_vanish: true,
                    xx: ("IFxx", s.front_wheel_ixx),
                    yy: ("IFyy", s.front_wheel_iyy),
                    zz: ("IFxx", s.front_wheel_ixx),
                    xz: 0.0,
                },
            ],
        )
    }
}
