//! What a candidate is: effects of the library (or a correction of a
//! measured parameter) with the parameters a fit frees when it is added,
//! their scales, floors, priors and ties, and the fixed values it needs.
//! Identification takes candidates as data; it never looks inside an
//! effect.

use serde::Serialize;

/// A fitted effect parameter.
#[derive(Clone, Debug, Serialize)]
pub struct EffectParameter {
    /// Model parameter symbol.
    pub symbol: String,
    /// Other symbols set to the same value (e.g. front and rear rolling
    /// resistance coefficients).
    pub tied: Vec<String>,
    /// Model parameters this one moves, when `symbol` is not one of the
    /// model's own but a quantity of the bicycle file that the model holds
    /// in several parameters (the front assembly's mass-centre height
    /// `zH`: the steer-axis point, the front wheel centre from it and the
    /// offset from the axis). Each `(model symbol, coefficient)` is
    /// simulated at its base value plus the coefficient times this value's
    /// change from `initial` (the tangent of the file's conversion to the
    /// model's parameters). Empty: `symbol` and `tied` are model parameters
    /// set to the value.
    pub moves: Vec<(String, f64)>,
    /// Typical magnitude (difference step and LM scaling).
    pub scale: f64,
    /// Physical only when positive: a dissipation, or a corrected mass or
    /// principal moment of inertia.
    pub dissipative: bool,
    /// Unit, for reports.
    pub unit: String,
    /// Starting value of the fit (default a tenth of the scale).
    pub initial: Option<f64>,
    /// Smallest value the model is simulated with (values below are held
    /// there): for parameters the model is undefined or singular without,
    /// such as a relaxation length.
    pub lower: Option<f64>,
    /// Largest value the model is simulated with (values above are held
    /// there): a law's shape beyond which it would be another effect (a
    /// friction smoothed so widely that it is a damper).
    pub upper: Option<f64>,
    /// A parameter of the law's shape (a friction's smoothing rate), not of
    /// the effect's size: the effect is absent when its size parameters
    /// are, and the fit starts it from `initial` in every start.
    pub shape: bool,
    /// Gaussian prior `(mean, standard deviation)`: a measured parameter
    /// corrected by identification moves only as far as the data demand
    /// (the fit adds `((value - mean) / sd)^2` to its weighted sum).
    pub prior: Option<(f64, f64)>,
    /// Where the prior's tail turns from Gaussian to heavy, in its standard
    /// deviations: within it the fit adds `((value - mean) / sd)^2`, beyond
    /// it a penalty growing with the log of the distance, whose pull falls
    /// as the distance grows (`heavy_tailed` in `problem.rs`). A
    /// measurement can be grossly wrong (a lamp or a bag on the handlebar
    /// that the file forgot); a Gaussian tail, or a linear one, would then
    /// pull the corrected value back and spread the rest of the error over
    /// other parameters. (Scaled with the prior when the prior is put on
    /// the data's scale.)
    pub gross_beyond: f64,
}

/// A floor or ceiling of a fitted parameter, with its value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Bound {
    Floor(f64),
    Ceiling(f64),
}

impl EffectParameter {
    /// The value the model is simulated with for fitted value `v`: `v`
    /// held within the floor and the ceiling.
    pub fn simulated(&self, v: f64) -> f64 {
        let v = self.lower.map_or(v, |lo| v.max(lo));
        self.upper.map_or(v, |hi| v.min(hi))
    }

    /// The bound a fitted value `v` ended on, if any: the data asked for a
    /// value beyond it, so `v` is a limit, not an estimate.
    pub fn on_bound(&self, v: f64) -> Option<Bound> {
        let near = |b: f64| (v - b).abs() <= 1e-9 * b.abs().max(self.scale);
        match (self.lower, self.upper) {
            (Some(lo), _) if v <= lo || near(lo) => Some(Bound::Floor(lo)),
            (_, Some(hi)) if v >= hi || near(hi) => Some(Bound::Ceiling(hi)),
            _ => None,
        }
    }

    /// Whether `v` lies beyond the floor or the ceiling, where the response
    /// does not move with it.
    pub fn held_at_bound(&self, v: f64) -> bool {
        self.lower.is_some_and(|lo| v < lo) || self.upper.is_some_and(|hi| v > hi)
    }
}

/// A candidate effect (or a combination): the parameters fitted when it is
/// added, and fixed parameters it needs (e.g. the air density).
#[derive(Clone, Debug, Serialize)]
pub struct Candidate {
    pub name: String,
    /// Effects of the library it switches on.
    pub effects: Vec<String>,
    pub parameters: Vec<EffectParameter>,
    pub fixed: Vec<(String, f64)>,
    /// A speed-decay effect (rolling resistance, drag).
    pub speed_decay: bool,
    /// Why this effect is suspected, from the residual pattern.
    pub reason: String,
    /// Simulated with the alternative model (e.g. the tyre model, which
    /// replaces the no-slip constraints) instead of the base model.
    pub alternative_model: bool,
    /// Its law is not smooth at its base value (Coulomb friction: a
    /// describing-function equivalent). The score test linearises at that
    /// value and sees only the law's slope there, not the stick and slip a
    /// finite torque causes, so its prediction can miss the fitted gain by
    /// far: such a candidate is not screened, it is always fitted.
    pub nonsmooth: bool,
}

/// A test fixture: friction's smoothing rate between `lower` and `upper`.
#[cfg(test)]
pub(super) fn smoothing_rate(lower: Option<f64>, upper: Option<f64>) -> EffectParameter {
    EffectParameter {
        symbol: "w_steer".into(),
        tied: Vec::new(),
        moves: Vec::new(),
        scale: 0.05,
        dissipative: false,
        unit: "rad/s".into(),
        initial: Some(0.1),
        lower,
        upper,
        shape: true,
        prior: None,
        gross_beyond: PLAUSIBLE_PRIOR_SDS,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_beyond_a_floor_or_ceiling_is_simulated_at_it_and_a_value_on_it_still_moves() {
        let w = smoothing_rate(Some(0.002), Some(0.1));
        assert_eq!(w.simulated(0.5), 0.1);
        assert_eq!(w.simulated(-1.0), 0.002);
        assert_eq!(w.simulated(0.03), 0.03);
        assert!(w.held_at_bound(0.5) && w.held_at_bound(0.001));
        // On the bound the response still moves with it (a fit started
        // there can leave it).
        assert!(!w.held_at_bound(0.1) && !w.held_at_bound(0.002) && !w.held_at_bound(0.03));
        assert_eq!(w.on_bound(0.1), Some(Bound::Ceiling(0.1)));
        assert_eq!(w.on_bound(0.002), Some(Bound::Floor(0.002)));
        assert_eq!(w.on_bound(0.03), None);
        let free = smoothing_rate(None, None);
        assert_eq!(free.simulated(-3.0), -3.0);
        assert!(!free.held_at_bound(1e9));
    }
}

/// A correction further than this many prior standard deviations from its
/// measured value is no plausible rival explanation (beyond three, a
/// Gaussian prior gives it odds below 1 in 370).
pub const PLAUSIBLE_PRIOR_SDS: f64 = 3.0;
