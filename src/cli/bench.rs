//! `bikedyn bench`: timing and operation-count figures of the generated
//! code, the simulation and the measured-run pipeline; or one full
//! `identify` on a synthetic set. The work is `bikedyn::bench`; this calls
//! each section and prints it as soon as it is measured.

use super::ProgressDisplay;
use anyhow::Result;
use bikedyn::bench::{self, BenchOptions, IdentifyBenchOptions, MeasuredRunFigures};
use bikedyn::identify::report;

/// Run `bikedyn bench` (`identify`: time one identification instead).
pub fn run(quick: bool, identify: bool) -> Result<bool> {
    if identify {
        identify_bench()?;
    } else {
        let opts = BenchOptions { quick };
        super::bench_generated::codegen(&bench::codegen()?)?;
        super::bench_generated::functions(&bench::generated_functions(&opts))?;
        super::bench_generated::linearization(&bench::linearization(&opts)?)?;
        super::bench_generated::sweep(&bench::sweep(&opts))?;
        measured_runs(&bench::measured_runs(&opts)?)?;
        super::bench_simulate::simulation(&bench::simulation(&opts)?)?;
    }
    Ok(true)
}

/// A full `identify` on a 12-run synthetic set (steer damping hidden), made
/// in a temporary folder: the set's runs as `bikedyn synth` prints them,
/// the summary and the time.
fn identify_bench() -> Result<()> {
    let display = ProgressDisplay::new();
    let b = bench::identify_bench(&IdentifyBenchOptions::default(), &|p| display.show(p))?;
    drop(display);
    eprintln!("identify: model {} (driven twin {})", b.model, b.driven_model);
    for r in &b.runs {
        super::synth::print_run(r)?;
    }
    outln!("wrote {} runs to {}", b.runs.len(), b.set.display());
    outln!("{}", report::summary(&b.outcome));
    outln!(
        "identify, 12-run set ({} kicks): {:.1} s wall clock on {} threads, {} simulations (target < 5 s on 2 cores, issue 17)",
        b.kicks,
        b.seconds,
        b.threads,
        b.simulations
    );
    Ok(())
}

/// The measured-run section: one thesis-style run end to end (read,
/// angles, speed, clock, kick, fits) and one TU Delft log, on one core.
fn measured_runs(m: &MeasuredRunFigures) -> Result<()> {
    outln!(
        "\n== measured runs (bikedyn fit), median of {}, one thread ==",
        m.repetitions
    );
    outln!(
        "calibration run (misalignment estimate, read excluded): {:>8.2} ms",
        m.calibration_ms
    );
    outln!(
        "thesis-style run, end to end ({}): {:>8.2} ms",
        m.run.display(),
        m.run_ms
    );
    if let Some(log) = &m.log {
        outln!(
            "TU Delft log, end to end ({} kicks, {}): {:>8.2} ms",
            log.kicks,
            log.path.display(),
            log.ms
        );
    }
    Ok(())
}
