//! Errors and warnings of loading, validating and converting parameter sets.
//!
//! Errors are data-dependent failures with one variant per cause; every
//! message names the file (when there is one), the line (when there is one)
//! and the field. Warnings are returned beside a value that is still usable.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where a value came from: a file and, when known, the line of its key.
///
/// Displays as `""` when nothing is known, otherwise as ` (in FILE, line N)`,
/// so it can be appended to any message.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Origin {
    /// The file the value was read from (the name given for messages).
    pub path: Option<PathBuf>,
    /// 1-based line of the field's key in that file.
    pub line: Option<usize>,
}

impl Origin {
    /// An origin naming a file and, optionally, a line.
    pub fn new(path: &Path, line: Option<usize>) -> Self {
        Origin {
            path: Some(path.to_path_buf()),
            line,
        }
    }
}

impl fmt::Display for Origin {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.path, self.line) {
            (Some(p), Some(l)) => write!(f, " (in {}, line {l})", p.display()),
            (Some(p), None) => write!(f, " (in {})", p.display()),
            (None, Some(l)) => write!(f, " (line {l})"),
            (None, None) => Ok(()),
        }
    }
}

/// Everything that can go wrong while reading, validating or converting a
/// parameter set. Field names are the file symbols (`mB`, `m3`, `I4xz`, ...).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ParameterError {
    /// The file could not be read.
    #[error("cannot read parameter file {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },

    /// The file is not valid TOML.
    #[error("{}{}: invalid TOML: {message}", path.display(), fmt_line(*line))]
    Toml {
        /// The file.
        path: PathBuf,
        /// 1-based line of the error, when the parser reports a position.
        line: Option<usize>,
        /// The TOML parser's message.
        message: String,
    },

    /// A line of a text (`name = value`) file cannot be read.
    #[error("{}:{line}: cannot read `{text}`: {reason}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// The offending line (trimmed).
        text: String,
        /// What is wrong with it.
        reason: String,
    },

    /// A required parameter is absent.
    #[error("{}: missing parameter `{field}`", path.display())]
    MissingField {
        /// The file.
        path: PathBuf,
        /// The missing symbol.
        field: String,
    },

    /// Several required parameters are absent (all are listed).
    #[error("{}: missing {} parameters: {}", path.display(), fields.len(), fields.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", "))]
    MissingFields {
        /// The file.
        path: PathBuf,
        /// Every missing symbol, in the form's order.
        fields: Vec<String>,
    },

    /// The `[feedback]` table cannot be read.
    #[error("{}:{line}: [feedback]: {why}", path.display())]
    Feedback {
        /// The file.
        path: PathBuf,
        /// 1-based line of the offending key.
        line: usize,
        /// What is wrong.
        why: String,
    },

    /// A name that is not a parameter of the detected (or forced) form.
    #[error("{}:{line}: unknown parameter `{field}` ({why})", path.display())]
    UnknownField {
        /// The file.
        path: PathBuf,
        /// 1-based line of the name.
        line: usize,
        /// The unknown name.
        field: String,
        /// Why it is rejected (e.g. "not a thesis-form symbol").
        why: &'static str,
    },

    /// A raw measurement file of bicycleparameters (`<Name>Measured.txt`:
    /// pendulum periods, lengths and angles measured on the bicycle), not a
    /// parameter set: it must be processed into one first.
    #[error("{}:{line}: `{field}` is a raw measurement: this is a bicycleparameters `<Name>Measured.txt` file (pendulum periods, measured lengths and angles), not a parameter set; process it with bicycleparameters into `<Name>Benchmark.txt` and give that", path.display())]
    RawMeasurementFile { path: PathBuf, line: usize, field: String },

    /// The same parameter is given twice in a text file.
    #[error("{}:{line}: parameter `{field}` given twice (first on line {first_line})", path.display())]
    DuplicateField {
        /// The file.
        path: PathBuf,
        /// 1-based line of the repetition.
        line: usize,
        /// 1-based line of the first occurrence.
        first_line: usize,
        /// The repeated name.
        field: String,
    },

    /// A TOML value of the wrong type (parameters are numbers, `form` a string).
    #[error("{}:{line}: `{field}` must be {expected}, found {found}", path.display())]
    WrongType {
        /// The file.
        path: PathBuf,
        /// 1-based line of the key.
        line: usize,
        /// The key.
        field: String,
        /// What was expected.
        expected: &'static str,
        /// The TOML type found.
        found: &'static str,
    },

    /// A value is NaN or infinite.
    #[error("parameter `{field}` is not finite: {value:?}{origin}")]
    NotFinite {
        /// The symbol.
        field: String,
        /// The value.
        value: f64,
        /// File and line, when read from a file.
        origin: Origin,
    },

    /// A wheelbase, `g`, rear-frame mass, radius, mass or diagonal inertia
    /// that is not > 0 (zeros are allowed only for degenerate bodies, see
    /// [`ParameterWarning::Degenerate`]).
    #[error("parameter `{field}` must be positive, found {value:?}{origin}")]
    NonPositive {
        /// The symbol.
        field: String,
        /// The value.
        value: f64,
        /// File and line, when read from a file.
        origin: Origin,
    },

    /// A value so large in magnitude that the equations, which multiply up
    /// to a dozen parameters, would overflow double precision.
    #[error("parameter `{field}` = {value:?} is too large: at most {limit:e} in SI units, else the equations overflow double precision{origin}")]
    TooLarge {
        /// The symbol.
        field: String,
        /// The value.
        value: f64,
        /// The largest magnitude accepted.
        limit: f64,
        /// File and line, when read from a file.
        origin: Origin,
    },

    /// An uncertainty (`+/-std`) that is negative or not finite.
    #[error("{}:{line}: uncertainty of `{field}` must be finite and >= 0, found {value:?}", path.display())]
    InvalidUncertainty {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The symbol.
        field: String,
        /// The value.
        value: f64,
    },

    /// A body's inertia tensor is not positive definite.
    #[error(
        "inertia tensor of the {body} is not positive definite \
         (xx {ixx:?}, zz {izz:?}, xz {ixz:?}: xx*zz - xz^2 = {det:?}){origin}"
    )]
    NonPhysicalInertia {
        /// The body (`"rear wheel"`, `"rear frame"`, `"handlebar"`, `"front wheel"`).
        body: &'static str,
        /// Tensor entry xx.
        ixx: f64,
        /// Tensor entry zz.
        izz: f64,
        /// Tensor entry xz.
        ixz: f64,
        /// `ixx * izz - ixz^2`, which must be > 0.
        det: f64,
        /// The file, when read from a file.
        origin: Origin,
    },

    /// A TOML file has both thesis-only and benchmark-only keys.
    #[error(
        "{}: cannot tell the parameter form: thesis key `{thesis_key}` (line {thesis_line}) \
         and benchmark key `{benchmark_key}` (line {benchmark_line}); \
         add `form = \"thesis\"` or `form = \"benchmark\"`",
        path.display()
    )]
    AmbiguousForm {
        /// The file.
        path: PathBuf,
        /// A thesis-only key found.
        thesis_key: String,
        /// Its line.
        thesis_line: usize,
        /// A benchmark-only key found.
        benchmark_key: String,
        /// Its line.
        benchmark_line: usize,
    },

    /// A TOML file has neither thesis nor benchmark keys (only `g`, or nothing).
    #[error(
        "{}: cannot tell the parameter form: no thesis keys (Rt, x3, m2, ...) and no \
         benchmark keys (w, c, lam, ...)",
        path.display()
    )]
    UnknownForm {
        /// The file.
        path: PathBuf,
    },

    /// `form = "..."` names neither form.
    #[error("{}:{line}: `form` must be \"thesis\", \"benchmark\" or \"MooreRiderLean2012\", found \"{value}\"", path.display())]
    InvalidForm {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The value given.
        value: String,
    },

    /// Thesis to benchmark: no frame pitch puts the upright front wheel on the
    /// ground, ahead of the rear wheel (`|Rd - Rt|` exceeds the reach from the
    /// rear wheel centre to the front wheel centre in frame axes, or the only
    /// root puts the front wheel behind).
    #[error(
        "no ground contact for the front wheel: Rd - Rt = {height_difference:?} but the \
         front wheel centre is {reach:?} m from the rear wheel centre ({detail})"
    )]
    NoGroundContact {
        /// `Rd - Rt` (m).
        height_difference: f64,
        /// `sqrt((x4 + x5)^2 + (z4 + z5)^2)` (m).
        reach: f64,
        /// Which condition failed.
        detail: &'static str,
    },

    /// The steer axis is not tilted less than 90 degrees from vertical, so it
    /// does not meet the ground ahead of the wheels in the usual way.
    #[error("steer-axis tilt {tilt:?} rad is not within (-pi/2, pi/2)")]
    SteerAxisNotUpright {
        /// The steer-axis tilt `lam` from vertical (rad).
        tilt: f64,
    },

    /// A thesis set whose geometry is no upright bicycle: its steer-axis
    /// point and front wheel (`x4`, `z4`, `x5`, `z5`, with the radii) give
    /// no frame pitch with the front wheel on the ground ahead of the rear
    /// one and the steer axis leaning less than 90 degrees from vertical.
    /// `field` is the likeliest culprit (a value of the wrong sign against
    /// every real bicycle: `x4 > 0`, `z5 < 0`), else `x4`.
    #[error(
        "parameter `{field}` = {value:?}{origin}: the geometry (x4, z4, x5, z5) {problem}; a bicycle's steer axis \
         leans back less than 90 degrees (with x4 > 0 and z5 < 0) and its front wheel is on the ground ahead of the rear one"
    )]
    ImpossibleGeometry {
        /// The symbol named (`x4`, `z5`).
        field: String,
        /// Its value (m).
        value: f64,
        /// What it gives (a steer-axis tilt out of range, no ground contact).
        problem: String,
        /// File and line, when read from a file.
        origin: Origin,
    },

    /// The steer-axis tilt `lam` of a benchmark set is not within the stated
    /// range `(-pi/2, pi/2)` rad (exclusive: `lam = pi/2` is a horizontal steer
    /// axis, a degenerate bicycle). A value such as 18 was probably meant in
    /// degrees; the message then gives it in radians.
    #[error("parameter `{field}` = {value:?} rad is outside the steer-axis tilt range (-pi/2, pi/2) rad{hint}{origin}", hint = degrees_hint(*value))]
    TiltOutOfRange {
        /// The symbol (`lam`).
        field: String,
        /// The value (rad).
        value: f64,
        /// File and line, when read from a file.
        origin: Origin,
    },

    /// A set in J. K. Moore's (2012) parameters (bicycleparameters'
    /// `MooreRiderLean2012ParameterSet`, or `Moore2012ParameterSet` without
    /// the rider) that cannot be read or converted.
    #[error("{}{}: {why} (read as J. K. Moore's 2012 parameters, bicycleparameters' MooreRiderLean2012ParameterSet)", path.display(), fmt_line(*line))]
    MooreSet {
        /// The file.
        path: PathBuf,
        /// 1-based line of the key at fault, when there is one.
        line: Option<usize>,
        /// What is wrong.
        why: String,
    },

    /// A parameter set was of the other form than the one required.
    #[error("{}: expected {expected}-form parameters, found {found}-form", path.display())]
    WrongForm {
        /// The file.
        path: PathBuf,
        /// The form required.
        expected: &'static str,
        /// The form found.
        found: &'static str,
    },
}

/// `text` cut to at most `max` characters, with the number left out.
pub fn cut(text: &str, max: usize) -> String {
    let n = text.chars().count();
    if n <= max {
        text.to_string()
    } else {
        format!(
            "{}... ({} more characters)",
            text.chars().take(max).collect::<String>(),
            n - max
        )
    }
}

/// `"; if 18 is in degrees, that is 0.314159 rad"` for values that look like
/// an angle in degrees (magnitude at most 360), else `""`.
pub(crate) fn degrees_hint(value: f64) -> String {
    if value.is_finite() && value.abs() >= 1.0 && value.abs() <= 360.0 {
        format!(
            "; it looks like degrees: {value} deg is {} rad",
            crate::number_text::format_significant(value.to_radians(), 6)
        )
    } else {
        String::new()
    }
}

fn fmt_line(line: Option<usize>) -> String {
    match line {
        Some(l) => format!(":{l}"),
        None => String::new(),
    }
}

impl ParameterError {
    /// Attach a file (and the line of the field, looked up with `line_of`) to
    /// validation errors that have no origin yet. Other errors are unchanged.
    pub fn located(self, path: &Path, line_of: impl Fn(&str) -> Option<usize>) -> Self {
        match self {
            ParameterError::NotFinite { field, value, origin } if origin.path.is_none() => ParameterError::NotFinite {
                origin: Origin::new(path, line_of(&field)),
                field,
                value,
            },
            ParameterError::NonPositive { field, value, origin } if origin.path.is_none() => {
                ParameterError::NonPositive {
                    origin: Origin::new(path, line_of(&field)),
                    field,
                    value,
                }
            }
            ParameterError::TooLarge {
                field,
                value,
                limit,
                origin,
            } if origin.path.is_none() => ParameterError::TooLarge {
                origin: Origin::new(path, line_of(&field)),
                field,
                value,
                limit,
            },
            ParameterError::TiltOutOfRange { field, value, origin } if origin.path.is_none() => {
                ParameterError::TiltOutOfRange {
                    origin: Origin::new(path, line_of(&field)),
                    field,
                    value,
                }
            }
            ParameterError::ImpossibleGeometry {
                field,
                value,
                problem,
                origin,
            } if origin.path.is_none() => ParameterError::ImpossibleGeometry {
                origin: Origin::new(path, line_of(&field)),
                field,
                value,
                problem,
            },
            ParameterError::NonPhysicalInertia {
                body,
                ixx,
                izz,
                ixz,
                det,
                origin,
            } if origin.path.is_none() => ParameterError::NonPhysicalInertia {
                body,
                ixx,
                izz,
                ixz,
                det,
                origin: Origin::new(path, None),
            },
            other => other,
        }
    }

    /// The field (symbol) the error is about, if it is about one.
    pub fn field(&self) -> Option<&str> {
        match self {
            ParameterError::MissingField { field, .. }
            | ParameterError::UnknownField { field, .. }
            | ParameterError::RawMeasurementFile { field, .. }
            | ParameterError::DuplicateField { field, .. }
            | ParameterError::WrongType { field, .. }
            | ParameterError::NotFinite { field, .. }
            | ParameterError::NonPositive { field, .. }
            | ParameterError::TiltOutOfRange { field, .. }
            | ParameterError::ImpossibleGeometry { field, .. }
            | ParameterError::TooLarge { field, .. }
            | ParameterError::InvalidUncertainty { field, .. } => Some(field),
            _ => None,
        }
    }

    /// The 1-based line the error is about, if it has one.
    pub fn line(&self) -> Option<usize> {
        match self {
            ParameterError::Toml { line, .. } | ParameterError::MooreSet { line, .. } => *line,
            ParameterError::Syntax { line, .. }
            | ParameterError::UnknownField { line, .. }
            | ParameterError::RawMeasurementFile { line, .. }
            | ParameterError::DuplicateField { line, .. }
            | ParameterError::WrongType { line, .. }
            | ParameterError::InvalidUncertainty { line, .. }
            | ParameterError::InvalidForm { line, .. } => Some(*line),
            ParameterError::NotFinite { origin, .. }
            | ParameterError::NonPositive { origin, .. }
            | ParameterError::TiltOutOfRange { origin, .. }
            | ParameterError::ImpossibleGeometry { origin, .. }
            | ParameterError::TooLarge { origin, .. } => origin.line,
            _ => None,
        }
    }
}

/// Something suspicious in a parameter set that does not prevent its use.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum ParameterWarning {
    /// The principal moments of a body violate the triangle inequality
    /// (the largest exceeds the sum of the other two), which no rigid body of
    /// real matter can do. The thesis's own handlebar (I4) and front wheel
    /// (I5) tensors do this, so it is not an error.
    TriangleInequality {
        /// `"rear wheel"`, `"rear frame"`, `"handlebar"` (handlebar and fork)
        /// or `"front wheel"`.
        body: &'static str,
        /// Principal moments, largest first (kg m^2).
        principal: [f64; 3],
        /// `principal[0] - principal[1] - principal[2]` (> 0, kg m^2).
        excess: f64,
    },
    /// A degenerate body, allowed but unusual: a wheel of zero radius (a
    /// skate), a point mass (zero inertia tensor), or no body at all (zero
    /// mass and zero tensor). The two-mass-skate bicycle
    /// (`TmsBenchmark.txt`) has all three.
    Degenerate {
        /// `"rear wheel"`, `"rear frame"`, `"handlebar"` or `"front wheel"`.
        body: &'static str,
        /// What is degenerate.
        what: &'static str,
    },
    /// A name in a text file that is not a Table 1 parameter but is known from
    /// the HumanControl / BicycleParameters files (nominal speed `v`, lateral
    /// offsets `yB`, `yH`, the sub-bodies `G` and `S` of the front frame, ...).
    /// It is kept in the text file's `MeasuredBenchmark::extras`
    /// (`bikedyn::bicycle::files`) and does not enter the model.
    ExtraField {
        /// The name.
        field: String,
        /// Its value.
        value: f64,
        /// 1-based line.
        line: usize,
        /// What the name means.
        meaning: &'static str,
    },
    /// A length so large that it was probably given in millimetres (more
    /// than 10 m; a wheelbase of 1020 is 1.02 m).
    LooksLikeMillimetres {
        /// The symbol.
        field: &'static str,
        /// The value as given (read as metres).
        value: f64,
    },
    /// A body's mass centre is below the ground plane when the bicycle is
    /// upright.
    MassCentreBelowGround {
        /// `"rear frame"` or `"handlebar"`.
        body: &'static str,
        /// Height of the mass centre above the ground (< 0, m).
        height: f64,
    },
}

impl fmt::Display for ParameterWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParameterWarning::TriangleInequality {
                body,
                principal,
                excess,
            } => write!(
                f,
                "principal moments of the {body} [{}, {}, {}] kg m^2 violate the triangle \
                 inequality by {} kg m^2",
                crate::number_text::format_significant(principal[0], 6),
                crate::number_text::format_significant(principal[1], 6),
                crate::number_text::format_significant(principal[2], 6),
                crate::number_text::format_significant(*excess, 6),
            ),
            ParameterWarning::LooksLikeMillimetres { field, value } => write!(
                f,
                "`{field}` = {value:?} m is implausibly long for a bicycle; if it is in millimetres, \
                 write {} (metres)",
                crate::number_text::format_significant(value / 1000.0, 6)
            ),
            ParameterWarning::MassCentreBelowGround { body, height } => write!(
                f,
                "the {body} mass centre is {} m below the ground when upright",
                crate::number_text::format_significant(-height, 6)
            ),
            ParameterWarning::Degenerate { body, what } => {
                write!(f, "the {body} is degenerate: {what}")
            }
            ParameterWarning::ExtraField {
                field,
                value,
                line,
                meaning,
            } => write!(
                f,
                "line {line}: `{field} = {value:?}` ({meaning}) is not a model parameter; kept aside"
            ),
        }
    }
}
