//! A small expression language for declaring models.
//!
//! Models are data: they are written with these expressions, validated, and
//! only then handed to the derivation stage (Symbolica). Keeping our own AST
//! here means a model file never touches the CAS, and validation can list every
//! name a model uses.

use std::collections::BTreeSet;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A scalar expression in parameters, coordinates, their rates and time.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// Exact rational number `num / den`.
    Num(i64, i64),
    /// A model parameter, by name.
    Param(String),
    /// A generalized coordinate, by name.
    Coord(String),
    /// The time derivative of a coordinate, by the coordinate's name.
    Rate(String),
    /// Time `t` (s).
    Time,
    /// Sum.
    Add(Vec<Expr>),
    /// Product.
    Mul(Vec<Expr>),
    /// Integer power.
    Pow(Box<Expr>, i32),
    /// Sine.
    Sin(Box<Expr>),
    /// Cosine.
    Cos(Box<Expr>),
    /// Square root.
    Sqrt(Box<Expr>),
}

/// A parameter.
pub fn param(name: &str) -> Expr {
    Expr::Param(name.to_string())
}
/// A coordinate.
pub fn coord(name: &str) -> Expr {
    Expr::Coord(name.to_string())
}
/// The rate (time derivative) of a coordinate.
pub fn rate(name: &str) -> Expr {
    Expr::Rate(name.to_string())
}
/// Time.
pub fn time() -> Expr {
    Expr::Time
}
/// An integer constant.
pub fn num(n: i64) -> Expr {
    Expr::Num(n, 1)
}
/// A rational constant `n / d`.
pub fn ratio(n: i64, d: i64) -> Expr {
    Expr::Num(n, d)
}

impl Expr {
    /// Sine of this expression.
    pub fn sin(self) -> Expr {
        Expr::Sin(Box::new(self))
    }
    /// Cosine of this expression.
    pub fn cos(self) -> Expr {
        Expr::Cos(Box::new(self))
    }
    /// Square root of this expression.
    pub fn sqrt(self) -> Expr {
        Expr::Sqrt(Box::new(self))
    }
    /// Integer power.
    pub fn powi(self, n: i32) -> Expr {
        Expr::Pow(Box::new(self), n)
    }
    /// True for the exact constant zero.
    pub fn is_zero(&self) -> bool {
        matches!(self, Expr::Num(0, _))
    }

    /// Visit every leaf name: `(kind, name)` with kind "parameter",
    /// "coordinate", "rate" or "time".
    pub fn names(&self, out: &mut BTreeSet<(&'static str, String)>) {
        match self {
            Expr::Num(..) => {}
            Expr::Param(n) => {
                out.insert(("parameter", n.clone()));
            }
            Expr::Coord(n) => {
                out.insert(("coordinate", n.clone()));
            }
            Expr::Rate(n) => {
                out.insert(("rate", n.clone()));
            }
            Expr::Time => {
                out.insert(("time", String::new()));
            }
            Expr::Add(v) | Expr::Mul(v) => v.iter().for_each(|e| e.names(out)),
            Expr::Pow(e, _) | Expr::Sin(e) | Expr::Cos(e) | Expr::Sqrt(e) => e.names(out),
        }
    }
}

impl From<i64> for Expr {
    fn from(n: i64) -> Expr {
        num(n)
    }
}

impl Add for Expr {
    type Output = Expr;
    fn add(self, o: Expr) -> Expr {
        match (self, o) {
            (a, b) if b.is_zero() => a,
            (a, b) if a.is_zero() => b,
            (Expr::Add(mut v), b) => {
                v.push(b);
                Expr::Add(v)
            }
            (a, b) => Expr::Add(vec![a, b]),
        }
    }
}
impl Sub for Expr {
    type Output = Expr;
    fn sub(self, o: Expr) -> Expr {
        self + (-o)
    }
}
impl Mul for Expr {
    type Output = Expr;
    fn mul(self, o: Expr) -> Expr {
        match (self, o) {
            (a, _) if a.is_zero() => num(0),
            (_, b) if b.is_zero() => num(0),
            (Expr::Num(1, 1), b) => b,
            (a, Expr::Num(1, 1)) => a,
            (Expr::Mul(mut v), b) => {
                v.push(b);
                Expr::Mul(v)
            }
            (a, b) => Expr::Mul(vec![a, b]),
        }
    }
}
impl Div for Expr {
    type Output = Expr;
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn div(self, o: Expr) -> Expr {
        self * o.powi(-1)
    }
}
impl Neg for Expr {
    type Output = Expr;
    fn neg(self) -> Expr {
        match self {
            Expr::Num(n, d) => Expr::Num(-n, d),
            e => Expr::Num(-1, 1) * e,
        }
    }
}

/// A 3-vector of expressions, components in some frame.
pub type Vec3 = [Expr; 3];

/// Shorthand for a 3-vector.
pub fn vec3(x: Expr, y: Expr, z: Expr) -> Vec3 {
    [x, y, z]
}

/// A symmetric 3x3 tensor, components in some frame.
pub type Tensor3 = [[Expr; 3]; 3];

/// Inertia tensor with the `xz` product only (bodies symmetric about their
/// x-z plane, as every body of a bicycle in the Whipple model).
pub fn inertia_xz(ixx: Expr, iyy: Expr, izz: Expr, ixz: Expr) -> Tensor3 {
    [[ixx, num(0), ixz.clone()], [num(0), iyy, num(0)], [ixz, num(0), izz]]
}

/// Inertia tensor of a body of revolution about its y axis (a wheel):
/// `diag(i_diametral, i_axial, i_diametral)`.
pub fn inertia_wheel(i_diametral: Expr, i_axial: Expr) -> Tensor3 {
    [
        [i_diametral.clone(), num(0), num(0)],
        [num(0), i_axial, num(0)],
        [num(0), num(0), i_diametral],
    ]
}
