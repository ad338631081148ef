//! The run-time view of a set of generated models: what each model is
//! ([`ModelInfo`]) and how to run generic code on a model chosen by name
//! ([`ModelVisitor`]; the generated registry's `with_model(name, visitor)`
//! matches the name and calls `visitor.visit::<ThatModel>()`).

use crate::model::{CoordinateRole, EffectDeclaration, MultibodyModel, ParameterInfo};

/// What a generated model is, for listings and model selection.
#[derive(Clone, Copy, Debug)]
pub struct ModelInfo {
    pub name: &'static str,
    pub doc: &'static str,
    pub base: &'static str,
    pub free_speed: bool,
    pub effects: &'static [&'static str],
    pub coordinates: &'static [&'static str],
    pub independent: &'static [usize],
    pub parameters: &'static [ParameterInfo],
    /// Extra first-order states (e.g. lagged tyre forces).
    pub states: &'static [&'static str],
    /// Declared meanings of coordinates: `(role, coordinate index)`.
    pub coordinate_roles: &'static [(CoordinateRole, usize)],
    /// The effects applied, with their identification declarations.
    pub effect_declarations: &'static [EffectDeclaration],
    /// Position in `parameters` of the forward speed a driven-speed model
    /// imposes (set by each job, not by a bicycle).
    pub forward_speed_parameter: Option<usize>,
}

impl ModelInfo {
    /// The record of model `M`.
    pub const fn of<M: MultibodyModel>() -> ModelInfo {
        ModelInfo {
            name: M::NAME,
            doc: M::DOC,
            base: M::BASE,
            free_speed: M::FREE_SPEED,
            effects: M::EFFECTS,
            coordinates: M::COORDINATES,
            independent: M::INDEPENDENT,
            parameters: M::PARAMETER_INFO,
            states: M::STATES,
            coordinate_roles: M::COORDINATE_ROLES,
            effect_declarations: M::EFFECT_DECLARATIONS,
            forward_speed_parameter: M::FORWARD_SPEED_PARAMETER,
        }
    }

    /// The coordinate with meaning `role`, by name.
    pub fn coordinate_with_role(&self, role: CoordinateRole) -> Option<&'static str> {
        self.coordinate_roles
            .iter()
            .find(|(r, _)| *r == role)
            .map(|&(_, i)| self.coordinates[i])
    }

    /// The independent coordinates the rolling bicycle lacks, by name:
    /// those with no declared role (a leaning rider's `lean`). A model with
    /// one has no second-order roll-steer form.
    pub fn added_coordinates(&self) -> Vec<&'static str> {
        crate::model::added_coordinates(self.independent, self.coordinate_roles)
            .into_iter()
            .map(|k| self.coordinates[self.independent[k]])
            .collect()
    }

    /// The declaration of the applied effect `name`.
    pub fn effect(&self, name: &str) -> Option<&'static EffectDeclaration> {
        self.effect_declarations.iter().find(|e| e.name == name)
    }

    /// The parameter called `name`.
    pub fn parameter(&self, name: &str) -> Option<&'static ParameterInfo> {
        self.parameters.iter().find(|p| p.name == name)
    }
}

/// Generic code to run on a model chosen at run time.
pub trait ModelVisitor {
    type Output;
    fn visit<M: MultibodyModel>(self) -> Self::Output;
}

/// A set of generated models, as one code generation wrote them: its
/// models and the dispatch from a name to a model type. Every generated
/// registry (`models.rs` of `bikedyn_modeler::codegen::generate`) defines a
/// unit struct `Registry` implementing it, so the application's pipelines
/// (bicycle resolution, synthetic sets, identification) run on the models
/// of bikedyn's build or of a user's own build script alike.
pub trait ModelRegistry: Copy + Default + std::fmt::Debug + Send + Sync + 'static {
    /// Every model of the registry, in declaration order.
    fn models() -> &'static [ModelInfo];
    /// Run `visitor` on the model called `name`; `None` when the registry
    /// has no model of that name.
    fn with_model<V: ModelVisitor>(name: &str, visitor: V) -> Option<V::Output>;
}
