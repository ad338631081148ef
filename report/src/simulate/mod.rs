//! Output of a simulation: the time-history CSV and the time-history plot
//! ([`plot`]). The simulation itself is `bikedyn_runtime::simulate`.

pub mod plot;

use std::io::Write;
use std::path::Path;

use bikedyn_runtime::simulate::Simulation;

use crate::output::{write_atomic, OutputError};

/// CSV header: `t`, every coordinate, `d` + every coordinate, `speed`,
/// `kinetic_energy`, `potential_energy`, `constraint_residual`, then the
/// extra states by name (models with states only).
pub fn simulation_csv_header(sim: &Simulation) -> Vec<String> {
    let mut h = vec!["t".to_string()];
    h.extend(sim.coordinates.iter().map(|c| c.to_string()));
    h.extend(sim.coordinates.iter().map(|c| format!("d{c}")));
    for s in ["speed", "kinetic_energy", "potential_energy", "constraint_residual"] {
        h.push(s.into());
    }
    h.extend(sim.states.iter().map(|s| s.to_string()));
    h
}

/// Write the CSV (see [`simulation_csv_header`]): time with 6 decimals,
/// every other value in scientific notation with 12 decimals.
pub fn write_simulation_csv<W: Write>(w: W, sim: &Simulation) -> Result<(), csv::Error> {
    let mut c = csv::Writer::from_writer(w);
    c.write_record(simulation_csv_header(sim))?;
    for i in 0..sim.t.len() {
        let mut row = vec![format!("{:.6}", sim.t[i])];
        row.extend(sim.p[i].iter().map(|x| format!("{x:.12e}")));
        row.extend(sim.dp[i].iter().map(|x| format!("{x:.12e}")));
        for x in [
            sim.speed[i],
            sim.kinetic_energy[i],
            sim.potential_energy[i],
            sim.constraint_residual[i],
        ] {
            row.push(format!("{x:.12e}"));
        }
        row.extend(sim.z[i].iter().map(|x| format!("{x:.12e}")));
        c.write_record(&row)?;
    }
    c.flush()?;
    Ok(())
}

/// Write the CSV atomically to `path`.
pub fn save_simulation_csv(path: impl AsRef<Path>, sim: &Simulation) -> Result<(), OutputError> {
    write_atomic(path, |w| write_simulation_csv(w, sim))
}
