//! The report's words for what the library leaves
//! (`identify::remaining` in the runtime computes it).

use bikedyn_runtime::identify::remaining::{Part, PatternTerm, Remaining, State};

fn state_text(s: State) -> &'static str {
    match s {
        State::Speed => "speed",
        State::SpeedSquared => "speed squared",
        State::LogAmplitude => "log amplitude",
    }
}

fn term_text(t: &PatternTerm) -> String {
    let (part, unit) = match t.part {
        Part::Real => ("real part", "1/s"),
        Part::Imaginary => ("imaginary part", "rad/s"),
    };
    match t.state {
        None => format!("{part} {:+.3} +- {:.3} {unit} on average", t.coefficient, t.stderr),
        Some(s) => format!(
            "{part} {:+.3} +- {:.3} {unit} per standard deviation of {}",
            t.coefficient,
            t.stderr,
            state_text(s)
        ),
    }
}

/// The states the pattern was sought in, in words.
pub fn regressors_text(r: &Remaining) -> String {
    std::iter::once("a constant")
        .chain(r.regressors.iter().map(|s| state_text(*s)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The finding in words: whether a structured residual remains, and what
/// share of a perfect model's gain the library made (`+-`: one standard
/// error). `what` names the measurements: "kicks", or a table's "rows".
pub fn remaining_sentence(r: &Remaining, what: &str) -> String {
    let pct = |x: f64| {
        if x.is_finite() {
            format!("{:.0} %", 100.0 * x)
        } else {
            "- (the base model is already within the scatter)".to_string()
        }
    };
    let figures = format!(
        "weave eigenvalue RMS: base model {:.3}, with the library {:.3} (held out {:.3}), floor of the {what}' scatter {:.3} 1/s over {} {what}; pattern in {} tested: F = {:.2} on {} and {} degrees of freedom, p = {:.2e}",
        r.base_rms,
        r.after_rms,
        r.held_out_rms,
        r.floor_rms,
        r.kicks,
        regressors_text(r),
        r.f,
        r.df[0],
        r.df[1],
        r.p_value,
    );
    if r.structured {
        let shows = if r.pattern.is_empty() {
            String::new()
        } else {
            format!(
                "; it shows as {} (1 SE)",
                r.pattern.iter().map(term_text).collect::<Vec<_>>().join(", ")
            )
        };
        format!(
            "a structured residual remains: the library explains {} of what a perfect model would ({} held out){shows} ({figures})",
            pct(r.explained),
            pct(r.explained_held_out),
        )
    } else {
        format!(
            "no structured residual remains in the weave: what the library leaves is within the {what}' scatter; it explains {} of what a perfect model would ({} held out) ({figures})",
            pct(r.explained),
            pct(r.explained_held_out),
        )
    }
}

/// Whether the time series' residual follows the motion, in words, one
/// clause per channel.
pub fn state_correlation_sentence(c: &[bikedyn_runtime::identify::state_correlation::StateCorrelation]) -> String {
    use bikedyn_runtime::identify::state_correlation::{Channel, StateSignal};
    let state = |s: StateSignal| match s {
        StateSignal::Roll => "roll channel",
        StateSignal::RollRate => "roll channel's rate",
        StateSignal::Steer => "steer angle",
        StateSignal::SteerRate => "steer rate",
    };
    let clauses: Vec<String> = c
        .iter()
        .map(|x| {
            let channel = match x.channel {
                Channel::Roll => "roll",
                Channel::Steer => "steer",
            };
            let along: Vec<String> = x
                .coefficients
                .iter()
                .filter(|(_, b, se)| b.abs() > 2.0 * se)
                .map(|(s, b, se)| format!("{} {b:+.3e} +- {se:.1e} per standard deviation", state(*s)))
                .collect();
            let test = format!(
                "R^2 = {:.3}, F = {:.2} on {:.0} and {:.0} effective degrees of freedom, p = {:.2e}; lag-1 autocorrelation {:.2}",
                x.r_squared, x.f, x.dof.0, x.dof.1, x.p_value, x.whiteness_lag1
            );
            if x.significant {
                format!(
                    "the {channel} residual follows the simulated states ({test}){}",
                    if along.is_empty() {
                        String::new()
                    } else {
                        format!(", along the {}", along.join(", "))
                    }
                )
            } else {
                format!("the {channel} residual does not follow the simulated states beyond chance ({test})")
            }
        })
        .collect();
    format!("in the time series, {}", clauses.join("; "))
}
