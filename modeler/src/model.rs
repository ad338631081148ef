//! Declaring a multibody model: coordinates, parameters, frames built from
//! elementary rotations, points, bodies, constraints and applied forces.
//!
//! A [`ModelBuilder`] collects declarations; [`ModelBuilder::build`] validates
//! the whole model at once and reports every problem it finds
//! ([`ModelError::Invalid`]), then freezes it into a [`Model`] that the
//! derivation stage ([`crate::derive`]) consumes.
//!
//! The parts a model declares (coordinates, parameters, frames, points,
//! bodies, constraints, forces, states) are in `declarations.rs`; the
//! validation and its diagnostics in `validation.rs`; here, the frozen
//! [`Model`], the files it comes from and its [`ModelBuilder`].

mod declarations;
mod validation;

pub use declarations::{
    AppliedForce, Body, Coordinate, CoordinateRole, EffectInfo, Force, Frame, Holonomic, Nonholonomic, Parameter,
    ParameterRole, Point, Role, State, Uncertainty,
};
pub use validation::{validate, Diagnostic, ModelError, BICYCLE_JOBS};

// The handles live with the expressions that refer to them (`expr`
// depends on no other module); they are the model's vocabulary, so they are
// named from here too.
pub use crate::expr::{Axis, BodyId, FrameId, PointId, GROUND};
use crate::expr::{Expr, Tensor3, Vec3};

/// A file a model is declared in, as a model file declares it: its path
/// and, for the files inside the modeler, its text (`include_str!` of the
/// file itself). The text is hashed into the committed generated code's
/// inputs hash, so that any edit of the file is noticed and named.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SourceFile {
    pub path: &'static str,
    pub text: Option<&'static str>,
}

impl SourceFile {
    /// A file whose text is part of the model's inputs.
    pub const fn new(path: &'static str, text: &'static str) -> SourceFile {
        SourceFile { path, text: Some(text) }
    }
}

/// A path alone: a user's model file outside the modeler (derived at every
/// build, so nothing needs its text).
impl From<&'static str> for SourceFile {
    fn from(path: &'static str) -> SourceFile {
        SourceFile { path, text: None }
    }
}

/// A file a model came from, as the model records it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Source {
    pub path: String,
    /// FNV-1a hash of the file's text, when the model file gave it.
    pub text_hash: Option<u64>,
}

/// A frozen, validated model.
#[derive(Clone, Debug)]
pub struct Model {
    pub name: String,
    pub doc: String,
    /// Files the model is declared in: its model files and the effects it
    /// applies (named in the generated header).
    pub sources: Vec<Source>,
    /// The base model this one is declared from (its own name for a base).
    pub base: String,
    /// True when forward speed is a degree of freedom (no driving constraint).
    pub free_speed: bool,
    /// Effects applied, in order.
    pub effects: Vec<EffectInfo>,
    /// Forward speed of the bicycle (m/s) as an expression in parameters,
    /// coordinates and rates (e.g. the driving parameter `V`, or `Rt psi'`).
    pub forward_speed: Option<Expr>,
    pub coordinates: Vec<Coordinate>,
    pub parameters: Vec<Parameter>,
    pub frames: Vec<Frame>,
    pub points: Vec<Point>,
    pub bodies: Vec<Body>,
    pub holonomic: Vec<Holonomic>,
    pub nonholonomic: Vec<Nonholonomic>,
    pub forces: Vec<AppliedForce>,
    /// Extra first-order states.
    pub states: Vec<State>,
    /// Points whose global positions are emitted.
    pub points_of_interest: Vec<PointId>,
    /// Gravity: parameter name and the global axis it acts against (Z up).
    pub gravity: Option<(String, Axis)>,
}

/// Collects declarations; see the module docs.
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    m: Model,
    /// The effect being applied (see [`ModelBuilder::begin_effect`]).
    effect: Option<String>,
    /// Roles given to names that were not declared: `(name, role)`,
    /// reported by [`ModelBuilder::build`].
    unresolved_roles: Vec<(String, &'static str)>,
}

impl Model {
    /// Check that the model declares every coordinate role the `jobs` need
    /// (e.g. [`BICYCLE_JOBS`]); the error lists each missing role with its
    /// job.
    pub fn check_roles(&self, jobs: &[(&'static str, &[CoordinateRole])]) -> Result<(), ModelError> {
        let mut problems = Vec::new();
        for &(job, roles) in jobs {
            for role in roles {
                if !self.coordinates.iter().any(|c| c.meaning == Some(*role)) {
                    problems.push(Diagnostic::MissingRole {
                        role: role.variant(),
                        job,
                    });
                }
            }
        }
        if problems.is_empty() {
            Ok(())
        } else {
            Err(ModelError::Invalid {
                model: self.name.clone(),
                problems,
            })
        }
    }

    /// Start declaring a model.
    pub fn builder(name: &str) -> ModelBuilder {
        ModelBuilder {
            effect: None,
            unresolved_roles: Vec::new(),
            m: Model {
                name: name.to_string(),
                doc: String::new(),
                sources: Vec::new(),
                base: name.to_string(),
                free_speed: false,
                effects: Vec::new(),
                forward_speed: None,
                coordinates: Vec::new(),
                parameters: Vec::new(),
                frames: vec![Frame {
                    name: "ground".into(),
                    parent: GROUND,
                    rotations: vec![],
                }],
                points: Vec::new(),
                bodies: Vec::new(),
                holonomic: Vec::new(),
                nonholonomic: Vec::new(),
                forces: Vec::new(),
                states: Vec::new(),
                points_of_interest: Vec::new(),
                gravity: None,
            },
        }
    }

    /// Parameter by name.
    pub fn parameter(&self, name: &str) -> Option<&Parameter> {
        self.parameters.iter().find(|p| p.name == name)
    }

    /// Index of a coordinate.
    pub fn coordinate_index(&self, name: &str) -> Option<usize> {
        self.coordinates.iter().position(|c| c.name == name)
    }

    /// Names of the holonomic constraints.
    pub fn holonomic_names(&self) -> Vec<String> {
        self.holonomic
            .iter()
            .map(|h| match h {
                Holonomic::Residual { name, .. }
                | Holonomic::PointComponent { name, .. }
                | Holonomic::PointComponentStationary { name, .. } => name.clone(),
            })
            .collect()
    }

    /// Names of the nonholonomic constraints.
    pub fn nonholonomic_names(&self) -> Vec<String> {
        self.nonholonomic
            .iter()
            .map(|h| match h {
                Nonholonomic::ContactVelocity { name, .. } | Nonholonomic::Linear { name, .. } => name.clone(),
            })
            .collect()
    }
}

impl ModelBuilder {
    /// Documentation line of the model.
    pub fn doc(mut self, doc: &str) -> Self {
        self.m.doc = doc.to_string();
        self
    }
    /// A file the model is declared in (shown in generated headers; with
    /// its text, part of the inputs hash of the committed code).
    pub fn source(mut self, file: impl Into<SourceFile>) -> Self {
        self.add_source(file);
        self
    }
    /// Record one more file the model comes from (an effect's file, a
    /// variant's base model file); a path already recorded is kept once.
    pub fn add_source(&mut self, file: impl Into<SourceFile>) {
        let file = file.into();
        if self.m.sources.iter().any(|s| s.path == file.path) {
            return;
        }
        self.m.sources.push(Source {
            path: file.path.to_string(),
            text_hash: file.text.map(|t| crate::hash::fnv1a(t.as_bytes())),
        });
    }
    /// Declare a coordinate (and its rate).
    pub fn coordinate(&mut self, name: &str, role: Role, guess: f64, doc: &str) -> Expr {
        self.m.coordinates.push(Coordinate {
            name: name.into(),
            doc: doc.into(),
            role,
            guess,
            upright: None,
            meaning: None,
        });
        Expr::Coord(name.into())
    }
    /// Declare a parameter the bicycle must give.
    pub fn parameter(&mut self, name: &str, doc: &str) -> Expr {
        self.m.parameters.push(Parameter {
            name: name.into(),
            doc: doc.into(),
            default: None,
            effect: self.effect.clone(),
            meaning: None,
            lower: None,
            uncertainty: None,
        });
        Expr::Param(name.into())
    }
    /// Declare a parameter with a default value (effect parameters: the
    /// value at which the effect is absent, usually 0).
    pub fn parameter_with_default(&mut self, name: &str, doc: &str, default: f64) -> Expr {
        self.m.parameters.push(Parameter {
            name: name.into(),
            doc: doc.into(),
            default: Some(default),
            effect: self.effect.clone(),
            meaning: None,
            lower: None,
            uncertainty: None,
        });
        Expr::Param(name.into())
    }
    /// The coordinate's exact value in the physical upright configuration
    /// (see [`Coordinate::upright`]).
    pub fn upright_value(&mut self, coordinate: &str, value: Expr) {
        if let Some(c) = self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            c.upright = Some(value);
        }
    }
    /// A physical lower bound of parameter `parameter`: values below
    /// `bound` (or equal to it, when `strict`) are refused when a bicycle is
    /// read, e.g. a negative damping coefficient or a zero relaxation length.
    pub fn lower_bound(&mut self, parameter: &str, bound: f64, strict: bool) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(p) => p.lower = Some((bound, strict)),
            None => self.unresolved_roles.push((parameter.to_string(), "lower bound")),
        }
    }
    /// Declare how well a measured parameter is known (see [`Uncertainty`]).
    pub fn uncertainty(&mut self, parameter: &str, uncertainty: Uncertainty) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(p) => p.uncertainty = Some(uncertainty),
            None => self.unresolved_roles.push((parameter.to_string(), "uncertainty")),
        }
    }
    /// Declare what coordinate `coordinate` means (see [`CoordinateRole`]).
    /// An undeclared name or a meaning given to two coordinates is reported
    /// by [`ModelBuilder::build`].
    pub fn coordinate_role(&mut self, coordinate: &str, role: CoordinateRole) {
        match self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            Some(c) => c.meaning = Some(role),
            None => self.unresolved_roles.push((coordinate.to_string(), role.variant())),
        }
    }
    /// Declare what parameter `parameter` means (see [`ParameterRole`]).
    pub fn parameter_role(&mut self, parameter: &str, role: ParameterRole) {
        match self.m.parameters.iter_mut().find(|c| c.name == parameter) {
            Some(c) => c.meaning = Some(role),
            None => self.unresolved_roles.push((parameter.to_string(), role.variant())),
        }
    }
    /// Change a coordinate's role (for model variants, e.g. free speed).
    pub fn set_role(&mut self, coordinate: &str, role: Role) {
        if let Some(c) = self.m.coordinates.iter_mut().find(|c| c.name == coordinate) {
            c.role = role;
        }
    }
    /// Mark the model as a variant of `base` (shown in the registry).
    pub fn set_base(&mut self, base: &str) {
        self.m.base = base.to_string();
    }
    /// Declare that forward speed is a degree of freedom.
    pub fn set_free_speed(&mut self, free: bool) {
        self.m.free_speed = free;
    }
    /// The forward speed of the bicycle (m/s) as an expression.
    pub fn forward_speed(&mut self, speed: Expr) {
        self.m.forward_speed = Some(speed);
    }
    /// Rename the model (variants built from another model's declaration).
    pub fn set_name(&mut self, name: &str) {
        self.m.name = name.to_string();
    }
    /// Start applying an effect: parameters and forces declared until
    /// [`ModelBuilder::end_effect`] belong to it.
    pub fn begin_effect(&mut self, name: &str, doc: &str) {
        self.m.effects.push(EffectInfo {
            name: name.into(),
            doc: doc.into(),
            identification: None,
        });
        self.effect = Some(name.to_string());
    }
    /// How identification tests the effect being applied.
    pub fn declare_identification(&mut self, identification: crate::identification::Identification) {
        if let Some(e) = self.m.effects.last_mut() {
            e.identification = Some(identification);
        }
    }
    /// Stop attributing declarations to the current effect.
    pub fn end_effect(&mut self) {
        self.effect = None;
    }
    /// The model as declared so far (read-only; effects inspect bodies,
    /// points and parameters through it).
    pub fn model(&self) -> &Model {
        &self.m
    }
    /// Declare a frame reached from `parent` by elementary rotations.
    pub fn frame(&mut self, name: &str, parent: FrameId, rotations: Vec<(Axis, Expr)>) -> FrameId {
        self.m.frames.push(Frame {
            name: name.into(),
            parent,
            rotations,
        });
        FrameId(self.m.frames.len() - 1)
    }
    /// Declare a point `base + sum A_frame v`.
    pub fn point(&mut self, name: &str, base: Option<PointId>, offsets: Vec<(FrameId, Vec3)>) -> PointId {
        self.m.points.push(Point {
            name: name.into(),
            base,
            offsets,
        });
        PointId(self.m.points.len() - 1)
    }
    /// Declare a rigid body.
    pub fn body(&mut self, name: &str, frame: FrameId, mass: Expr, inertia: Tensor3, mass_centre: PointId) -> BodyId {
        self.m.bodies.push(Body {
            name: name.into(),
            frame,
            mass,
            inertia,
            mass_centre,
        });
        BodyId(self.m.bodies.len() - 1)
    }
    /// Move a body's mass centre to another point (for model variants).
    pub fn move_mass_centre(&mut self, body: BodyId, point: PointId) {
        self.m.bodies[body.0].mass_centre = point;
    }
    /// Replace the documentation line (for model variants).
    pub fn set_doc(&mut self, doc: &str) {
        self.m.doc = doc.to_string();
    }
    /// Add a holonomic constraint.
    pub fn holonomic(&mut self, c: Holonomic) {
        self.m.holonomic.push(c);
    }
    /// Add a nonholonomic constraint.
    pub fn nonholonomic(&mut self, c: Nonholonomic) {
        self.m.nonholonomic.push(c);
    }
    /// Remove a nonholonomic constraint by name (effects that replace one,
    /// e.g. tyre slip replacing a wheel's lateral no-slip condition); false
    /// when there is none of that name.
    pub fn remove_nonholonomic(&mut self, name: &str) -> bool {
        let before = self.m.nonholonomic.len();
        self.m.nonholonomic.retain(|n| match n {
            Nonholonomic::ContactVelocity { name: k, .. } | Nonholonomic::Linear { name: k, .. } => k != name,
        });
        self.m.nonholonomic.len() < before
    }
    /// Declare an extra first-order state with its rate `dz/dt`; returns the
    /// state as an expression.
    pub fn state(&mut self, name: &str, doc: &str, rate: Expr) -> Expr {
        self.m.states.push(State {
            name: name.into(),
            doc: doc.into(),
            rate,
            effect: self.effect.clone(),
        });
        Expr::State(name.into())
    }
    /// Add an applied force (conservative or of unknown sign of power).
    pub fn force(&mut self, f: Force) {
        self.m.forces.push(AppliedForce {
            force: f,
            effect: self.effect.clone(),
            dissipative: false,
        });
    }
    /// Add a dissipative force: its power `p'^T Q` is never positive
    /// (checked by `bikedyn verify`).
    pub fn dissipative_force(&mut self, f: Force) {
        self.m.forces.push(AppliedForce {
            force: f,
            effect: self.effect.clone(),
            dissipative: true,
        });
    }
    /// Emit the global position of this point.
    pub fn point_of_interest(&mut self, p: PointId) {
        self.m.points_of_interest.push(p);
    }
    /// Uniform gravity of magnitude `param` acting along minus `up`.
    pub fn gravity(&mut self, param: &str, up: Axis) {
        self.m.gravity = Some((param.into(), up));
    }

    /// Validate everything and freeze the model.
    pub fn build(self) -> Result<Model, ModelError> {
        let mut problems: Vec<Diagnostic> = self
            .unresolved_roles
            .iter()
            .map(|(name, role)| Diagnostic::Undeclared {
                kind: "coordinate or parameter",
                name: name.clone(),
                used_in: format!("the role `{role}`"),
            })
            .collect();
        problems.extend(validate(&self.m));
        if problems.is_empty() {
            Ok(self.m)
        } else {
            Err(ModelError::Invalid {
                model: self.m.name.clone(),
                problems,
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expr::{coord, num, param, rate, vec3};

    #[test]
    fn validation_reports_every_problem_at_once() {
        let mut m = Model::builder("broken");
        let th = m.coordinate("theta", Role::Independent, 0.0, "angle");
        m.coordinate("theta", Role::Dependent, 0.0, "again");
        m.parameter("L", "length");
        let f = m.frame("pendulum", GROUND, vec![(Axis::Y, th + coord("undeclared"))]);
        let p = m.point(
            "tip",
            None,
            vec![(f, vec3(param("L") * rate("theta"), num(0), param("missing")))],
        );
        let _ = m.body("bob", f, param("m"), crate::expr::inertia_wheel(num(1), num(1)), p);
        let err = m.build().unwrap_err();
        let ModelError::Invalid { problems, .. } = &err;
        let has = |d: &Diagnostic| problems.contains(d);
        assert!(has(&Diagnostic::Duplicate {
            kind: "coordinate",
            name: "theta".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "coordinate",
            name: "undeclared".into(),
            used_in: "frame `pendulum`".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "parameter",
            name: "missing".into(),
            used_in: "point `tip`".into()
        }));
        assert!(has(&Diagnostic::Undeclared {
            kind: "parameter",
            name: "m".into(),
            used_in: "mass of body `bob`".into()
        }));
        assert!(has(&Diagnostic::RateInGeometry {
            item: "point `tip`".into()
        }));
        assert!(has(&Diagnostic::HolonomicCount {
            dependent: 1,
            constraints: 0
        }));
        assert!(has(&Diagnostic::DegreesOfFreedom {
            coordinates: 2,
            independent: 1,
            constraints: 0
        }));
        let text = err.to_string();
        assert!(text.contains("7 problems") || problems.len() >= 7, "{text}");
    }

    #[test]
    fn asymmetric_inertia_and_time_in_geometry_are_reported() {
        let mut m = Model::builder("bad");
        let th = m.coordinate("theta", Role::Independent, 0.0, "angle");
        let f = m.frame("a", GROUND, vec![(Axis::Z, th * crate::expr::time())]);
        let p = m.point("c", None, vec![(f, vec3(num(1), num(0), num(0)))]);
        let mut i = crate::expr::inertia_wheel(num(1), num(2));
        i[0][1] = num(3);
        m.body("b", f, num(1), i, p);
        let ModelError::Invalid { problems, .. } = m.build().unwrap_err();
        assert!(problems.contains(&Diagnostic::AsymmetricInertia { body: "b".into() }));
        assert!(problems.contains(&Diagnostic::TimeDependentGeometry {
            item: "frame `a`".into()
        }));
    }

    #[test]
    fn the_thesis_models_validate() {
        let models = crate::models::all().unwrap();
        let thesis = models.iter().find(|m| m.name == "thesis_whipple").unwrap();
        assert_eq!(thesis.coordinates.len(), 9);
        assert_eq!(thesis.holonomic.len(), 3);
        assert_eq!(thesis.nonholonomic.len(), 4);
        let names: Vec<&str> = thesis.coordinates.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["xc", "yc", "phi", "theta", "psi", "beta", "gamma", "eps", "xi"]);
        let offset = models.iter().find(|m| m.name == "whipple_offset").unwrap();
        assert!(offset.parameters.iter().any(|p| p.name == "d4"));
    }

    /// A bicycle model without a role a job needs is refused when it is
    /// generated, naming the role and the job (issue 16, point 1).
    #[test]
    fn a_model_without_the_roles_the_jobs_need_is_refused_at_generation() {
        let models = crate::models::all().unwrap();
        for m in &models {
            m.check_roles(BICYCLE_JOBS).unwrap();
        }
        let mut m = models.iter().find(|m| m.name == "whipple_offset").unwrap().clone();
        for c in m.coordinates.iter_mut() {
            if c.meaning == Some(CoordinateRole::Steer) {
                c.meaning = None;
            }
        }
        let err = m.check_roles(BICYCLE_JOBS).unwrap_err().to_string();
        assert!(
            err.contains("`Steer`") && err.contains("the linear roll-steer analysis"),
            "{err}"
        );
        assert!(err.contains("identification residuals"), "{err}");
        assert!(!err.contains("`Roll`"), "{err}");
    }
}
