//! Parameter files in TOML, of either form.
//!
//! Keys are the symbols of one form ([`ThesisParameters::SYMBOLS`] or
//! [`BenchmarkParameters::SYMBOLS`]), either at the top level or inside a
//! `[parameters]` table. When a `[parameters]` table exists it is used and the
//! other tables are ignored (so a reference file such as `meijaard2007.toml`,
//! with `[canonical]` and `[[eigenvalues]]` beside its `[parameters]`, loads).
//! The form is detected from the keys (thesis-only symbols such as `Rt`, `x3`
//! against benchmark-only ones such as `w`, `lam`; `g` is shared) or forced
//! with `form = "thesis"` or `form = "benchmark"`. Values are TOML integers or
//! floats (`nan` and `inf` parse, then fail validation). Every key must be
//! known; the thesis `d4` may be omitted (it defaults to 0). Loading validates
//! the set and returns the warnings beside it.
//!
//! A file of J. K. Moore's (2012) parameters (bicycleparameters'
//! `MooreRiderLean2012ParameterSet`; TOML or text, told by its keys or
//! `form = "MooreRiderLean2012"`) is converted on reading to the benchmark
//! form, its leaning rider to the `rider_lean` model's parameters, returned
//! with the extra symbols (`bikedyn_runtime::parameters::moore`).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

use bikedyn_runtime::feedback::{GainSchedule, GAIN_NAMES};
use bikedyn_runtime::parameters::moore::{self, MOORE_FORM};
use bikedyn_runtime::parameters::{
    BenchmarkParameters, Form, ParameterError, ParameterSet, ParameterWarning, ThesisParameters,
};
use nalgebra::Matrix2x4;

use super::text_file::{moore_from_text_str_with_extra, text_is_moore, MeasuredBenchmark};
use super::{missing, missing_all, read, LoadedSet, ParameterFile, ParameterSetFile};

impl ParameterFile for ParameterSet {
    /// Read and validate a parameter file. Files ending in `.toml`, and
    /// others whose content is TOML (quoted values, `[tables]`, `form = `:
    /// a pipe, `/dev/stdin`, a `.txt` name), are read as TOML
    /// ([`from_toml_str`](Self::from_toml_str)), all others as benchmark
    /// text files ([`from_text_str`](Self::from_text_str)).
    ///
    /// Returns the set and its warnings (triangle inequality, extra names of
    /// text files). To keep the `+/-` uncertainties of a text file, use
    /// [`MeasuredBenchmark::load`].
    fn load(path: impl AsRef<Path>) -> Result<(ParameterSet, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        let text = read(path)?;
        if is_toml(path, &text) {
            Self::from_toml_str(&text, path)
        } else if text_is_moore(&text) {
            Self::from_file_text_with_extra(&text, path, &[]).map(|l| (l.set, l.warnings))
        } else {
            Self::from_text_str(&text, path)
        }
    }

    /// Parse and validate TOML text (format in [`ParameterSet`]); `path` is
    /// only used in messages.
    fn from_toml_str(
        text: &str,
        path: impl AsRef<Path>,
    ) -> Result<(ParameterSet, Vec<ParameterWarning>), ParameterError> {
        Self::from_toml_str_with_extra(text, path, &[]).map(|(set, _, w)| (set, w))
    }

    /// TOML text with `form = "..."` and one commented line per symbol; it
    /// reads back to exactly this set.
    fn to_toml_string(&self) -> String {
        match self {
            ParameterSet::Thesis(p) => p.to_toml_string(),
            ParameterSet::Benchmark(p) => p.to_toml_string(),
        }
    }
}

impl ParameterSetFile for ParameterSet {
    /// Like [`from_toml_str`](Self::from_toml_str), also accepting the
    /// symbols in `extra` (e.g. effect parameters such as `c_steer`), which
    /// are returned by name. Any other unknown symbol is still an error
    /// naming the file and line.
    fn from_toml_str_with_extra(
        text: &str,
        path: impl AsRef<Path>,
        extra: &[&str],
    ) -> Result<(ParameterSet, BTreeMap<String, f64>, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        let mut fields = parse_toml_fields(text, path, extra)?;
        let extras: BTreeMap<String, f64> = extra
            .iter()
            .filter_map(|&e| fields.values.remove(e).map(|(v, _)| (e.to_string(), v)))
            .collect();
        if fields.moore {
            // J. K. Moore's parameters: the benchmark set they convert to,
            // the leaning rider's parameters joined to the extras.
            let conversion = moore::convert(&fields.values, path)?;
            let mut extras = extras;
            moore::join_rider(&conversion, &mut extras, extra, path)?;
            return Ok((
                ParameterSet::Benchmark(conversion.benchmark),
                extras,
                conversion.warnings,
            ));
        }
        let line_of = |f: &str| fields.values.get(f).map(|&(_, line)| line);
        let symbols: &[&str] = match fields.form {
            Form::Thesis => &ThesisParameters::SYMBOLS,
            Form::Benchmark => &BenchmarkParameters::SYMBOLS,
        };
        let absent: Vec<&str> = symbols
            .iter()
            .copied()
            .filter(|s| *s != "d4" && !fields.values.contains_key(*s))
            .collect();
        if let Some(err) = missing_all(path, &absent) {
            return Err(err);
        }
        let set = match fields.form {
            Form::Thesis => ParameterSet::Thesis(ThesisParameters::from_lookup(|sym| match fields.values.get(sym) {
                Some(&(v, _)) => Ok(v),
                None if sym == "d4" => Ok(0.0),
                None => Err(missing(path, sym)),
            })?),
            Form::Benchmark => ParameterSet::Benchmark(BenchmarkParameters::from_lookup(|sym| {
                fields
                    .values
                    .get(sym)
                    .map(|&(v, _)| v)
                    .ok_or_else(|| missing(path, sym))
            })?),
        };
        let warnings = set.validate().map_err(|e| e.located(path, line_of))?;
        Ok((set, extras, warnings))
    }

    /// Read and validate a parameter file, accepting the `extra` symbols
    /// (effect parameters) in TOML and text files alike (see
    /// [`from_toml_str_with_extra`](Self::from_toml_str_with_extra),
    /// [`MeasuredBenchmark::from_text_str_with_extra`]). The `+/-`
    /// uncertainties of a text file are kept (by symbol).
    fn load_with_extra(path: impl AsRef<Path>, extra: &[&str]) -> Result<LoadedSet, ParameterError> {
        let path = path.as_ref();
        let text = read(path)?;
        Self::from_file_text_with_extra(&text, path, extra)
    }

    /// [`load_with_extra`](Self::load_with_extra) of a file's text already
    /// read (a file dropped on the browser explorer): TOML or the text
    /// form, told apart as for a file; `path` names it in messages.
    fn from_file_text_with_extra(
        text: &str,
        path: impl AsRef<Path>,
        extra: &[&str],
    ) -> Result<LoadedSet, ParameterError> {
        let path = path.as_ref();
        let text = text.to_string();
        if is_toml(path, &text) {
            let feedback = feedback_from_toml_str(&text, path)?;
            Self::from_toml_str_with_extra(&text, path, extra).map(|(set, effects, warnings)| LoadedSet {
                set,
                effects,
                uncertainties: BTreeMap::new(),
                warnings,
                feedback,
            })
        } else if text_is_moore(&text) {
            moore_from_text_str_with_extra(&text, path, extra).map(|(set, effects, warnings)| LoadedSet {
                set: ParameterSet::Benchmark(set),
                effects,
                uncertainties: BTreeMap::new(),
                warnings,
                feedback: None,
            })
        } else {
            MeasuredBenchmark::from_text_str_with_extra(&text, path, extra).map(|(m, effects, warnings)| LoadedSet {
                set: ParameterSet::Benchmark(m.parameters),
                effects,
                uncertainties: m.uncertainties,
                warnings,
                feedback: None,
            })
        }
    }

    /// Parse and validate a benchmark text file (`name = value` or
    /// `name = value+/-std` per line, see [`MeasuredBenchmark`]); the
    /// uncertainties are dropped and the extra names (`v`, ...) are reported as
    /// [`ParameterWarning::ExtraField`]. `path` is only used in messages.
    fn from_text_str(
        text: &str,
        path: impl AsRef<Path>,
    ) -> Result<(ParameterSet, Vec<ParameterWarning>), ParameterError> {
        let (measured, warnings) = MeasuredBenchmark::from_text_str(text, path)?;
        Ok((ParameterSet::Benchmark(measured.parameters), warnings))
    }
}

impl ParameterFile for ThesisParameters {
    /// Parse and validate TOML text that must hold the thesis form (detected
    /// or forced); a benchmark-form file is [`ParameterError::WrongForm`]
    /// (convert it with [`ParameterSet::to_thesis`] instead).
    fn from_toml_str(text: &str, path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        match ParameterSet::from_toml_str(text, path)? {
            (ParameterSet::Thesis(p), w) => Ok((p, w)),
            (other, _) => Err(wrong_form(path, Form::Thesis, other.form())),
        }
    }

    /// Read and validate a thesis-form TOML file.
    fn load(path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        Self::from_toml_str(&read(path)?, path)
    }

    /// TOML text (`form = "thesis"`, one commented `symbol = value` line per
    /// symbol, shortest round-trip float representation): reads back exactly.
    fn to_toml_string(&self) -> String {
        write_toml(
            Form::Thesis,
            |s| self.get(s),
            ThesisParameters::describe,
            "Thesis-form bicycle parameters (Martin Recuero 2009). Axes X forward, Y left, \
             Z up; SI units.",
        )
    }
}

impl ParameterFile for BenchmarkParameters {
    /// Parse and validate TOML text that must hold the benchmark form
    /// (detected or forced); a thesis-form file is
    /// [`ParameterError::WrongForm`].
    fn from_toml_str(text: &str, path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        match ParameterSet::from_toml_str(text, path)? {
            (ParameterSet::Benchmark(p), w) => Ok((p, w)),
            (other, _) => Err(wrong_form(path, Form::Benchmark, other.form())),
        }
    }

    /// Read and validate a benchmark-form file: TOML when the name ends in
    /// `.toml` or the content is TOML, else the text format (uncertainties
    /// dropped; see [`MeasuredBenchmark::load`] to keep them).
    fn load(path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError> {
        let path = path.as_ref();
        match ParameterSet::load(path)? {
            (ParameterSet::Benchmark(p), w) => Ok((p, w)),
            (other, _) => Err(wrong_form(path, Form::Benchmark, other.form())),
        }
    }

    /// TOML text (`form = "benchmark"`, one commented `symbol = value` line per
    /// symbol, shortest round-trip float representation): reads back exactly.
    fn to_toml_string(&self) -> String {
        write_toml(
            Form::Benchmark,
            |s| self.get(s),
            BenchmarkParameters::describe,
            "Benchmark-form bicycle parameters (Meijaard et al. 2007, Table 1). Axes x \
             forward, y right, z down; SI units.",
        )
    }
}

/// Whether a parameter file is TOML: by its extension `.toml`, else by its
/// content, so a file read through `/dev/stdin`, `<(...)`, a `.txt` name
/// or no extension is read in the format it is in. The text format
/// (`name = value[+/-std]` per line) has no quotes and no `[tables]`;
/// every TOML parameter file has `form = "..."` or quoted values or
/// tables, and a TOML file of bare numbers reads the same either way.
pub(crate) fn is_toml(path: &Path, text: &str) -> bool {
    if let Some(e) = path.extension() {
        if e.eq_ignore_ascii_case("toml") {
            return true;
        }
    }
    text.lines().map(str::trim).any(|l| {
        !l.starts_with('#') && (l.starts_with('[') || l.contains('"') || l.contains('\'') || l.starts_with("form"))
    })
}

fn wrong_form(path: &Path, expected: Form, found: Form) -> ParameterError {
    ParameterError::WrongForm {
        path: path.to_path_buf(),
        expected: expected.name(),
        found: found.name(),
    }
}

/// 1-based line of a byte offset.
pub(crate) fn line_of_offset(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    text.as_bytes()[..end].iter().filter(|&&b| b == b'\n').count() + 1
}

/// Format an `f64` as a TOML float that parses back to the same value
/// (shortest round-trip digits; `nan`, `inf`, `-inf` spelled the TOML way).
pub(crate) fn toml_float(x: f64) -> String {
    if x.is_nan() {
        "nan".to_string()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.to_string()
    } else {
        // Debug prints the shortest representation that round-trips, always
        // with a `.` or an exponent (`85.0`, `1e-7`), both valid TOML floats.
        format!("{x:?}")
    }
}

fn write_toml(
    form: Form,
    get: impl Fn(&str) -> Option<f64>,
    describe: fn(&str) -> Option<&'static str>,
    header: &str,
) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# {header}");
    let _ = writeln!(out, "form = \"{}\"", form.name());
    for &sym in form.symbols() {
        let value = toml_float(get(sym).unwrap_or(f64::NAN));
        let line = format!("{sym} = {value}");
        let _ = writeln!(out, "{line:<32} # {}", describe(sym).unwrap_or(""));
    }
    out
}

/// The numeric fields of a TOML parameter table, with their lines.
struct TomlFields {
    form: Form,
    /// J. K. Moore's (2012) parameters (by their keys or `form`), read
    /// under his names; `form` is then the benchmark form they convert to.
    moore: bool,
    values: BTreeMap<String, (f64, usize)>,
}

fn toml_type(value: &DeValue<'_>) -> &'static str {
    match value {
        DeValue::String(_) => "a string",
        DeValue::Integer(_) => "an integer",
        DeValue::Float(_) => "a float",
        DeValue::Boolean(_) => "a boolean",
        DeValue::Datetime(_) => "a datetime",
        DeValue::Array(_) => "an array",
        DeValue::Table(_) => "a table",
    }
}

fn parse_toml_fields(text: &str, path: &Path, extra: &[&str]) -> Result<TomlFields, ParameterError> {
    let pb = || path.to_path_buf();
    let line = |span: std::ops::Range<usize>| line_of_offset(text, span.start);
    let doc = DeTable::parse(text).map_err(|e| ParameterError::Toml {
        path: pb(),
        line: e.span().map(|s| line_of_offset(text, s.start)),
        message: e.message().trim().to_string(),
    })?;
    let root = doc.get_ref();

    // Choose the table that holds the parameters.
    let mut forced: Option<(String, usize)> = None;
    let table: &DeTable<'_> = match root.get_key_value("parameters") {
        Some((key, value)) => {
            let DeValue::Table(t) = value.get_ref() else {
                return Err(ParameterError::WrongType {
                    path: pb(),
                    line: line(key.span()),
                    field: "parameters".to_string(),
                    expected: "a table",
                    found: toml_type(value.get_ref()),
                });
            };
            // Other tables are ignored; a stray top-level scalar other than
            // `form` is a mistake.
            for (k, v) in root.iter() {
                let name: &str = k.get_ref();
                match v.get_ref() {
                    DeValue::Table(_) | DeValue::Array(_) => {}
                    _ if name == "form" => forced = Some(form_value(k, v, path, text)?),
                    _ if name == "parameters" => {}
                    _ => {
                        return Err(ParameterError::UnknownField {
                            path: pb(),
                            line: line(k.span()),
                            field: name.to_string(),
                            why: "only `form` and tables may sit beside a [parameters] table",
                        })
                    }
                }
            }
            t
        }
        None => root,
    };

    // Entries in file order.
    let mut entries: Vec<(&Spanned<_>, &Spanned<DeValue<'_>>)> = table.iter().collect();
    entries.sort_by_key(|(k, _)| k.span().start);
    if let Some((k, v)) = entries.iter().find(|(k, _)| k.get_ref() == "form") {
        forced = Some(form_value(k, v, path, text)?);
    }

    let moore = match &forced {
        Some((name, _)) => name == MOORE_FORM,
        None => moore::is_moore_set(entries.iter().map(|(k, _)| -> &str { k.get_ref() })),
    };
    let form = match forced {
        _ if moore => Form::Benchmark,
        Some((name, l)) => Form::from_name(&name).ok_or(ParameterError::InvalidForm {
            path: pb(),
            line: l,
            value: name,
        })?,
        None => detect_form(&entries, path, text)?,
    };

    let mut values = BTreeMap::new();
    for (k, v) in entries {
        let name: &str = k.get_ref();
        let l = line(k.span());
        if name == "form" || (name == "feedback" && matches!(v.get_ref(), DeValue::Table(_))) {
            continue;
        }
        let known = if moore {
            moore::is_moore_symbol(name)
        } else {
            form.symbols().contains(&name)
        };
        if !known && !extra.contains(&name) {
            return Err(ParameterError::UnknownField {
                path: pb(),
                line: l,
                field: name.to_string(),
                why: match (form, extra.is_empty()) {
                    _ if moore => "not one of Moore's (2012) keys nor an effect parameter (see `bikedyn params show`)",
                    // A key of Moore's among another form's: say why it is
                    // not read as his (basu_mandal2007.toml mixes them).
                    _ if moore::is_moore_symbol(name) => {
                        "a key of J. K. Moore's 2012 parameters (bicycleparameters' MooreRiderLean2012ParameterSet), \
                         which a file gives alone, without benchmark or thesis symbols; this file has those"
                    }
                    (Form::Thesis, true) => "not a thesis-form symbol",
                    (Form::Benchmark, true) => "not a benchmark-form symbol",
                    (Form::Thesis, false) => {
                        "neither a thesis-form symbol nor a parameter of any model's effects or added bodies"
                    }
                    (Form::Benchmark, false) => {
                        "neither a benchmark-form symbol nor a parameter of any model's effects or added bodies"
                    }
                },
            });
        }
        let value = match v.get_ref() {
            DeValue::Float(f) => f.as_str().parse::<f64>().ok(),
            DeValue::Integer(i) => i64::from_str_radix(i.as_str(), i.radix())
                .ok()
                .map(|n| n as f64)
                .or_else(|| i.as_str().parse::<f64>().ok()),
            other => {
                return Err(ParameterError::WrongType {
                    path: pb(),
                    line: l,
                    field: name.to_string(),
                    expected: "a number",
                    found: toml_type(other),
                })
            }
        };
        let value = value.ok_or_else(|| ParameterError::Toml {
            path: pb(),
            line: Some(l),
            message: format!("cannot read the number of `{name}`"),
        })?;
        values.insert(name.to_string(), (value, l));
    }
    Ok(TomlFields { form, moore, values })
}

fn form_value(
    key: &Spanned<std::borrow::Cow<'_, str>>,
    value: &Spanned<DeValue<'_>>,
    path: &Path,
    text: &str,
) -> Result<(String, usize), ParameterError> {
    let l = line_of_offset(text, key.span().start);
    match value.get_ref() {
        DeValue::String(s) => Ok((s.to_string(), l)),
        other => Err(ParameterError::WrongType {
            path: path.to_path_buf(),
            line: l,
            field: "form".to_string(),
            expected: "\"thesis\", \"benchmark\" or \"MooreRiderLean2012\"",
            found: toml_type(other),
        }),
    }
}

fn detect_form(
    entries: &[(&Spanned<std::borrow::Cow<'_, str>>, &Spanned<DeValue<'_>>)],
    path: &Path,
    text: &str,
) -> Result<Form, ParameterError> {
    let first_of = |form: Form, other: Form| {
        entries.iter().find_map(|(k, _)| {
            let name: &str = k.get_ref();
            (form.symbols().contains(&name) && !other.symbols().contains(&name))
                .then(|| (name.to_string(), line_of_offset(text, k.span().start)))
        })
    };
    match (
        first_of(Form::Thesis, Form::Benchmark),
        first_of(Form::Benchmark, Form::Thesis),
    ) {
        (Some(_), None) => Ok(Form::Thesis),
        (None, Some(_)) => Ok(Form::Benchmark),
        (Some((thesis_key, thesis_line)), Some((benchmark_key, benchmark_line))) => {
            Err(ParameterError::AmbiguousForm {
                path: path.to_path_buf(),
                thesis_key,
                thesis_line,
                benchmark_key,
                benchmark_line,
            })
        }
        (None, None) => Err(ParameterError::UnknownForm {
            path: PathBuf::from(path),
        }),
    }
}

/// The controller a TOML parameter file declares, if any: a top-level
/// `[feedback]` table of full-state feedback gains `u = -K(v) x`
/// ([`bikedyn_runtime::feedback`]; bicycleparameters' gain names, benchmark signs).
/// Each gain is a number (constant) or a list of its values at the
/// table's `speeds` (m/s, increasing): linear between them, held beyond.
/// Gains not given are zero.
///
/// ```toml
/// [feedback]
/// speeds = [0.0, 1.5, 4.7]
/// kTdel_phid = [0.0, -12.48, 0.0]
/// ```
pub fn feedback_from_toml_str(text: &str, path: impl AsRef<Path>) -> Result<Option<GainSchedule>, ParameterError> {
    let path = path.as_ref();
    let Ok(doc) = DeTable::parse(text) else {
        // The parameters' own reading reports the syntax error.
        return Ok(None);
    };
    let root = doc.get_ref();
    let Some((key, value)) = root.get_key_value("feedback") else {
        return Ok(None);
    };
    let at = |span: std::ops::Range<usize>| line_of_offset(text, span.start);
    let bad = |line: usize, why: String| ParameterError::Feedback {
        path: path.to_path_buf(),
        line,
        why,
    };
    let DeValue::Table(table) = value.get_ref() else {
        return Err(bad(
            at(key.span()),
            format!("`feedback` must be a table, not {}", toml_type(value.get_ref())),
        ));
    };
    let number = |v: &Spanned<DeValue<'_>>, name: &str| -> Result<f64, ParameterError> {
        let x = match v.get_ref() {
            DeValue::Float(f) => f.as_str().parse::<f64>().ok(),
            DeValue::Integer(i) => i.as_str().parse::<f64>().ok(),
            other => {
                return Err(bad(
                    at(v.span()),
                    format!("`{name}` holds {}, not a number", toml_type(other)),
                ))
            }
        };
        match x {
            Some(x) if x.is_finite() => Ok(x),
            _ => Err(bad(at(v.span()), format!("`{name}` is not a finite number"))),
        }
    };
    // A number, or a list of numbers, with the line of its name.
    let values =
        |k: &Spanned<std::borrow::Cow<'_, str>>, v: &Spanned<DeValue<'_>>| -> Result<Vec<f64>, ParameterError> {
            let name: &str = k.get_ref();
            match v.get_ref() {
                DeValue::Array(items) => items.iter().map(|x| number(x, name)).collect(),
                _ => Ok(vec![number(v, name)?]),
            }
        };
    let mut speeds: Option<(Vec<f64>, usize)> = None;
    let mut gains: Vec<(usize, Vec<f64>, usize, bool)> = Vec::new();
    for (k, v) in table.iter() {
        let name: &str = k.get_ref();
        let line = at(k.span());
        if name == "speeds" {
            speeds = Some((values(k, v)?, line));
        } else if let Some(j) = GAIN_NAMES.iter().position(|g| *g == name) {
            let list = matches!(v.get_ref(), DeValue::Array(_));
            gains.push((j, values(k, v)?, line, list));
        } else {
            return Err(bad(
                line,
                format!(
                    "unknown key `{name}` (the table holds `speeds` and the gains {})",
                    GAIN_NAMES.join(", ")
                ),
            ));
        }
    }
    let knots = match &speeds {
        Some((s, _)) => s.clone(),
        None => vec![0.0],
    };
    let mut k = vec![Matrix2x4::<f64>::zeros(); knots.len()];
    for (j, vals, line, list) in &gains {
        if *list && speeds.is_none() {
            return Err(bad(
                *line,
                format!(
                    "`{}` is a list but the table has no `speeds` to give its knots",
                    GAIN_NAMES[*j]
                ),
            ));
        }
        let at_knot = |i: usize| if *list { vals[i] } else { vals[0] };
        if *list && vals.len() != knots.len() {
            return Err(bad(
                *line,
                format!(
                    "`{}` has {} values for {} speeds",
                    GAIN_NAMES[*j],
                    vals.len(),
                    knots.len()
                ),
            ));
        }
        for (i, m) in k.iter_mut().enumerate() {
            m[(j / 4, j % 4)] = at_knot(i);
        }
    }
    let line = speeds.as_ref().map_or(at(key.span()), |(_, l)| *l);
    GainSchedule::new(knots, k)
        .map(Some)
        .map_err(|e| bad(line, e.to_string()))
}
