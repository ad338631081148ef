//! How identification treats an effect: the declaration each effect file
//! gives beside its forces ([`Identification`]), emitted into the generated
//! metadata. Plain data, depending on no other module, so the model
//! ([`crate::model`]) and the effect library ([`crate::effects`], which
//! re-exports these types) can both name it.

/// What identification needs to test an effect as a candidate, declared in
/// the effect's own file beside its forces and emitted into the generated
/// metadata (`bikedyn_runtime::model::EffectDeclaration`), where the
/// identification reads it. The types mirror the runtime's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Identification {
    /// The effect is a candidate.
    Candidate(Candidate),
    /// The effect is never a candidate, for this reason (e.g. a known input
    /// of the experiment rather than a property to find).
    OptOut(&'static str),
}

/// How a candidate effect is fitted and recognised.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// The parameters fitted.
    pub fitted: &'static [Fitted],
    /// Parameters held at the bicycle's value (or their default) while
    /// fitting, e.g. the air density beside the drag area.
    pub held: &'static [&'static str],
    /// It shows as a loss of speed during the response.
    pub speed_decay: bool,
    /// The residual patterns of the base model that point to it.
    pub signatures: &'static [Signature],
    /// Why that pattern points to it, in a researcher's words.
    pub reason: &'static str,
    /// How the linear (eigenvalue) prediction represents it when its own
    /// linearization about upright is not useful.
    pub linear_equivalent: Option<LinearEquivalent>,
    /// It changes the degrees of freedom (tyre slip), so it is fitted with
    /// a model of its own rather than the identification model.
    pub own_model: bool,
}

/// A fitted parameter of a candidate effect.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fitted {
    pub symbol: &'static str,
    /// Parameters tied to it (they take the same value), e.g. the front
    /// rolling-resistance coefficient tied to the rear one.
    pub tied: &'static [&'static str],
    /// Typical magnitude, in the parameter's unit (scales the fit).
    pub scale: f64,
    /// It dissipates energy, so it must come out positive to be physical.
    pub dissipative: bool,
    /// Floor of the fit, if any (a relaxation length toward zero is a stiff,
    /// rigid tyre).
    pub floor: Option<f64>,
    /// Ceiling of the fit, if any (above it the law would become another
    /// effect of the library).
    pub ceiling: Option<f64>,
    /// The fit starts from the parameter's default rather than a tenth of
    /// its scale.
    pub start_at_default: bool,
    /// A parameter of the law's shape (the smoothing rate of Coulomb
    /// friction), not of the effect's size: the effect is absent when its
    /// size parameters are, whatever the shape. The fit starts from the
    /// bicycle's value (its file's, else the default), and a bicycle file
    /// that sets it does not thereby declare the effect present.
    pub shape: bool,
}

impl Fitted {
    /// A fitted parameter with no tie, floor or special start.
    pub const fn plain(symbol: &'static str, scale: f64, dissipative: bool) -> Fitted {
        Fitted {
            symbol,
            tied: &[],
            scale,
            dissipative,
            floor: None,
            ceiling: None,
            start_at_default: false,
            shape: false,
        }
    }
}

/// Residual patterns of the base model that the diagnosis tests, each
/// pointing to the effects that declare it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Signature {
    /// Measured weave more damped and slower than predicted.
    WeaveDampingAndFrequency,
    /// Damping that grows as the amplitude falls.
    AmplitudeDependentDamping,
    /// A steady lean after the kick.
    SteadyLean,
    /// A weave frequency error that grows with speed.
    FrequencyShiftWithSpeed,
    /// A loss of speed during the response.
    SpeedDecay,
}

impl Signature {
    /// The variant's name, as the emitted code spells it.
    pub fn variant(self) -> &'static str {
        match self {
            Signature::WeaveDampingAndFrequency => "WeaveDampingAndFrequency",
            Signature::AmplitudeDependentDamping => "AmplitudeDependentDamping",
            Signature::SteadyLean => "SteadyLean",
            Signature::FrequencyShiftWithSpeed => "FrequencyShiftWithSpeed",
            Signature::SpeedDecay => "SpeedDecay",
        }
    }
}

/// A linear stand-in for an effect whose linearization about upright is not
/// useful.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LinearEquivalent {
    /// Coulomb friction torque `torque` as the viscous damping `damping` of
    /// its describing function at the response's amplitude: for a sinusoid
    /// of rate amplitude `A`, `c_eq = 4 T / (pi A)`.
    DescribingFunctionDamping {
        torque: &'static str,
        damping: &'static str,
    },
}
