//! Sensitivities of the critical speeds and eigenvalues
//! (`bikedyn_runtime::sensitivity`) as a ranked terminal table and as CSV.

use std::fmt::Write as _;
use std::io::Write;

use crate::output::{format_significant, format_table};
use bikedyn_runtime::sensitivity::{CriticalSensitivity, ModeSensitivity};

/// Rows of the eigenvalue tables (the largest; CSV and JSON hold every one).
pub const EIGEN_TABLE_ROWS: usize = 8;

/// One parameter of the ranked table: `(derivative, elasticity)` of each
/// speed, where that speed exists.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RankedRow {
    pub parameter: &'static str,
    pub value: f64,
    pub weave: Option<(f64, f64)>,
    pub capsize: Option<(f64, f64)>,
}

impl RankedRow {
    /// The larger of the two elasticities' sizes.
    pub fn size(&self) -> f64 {
        self.weave
            .map_or(0.0, |x| x.1.abs())
            .max(self.capsize.map_or(0.0, |x| x.1.abs()))
    }
}

/// The parameters in the order of the ranked table: by the larger of the two
/// elasticities' sizes (weave speed, capsize speed), largest first.
pub fn ranked(weave: Option<&CriticalSensitivity>, capsize: Option<&CriticalSensitivity>) -> Vec<RankedRow> {
    let first = weave.or(capsize).map(|c| c.derivatives.as_slice()).unwrap_or(&[]);
    let find = |c: Option<&CriticalSensitivity>, p: &str| {
        c.and_then(|c| c.derivatives.iter().find(|d| d.parameter == p))
            .map(|d| (d.derivative, d.elasticity))
    };
    let mut rows: Vec<RankedRow> = first
        .iter()
        .map(|d| RankedRow {
            parameter: d.parameter,
            value: d.value,
            weave: find(weave, d.parameter),
            capsize: find(capsize, d.parameter),
        })
        .collect();
    rows.sort_by(|a, b| b.size().total_cmp(&a.size()));
    rows
}

/// The ranked table of the critical speeds' sensitivities, then, when
/// given, the eigenvalues' at a speed (their largest entries).
pub fn sensitivity_table(
    form: &str,
    weave: Option<&CriticalSensitivity>,
    capsize: Option<&CriticalSensitivity>,
    eigen: Option<(f64, &[ModeSensitivity])>,
) -> String {
    let mut out = String::new();
    let f = |x: f64| format_significant(x, 5);
    let speed =
        |c: Option<&CriticalSensitivity>| c.map_or("none in the range".to_string(), |c| format!("{} m/s", f(c.speed)));
    let _ = writeln!(
        out,
        "weave speed v_w = {}, capsize speed v_c = {}",
        speed(weave),
        speed(capsize)
    );
    let source = if form == "thesis" {
        "thesis form (Martin Recuero 2009)"
    } else {
        "benchmark form (Meijaard et al. 2007)"
    };
    let _ = writeln!(
        out,
        "elasticity e = (p / v) dv/dp: per cent change of the speed per per cent change of the parameter; parameters in {source}, SI units; exact derivatives (rounding below 1e-12 of the largest elasticity shown as 0)"
    );
    let header: Vec<String> = ["rank", "param", "value", "dv_w/dp", "e_w", "dv_c/dp", "e_c"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let all = ranked(weave, capsize);
    // Elasticities below 1e-12 of the largest are rounding (a parameter
    // that does not enter, such as IBxx for the capsize speed, which
    // depends on the stiffness only): shown as 0.
    let largest = all.iter().map(RankedRow::size).fold(0.0, f64::max);
    let cell = |x: Option<(f64, f64)>, k: usize, value: f64| {
        x.map_or("-".to_string(), |x| {
            if value != 0.0 && x.1.abs() < 1e-12 * largest {
                return "0".to_string();
            }
            f(if k == 0 { x.0 } else { x.1 })
        })
    };
    let rows: Vec<Vec<String>> = all
        .iter()
        .enumerate()
        .map(|(k, r)| {
            vec![
                (k + 1).to_string(),
                r.parameter.to_string(),
                f(r.value),
                cell(r.weave, 0, r.value),
                cell(r.weave, 1, r.value),
                cell(r.capsize, 0, r.value),
                cell(r.capsize, 1, r.value),
            ]
        })
        .collect();
    out.push_str(&format_table(&header, &rows));
    if let Some((v, modes)) = eigen {
        for m in modes {
            let _ = writeln!(
                out,
                "\n{} eigenvalue at v = {} m/s: s = {} {} {}i 1/s, ds/dv = {} {} {}i (1/s per m/s); {} largest of {} parameters by |p ds/dp|:",
                m.mode,
                f(v),
                f(m.eigenvalue[0]),
                if m.eigenvalue[1] < 0.0 { '-' } else { '+' },
                f(m.eigenvalue[1].abs()),
                f(m.speed_derivative[0]),
                if m.speed_derivative[1] < 0.0 { '-' } else { '+' },
                f(m.speed_derivative[1].abs()),
                EIGEN_TABLE_ROWS.min(m.derivatives.len()),
                m.derivatives.len()
            );
            let header: Vec<String> = ["param", "value", "d Re s/dp", "d Im s/dp", "p d Re s/dp", "p d Im s/dp"]
                .iter()
                .map(|s| s.to_string())
                .collect();
            let rows: Vec<Vec<String>> = m
                .derivatives
                .iter()
                .take(EIGEN_TABLE_ROWS)
                .map(|d| {
                    vec![
                        d.parameter.to_string(),
                        f(d.value),
                        f(d.derivative[0]),
                        f(d.derivative[1]),
                        f(d.scaled[0]),
                        f(d.scaled[1]),
                    ]
                })
                .collect();
            out.push_str(&format_table(&header, &rows));
        }
    }
    out
}

/// Columns of [`write_sensitivity_csv`].
pub const CSV_COLUMNS: [&str; 7] = [
    "quantity",
    "rank",
    "parameter",
    "value",
    "derivative",
    "elasticity",
    "scaled",
];

/// Write the sensitivities as CSV, one row per quantity and parameter:
/// `quantity` is `weave_speed`, `capsize_speed` (then `derivative` is
/// dv/dp, `elasticity` (p/v) dv/dp, `scaled` p dv/dp in m/s), or
/// `re_MODE`, `im_MODE` for the real and imaginary parts of an eigenvalue
/// at the speed (`derivative` d/dp, `scaled` p d/dp in 1/s, no
/// elasticity); `rank` is the parameter's place within its quantity.
pub fn write_sensitivity_csv<W: Write>(
    w: W,
    weave: Option<&CriticalSensitivity>,
    capsize: Option<&CriticalSensitivity>,
    modes: &[ModeSensitivity],
) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(CSV_COLUMNS)?;
    for (name, c) in [("weave_speed", weave), ("capsize_speed", capsize)] {
        let Some(c) = c else { continue };
        for (k, d) in c.derivatives.iter().enumerate() {
            wr.write_record([
                name.to_string(),
                (k + 1).to_string(),
                d.parameter.to_string(),
                format!("{:?}", d.value),
                format!("{:?}", d.derivative),
                format!("{:?}", d.elasticity),
                format!("{:?}", d.value * d.derivative),
            ])?;
        }
    }
    for m in modes {
        for (part, i) in [("re", 0), ("im", 1)] {
            for (k, d) in m.derivatives.iter().enumerate() {
                wr.write_record([
                    format!("{part}_{}", m.mode),
                    (k + 1).to_string(),
                    d.parameter.to_string(),
                    format!("{:?}", d.value),
                    format!("{:?}", d.derivative[i]),
                    String::new(),
                    format!("{:?}", d.scaled[i]),
                ])?;
            }
        }
    }
    wr.flush()?;
    Ok(())
}
