//! A small expression language for declaring models.
//!
//! Models are data: they are written with these expressions, validated, and
//! only then handed to the derivation stage (Symbolica). Keeping our own AST
//! here means a model file never touches the CAS, and validation can list every
//! name a model uses.

use std::collections::BTreeSet;
use std::ops::{Add, Div, Mul, Neg, Sub};

// The handles of a model's frames, points and bodies are declared here, with
// the expressions that refer to them, so that this module depends on no
// other; `crate::model` names them too.

/// Axis of an elementary rotation, in the frame being rotated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// Index 0, 1, 2.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// Handle of a frame. [`GROUND`] is the inertial frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameId(pub usize);
/// The inertial (ground) frame.
pub const GROUND: FrameId = FrameId(0);
/// Handle of a point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointId(pub usize);
/// Handle of a body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BodyId(pub usize);

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
    /// Exponential.
    Exp(Box<Expr>),
    /// Inverse cosine (principal value).
    Acos(Box<Expr>),
    /// Inverse tangent (principal value).
    Atan(Box<Expr>),
    /// A global component (0 = X, 1 = Y, 2 = Z) of a declared point's
    /// position, resolved by the derivation from the point's declaration.
    Position(usize, u8),
    /// A global component of a declared point's velocity (the time rate of
    /// its position as declared: for a geometric point such as a wheel's
    /// contact, its travel velocity).
    Velocity(usize, u8),
    /// A global component of a frame's unit axis: `FrameAxis(frame, axis,
    /// component)` is component `component` of the frame's `axis` in ground
    /// axes (a direction cosine).
    FrameAxis(usize, u8, u8),
    /// A global component of a frame's angular velocity.
    AngularVelocity(usize, u8),
    /// `MaterialVelocity(body, point, k)`: global component `k` of the
    /// velocity of the material point of `body` that coincides with `point`
    /// (e.g. the rim point at a wheel's contact: zero when rolling without slip).
    MaterialVelocity(usize, usize, u8),
    /// An extra first-order state of the model (e.g. a lagged tyre force),
    /// by name; its rate is declared with `ModelBuilder::state`.
    State(String),
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
/// The exact value of a finite `f64` as a rational constant (its binary
/// expansion; e.g. `exact(FRAC_PI_2)` emits back to exactly `FRAC_PI_2`).
pub fn exact(x: f64) -> Expr {
    assert!(x.is_finite(), "exact() needs a finite number");
    if x == 0.0 {
        return num(0);
    }
    let (mut m, mut e) = {
        let bits = x.abs().to_bits();
        let exp = ((bits >> 52) & 0x7ff) as i64;
        let frac = bits & ((1u64 << 52) - 1);
        if exp == 0 {
            (frac as i64, -1074)
        } else {
            ((frac | (1u64 << 52)) as i64, exp - 1075)
        }
    };
    while m % 2 == 0 && e < 0 {
        m /= 2;
        e += 1;
    }
    let sign = if x < 0.0 { -1 } else { 1 };
    assert!((-62..=10).contains(&e), "exact(): {x} is out of range");
    if e >= 0 {
        Expr::Num(sign * m * (1i64 << e), 1)
    } else {
        Expr::Num(sign * m, 1i64 << (-e))
    }
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
    /// Exponential.
    pub fn exp(self) -> Expr {
        Expr::Exp(Box::new(self))
    }
    /// Inverse cosine.
    pub fn acos(self) -> Expr {
        Expr::Acos(Box::new(self))
    }
    /// Inverse tangent.
    pub fn atan(self) -> Expr {
        Expr::Atan(Box::new(self))
    }
    /// Hyperbolic tangent, written `1 - 2 / (exp(2 x) + 1)` so that generated
    /// code needs only `exp` (and stays finite for large |x|).
    pub fn tanh(self) -> Expr {
        num(1) - num(2) / ((num(2) * self).exp() + num(1))
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
            Expr::Pow(e, _)
            | Expr::Sin(e)
            | Expr::Cos(e)
            | Expr::Sqrt(e)
            | Expr::Exp(e)
            | Expr::Acos(e)
            | Expr::Atan(e) => e.names(out),
            // Kinematic leaves depend on every coordinate (and rate) their
            // point or frame does; the derivation checks them.
            Expr::Position(..) | Expr::FrameAxis(..) => {
                out.insert(("kinematics", String::new()));
            }
            Expr::Velocity(..) | Expr::AngularVelocity(..) | Expr::MaterialVelocity(..) => {
                out.insert(("kinematic rate", String::new()));
            }
            Expr::State(n) => {
                out.insert(("state", n.clone()));
            }
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

/// Dot product of two 3-vectors.
pub fn dot3(a: &Vec3, b: &Vec3) -> Expr {
    a[0].clone() * b[0].clone() + a[1].clone() * b[1].clone() + a[2].clone() * b[2].clone()
}

/// Global position of a point, as expressions.
pub fn position(p: PointId) -> Vec3 {
    [0u8, 1, 2].map(|k| Expr::Position(p.0, k))
}

/// Global velocity of a point (time rate of its declared position).
pub fn velocity(p: PointId) -> Vec3 {
    [0u8, 1, 2].map(|k| Expr::Velocity(p.0, k))
}

/// Unit axis `axis` of `frame`, in ground components.
pub fn frame_axis(frame: FrameId, axis: Axis) -> Vec3 {
    [0u8, 1, 2].map(|k| Expr::FrameAxis(frame.0, axis.index() as u8, k))
}

/// Angular velocity of `frame`, in ground components.
pub fn angular_velocity(frame: FrameId) -> Vec3 {
    [0u8, 1, 2].map(|k| Expr::AngularVelocity(frame.0, k))
}

/// `sqrt(x^2 + eps^2)`: a magnitude that is smooth at zero (so that exact
/// derivatives exist at rest, e.g. in a linearization at zero speed).
pub fn smooth_norm(v: &Vec3, eps: Expr) -> Expr {
    (dot3(v, v) + eps.powi(2)).sqrt()
}

/// Velocity (ground components) of the material point of `body` at `point`.
pub fn material_velocity(body: BodyId, point: PointId) -> Vec3 {
    [0u8, 1, 2].map(|k| Expr::MaterialVelocity(body.0, point.0, k))
}

/// Cross product of two 3-vectors.
pub fn cross3(a: &Vec3, b: &Vec3) -> Vec3 {
    [
        a[1].clone() * b[2].clone() - a[2].clone() * b[1].clone(),
        a[2].clone() * b[0].clone() - a[0].clone() * b[2].clone(),
        a[0].clone() * b[1].clone() - a[1].clone() * b[0].clone(),
    ]
}
