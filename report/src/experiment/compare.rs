//! The table of measured against predicted weave eigenvalues (the
//! residuals of `bikedyn_runtime::experiment::compare`).

use bikedyn_runtime::experiment::compare::Residual;

/// Plain-text residual table.
pub fn format_residuals(rows: &[Residual]) -> String {
    let header: Vec<String> = [
        "run",
        "kick t (s)",
        "v (m/s)",
        "measured",
        "predicted",
        "diff re",
        "diff im",
        "z re",
        "z im",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let body: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.run.clone(),
                format!("{:.2}", r.kick_time),
                format!("{:.2}", r.mean_speed),
                format!("{:.3}{:+.3}i", r.measured[0], r.measured[1]),
                format!("{:.3}{:+.3}i", r.predicted[0], r.predicted[1]),
                format!("{:+.3}", r.measured[0] - r.predicted[0]),
                format!("{:+.3}", r.measured[1] - r.predicted[1]),
                format!("{:+.1}", r.z[0]),
                format!("{:+.1}", r.z[1]),
            ]
        })
        .collect();
    crate::output::format_table(&header, &body)
}
