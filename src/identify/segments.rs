//! The measured segments identification fits: every kick of the processed
//! runs with a free-response window, carried on to the end of the free
//! motion.

use crate::fit::FitOutcome;
use bikedyn_runtime::experiment::{accept::Rejected, kicks::WindowEnd, PipelineOptions};
use bikedyn_runtime::identify::Segment;

/// The measured segments and what was left out.
pub struct Segments {
    /// One per kick with a usable window. A segment's `weave` is the kick's
    /// measured weave eigenvalue: `None` where `fit` refused the fit.
    pub segments: Vec<Segment>,
    /// Why each segment's fitted eigenvalue was refused (`None`: it is a
    /// measured weave eigenvalue), as `fit` judged it.
    pub rejected: Vec<Option<Rejected>>,
    /// Runs and kicks without a usable window, with the reason.
    pub skipped: Vec<String>,
}

/// The measured segments of a processed set: every kick with a free
/// response window, roll and steer from the pipeline's angles (IMU clock),
/// speed from the reed switch moved onto the IMU clock.
pub fn segments(out: &FitOutcome) -> Segments {
    let mut segs = Segments {
        segments: Vec::new(),
        rejected: Vec::new(),
        skipped: Vec::new(),
    };
    for r in &out.reports {
        if let Some(log) = &r.log {
            log_segments(r, log, &mut segs);
            continue;
        }
        let (Some(ang), Some(sp)) = (&r.angles, &r.speed) else {
            segs.skipped
                .push(format!("{}: no angle and speed record", r.run.display()));
            continue;
        };
        let offset = r.clock_offset.map_or(0.0, |c| c.value);
        for k in &r.kicks {
            let [w0, mut w1] = k.window;
            // The eigenvalue fit stops where the oscillation has decayed (or
            // drifts, or the speed has changed much); the nonlinear model
            // describes what follows too, and slow effects (speed decay, a
            // steady lean) show mostly there. So the identification window
            // goes on to the end of the free motion: the record's end, a
            // gap, or a fall, at most IDENTIFY_WINDOW after the start.
            if matches!(
                k.window_end,
                WindowEnd::Decayed | WindowEnd::Drift | WindowEnd::SpeedChange
            ) {
                let fall = PipelineOptions::default().kicks.fall_angle;
                let dt = (ang.t[ang.t.len() - 1] - ang.t[0]) / (ang.t.len().max(2) - 1) as f64;
                let i0 = ang.t.partition_point(|&x| x < w0);
                let mut end = w1;
                for i in i0..ang.t.len() {
                    if ang.t[i] > w0 + IDENTIFY_WINDOW
                        || ang.roll[i].abs() > fall
                        || (i > i0 && ang.t[i] - ang.t[i - 1] > 3.0 * dt)
                    {
                        break;
                    }
                    end = ang.t[i];
                }
                w1 = end.max(w1);
            }
            let idx: Vec<usize> = (0..ang.t.len()).filter(|&i| ang.t[i] >= w0 && ang.t[i] <= w1).collect();
            let speed_idx: Vec<usize> = (0..sp.t.len())
                .filter(|&i| sp.t[i] + offset >= w0 && sp.t[i] + offset <= w1 && sp.v[i].is_finite())
                .collect();
            let weave = k.measured_weave().map(|f| (f.eigenvalue, f.eigenvalue_stderr));
            let seg = Segment::new(
                r.run.display().to_string(),
                w0,
                idx.iter().map(|&i| ang.t[i] - w0).collect(),
                idx.iter().map(|&i| ang.roll[i]).collect(),
                idx.iter().map(|&i| ang.steer[i]).collect(),
                speed_idx.iter().map(|&i| sp.t[i] + offset - w0).collect(),
                speed_idx.iter().map(|&i| sp.v[i]).collect(),
                weave,
            )
            .map(Segment::with_steer_bias);
            keep(seg, 0.5, r, k, [w0, w1], &mut segs);
        }
    }
    segs
}

/// The segments of a TU Delft log: each kick's free-response window as the
/// measured-run pipeline found it (the next kick, or the decay into noise,
/// ends it; after the decay the person running beside the riderless
/// bicycle may already hold it). The roll channel is the gyro's roll rate
/// (the log's lean angle is a filter's estimate, distorted by the lateral
/// acceleration of the kick); steer is the fork angle, the angle the
/// model's steer is; speed is the log's, held by the hub motor, so these
/// segments are simulated with the speed imposed.
///
/// Signs: the logs have roll and fork angle of the same sign when the
/// bicycle steers into the lean (benchmark convention, steer positive to
/// the right), bikedyn's models have steer positive to the left: the fork
/// angle is negated. (A mirror image of both would be the same motion for
/// the symmetric models; only a lateral mass offset would flip.)
fn log_segments(
    r: &bikedyn_runtime::experiment::RunReport,
    log: &bikedyn_runtime::experiment::records::TudelftLog,
    segs: &mut Segments,
) {
    for k in &r.kicks {
        let [w0, w1] = k.window;
        let idx: Vec<usize> = (0..log.t.len()).filter(|&i| log.t[i] >= w0 && log.t[i] <= w1).collect();
        let pick = |x: &[f64]| idx.iter().map(|&i| x[i]).collect::<Vec<f64>>();
        let t: Vec<f64> = idx.iter().map(|&i| log.t[i] - w0).collect();
        let steer: Vec<f64> = idx.iter().map(|&i| -log.fork[i]).collect();
        let weave = k.measured_weave().map(|f| (f.eigenvalue, f.eigenvalue_stderr));
        let seg = Segment::with_roll_rate(
            r.run.display().to_string(),
            w0,
            t.clone(),
            pick(&log.roll),
            pick(&log.roll_rate),
            steer,
            t,
            pick(&log.speed),
            weave,
        );
        keep(seg, MIN_LOG_WINDOW, r, k, [w0, w1], segs);
    }
}

/// Keep a kick's segment if it is at least `min_len` s long, with the
/// eigenvalue fit's speeds, quality and verdict; else say why it was
/// skipped.
fn keep(
    seg: Option<Segment>,
    min_len: f64,
    r: &bikedyn_runtime::experiment::RunReport,
    k: &bikedyn_runtime::experiment::KickFit,
    [w0, w1]: [f64; 2],
    segs: &mut Segments,
) {
    match seg {
        Some(mut s) if s.duration() >= min_len => {
            // The eigenvalue belongs to the fit window: compare and draw it
            // at that window's speeds.
            if k.mean_speed.is_finite() && k.speed_interval.iter().all(|v| v.is_finite()) {
                s.mean_speed = k.mean_speed;
                s.speed_interval = k.speed_interval;
            }
            s.weave_r2 = k.measured_weave().map(|f| f.r2);
            segs.segments.push(s);
            segs.rejected.push(k.rejected);
        }
        _ => segs.skipped.push(format!(
            "{}: kick at {:.2} s has no usable window ({w0:.2}-{w1:.2} s)",
            r.run.display(),
            k.kick_time,
        )),
    }
}

/// Whether the inputs are TU Delft logs (the hub motor holds the speed, so
/// it is imposed on the model) rather than thesis-style runs (free speed
/// after the release). Both in one request is an error.
pub fn speed_imposed(inputs: &[std::path::PathBuf]) -> Result<bool, super::IdentifyError> {
    use crate::runs::{classify, Input};
    let (mut logs, mut runs) = (Vec::new(), Vec::new());
    for path in inputs {
        for input in classify(path)? {
            match input {
                Input::Log(p) => logs.push(p),
                Input::Set { .. } => runs.push(path.clone()),
            }
        }
    }
    if !logs.is_empty() && !runs.is_empty() {
        return Err(super::IdentifyError::MixedInputs {
            inputs: runs.iter().chain(&logs).map(|p| p.display().to_string()).collect(),
        });
    }
    Ok(!logs.is_empty())
}

/// Shortest window of a log's kick (s): about a weave period of a heavily
/// damped response (the assisted bicycle's decays within one or two).
const MIN_LOG_WINDOW: f64 = 0.4;

/// Longest identification window after a kick (s): a few weave periods and
/// long enough for the speed to fall measurably; longer costs simulation
/// time for little more information.
const IDENTIFY_WINDOW: f64 = 4.0;
