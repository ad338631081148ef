//! Frequency responses (`bikedyn_runtime::frequency`) as CSV: one row per
//! frequency and input-output pair.

use std::io::Write;

use bikedyn_runtime::frequency::FrequencyResponse;

/// Columns of [`write_frequency_response_csv`].
pub const CSV_COLUMNS: [&str; 9] = [
    "omega",
    "frequency_hz",
    "input",
    "output",
    "re",
    "im",
    "magnitude",
    "magnitude_db",
    "phase_deg",
];

/// Write a frequency response as CSV: `omega` (rad/s), `frequency_hz`,
/// `input` (`roll_torque`, `steer_torque`), `output` (`roll`, `steer`),
/// `re`, `im` and `magnitude` of `G(i omega)` (rad/(N m)), `magnitude_db`
/// (dB re 1 rad/(N m)), `phase_deg` (unwrapped along the frequencies).
pub fn write_frequency_response_csv<W: Write>(w: W, r: &FrequencyResponse) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(CSV_COLUMNS)?;
    for g in &r.responses {
        for (k, &omega) in r.omega.iter().enumerate() {
            wr.write_record([
                format!("{omega:?}"),
                format!("{:?}", omega / std::f64::consts::TAU),
                g.input.to_string(),
                g.output.to_string(),
                format!("{:?}", g.re[k]),
                format!("{:?}", g.im[k]),
                format!("{:?}", g.re[k].hypot(g.im[k])),
                format!("{:?}", g.magnitude_db[k]),
                format!("{:?}", g.phase_deg[k]),
            ])?;
        }
    }
    wr.flush()?;
    Ok(())
}
