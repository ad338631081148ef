//! Residual diagnosis: what the base model's residuals show (weave
//! eigenvalue offsets, amplitude dependence, steady lean, speed trends) and
//! the effects whose files declare that pattern.

use bikedyn_runtime::identify::{pooled_rms, RollChannel, Segment, SegmentError};
use bikedyn_runtime::model::{EffectIdentification, Signature};
use bikedyn_runtime::registry::ModelInfo;

/// A finding of the residual diagnosis: what the base model's residuals
/// show and the effects it points to.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Finding {
    /// The residual pattern looked for.
    pub pattern: String,
    /// What the residuals show, with standard errors.
    pub evidence: String,
    /// The effects whose files declare this pattern.
    pub suspects: Vec<String>,
    /// Whether the pattern exceeds two standard errors.
    pub significant: bool,
}

/// A kick's amplitude: the peak of its measured roll channel (rad, or
/// rad/s for a roll-rate channel).
pub(super) fn peak_roll(s: &Segment) -> f64 {
    s.roll.iter().fold(0.0f64, |a, b| a.max(b.abs()))
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
pub fn diagnose(
    models: &[&ModelInfo],
    segs: &[Segment],
    predicted: &[Option<[f64; 2]>],
    before: &[SegmentError],
    sims_mean_roll: &[f64],
    speed_imposed: bool,
) -> Vec<Finding> {
    let channel = segs.first().map_or(RollChannel::Angle, |s| s.roll_channel);
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
    let amp: Vec<f64> = pairs.iter().map(|p| peak_roll(&segs[p.0]).max(1e-6).ln()).collect();
    let (b, sb) = slope(&amp, &dre);
    f.push(Finding {
        pattern: "damping that depends on amplitude".into(),
        evidence: format!(
            "slope of the real-part residual against ln(peak {}): {b:+.3} +- {sb:.3} 1/s (positive: more damping at small amplitude)",
            channel.describe()
        ),
        suspects: suspects(Signature::AmplitudeDependentDamping),
        significant: b > 2.0 * sb,
    });
    // A steady lean shows in the roll angle; a roll-rate channel has none.
    let (mb, sbias) = mean_se(sims_mean_roll);
    if channel == RollChannel::Angle {
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
    }
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
    // With the speed imposed (a motor held it) a speed decay is no model error.
    if speed_imposed {
        return f;
    }
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
