//! Discovery in the time series (issue 37, item 2): after the library's
//! search, the terms of the dictionary of generalized forces that the
//! identification model carries (`modeler/src/effects/generalized_forces.rs`)
//! are tried one at a time through the nonlinear simulation of every kick,
//! with the library's selection refitted beside them and the same tests
//! (`bikedyn_runtime::identify::discovery::time_series`). This file builds
//! the candidates, runs the search inside the model's type, and says what
//! was found in physical words; the runtime computes.

use super::discovery::{effect_file, reading};
use super::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::discovery::time_series::{
    discover_in_time_series, NotSearched, SecondStart, TimeSeriesDiscovery,
};
use bikedyn_runtime::identify::discovery::{FoundTerm, Signal, Term, ALIKE_BIC};
use bikedyn_runtime::identify::{pooled_rms, Candidate, EffectParameter, Identification, IdentifyOptions, Segment};
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::model::unit_of;
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::MultibodyModel;
use serde::Serialize;

pub use super::candidates::DICTIONARY_EFFECT;

/// Most terms the search adds.
pub const MAX_TERMS: usize = 2;

/// Typical size of a term's coefficient (the fit's scale, never a bound):
/// a tenth of a newton metre on the steer and one on the roll equation
/// per unit of the signal (rad, rad/s), per (5 m/s)^p for a speed power
/// `p` (a bicycle's weave runs at a few metres per second).
fn scale(term: &Term) -> f64 {
    let equation = match term.equation {
        bikedyn_runtime::identify::discovery::Coordinate::Roll => 1.0,
        bikedyn_runtime::identify::discovery::Coordinate::Steer => 0.1,
    };
    equation / 5f64.powi(i32::from(term.speed_power))
}

/// The dictionary's terms that model `info` carries, each a candidate of
/// one parameter (its coefficient in the model's signs). A Coulomb-like
/// term must come out positive (it dissipates) and is always fitted (its
/// law is not smooth at zero, see [`Candidate::nonsmooth`]).
pub fn terms(info: &ModelInfo) -> Vec<(Term, Candidate)> {
    Term::time_series_dictionary()
        .into_iter()
        .filter_map(|t| {
            let symbol = t.model_symbol();
            let p = info.parameter(&symbol)?;
            let coulomb = matches!(t.signal, Signal::Coulomb(_));
            Some((
                t,
                Candidate {
                    name: t.name(),
                    effects: vec![DICTIONARY_EFFECT.to_string()],
                    parameters: vec![EffectParameter {
                        symbol,
                        tied: Vec::new(),
                        moves: Vec::new(),
                        scale: scale(&t),
                        dissipative: coulomb,
                        unit: unit_of(p.doc).unwrap_or_default().to_string(),
                        initial: None,
                        lower: None,
                        upper: None,
                        shape: false,
                        prior: None,
                        gross_beyond: bikedyn_runtime::identify::PLAUSIBLE_PRIOR_SDS,
                    }],
                    fixed: Vec::new(),
                    speed_decay: false,
                    reason: "a term of the dictionary of generalized forces".into(),
                    alternative_model: false,
                    nonsmooth: coulomb,
                },
            ))
        })
        .collect()
}

/// Roll-channel errors of one stage (rad, or rad/s for a rate channel):
/// pooled over every kick and its median run, fitted and held out.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct StageErrors {
    pub roll_rms: f64,
    pub roll_rms_held_out: f64,
    pub steer_rms: f64,
    pub steer_rms_held_out: f64,
}

impl StageErrors {
    fn of(fit: &bikedyn_runtime::identify::CandidateFit) -> Self {
        Self {
            roll_rms: pooled_rms(&fit.errors, 0),
            roll_rms_held_out: pooled_rms(&fit.held_out, 0),
            steer_rms: pooled_rms(&fit.errors, 1),
            steer_rms_held_out: pooled_rms(&fit.held_out, 1),
        }
    }
}

/// What the search in the time series found, with the errors of the three
/// stages: the base model, the library's selection, and with the terms.
#[derive(Clone, Debug, Serialize)]
pub struct TimeSeriesFound {
    #[serde(flatten)]
    pub search: TimeSeriesDiscovery,
    /// Each added term with its coefficient in the benchmark's signs (roll
    /// and steer positive to the right), `(value, one standard error)`.
    pub terms: Vec<FoundTerm>,
    /// Each found term in physical words.
    pub readings: Vec<String>,
    pub base: StageErrors,
    pub library: StageErrors,
    /// With the terms added. (Named apart from the search's own `after`,
    /// the fit, which the flattened search also writes.)
    pub with_terms: StageErrors,
}

/// Why the search in the time series did not run, or what it found.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum TimeSeriesOutcome {
    Ran(Box<TimeSeriesFound>),
    NotRun { reason: String },
}

/// The search inside the identification model's type.
pub(super) struct Search<'a, R: ModelRegistry> {
    pub(super) bike: &'a Bicycle<R>,
    pub(super) segments: &'a [Segment],
    pub(super) library: &'a Identification,
    pub(super) candidates: &'a [Candidate],
    pub(super) terms: &'a [(Term, Candidate)],
    pub(super) opts: &'a IdentifyOptions,
    pub(super) progress: &'a (dyn Fn(&str, Option<(usize, usize)>) + Sync),
}

impl<R: ModelRegistry> ModelVisitor for Search<'_, R> {
    type Output = Result<TimeSeriesOutcome, IdentifyError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let lookup = self.bike.lookup()?;
        let base = parameter_vector::<M>(&lookup, 5.0)?;
        let candidates: Vec<Candidate> = self.terms.iter().map(|(_, c)| c.clone()).collect();
        let found = discover_in_time_series::<M>(
            &base,
            self.segments,
            self.library,
            self.candidates,
            &candidates,
            self.opts,
            MAX_TERMS,
            self.progress,
        )?;
        Ok(match found {
            Err(NotSearched::AlternativeModel(c)) => TimeSeriesOutcome::NotRun {
                reason: format!(
                    "the library's `{c}` is fitted with a model of its own, which does not carry the dictionary"
                ),
            },
            Err(NotSearched::NoTerms) => TimeSeriesOutcome::NotRun {
                reason: "the identification model carries no term of the dictionary".into(),
            },
            Ok(search) => TimeSeriesOutcome::Ran(Box::new(found_terms(search, self.library, self.terms))),
        })
    }
}

/// The added terms in the benchmark's signs, with the terms each step's
/// rows do not tell from the added one (criterion within [`ALIKE_BIC`]).
fn found_terms(
    search: TimeSeriesDiscovery,
    library: &Identification,
    dictionary: &[(Term, Candidate)],
) -> TimeSeriesFound {
    let term_of = |name: &str| dictionary.iter().find(|(_, c)| c.name == name).map(|(t, _)| *t);
    let mut terms = Vec::new();
    for name in &search.selected {
        let Some(term) = term_of(name) else { continue };
        let symbol = term.model_symbol();
        let Some(k) = search.after.parameters.iter().position(|p| p.symbol == symbol) else {
            continue;
        };
        let value = search.after.values[k] * term.model_sign();
        let se = search.after.stderr[k];
        let alike = search
            .steps
            .iter()
            .find(|s| s.added.contains(name))
            .map(|s| {
                let added = s.added_trial().and_then(|t| t.fit.as_ref()).map_or(f64::NAN, |f| f.bic);
                s.trials
                    .iter()
                    .filter(|t| !t.verdict.added())
                    .filter(|t| t.fit.as_ref().is_some_and(|f| (f.bic - added).abs() < ALIKE_BIC))
                    .filter_map(|t| term_of(&t.name))
                    .collect()
            })
            .unwrap_or_default();
        terms.push(FoundTerm {
            term,
            coefficient: Some((value, se)),
            time_constant: None,
            alike,
        });
    }
    TimeSeriesFound {
        readings: terms.iter().map(reading).collect(),
        base: StageErrors::of(&library.before),
        library: StageErrors::of(&library.after),
        with_terms: StageErrors::of(&search.after),
        terms,
        search,
    }
}

/// The summary's lines: the finding, and the roll error of the three
/// stages, fitted and held out by the folds of runs.
pub fn sentence(o: &TimeSeriesOutcome, unit: &str, scale: f64) -> String {
    match o {
        TimeSeriesOutcome::NotRun { reason } => format!("discovery in the time series not run: {reason}"),
        TimeSeriesOutcome::Ran(f) => {
            // The first step's trials: every term, and the pairs tried
            // when no term passed alone.
            let tried = |pairs: bool| {
                f.search.steps.first().map_or(0, |s| {
                    s.trials.iter().filter(|t| (t.members.len() > 1) == pairs).count()
                })
            };
            let found = if f.readings.is_empty() {
                format!(
                    "discovered in the time series: no term of the dictionary passes ({} terms, {} pairs tried)",
                    tried(false),
                    tried(true)
                )
            } else {
                format!("discovered in the time series: {}", f.readings.join("; "))
            };
            // What the backward check removed: the library's members, and
            // terms that entered before the last and stood in for it.
            let dictionary: Vec<String> = Term::time_series_dictionary().iter().map(Term::name).collect();
            // (The corrections a kept second start left out are said with it.)
            let left_out = |r: &String| {
                f.search
                    .second_start
                    .as_ref()
                    .is_some_and(|s| s.kept_second && s.left_out.iter().any(|l| &l.candidate == r))
            };
            let (terms, members): (Vec<&String>, Vec<&String>) = f
                .search
                .removed
                .iter()
                .filter(|r| !left_out(r))
                .partition(|r| dictionary.contains(r));
            let list = |names: &[&String]| names.iter().map(|n| n.as_str()).collect::<Vec<_>>().join(", ");
            let mut found = found;
            if let Some(second) = &f.search.second_start {
                found.push('\n');
                found.push_str(&second_start_sentence(second));
            }
            if !members.is_empty() {
                found.push_str(&format!(
                    "\nwith the terms, the backward check removed from the library's selection: {} (the terms explain the data better without it, or as well within one standard error of the held-out error)",
                    list(&members)
                ));
            }
            if !terms.is_empty() {
                found.push_str(&format!(
                    "\nthe backward check removed terms that entered before the last: {} (the model explains the data better without them, or as well within one standard error of the held-out error)",
                    list(&terms)
                ));
            }
            format!(
                "{found}\nroll RMS: base model {:.3}, with the library {:.3}, with the discovered terms {:.3} {unit}; held out: {:.3} -> {:.3} -> {:.3} {unit}",
                f.base.roll_rms * scale,
                f.library.roll_rms * scale,
                f.with_terms.roll_rms * scale,
                f.base.roll_rms_held_out * scale,
                f.library.roll_rms_held_out * scale,
                f.with_terms.roll_rms_held_out * scale,
            )
        }
    }
}

/// Why the search started twice, and which start's model was kept.
fn second_start_sentence(s: &SecondStart) -> String {
    let left: Vec<String> = s
        .left_out
        .iter()
        .map(|l| {
            format!(
                "`{}` ({} = {:.4}, {:.1} prior sd from the measured value)",
                l.candidate, l.symbol, l.value, l.prior_sds
            )
        })
        .collect();
    let terms = if s.other_selected.is_empty() {
        "no term".to_string()
    } else {
        format!("terms {}", s.other_selected.join(", "))
    };
    let (kept, verdict, other) = if s.kept_second {
        (
            "kept",
            "lower",
            format!("the first start (the library's whole selection, {terms})"),
        )
    } else {
        (
            "not kept",
            "not lower",
            format!("the first start; the second found {terms}"),
        )
    };
    format!(
        "second start of the search without the library's corrections beyond their plausible range, {}: {kept}, its held-out error {:.4} against {:.4} of {other}: {verdict} by more than one standard error ({:.4})",
        left.join(", "),
        s.cv_second,
        s.cv_first,
        s.standard_error
    )
}

/// The effect file of the found terms (`None` when none was found).
pub fn effect_file_of(o: &TimeSeriesOutcome) -> Option<Result<String, String>> {
    match o {
        TimeSeriesOutcome::Ran(f) if !f.terms.is_empty() => Some(effect_file("discovered", &f.terms)),
        _ => None,
    }
}

/// The report's section: every step of the search in the time series, each
/// term tried with its fit and verdict, and the errors of the three stages.
pub fn markdown(f: &TimeSeriesFound) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "\n## Discovery in the time series: terms of the dictionary\n\nGeneralized forces on the roll and steer equations that the model carries (`{DICTIONARY_EFFECT}`, every coefficient zero by default, in the model's signs: steer positive to the left), each tried as a candidate of its own after the library's search, with the library's selection refitted beside it and the same tests (criterion, held-out error of the same folds of runs, a gain consistent run by run). At most {MAX_TERMS} terms are added.\n"
    );
    if let Some(second) = &f.search.second_start {
        let _ = writeln!(
            s,
            "The library took corrections beyond their plausible range ({PLAUSIBLE} prior standard deviations), so the search started twice: from the library's whole selection, and from it without those corrections. The model of the second start is kept only if it predicts the held-out runs better than the first's by more than one standard error. {}.\n\nThe steps of the start kept:\n",
            second_start_sentence(second).replacen("second start", "Second start", 1),
            PLAUSIBLE = bikedyn_runtime::identify::PLAUSIBLE_PRIOR_SDS
        );
    }
    super::words::steps_markdown(&mut s, &f.search.steps, 1);
    let _ = writeln!(
        s,
        "Roll channel RMS (the fitted kicks; held out by the folds of runs): base model {:.4} ({:.4}), with the library {:.4} ({:.4}), with the discovered terms {:.4} ({:.4}) (rad or rad/s).",
        f.base.roll_rms,
        f.base.roll_rms_held_out,
        f.library.roll_rms,
        f.library.roll_rms_held_out,
        f.with_terms.roll_rms,
        f.with_terms.roll_rms_held_out
    );
    s
}
