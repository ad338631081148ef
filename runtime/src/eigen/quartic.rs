//! Roots of a real quartic `k4 s^4 + k3 s^3 + k2 s^2 + k1 s + k0`.
//!
//! Method (about 200 flops, no allocation):
//! 1. normalise to a monic quartic and scale `s = rho z` with `rho` a power of two
//!    near the root magnitude (exact, avoids overflow and keeps the numbers O(1));
//! 2. Ferrari: the largest real root `y` of the resolvent cubic gives a real
//!    factorisation `(z^2 + p1 z + q1)(z^2 + p2 z + q2)`; for a real quartic it pairs
//!    complex-conjugate roots together, and for four real roots it pairs the two
//!    largest and the two smallest (so a near-double root is kept inside one factor
//!    whenever it is formed by neighbouring roots at the top or bottom);
//! 3. refine the factorisation by Newton on the four coefficient equations
//!    (Bairstow-style; well conditioned for clusters inside one factor);
//! 4. roots of each factor by the cancellation-free quadratic formula (a complex
//!    pair comes out exactly conjugate, a real root has imaginary part exactly 0);
//! 5. polish every root by guarded Newton on the *unnormalised* quartic (exactly
//!    scaled), accepting a step only if the residual decreases and the step is
//!    shorter than half the distance to the nearest other root (so a near-double
//!    root never jumps onto its partner); the upper root of a pair is polished and
//!    the lower set to its conjugate.
//!
//! A backward-error check guards the result; on failure the roots are recomputed
//! from the Schur form of the companion matrix (iteration cap) and polished the same way.

use nalgebra::{Complex, Matrix4};

use super::float::{self, mul_add};
use crate::linalg::solve_in_place;

pub(crate) type C64 = Complex<f64>;

const EPS: f64 = f64::EPSILON;

/// Power of two nearest (in log scale) to a finite positive `r`.
fn pow2_near(r: f64) -> f64 {
    // exponent of a normal r (subnormal/zero/huge clamped)
    let e = ((r.to_bits() >> 52) & 0x7ff) as i64 - 1023;
    let e = e.clamp(-1000, 1000);
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// Roots of `k[4] s^4 + ... + k[0]` (`k[i]` multiplies `s^i`), `k[4] != 0`, all finite.
/// Sorted by descending real part, then descending imaginary part.
/// Returns `None` only if no method produced finite roots with a small backward error.
pub(crate) fn quartic_roots(k: &[f64; 5]) -> Option<[C64; 4]> {
    let k4 = k[4];
    let ([a, b, c, d], rho) = monic_scaled(k)?;
    if a == 0.0 && b == 0.0 && c == 0.0 && d == 0.0 {
        return Some([C64::new(0.0, 0.0); 4]);
    }
    let (r1, r2) = (rho, rho * rho);
    // Unnormalised coefficients in the scaled variable, divided by a power of two
    // near |k4|: e[i] = k[i] rho^i / sigma (exact scalings).
    let sigma = pow2_near(k4.abs());
    let e = [
        k[0] / sigma,
        k[1] / sigma * r1,
        k[2] / sigma * r2,
        k[3] / sigma * (r2 * r1),
        k[4] / sigma * (r2 * r2),
    ];
    if !e.iter().all(|x| x.is_finite()) {
        return None;
    }
    let mut z = ferrari(a, b, c, d).and_then(|z| polish_all(&e, z));
    if z.is_none() {
        z = companion(a, b, c, d).and_then(|z| polish_all(&e, z));
    }
    let mut z = z?;
    for x in z.iter_mut() {
        *x *= rho;
    }
    if !z.iter().all(|x| x.re.is_finite() && x.im.is_finite()) {
        return None;
    }
    sort_desc(&mut z);
    Some(z)
}

/// The quartic made monic and scaled, `z^4 + a z^3 + b z^2 + c z + d` with
/// `s = rho z` and `rho` a power of two near the largest root magnitude
/// (exact scalings), as `([a, b, c, d], rho)`; `None` if `k[4] = 0` or a
/// coefficient is not finite. An all-zero lower part gives `rho = 1`.
fn monic_scaled(k: &[f64; 5]) -> Option<([f64; 4], f64)> {
    let k4 = k[4];
    if k4 == 0.0 || !k.iter().all(|x| x.is_finite()) {
        return None;
    }
    let (a, b, c, d) = (k[3] / k4, k[2] / k4, k[1] / k4, k[0] / k4);
    if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) {
        return None;
    }
    if a == 0.0 && b == 0.0 && c == 0.0 && d == 0.0 {
        return Some(([0.0; 4], 1.0));
    }
    // rho ~ max(|a|, |b|^(1/2), |c|^(1/3), |d|^(1/4)) as a power of two, from exponents.
    let ex = |x: f64, n: i64| -> i64 {
        if x == 0.0 {
            i64::MIN / 2
        } else {
            (((x.to_bits() >> 52) & 0x7ff) as i64 - 1023).div_euclid(n)
        }
    };
    let er = ex(a, 1).max(ex(b, 2)).max(ex(c, 3)).max(ex(d, 4)).clamp(-1000, 1000);
    let rho = f64::from_bits(((er + 1023) as u64) << 52);
    let (r1, r2) = (rho, rho * rho);
    Some(([a / r1, b / r2, c / (r2 * r1), d / (r2 * r2)], rho))
}

/// The discriminant of the quartic `k`, made monic and scaled as in
/// [`quartic_roots`] (positive factors that keep its sign), and the number of
/// its real roots from the discriminant's sign and two more invariants (no
/// root is solved for): `None` as [`monic_scaled`]. A negative discriminant
/// means two real roots and a complex pair; a positive one four real roots
/// (when `P = 8 b - 3 a^2` and `D = 64 d - 16 b^2 + 16 a^2 b - 16 a c - 3 a^4`
/// are both negative) or two complex pairs; zero, a repeated root (the count
/// is then `None`). So where roots collide the discriminant is zero, and where
/// the number of real roots changes, the count does (about 50 flops, against a
/// root solve's 200 and a labelling).
pub(crate) fn discriminant(k: &[f64; 5]) -> Option<(f64, Option<u8>)> {
    // Monic only (one division): the scaling by `rho` changes none of the
    // three signs and, being by a power of two, no rounding; it is needed
    // only where the unscaled terms would overflow or underflow.
    let r = 1.0 / k[4];
    let monic = [k[3] * r, k[2] * r, k[1] * r, k[0] * r];
    match monic_invariants(monic) {
        Some((delta, real)) if delta.is_finite() && delta != 0.0 => Some((delta, real)),
        _ => monic_invariants(monic_scaled(k)?.0),
    }
}

/// The discriminant and real-root count of `z^4 + a z^3 + b z^2 + c z + d`
/// (see [`discriminant`]); `None` if a coefficient is not finite.
fn monic_invariants([a, b, c, d]: [f64; 4]) -> Option<(f64, Option<u8>)> {
    if !(a.is_finite() && b.is_finite() && c.is_finite() && d.is_finite()) {
        return None;
    }
    let (a2, b2, c2, d2) = (a * a, b * b, c * c, d * d);
    let delta = 256.0 * d2 * d - 192.0 * a * c * d2 - 128.0 * b2 * d2 + 144.0 * b * c2 * d - 27.0 * c2 * c2
        + 144.0 * a2 * b * d2
        - 6.0 * a2 * c2 * d
        - 80.0 * a * b2 * c * d
        + 18.0 * a * b * c2 * c
        + 16.0 * b2 * b2 * d
        - 4.0 * b2 * b * c2
        - 27.0 * a2 * a2 * d2
        + 18.0 * a2 * a * b * c * d
        - 4.0 * a2 * a * c2 * c
        - 4.0 * a2 * b2 * b * d
        + a2 * b2 * c2;
    let p = 8.0 * b - 3.0 * a2;
    let dd = 64.0 * d - 16.0 * b2 + 16.0 * a2 * b - 16.0 * a * c - 3.0 * a2 * a2;
    let real = if delta < 0.0 {
        Some(2)
    } else if delta > 0.0 {
        Some(if p < 0.0 && dd < 0.0 { 4 } else { 0 })
    } else {
        None
    };
    Some((delta, real))
}

/// Sort by descending real part, then descending imaginary part.
pub(crate) fn sort_desc(z: &mut [C64; 4]) {
    crate::small_sort::sort4_by(z, |x, y| {
        y.re.partial_cmp(&x.re)
            .unwrap_or(std::cmp::Ordering::Equal)
            .then(y.im.partial_cmp(&x.im).unwrap_or(std::cmp::Ordering::Equal))
    });
}

/// `p(x)`, `p'(x)` and the running-error scale `sum |e_i| |x|^i` for real `x`.
#[inline]
fn horner_real(e: &[f64; 5], x: f64) -> (f64, f64, f64) {
    let mut p = e[4];
    let mut dp = 0.0f64;
    let mut s = e[4].abs();
    let ax = x.abs();
    for i in (0..4).rev() {
        dp = dp * x + p;
        p = p * x + e[i];
        s = s * ax + e[i].abs();
    }
    (p, dp, s)
}

/// Complex Horner: `p(z)`, `p'(z)`, scale `sum |e_i| |z|^i`.
#[inline]
fn horner_complex(e: &[f64; 5], z: C64) -> (C64, C64, f64) {
    let (zr, zi) = (z.re, z.im);
    let (mut pr, mut pi) = (e[4], 0.0);
    let (mut dr, mut di) = (0.0, 0.0);
    let mut s = e[4].abs();
    let az = float::max(z.re.abs(), z.im.abs()) * std::f64::consts::SQRT_2; // >= |z|
    for i in (0..4).rev() {
        let ndr = dr * zr - di * zi + pr;
        let ndi = dr * zi + di * zr + pi;
        dr = ndr;
        di = ndi;
        let npr = pr * zr - pi * zi + e[i];
        let npi = pr * zi + pi * zr;
        pr = npr;
        pi = npi;
        s = s * az + e[i].abs();
    }
    (C64::new(pr, pi), C64::new(dr, di), s)
}

/// Largest real root of the monic cubic `y^3 + bb y^2 + cc y + dd`.
fn largest_real_cubic_root(bb: f64, cc: f64, dd: f64) -> f64 {
    let sh = bb / 3.0;
    let p = cc - bb * sh;
    let q = dd - sh * cc + 2.0 * sh * sh * sh;
    // t^3 + p t + q = 0, y = t - sh.
    let t = if p == 0.0 {
        float::cbrt(-q)
    } else {
        let h = (q / 2.0) * (q / 2.0) + (p / 3.0) * (p / 3.0) * (p / 3.0);
        if h > 0.0 {
            let aa = -(q.signum()) * float::cbrt((q / 2.0).abs() + h.sqrt());
            if aa == 0.0 {
                0.0
            } else {
                aa - p / (3.0 * aa)
            }
        } else {
            // three real roots (p < 0)
            let m = (-p / 3.0).sqrt();
            let cos3 = ((-q / 2.0) / (m * m * m)).clamp(-1.0, 1.0);
            2.0 * m * (cos3.acos() / 3.0).cos()
        }
    };
    let mut y = t - sh;
    // Guarded Newton polish on the cubic.
    let f = |y: f64| ((y + bb) * y + cc) * y + dd;
    let df = |y: f64| (3.0 * y + 2.0 * bb) * y + cc;
    let mut fy = f(y);
    for _ in 0..4 {
        let d = df(y);
        if fy == 0.0 || d == 0.0 || !d.is_finite() {
            break;
        }
        let yn = y - fy / d;
        let fn_ = f(yn);
        if !(fn_.abs() < fy.abs()) {
            break;
        }
        y = yn;
        fy = fn_;
    }
    y
}

/// Ferrari factorisation + refinement + quadratic roots (unpolished).
fn ferrari(a: f64, b: f64, c: f64, d: f64) -> Option<[C64; 4]> {
    // Resolvent: y^3 - b y^2 + (a c - 4 d) y - (a^2 d - 4 b d + c^2) = 0.
    let y = largest_real_cubic_root(-b, mul_add(a, c, -4.0 * d), -(a * a * d - 4.0 * b * d + c * c));
    if !y.is_finite() {
        return None;
    }
    let alpha2 = float::max(mul_add(0.25 * a, a, y - b), 0.0);
    let beta2 = float::max(mul_add(0.25 * y, y, -d), 0.0);
    let ab2 = 0.5 * mul_add(a, 0.5 * y, -c); // alpha * beta
    let (alpha, beta) = if alpha2 >= beta2 {
        let al = alpha2.sqrt();
        (al, if al > 0.0 { ab2 / al } else { 0.0 })
    } else {
        let be = beta2.sqrt() * if ab2 < 0.0 { -1.0 } else { 1.0 };
        (ab2 / be, be)
    };
    let mut f = [0.5 * a - alpha, 0.5 * y - beta, 0.5 * a + alpha, 0.5 * y + beta];
    // Recompute the smaller constant term from the product (less cancellation).
    if f[1].abs() < f[3].abs() {
        if f[3] != 0.0 {
            f[1] = d / f[3];
        }
    } else if f[1] != 0.0 {
        f[3] = d / f[1];
    }
    let f = refine_factors(a, b, c, d, f);
    if !f.iter().all(|x| x.is_finite()) {
        return None;
    }
    let (u, w) = (quadratic_roots(f[0], f[1]), quadratic_roots(f[2], f[3]));
    Some([u[0], u[1], w[0], w[1]])
}

fn factor_residual(a: f64, b: f64, c: f64, d: f64, f: &[f64; 4]) -> [f64; 4] {
    let [p1, q1, p2, q2] = *f;
    [
        p1 + p2 - a,
        mul_add(p1, p2, q1 + q2) - b,
        mul_add(p1, q2, p2 * q1) - c,
        mul_add(q1, q2, -d),
    ]
}

/// Newton on `(z^2+p1 z+q1)(z^2+p2 z+q2) = z^4+a z^3+b z^2+c z+d`, accepting only
/// residual-decreasing steps.
fn refine_factors(a: f64, b: f64, c: f64, d: f64, mut f: [f64; 4]) -> [f64; 4] {
    let nrm = |r: &[f64; 4]| r.iter().fold(0.0f64, |m, x| float::max(m, x.abs()));
    let mut r = factor_residual(a, b, c, d, &f);
    let mut rn = nrm(&r);
    let tiny = 4.0 * EPS * (1.0 + a.abs() + b.abs() + c.abs() + d.abs());
    for _ in 0..4 {
        if rn <= tiny || !rn.is_finite() {
            break;
        }
        let [p1, q1, p2, q2] = f;
        #[rustfmt::skip]
        let mut j = [
            1.0, 0.0, 1.0, 0.0,
            p2, 1.0, p1, 1.0,
            q2, p2, q1, p1,
            0.0, q2, 0.0, q1,
        ];
        let mut dx = [-r[0], -r[1], -r[2], -r[3]];
        if solve_in_place(&mut j, 4, &mut dx, 1).is_err() || !dx.iter().all(|v| v.is_finite()) {
            break;
        }
        let fnew = [p1 + dx[0], q1 + dx[1], p2 + dx[2], q2 + dx[3]];
        let rnew = factor_residual(a, b, c, d, &fnew);
        let rnn = nrm(&rnew);
        if !(rnn < rn) {
            break;
        }
        f = fnew;
        r = rnew;
        rn = rnn;
    }
    f
}

/// Roots of `z^2 + p z + q` (real roots: larger first; complex: upper first).
fn quadratic_roots(p: f64, q: f64) -> [C64; 2] {
    let h = -0.5 * p;
    let disc = mul_add(h, h, -q);
    if disc >= 0.0 {
        let sq = disc.sqrt();
        let big = if h >= 0.0 { h + sq } else { h - sq };
        let small = if big != 0.0 { q / big } else { 0.0 };
        let (x1, x2) = if big >= small { (big, small) } else { (small, big) };
        [C64::new(x1, 0.0), C64::new(x2, 0.0)]
    } else {
        let w = (-disc).sqrt();
        [C64::new(h, w), C64::new(h, -w)]
    }
}

/// Roots from the Schur form of the companion matrix (fallback).
fn companion(a: f64, b: f64, c: f64, d: f64) -> Option<[C64; 4]> {
    #[rustfmt::skip]
    let m = Matrix4::new(
        -a, -b, -c, -d,
        1.0, 0.0, 0.0, 0.0,
        0.0, 1.0, 0.0, 0.0,
        0.0, 0.0, 1.0, 0.0,
    );
    let schur = nalgebra::linalg::Schur::try_new(m, EPS, 1000)?;
    let ev = schur.complex_eigenvalues();
    let mut z = [ev[0], ev[1], ev[2], ev[3]];
    // Enforce exact conjugate pairs / exactly real roots.
    sort_desc(&mut z);
    let mut out = [C64::new(0.0, 0.0); 4];
    let mut used = [false; 4];
    let mut n = 0;
    for i in 0..4 {
        if used[i] {
            continue;
        }
        used[i] = true;
        if z[i].im == 0.0 {
            out[n] = z[i];
            n += 1;
            continue;
        }
        // partner: unused with closest conjugate
        let mut best = None;
        for j in 0..4 {
            if !used[j] {
                let dist = (z[j] - z[i].conj()).norm();
                if best.is_none_or(|(_, bd)| dist < bd) {
                    best = Some((j, dist));
                }
            }
        }
        let (j, _) = best?;
        used[j] = true;
        let re = 0.5 * (z[i].re + z[j].re);
        let im = 0.5 * (z[i].im.abs() + z[j].im.abs());
        out[n] = C64::new(re, im);
        out[n + 1] = C64::new(re, -im);
        n += 2;
    }
    Some(out)
}

/// Backward-error bound accepted after polishing: `|p(z)| <= 1e-9 sum |e_i| |z|^i`.
const BACKWARD_TOL: f64 = 1e-9;

/// Residual regarded as rounding noise: `|p(z)| <= 2 eps sum |e_i| |z|^i`.
const NOISE: f64 = 2.0 * EPS;

/// Guarded Newton polish of all roots (pairs kept exactly conjugate). `None` if a
/// root is non-finite or fails the backward-error test.
fn polish_all(e: &[f64; 5], z: [C64; 4]) -> Option<[C64; 4]> {
    let mut gap = [f64::INFINITY; 4];
    for i in 0..4 {
        for j in i + 1..4 {
            let d = (z[i] - z[j]).norm_sqr();
            gap[i] = float::min(gap[i], d);
            gap[j] = float::min(gap[j], d);
        }
    }
    for g in gap.iter_mut() {
        *g = g.sqrt();
    }
    let mut out = z;
    for i in 0..4 {
        if z[i].im == 0.0 {
            out[i] = C64::new(polish_real(e, z[i].re, gap[i])?, 0.0);
        } else if z[i].im > 0.0 {
            let w = polish_complex(e, z[i], gap[i])?;
            out[i] = w;
            let mut found = false;
            for j in 0..4 {
                if j != i && z[j] == z[i].conj() {
                    out[j] = w.conj();
                    found = true;
                    break;
                }
            }
            if !found {
                return None;
            }
        }
    }
    Some(out)
}

/// Newton polish of a real root. A step is taken without re-checking the residual
/// when it is tiny compared with the root and with the gap to the other roots (the
/// quadratically convergent regime of a simple root); otherwise it must decrease
/// the residual. Returns `None` on a backward-error failure.
fn polish_real(e: &[f64; 5], x0: f64, gap: f64) -> Option<f64> {
    let mut x = x0;
    let (mut p, mut dp, mut sc) = horner_real(e, x);
    for _ in 0..8 {
        // at rounding-noise level the root is as good as the evaluation allows; a
        // further step would only wander (notably inside a near-double cluster)
        if p.abs() <= NOISE * sc || dp == 0.0 {
            break;
        }
        let step = p / dp;
        let sa = step.abs();
        if !(sa < 0.5 * gap) {
            break;
        }
        if sa <= 1e-9 * float::max(x.abs(), float::min(gap, 1.0)) && sa <= 1e-6 * gap {
            // simple root, converged to within ~1e-18 after this step
            x -= step;
            return (p.abs() <= BACKWARD_TOL * sc).then_some(x);
        }
        let xn = x - step;
        let (pn, dpn, scn) = horner_real(e, xn);
        if !(pn.abs() < p.abs()) {
            break;
        }
        x = xn;
        p = pn;
        dp = dpn;
        sc = scn;
    }
    (x.is_finite() && p.abs() <= BACKWARD_TOL * sc).then_some(x)
}

/// Complex counterpart of [`polish_real`]; never crosses the real axis.
fn polish_complex(e: &[f64; 5], z0: C64, gap: f64) -> Option<C64> {
    let mut z = z0;
    let gap = float::min(gap, 2.0 * z0.im.abs());
    let g2 = gap * gap;
    let (mut p, mut dp, mut sc) = horner_complex(e, z);
    let mut p2 = p.norm_sqr();
    for _ in 0..8 {
        let d2 = dp.norm_sqr();
        if p2 <= NOISE * NOISE * sc * sc || d2 == 0.0 {
            break;
        }
        let step = p * dp.conj() / d2;
        let sn2 = step.norm_sqr();
        if !(sn2 < 0.25 * g2) {
            break;
        }
        if sn2 <= 1e-18 * float::max(z.norm_sqr(), float::min(g2, 1.0)) && sn2 <= 1e-12 * g2 {
            z -= step;
            return (p2 <= BACKWARD_TOL * BACKWARD_TOL * sc * sc).then_some(z);
        }
        let zn = z - step;
        let (pn, dpn, scn) = horner_complex(e, zn);
        let pn2 = pn.norm_sqr();
        if !(pn2 < p2) {
            break;
        }
        z = zn;
        p = pn;
        p2 = pn2;
        dp = dpn;
        sc = scn;
    }
    let _ = p;
    (z.re.is_finite() && z.im.is_finite() && p2 <= BACKWARD_TOL * BACKWARD_TOL * sc * sc).then_some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `k` of `prod (s - r)` for four roots given as real numbers and
    /// conjugate pairs.
    fn from_roots(r: [C64; 4]) -> [f64; 5] {
        let mut p = [
            C64::new(1.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
            C64::new(0.0, 0.0),
        ];
        for (n, z) in r.iter().enumerate() {
            for i in (1..=n + 1).rev() {
                p[i] = p[i - 1] - *z * p[i];
            }
            p[0] = -*z * p[0];
        }
        // p[i] multiplies s^(n - i) so far: reverse to `k[i]` of `s^i`.
        let mut k = [0.0; 5];
        for i in 0..5 {
            k[i] = p[4 - i].re;
        }
        k
    }

    /// The discriminant's sign is that of `prod_{i<j} (r_i - r_j)^2`, and the
    /// count of real roots is right, for four real roots, two complex pairs,
    /// and two real roots and a pair, whatever the scale of the roots or the
    /// leading coefficient.
    #[test]
    fn discriminant_sign_and_real_root_count() {
        let re = |x: f64| C64::new(x, 0.0);
        let cases = [
            ([re(1.0), re(2.0), re(-3.0), re(4.5)], 1.0, 4),
            ([C64::new(0.5, 2.0), C64::new(0.5, -2.0), re(-1.0), re(3.0)], -1.0, 2),
            (
                [
                    C64::new(-0.5, 6.0),
                    C64::new(-0.5, -6.0),
                    C64::new(2.0, 1.0),
                    C64::new(2.0, -1.0),
                ],
                1.0,
                0,
            ),
            (
                [
                    C64::new(2.75, 0.06),
                    C64::new(2.75, -0.06),
                    C64::new(-3.1, 0.04),
                    C64::new(-3.1, -0.04),
                ],
                1.0,
                0,
            ),
            (
                [C64::new(-0.1, 0.01), C64::new(-0.1, -0.01), re(-12.0), re(5.0)],
                -1.0,
                2,
            ),
            ([re(-0.1), re(-0.1001), re(-12.0), re(5.0)], 1.0, 4),
        ];
        for (roots, sign, real) in cases {
            for scale in [1e-3, 1.0, 1e4] {
                let mut k = from_roots(roots.map(|z| z * scale));
                for x in k.iter_mut() {
                    *x *= -7.5;
                }
                let (d, n) = discriminant(&k).unwrap();
                assert_eq!((d.signum(), n), (sign, Some(real)), "{roots:?} x {scale}: {d}");
            }
        }
        assert_eq!(discriminant(&[0.0, 0.0, 0.0, 0.0, 1.0]), Some((0.0, None)));
        assert_eq!(discriminant(&[1.0, 0.0, 0.0, 0.0, f64::NAN]), None);
    }
}
