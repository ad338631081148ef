//! The acceptance verdicts of measured eigenvalues in words
//! (`bikedyn_runtime::experiment::accept`): a short label for table cells
//! and a sentence with the test's numbers.

use bikedyn_runtime::experiment::accept::{Rejected, SpeedFormRejected};

/// A few words for a table cell.
pub fn rejected_label(r: &Rejected) -> &'static str {
    match r {
        Rejected::NoFit => "no fit",
        Rejected::OnlySpeedForm { .. } => "speed form refused",
        Rejected::AboveNyquist { .. } => "above Nyquist/4",
        Rejected::FewPeriods { .. } => "too few periods",
        Rejected::LowR2 { .. } => "low r2",
        Rejected::LargeStderr { .. } => "large stderr",
        Rejected::NoSpeed => "no speed",
        Rejected::NoModelWeave { .. } => "no model weave",
        Rejected::Outlier { .. } => "outlier",
    }
}

/// Why a fitted eigenvalue is not a measured weave eigenvalue, with the
/// test's numbers.
pub fn rejected_text(r: &Rejected) -> String {
    match *r {
        Rejected::NoFit => "no form of the fit converged to an oscillation".into(),
        Rejected::OnlySpeedForm { why } => format!(
            "only the speed-varying form converged, and it may not be reported: {}",
            speed_form_text(&why)
        ),
        Rejected::AboveNyquist { omega, limit, rate } => format!(
            "frequency {omega:.2} rad/s above {limit:.2} rad/s, a quarter of the Nyquist frequency of the {rate:.0} Hz record: not an oscillation the record resolves"
        ),
        Rejected::FewPeriods { periods, min } => {
            format!("the window holds {periods:.2} periods of the fitted frequency, fewer than {min}: not an oscillation the record resolves")
        }
        Rejected::LowR2 { r2, min } => format!("fit r2 {r2:.3} below {min}: not a clean oscillation"),
        Rejected::LargeStderr {
            stderr,
            modulus,
            max_fraction,
        } => format!(
            "standard errors {:.3}, {:.3} 1/s above {:.0} % of the eigenvalue's modulus {modulus:.3} 1/s: not determined",
            stderr[0],
            stderr[1],
            100.0 * max_fraction
        ),
        Rejected::NoSpeed => "no speed record in the window: no speed to place the eigenvalue at".into(),
        Rejected::NoModelWeave { speed } => {
            format!("the model has no oscillatory weave at {speed:.2} m/s (merged with the slow modes)")
        }
        Rejected::Outlier {
            measured,
            predicted,
            sigmas,
            max,
        } => format!(
            "measured {:.2}{:+.2}i misses the model's {:.2}{:+.2}i by {sigmas:.1} robust standard deviations of the other kicks' misfits (its own standard error included; beyond {max})",
            measured[0], measured[1], predicted[0], predicted[1]
        ),
    }
}

/// A few words for why the speed-varying form is not reported.
pub fn speed_form_label(r: &SpeedFormRejected) -> &'static str {
    match r {
        SpeedFormRejected::NoBound => "no model slope",
        SpeedFormRejected::SmallSpeedChange { .. } => "speed change too small",
        SpeedFormRejected::NotSignificant { .. } => "slope not significant",
        SpeedFormRejected::Implausible { .. } => "slope implausible",
    }
}

/// Why the speed-varying form is not reported (the constant form is), with
/// the test's numbers.
pub fn speed_form_text(r: &SpeedFormRejected) -> String {
    match *r {
        SpeedFormRejected::NoBound => {
            "no model slope d(lambda)/dv at the kick's speed to bound the speed-varying form's".into()
        }
        SpeedFormRejected::SmallSpeedChange {
            speed_change,
            model_change,
            stderr,
        } => format!(
            "over the window's speed change of {speed_change:.3} m/s the model's weave moves by {model_change:.3} 1/s, less than the eigenvalue's standard error {stderr:.3} 1/s"
        ),
        SpeedFormRejected::NotSignificant {
            slope,
            stderr,
            min_sigmas,
        } => format!(
            "slope {:.2}{:+.2}i (1/s)/(m/s) is within {min_sigmas} standard errors ({:.2}, {:.2}) of zero in both parts",
            slope[0], slope[1], stderr[0], stderr[1]
        ),
        SpeedFormRejected::Implausible { slope, model, factor } => format!(
            "slope of modulus {slope:.2} (1/s)/(m/s) beyond {factor} times the model's {model:.3} at the kick's speed"
        ),
    }
}
