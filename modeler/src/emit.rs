//! Code emission: derived expressions -> optimized Rust source.
//!
//! Optimisation is our own common-subexpression elimination: every output of
//! one function is converted into a single hash-consed DAG (identical
//! subexpressions, including `sin`/`cos` of the same angle, become one node),
//! and each node is emitted once as a `let`, named by a hash of what it
//! computes (`temporary_names`) so that a model change renames only the
//! expressions it changes. Tokens are built with `quote`, checked by
//! `syn::parse2`, and formatted by `prettyplease`, so the output is stable
//! and diffs like the change. The functions are generic over the runtime's `Scalar`
//! trait so that dual numbers can flow through them (exact derivatives for the
//! linearization without emitting derivative code).
//!
//! Layout: `emit/dag.rs` (the DAG and its operation counts),
//! `emit/names.rs` (temporaries' names, literals), `emit/function.rs` (one
//! function); this file emits a whole model.

mod dag;
mod function;
mod names;

use dag::Input;
pub use dag::{FunctionReport, OpCount};
use function::emit_function;
use names::Names;

use crate::derive::Derived;
use crate::model::Role;
use crate::registry::camel;
pub use crate::registry::{emit_registry, EmitError};
use proc_macro2::TokenStream;
use quote::{format_ident, quote};
use std::collections::HashMap;

/// The emitted source of one model and its statistics.
pub struct Emitted {
    /// Formatted Rust source, with header.
    pub source: String,
    pub reports: Vec<FunctionReport>,
}

/// Emit the whole model: one module body with the generated functions, the
/// model's metadata, and the `MultibodyModel` implementation.
pub fn emit(d: &Derived) -> Result<Emitted, EmitError> {
    let m = &d.model;
    let mut inputs = HashMap::new();
    for (i, s) in d.symbols.params.iter().enumerate() {
        inputs.insert(*s, Input::Param(i));
    }
    for (i, s) in d.symbols.coords.iter().enumerate() {
        inputs.insert(*s, Input::Coord(i));
    }
    for (i, s) in d.symbols.rates.iter().enumerate() {
        inputs.insert(*s, Input::Rate(i));
    }
    inputs.insert(d.symbols.time, Input::Time);
    // Extra states are read from the parameter slice, after the parameters.
    let np = d.symbols.params.len();
    for (i, s) in d.symbols.states.iter().enumerate() {
        inputs.insert(*s, Input::Param(np + i));
    }
    let names = Names {
        params: m
            .parameters
            .iter()
            .map(|p| format_ident!("p_{}", p.name))
            .chain(m.states.iter().map(|z| format_ident!("z_{}", z.name)))
            .collect(),
        coords: m.coordinates.iter().map(|c| format_ident!("q_{}", c.name)).collect(),
        rates: m.coordinates.iter().map(|c| format_ident!("dq_{}", c.name)).collect(),
    };
    let mut fns = Vec::new();
    let mut reports = Vec::new();
    for q in &d.quantities {
        let (t, r) = emit_function(q, &inputs, &names)?;
        fns.push(t);
        reports.push(r);
    }
    let ty = format_ident!("{}", camel(&m.name));
    let name = &m.name;
    let coords: Vec<&str> = m.coordinates.iter().map(|c| c.name.as_str()).collect();
    let params: Vec<&str> = m.parameters.iter().map(|c| c.name.as_str()).collect();
    let holo = m.holonomic_names();
    let nonholo = m.nonholonomic_names();
    let poi: Vec<&str> = m
        .points_of_interest
        .iter()
        .map(|p| m.points[p.0].name.as_str())
        .collect();
    let indep: Vec<usize> = m
        .coordinates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.role == Role::Independent)
        .map(|(i, _)| i)
        .collect();
    let dep: Vec<usize> = m
        .coordinates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.role == Role::Dependent)
        .map(|(i, _)| i)
        .collect();
    let guess: Vec<proc_macro2::Literal> = m
        .coordinates
        .iter()
        .map(|c| proc_macro2::Literal::f64_suffixed(c.guess))
        .collect();
    let mut layout = Vec::new();
    let mut offset = 0usize;
    for q in d.quantities.iter().filter(|q| q.shared) {
        if let crate::derive::Shape::Buffer { .. } = q.shape {
            let (n, len) = (q.name, q.outputs.len());
            layout.push(quote!((#n, #offset, #len)));
            offset += len;
        }
    }
    let flop_names: Vec<&str> = reports.iter().map(|r| r.name).collect();
    let flop_counts: Vec<usize> = reports.iter().map(|r| r.after.total()).collect();
    let coord_docs: Vec<String> = m
        .coordinates
        .iter()
        .map(|c| format!("`{}`: {}", c.name, c.doc))
        .collect();
    let param_docs: Vec<String> = m
        .parameters
        .iter()
        .map(|c| format!("`{}`: {}", c.name, c.doc))
        .collect();
    let model_doc = format!("Generated model `{}`: {}", m.name, m.doc);
    let doc = &m.doc;
    let base = &m.base;
    let free_speed = m.free_speed;
    let effects: Vec<&str> = m.effects.iter().map(|e| e.name.as_str()).collect();
    let param_info = m.parameters.iter().map(|p| {
        let (n, pd) = (&p.name, &p.doc);
        let default = match p.default {
            Some(x) => {
                let l = proc_macro2::Literal::f64_suffixed(x);
                quote!(Some(#l))
            }
            None => quote!(None),
        };
        let effect = match &p.effect {
            Some(e) => quote!(Some(#e)),
            None => quote!(None),
        };
        let lower = match p.lower {
            Some((b, strict)) => {
                let l = proc_macro2::Literal::f64_suffixed(b);
                quote!(Some((#l, #strict)))
            }
            None => quote!(None),
        };
        let uncertainty = match p.uncertainty {
            Some(crate::model::Uncertainty::Relative(r)) => {
                let l = proc_macro2::Literal::f64_suffixed(r);
                quote!(Some(bikedyn_runtime::model::Uncertainty::Relative(#l)))
            }
            Some(crate::model::Uncertainty::Absolute(a)) => {
                let l = proc_macro2::Literal::f64_suffixed(a);
                quote!(Some(bikedyn_runtime::model::Uncertainty::Absolute(#l)))
            }
            None => quote!(None),
        };
        quote!(bikedyn_runtime::model::ParameterInfo { name: #n, doc: #pd, default: #default, effect: #effect, lower: #lower, uncertainty: #uncertainty })
    });
    let force_info = m.forces.iter().map(|f| {
        let n = f.name();
        let dis = f.dissipative;
        let effect = match &f.effect {
            Some(e) => quote!(Some(#e)),
            None => quote!(None),
        };
        quote!(bikedyn_runtime::model::ForceInfo { name: #n, effect: #effect, dissipative: #dis })
    });
    let param_pos = |name: &str| m.parameters.iter().position(|p| p.name == name);
    let opt = |x: Option<usize>| match x {
        Some(i) => quote!(Some(#i)),
        None => quote!(None),
    };
    // The forward-speed parameter of a driven model (`V`), and the
    // independent coordinate whose rate carries the speed in a free one.
    let speed_param = opt(match &m.forward_speed {
        Some(crate::expr::Expr::Param(n)) => param_pos(n),
        _ => None,
    });
    let speed_coord = opt(m.forward_speed.as_ref().and_then(|e| {
        let mut names = std::collections::BTreeSet::new();
        e.names(&mut names);
        indep
            .iter()
            .copied()
            .find(|&i| names.contains(&("rate", m.coordinates[i].name.clone())))
    }));
    let gravity_param = opt(m.gravity.as_ref().and_then(|(g, _)| param_pos(g)));
    // Effects with their identification declarations.
    let effect_decls = m.effects.iter().map(effect_declaration_tokens);
    // Declared meanings (roll, steer, wheel radii, ...), in declaration order.
    let coord_roles = m.coordinates.iter().enumerate().filter_map(|(i, c)| {
        c.meaning.map(|r| {
            let v = proc_macro2::Ident::new(r.variant(), proc_macro2::Span::call_site());
            quote!((bikedyn_runtime::model::CoordinateRole::#v, #i))
        })
    });
    let param_roles = m.parameters.iter().enumerate().filter_map(|(i, p)| {
        p.meaning.map(|r| {
            let v = proc_macro2::Ident::new(r.variant(), proc_macro2::Span::call_site());
            quote!((bikedyn_runtime::model::ParameterRole::#v, #i))
        })
    });
    let nforces = m.forces.len();
    // Dual widths of this model's linearizations, fixed here so that only
    // they are compiled.
    let lin_width = 2 * indep.len();
    let lin_half = indep.len();
    let ss_width = 2 * indep.len() + m.states.len();
    let states: Vec<&str> = m.states.iter().map(|z| z.name.as_str()).collect();
    let state_docs: Vec<&str> = m.states.iter().map(|z| z.doc.as_str()).collect();
    let tokens = quote! {
        use bikedyn_runtime::{MultibodyModel, Scalar};

        #[doc = #model_doc]
        #[derive(Clone, Copy, Debug, Default)]
        pub struct #ty;

        /// Generalized coordinates:
        #(#[doc = #coord_docs])*
        pub const COORDINATES: &[&str] = &[#(#coords),*];
        /// Parameters:
        #(#[doc = #param_docs])*
        pub const PARAMETERS: &[&str] = &[#(#params),*];

        #(#fns)*

        #[allow(clippy::approx_constant)]
        impl MultibodyModel for #ty {
            const NAME: &'static str = #name;
            const DOC: &'static str = #doc;
            const BASE: &'static str = #base;
            const FREE_SPEED: bool = #free_speed;
            const EFFECTS: &'static [&'static str] = &[#(#effects),*];
            const PARAMETER_INFO: &'static [bikedyn_runtime::model::ParameterInfo] = &[#(#param_info),*];
            const FORCES: &'static [bikedyn_runtime::model::ForceInfo] = &[#(#force_info),*];
            const FORWARD_SPEED_PARAMETER: Option<usize> = #speed_param;
            const SPEED_COORDINATE: Option<usize> = #speed_coord;
            const GRAVITY_PARAMETER: Option<usize> = #gravity_param;
            const EFFECT_DECLARATIONS: &'static [bikedyn_runtime::model::EffectDeclaration] = &[#(#effect_decls),*];
            const COORDINATE_ROLES: &'static [(bikedyn_runtime::model::CoordinateRole, usize)] = &[#(#coord_roles),*];
            const PARAMETER_ROLES: &'static [(bikedyn_runtime::model::ParameterRole, usize)] = &[#(#param_roles),*];
            const STATES: &'static [&'static str] = &[#(#states),*];
            const STATE_DOCS: &'static [&'static str] = &[#(#state_docs),*];
            const COORDINATES: &'static [&'static str] = COORDINATES;
            const PARAMETERS: &'static [&'static str] = PARAMETERS;
            const HOLONOMIC: &'static [&'static str] = &[#(#holo),*];
            const NONHOLONOMIC: &'static [&'static str] = &[#(#nonholo),*];
            const POINTS: &'static [&'static str] = &[#(#poi),*];
            const INDEPENDENT: &'static [usize] = &[#(#indep),*];
            const DEPENDENT: &'static [usize] = &[#(#dep),*];
            const INITIAL_GUESS: &'static [f64] = &[#(#guess),*];
            const ALL_QUANTITIES_LAYOUT: &'static [(&'static str, usize, usize)] = &[#(#layout),*];
            const FLOPS: &'static [(&'static str, usize)] = &[#((#flop_names, #flop_counts)),*];
            fn all_quantities<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { all_quantities(param, t, p, dp, out) }
            fn mass_matrix<T: Scalar>(param: &[T], p: &[T], out: &mut [T]) { mass_matrix(param, p, out) }
            fn quadratic_velocity_forces<T: Scalar>(param: &[T], p: &[T], dp: &[T], out: &mut [T]) { quadratic_velocity_forces(param, p, dp, out) }
            fn gravity_forces<T: Scalar>(param: &[T], p: &[T], out: &mut [T]) { gravity_forces(param, p, out) }
            fn applied_forces<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { applied_forces(param, t, p, dp, out) }
            fn holonomic_residuals<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]) { holonomic_residuals(param, t, p, out) }
            fn holonomic_jacobian<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]) { holonomic_jacobian(param, t, p, out) }
            fn holonomic_time_derivative<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]) { holonomic_time_derivative(param, t, p, out) }
            fn holonomic_convective<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { holonomic_convective(param, t, p, dp, out) }
            fn nonholonomic_velocities<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { nonholonomic_velocities(param, t, p, dp, out) }
            fn nonholonomic_matrix<T: Scalar>(param: &[T], t: T, p: &[T], out: &mut [T]) { nonholonomic_matrix(param, t, p, out) }
            fn nonholonomic_convective<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { nonholonomic_convective(param, t, p, dp, out) }
            fn kinetic_energy<T: Scalar>(param: &[T], p: &[T], dp: &[T]) -> T { kinetic_energy(param, p, dp) }
            fn potential_energy<T: Scalar>(param: &[T], p: &[T]) -> T { potential_energy(param, p) }
            fn point_positions<T: Scalar>(param: &[T], p: &[T], out: &mut [T]) { point_positions(param, p, out) }
            fn applied_force_terms<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { debug_assert_eq!(out.len(), #nforces * COORDINATES.len()); applied_force_terms(param, t, p, dp, out) }
            fn forward_speed<T: Scalar>(param: &[T], p: &[T], dp: &[T]) -> T { forward_speed(param, p, dp) }
            fn state_rates<T: Scalar>(param: &[T], t: T, p: &[T], dp: &[T], out: &mut [T]) { state_rates(param, t, p, dp, out) }
            fn upright_configuration<T: Scalar>(param: &[T], p: &[T], out: &mut [T]) { upright_configuration(param, p, out) }
            fn upright_velocity_terms_jacobian(param: &[f64], t: f64, p: &[f64], dp: &[f64], out: &mut [f64]) { upright_velocity_terms_jacobian(param, t, p, dp, out) }
            fn linearize_with_rest_exact(param: &[f64], dq0: &[f64]) -> Result<bikedyn_runtime::linearize::WithRest, bikedyn_runtime::linearize::LinearizeError> {
                bikedyn_runtime::linearize::linearize_with_rest::<Self, #lin_half, #lin_width>(param, dq0)
            }
            fn state_space_exact(param: &[f64], dq0: &[f64]) -> Result<bikedyn_runtime::linearize::StateMatrix, bikedyn_runtime::linearize::LinearizeError> {
                bikedyn_runtime::linearize::state_space_dual::<Self, #ss_width>(param, dq0)
            }
        }
    };
    let file = syn::parse2::<syn::File>(tokens).map_err(|e| EmitError::Syntax(e.to_string()))?;
    let body = prettyplease::unparse(&file);
    let header = crate::snapshot::header(m);
    Ok(Emitted {
        source: format!("{header}{body}"),
        reports,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::derive::derive;
    use crate::expr::{inertia_wheel, num, param, rate, vec3};
    use crate::model::{Axis, Force, Model, Role, GROUND};
    use symbolica::prelude::*;

    /// A planar pendulum with a driven pivot: small enough to check the
    /// derivation by hand. Coordinates: pivot x (driven), angle theta.
    fn pendulum() -> Model {
        let mut m = Model::builder("pendulum").source("modeler/src/emit.rs");
        let th = m.coordinate("theta", Role::Independent, 0.0, "angle (rad)");
        let x = m.coordinate("x", Role::Dependent, 0.0, "pivot position (m)");
        let l = m.parameter("L", "length (m)");
        m.parameter("m", "mass (kg)");
        m.parameter("I", "inertia (kg m^2)");
        m.parameter("g", "gravity (m/s^2)");
        m.parameter("c", "damping (N m s)");
        m.parameter("F", "horizontal push on the bob (N)");
        m.gravity("g", Axis::Z);
        let f = m.frame("arm", GROUND, vec![(Axis::Y, th)]);
        let pivot = m.point("pivot", None, vec![(GROUND, vec3(x.clone(), num(0), num(0)))]);
        let bob = m.point("bob", Some(pivot), vec![(f, vec3(num(0), num(0), -l))]);
        let body = m.body("bob", f, param("m"), inertia_wheel(param("I"), param("I")), bob);
        m.force(Force::AtMassCentre {
            name: "push".into(),
            body,
            frame: GROUND,
            force: vec3(param("F"), num(0), num(0)),
        });
        m.holonomic(crate::model::Holonomic::Residual {
            name: "drive".into(),
            expr: x - crate::expr::time(),
        });
        m.force(Force::Generalized {
            name: "damper".into(),
            coordinate: "theta".into(),
            expr: -(param("c") * rate("theta")),
        });
        m.point_of_interest(bob);
        m.build().unwrap()
    }

    #[test]
    fn pendulum_derivation_matches_hand_calculation() {
        crate::codegen::on_symbolica_thread(pendulum_derivation);
    }

    fn pendulum_derivation() {
        let d = derive(&pendulum());
        let q = |name: &str| d.quantities.iter().find(|q| q.name == name).unwrap();
        let (th, l, mm, i, g) = (
            symbol!("bikedyn_pendulum::q_theta"),
            symbol!("bikedyn_pendulum::p_L"),
            symbol!("bikedyn_pendulum::p_m"),
            symbol!("bikedyn_pendulum::p_I"),
            symbol!("bikedyn_pendulum::p_g"),
        );
        let (th, l, mm, i, g) = (Atom::var(th), Atom::var(l), Atom::var(mm), Atom::var(i), Atom::var(g));
        let is_zero = |a: Atom| {
            a.expand()
                .replace(Symbol::COS.call((&th,)).pow(Atom::num(2)))
                .with(Atom::num(1) - Symbol::SIN.call((&th,)).pow(Atom::num(2)))
                .expand()
                .is_zero()
        };
        // The bob is at (x - L sin(theta), 0, -L cos(theta)) (theta rotates
        // about y), so M = [[m L^2 + I, -m L cos(theta)], [-m L cos(theta), m]].
        let mass = &q("mass_matrix").outputs;
        assert!(is_zero(&mass[0] - (&mm * &l * &l + &i)), "M11 = {}", mass[0]);
        assert!(
            is_zero(&mass[1] + &mm * &l * Symbol::COS.call((&th,))),
            "M12 = {}",
            mass[1]
        );
        assert!(is_zero(&mass[3] - &mm), "M22 = {}", mass[3]);
        // Qgrav_theta = -m g L sin(theta): the bob is at z = -L cos(theta).
        assert!(is_zero(
            &q("gravity_forces").outputs[0] + &mm * &g * &l * Symbol::SIN.call((&th,))
        ));
        // Applied: damper -c theta' and the push F at the bob (virtual work
        // F dx_bob with x_bob = x - L sin(theta)).
        let (c, f, dth) = (
            Atom::var(symbol!("bikedyn_pendulum::p_c")),
            Atom::var(symbol!("bikedyn_pendulum::p_F")),
            Atom::var(symbol!("bikedyn_pendulum::dq_theta")),
        );
        let applied = &q("applied_forces").outputs;
        assert!(
            is_zero(&applied[0] + &c * &dth + &f * &l * Symbol::COS.call((&th,))),
            "Q_theta = {}",
            applied[0]
        );
        assert!(is_zero(&applied[1] - &f), "Q_x = {}", applied[1]);
        // Rheonomic constraint x - t: Cq = [0, 1], Ct = -1.
        assert!(q("holonomic_jacobian").outputs[0].is_zero());
        assert!(is_zero(&q("holonomic_time_derivative").outputs[0] + Atom::num(1)));
    }

    #[test]
    fn pendulum_emission_shares_subexpressions_and_parses() {
        crate::codegen::on_symbolica_thread(pendulum_emission);
    }

    fn pendulum_emission() {
        let d = derive(&pendulum());
        let e = emit(&d).unwrap();
        assert!(e.source.starts_with("// @generated"));
        syn::parse_file(&e.source).unwrap();
        for f in [
            "pub fn mass_matrix<T: Scalar>",
            "pub fn quadratic_velocity_forces<T: Scalar>",
            "pub fn all_quantities<T: Scalar>",
            "sin_cos()",
        ] {
            assert!(e.source.contains(f), "missing {f}");
        }
        let all = e.reports.iter().find(|r| r.name == "all_quantities").unwrap();
        assert!(
            all.after.total() < all.before.total(),
            "CSE must remove operations: {:?}",
            all
        );
        // The damper appears as an applied force on theta.
        assert!(e.source.contains("p_c"));
    }

    #[test]
    fn fnv_hash_is_stable() {
        use crate::registry::fnv1a;
        assert_eq!(fnv1a(b"bikedyn"), fnv1a(b"bikedyn"));
        assert_ne!(fnv1a(b"a"), fnv1a(b"b"));
    }
}

/// The runtime's `EffectDeclaration` literal of an applied effect.
fn effect_declaration_tokens(e: &crate::model::EffectInfo) -> TokenStream {
    use crate::effects::{Identification, LinearEquivalent};
    let (name, doc) = (&e.name, &e.doc);
    let rt = quote!(bikedyn_runtime::model);
    let opt_f64 = |x: Option<f64>| match x {
        Some(v) => {
            let l = proc_macro2::Literal::f64_suffixed(v);
            quote!(Some(#l))
        }
        None => quote!(None),
    };
    let ident = match e.identification {
        None => quote!(None),
        Some(Identification::OptOut(why)) => quote!(Some(#rt::EffectIdentification::OptOut(#why))),
        Some(Identification::Candidate(c)) => {
            let fitted = c.fitted.iter().map(|f| {
                let (sym, tied, dis, sad, shape) = (f.symbol, f.tied, f.dissipative, f.start_at_default, f.shape);
                let scale = proc_macro2::Literal::f64_suffixed(f.scale);
                let floor = opt_f64(f.floor);
                let ceiling = opt_f64(f.ceiling);
                quote!(#rt::FittedParameter {
                    symbol: #sym, tied: &[#(#tied),*], scale: #scale, dissipative: #dis, floor: #floor, ceiling: #ceiling, start_at_default: #sad, shape: #shape
                })
            });
            let held = c.held;
            let sigs = c.signatures.iter().map(|s| {
                let v = proc_macro2::Ident::new(s.variant(), proc_macro2::Span::call_site());
                quote!(#rt::Signature::#v)
            });
            let (decay, reason, own) = (c.speed_decay, c.reason, c.own_model);
            let lin = match c.linear_equivalent {
                None => quote!(None),
                Some(LinearEquivalent::DescribingFunctionDamping { torque, damping }) => {
                    quote!(Some(#rt::LinearEquivalent::DescribingFunctionDamping { torque: #torque, damping: #damping }))
                }
            };
            quote!(Some(#rt::EffectIdentification::Candidate(#rt::CandidateDeclaration {
                fitted: &[#(#fitted),*],
                held: &[#(#held),*],
                speed_decay: #decay,
                signatures: &[#(#sigs),*],
                reason: #reason,
                linear_equivalent: #lin,
                own_model: #own,
            })))
        }
    };
    quote!(#rt::EffectDeclaration { name: #name, doc: #doc, identification: #ident })
}
