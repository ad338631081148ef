//! The Meijaard et al. (2007) benchmark through the generated multibody
//! equations (the offset model), to the published digits.
//! Reference figures: runtime/tests/data/meijaard2007.toml (copied from the
//! paper: Proc. R. Soc. A 463:1955-1982, doi 10.1098/rspa.2007.1857).

use crate::common::*;
use bikedyn::bicycle::{canonical_of, Bicycle};
use bikedyn::generated::{ThesisWhipple, WhippleOffset};
use bikedyn::runtime::eigen::{critical_speeds, eigenvalues};
use bikedyn::runtime::linearize::{canonical_matrices, linearize, linearize_finite_difference, parameter_vector};
use bikedyn::runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn::runtime::CanonicalMatrices;
use nalgebra::Matrix2;

fn reference() -> toml::Table {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/runtime/tests/data/meijaard2007.toml");
    std::fs::read_to_string(path).unwrap().parse().unwrap()
}

fn matrix(t: &toml::Table, name: &str) -> Matrix2<f64> {
    let rows = t["canonical"][name].as_array().unwrap();
    let e = |i: usize, j: usize| rows[i].as_array().unwrap()[j].as_float().unwrap();
    Matrix2::new(e(0, 0), e(0, 1), e(1, 0), e(1, 1))
}

fn benchmark_canonical() -> CanonicalMatrices {
    Bicycle::resolve("benchmark").unwrap().canonical().unwrap()
}

/// Relative error per entry; entries published as exactly zero are compared
/// with the matrix's largest entry as the scale.
fn assert_matrix_close(name: &str, got: &Matrix2<f64>, want: &Matrix2<f64>, rel: f64) {
    let scale = want.amax();
    for i in 0..2 {
        for j in 0..2 {
            let (g, w) = (got[(i, j)], want[(i, j)]);
            let denom = if w == 0.0 { scale } else { w.abs() };
            assert!(
                (g - w).abs() <= rel * denom,
                "{name}[{i}][{j}] = {g:.17} but the paper gives {w:.17} (rel error {:.2e})",
                (g - w).abs() / denom
            );
        }
    }
}

#[test]
fn canonical_matrices_of_the_benchmark_match_the_paper_to_1e12() {
    let t = reference();
    let c = benchmark_canonical();
    assert_matrix_close("M0", &c.m0, &matrix(&t, "M"), 1e-12);
    assert_matrix_close("C1", &c.c1, &matrix(&t, "C1"), 1e-12);
    assert_matrix_close("K0", &c.k0, &matrix(&t, "K0"), 1e-12);
    assert_matrix_close("K2", &c.k2, &matrix(&t, "K2"), 1e-12);
}

#[test]
fn table2_eigenvalues_through_the_generated_equations() {
    let t = reference();
    let c = benchmark_canonical();
    // 1e-12 relative, but never below 1e-14 absolute: the roots of a
    // spectrum reaching 16 1/s carry a roundoff of some 1e-15 each, which a
    // root near zero (capsize about v_c: -0.0041 at 6 m/s) keeps in full.
    let close = |g: f64, w: f64| (g - w).abs() <= (1e-12 * w.abs()).max(1e-14);
    for row in t["eigenvalues"].as_array().unwrap() {
        let v = row["v"].as_float().unwrap();
        let ev = eigenvalues(&c, v).unwrap();
        let mut want: Vec<(f64, f64)> = Vec::new();
        if let Some(r) = row.get("real") {
            want.extend(r.as_array().unwrap().iter().map(|x| (x.as_float().unwrap(), 0.0)));
        }
        if let Some(w) = row.get("weave") {
            let w = w.as_array().unwrap();
            let (re, im) = (w[0].as_float().unwrap(), w[1].as_float().unwrap());
            want.push((re, im));
            want.push((re, -im));
        }
        for k in ["capsize", "castering"] {
            if let Some(x) = row.get(k) {
                want.push((x.as_float().unwrap(), 0.0));
            }
        }
        assert_eq!(want.len(), 4);
        for (re, im) in want {
            assert!(
                ev.iter().any(|s| close(s.re, re) && close(s.im, im)),
                "v = {v}: no eigenvalue within tolerance of {re} + {im}i; got {ev:?}"
            );
        }
    }
}

#[test]
fn critical_speeds_of_the_benchmark_to_1e10() {
    let t = reference();
    let cs = &t["critical_speeds"];
    let crit = critical_speeds(&benchmark_canonical(), 0.0, 10.0).unwrap();
    let check = |got: Option<f64>, key: &str| {
        let want = cs[key].as_float().unwrap();
        let got = got.unwrap_or_else(|| panic!("{key} not found"));
        assert!((got - want).abs() < 1e-10, "{key}: {got:.14} vs {want:.14}");
    };
    check(crit.weave_real_pair_merge, "weave_real_pair_merge");
    check(crit.weave_speed, "weave_speed");
    check(crit.capsize_speed, "capsize_speed");
    assert_eq!(crit.stable_intervals.len(), 1);
}

#[test]
fn exact_linearization_is_more_accurate_than_the_thesis_finite_differences() {
    let p = BenchmarkParameters::benchmark_bicycle().to_thesis().unwrap();
    let v: f64 = 4.0;
    let param = parameter_vector::<WhippleOffset>(|s| p.get(s), v).unwrap();
    let exact = linearize::<WhippleOffset>(&param).unwrap();
    let fd = linearize_finite_difference::<WhippleOffset>(&param, 1e-6).unwrap();
    let t = reference();
    // The paper's matrices at v, converted to the thesis's steer sign (gamma = -delta).
    let flip = |m: &Matrix2<f64>| Matrix2::new(m[(0, 0)], -m[(0, 1)], -m[(1, 0)], m[(1, 1)]);
    let want = [
        flip(&matrix(&t, "M")),
        flip(&(matrix(&t, "C1") * v)),
        flip(&(matrix(&t, "K0") * 9.81 + matrix(&t, "K2") * (v * v))),
    ];
    let err = |l: &bikedyn::runtime::linearize::Linearization| {
        [&l.mass, &l.damping, &l.stiffness]
            .iter()
            .zip(&want)
            .map(|(m, w)| {
                (0..4)
                    .map(|k| (m[(k / 2, k % 2)] - w[(k / 2, k % 2)]).abs())
                    .fold(0.0, f64::max)
                    / w.amax()
            })
            .fold(0.0, f64::max)
    };
    let (e_exact, e_fd) = (err(&exact), err(&fd));
    println!("M, C, K at {v} m/s vs the paper: exact (dual numbers) {e_exact:.2e}, thesis finite differences (h = 1e-6) {e_fd:.2e}");
    assert!(e_exact < 1e-13, "exact linearization off by {e_exact:e}");
    assert!(
        e_fd > 10.0 * e_exact.max(1e-16),
        "finite differences should be visibly less accurate: {e_fd:e}"
    );
    assert!(
        e_fd < 1e-4,
        "the finite-difference cross-check must still agree roughly: {e_fd:e}"
    );
}

#[test]
fn thesis_model_and_offset_model_agree_when_the_offset_is_zero() {
    let p = ThesisParameters::thesis_bicycle();
    assert_eq!(p.fork_com_offset, 0.0);
    let a = canonical_matrices::<ThesisWhipple>(|s| p.get(s)).unwrap();
    let b = canonical_matrices::<WhippleOffset>(|s| p.get(s)).unwrap();
    for (x, y) in [(a.m0, b.m0), (a.c1, b.c1), (a.k0, b.k0), (a.k2, b.k2)] {
        assert!((x - y).amax() <= 1e-13 * x.amax(), "{x} vs {y}");
    }
    assert_eq!(canonical_of(&p).unwrap(), a);
}

#[test]
fn cli_stability_of_the_benchmark_prints_the_published_speeds() {
    let out = bikedyn(&["stability", "--bike", "benchmark", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!((v["weave_speed"].as_f64().unwrap() - 4.29238253634111).abs() < 1e-10);
    assert!((v["capsize_speed"].as_f64().unwrap() - 6.02426201538837).abs() < 1e-10);
    let iv = v["stable_intervals"].as_array().unwrap();
    assert_eq!(iv.len(), 1);
}
