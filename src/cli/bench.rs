//! `bikedyn bench`: timing and operation-count figures of the generated
//! code, the simulation and the measured-run pipeline; or one full
//! `identify` on a synthetic set.

use anyhow::Result;
use bikedyn::identify::{report, IdentifyRequest};
use bikedyn::runtime::experiment::{self, read, PipelineOptions};
use std::path::Path;

/// Run `bikedyn bench` (`identify`: time one identification instead).
pub fn run(quick: bool, identify: bool) -> Result<bool> {
    if identify {
        identify_bench()?;
    } else {
        super::bench_generated::run(quick)?;
    }
    Ok(true)
}

/// A scratch folder `name-<pid>` in the system's temporary folder, which
/// must exist: a bench never creates a missing `TMPDIR` (nor leaves one).
fn scratch(name: &str) -> Result<std::path::PathBuf> {
    let root = std::env::temp_dir();
    if !root.is_dir() {
        anyhow::bail!(
            "the temporary folder {} (TMPDIR) does not exist or is no folder: create it, or set TMPDIR to an existing folder",
            root.display()
        );
    }
    Ok(root.join(format!("{name}-{}", std::process::id())))
}

/// A full `identify` on a 12-run synthetic set (steer damping hidden), made
/// in a temporary folder.
fn identify_bench() -> Result<()> {
    let dir = scratch("bikedyn-bench-identify")?;
    let _ = std::fs::remove_dir_all(&dir);
    super::synth::thesis_set(&dir, 12, 22, &["c_steer=0.25"])?;
    let request = IdentifyRequest {
        inputs: vec![dir.clone()],
        ..IdentifyRequest::default()
    };
    let t = std::time::Instant::now();
    let o = super::identify::run_with_progress(&request)?;
    let secs = t.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&dir);
    outln!("{}", report::summary(&o));
    outln!(
        "identify, 12-run set ({} kicks): {secs:.1} s wall clock on {} threads, {} simulations (target < 5 s on 2 cores, issue 17)",
        o.segments.len(),
        rayon::current_num_threads(),
        o.identification.simulations
    );
    Ok(())
}

/// `bikedyn bench` section: time to process one thesis-style run end to end
/// (read, angles, speed, clock, kick, fits) and one TU Delft log, on one
/// core. Uses `../shared` when present, else a synthetic run written to a
/// temporary folder (and no TU Delft figure).
pub fn experiment(quick: bool) -> Result<()> {
    use bikedyn::report::experiment::synth::write_run;
    use bikedyn::runtime::experiment::angles::Calibration;
    use bikedyn::runtime::experiment::synth::{rest_trajectory, ResponseSpec, SensorModel};
    use std::time::Instant;
    let reps = if quick { 5 } else { 30 };
    outln!("\n== measured runs (bikedyn fit), median of {reps}, one thread ==");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared");
    let (run_dir, cal_dir, log) = if root.join("data/dev/run01").is_dir() {
        (
            root.join("data/dev/run01"),
            root.join("data/dev/calibration"),
            Some(root.join("realdata/tudelft_sbw_kicks/logs/eigen_normal_sil6.5n2_16.2kph.log")),
        )
    } else {
        let d = scratch("bikedyn-bench")?;
        let spec = ResponseSpec::default();
        let s = SensorModel::default();
        write_run(
            &d.join("calibration"),
            "calibration",
            read::RunKind::Calibration,
            &rest_trajectory(10.0, spec.frame_pitch, 0.3),
            &s,
            1,
        )?;
        write_run(&d.join("run01"), "run01", read::RunKind::Run, &spec.trajectory(), &s, 2)?;
        (d.join("run01"), d.join("calibration"), None)
    };
    let opt = PipelineOptions::default();
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let cal_run = read::read_run(&cal_dir)?;
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        std::hint::black_box(Calibration::estimate(&cal_run, opt.frame_pitch));
        times.push(t.elapsed().as_secs_f64());
    }
    outln!(
        "calibration run (misalignment estimate, read excluded): {:>8.2} ms",
        1e3 * median(times)
    );
    let cal = Calibration::estimate(&cal_run, opt.frame_pitch);
    let mut times = Vec::new();
    for _ in 0..reps {
        let t = Instant::now();
        let run = read::read_run(&run_dir)?;
        std::hint::black_box(experiment::process_thesis_run(&run, &cal, &opt));
        times.push(t.elapsed().as_secs_f64());
    }
    outln!(
        "thesis-style run, end to end ({}): {:>8.2} ms",
        run_dir.display(),
        1e3 * median(times)
    );
    if let Some(log) = log.filter(|l| l.is_file()) {
        let mut times = Vec::new();
        let mut kicks = 0;
        for _ in 0..reps.min(10) {
            let t = Instant::now();
            let l = read::read_tudelft(&log)?;
            kicks = experiment::process_tudelft(&l, &opt).kicks.len();
            times.push(t.elapsed().as_secs_f64());
        }
        outln!(
            "TU Delft log, end to end ({kicks} kicks, {}): {:>8.2} ms",
            log.display(),
            1e3 * median(times)
        );
    }
    Ok(())
}
