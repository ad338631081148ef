//! `bikedyn identify`: close the loop on a measured set (issue 9). The
//! measured-run pipeline (`fit`) finds the kicks and their windows; the
//! numerics are `runtime::identify` (time-series residuals against the
//! nonlinear simulation, stepwise selection by BIC and cross-validation);
//! this module builds the candidates from the effect library, diagnoses the
//! residual pattern, and writes the report folder.

use crate::bicycle::Bicycle;
use crate::fit::{run_fit, FitArgs, FitOutcome};
use crate::generated::{with_model, MODELS};
use anyhow::{bail, Context, Result};
use bikedyn_runtime::experiment::{kicks::WindowEnd, PipelineOptions};
use bikedyn_runtime::identify::plot::{plot_continuation, plot_run, Channel, MeasuredWeave};
use bikedyn_runtime::identify::{
    identify, pooled_rms, Candidate, EffectParameter, Factory, Identification, IdentifyOptions, ModelFactory, Segment,
    SegmentError, Setup,
};
use bikedyn_runtime::linearize::{lateral_block, linearize_at_speed, parameter_vector, state_space_at_speed};
use bikedyn_runtime::model::{CandidateDeclaration, EffectIdentification, LinearEquivalent, Signature};
use bikedyn_runtime::output::{save_json, write_string_atomic};
use bikedyn_runtime::registry::{ModelInfo, ModelVisitor};
use bikedyn_runtime::MultibodyModel;
use clap::Args;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// The committed example set: six runs of the thesis bicycle made by
/// `bikedyn synth` with steer damping hidden (`examples/data/README.md`).
pub const EXAMPLE_SET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/hidden_steer_damping");

/// Arguments of `bikedyn identify`.
#[derive(Args, Debug, Clone)]
pub struct IdentifyArgs {
    /// Set folders (all runs) or run folders.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Calibration run (default: `calibration/` beside the runs).
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// Bicycle (built-in name or parameter file); its effect parameters, if
    /// any, are part of the model before identification.
    #[arg(long, default_value = "thesis")]
    pub bike: String,
    /// Candidate effects to consider (comma-separated; default: every
    /// effect of the library that identification supports).
    #[arg(long, value_delimiter = ',')]
    pub effects: Vec<String>,
    /// Report folder (report.md, report.json, plots, fitted parameter file).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Print the JSON summary instead of the text summary.
    #[arg(long)]
    pub json: bool,
    /// Folds of the cross-validation over runs.
    #[arg(long, default_value_t = 4)]
    pub folds: usize,
}

/// The identification model, its driven twin, and the alternative model
/// (free speed, with states: the tyre model) if the registry has one. Each is
/// chosen by capability: it can represent the bicycle (has every parameter
/// the bicycle sets) and carries the most effects.
fn identification_models(
    bike: &Bicycle,
) -> Result<(&'static ModelInfo, &'static ModelInfo, Option<&'static ModelInfo>)> {
    let nonzero = bike.nonzero_parameters()?;
    let (free, driven) = identification_model_pair(bike)?;
    let alt = MODELS
        .iter()
        .filter(|m| {
            m.free_speed
                && !m.states.is_empty()
                && crate::models::fits(m, &nonzero)
                && free.effects.iter().all(|e| m.effects.contains(e))
        })
        .max_by_key(|m| m.effects.len());
    Ok((free, driven, alt))
}

/// The free-speed model without extra states that can represent the
/// bicycle and carries the most effects (every candidate of the library on
/// every geometry), and its driven-speed twin (same effects).
fn identification_model_pair(bike: &Bicycle) -> Result<(&'static ModelInfo, &'static ModelInfo)> {
    let nonzero = bike.nonzero_parameters()?;
    let free = MODELS
        .iter()
        .filter(|m| m.free_speed && m.states.is_empty() && crate::models::fits(m, &nonzero))
        .max_by_key(|m| m.effects.len())
        .with_context(|| format!("no free-speed model in the registry can represent `{}`", bike.name))?;
    let driven = MODELS
        .iter()
        .find(|m| !m.free_speed && m.effects == free.effects && crate::models::fits(m, &nonzero))
        .with_context(|| format!("no driven-speed model with the effects of `{}`", free.name))?;
    Ok((free, driven))
}

/// The candidates for a model: every effect it carries whose effect file
/// declares it a candidate (and is in `only` when given), with what its
/// declaration says: fitted parameters, ties, floors, held companions,
/// speed decay and the reason. An effect declared "own model" (tyre slip)
/// comes from the alternative model `alt`.
pub fn candidates(
    info: &ModelInfo,
    alt: Option<&ModelInfo>,
    bike: &Bicycle,
    only: &[String],
) -> Result<Vec<Candidate>> {
    let declared = |m: &ModelInfo| -> Vec<(&'static str, CandidateDeclaration)> {
        m.effect_declarations
            .iter()
            .filter_map(|e| match e.identification {
                Some(EffectIdentification::Candidate(c)) => Some((e.name, c)),
                _ => None,
            })
            .collect()
    };
    let mut pool: Vec<(&ModelInfo, &'static str, CandidateDeclaration)> = declared(info)
        .into_iter()
        .filter(|(_, c)| !c.own_model)
        .map(|(n, c)| (info, n, c))
        .collect();
    if let Some(a) = alt {
        pool.extend(
            declared(a)
                .into_iter()
                .filter(|(_, c)| c.own_model)
                .map(|(n, c)| (a, n, c)),
        );
    }
    for o in only {
        if !pool.iter().any(|(_, n, _)| n == o) {
            let known: Vec<&str> = pool.iter().map(|(_, n, _)| *n).collect();
            bail!(
                "--effects: `{o}` is not a candidate effect of the identification models ({})",
                known.join(", ")
            );
        }
    }
    let mut out = Vec::new();
    for (info, effect, d) in pool {
        if !(only.is_empty() || only.iter().any(|o| o == effect)) {
            continue;
        }
        let unit = |sym: &str| {
            info.parameter(sym)
                .map(|p| {
                    p.doc
                        .rsplit_once('(')
                        .map_or("", |(_, u)| u.trim_end_matches(')'))
                        .to_string()
                })
                .unwrap_or_default()
        };
        out.push(Candidate {
            name: effect.to_string(),
            effects: vec![effect.to_string()],
            parameters: d
                .fitted
                .iter()
                .map(|f| EffectParameter {
                    symbol: f.symbol.to_string(),
                    tied: f.tied.iter().map(|t| t.to_string()).collect(),
                    scale: f.scale,
                    dissipative: f.dissipative,
                    unit: unit(f.symbol),
                    initial: f
                        .start_at_default
                        .then(|| info.parameter(f.symbol).and_then(|p| p.default))
                        .flatten(),
                    lower: f.floor,
                })
                .collect(),
            fixed: d
                .held
                .iter()
                .filter_map(|sym| bike.value(sym).map(|v| (sym.to_string(), v)))
                .collect(),
            speed_decay: d.speed_decay,
            reason: d.reason.to_string(),
            alternative_model: d.own_model,
        });
    }
    Ok(out)
}

/// Effects a model carries that identification never tests, with the
/// reason their files give (or that they declare nothing).
pub fn not_candidates(info: &ModelInfo) -> Vec<(&'static str, String)> {
    info.effect_declarations
        .iter()
        .filter_map(|e| match e.identification {
            Some(EffectIdentification::Candidate(_)) => None,
            Some(EffectIdentification::OptOut(why)) => Some((e.name, why.to_string())),
            None => Some((e.name, "its effect file declares no identification".to_string())),
        })
        .collect()
}

/// The measured segments of a processed set: every kick with a free
/// response window, roll and steer from the pipeline's angles (IMU clock),
/// speed from the reed switch moved onto the IMU clock.
pub fn segments(out: &FitOutcome) -> (Vec<Segment>, Vec<String>) {
    let mut segs = Vec::new();
    let mut skipped = Vec::new();
    for r in &out.reports {
        let (Some(ang), Some(sp)) = (&r.angles, &r.speed) else {
            skipped.push(format!(
                "{}: no angles or speed record (TU Delft logs are not identified yet)",
                r.run.display()
            ));
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
            let weave = k.chosen_fit().map(|f| (f.eigenvalue, f.eigenvalue_stderr));
            let seg = Segment::new(
                r.run.display().to_string(),
                w0,
                idx.iter().map(|&i| ang.t[i] - w0).collect(),
                idx.iter().map(|&i| ang.roll[i]).collect(),
                idx.iter().map(|&i| ang.steer[i]).collect(),
                speed_idx.iter().map(|&i| sp.t[i] + offset - w0).collect(),
                speed_idx.iter().map(|&i| sp.v[i]).collect(),
                weave,
            );
            match seg {
                Some(mut s) if s.duration() >= 0.5 => {
                    // The eigenvalue belongs to the fit window: compare and
                    // draw it at that window's speeds.
                    if k.mean_speed.is_finite() && k.speed_interval.iter().all(|v| v.is_finite()) {
                        s.mean_speed = k.mean_speed;
                        s.speed_interval = k.speed_interval;
                    }
                    segs.push(s)
                }
                _ => skipped.push(format!(
                    "{}: kick at {:.2} s has no usable window ({:.2}-{:.2} s)",
                    r.run.display(),
                    k.kick_time,
                    w0,
                    w1
                )),
            }
        }
        if r.kicks.is_empty() {
            skipped.push(format!("{}: no kick found", r.run.display()));
        }
    }
    (segs, skipped)
}

/// Longest identification window after a kick (s): a few weave periods and
/// long enough for the speed to fall measurably; longer costs simulation
/// time for little more information.
const IDENTIFY_WINDOW: f64 = 4.0;

/// Weave eigenvalue `[re, im]` of a linearization (the complex pair with
/// the highest frequency), if any.
fn weave_of(l: &bikedyn_runtime::linearize::Linearization) -> Option<[f64; 2]> {
    let m = nalgebra::Matrix2::from_fn(|i, j| l.mass[(i, j)]);
    let c = nalgebra::Matrix2::from_fn(|i, j| l.damping[(i, j)]);
    let k = nalgebra::Matrix2::from_fn(|i, j| l.stiffness[(i, j)]);
    let mi = m.try_inverse()?;
    let (a, b) = (-mi * k, -mi * c);
    let mut s = nalgebra::Matrix4::zeros();
    s[(0, 2)] = 1.0;
    s[(1, 3)] = 1.0;
    for i in 0..2 {
        for j in 0..2 {
            s[(2 + i, j)] = a[(i, j)];
            s[(2 + i, 2 + j)] = b[(i, j)];
        }
    }
    s.complex_eigenvalues()
        .iter()
        .filter(|z| z.im > 1e-9)
        .max_by(|x, y| x.im.total_cmp(&y.im))
        .map(|z| [z.re, z.im])
}

struct WeaveCurve<'a> {
    lookup: &'a dyn Fn(&str) -> Option<f64>,
    speeds: &'a [f64],
}

impl ModelVisitor for WeaveCurve<'_> {
    type Output = Result<Vec<Option<[f64; 2]>>>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let p = parameter_vector::<M>(self.lookup, 1.0)?;
        Ok(self
            .speeds
            .iter()
            .map(|&v| {
                linearize_at_speed::<M>(&p, v)
                    .ok()
                    .and_then(|l| weave_of(&lateral_block::<M>(&l)))
            })
            .collect())
    }
}

/// Predicted weave eigenvalues of the driven model with effect values
/// `values` set on top of the bicycle, at each of `speeds` (m/s).
pub fn predict(
    driven: &ModelInfo,
    bike: &Bicycle,
    values: &BTreeMap<String, f64>,
    speeds: &[f64],
) -> Result<Vec<Option<[f64; 2]>>> {
    let base = bike.lookup()?;
    let lookup = |s: &str| values.get(s).copied().or_else(|| base(s));
    let guide = with_model(
        driven.name,
        WeaveCurve {
            lookup: &lookup,
            speeds,
        },
    )
    .expect("registered model")?;
    // Effects the driven model lacks (the tyre model's) are predicted with
    // the alternative model's state-space linearization.
    if let Some(alt) = values
        .keys()
        .any(|k| driven.parameter(k).is_none())
        .then(|| identification_models(bike).ok().and_then(|m| m.2))
        .flatten()
    {
        return with_model(
            alt.name,
            StateSpaceWeave {
                lookup: &lookup,
                speeds,
                guide: &guide,
            },
        )
        .expect("registered model");
    }
    Ok(guide)
}

/// Effect values of a fit, tied symbols and fixed companions included.
fn effect_values(
    fit: &bikedyn_runtime::identify::CandidateFit,
    values: &[f64],
    cands: &[Candidate],
) -> BTreeMap<String, f64> {
    let mut m = BTreeMap::new();
    for (p, v) in fit.parameters.iter().zip(values) {
        m.insert(p.symbol.clone(), *v);
        for t in &p.tied {
            m.insert(t.clone(), *v);
        }
    }
    for c in cands.iter().filter(|c| fit.effects.contains(&c.name)) {
        for (s, v) in &c.fixed {
            m.insert(s.clone(), *v);
        }
    }
    m
}

/// Mean absolute rate of a sampled angle (rad/s).
fn mean_abs_rate(t: &[f64], x: &[f64]) -> f64 {
    let d: Vec<f64> = t
        .windows(2)
        .zip(x.windows(2))
        .filter(|(a, _)| a[1] > a[0])
        .map(|(a, b)| ((b[1] - b[0]) / (a[1] - a[0])).abs())
        .collect();
    d.iter().sum::<f64>() / d.len().max(1) as f64
}

/// Effect values for a linear (eigenvalue) prediction: each effect whose
/// file declares a linear equivalent is replaced by it. Coulomb steer
/// friction has no useful linearization about upright (the smoothed law
/// linearizes to a stiff damper `T / w`), so it declares its
/// describing-function equivalent viscous damping at the response's steer
/// rate: for a sinusoid of amplitude `A`, `c_eq = 4 T / (pi A)`, with
/// `A = (pi / 2) mean|rate|`.
fn linear_equivalent(
    info: &ModelInfo,
    values: &BTreeMap<String, f64>,
    mean_abs_steer_rate: f64,
) -> BTreeMap<String, f64> {
    let mut v = values.clone();
    for e in info.effect_declarations {
        let Some(EffectIdentification::Candidate(CandidateDeclaration {
            linear_equivalent: Some(LinearEquivalent::DescribingFunctionDamping { torque, damping }),
            ..
        })) = e.identification
        else {
            continue;
        };
        if let Some(t) = v.get(torque).copied().filter(|t| *t != 0.0) {
            let amp = std::f64::consts::FRAC_PI_2 * mean_abs_steer_rate;
            let c_eq = if amp > 0.0 {
                4.0 * t / (std::f64::consts::PI * amp)
            } else {
                0.0
            };
            *v.entry(damping.into()).or_insert(0.0) += c_eq;
            v.insert(torque.into(), 0.0);
        }
    }
    v
}

/// Simulated channels of every segment before and after (plots, bias,
/// amplitude of the steer rate), and the typical segment.
struct RunPlot {
    segment: usize,
    before: Vec<Option<bikedyn_runtime::identify::Sim>>,
    after: Vec<Option<bikedyn_runtime::identify::Sim>>,
}

struct Identify<'a> {
    bike: &'a Bicycle,
    alt: Option<&'static ModelInfo>,
    segments: &'a [Segment],
    candidates: &'a [Candidate],
    opts: &'a IdentifyOptions,
    progress: &'a (dyn Fn(&str) + Sync),
}

impl ModelVisitor for Identify<'_> {
    type Output = Result<(Identification, Option<RunPlot>)>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let lookup = self.bike.lookup()?;
        let base = parameter_vector::<M>(&lookup, 5.0)?;
        let alt: Option<Box<dyn ModelFactory>> = match self.alt {
            Some(a) => Some(with_model(a.name, MakeFactory { lookup: &lookup }).expect("registered model")?),
            None => None,
        };
        let id = identify::<M>(
            &base,
            self.segments,
            self.candidates,
            alt.as_deref(),
            self.opts,
            self.progress,
        )?;
        // The typical run: median roll error before.
        let mut order: Vec<usize> = (0..self.segments.len()).collect();
        order.sort_by(|&a, &b| id.before.errors[a].roll_rms.total_cmp(&id.before.errors[b].roll_rms));
        let sel: Vec<&Candidate> = id
            .selected
            .iter()
            .filter_map(|n| self.candidates.iter().find(|c| &c.name == n))
            .collect();
        let before = Setup::new::<M>(&base, self.segments, &id.weights, &[])?;
        let after = match alt.as_deref().filter(|_| sel.iter().any(|c| c.alternative_model)) {
            Some(f) => f.setup(self.segments, &id.weights, &sel)?,
            None => Setup::new::<M>(&base, self.segments, &id.weights, &sel)?,
        };
        let plot = order.get(order.len() / 2).map(|&s| RunPlot {
            segment: s,
            before: (0..self.segments.len())
                .map(|i| before.simulated(&[], &self.segments[i], &id.before.nuisance[i]).ok())
                .collect(),
            after: (0..self.segments.len())
                .map(|i| {
                    after
                        .simulated(&id.after.values, &self.segments[i], &id.after.nuisance[i])
                        .ok()
                })
                .collect(),
        });
        Ok((id, plot))
    }
}

struct MakeFactory<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
}

impl<F: Fn(&str) -> Option<f64>> ModelVisitor for MakeFactory<'_, F> {
    type Output = Result<Box<dyn ModelFactory>>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        Ok(Box::new(Factory::<M>::new(parameter_vector::<M>(self.lookup, 5.0)?)))
    }
}

/// Weave eigenvalues of a model with extra states (state-space
/// linearization): the complex eigenvalue nearest each `guide` (the no-slip
/// model's weave).
struct StateSpaceWeave<'a> {
    lookup: &'a dyn Fn(&str) -> Option<f64>,
    speeds: &'a [f64],
    guide: &'a [Option<[f64; 2]>],
}

impl ModelVisitor for StateSpaceWeave<'_> {
    type Output = Result<Vec<Option<[f64; 2]>>>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let p = parameter_vector::<M>(self.lookup, 1.0)?;
        Ok(self
            .speeds
            .iter()
            .zip(self.guide)
            .map(|(&v, g)| {
                let g = (*g)?;
                let ss = state_space_at_speed::<M>(&p, v).ok()?;
                ss.a.complex_eigenvalues()
                    .iter()
                    .filter(|z| z.im > 1e-9)
                    .min_by(|x, y| {
                        let d = |z: &nalgebra::Complex<f64>| (z.re - g[0]).hypot(z.im - g[1]);
                        d(x).total_cmp(&d(y))
                    })
                    .map(|z| [z.re, z.im])
            })
            .collect())
    }
}

/// A finding of the residual diagnosis: what the base model's residuals
/// show and the effects it points to.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Finding {
    pub pattern: String,
    pub evidence: String,
    pub suspects: Vec<String>,
    pub significant: bool,
}

fn mean_se(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    if n < 1.0 {
        return (f64::NAN, f64::NAN);
    }
    let m = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

fn slope(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    if n < 3.0 {
        return (f64::NAN, f64::NAN);
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let b = sxy / sxx;
    let res: f64 = x.iter().zip(y).map(|(a, c)| (c - my - b * (a - mx)).powi(2)).sum();
    (b, (res / (n - 2.0) / sxx).sqrt())
}

/// Relate the base model's residuals to candidate effects (issue 9,
/// point 2). Significance: two standard errors.
fn diagnose(
    models: &[&ModelInfo],
    segs: &[Segment],
    predicted: &[Option<[f64; 2]>],
    before: &[SegmentError],
    sims_mean_roll: &[f64],
) -> Vec<Finding> {
    // The effects whose files declare a pattern, in the models' order.
    let suspects = |sig: Signature| -> Vec<String> {
        let mut out: Vec<String> = Vec::new();
        for m in models {
            for e in m.effect_declarations {
                if let Some(EffectIdentification::Candidate(c)) = e.identification {
                    if c.signatures.contains(&sig) && !out.iter().any(|x| x == e.name) {
                        out.push(e.name.to_string());
                    }
                }
            }
        }
        out
    };
    let mut f = Vec::new();
    let pairs: Vec<(usize, [f64; 2], [f64; 2])> = segs
        .iter()
        .enumerate()
        .filter_map(|(i, s)| Some((i, s.weave?.0, predicted[i]?)))
        .collect();
    let dre: Vec<f64> = pairs.iter().map(|p| p.1[0] - p.2[0]).collect();
    let dim: Vec<f64> = pairs.iter().map(|p| p.1[1] - p.2[1]).collect();
    let (mre, sre) = mean_se(&dre);
    let (mim, sim) = mean_se(&dim);
    f.push(Finding {
        pattern: "weave damping and frequency".into(),
        evidence: format!(
            "measured minus predicted weave eigenvalue over {} kicks: real part {mre:+.3} +- {sre:.3} 1/s, imaginary part {mim:+.3} +- {sim:.3} rad/s",
            pairs.len()
        ),
        suspects: if mre < 0.0 && mim < 0.0 {
            suspects(Signature::WeaveDampingAndFrequency)
        } else {
            vec![]
        },
        significant: mre < -2.0 * sre && mim < -2.0 * sim,
    });
    let amp: Vec<f64> = pairs
        .iter()
        .map(|p| segs[p.0].roll.iter().fold(0.0f64, |a, b| a.max(b.abs())).max(1e-6).ln())
        .collect();
    let (b, sb) = slope(&amp, &dre);
    f.push(Finding {
        pattern: "damping that depends on amplitude".into(),
        evidence: format!(
            "slope of the real-part residual against ln(peak roll): {b:+.3} +- {sb:.3} 1/s (positive: more damping at small amplitude)"
        ),
        suspects: suspects(Signature::AmplitudeDependentDamping),
        significant: b > 2.0 * sb,
    });
    let (mb, sbias) = mean_se(sims_mean_roll);
    f.push(Finding {
        pattern: "steady lean after the kick".into(),
        evidence: format!(
            "mean roll residual over the second half of each window: {:+.3} +- {:.3} deg",
            mb.to_degrees(),
            sbias.to_degrees()
        ),
        suspects: suspects(Signature::SteadyLean),
        significant: mb.abs() > 2.0 * sbias,
    });
    let sp: Vec<f64> = pairs.iter().map(|p| segs[p.0].mean_speed).collect();
    let (bs, sbs) = slope(&sp, &dim);
    f.push(Finding {
        pattern: "frequency shift growing with speed".into(),
        evidence: format!("slope of the imaginary-part residual against speed: {bs:+.3} +- {sbs:.3} rad/s per m/s"),
        // Inertia errors shift the frequency too; they are not candidates yet.
        suspects: suspects(Signature::FrequencyShiftWithSpeed)
            .into_iter()
            .chain(["inertia errors".to_string()])
            .collect(),
        significant: bs.abs() > 2.0 * sbs,
    });
    let decel: Vec<f64> = segs
        .iter()
        .filter(|s| s.speed.len() >= 3)
        .map(|s| slope(&s.speed_t, &s.speed).0)
        .filter(|x| x.is_finite())
        .collect();
    let (md, sd) = mean_se(&decel);
    let speed_rms = pooled_rms(before, 2);
    f.push(Finding {
        pattern: "speed decay".into(),
        evidence: format!(
            "mean measured speed slope over the windows {md:+.3} +- {sd:.3} m/s^2; the base model (no loss) misses it by {speed_rms:.3} m/s RMS"
        ),
        suspects: suspects(Signature::SpeedDecay),
        significant: md < -2.0 * sd,
    });
    f
}

/// Everything the report needs.
pub struct Outcome {
    pub identification: Identification,
    pub segments: Vec<Segment>,
    pub skipped: Vec<String>,
    pub candidates: Vec<Candidate>,
    pub findings: Vec<Finding>,
    pub predicted_before: Vec<Option<[f64; 2]>>,
    pub predicted_after: Vec<Option<[f64; 2]>>,
    pub predicted_held_out: Vec<Option<[f64; 2]>>,
    pub values_after: BTreeMap<String, f64>,
    pub model: &'static str,
    pub driven_model: &'static str,
    pub seconds: f64,
    /// Mean |steer rate| of each segment in the fitted simulation (rad/s).
    pub steer_rate: Vec<f64>,
    run_plot: Option<RunPlot>,
}

/// RMS of |measured - predicted| weave eigenvalue (1/s) over segments.
pub fn eigen_rms(segs: &[Segment], pred: &[Option<[f64; 2]>]) -> f64 {
    let d: Vec<f64> = segs
        .iter()
        .zip(pred)
        .filter_map(|(s, p)| {
            let (m, _) = s.weave?;
            let p = (*p)?;
            Some((m[0] - p[0]).powi(2) + (m[1] - p[1]).powi(2))
        })
        .collect();
    (d.iter().sum::<f64>() / d.len().max(1) as f64).sqrt()
}

/// Run identification on the inputs.
pub fn run_identify(a: &IdentifyArgs) -> Result<Outcome> {
    let start = std::time::Instant::now();
    let bike = Bicycle::resolve(&a.bike)?;
    let (free, driven, alt) = identification_models(&bike)?;
    let cands = candidates(free, alt, &bike, &a.effects)?;
    // A conclusion ("no effect warranted") means something only when
    // effects were tried.
    if cands.is_empty() {
        bail!(
            "no candidate effect for `{}` through model `{}` (effects: {}): identification would conclude without testing anything",
            bike.name,
            free.name,
            if free.effects.is_empty() { "none".to_string() } else { free.effects.join(", ") }
        );
    }
    eprintln!("identify: model {} (driven twin {})", free.name, driven.name);
    let fit_args = FitArgs {
        inputs: a.inputs.clone(),
        calibration: a.calibration.clone(),
        bike: Some(a.bike.clone()),
        json: false,
        plot: None,
        angles: "direct".into(),
        nominal_clock: false,
    };
    let out = run_fit(&fit_args)?;
    let (segs, mut skipped) = segments(&out);
    skipped.extend(out.errors.iter().cloned());
    if segs.len() < 2 {
        bail!(
            "identification needs at least two kicks with a free-response window; found {}{}",
            segs.len(),
            if skipped.is_empty() {
                String::new()
            } else {
                format!(" ({})", skipped.join("; "))
            }
        );
    }
    let opts = IdentifyOptions {
        folds: a.folds,
        ..IdentifyOptions::default()
    };
    let bar = indicatif::ProgressBar::new_spinner();
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let progress = |m: &str| bar.set_message(format!("identify: fitted {m}"));
    let (id, run_plot) = with_model(
        free.name,
        Identify {
            bike: &bike,
            alt,
            segments: &segs,
            candidates: &cands,
            opts: &opts,
            progress: &progress,
        },
    )
    .expect("registered model")?;
    bar.finish_and_clear();
    let speeds: Vec<f64> = segs.iter().map(|s| s.mean_speed).collect();
    let predicted_before = predict(driven, &bike, &BTreeMap::new(), &speeds)?;
    let values_after = effect_values(&id.after, &id.after.values, &cands);
    // Steer-rate amplitude of each segment, from the fitted simulation.
    let steer_rate: Vec<f64> = (0..segs.len())
        .map(|i| {
            run_plot
                .as_ref()
                .and_then(|rp| rp.after[i].as_ref())
                .map_or(f64::NAN, |sim| mean_abs_rate(&segs[i].t, &sim.steer))
        })
        .collect();
    let mut predicted_after = Vec::with_capacity(segs.len());
    for (i, &v) in speeds.iter().enumerate() {
        let vals = linear_equivalent(driven, &values_after, steer_rate[i]);
        predicted_after.push(predict(driven, &bike, &vals, &[v])?[0]);
    }
    // Held out: each segment predicted with the values fitted without its fold.
    let mut predicted_held_out = vec![None; segs.len()];
    for (f, vals) in id.after.fold_values.iter().enumerate() {
        let idx: Vec<usize> = (0..segs.len()).filter(|&s| s % id.folds == f).collect();
        let sp: Vec<f64> = idx.iter().map(|&s| speeds[s]).collect();
        let fold_vals = effect_values(&id.after, vals, &cands);
        for (k, &s) in idx.iter().enumerate() {
            predicted_held_out[s] = predict(
                driven,
                &bike,
                &linear_equivalent(driven, &fold_vals, steer_rate[s]),
                &sp[k..=k],
            )?[0];
        }
    }
    // Steady bias: the base model's roll residual over the second half of
    // each window.
    let bias: Vec<f64> = run_plot
        .as_ref()
        .map(|rp| {
            segs.iter()
                .zip(&rp.before)
                .filter_map(|(s, sim)| {
                    let sim = sim.as_ref()?;
                    let h = s.t.len() / 2;
                    let n = (s.t.len() - h).max(1) as f64;
                    Some((h..s.t.len()).map(|k| s.roll[k] - sim.roll[k]).sum::<f64>() / n)
                })
                .collect()
        })
        .unwrap_or_default();
    let models: Vec<&ModelInfo> = std::iter::once(free).chain(alt).collect();
    let findings = diagnose(&models, &segs, &predicted_before, &id.before.errors, &bias);
    Ok(Outcome {
        identification: id,
        segments: segs,
        skipped,
        candidates: cands,
        findings,
        predicted_before,
        predicted_after,
        predicted_held_out,
        values_after,
        model: free.name,
        driven_model: driven.name,
        seconds: start.elapsed().as_secs_f64(),
        steer_rate,
        run_plot,
    })
}

fn display_name(c: &Candidate) -> String {
    if c.speed_decay {
        format!("{} (speed decay)", c.name)
    } else {
        c.name.clone()
    }
}

fn errors_json(o: &Outcome, after: bool) -> Value {
    let id = &o.identification;
    let fit = if after { &id.after } else { &id.before };
    let pred = if after { &o.predicted_after } else { &o.predicted_before };
    let held_pred = if after {
        &o.predicted_held_out
    } else {
        &o.predicted_before
    };
    json!({
        "eigen_rms": eigen_rms(&o.segments, pred),
        "median_run_roll_rms": median(fit.errors.iter().map(|e| e.roll_rms)),
        "median_run_steer_rms": median(fit.errors.iter().map(|e| e.steer_rms)),
        "roll_rms": pooled_rms(&fit.errors, 0),
        "steer_rms": pooled_rms(&fit.errors, 1),
        "speed_rms": pooled_rms(&fit.errors, 2),
        "held_out": {
            "eigen_rms": eigen_rms(&o.segments, held_pred),
            "roll_rms": pooled_rms(&fit.held_out, 0),
            "steer_rms": pooled_rms(&fit.held_out, 1),
            "speed_rms": pooled_rms(&fit.held_out, 2),
        },
        "per_run": o.segments.iter().enumerate().map(|(i, s)| json!({
            "run": s.run,
            "window_start": s.t0,
            "roll_rms": fit.errors[i].roll_rms,
            "steer_rms": fit.errors[i].steer_rms,
            "speed_rms": fit.errors[i].speed_rms,
            "held_out_roll_rms": fit.held_out[i].roll_rms,
            "measured_weave": s.weave.map(|w| w.0),
            "predicted_weave": pred[i],
        })).collect::<Vec<_>>(),
    })
}

/// The JSON summary (schema in README, "Closing the loop").
pub fn outcome_json(o: &Outcome) -> Value {
    let id = &o.identification;
    let sel: Vec<String> = id
        .selected
        .iter()
        .filter_map(|n| o.candidates.iter().find(|c| &c.name == n))
        .map(display_name)
        .collect();
    let mut params = serde_json::Map::new();
    for (p, (v, se)) in id
        .after
        .parameters
        .iter()
        .zip(id.after.values.iter().zip(&id.after.stderr))
    {
        params.insert(
            p.symbol.clone(),
            json!({"value": v, "low": v - 1.96 * se, "high": v + 1.96 * se, "stderr": se, "unit": p.unit, "tied": p.tied}),
        );
    }
    let mut cands = Vec::new();
    for (k, step) in id.steps.iter().enumerate() {
        for ((name, f), (_, verdict)) in step.tried.iter().zip(&step.verdicts) {
            cands.push(json!({
                "step": k + 1,
                "name": name,
                "extends": step.base,
                "score": f.bic - step.base_bic,
                "cv": f.cv,
                "base_cv": step.base_cv,
                "values": f.values,
                "selected": step.added.as_deref() == Some(name.as_str()),
                "verdict": verdict,
            }));
        }
        for (name, why) in &step.failed {
            cands.push(json!({
                "step": k + 1,
                "name": name,
                "extends": step.base,
                "score": Value::Null,
                "cv": Value::Null,
                "selected": false,
                "verdict": why,
            }));
        }
    }
    json!({
        "selected_effects": sel,
        "parameters": params,
        "candidates": cands,
        "error_before": errors_json(o, false),
        "error_after": errors_json(o, true),
        "model": o.model,
        "driven_model": o.driven_model,
        "kicks": o.segments.len(),
        "skipped": o.skipped,
        "findings": o.findings,
        "weights": id.weights,
        "folds": id.folds,
        "simulations": id.simulations,
        "seconds": o.seconds,
    })
}

fn median(x: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = x.filter(|a| a.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

fn fmt_c(z: Option<[f64; 2]>) -> String {
    z.map_or("-".into(), |z| format!("{:.3}{:+.3}i", z[0], z[1]))
}

/// Five-line summary.
pub fn summary(o: &Outcome) -> String {
    let id = &o.identification;
    let b = errors_json(o, false);
    let a = errors_json(o, true);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "kicks: {} from {} runs ({} skipped); model {}",
        o.segments.len(),
        o.segments
            .iter()
            .map(|s| &s.run)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        o.skipped.len(),
        o.model
    );
    let sel = if id.selected.is_empty() {
        "no effect warranted".to_string()
    } else {
        id.selected.join(" + ")
    };
    let _ = writeln!(s, "selected: {sel}");
    let vals: Vec<String> = id
        .after
        .parameters
        .iter()
        .zip(id.after.values.iter().zip(&id.after.stderr))
        .map(|(p, (v, se))| format!("{} = {:.4} +- {:.4} {}", p.symbol, v, 1.96 * se, p.unit))
        .collect();
    let _ = writeln!(
        s,
        "parameters (95 %): {}",
        if vals.is_empty() { "-".into() } else { vals.join(", ") }
    );
    let _ = writeln!(
        s,
        "error before -> after: weave eigenvalue RMS {:.3} -> {:.3} 1/s, roll RMS {:.3} -> {:.3} deg (median run {:.3} -> {:.3}), steer RMS {:.3} -> {:.3} deg",
        b["eigen_rms"].as_f64().unwrap_or(f64::NAN),
        a["eigen_rms"].as_f64().unwrap_or(f64::NAN),
        b["roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        a["roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        b["median_run_roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        a["median_run_roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        b["steer_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        a["steer_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
    );
    let _ = write!(
        s,
        "held-out runs: weave RMS {:.3} -> {:.3} 1/s, roll RMS {:.3} -> {:.3} deg ({} folds, {} simulations, {:.1} s)",
        b["held_out"]["eigen_rms"].as_f64().unwrap_or(f64::NAN),
        a["held_out"]["eigen_rms"].as_f64().unwrap_or(f64::NAN),
        b["held_out"]["roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        a["held_out"]["roll_rms"].as_f64().unwrap_or(f64::NAN).to_degrees(),
        id.folds,
        id.simulations,
        o.seconds
    );
    s
}

/// Parameter file of the identified bicycle: the bicycle plus the fitted
/// effect values.
fn fitted_toml(bike: &Bicycle, values: &BTreeMap<String, f64>, o: &Outcome) -> String {
    let mut s = bike.parameters.to_toml_string();
    let _ = writeln!(
        s,
        "\n# Effects identified by `bikedyn identify` (model {}; driven-speed twin {}).",
        o.model, o.driven_model
    );
    for (k, v) in bike.effects.iter().filter(|(k, _)| !values.contains_key(*k)) {
        let _ = writeln!(s, "{k} = {v:e}");
    }
    for (k, v) in values {
        let _ = writeln!(s, "{k} = {v:.6e}");
    }
    s
}

fn report_markdown(o: &Outcome, a: &IdentifyArgs, dir: &Path) -> String {
    let id = &o.identification;
    let mut s = String::new();
    let inputs: Vec<String> = a.inputs.iter().map(|p| p.display().to_string()).collect();
    let _ = writeln!(s, "# Identification report\n");
    let _ = writeln!(
        s,
        "Data: {} ({} kicks). Bicycle: `{}`. Model: `{}` (nonlinear, free forward speed, every effect of the library absent unless fitted); weave predictions from its driven-speed twin `{}`.\n",
        inputs.join(", "),
        o.segments.len(),
        a.bike,
        o.model,
        o.driven_model
    );
    let _ = writeln!(s, "## Summary\n\n```\n{}\n```\n", summary(o));
    let _ = writeln!(s, "## What was done\n");
    let _ = writeln!(s, "1. The measured-run pipeline (`bikedyn fit`) found every kick and its free-response window, and estimated mounting misalignments (calibration run) and clock offsets: these sensor effects are nuisances, never reported as mechanics.");
    let _ = writeln!(s, "2. Each window was simulated with the full nonlinear equations from its own initial state (roll, steer, their rates, speed; fitted per run as nuisance parameters), and compared with the measured roll, steer and speed.");
    let _ = writeln!(s, "3. The residual pattern of the model without any added effect was related to the effects of the library (below).");
    let _ = writeln!(s, "4. Candidates were added one at a time and fitted jointly over all runs (Levenberg-Marquardt). One was kept only if it lowers the Bayesian information criterion (effective sample sizes for correlated residuals), lowers the error on held-out runs ({}-fold cross-validation by run), and its dissipative parameters are positive. The search stops when no candidate passes.\n", id.folds);
    let med = |f: &dyn Fn(&bikedyn_runtime::identify::Weights) -> f64| median(id.weights.iter().map(f));
    let _ = writeln!(s, "Channel scales (each run's RMS residual under the base model, at least the best run's; median over runs): roll {:.3} deg, steer {:.3} deg, speed {:.3} m/s. Each run and channel is weighed by its own scale, so a run that diverges toward a fall cannot outweigh the others.\n", med(&|w| w.roll).to_degrees(), med(&|w| w.steer).to_degrees(), med(&|w| w.speed));
    let _ = writeln!(s, "## Residual diagnosis (base model)\n");
    let _ = writeln!(
        s,
        "| pattern | evidence | points to | significant (2 sigma) |\n|---|---|---|---|"
    );
    for f in &o.findings {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            f.pattern,
            f.evidence,
            f.suspects.join(", "),
            if f.significant { "yes" } else { "no" }
        );
    }
    let _ = writeln!(s, "\nCandidates and why each is suspected:\n");
    for c in &o.candidates {
        let p: Vec<String> = c
            .parameters
            .iter()
            .map(|p| format!("`{}` ({})", p.symbol, p.unit))
            .collect();
        let _ = writeln!(
            s,
            "* `{}`{}: {} Fitted: {}.",
            c.name,
            if c.speed_decay { " (speed decay)" } else { "" },
            c.reason,
            p.join(", ")
        );
    }
    if let Some(info) = MODELS.iter().find(|m| m.name == o.model) {
        for (e, why) in not_candidates(info) {
            let _ = writeln!(s, "* `{e}` is not a candidate: {why}.");
        }
    }
    let _ = writeln!(s, "\n## Ranking of the candidates\n");
    for (k, step) in id.steps.iter().enumerate() {
        let base = if step.base.is_empty() {
            "the base model".to_string()
        } else {
            step.base.join(" + ")
        };
        let _ = writeln!(
            s,
            "Step {}: added to {base} (BIC {:.1}, held-out error {:.4}).\n",
            k + 1,
            step.base_bic,
            step.base_cv
        );
        let _ = writeln!(
            s,
            "| candidate | fitted values | BIC change | held-out error | verdict |\n|---|---|---|---|---|"
        );
        let mut rows: Vec<usize> = (0..step.tried.len()).collect();
        rows.sort_by(|&x, &y| step.tried[x].1.bic.total_cmp(&step.tried[y].1.bic));
        for r in rows {
            let (name, f) = &step.tried[r];
            let vals: Vec<String> = f
                .parameters
                .iter()
                .zip(f.values.iter().zip(&f.stderr))
                .map(|(p, (v, se))| format!("{} = {:.4} +- {:.4}", p.symbol, v, se))
                .collect();
            let cv = if f.cv.is_finite() {
                format!("{:.4}", f.cv)
            } else {
                "-".into()
            };
            let _ = writeln!(
                s,
                "| `{name}` | {} | {:+.1} | {cv} | {} |",
                vals.join(", "),
                f.bic - step.base_bic,
                step.verdicts[r].1
            );
        }
        for (name, why) in &step.failed {
            let _ = writeln!(s, "| `{name}` | - | - | - | {why} |");
        }
        let _ = writeln!(s);
    }
    if id.selected.is_empty() {
        let _ = writeln!(s, "**No effect warranted.** No candidate lowered both the information criterion and the held-out error with physical parameter values: the residual of the base model is not explained better by any effect of the library than by noise. The model is left as it is.\n");
    } else {
        let _ = writeln!(
            s,
            "## Identified effects\n\n| parameter | value | 95 % interval | unit |\n|---|---|---|---|"
        );
        for (p, (v, se)) in id
            .after
            .parameters
            .iter()
            .zip(id.after.values.iter().zip(&id.after.stderr))
        {
            let _ = writeln!(
                s,
                "| `{}`{} | {:.5} | [{:.5}, {:.5}] | {} |",
                p.symbol,
                if p.tied.is_empty() {
                    String::new()
                } else {
                    format!(" (= `{}`)", p.tied.join("`, `"))
                },
                v,
                v - 1.96 * se,
                v + 1.96 * se,
                p.unit
            );
        }
        let _ = writeln!(s);
    }
    let b = errors_json(o, false);
    let af = errors_json(o, true);
    let g = |v: &Value, k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    let _ = writeln!(s, "## Error before and after\n\n| | weave eigenvalue RMS (1/s) | roll RMS (deg) | steer RMS (deg) | speed RMS (m/s) |\n|---|---|---|---|---|");
    for (label, v) in [
        ("fitted runs, before", &b),
        ("fitted runs, after", &af),
        ("held-out runs, before", &b["held_out"]),
        ("held-out runs, after", &af["held_out"]),
    ] {
        let _ = writeln!(
            s,
            "| {label} | {:.4} | {:.4} | {:.4} | {:.4} |",
            g(v, "eigen_rms"),
            g(v, "roll_rms").to_degrees(),
            g(v, "steer_rms").to_degrees(),
            g(v, "speed_rms")
        );
    }
    let _ = writeln!(s, "\nPer run (roll RMS in deg; weave eigenvalues in 1/s):\n\n| run | window start (s) | speed over the eigenvalue fit (m/s) | measured weave | predicted before | predicted after | roll before | roll after | roll after, held out |\n|---|---|---|---|---|---|---|---|---|");
    for (i, seg) in o.segments.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.2}-{:.2} | {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            seg.run,
            seg.t0,
            seg.speed_interval[0],
            seg.speed_interval[1],
            fmt_c(seg.weave.map(|w| w.0)),
            fmt_c(o.predicted_before[i]),
            fmt_c(o.predicted_after[i]),
            id.before.errors[i].roll_rms.to_degrees(),
            id.after.errors[i].roll_rms.to_degrees(),
            id.after.held_out[i].roll_rms.to_degrees()
        );
    }
    let _ = writeln!(s, "\n## Plots\n\n* `continuation.svg`: weave eigenvalue over speed, model before (thin) and after (thick), with each measured eigenvalue on its speed interval.\n* `run_residuals.svg`: measured and simulated roll, steer and speed of a typical run (median error), before and after.\n");
    if !o.skipped.is_empty() {
        let _ = writeln!(s, "## Skipped\n");
        for k in &o.skipped {
            let _ = writeln!(s, "* {k}");
        }
        let _ = writeln!(s);
    }
    let fitted = dir.join("fitted.toml");
    let _ = writeln!(s, "## Reproduce\n\nThe identified bicycle is `{}`: the bicycle's parameters plus the fitted effect values, for the model `{}` (driven speed) or `{}` (free speed). To refit from it, and to simulate it:\n\n```sh\nbikedyn identify {} --bike {}\nbikedyn simulate --bike {} --model {} --speed 5 --kick 0.5:3 --duration 6 --plot kick.svg\n```\n\nThe refit starts from the identified bicycle: the effects found here are part of its model, so the refit should warrant nothing more.", fitted.display(), o.driven_model, o.model, inputs.join(" "), fitted.display(), fitted.display(), o.model);
    s
}

/// Write the report folder.
pub fn write_report(o: &Outcome, a: &IdentifyArgs, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let bike = Bicycle::resolve(&a.bike)?;
    save_json(dir.join("report.json"), &outcome_json(o))?;
    write_string_atomic(dir.join("fitted.toml"), &fitted_toml(&bike, &o.values_after, o))?;
    // Continuation diagram before and after.
    let vmax = o.segments.iter().map(|s| s.speed_interval[1]).fold(7.0, f64::max) + 1.0;
    let speeds: Vec<f64> = (1..=200).map(|i| vmax * i as f64 / 200.0).collect();
    let (_, driven, _) = identification_models(&bike)?;
    let curve = |vals: &BTreeMap<String, f64>| -> Result<Vec<(f64, f64, f64)>> {
        let pts: Vec<(f64, f64, f64)> = predict(driven, &bike, vals, &speeds)?
            .into_iter()
            .zip(&speeds)
            .filter_map(|(z, &v)| z.map(|z| (v, z[0], z[1])))
            .collect();
        // The weave, followed down from high speed until it stops being
        // one complex pair (a jump far beyond the typical step means
        // another pair took over, e.g. capsize-castering at low speed).
        let steps: Vec<f64> = pts
            .windows(2)
            .map(|w| (w[1].1 - w[0].1).hypot(w[1].2 - w[0].2))
            .collect();
        let typical = median(steps.iter().copied());
        let mut start = 0;
        for k in (0..steps.len()).rev() {
            if steps[k] > 10.0 * typical.max(1e-9) {
                start = k + 1;
                break;
            }
        }
        Ok(pts[start..].to_vec())
    };
    let measured: Vec<MeasuredWeave> = o
        .segments
        .iter()
        .filter_map(|s| {
            let (w, se) = s.weave?;
            Some(MeasuredWeave {
                speed_interval: s.speed_interval,
                mean_speed: s.mean_speed,
                eigenvalue: w,
                stderr: se,
            })
        })
        .collect();
    let label = if o.identification.selected.is_empty() {
        "no effect warranted".to_string()
    } else {
        o.identification.selected.join(" + ")
    };
    let mut rates: Vec<f64> = o.steer_rate.iter().copied().filter(|x| x.is_finite()).collect();
    rates.sort_by(f64::total_cmp);
    let median_rate = rates.get(rates.len() / 2).copied().unwrap_or(f64::NAN);
    let driven_info = MODELS
        .iter()
        .find(|m| m.name == o.driven_model)
        .context("the identification's driven model is registered")?;
    for ext in ["svg", "png"] {
        plot_continuation(
            &dir.join(format!("continuation.{ext}")),
            &curve(&BTreeMap::new())?,
            &curve(&linear_equivalent(driven_info, &o.values_after, median_rate))?,
            &label,
            &measured,
        )?;
    }
    if let Some(rp) = &o.run_plot {
        let s = &o.segments[rp.segment];
        let deg = |x: &[f64]| x.iter().map(|v| v.to_degrees()).collect::<Vec<f64>>();
        let (Some(b), Some(a)) = (&rp.before[rp.segment], &rp.after[rp.segment]) else {
            bail!("the typical run could not be simulated for the plot");
        };
        let (mr, br, ar) = (deg(&s.roll), deg(&b.roll), deg(&a.roll));
        let (ms, bs, as_) = (deg(&s.steer), deg(&b.steer), deg(&a.steer));
        for ext in ["svg", "png"] {
            plot_run(
                &dir.join(format!("run_residuals.{ext}")),
                &format!(
                    "{} (window from {:.2} s): measured and simulated, before and after",
                    Path::new(&s.run)
                        .file_name()
                        .map_or(s.run.clone(), |n| n.to_string_lossy().into_owned()),
                    s.t0
                ),
                &[
                    Channel {
                        name: "roll",
                        unit: "deg",
                        t: &s.t,
                        measured: &mr,
                        before: &br,
                        after: &ar,
                    },
                    Channel {
                        name: "steer",
                        unit: "deg",
                        t: &s.t,
                        measured: &ms,
                        before: &bs,
                        after: &as_,
                    },
                    Channel {
                        name: "speed",
                        unit: "m/s",
                        t: &s.speed_t,
                        measured: &s.speed,
                        before: &b.speed,
                        after: &a.speed,
                    },
                ],
            )?;
        }
    }
    write_string_atomic(dir.join("report.md"), &report_markdown(o, a, dir))?;
    Ok(())
}

/// `bikedyn identify`.
pub fn command(a: &IdentifyArgs) -> Result<bool> {
    let o = run_identify(a)?;
    if let Some(dir) = &a.report {
        write_report(&o, a, dir)?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&outcome_json(&o))?);
    } else {
        println!("{}", summary(&o));
        if let Some(dir) = &a.report {
            println!("report: {}", dir.join("report.md").display());
        }
    }
    Ok(true)
}
