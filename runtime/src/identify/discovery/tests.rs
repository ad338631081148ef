//! The discovery search on tables made by the benchmark bicycle's own
//! equations with a term written in.

use super::*;
use nalgebra::{Matrix2, Matrix2x4};

/// The benchmark bicycle's canonical matrices (Meijaard et al. 2007,
/// Table 2 values rounded as published in its equation 12).
fn benchmark(v: f64) -> PlantAt {
    let m0 = Matrix2::new(80.81722, 2.31941332208709, 2.31941332208709, 0.29784188199686);
    let c1 = Matrix2::new(0.0, 33.86641391492494, -0.85035641456978, 1.68540397397560);
    let k0 = Matrix2::new(-80.95, -2.59951685249872, -2.59951685249872, -0.80329488458618);
    let k2 = Matrix2::new(0.0, 76.59734589573222, 0.0, 2.65431523794604);
    PlantAt {
        mass: m0,
        damping: c1 * v,
        stiffness: k0 * 9.81 + k2 * v * v,
        feedback: Matrix2x4::zeros(),
    }
}

/// The benchmark bicycle at the rows' speeds (as `rows_with` makes
/// them).
fn plant(_: &[f64]) -> Vec<Option<PlantAt>> {
    (0..9).map(|i| Some(benchmark(4.0 + 0.5 * i as f64))).collect()
}

fn rows_with(terms: &[Term], theta: &[f64]) -> Vec<Row> {
    (0..9)
        .map(|i| {
            let v = 4.0 + 0.5 * i as f64;
            let a = state_matrix(&benchmark(v), terms, theta, v).unwrap();
            let guide = state_matrix(&benchmark(v), &[], &[], v).unwrap();
            let g = weave_near(&guide, Complex::new(0.0, 100.0)).unwrap();
            let w = weave_near(&a, g).unwrap();
            Row {
                speed: v,
                measured: [w.re, w.im],
                stderr: [0.01, 0.01],
            }
        })
        .collect()
}

/// Measurement scatter of about one standard error (fixed
/// pseudo-random values).
fn scattered(mut rows: Vec<Row>) -> Vec<Row> {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for r in &mut rows {
        r.measured[0] += 0.02 * uniform();
        r.measured[1] += 0.02 * uniform();
    }
    rows
}

#[test]
fn a_term_on_the_rate_enters_the_damping_and_a_lag_adds_a_state() {
    let steer_damper = Term {
        equation: Coordinate::Steer,
        signal: Signal::Rate(Coordinate::Steer),
        speed_power: 0,
        lagged: false,
    };
    let p = benchmark(5.0);
    let a = state_matrix(&p, &[steer_damper], &[-2.0], 5.0).unwrap();
    let mut damped = p;
    damped.damping[(1, 1)] += 2.0;
    let b = state_matrix(&damped, &[], &[], 5.0).unwrap();
    assert!((&a - &b).norm() < 1e-12);
    let lagged = Term {
        lagged: true,
        ..steer_damper
    };
    assert_eq!(
        state_matrix(&p, &[lagged], &[-2.0, 0.1f64.ln()], 5.0).unwrap().nrows(),
        5
    );
    // A very fast lag is the direct term.
    let fast = state_matrix(&p, &[lagged], &[-2.0, 1e-7f64.ln()], 5.0).unwrap();
    let w = weave_near(&fast, Complex::new(-1.0, 5.0)).unwrap();
    let d = weave_near(&b, Complex::new(-1.0, 5.0)).unwrap();
    assert!((w - d).norm() < 1e-4, "{w} vs {d}");
}

#[test]
fn an_added_steer_inertia_is_found_with_its_value_and_the_control_gets_nothing() {
    let inertia = Term {
        equation: Coordinate::Steer,
        signal: Signal::Acceleration(Coordinate::Steer),
        speed_power: 0,
        lagged: false,
    };
    // Q = theta delta'': an added inertia of 0.05 kg m^2 is theta = -0.05.
    let rows = scattered(rows_with(&[inertia], &[-0.05]));
    let problem = Problem {
        rows: &rows,
        plant: &plant,
        library: &[],
        dictionary: Term::dictionary(false),
        max_terms: 2,
        max_folds: 10,
        folds: None,
        reference: None,
    };
    let d = discover(&problem).unwrap();
    assert_eq!(d.terms.len(), 1, "{:?}", d.terms);
    assert_eq!(d.terms[0].term, inertia);
    let (value, _) = d.terms[0].coefficient.unwrap();
    assert!((value + 0.05).abs() < 0.05 * 0.25, "{value}");
    let control = scattered(rows_with(&[], &[]));
    let d = discover(&Problem {
        rows: &control,
        ..problem
    })
    .unwrap();
    assert!(d.terms.is_empty(), "{:?}", d.terms);
}

/// On runs the library's values come from the time series and stay
/// fixed here. Where they moved the weave away from the measured
/// eigenvalues (here: an extra steer damping the rows do not have), a
/// term that takes the drift back beats them, but not the base model,
/// which predicts the rows within their scatter: with the base model as
/// the reference no term is a finding.
#[test]
fn a_term_that_only_takes_back_the_librarys_drift_is_no_finding() {
    fn drifted(_: &[f64]) -> Vec<Option<PlantAt>> {
        (0..9)
            .map(|i| {
                let mut p = benchmark(4.0 + 0.5 * i as f64);
                p.damping[(1, 1)] += 0.4;
                Some(p)
            })
            .collect()
    }
    let base: Vec<Option<[f64; 2]>> = rows_with(&[], &[]).iter().map(|r| Some(r.measured)).collect();
    let rows = scattered(rows_with(&[], &[]));
    let problem = Problem {
        rows: &rows,
        plant: &drifted,
        library: &[],
        dictionary: Term::dictionary(false),
        max_terms: 2,
        max_folds: 10,
        folds: None,
        reference: None,
    };
    let against_library = discover(&problem).unwrap();
    assert!(
        !against_library.terms.is_empty(),
        "the drift is large enough to be taken back"
    );
    let against_base = discover(&Problem {
        reference: Some(&base),
        ..problem
    })
    .unwrap();
    assert!(against_base.terms.is_empty(), "{:?}", against_base.terms);
    assert!(against_base
        .trials
        .iter()
        .any(|t| matches!(t.verdict, Verdict::NotBetterThanReference { .. })));
}
