//! The benchmark text format of BicycleParameters and HumanControl.

use std::collections::BTreeMap;
use std::path::Path;

use super::{missing_all, read};
use bikedyn_runtime::parameters::moore;
use bikedyn_runtime::parameters::{BenchmarkParameters, Origin, ParameterError, ParameterWarning};

/// Names accepted in text files beside the Table 1 symbols, with their
/// meaning. They do not enter the model; they are kept in
/// [`MeasuredBenchmark::extras`].
pub const EXTRA_TEXT_FIELDS: [(&str, &str); 26] = [
    ("v", "nominal forward speed of HumanControl files (m/s)"),
    ("yB", "lateral offset of the rear-frame mass centre (m), 0 in the model"),
    (
        "yH",
        "lateral offset of the front-frame mass centre (m), 0 in the model",
    ),
    (
        "IRzz",
        "rear wheel moment about the vertical diameter (kg m^2), IRxx in the model",
    ),
    (
        "IFzz",
        "front wheel moment about the vertical diameter (kg m^2), IFxx in the model",
    ),
    ("d1", "BicycleParameters geometry: rear wheel centre to steer axis (m)"),
    (
        "d2",
        "BicycleParameters geometry: along the steer axis between the wheel centres (m)",
    ),
    (
        "d3",
        "BicycleParameters geometry: fork offset, steer axis to front wheel centre (m)",
    ),
    ("xcl", "x of a reference point of HumanControl's rider models (m)"),
    ("zcl", "z of a reference point of HumanControl's rider models (m)"),
    ("mG", "mass of front-frame sub-body G (kg), included in mH"),
    ("xG", "x of the mass centre of front-frame sub-body G (m)"),
    ("zG", "z of the mass centre of front-frame sub-body G (m)"),
    ("IGxx", "inertia xx of front-frame sub-body G (kg m^2)"),
    ("IGyy", "inertia yy of front-frame sub-body G (kg m^2)"),
    ("IGzz", "inertia zz of front-frame sub-body G (kg m^2)"),
    ("IGxz", "inertia xz of front-frame sub-body G (kg m^2)"),
    ("mS", "mass of front-frame sub-body S (kg), included in mH"),
    ("xS", "x of the mass centre of front-frame sub-body S (m)"),
    ("zS", "z of the mass centre of front-frame sub-body S (m)"),
    ("ISxx", "inertia xx of front-frame sub-body S (kg m^2)"),
    ("ISyy", "inertia yy of front-frame sub-body S (kg m^2)"),
    ("ISzz", "inertia zz of front-frame sub-body S (kg m^2)"),
    ("ISxz", "inertia xz of front-frame sub-body S (kg m^2)"),
    ("yG", "lateral offset of the mass centre of sub-body G (m)"),
    ("yS", "lateral offset of the mass centre of sub-body S (m)"),
];

/// A benchmark set read from a text file, with its measurement
/// uncertainties and the extra names the file carried.
///
/// One parameter per line, `name = value`, `name=value` or
/// `name = value+/-std`, in any order; blank lines and `#` comments are
/// allowed, as are CRLF line ends and trailing tabs. A value is a number or a
/// small expression of numbers and `pi` with `+ - * /` and parentheses
/// (HumanControl's `BenchmarkPar.txt` has `lam=pi/10`). Names are the
/// Meijaard symbols ([`BenchmarkParameters::SYMBOLS`]) plus the extra names in
/// [`EXTRA_TEXT_FIELDS`] (e.g. the nominal speed `v`), which are kept aside and
/// reported as [`ParameterWarning::ExtraField`]; any other name is
/// [`ParameterError::UnknownField`] with its line.
///
/// ```
/// use bikedyn::bicycle::files::MeasuredBenchmark;
/// let text = "w = 1.02+/-0.002\nc=0.08\nlam=pi/10\ng=9.81\nv=5\nrR=0.3\nmR=2\nIRxx=0.0603\n\
///             IRyy=0.12\nxB=0.3\nzB=-0.9\nmB=85\nIBxx=9.2\nIByy=11\nIBzz=2.8\nIBxz=2.4\n\
///             xH=0.9\nzH=-0.7\nmH=4\nIHxx=0.05892\nIHyy=0.06\nIHzz=0.00708\nIHxz=-0.00756\n\
///             rF=0.35\nmF=3\nIFxx=0.1405\nIFyy=0.28\n";
/// let (m, warnings) = MeasuredBenchmark::from_text_str(text, "BenchmarkPar.txt").unwrap();
/// assert_eq!(m.uncertainty("w"), Some(0.002));
/// assert_eq!(m.extras["v"], 5.0);
/// assert_eq!(warnings.len(), 1); // the extra `v`
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct MeasuredBenchmark {
    /// The Table 1 parameters (nominal values).
    pub parameters: BenchmarkParameters,
    /// Standard deviations given as `value+/-std`, by name (Table 1 symbols
    /// and extra names alike); names given without `+/-` are absent.
    pub uncertainties: BTreeMap<String, f64>,
    /// Values of the extra names ([`EXTRA_TEXT_FIELDS`]) found in the file.
    pub extras: BTreeMap<String, f64>,
}

impl MeasuredBenchmark {
    /// Read and validate a text file (format in [`MeasuredBenchmark`]). Returns
    /// the set and its warnings: one [`ParameterWarning::ExtraField`] per
    /// extra name, then the validation warnings.
    pub fn load(path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        Self::from_text_str(&read(path)?, path)
    }

    /// Parse and validate text; `path` is only used in messages.
    pub fn from_text_str(text: &str, path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        Self::from_text_str_with_extra(text, path, &[]).map(|(m, _, w)| (m, w))
    }

    /// [`MeasuredBenchmark::from_text_str`] that also accepts the symbols in
    /// `accepted` (the effect parameters of the generated models, e.g.
    /// `c_steer`, `Kc_roll_rate`), returned by name beside the set: a user
    /// adds the effects of a real bicycle to its bicycleparameters file.
    #[allow(clippy::type_complexity)]
    pub fn from_text_str_with_extra(
        text: &str,
        path: impl AsRef<Path>,
        accepted: &[&str],
    ) -> Result<(Self, BTreeMap<String, f64>, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        let mut accepted_values = BTreeMap::new();
        let pb = || path.to_path_buf();
        let mut values: BTreeMap<String, (f64, usize)> = BTreeMap::new();
        let mut uncertainties = BTreeMap::new();
        let mut extras = BTreeMap::new();
        let mut warnings = Vec::new();
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        for (index, raw) in text.lines().enumerate() {
            let line = index + 1;
            let Some((name, value, std)) = parse_line(raw, line, path)? else {
                continue;
            };
            let name = name.as_str();
            let syntax = |reason: String| ParameterError::Syntax {
                path: pb(),
                line,
                text: bikedyn_runtime::parameters::cut(raw.trim(), 80),
                reason: bikedyn_runtime::parameters::cut(&reason, 160),
            };
            if let Some(&(_, first_line)) = values.get(name) {
                return Err(ParameterError::DuplicateField {
                    path: pb(),
                    line,
                    first_line,
                    field: name.to_string(),
                });
            }
            if let Some(s) = std {
                if !(s.is_finite() && s >= 0.0) {
                    return Err(ParameterError::InvalidUncertainty {
                        path: pb(),
                        line,
                        field: name.to_string(),
                        value: s,
                    });
                }
                uncertainties.insert(name.to_string(), s);
            }
            if accepted.contains(&name) {
                if !value.is_finite() {
                    return Err(syntax(format!("value of `{name}` is not finite")));
                }
                accepted_values.insert(name.to_string(), value);
            } else if let Some(&(_, meaning)) = EXTRA_TEXT_FIELDS.iter().find(|(n, _)| *n == name) {
                extras.insert(name.to_string(), value);
                warnings.push(ParameterWarning::ExtraField {
                    field: name.to_string(),
                    value,
                    line,
                    meaning,
                });
            } else if is_raw_measurement(name) {
                return Err(ParameterError::RawMeasurementFile {
                    path: pb(),
                    line,
                    field: name.to_string(),
                });
            } else if !BenchmarkParameters::SYMBOLS.contains(&name) {
                return Err(ParameterError::UnknownField {
                    path: pb(),
                    line,
                    field: name.to_string(),
                    why: if accepted.is_empty() {
                        "not a benchmark symbol nor a known extra name"
                    } else {
                        "not a benchmark symbol, an effect parameter (see `bikedyn params show`) nor a known extra name"
                    },
                });
            }
            values.insert(name.to_string(), (value, line));
        }
        let absent: Vec<&str> = BenchmarkParameters::SYMBOLS
            .iter()
            .copied()
            .filter(|s| !values.contains_key(*s))
            .collect();
        if let Some(err) = missing_all(&pb(), &absent) {
            return Err(err);
        }
        let parameters = BenchmarkParameters::from_lookup(|sym| {
            values
                .get(sym)
                .map(|&(v, _)| v)
                .ok_or_else(|| ParameterError::MissingField {
                    path: pb(),
                    field: sym.to_string(),
                })
        })?;
        let line_of = |f: &str| values.get(f).map(|&(_, l)| l);
        warnings.extend(parameters.validate().map_err(|e| e.located(path, line_of))?);
        Ok((
            MeasuredBenchmark {
                parameters,
                uncertainties,
                extras,
            },
            accepted_values,
            warnings,
        ))
    }

    /// The standard deviation given for `symbol`, if any.
    pub fn uncertainty(&self, symbol: &str) -> Option<f64> {
        self.uncertainties.get(symbol).copied()
    }
}

/// One line of a text file: `None` for a blank or comment line, else its
/// name, value and `+/-` uncertainty (not yet checked).
#[allow(clippy::type_complexity)]
fn parse_line(raw: &str, line: usize, path: &Path) -> Result<Option<(String, f64, Option<f64>)>, ParameterError> {
    let content = raw.split('#').next().unwrap_or("").trim();
    if content.is_empty() {
        return Ok(None);
    }
    let syntax = |reason: String| ParameterError::Syntax {
        path: path.to_path_buf(),
        line,
        text: bikedyn_runtime::parameters::cut(raw.trim(), 80),
        reason: bikedyn_runtime::parameters::cut(&reason, 160),
    };
    let Some((name, rhs)) = content.split_once('=') else {
        return Err(syntax("expected `name = value`".to_string()));
    };
    let name = name.trim();
    if !is_identifier(name) {
        return Err(syntax(format!("`{name}` is not a parameter name")));
    }
    let (nominal, std) = match rhs.split_once("+/-") {
        Some((n, s)) => (n, Some(s)),
        None => (rhs, None),
    };
    let value = evaluate(nominal).map_err(|r| syntax(format!("value: {r}")))?;
    let std = std
        .map(|s| evaluate(s).map_err(|r| syntax(format!("uncertainty: {r}"))))
        .transpose()?;
    Ok(Some((name.to_string(), value, std)))
}

/// Whether a text file holds J. K. Moore's (2012) parameters
/// ([`moore::is_moore_set`] of its names).
pub(super) fn text_is_moore(text: &str) -> bool {
    let names = text.lines().filter_map(|raw| {
        let content = raw.split('#').next().unwrap_or("").trim();
        content.split_once('=').map(|(n, _)| n.trim())
    });
    moore::is_moore_set(names)
}

/// A text file of J. K. Moore's (2012) parameters (`name = value` per
/// line, as for the benchmark text form), with the `accepted` names (effect
/// and leaning-rider parameters) beside them: the converted benchmark set,
/// the accepted values given with the rider's converted parameters added,
/// and the warnings. Uncertainties (`+/-`) are refused: they would not
/// reach the converted parameters.
#[allow(clippy::type_complexity)]
pub(super) fn moore_from_text_str_with_extra(
    text: &str,
    path: &Path,
    accepted: &[&str],
) -> Result<(BenchmarkParameters, BTreeMap<String, f64>, Vec<ParameterWarning>), ParameterError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut values: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    let mut accepted_values = BTreeMap::new();
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let Some((name, value, std)) = parse_line(raw, line, path)? else {
            continue;
        };
        if let Some(&(_, first_line)) = values.get(&name) {
            return Err(ParameterError::DuplicateField {
                path: path.to_path_buf(),
                line,
                first_line,
                field: name,
            });
        }
        if std.is_some() {
            return Err(ParameterError::MooreSet {
                path: path.to_path_buf(),
                line: Some(line),
                why: format!(
                    "`{name}` has an uncertainty (`+/-`), which the conversion to the benchmark form would not carry; give nominal values"
                ),
            });
        }
        if accepted.contains(&name.as_str()) {
            if !value.is_finite() {
                return Err(ParameterError::NotFinite {
                    field: name,
                    value,
                    origin: Origin::new(path, Some(line)),
                });
            }
            accepted_values.insert(name.clone(), value);
        } else if !moore::is_moore_symbol(&name) {
            return Err(ParameterError::UnknownField {
                path: path.to_path_buf(),
                line,
                field: name,
                why: "not one of Moore's (2012) keys nor an effect parameter (see `bikedyn params show`)",
            });
        }
        values.insert(name, (value, line));
    }
    for k in accepted_values.keys() {
        values.remove(k);
    }
    let conversion = moore::convert(&values, path)?;
    moore::join_rider(&conversion, &mut accepted_values, accepted, path)?;
    Ok((conversion.benchmark, accepted_values, conversion.warnings))
}

fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// Evaluate a value: a number, or an expression of numbers, `pi`, `nan`,
/// `inf` with `+ - * /`, unary signs and parentheses.
pub(super) fn evaluate(text: &str) -> Result<f64, String> {
    let mut parser = Expr {
        s: text.trim().as_bytes(),
        pos: 0,
    };
    if parser.s.is_empty() {
        return Err("empty".to_string());
    }
    let v = parser.sum()?;
    parser.skip_space();
    if parser.pos != parser.s.len() {
        return Err(format!(
            "unexpected `{}`",
            String::from_utf8_lossy(&parser.s[parser.pos..])
        ));
    }
    Ok(v)
}

/// Recursive-descent evaluator over the bytes of one value.
struct Expr<'a> {
    s: &'a [u8],
    pos: usize,
}

impl Expr<'_> {
    fn skip_space(&mut self) {
        while self.pos < self.s.len() && self.s[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn peek(&mut self) -> Option<u8> {
        self.skip_space();
        self.s.get(self.pos).copied()
    }

    fn sum(&mut self) -> Result<f64, String> {
        let mut v = self.product()?;
        while let Some(op @ (b'+' | b'-')) = self.peek() {
            self.pos += 1;
            let r = self.product()?;
            v = if op == b'+' { v + r } else { v - r };
        }
        Ok(v)
    }

    fn product(&mut self) -> Result<f64, String> {
        let mut v = self.factor()?;
        while let Some(op @ (b'*' | b'/')) = self.peek() {
            self.pos += 1;
            let r = self.factor()?;
            v = if op == b'*' { v * r } else { v / r };
        }
        Ok(v)
    }

    fn factor(&mut self) -> Result<f64, String> {
        match self.peek() {
            None => Err("expression ends early".to_string()),
            Some(b'-') => {
                self.pos += 1;
                Ok(-self.factor()?)
            }
            Some(b'+') => {
                self.pos += 1;
                self.factor()
            }
            Some(b'(') => {
                self.pos += 1;
                let v = self.sum()?;
                if self.peek() != Some(b')') {
                    return Err("missing `)`".to_string());
                }
                self.pos += 1;
                Ok(v)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(),
            Some(c) if c.is_ascii_alphabetic() => {
                let start = self.pos;
                while self.pos < self.s.len() && self.s[self.pos].is_ascii_alphanumeric() {
                    self.pos += 1;
                }
                let word = String::from_utf8_lossy(&self.s[start..self.pos]).to_lowercase();
                match word.as_str() {
                    "pi" => Ok(std::f64::consts::PI),
                    "nan" => Ok(f64::NAN),
                    "inf" | "infinity" => Ok(f64::INFINITY),
                    _ => Err(format!("unknown name `{word}`")),
                }
            }
            Some(c) => Err(format!("unexpected `{}`", c as char)),
        }
    }

    /// Decimal number with optional fraction and exponent.
    fn number(&mut self) -> Result<f64, String> {
        let start = self.pos;
        let digits = |p: &mut Self| {
            while p.pos < p.s.len() && (p.s[p.pos].is_ascii_digit() || p.s[p.pos] == b'.') {
                p.pos += 1;
            }
        };
        digits(self);
        if self.pos < self.s.len() && matches!(self.s[self.pos], b'e' | b'E') {
            self.pos += 1;
            if self.pos < self.s.len() && matches!(self.s[self.pos], b'+' | b'-') {
                self.pos += 1;
            }
            digits(self);
        }
        let token = String::from_utf8_lossy(&self.s[start..self.pos]);
        token.parse::<f64>().map_err(|_| format!("`{token}` is not a number"))
    }
}

/// Whether `name` is one of the raw measurements of bicycleparameters'
/// `<Name>Measured.txt` files (and no benchmark symbol): pendulum periods
/// (`TcB1`, `TtH2`, ...), mass-centre measurements (`aB1`, `alphaH3`),
/// fork and wheel measurements (`lP`, `nF`, `dR`, `f`, `gamma`, ...).
fn is_raw_measurement(name: &str) -> bool {
    const PLAIN: &[&str] = &[
        "lP", "lF", "lR", "nF", "nR", "dP", "dF", "dR", "f", "gamma", "lamst", "lsp", "lst", "lcs", "hbb", "whb",
        "LhbF", "LhbR",
    ];
    const NUMBERED: &[&str] = &[
        "d", "h", "aB", "aH", "aS", "aG", "alphaB", "alphaH", "alphaS", "alphaG", "TcB", "TcH", "TcF", "TcR", "TcS",
        "TcG", "TcD", "TtB", "TtH", "TtF", "TtR", "TtP", "TtS", "TtG", "TtD",
    ];
    PLAIN.contains(&name)
        || NUMBERED.iter().any(|p| {
            name.strip_prefix(p)
                .is_some_and(|rest| !rest.is_empty() && rest.chars().all(|c| c.is_ascii_digit()))
        })
}
