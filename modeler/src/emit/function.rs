//! One emitted function: its outputs converted into the DAG, each node
//! written once as a `let`, and its report of operation counts.

use super::dag::{count_dag, Dag, FunctionReport, Input, Node, OpCount};
use super::names::{content_hashes, ident, lit, temporary_names, Names};
use crate::derive::{Quantity, Shape};
use crate::registry::EmitError;
use proc_macro2::TokenStream;
use quote::quote;
use std::collections::HashMap;
use symbolica::prelude::*;

/// Emit one function; returns its tokens and report.
pub(super) fn emit_function(
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
