//! Sensitivities of the critical speeds and eigenvalues
//! (`bikedyn_runtime::sensitivity`) as a ranked terminal table and as CSV.

use std::fmt::Write as _;
use std::io::Write;

use crate::output::{format_significant, format_table};
use bikedyn_runtime::sensitivity::{CriticalSensitivity, ModeSensitivity};

/// Rows of the eigenvalue tables (the largest; CSV and JSON hold every one).
pub const EIGEN_TABLE_ROWS: usize = 8;

/// The parameters in the order of the ranked table: by the larger of the two
/// elasticities' sizes (weave speed, capsize speed), largest first, with
/// their value and the two derivatives, where each speed exists.
pub fn ranked(
    weave: Option<&CriticalSensitivity>,
    capsize: Option<&CriticalSensitivity>,
) -> Vec<(&'static str, f64, Option<(f64, f64)>, Option<(f64, f64)>)> {
    let first = weave.or(capsize).map(|c| c.derivatives.as_slice()).unwrap_or(&[]);
    let find = |c: Option<&CriticalSensitivity>, p: &str| {
        c.and_then(|c| c.derivatives.iter().find(|d| d.parameter == p))
            .map(|d| (d.derivative, d.elasticity))
    };
    let mut rows: Vec<_> = first
        .iter()
        .map(|d| (d.parameter, d.value, find(weave, d.parameter), find(capsize, d.parameter)))
        .collect();
    let size = |r: &(&str, f64, Option<(f64, f64)>, Option<(f64, f64)>)| {
        r.2.map_or(0.0, |x| x.1.abs()).max(r.3.map_or(0.0, |x| x.1.abs()))
    };
    rows.sort_by(|a, b| size(b).total_cmp(&size(a)));
    rows
}

/// The ranked table of the critical speeds' sensitivities, then, when
/// given, the eigenvalues' at a speed (their largest entries).
pub fn sensitivity_table(
    weave: Option<&CriticalSensitivity>,
    capsize: Option<&CriticalSensitivity>,
    eigen: Option<(f64, &[ModeSensitivity])>,
) -> String {
    let mut out = String::new();
    let f = |x: f64| format_significant(x, 5);
    let speed = |c: Option<&CriticalSensitivity>| c.map_or("none in the range".to_string(), |c| format!("{} m/s", f(c.speed)));
    let _ = writeln!(
        out,
        "weave speed v_w = {}, capsize speed v_c = {}",
        speed(weave),
        speed(capsize)
    );
    let _ = writeln!(
        out,
        "elasticity e = (p / v) dv/dp: per cent change of the speed per per cent change of the parameter; parameters in benchmark form (Meijaard et al. 2007, SI units)"
    );
    let header: Vec<String> = ["rank", "param", "value", "dv_w/dp", "e_w", "dv_c/dp", "e_c"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let cell = |x: Option<(f64, f64)>, k: usize| {
        x.map_or("-".to_string(), |x| {
            let v = if k == 0 { x.0 } else { x.1 };
            f(v)
        })
    };
    let rows: Vec<Vec<String>> = ranked(weave, capsize)
        .iter()
        .enumerate()
        .map(|(k, (p, value, w, c))| {
            vec![
                (k + 1).to_string(),
                p.to_string(),
                f(*value),
                cell(*w, 0),
                cell(*w, 1),
                cell(*c, 0),
                cell(*c, 1),
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
pub const CSV_COLUMNS: [&str; 7] = ["quantity", "rank", "parameter", "value", "derivative", "elasticity", "scaled"];

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
