//! The terminal rendering of the library's progress reports (a bar with
//! its time left on a terminal, one line per step otherwise).

use bikedyn::progress::Progress;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::OnceLock;
use std::time::Duration;

/// Renders the library's progress reports on standard error. On a
/// terminal: a bar with the stage's count and an estimate of the time left
/// for stages whose size is known (runs processed; a step's candidate fits;
/// its cross-validations), shown when the stage has more than three steps,
/// and a spinner with the last stage done otherwise. Not on a terminal (a
/// log, a pipe): one line per step with the counts, the time so far and the
/// estimate of the stage's time left.
pub struct ProgressDisplay {
    bar: OnceLock<ProgressBar>,
    spinner: OnceLock<ProgressBar>,
    start: std::time::Instant,
    /// The current counted stage: its total and when it started.
    stage: std::sync::Mutex<Option<(usize, std::time::Instant)>>,
}

impl ProgressDisplay {
    pub fn new() -> Self {
        Self {
            bar: OnceLock::new(),
            spinner: OnceLock::new(),
            start: std::time::Instant::now(),
            stage: std::sync::Mutex::new(None),
        }
    }

    /// The time left in a stage of `total` steps with `done` done since
    /// `started` (s): the mean time per step so far, times the steps left.
    fn time_left(done: usize, total: usize, started: std::time::Instant) -> f64 {
        let per_step = started.elapsed().as_secs_f64() / done.max(1) as f64;
        per_step * total.saturating_sub(done) as f64
    }

    /// Show one report (the library's callback).
    pub fn show(&self, p: Progress<'_>) {
        let terminal = std::io::stderr().is_terminal();
        let what = if p.step == "runs" { "runs processed" } else { p.step };
        // A new counted stage starts at its first step or when the total
        // changes (the next step of a selection fits fewer candidates).
        let stage_start = p.total.map(|total| {
            let mut stage = self.stage.lock().unwrap_or_else(|e| e.into_inner());
            match *stage {
                Some((t, started)) if t == total && p.done > 1 => started,
                _ => {
                    // The stage's clock starts at its first report, so the
                    // estimate uses the steps after the first (`time_left`
                    // below is given `done - 1` of `total - 1`).
                    let started = std::time::Instant::now();
                    *stage = Some((total, started));
                    started
                }
            }
        });
        if !terminal {
            let secs = self.start.elapsed().as_secs_f64();
            match (p.total, stage_start) {
                (Some(total), Some(started)) => {
                    let left = if p.done >= total {
                        String::new()
                    } else if p.done > 1 {
                        let left = Self::time_left(p.done - 1, total - 1, started);
                        format!(", about {} left in this stage", format_duration(left))
                    } else {
                        String::new()
                    };
                    eprintln!("progress: {what} ({} of {total}, {secs:.1} s{left})", p.done);
                }
                _ => eprintln!("progress: {what} ({} done, {secs:.1} s)", p.done),
            }
            return;
        }
        match p.total {
            Some(total) => {
                let bar = self.bar.get_or_init(|| {
                    let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::hidden());
                    if let Ok(style) =
                        ProgressStyle::with_template("{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
                    {
                        bar.set_style(style);
                    }
                    bar
                });
                if p.done <= 1 || bar.length() != Some(total as u64) {
                    bar.reset();
                    bar.set_length(total as u64);
                }
                if total > 3 && bar.is_hidden() {
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                }
                if let Some(s) = self.spinner.get() {
                    s.set_message(format!("identify: {what}"));
                }
                bar.set_message(what.to_string());
                bar.set_position(p.done as u64);
            }
            None => {
                let spinner = self.spinner.get_or_init(|| {
                    let s = ProgressBar::new_spinner();
                    s.enable_steady_tick(Duration::from_millis(200));
                    s
                });
                spinner.set_message(format!("identify: {what}"));
            }
        }
    }
}

/// "12 s", "3 min 5 s".
fn format_duration(secs: f64) -> String {
    let s = secs.max(0.0).round() as u64;
    if s < 60 {
        format!("{s} s")
    } else {
        format!("{} min {} s", s / 60, s % 60)
    }
}

impl Drop for ProgressDisplay {
    fn drop(&mut self) {
        for b in [self.bar.get(), self.spinner.get()].into_iter().flatten() {
            b.finish_and_clear();
        }
    }
}
