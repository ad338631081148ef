//! Symbolic derivation (Symbolica): from a validated [`Model`] to the named
//! quantities of Lagrange's equations of the first kind, as in the thesis's
//! `Bicicleta.m`: mass matrix (eq. 32), quadratic-velocity forces (eq. 36),
//! gravity forces (eq. 38), applied forces, holonomic residuals and their
//! derivatives, the nonholonomic matrix and its convective term, energies and
//! point positions. Every derivative here is exact (symbolic).

use crate::expr::Expr;
use crate::model::{Axis, Force, Holonomic, Model, Nonholonomic, Role, GROUND};
use std::collections::HashMap;
use std::time::{Duration, Instant};
use symbolica::prelude::*;

/// Which inputs a generated function takes besides the parameters: this is
/// its signature, which must match the corresponding `MultibodyModel` method.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Inputs {
    pub time: bool,
    pub coordinates: bool,
    pub rates: bool,
}

/// How the outputs are returned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Written into `out` (row-major `rows x cols`).
    Buffer { rows: usize, cols: usize },
    /// Returned as a scalar.
    Scalar,
}

/// One derived quantity, to become one generated function.
#[derive(Clone, Debug)]
pub struct Quantity {
    /// Function name (e.g. `mass_matrix`).
    pub name: &'static str,
    /// One-line description (becomes the doc comment).
    pub doc: &'static str,
    pub inputs: Inputs,
    pub shape: Shape,
    /// Output expressions (row-major).
    pub outputs: Vec<Atom>,
    /// Included in `all_quantities` (the shared evaluation of everything the
    /// equations of motion need).
    pub shared: bool,
}

/// The symbols standing for the inputs of generated code.
pub struct Symbols {
    pub params: Vec<Symbol>,
    /// Extra first-order states; generated code reads them after the
    /// parameters, in the `param` slice.
    pub states: Vec<Symbol>,
    pub coords: Vec<Symbol>,
    pub rates: Vec<Symbol>,
    pub time: Symbol,
}

/// Everything derived for one model.
pub struct Derived {
    pub model: Model,
    pub symbols: Symbols,
    pub quantities: Vec<Quantity>,
    /// Wall time of the symbolic derivation.
    pub elapsed: Duration,
}

/// Inverse cosine and tangent as opaque functions: they appear only in
/// closed-form upright values, which are never differentiated; the emitter
/// maps them to `Scalar::acos` and `Scalar::atan`.
pub fn acos_symbol() -> Symbol {
    symbol!("bikedyn::acos")
}
/// See [`acos_symbol`].
pub fn atan_symbol() -> Symbol {
    symbol!("bikedyn::atan")
}

type V3 = [Atom; 3];
type M3 = [[Atom; 3]; 3];

fn zero() -> Atom {
    Atom::num(0)
}

fn mat_mul(a: &M3, b: &M3) -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).fold(zero(), |s, k| s + &a[i][k] * &b[k][j])))
}
fn mat_vec(a: &M3, v: &V3) -> V3 {
    std::array::from_fn(|i| (0..3).fold(zero(), |s, k| s + &a[i][k] * &v[k]))
}
fn mat_t_vec(a: &M3, v: &V3) -> V3 {
    std::array::from_fn(|i| (0..3).fold(zero(), |s, k| s + &a[k][i] * &v[k]))
}
fn dot(a: &V3, b: &V3) -> Atom {
    (0..3).fold(zero(), |s, k| s + &a[k] * &b[k])
}
fn cross(a: &V3, b: &V3) -> V3 {
    [
        &a[1] * &b[2] - &a[2] * &b[1],
        &a[2] * &b[0] - &a[0] * &b[2],
        &a[0] * &b[1] - &a[1] * &b[0],
    ]
}
fn identity() -> M3 {
    std::array::from_fn(|i| std::array::from_fn(|j| Atom::num(if i == j { 1 } else { 0 })))
}

/// Elementary rotation matrix about `axis` by `angle` (right-handed; the
/// thesis's A_theta, A_psi, A_gam, ...).
fn rotation(axis: Axis, angle: &Atom) -> M3 {
    let c = Symbol::COS.call((angle,));
    let s = Symbol::SIN.call((angle,));
    let (o, l) = (zero(), Atom::num(1));
    match axis {
        Axis::X => [[l, o.clone(), o.clone()], [o.clone(), c.clone(), -&s], [o, s, c]],
        Axis::Y => [
            [c.clone(), o.clone(), s.clone()],
            [o.clone(), l, o.clone()],
            [-&s, o, c],
        ],
        Axis::Z => [[c.clone(), -&s, o.clone()], [s, c, o.clone()], [o.clone(), o, l]],
    }
}

struct Deriver<'a> {
    m: &'a Model,
    sym: Symbols,
    param_index: HashMap<&'a str, usize>,
    coord_index: HashMap<&'a str, usize>,
    state_index: HashMap<&'a str, usize>,
    /// Kinematics, filled once frames and points are derived (geometry
    /// itself never refers to them: validation forbids it).
    rot: Vec<M3>,
    omega_global: Vec<V3>,
    points: Vec<V3>,
}

impl<'a> Deriver<'a> {
    fn atom(&self, e: &Expr) -> Atom {
        match e {
            Expr::Num(n, d) => Atom::num(*n) / Atom::num(*d),
            Expr::Param(n) => Atom::var(self.sym.params[self.param_index[n.as_str()]]),
            Expr::Coord(n) => Atom::var(self.sym.coords[self.coord_index[n.as_str()]]),
            Expr::Rate(n) => Atom::var(self.sym.rates[self.coord_index[n.as_str()]]),
            Expr::Time => Atom::var(self.sym.time),
            Expr::Add(v) => v.iter().fold(zero(), |s, e| s + self.atom(e)),
            Expr::Mul(v) => v.iter().fold(Atom::num(1), |s, e| s * self.atom(e)),
            Expr::Pow(b, n) => self.atom(b).pow(Atom::num(*n as i64)),
            Expr::Sin(a) => Symbol::SIN.call((&self.atom(a),)),
            Expr::Cos(a) => Symbol::COS.call((&self.atom(a),)),
            Expr::Sqrt(a) => Symbol::SQRT.call((&self.atom(a),)),
            Expr::Exp(a) => Symbol::EXP.call((&self.atom(a),)),
            Expr::Acos(a) => acos_symbol().call((&self.atom(a),)),
            Expr::Atan(a) => atan_symbol().call((&self.atom(a),)),
            Expr::Position(p, k) => self.points[*p][*k as usize].clone(),
            Expr::Velocity(p, k) => self.time_rate(&self.points[*p][*k as usize]),
            Expr::FrameAxis(f, axis, k) => self.rot[*f][*k as usize][*axis as usize].clone(),
            Expr::AngularVelocity(f, k) => self.omega_global[*f][*k as usize].clone(),
            Expr::MaterialVelocity(b, p, k) => self.material_velocity(*b, *p)[*k as usize].clone(),
            Expr::State(n) => Atom::var(self.sym.states[self.state_index[n.as_str()]]),
        }
    }
    /// Velocity of the material point of body `b` at point `p`:
    /// `v_G + w x (r_P - r_G)`.
    fn material_velocity(&self, b: usize, p: usize) -> V3 {
        let body = &self.m.bodies[b];
        let rg = &self.points[body.mass_centre.0];
        let vg: V3 = std::array::from_fn(|i| self.time_rate(&rg[i]));
        let rel: V3 = std::array::from_fn(|i| &self.points[p][i] - &rg[i]);
        let wxr = cross(&self.omega_global[body.frame.0], &rel);
        std::array::from_fn(|i| &vg[i] + &wxr[i])
    }
    fn vec(&self, v: &[Expr; 3]) -> V3 {
        std::array::from_fn(|i| self.atom(&v[i]))
    }

    /// Total time derivative of an expression in (t, q): sum dE/dq_j q'_j + dE/dt.
    fn time_rate(&self, e: &Atom) -> Atom {
        let mut s = e.derivative(self.sym.time);
        for (j, q) in self.sym.coords.iter().enumerate() {
            s += e.derivative(*q) * Atom::var(self.sym.rates[j]);
        }
        s
    }
}

/// Derive every quantity of a model.
pub fn derive(model: &Model) -> Derived {
    let start = Instant::now();
    let ns = &model.name;
    let mk = |kind: &str, n: &str| symbol!(&format!("bikedyn_{ns}::{kind}_{n}"));
    let sym = Symbols {
        params: model.parameters.iter().map(|p| mk("p", &p.name)).collect(),
        states: model.states.iter().map(|p| mk("z", &p.name)).collect(),
        coords: model.coordinates.iter().map(|c| mk("q", &c.name)).collect(),
        rates: model.coordinates.iter().map(|c| mk("dq", &c.name)).collect(),
        time: mk("t", "time"),
    };
    let d = Deriver {
        m: model,
        param_index: model
            .parameters
            .iter()
            .enumerate()
            .map(|(i, p)| (p.name.as_str(), i))
            .collect(),
        coord_index: model
            .coordinates
            .iter()
            .enumerate()
            .map(|(i, p)| (p.name.as_str(), i))
            .collect(),
        state_index: model
            .states
            .iter()
            .enumerate()
            .map(|(i, p)| (p.name.as_str(), i))
            .collect(),
        sym,
        rot: Vec::new(),
        omega_global: Vec::new(),
        points: Vec::new(),
    };
    let mut d = d;
    let nq = model.coordinates.len();
    let (coord_syms, rate_syms) = (d.sym.coords.clone(), d.sym.rates.clone());
    let q_at = |j: usize| coord_syms[j];
    let dq = |j: usize| Atom::var(rate_syms[j]);

    // Kinematics: frame rotation matrices (global) and body-axis angular velocities.
    let mut rot: Vec<M3> = Vec::with_capacity(d.m.frames.len());
    let mut omega_local: Vec<V3> = Vec::with_capacity(d.m.frames.len());
    for (fi, f) in d.m.frames.iter().enumerate() {
        if fi == GROUND.0 {
            rot.push(identity());
            omega_local.push([zero(), zero(), zero()]);
            continue;
        }
        let mut a = rot[f.parent.0].clone();
        let mut w = omega_local[f.parent.0].clone();
        for (axis, angle) in &f.rotations {
            let angle = d.atom(angle);
            let r = rotation(*axis, &angle);
            a = mat_mul(&a, &r);
            // Angular velocity in the new axes: R^T w_prev + e_axis * d(angle)/dt.
            w = mat_t_vec(&r, &w);
            let k = axis.index();
            w[k] = &w[k] + d.time_rate(&angle);
        }
        rot.push(a);
        omega_local.push(w);
    }
    let mut points: Vec<V3> = Vec::with_capacity(d.m.points.len());
    for p in &d.m.points {
        let mut r = match p.base {
            Some(b) => points[b.0].clone(),
            None => [zero(), zero(), zero()],
        };
        for (f, v) in &p.offsets {
            let g = mat_vec(&rot[f.0], &d.vec(v));
            r = std::array::from_fn(|i| &r[i] + &g[i]);
        }
        points.push(r);
    }
    d.omega_global = rot.iter().zip(&omega_local).map(|(a, w)| mat_vec(a, w)).collect();
    d.rot = rot.clone();
    d.points = points.clone();
    // Jacobians H_i = dRG_i/dp (3 x nq) and Gl_i = d(omega_local)/dp' (3 x nq).
    let jac = |v: &V3, s: &dyn Fn(usize) -> Symbol| -> Vec<V3> {
        (0..nq)
            .map(|j| std::array::from_fn(|i| v[i].derivative(s(j))))
            .collect()
    };
    let body_h: Vec<Vec<V3>> =
        d.m.bodies
            .iter()
            .map(|b| jac(&points[b.mass_centre.0], &|j| q_at(j)))
            .collect();
    let body_g: Vec<Vec<V3>> =
        d.m.bodies
            .iter()
            .map(|b| jac(&omega_local[b.frame.0], &|j| d.sym.rates[j]))
            .collect();
    let masses: Vec<Atom> = d.m.bodies.iter().map(|b| d.atom(&b.mass)).collect();
    let inertias: Vec<M3> =
        d.m.bodies
            .iter()
            .map(|b| std::array::from_fn(|i| std::array::from_fn(|j| d.atom(&b.inertia[i][j]))))
            .collect();

    // Mass matrix, eq. 32: M = sum m H^T H + Gl^T I Gl.
    let mut mass = vec![zero(); nq * nq];
    for a in 0..nq {
        for b in a..nq {
            let mut s = zero();
            for i in 0..d.m.bodies.len() {
                s += &masses[i] * dot(&body_h[i][a], &body_h[i][b]);
                s += dot(&body_g[i][a], &mat_vec(&inertias[i], &body_g[i][b]));
            }
            mass[a * nq + b] = s.clone();
            mass[b * nq + a] = s;
        }
    }
    // Kinetic energy T = 1/2 sum (m v.v + w.I w) and quadratic-velocity
    // forces. Eq. 36, Qv = -d(M p')/dp p' + dT/dp, is evaluated in its
    // equivalent body-level form (Lagrange's equations applied body by body):
    //   Qv = -sum_i [ m_i H_i^T (dH_i/dt p') + Gl_i^T (I_i (dGl_i/dt p') + w_i x I_i w_i) ],
    // with dH/dt p' = sum_j d(H p')/dp_j p'_j; it has far fewer operations.
    // `bikedyn verify` checks Qv against eq. 36 by finite differences.
    let rate_of = |v: &Atom| (0..nq).fold(zero(), |s, j| s + v.derivative(q_at(j)) * dq(j));
    let mut kinetic = zero();
    let mut qv = vec![zero(); nq];
    for (i, b) in d.m.bodies.iter().enumerate() {
        let vel: V3 = std::array::from_fn(|k| (0..nq).fold(zero(), |s, j| s + &body_h[i][j][k] * dq(j)));
        let w = &omega_local[b.frame.0];
        let iw = mat_vec(&inertias[i], w);
        kinetic += (&masses[i] * dot(&vel, &vel) + dot(w, &iw)) / Atom::num(2);
        let acc: V3 = std::array::from_fn(|k| rate_of(&vel[k]));
        let alpha: V3 = std::array::from_fn(|k| rate_of(&w[k]));
        let ia = mat_vec(&inertias[i], &alpha);
        let gyro = cross(w, &iw);
        let torque: V3 = std::array::from_fn(|k| &ia[k] + &gyro[k]);
        for a in 0..nq {
            qv[a] = &qv[a] - &masses[i] * dot(&body_h[i][a], &acc) - dot(&body_g[i][a], &torque);
        }
    }
    // Gravity, eq. 38: Qgrav = sum H^T [0 0 -m g]; potential V = sum m g z.
    let (gravity, potential) = match &d.m.gravity {
        Some((g, up)) => {
            let g = Atom::var(d.sym.params[d.param_index[g.as_str()]]);
            let k = up.index();
            let pot = (0..d.m.bodies.len()).fold(zero(), |s, i| {
                s + &masses[i] * &g * &points[d.m.bodies[i].mass_centre.0][k]
            });
            let qg = (0..nq)
                .map(|a| (0..d.m.bodies.len()).fold(zero(), |s, i| s - &masses[i] * &g * &body_h[i][a][k]))
                .collect();
            (qg, pot)
        }
        None => (vec![zero(); nq], zero()),
    };
    // Applied forces, one generalized-force vector per declared force
    // (virtual work), and their sum.
    let mut applied = vec![zero(); nq];
    let mut force_terms = Vec::with_capacity(d.m.forces.len() * nq);
    for f in &d.m.forces {
        let mut q = vec![zero(); nq];
        match &f.force {
            Force::Generalized { coordinate, expr, .. } => {
                q[d.coord_index[coordinate.as_str()]] = d.atom(expr);
            }
            Force::AtMassCentre { body, frame, force, .. } => {
                let fg = mat_vec(&rot[frame.0], &d.vec(force));
                for a in 0..nq {
                    q[a] = dot(&body_h[body.0][a], &fg);
                }
            }
            Force::AtPoint { point, force, .. } => {
                let fg = d.vec(force);
                let hp = jac(&points[point.0], &|j| q_at(j));
                for a in 0..nq {
                    q[a] = dot(&hp[a], &fg);
                }
            }
            Force::OnBodyAtPoint { body, point, force, .. } => {
                let fg = d.vec(force);
                let vm = d.material_velocity(body.0, point.0);
                let jm = jac(&vm, &|j| d.sym.rates[j]);
                for a in 0..nq {
                    q[a] = dot(&jm[a], &fg);
                }
            }
            Force::Torque { body, torque, .. } => {
                let tg = d.vec(torque);
                let gw = jac(&d.omega_global[d.m.bodies[body.0].frame.0], &|j| d.sym.rates[j]);
                for a in 0..nq {
                    q[a] = dot(&gw[a], &tg);
                }
            }
        }
        for a in 0..nq {
            applied[a] = &applied[a] + &q[a];
        }
        force_terms.extend(q);
    }
    // The upright configuration: closed-form values where the model gives
    // them, the coordinate's own value (from `p`) elsewhere.
    let upright: Vec<Atom> =
        d.m.coordinates
            .iter()
            .enumerate()
            .map(|(j, c)| match &c.upright {
                Some(e) => d.atom(e),
                None => Atom::var(coord_syms[j]),
            })
            .collect();
    let state_rates: Vec<Atom> = d.m.states.iter().map(|st| d.atom(&st.rate)).collect();
    let forward_speed = d.m.forward_speed.as_ref().map(|e| d.atom(e)).unwrap_or_else(zero);
    // Holonomic constraints: Res, Cq, Ct, dCqdp = d(Cq p')/dp p'.
    let res: Vec<Atom> =
        d.m.holonomic
            .iter()
            .map(|h| match h {
                Holonomic::Residual { expr, .. } => d.atom(expr),
                Holonomic::PointComponent { point, axis, .. } => points[point.0][axis.index()].clone(),
                Holonomic::PointComponentStationary {
                    point,
                    axis,
                    coordinate,
                    ..
                } => points[point.0][axis.index()].derivative(q_at(d.coord_index[coordinate.as_str()])),
            })
            .collect();
    let nh = res.len();
    let cq: Vec<Atom> = (0..nh)
        .flat_map(|i| (0..nq).map(|j| res[i].derivative(q_at(j))).collect::<Vec<_>>())
        .collect();
    let ct: Vec<Atom> = res.iter().map(|r| r.derivative(d.sym.time)).collect();
    let convective = |rows: &[Atom], n: usize| -> Vec<Atom> {
        (0..n)
            .map(|i| {
                let bdq = (0..nq).fold(zero(), |s, k| s + &rows[i * nq + k] * dq(k));
                (0..nq).fold(zero(), |s, j| s + bdq.derivative(q_at(j)) * dq(j))
            })
            .collect()
    };
    let dcqdp = convective(&cq, nh);
    // Nonholonomic constraints: velocities, B = d(vel)/dp', dBdp = d(B p')/dp p'.
    let vel: Vec<Atom> = d
        .m
        .nonholonomic
        .iter()
        .map(|n| match n {
            Nonholonomic::ContactVelocity { body, point, axis, .. } => {
                let b = &d.m.bodies[body.0];
                let rg = &points[b.mass_centre.0];
                let vg: V3 = std::array::from_fn(|i| (0..nq).fold(zero(), |s, j| s + &body_h[body.0][j][i] * dq(j)));
                let w = mat_vec(&rot[b.frame.0], &omega_local[b.frame.0]);
                let rel: V3 = std::array::from_fn(|i| &points[point.0][i] - &rg[i]);
                let wxr = cross(&w, &rel);
                &vg[axis.index()] + &wxr[axis.index()]
            }
            Nonholonomic::Linear { expr, .. } => d.atom(expr),
        })
        .collect();
    let nnh = vel.len();
    let bmat: Vec<Atom> = (0..nnh)
        .flat_map(|i| (0..nq).map(|j| vel[i].derivative(d.sym.rates[j])).collect::<Vec<_>>())
        .collect();
    let dbdp: Vec<Atom> = vel.iter().map(rate_of).collect();
    let poi: Vec<Atom> =
        d.m.points_of_interest
            .iter()
            .flat_map(|p| points[p.0].clone())
            .collect();

    // The velocity terms of the reduced equations (Qv + Qext, and the
    // convective terms gamma that give F) with their first derivatives, for
    // the exact linearization about upright straight running: the runtime
    // applies the chain rule through the solved coordinates and velocities
    // in f64, instead of evaluating these, the costliest functions, in dual
    // numbers. Only the independent and dependent coordinates move with the
    // independent ones; every rate does.
    let moving: Vec<usize> = [Role::Independent, Role::Dependent]
        .iter()
        .flat_map(|role| (0..nq).filter(move |&j| d.m.coordinates[j].role == *role))
        .collect();
    let velocity_terms: Vec<Atom> = (0..nq)
        .map(|a| &qv[a] + &applied[a])
        .chain(dcqdp.iter().cloned())
        .chain(dbdp.iter().cloned())
        .collect();
    let n_vt = velocity_terms.len();
    let vt_cols = 1 + moving.len() + nq;
    // Upright, the independent coordinates are zero and the ignorable ones
    // keep their initial guess: where that is zero, it is substituted after
    // differentiating, which removes most terms of the derivatives.
    let at_upright: Vec<Symbol> = (0..nq)
        .filter(|&j| {
            let c = &d.m.coordinates[j];
            c.role == Role::Independent || (c.role == Role::Ignorable && c.upright.is_none() && c.guess == 0.0)
        })
        .map(q_at)
        .collect();
    let upright_value = |e: Atom| {
        at_upright.iter().fold(e, |e, &q| {
            let q = Atom::var(q);
            e.replace(Symbol::SIN.call((&q,)))
                .with(zero())
                .replace(Symbol::COS.call((&q,)))
                .with(Atom::num(1))
                .replace(q)
                .with(zero())
        })
    };
    let velocity_terms_jacobian: Vec<Atom> = velocity_terms
        .iter()
        .flat_map(|r| {
            std::iter::once(r.clone())
                .chain(moving.iter().map(|&j| r.derivative(q_at(j))))
                .chain((0..nq).map(|j| r.derivative(rate_syms[j])))
        })
        .map(upright_value)
        .collect();
    let (all, no_t, t_only) = (
        Inputs {
            time: true,
            coordinates: true,
            rates: true,
        },
        Inputs {
            time: false,
            coordinates: true,
            rates: true,
        },
        Inputs {
            time: true,
            coordinates: true,
            rates: false,
        },
    );
    let pos = Inputs {
        time: false,
        coordinates: true,
        rates: false,
    };
    let buf = |rows, cols| Shape::Buffer { rows, cols };
    let quantities = vec![
        Quantity {
            name: "mass_matrix",
            doc: "Mass matrix M(p), thesis eq. 32 (row-major nq x nq).",
            inputs: pos,
            shape: buf(nq, nq),
            outputs: mass,
            shared: true,
        },
        Quantity {
            name: "quadratic_velocity_forces",
            doc: "Quadratic-velocity forces Qv = -d(M p')/dp p' + dT/dp, thesis eq. 36.",
            inputs: no_t,
            shape: buf(nq, 1),
            outputs: qv,
            shared: true,
        },
        Quantity {
            name: "gravity_forces",
            doc: "Gravity forces Qgrav = sum H_i^T [0 0 -m_i g], thesis eq. 38.",
            inputs: pos,
            shape: buf(nq, 1),
            outputs: gravity,
            shared: true,
        },
        Quantity {
            name: "applied_forces",
            doc: "Applied generalized forces Qext(p, p', t).",
            inputs: all,
            shape: buf(nq, 1),
            outputs: applied,
            shared: true,
        },
        Quantity {
            name: "holonomic_residuals",
            doc: "Holonomic constraint residuals Res(p, t).",
            inputs: t_only,
            shape: buf(nh, 1),
            outputs: res,
            shared: true,
        },
        Quantity {
            name: "holonomic_jacobian",
            doc: "Holonomic constraint Jacobian Cq = dRes/dp (row-major nh x nq).",
            inputs: t_only,
            shape: buf(nh, nq),
            outputs: cq,
            shared: true,
        },
        Quantity {
            name: "holonomic_time_derivative",
            doc: "Ct = dRes/dt.",
            inputs: t_only,
            shape: buf(nh, 1),
            outputs: ct,
            shared: true,
        },
        Quantity {
            name: "holonomic_convective",
            doc: "dCqdp = d(Cq p')/dp p'.",
            inputs: all,
            shape: buf(nh, 1),
            outputs: dcqdp,
            shared: true,
        },
        Quantity {
            name: "nonholonomic_velocities",
            doc: "Constrained velocities (contact-point velocities), zero when the constraints hold.",
            inputs: all,
            shape: buf(nnh, 1),
            outputs: vel,
            shared: true,
        },
        Quantity {
            name: "nonholonomic_matrix",
            doc: "Nonholonomic matrix B = d(velocities)/dp' (row-major nnh x nq).",
            inputs: t_only,
            shape: buf(nnh, nq),
            outputs: bmat,
            shared: true,
        },
        Quantity {
            name: "nonholonomic_convective",
            doc: "dBdp = d(B p')/dp p'.",
            inputs: all,
            shape: buf(nnh, 1),
            outputs: dbdp,
            shared: true,
        },
        Quantity {
            name: "kinetic_energy",
            doc: "Kinetic energy T = 1/2 p'^T M p' (J).",
            inputs: no_t,
            shape: Shape::Scalar,
            outputs: vec![kinetic],
            shared: true,
        },
        Quantity {
            name: "potential_energy",
            doc: "Gravitational potential energy V (J), Qgrav = -dV/dp.",
            inputs: pos,
            shape: Shape::Scalar,
            outputs: vec![potential],
            shared: true,
        },
        Quantity {
            name: "point_positions",
            doc: "Global positions of the points of interest (x, y, z per point).",
            inputs: pos,
            shape: buf(d.m.points_of_interest.len(), 3),
            outputs: poi,
            shared: true,
        },
        Quantity {
            name: "applied_force_terms",
            doc: "Generalized force of each declared force (row-major nforces x nq), in the order of FORCES; their sum is applied_forces.",
            inputs: all,
            shape: buf(d.m.forces.len(), nq),
            outputs: force_terms,
            shared: false,
        },
        Quantity {
            name: "upright_configuration",
            doc: "The physical upright configuration: coordinates with a closed-form upright value get it, the others keep their value in `p`.",
            inputs: pos,
            shape: buf(nq, 1),
            outputs: upright,
            shared: false,
        },
        Quantity {
            name: "state_rates",
            doc: "Rates of the extra first-order states (read after the parameters in `param`).",
            inputs: all,
            shape: buf(d.m.states.len(), 1),
            outputs: state_rates,
            shared: false,
        },
        Quantity {
            name: "forward_speed",
            doc: "Forward speed of the bicycle (m/s) as the model declares it.",
            inputs: no_t,
            shape: Shape::Scalar,
            outputs: vec![forward_speed],
            shared: false,
        },
        Quantity {
            name: "upright_velocity_terms_jacobian",
            doc: "Velocity terms and their first derivatives upright, for the exact linearization (row-major): rows Qv + Qext (nq), dCqdp (nh), dBdp (nnh); columns the value, d/dp of the independent then the dependent coordinates, d/dp' of every coordinate. The independent coordinates are taken as zero and the ignorable ones without a closed-form upright value as their initial guess when it is zero: those entries of `p` are not read.",
            inputs: all,
            shape: buf(n_vt, vt_cols),
            outputs: velocity_terms_jacobian,
            shared: false,
        },
    ];
    // Every buffer quantity in one function, so that they share common
    // subexpressions and trigonometric evaluations.
    let all_outputs: Vec<Atom> = quantities
        .iter()
        .filter(|q| q.shared && matches!(q.shape, Shape::Buffer { .. }))
        .flat_map(|q| q.outputs.clone())
        .collect();
    let n_all = all_outputs.len();
    let mut quantities = quantities;
    quantities.push(Quantity {
        name: "all_quantities",
        doc: "Every buffer quantity above in one call (shared subexpressions), concatenated in declaration order.",
        inputs: all,
        shape: buf(n_all, 1),
        outputs: all_outputs,
        shared: false,
    });
    let Deriver { sym, .. } = d;
    Derived {
        model: model.clone(),
        symbols: sym,
        quantities,
        elapsed: start.elapsed(),
    }
}
