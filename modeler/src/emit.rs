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

use crate::derive::{Derived, Quantity, Shape};
use crate::model::Role;
use crate::registry::camel;
use crate::registry::fnv1a;
pub use crate::registry::{emit_registry, EmitError};
use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};
use std::collections::HashMap;
use symbolica::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Input {
    Param(usize),
    Coord(usize),
    Rate(usize),
    Time,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
enum Node {
    Input(Input),
    Const(u64),
    Add(Vec<usize>),
    Mul(Vec<usize>),
    Neg(usize),
    Recip(usize),
    Sin(usize),
    Cos(usize),
    Sqrt(usize),
    Exp(usize),
    Acos(usize),
    Atan(usize),
}

/// Operation counts of one function.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCount {
    /// Additions, subtractions, multiplications, divisions and negations.
    pub arithmetic: usize,
    /// Calls of sin, cos, sqrt.
    pub transcendental: usize,
}
impl OpCount {
    /// Total (each transcendental call counted once).
    pub fn total(&self) -> usize {
        self.arithmetic + self.transcendental
    }
}

/// Statistics of one emitted function.
#[derive(Clone, Debug)]
pub struct FunctionReport {
    pub name: &'static str,
    /// Operations of the expression trees as derived (no sharing).
    pub before: OpCount,
    /// Operations after common-subexpression elimination.
    pub after: OpCount,
}

struct Dag<'a> {
    nodes: Vec<Node>,
    index: HashMap<Node, usize>,
    inputs: &'a HashMap<Symbol, Input>,
    tree_ops: OpCount,
    function: &'static str,
}

impl<'a> Dag<'a> {
    fn add(&mut self, n: Node) -> usize {
        if let Some(&i) = self.index.get(&n) {
            return i;
        }
        self.nodes.push(n.clone());
        self.index.insert(n, self.nodes.len() - 1);
        self.nodes.len() - 1
    }
    fn constant(&mut self, x: f64) -> usize {
        self.add(Node::Const(x.to_bits()))
    }
    fn unsupported(&self, what: String) -> EmitError {
        EmitError::Unsupported {
            function: self.function.to_string(),
            what,
        }
    }
    fn number(&self, v: AtomView) -> Result<Option<f64>, EmitError> {
        if let AtomView::Num(n) = v {
            match n.get_coeff_view() {
                CoefficientView::Natural(nr, dr, ni, _) if ni == 0 => Ok(Some(nr as f64 / dr as f64)),
                _ => Err(self.unsupported(format!("the number {v}"))),
            }
        } else {
            Ok(None)
        }
    }
    fn pow(&mut self, base: usize, n: i64) -> usize {
        let m = n.unsigned_abs() as usize;
        let p = if m == 1 {
            base
        } else {
            self.tree_ops.arithmetic += m - 1;
            self.add(Node::Mul(vec![base; m]))
        };
        if n < 0 {
            self.tree_ops.arithmetic += 1;
            self.add(Node::Recip(p))
        } else {
            p
        }
    }
    fn convert(&mut self, v: AtomView) -> Result<usize, EmitError> {
        Ok(match v {
            AtomView::Num(_) => {
                let x = self.number(v)?.unwrap_or(0.0);
                self.constant(x)
            }
            AtomView::Var(s) => {
                let input = *self
                    .inputs
                    .get(&s.get_symbol())
                    .ok_or_else(|| self.unsupported(format!("the symbol {v}")))?;
                self.add(Node::Input(input))
            }
            AtomView::Fun(f) => {
                if f.get_nargs() != 1 {
                    return Err(self.unsupported(format!("the function {v}")));
                }
                let a = self.convert(f.get(0))?;
                self.tree_ops.transcendental += 1;
                let s = f.get_symbol();
                if s == Symbol::SIN {
                    self.add(Node::Sin(a))
                } else if s == Symbol::COS {
                    self.add(Node::Cos(a))
                } else if s == Symbol::SQRT {
                    self.add(Node::Sqrt(a))
                } else if s == Symbol::EXP {
                    self.add(Node::Exp(a))
                } else if s == crate::derive::acos_symbol() {
                    self.add(Node::Acos(a))
                } else if s == crate::derive::atan_symbol() {
                    self.add(Node::Atan(a))
                } else {
                    return Err(self.unsupported(format!("the function {v}")));
                }
            }
            AtomView::Pow(p) => {
                let (b, e) = p.get_base_exp();
                // Symbolica writes exp(x) as e^x.
                if let AtomView::Var(s) = b {
                    if s.get_symbol() == Symbol::E {
                        let x = self.convert(e)?;
                        self.tree_ops.transcendental += 1;
                        return Ok(self.add(Node::Exp(x)));
                    }
                }
                let base = self.convert(b)?;
                let e = self
                    .number(e)?
                    .ok_or_else(|| self.unsupported(format!("the power {v}")))?;
                if e.fract() == 0.0 {
                    self.pow(base, e as i64)
                } else if (2.0 * e).fract() == 0.0 {
                    // x^(k/2) = sqrt(x)^k
                    self.tree_ops.transcendental += 1;
                    let r = self.add(Node::Sqrt(base));
                    self.pow(r, (2.0 * e) as i64)
                } else {
                    return Err(self.unsupported(format!("the power {v}")));
                }
            }
            AtomView::Mul(m) => {
                let mut factors = Vec::new();
                let mut coeff = 1.0;
                for f in m.iter() {
                    match self.number(f)? {
                        Some(c) => coeff *= c,
                        None => factors.push(self.convert(f)?),
                    }
                }
                factors.sort_unstable();
                if coeff != 1.0 && coeff != -1.0 {
                    factors.insert(0, self.constant(coeff));
                }
                self.tree_ops.arithmetic += factors.len().saturating_sub(1);
                let prod = if factors.len() == 1 {
                    factors[0]
                } else {
                    self.add(Node::Mul(factors))
                };
                if coeff == -1.0 {
                    self.tree_ops.arithmetic += 1;
                    self.add(Node::Neg(prod))
                } else {
                    prod
                }
            }
            AtomView::Add(a) => {
                let mut terms = Vec::new();
                for t in a.iter() {
                    terms.push(self.convert(t)?);
                }
                terms.sort_unstable();
                self.tree_ops.arithmetic += terms.len().saturating_sub(1);
                self.add(Node::Add(terms))
            }
        })
    }
}

fn count_dag(nodes: &[Node]) -> OpCount {
    let mut c = OpCount::default();
    for n in nodes {
        match n {
            Node::Add(v) | Node::Mul(v) => c.arithmetic += v.len() - 1,
            Node::Neg(_) | Node::Recip(_) => c.arithmetic += 1,
            Node::Sin(_) | Node::Cos(_) | Node::Sqrt(_) | Node::Exp(_) | Node::Acos(_) | Node::Atan(_) => {
                c.transcendental += 1
            }
            Node::Input(_) | Node::Const(_) => {}
        }
    }
    c
}

fn lit(x: f64) -> TokenStream {
    let l = proc_macro2::Literal::f64_suffixed(x);
    quote!(T::cst(#l))
}

struct Names {
    params: Vec<Ident>,
    coords: Vec<Ident>,
    rates: Vec<Ident>,
}

/// Content hashes of the DAG's nodes: what each computes, written with the
/// names of its inputs, children before parents (a node's children have
/// lower indices). Sums and products hash their operands as a sorted set,
/// so the hash does not depend on the order in which derivation visited
/// them.
fn content_hashes(nodes: &[Node], names: &Names) -> Vec<u64> {
    let mut hashes: Vec<u64> = Vec::with_capacity(nodes.len());
    for n in nodes {
        let mut text: Vec<u8> = Vec::new();
        let mut children = |tag: &str, c: &[usize], commutative: bool| {
            let mut h: Vec<u64> = c.iter().map(|&i| hashes[i]).collect();
            if commutative {
                h.sort_unstable();
            }
            text.extend_from_slice(tag.as_bytes());
            for x in h {
                text.extend_from_slice(&x.to_le_bytes());
            }
        };
        match n {
            Node::Input(Input::Param(k)) => text.extend_from_slice(names.params[*k].to_string().as_bytes()),
            Node::Input(Input::Coord(k)) => text.extend_from_slice(names.coords[*k].to_string().as_bytes()),
            Node::Input(Input::Rate(k)) => text.extend_from_slice(names.rates[*k].to_string().as_bytes()),
            Node::Input(Input::Time) => text.extend_from_slice(b"t"),
            Node::Const(b) => {
                text.extend_from_slice(b"const");
                text.extend_from_slice(&b.to_le_bytes());
            }
            Node::Add(v) => children("add", v, true),
            Node::Mul(v) => children("mul", v, true),
            Node::Neg(a) => children("neg", &[*a], false),
            Node::Recip(a) => children("recip", &[*a], false),
            Node::Sin(a) => children("sin", &[*a], false),
            Node::Cos(a) => children("cos", &[*a], false),
            Node::Sqrt(a) => children("sqrt", &[*a], false),
            Node::Exp(a) => children("exp", &[*a], false),
            Node::Acos(a) => children("acos", &[*a], false),
            Node::Atan(a) => children("atan", &[*a], false),
        }
        hashes.push(fnv1a(&text));
    }
    hashes
}

/// Names of the temporaries, from what they compute ([`content_hashes`]):
/// `t_` and ten hexadecimal digits. A model change then renames only the
/// expressions it changes, and the emitted file diffs like the change; with
/// running numbers, one new term renumbered every later temporary. A
/// collision (two expressions, one name) takes the next free name by
/// rehashing, in the order of the nodes.
fn temporary_names(nodes: &[Node], hashes: &[u64]) -> Vec<Ident> {
    let mut taken = std::collections::HashSet::new();
    hashes
        .iter()
        .zip(nodes)
        .map(|(&h, n)| {
            if matches!(n, Node::Input(_) | Node::Const(_)) {
                // Inputs and constants are written by name or value.
                return format_ident!("unused");
            }
            let mut h = h;
            loop {
                let name = format!("t_{:010x}", h & 0xff_ffff_ffff);
                if taken.insert(name.clone()) {
                    return ident(&name);
                }
                h = fnv1a(&h.to_le_bytes());
            }
        })
        .collect()
}

fn ident(s: &str) -> Ident {
    Ident::new(s, Span::call_site())
}

/// Emit one function; returns its tokens and report.
fn emit_function(
    q: &Quantity,
    inputs: &HashMap<Symbol, Input>,
    names: &Names,
) -> Result<(TokenStream, FunctionReport), EmitError> {
    let mut dag = Dag {
        nodes: Vec::new(),
        index: HashMap::new(),
        inputs,
        tree_ops: OpCount::default(),
        function: q.name,
    };
    let outs: Vec<usize> = q
        .outputs
        .iter()
        .map(|a| dag.convert(a.as_view()))
        .collect::<Result<_, _>>()?;
    let report = FunctionReport {
        name: q.name,
        before: dag.tree_ops,
        after: count_dag(&dag.nodes),
    };
    let hashes = content_hashes(&dag.nodes, names);
    let temp = temporary_names(&dag.nodes, &hashes);
    // Operands of sums and products in the order of their content hashes
    // (constants first), which, unlike the order of derivation, a model
    // change does not shuffle.
    let canonical = |v: &[usize], nodes: &[Node]| -> Vec<usize> {
        let mut v = v.to_vec();
        v.sort_by_key(|&c| (!matches!(nodes[c], Node::Const(_)), hashes[c]));
        v
    };
    let var = |i: usize, nodes: &[Node]| -> TokenStream {
        match &nodes[i] {
            Node::Input(Input::Param(k)) => {
                let n = &names.params[*k];
                quote!(#n)
            }
            Node::Input(Input::Coord(k)) => {
                let n = &names.coords[*k];
                quote!(#n)
            }
            Node::Input(Input::Rate(k)) => {
                let n = &names.rates[*k];
                quote!(#n)
            }
            Node::Input(Input::Time) => quote!(t),
            Node::Const(b) => lit(f64::from_bits(*b)),
            _ => {
                let n = &temp[i];
                quote!(#n)
            }
        }
    };
    let mut body = Vec::new();
    // Load the inputs the expressions use.
    for n in &dag.nodes {
        if let Node::Input(inp) = n {
            let stmt = match inp {
                Input::Param(k) => {
                    let n = &names.params[*k];
                    quote!(let #n = param[#k];)
                }
                Input::Coord(k) => {
                    let n = &names.coords[*k];
                    quote!(let #n = p[#k];)
                }
                Input::Rate(k) => {
                    let n = &names.rates[*k];
                    quote!(let #n = dp[#k];)
                }
                Input::Time => quote!(),
            };
            body.push(stmt);
        }
    }
    // Pair sin(a) and cos(a) into one sin_cos call, emitted at the first of the two.
    let mut partner: HashMap<usize, (usize, usize)> = HashMap::new();
    {
        let mut sin_of = HashMap::new();
        let mut cos_of = HashMap::new();
        for (i, n) in dag.nodes.iter().enumerate() {
            match n {
                Node::Sin(a) => {
                    sin_of.insert(*a, i);
                }
                Node::Cos(a) => {
                    cos_of.insert(*a, i);
                }
                _ => {}
            }
        }
        for (a, &si) in &sin_of {
            if let Some(&ci) = cos_of.get(a) {
                partner.insert(si.min(ci), (si, ci));
                partner.insert(si.max(ci), (usize::MAX, usize::MAX));
            }
        }
    }
    for (i, n) in dag.nodes.iter().enumerate() {
        let t = &temp[i];
        if let Some(&(si, ci)) = partner.get(&i) {
            if si == usize::MAX {
                continue;
            }
            let Node::Sin(a) = dag.nodes[si] else {
                unreachable!("paired node is a sine")
            };
            let (s_id, c_id, a) = (&temp[si], &temp[ci], var(a, &dag.nodes));
            body.push(quote!(let (#s_id, #c_id): (T, T) = #a.sin_cos();));
            continue;
        }
        let e = match n {
            Node::Input(_) | Node::Const(_) => continue,
            Node::Add(v) => {
                let v = canonical(v, &dag.nodes);
                let mut it = v.iter().map(|&c| (c, matches!(dag.nodes[c], Node::Neg(_))));
                let mut pos: Vec<TokenStream> = Vec::new();
                let mut neg: Vec<TokenStream> = Vec::new();
                for (c, is_neg) in &mut it {
                    if is_neg {
                        if let Node::Neg(inner) = dag.nodes[c] {
                            neg.push(var(inner, &dag.nodes));
                        }
                    } else {
                        pos.push(var(c, &dag.nodes));
                    }
                }
                let first = if pos.is_empty() {
                    let f = neg.remove(0);
                    quote!(-#f)
                } else {
                    let f = pos.remove(0);
                    quote!(#f)
                };
                quote!(#first #(+ #pos)* #(- #neg)*)
            }
            Node::Mul(v) => {
                let f: Vec<_> = canonical(v, &dag.nodes).iter().map(|&c| var(c, &dag.nodes)).collect();
                let (h, rest) = f.split_first().expect("products have factors");
                quote!(#h #(* #rest)*)
            }
            Node::Neg(a) => {
                let a = var(*a, &dag.nodes);
                quote!(-#a)
            }
            Node::Recip(a) => {
                let a = var(*a, &dag.nodes);
                quote!(T::one() / #a)
            }
            Node::Sin(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.sin())
            }
            Node::Cos(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.cos())
            }
            Node::Sqrt(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.sqrt())
            }
            Node::Exp(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.exp())
            }
            Node::Acos(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.acos())
            }
            Node::Atan(a) => {
                let a = var(*a, &dag.nodes);
                quote!(#a.atan())
            }
        };
        body.push(quote!(let #t: T = #e;));
    }
    let name = ident(q.name);
    let doc = q.doc;
    // The declared inputs are the signature (that of `MultibodyModel`).
    let t_arg = if q.inputs.time { quote!(t: T,) } else { quote!() };
    let dp_arg = if q.inputs.rates { quote!(dp: &[T],) } else { quote!() };
    let tokens = match q.shape {
        Shape::Scalar => {
            let r = var(outs[0], &dag.nodes);
            let args = quote!(param: &[T], #t_arg p: &[T], #dp_arg);
            quote! {
                #[doc = #doc]
                #[allow(unused_variables, non_snake_case, clippy::all)]
                pub fn #name<T: Scalar>(#args) -> T {
                    #(#body)*
                    #r
                }
            }
        }
        Shape::Buffer { .. } => {
            let n = outs.len();
            let assigns = outs.iter().enumerate().map(|(k, &o)| {
                let v = var(o, &dag.nodes);
                quote!(out[#k] = #v;)
            });
            let args = quote!(param: &[T], #t_arg p: &[T], #dp_arg out: &mut [T]);
            quote! {
                #[doc = #doc]
                #[allow(unused_variables, non_snake_case, clippy::all)]
                pub fn #name<T: Scalar>(#args) {
                    debug_assert_eq!(out.len(), #n);
                    #(#body)*
                    #(#assigns)*
                }
            }
        }
    };
    Ok((tokens, report))
}

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
