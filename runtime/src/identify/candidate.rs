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
    /// Physical only when positive (dissipation).
    pub dissipative: bool,
    /// Unit, for reports.
    pub unit: String,
    /// Starting value of the fit (default a tenth of the scale).
    pub initial: Option<f64>,
    /// Smallest value the model is simulated with (values below are held
    /// there): for parameters the model is undefined or singular without,
    /// such as a relaxation length.
    pub lower: Option<f64>,
    /// Gaussian prior `(mean, standard deviation)`: a measured parameter
    /// corrected by identification moves only as far as the data demand
    /// (the fit adds `((value - mean) / sd)^2` to its weighted sum).
    pub prior: Option<(f64, f64)>,
    /// Where the prior's tail turns from Gaussian to exponential, in its
    /// standard deviations (Huber): within it the fit adds
    /// `((value - mean) / sd)^2`, beyond it a penalty growing linearly. A
    /// measurement can be grossly wrong (a lamp or a bag on the handlebar
    /// that the file forgot); a Gaussian tail would then pull the corrected
    /// value back and spread the rest of the error over other parameters.
    /// (Scaled with the prior when the prior is put on the data's scale.)
    pub gross_beyond: f64,
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
