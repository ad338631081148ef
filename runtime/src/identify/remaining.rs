//! What the library leaves: whether the measured weave eigenvalues still
//! differ from the identified model in a pattern, or only by the kicks' own
//! scatter, and how much of what a perfect model would explain the library
//! explained.
//!
//! The residual of each kick (measured minus predicted weave eigenvalue,
//! real and imaginary parts) is regressed on the states a missing effect
//! would act through: a constant, the kick's speed and its square, and the
//! log of its peak roll (amplitude; absent from a table). A model error is
//! a smooth function of these; the kicks' scatter is not. The regression's
//! residual mean square estimates that scatter, the floor of a perfect
//! model (one whose predictions carry no error in these states), and an F
//! test asks whether the pattern is larger than the scatter allows. The
//! share of the way from the base model to that floor that the library
//! went is reported as "explains N % of what a perfect model would", on the
//! fitted predictions and on the held-out ones.
//!
//! The test and the figures are unweighted (each kick counts once), as the
//! pooled eigenvalue RMS of the report is; a fit's own standard errors vary
//! tenfold between kicks and would let one long response set the verdict.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// The level of the test: a pattern whose F statistic would arise from
/// scatter alone less often than this is called structured.
pub const STRUCTURE_LEVEL: f64 = 0.01;

/// A state the remaining residual is regressed on (besides a constant).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum State {
    /// The kick's mean forward speed.
    Speed,
    /// Its square (curvature over speed).
    SpeedSquared,
    /// The log of the kick's peak roll (its amplitude).
    LogAmplitude,
}

/// Which part of the weave eigenvalue a term is of.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// Real part (1/s): damping.
    Real,
    /// Imaginary part (rad/s): frequency.
    Imaginary,
}

/// One significant term of the remaining pattern: the part's change per
/// standard deviation of a state over the kicks (`state` `None`: its mean
/// offset), beyond two standard errors.
#[derive(Clone, Debug, Serialize)]
pub struct PatternTerm {
    pub part: Part,
    pub state: Option<State>,
    /// Coefficient (1/s or rad/s) and its standard error.
    pub coefficient: f64,
    pub stderr: f64,
}

/// The eigenvalues of one kick (or one table row) and its states.
#[derive(Clone, Copy, Debug)]
pub struct KickWeave {
    /// Mean forward speed (m/s).
    pub speed: f64,
    /// Peak roll angle or rate of the kick (its amplitude, rad or rad/s);
    /// `None` for a table row.
    pub amplitude: Option<f64>,
    /// Measured weave eigenvalue `[re, im]` (1/s).
    pub measured: [f64; 2],
    /// Predicted by the base model, the identified model, and the model
    /// fitted without the kick's fold (`[re, im]`, 1/s).
    pub base: [f64; 2],
    pub after: [f64; 2],
    pub held_out: [f64; 2],
}

/// The remaining residual of the weave eigenvalues against the kicks'
/// scatter.
#[derive(Clone, Debug, Serialize)]
pub struct Remaining {
    /// Kicks (or rows) counted.
    pub kicks: usize,
    /// The states the pattern was sought in (beside a constant, always).
    pub regressors: Vec<State>,
    /// Pooled eigenvalue RMS (1/s): base model, identified model, held out,
    /// and the floor (the kicks' scatter about the best pattern, the RMS a
    /// perfect model would be expected to reach).
    pub base_rms: f64,
    pub after_rms: f64,
    pub held_out_rms: f64,
    pub floor_rms: f64,
    /// Share of `base - floor` (mean squares) the library removed, on the
    /// fitted and on the held-out predictions (1: all a perfect model
    /// would; can exceed 1 within the scatter).
    pub explained: f64,
    pub explained_held_out: f64,
    /// F statistic of the pattern in the identified model's residual, its
    /// degrees of freedom and the probability of one as large from
    /// scatter alone.
    pub f: f64,
    pub df: [usize; 2],
    pub p_value: f64,
    /// Whether a pattern beyond the scatter remains (`p_value` below
    /// [`STRUCTURE_LEVEL`]).
    pub structured: bool,
    /// The pattern's significant terms (beyond two standard errors).
    pub pattern: Vec<PatternTerm>,
}

/// Test the identified model's weave residual for a pattern in the kicks'
/// states; `None` when too few kicks remain for the test (fewer values than
/// twice the pattern's terms).
pub fn remaining(kicks: &[KickWeave]) -> Option<Remaining> {
    let kicks: Vec<&KickWeave> = kicks
        .iter()
        .filter(|k| {
            k.speed.is_finite()
                && [k.measured, k.base, k.after, k.held_out]
                    .iter()
                    .all(|e| e.iter().all(|x| x.is_finite()))
        })
        .collect();
    let n = kicks.len();
    if n < 4 {
        return None;
    }
    // The states, centred and scaled (the fit's conditioning); a state
    // that does not vary over the kicks is no regressor.
    let standard = |x: &[f64]| -> Option<Vec<f64>> {
        let m = x.iter().sum::<f64>() / x.len() as f64;
        let sd = (x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / x.len() as f64).sqrt();
        (sd > 1e-9 * m.abs().max(1.0)).then(|| x.iter().map(|a| (a - m) / sd).collect())
    };
    let mut columns: Vec<(Option<State>, Vec<f64>)> = vec![(None, vec![1.0; n])];
    let speeds: Vec<f64> = kicks.iter().map(|k| k.speed).collect();
    if let Some(v) = standard(&speeds) {
        columns.push((Some(State::Speed), v.clone()));
        if distinct(&speeds) >= 3 {
            let v2: Vec<f64> = v.iter().map(|x| x * x).collect();
            if let Some(v2) = standard(&v2) {
                columns.push((Some(State::SpeedSquared), v2));
            }
        }
    }
    let amplitudes: Option<Vec<f64>> = kicks
        .iter()
        .map(|k| k.amplitude.filter(|a| *a > 0.0).map(f64::ln))
        .collect();
    if let Some(a) = amplitudes.as_deref().and_then(standard) {
        columns.push((Some(State::LogAmplitude), a));
    }
    // Fewer terms while the kicks are too few for them (two values per
    // kick, and at least as many degrees of freedom left as terms used).
    while 2 * n < 4 * columns.len() && columns.len() > 1 {
        columns.pop();
    }
    let q = columns.len();
    let x = DMatrix::from_fn(n, q, |i, j| columns[j].1[i]);
    let residual = |f: &dyn Fn(&KickWeave) -> [f64; 2], c: usize| -> DVector<f64> {
        DVector::from_iterator(n, kicks.iter().map(|k| k.measured[c] - f(k)[c]))
    };
    let ms = |f: &dyn Fn(&KickWeave) -> [f64; 2]| -> f64 {
        (residual(f, 0).norm_squared() + residual(f, 1).norm_squared()) / (2 * n) as f64
    };
    let svd = x.clone().svd(true, true);
    let rank = svd.rank(1e-10 * svd.singular_values.max());
    let mut ss_pattern_free = 0.0;
    let mut ss_model = 0.0;
    let mut pattern = Vec::new();
    let xtx_inv = (x.transpose() * &x).try_inverse();
    for (c, part) in [(0usize, Part::Real), (1, Part::Imaginary)] {
        let r = residual(&|k| k.after, c);
        let beta = svd.solve(&r, 1e-12).ok()?;
        let e = &r - &x * &beta;
        ss_model += r.norm_squared();
        ss_pattern_free += e.norm_squared();
        // Each term's coefficient and standard error.
        if let Some(inv) = &xtx_inv {
            let s2 = e.norm_squared() / (n as f64 - q as f64).max(1.0);
            for (j, (state, _)) in columns.iter().enumerate() {
                let se = (s2 * inv[(j, j)]).sqrt();
                if beta[j].abs() > 2.0 * se {
                    pattern.push(PatternTerm {
                        part,
                        state: *state,
                        coefficient: beta[j],
                        stderr: se,
                    });
                }
            }
        }
    }
    let p = 2 * rank;
    let dof = 2 * n - p;
    if dof == 0 {
        return None;
    }
    let floor_ms = ss_pattern_free / dof as f64;
    let f = ((ss_model - ss_pattern_free) / p as f64) / floor_ms;
    let p_value = if f.is_finite() && floor_ms > 0.0 {
        FisherSnedecor::new(p as f64, dof as f64).map_or(f64::NAN, |d| d.sf(f))
    } else if ss_model > ss_pattern_free {
        0.0
    } else {
        1.0
    };
    let (base_ms, after_ms, held_ms) = (ms(&|k| k.base), ms(&|k| k.after), ms(&|k| k.held_out));
    let share = |ms: f64| {
        if base_ms > floor_ms {
            (base_ms - ms) / (base_ms - floor_ms)
        } else {
            f64::NAN
        }
    };
    // A pooled eigenvalue RMS is over |d|^2 = d_re^2 + d_im^2: twice the
    // mean square per part.
    let rms = |ms: f64| (2.0 * ms).sqrt();
    Some(Remaining {
        kicks: n,
        regressors: columns.into_iter().filter_map(|c| c.0).collect(),
        base_rms: rms(base_ms),
        after_rms: rms(after_ms),
        held_out_rms: rms(held_ms),
        floor_rms: rms(floor_ms),
        explained: share(after_ms),
        explained_held_out: share(held_ms),
        f,
        df: [p, dof],
        p_value,
        structured: p_value < STRUCTURE_LEVEL,
        pattern,
    })
}

fn distinct(x: &[f64]) -> usize {
    let mut v: Vec<f64> = x.to_vec();
    v.sort_by(f64::total_cmp);
    v.dedup_by(|a, b| (*a - *b).abs() <= 1e-6 * b.abs().max(1.0));
    v.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fixed stream of standard normal numbers (Box-Muller on a linear
    /// congruential generator), so the tests do not hang on a seed's luck
    /// beyond what the level states.
    fn normals(seed: u64, n: usize) -> Vec<f64> {
        let mut s = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut u = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| (-2.0 * u().ln()).sqrt() * (2.0 * std::f64::consts::PI * u()).cos())
            .collect()
    }

    /// Kicks at 3-6 m/s whose identified model is `after_error(v)` off the
    /// truth, measured with a scatter of 0.2 1/s; the base model is 1 1/s
    /// off in both parts.
    fn kicks(seed: u64, after_error: impl Fn(f64) -> [f64; 2]) -> Vec<KickWeave> {
        let z = normals(seed, 96);
        (0..48)
            .map(|i| {
                let v = 3.0 + 3.0 * (i % 12) as f64 / 11.0;
                let truth = [-1.0 + 0.2 * v, 5.0 + 0.5 * v];
                let measured = [truth[0] + 0.2 * z[2 * i], truth[1] + 0.2 * z[2 * i + 1]];
                let e = after_error(v);
                let after = [truth[0] + e[0], truth[1] + e[1]];
                KickWeave {
                    speed: v,
                    amplitude: Some(0.1 + 0.01 * (i % 5) as f64),
                    measured,
                    base: [truth[0] + 1.0, truth[1] - 1.0],
                    after,
                    held_out: after,
                }
            })
            .collect()
    }

    #[test]
    fn a_right_model_leaves_no_structured_residual_and_explains_what_a_perfect_model_would() {
        // Of twenty independent sets, none is called structured at the 1 %
        // level by more than chance allows (two would be very unlikely).
        let structured = (0..20)
            .filter(|&s| remaining(&kicks(s, |_| [0.0, 0.0])).unwrap().structured)
            .count();
        assert!(structured <= 1, "{structured} of 20 right models called structured");
        let r = remaining(&kicks(7, |_| [0.0, 0.0])).unwrap();
        assert!((r.explained - 1.0).abs() < 0.05, "{r:?}");
        // The floor is the scatter: 0.2 1/s per part, 0.28 as a pooled RMS.
        assert!((r.floor_rms - 0.2 * 2f64.sqrt()).abs() < 0.05, "{r:?}");
        assert!(!r.structured, "{r:?}");
    }

    #[test]
    fn a_frequency_error_growing_with_speed_is_a_structured_residual_named_by_its_state() {
        // The model's frequency is off by 0.3 rad/s per m/s from 4.5 m/s:
        // structured, the measured minus predicted frequency falls with
        // speed, and the share explained falls short of a perfect model's.
        let r = remaining(&kicks(3, |v| [0.0, 0.3 * (v - 4.5)])).unwrap();
        assert!(r.structured && r.p_value < 1e-6, "{r:?}");
        assert!(r.explained < 0.99 && r.explained > 0.5, "{r:?}");
        assert!(
            r.pattern
                .iter()
                .any(|t| t.part == Part::Imaginary && t.state == Some(State::Speed) && t.coefficient < 0.0),
            "{r:?}"
        );
        // An offset of the damping alone is a pattern too (the constant;
        // the model too little damped, the measured real part below it).
        let r = remaining(&kicks(3, |_| [0.25, 0.0])).unwrap();
        assert!(r.structured, "{r:?}");
        assert!(
            r.pattern
                .iter()
                .any(|t| t.part == Part::Real && t.state.is_none() && t.coefficient < 0.0),
            "{r:?}"
        );
    }

    #[test]
    fn too_few_kicks_or_unusable_ones_give_no_verdict() {
        let k = kicks(1, |_| [0.0, 0.0]);
        assert!(remaining(&k[..3]).is_none());
        let mut bad = k[..3].to_vec();
        bad.push(KickWeave {
            measured: [f64::NAN, 1.0],
            ..k[3]
        });
        assert!(remaining(&bad).is_none());
        // A table (no amplitudes) at one speed tests only the constant.
        let table: Vec<KickWeave> = k
            .iter()
            .map(|x| KickWeave {
                speed: 4.0,
                amplitude: None,
                ..*x
            })
            .collect();
        assert!(remaining(&table).unwrap().regressors.is_empty());
    }
}
