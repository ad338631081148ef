//! Names in the emitted code: each temporary named by a hash of what it
//! computes, so that a model change renames only the expressions it
//! changes; literals and identifiers as tokens.

use super::dag::{Input, Node};
use crate::registry::fnv1a;
use proc_macro2::{Ident, Span, TokenStream};
use quote::{format_ident, quote};

pub(super) fn lit(x: f64) -> TokenStream {
    let l = proc_macro2::Literal::f64_suffixed(x);
    quote!(T::cst(#l))
}

pub(super) struct Names {
    pub(super) params: Vec<Ident>,
    pub(super) coords: Vec<Ident>,
    pub(super) rates: Vec<Ident>,
}

/// Content hashes of the DAG's nodes: what each computes, written with the
/// names of its inputs, children before parents (a node's children have
/// lower indices). Sums and products hash their operands as a sorted set,
/// so the hash does not depend on the order in which derivation visited
/// them.
pub(super) fn content_hashes(nodes: &[Node], names: &Names) -> Vec<u64> {
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
pub(super) fn temporary_names(nodes: &[Node], hashes: &[u64]) -> Vec<Ident> {
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

pub(super) fn ident(s: &str) -> Ident {
    Ident::new(s, Span::call_site())
}
