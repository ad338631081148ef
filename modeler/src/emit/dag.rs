//! The hash-consed DAG of one function's outputs: every derived expression
//! converted into nodes, identical subexpressions (`sin`/`cos` of the same
//! angle included) one node, with the operation counts before and after
//! sharing that the codegen report prints.

use crate::registry::EmitError;
use std::collections::HashMap;
use symbolica::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum Input {
    Param(usize),
    Coord(usize),
    Rate(usize),
    Time,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(super) enum Node {
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

pub(super) struct Dag<'a> {
    pub(super) nodes: Vec<Node>,
    pub(super) index: HashMap<Node, usize>,
    pub(super) inputs: &'a HashMap<Symbol, Input>,
    pub(super) tree_ops: OpCount,
    pub(super) function: &'static str,
}

impl<'a> Dag<'a> {
    pub(super) fn add(&mut self, n: Node) -> usize {
        if let Some(&i) = self.index.get(&n) {
            return i;
        }
        self.nodes.push(n.clone());
        self.index.insert(n, self.nodes.len() - 1);
        self.nodes.len() - 1
    }
    pub(super) fn constant(&mut self, x: f64) -> usize {
        self.add(Node::Const(x.to_bits()))
    }
    pub(super) fn unsupported(&self, what: String) -> EmitError {
        EmitError::Unsupported {
            function: self.function.to_string(),
            what,
        }
    }
    pub(super) fn number(&self, v: AtomView) -> Result<Option<f64>, EmitError> {
        if let AtomView::Num(n) = v {
            match n.get_coeff_view() {
                CoefficientView::Natural(nr, dr, ni, _) if ni == 0 => Ok(Some(nr as f64 / dr as f64)),
                _ => Err(self.unsupported(format!("the number {v}"))),
            }
        } else {
            Ok(None)
        }
    }
    pub(super) fn pow(&mut self, base: usize, n: i64) -> usize {
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
    pub(super) fn convert(&mut self, v: AtomView) -> Result<usize, EmitError> {
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

pub(super) fn count_dag(nodes: &[Node]) -> OpCount {
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
