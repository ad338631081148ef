//! The canonical matrices of a benchmark-form bicycle from the closed-form
//! expressions of appendix A of Meijaard, Papadopoulos, Ruina & Schwab
//! (2007), "Linearized dynamics equations for the balance and steer of a
//! bicycle: a benchmark and review", Proc. R. Soc. A 463:1955-1982, doi
//! 10.1098/rspa.2007.1857.
//!
//! bikedyn computes canonical matrices from the generated multibody
//! equations; this independent route checks them (and the eigen analysis)
//! against the paper. Written over any [`Scalar`], it is also where
//! `sensitivity` takes the exact derivatives of the canonical matrices with
//! respect to the parameters (dual numbers seeded on them), after checking
//! that its values agree with the generated model's.

use crate::canonical::CanonicalMatrices;
use crate::parameters::BenchmarkParameters;
use crate::scalar::Scalar;
use nalgebra::Matrix2;

/// `M0`, `C1`, `K0`, `K2` of Meijaard et al. (2007), appendix A (eqs. A 1 - A 27),
/// benchmark axes (x forward, y right, z down), `q = [phi, delta]`.
///
/// Uses the paper's auxiliary quantities: total mass and mass centre
/// (`mT`, `xT`, `zT`), total inertia about the rear contact point (`ITxx`, `ITxz`,
/// `ITzz`, with `IRzz = IRxx`, `IFzz = IFxx`), front assembly `A = H + F`
/// (`mA`, `xA`, `zA`, `IAxx`, `IAxz`, `IAzz`), the perpendicular distance `uA` of its
/// mass centre from the steer axis, its steer-axis inertias `IAll`, `IAlx`, `IAlz`,
/// the trail ratio `mu = (c/w) cos(lam)`, gyrostatic coefficients
/// `SR = IRyy/rR`, `SF = IFyy/rF`, `ST = SR + SF`, and the static moment
/// `SA = mA uA + mu mT xT`.
pub fn meijaard_canonical(p: &BenchmarkParameters) -> CanonicalMatrices {
    meijaard_canonical_of_values(&BenchmarkParameters::SYMBOLS.map(|k| p.get(k).expect("a benchmark symbol")))
}

/// [`meijaard_canonical`] from the values in the order of
/// [`BenchmarkParameters::SYMBOLS`] (SI units).
pub fn meijaard_canonical_of_values(values: &[f64; 26]) -> CanonicalMatrices {
    let m = meijaard_canonical_in(values);
    CanonicalMatrices {
        m0: Matrix2::from_fn(|i, j| m.m0[i][j]),
        c1: Matrix2::from_fn(|i, j| m.c1[i][j]),
        k0: Matrix2::from_fn(|i, j| m.k0[i][j]),
        k2: Matrix2::from_fn(|i, j| m.k2[i][j]),
        g: m.g,
    }
}

/// The canonical matrices over any [`Scalar`], rows first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanonicalIn<T> {
    pub m0: [[T; 2]; 2],
    pub c1: [[T; 2]; 2],
    pub k0: [[T; 2]; 2],
    pub k2: [[T; 2]; 2],
    pub g: T,
}

/// [`meijaard_canonical`] over any [`Scalar`], from the parameters in the
/// order of [`BenchmarkParameters::SYMBOLS`]. With [`crate::Dual`] numbers
/// seeded on the parameters it gives the exact derivatives of `M0`, `C1`,
/// `K0`, `K2` with respect to each (`sensitivity` uses it so; the values
/// themselves come from the generated model there, checked against these).
pub fn meijaard_canonical_in<T: Scalar>(p: &[T; 26]) -> CanonicalIn<T> {
    let k = |x: f64| T::cst(x);
    let [w, c, lam, g, rr, mr, irxx, iryy, xb, zb, mb, ibxx, _ibyy, ibzz, ibxz, xh, zh, mh, ihxx, _ihyy, ihzz, ihxz, rf, mf, ifxx, ifyy] =
        *p;

    // (A 1-3) total mass and mass centre
    let mt = mr + mb + mh + mf;
    let xt = (xb * mb + xh * mh + w * mf) / mt;
    let zt = (-rr * mr + zb * mb + zh * mh - rf * mf) / mt;
    // (A 4-7) total inertia about the rear contact point
    let itxx = irxx + ibxx + ihxx + ifxx + mr * rr * rr + mb * zb * zb + mh * zh * zh + mf * rf * rf;
    let itxz = ibxz + ihxz - mb * xb * zb - mh * xh * zh + mf * w * rf;
    let irzz = irxx;
    let ifzz = ifxx;
    let itzz = irzz + ibzz + ihzz + ifzz + mb * xb * xb + mh * xh * xh + mf * w * w;
    // (A 8-13) front assembly A = H + F
    let ma = mh + mf;
    let xa = (xh * mh + w * mf) / ma;
    let za = (zh * mh - rf * mf) / ma;
    let iaxx = ihxx + ifxx + mh * (zh - za) * (zh - za) + mf * (rf + za) * (rf + za);
    let iaxz = ihxz - mh * (xh - xa) * (zh - za) + mf * (w - xa) * (rf + za);
    let iazz = ihzz + ifzz + mh * (xh - xa) * (xh - xa) + mf * (w - xa) * (w - xa);
    // (A 14-17) steer-axis quantities
    let (sl, cl) = lam.sin_cos();
    let ua = (xa - w - c) * cl - za * sl;
    let iall = ma * ua * ua + iaxx * sl * sl + k(2.0) * iaxz * sl * cl + iazz * cl * cl;
    let ialx = -ma * ua * za + iaxx * sl + iaxz * cl;
    let ialz = ma * ua * xa + iaxz * sl + iazz * cl;
    // (A 18-21)
    let mu = c / w * cl;
    // A skate wheel (zero radius) has zero spin inertia (the two-mass-skate
    // bicycle, Kooijman et al. 2011): its gyrostatic coefficient is 0 (and
    // so are its derivatives: the spin inertia must stay zero there).
    let gyrostatic = |i: T, r: T| {
        if i.re() == 0.0 && r.re() == 0.0 {
            T::zero()
        } else {
            i / r
        }
    };
    let sr = gyrostatic(iryy, rr);
    let sf = gyrostatic(ifyy, rf);
    let st = sr + sf;
    let sa = ma * ua + mu * mt * xt;
    // (A 22-27) canonical matrices
    let m_pd = ialx + mu * itxz;
    let m0 = [[itxx, m_pd], [m_pd, iall + k(2.0) * mu * ialz + mu * mu * itzz]];
    let k0 = [[mt * zt, -sa], [-sa, -sa * sl]];
    let k2 = [
        [T::zero(), (st - mt * zt) * cl / w],
        [T::zero(), (sa + sf * sl) * cl / w],
    ];
    let c1 = [
        [T::zero(), mu * st + sf * cl + itxz * cl / w - mu * mt * zt],
        [-(mu * st + sf * cl), ialz * cl / w + mu * (sa + itzz * cl / w)],
    ];
    CanonicalIn { m0, c1, k0, k2, g }
}
