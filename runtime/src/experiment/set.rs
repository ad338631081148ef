//! A set of thesis-style runs: its calibration vetted (settled, at rest,
//! a plausible mounting), the steer axis taken from the runs that agree on
//! it (a run apart left out of it: set aside if its files look swapped,
//! else flagged), then every run processed, one at a time.
//!
//! The runs come from a [`RunSource`]: reading them (from run folders, the
//! application's `bikedyn::runs`) is not the numerics' business, but when
//! they are read is, since a set may be larger than memory.

use super::angles::{self, Calibration};
use super::records::{ImuRecord, ThesisRun};
use super::{process_thesis_run, PipelineOptions, RunError, RunReport, STEER_AXIS_APART};
use nalgebra::Vector3;
use std::path::Path;

/// Where a set's calibration and runs come from, each read when asked for,
/// so that [`process_set`] decides how many records are in memory at once.
/// Runs are numbered from 0 to [`run_count`](Self::run_count)` - 1`.
pub trait RunSource {
    /// Why a run could not be had (unreadable, corrupt), or failed the
    /// set's own checks ([`RunError`]: the calibration not at rest, a
    /// run's files swapped, ...).
    type Error: From<RunError>;
    /// How many runs the set has (the calibration not counted).
    fn run_count(&self) -> usize;
    /// The calibration run as messages name it (its folder).
    fn calibration_path(&self) -> &Path;
    /// Run `i` as messages name it (its folder).
    fn run_path(&self, i: usize) -> &Path;
    /// The calibration run, whole.
    fn calibration(&self) -> Result<ThesisRun, Self::Error>;
    /// Run `i`'s two orientation records (frame, handlebar), checked
    /// against each other as in a whole run, without its reed switch's
    /// record: the steer axis needs only these.
    fn orientations(&self, i: usize) -> Result<(ImuRecord, ImuRecord), Self::Error>;
    /// Run `i`, whole.
    fn run(&self, i: usize) -> Result<ThesisRun, Self::Error>;
}

/// Shortest settled calibration record (s): four of
/// [`Calibration::MOTION_BLOCK`], what [`Calibration::motion`] needs to
/// tell rest from motion.
pub const MIN_SETTLED_S: f64 = 4.0 * Calibration::MOTION_BLOCK;

/// Largest mounting misalignment of a sensor (rad): the sensors are fixed
/// along the body axes, off by a few degrees (the example set's handlebar
/// sensor by 11); a calibration rotated half a turn gave 155 deg and was
/// used without a word.
pub const MAX_MISALIGNMENT_RAD: f64 = 30.0 * std::f64::consts::PI / 180.0;

/// Refuse a calibration whose estimated misalignment of either sensor is
/// beyond [`MAX_MISALIGNMENT_RAD`].
fn check_misalignment(cal: &Calibration, run: &Path) -> Result<(), RunError> {
    let (frame, handlebar) = cal.misalignment_angles();
    for (sensor, rotation, euler) in [("frame", &cal.frame, frame), ("handlebar", &cal.handlebar, handlebar)] {
        let angle = rotation.angle();
        if angle > MAX_MISALIGNMENT_RAD {
            return Err(RunError::ImplausibleMisalignment {
                run: run.to_path_buf(),
                sensor,
                angle,
                euler,
            });
        }
    }
    Ok(())
}

/// Process a set of thesis-style runs: calibration (completed with the
/// steer axis seen in the runs), then every run; a corrupt run gives its
/// error and the others go on. `progress` is called after each run.
///
/// Runs are read from `source` one at a time, twice: first their
/// orientations alone, of which only the relative rotations that show the
/// steer axis are kept, then each whole run, processed and dropped before
/// the next is read. So memory holds one run's records at a time, whatever
/// the set's size.
pub fn process_set<S: RunSource + ?Sized>(
    source: &S,
    opt: &PipelineOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<(Calibration, Vec<Result<RunReport, S::Error>>), S::Error> {
    let calibration = source.calibration_path();
    let cal_run = source.calibration()?;
    let mut cal = Calibration::estimate(&cal_run, opt.frame_pitch);
    match cal.motion(&cal_run) {
        Some(motion) if !motion.at_rest() => {
            return Err(RunError::NotAtRest {
                run: calibration.to_path_buf(),
                motion,
            }
            .into())
        }
        Some(_) => {}
        // Too short to tell rest from motion: a record cut to a few rows
        // gave a misalignment from noise, silently.
        None => {
            let t = &cal_run.frame.t;
            return Err(RunError::CalibrationTooShort {
                run: calibration.to_path_buf(),
                settled: t.last().map_or(0.0, |e| e - cal.settled_from),
                samples: t.len(),
            }
            .into());
        }
    }
    // The steer axis from the runs that agree on it: a bad run must not
    // turn it, and through it every other run's angles. A run whose own
    // axis lies apart is left out of it and flagged, not dropped: on
    // realistic sensors a good run's axis, from few samples above the
    // noise and with heading drift, can lie several medians out.
    // A run apart whose two files' tilts against gravity match the
    // calibration's sensors the other way round has its files swapped: it
    // is set aside, since its angles would be wrong.
    let rest_up = Calibration::typical_up(&cal_run.frame, &cal_run.handlebar, cal.settled_from);
    // Each run's relative rotations and its sensors' typical up.
    type Seen = (Vec<Vector3<f64>>, Option<(Vector3<f64>, Vector3<f64>)>);
    let seen: Vec<Result<Seen, S::Error>> = (0..source.run_count())
        .map(|i| {
            source.orientations(i).map(|(frame, handlebar)| {
                (
                    cal.relative_rotations(&frame, &handlebar),
                    Calibration::typical_up(&frame, &handlebar, cal.settled_from),
                )
            })
        })
        .collect();
    let readable: Vec<(usize, &Seen)> = seen
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.as_ref().ok().map(|r| (i, r)))
        .collect();
    let consensus =
        Calibration::steer_axis_consensus(&readable.iter().map(|(_, r)| r.0.as_slice()).collect::<Vec<_>>());
    // Runs apart (angle and limit), and among them the swapped ones.
    let mut apart: Vec<Option<(f64, f64)>> = vec![None; source.run_count()];
    let mut swapped: Vec<Option<S::Error>> = (0..source.run_count()).map(|_| None).collect();
    for ((i, (_, up)), v) in readable.iter().zip(&consensus.runs) {
        let angles::RunAxisVerdict::Inconsistent { angle, limit } = *v else {
            continue;
        };
        apart[*i] = Some((angle, limit));
        if let (Some((rest_f, rest_h)), Some((f, h))) = (rest_up, up) {
            let as_named = f.angle(&rest_f) + h.angle(&rest_h);
            let as_swapped = f.angle(&rest_h) + h.angle(&rest_f);
            if as_swapped < as_named {
                swapped[*i] = Some(
                    RunError::SensorsSwapped {
                        run: source.run_path(*i).to_path_buf(),
                        angle,
                        limit,
                        as_swapped,
                        as_named,
                    }
                    .into(),
                );
            }
        }
    }
    let unreadable: Vec<Option<S::Error>> = seen
        .into_iter()
        .zip(swapped)
        .map(|(r, swapped)| r.err().or(swapped))
        .collect();
    if let Some(axis) = consensus.axis {
        cal = cal.with_steer_axis(&cal_run, &axis);
    }
    drop(cal_run);
    check_misalignment(&cal, calibration)?;
    let out = apart
        .into_iter()
        .zip(unreadable)
        .enumerate()
        .map(|(i, (apart, unreadable))| {
            let rep = match unreadable {
                Some(e) => Err(e),
                None => source.run(i).map(|run| {
                        let mut report = process_thesis_run(&run, &cal, opt);
                        if let Some((angle, limit)) = apart {
                            report.notes.push(format!(
                                "{STEER_AXIS_APART}: its handlebar sensor turns about an axis {:.1} deg from the steer axis the set's other runs share (beyond {:.1} deg, {} times their median scatter or {:.0} deg); it is left out of the set's steer axis and fitted with it: check that its frame and handlebar files are not swapped and that both sensors sat on their mounts as in the other runs",
                                angle.to_degrees(),
                                limit.to_degrees(),
                                Calibration::STEER_AXIS_SCATTERS,
                                Calibration::STEER_AXIS_TOLERANCE.to_degrees()
                            ));
                        }
                        report
                    }),
            };
            progress();
            rep
        })
        .collect();
    Ok((cal, out))
}
