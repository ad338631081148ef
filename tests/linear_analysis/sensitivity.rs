//! Sensitivities of the critical speeds and eigenvalues (`bikedyn
//! sensitivity`): the exact derivatives against central differences of the
//! same quantities recomputed for perturbed bicycles, and against the
//! identities dimensional analysis imposes on the elasticities.

use bikedyn::bicycle::Bicycle;
use bikedyn::runtime::eigen::{critical_speeds, eigenvalues};
use bikedyn::runtime::parameters::Form;
use bikedyn::sensitivity::{sensitivity, Sensitivity, SensitivityError, SensitivityOptions};
use nalgebra::Complex;

fn of(bike: &str, form: Option<Form>, speed: Option<f64>) -> (Bicycle, Sensitivity) {
    let b = Bicycle::resolve(bike).unwrap();
    let s = sensitivity(
        &b,
        &SensitivityOptions {
            speed,
            form,
            ..SensitivityOptions::default()
        },
    )
    .unwrap();
    (b, s)
}

/// Relative step of the central differences, which are the five-point
/// stencil `(f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h`: its truncation
/// error is `h^4 f^(5) / 30`, about 1e-16 of the derivative at this step
/// even for the thesis bicycle's capsize speed, whose elasticity to the
/// wheelbase is about 6 (the three-point difference's `h^2 f^(3) / 6` was
/// 6e-7 of it there). The critical speeds are found to about 1e-13 m/s,
/// which the stencil turns into about 1.5e-13 / h, at most about 1e-8 on
/// an elasticity. The tolerance below (1e-6 on an elasticity, relative
/// above 1; the sizes are 1e-3 to 6) keeps a hundredfold margin.
const STEP: f64 = 1e-4;
const TOLERANCE: f64 = 1e-6;

/// The five-point central difference of `f` at `x` with step `h`.
fn central<T>(f: impl Fn(f64) -> T, x: f64, h: f64) -> T
where
    T: std::ops::Sub<Output = T> + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
{
    (f(x - 2.0 * h) - f(x + 2.0 * h) + (f(x + h) - f(x - h)) * 8.0) * (1.0 / (12.0 * h))
}

fn critical_speeds_match_central_differences(bike: &str, form: Option<Form>) {
    let (b, s) = of(bike, form, None);
    for (which, sens) in [("weave", s.weave_speed.as_ref()), ("capsize", s.capsize_speed.as_ref())] {
        let sens = sens.unwrap();
        assert_eq!(sens.derivatives.len(), 26);
        for d in &sens.derivatives {
            let h = STEP * d.value.abs().max(1e-2);
            let speed_at = |x: f64| {
                let c = b.with_parameter(d.parameter, x).unwrap().canonical().unwrap();
                let crit = critical_speeds(&c, 0.0, 10.0).unwrap();
                if which == "weave" {
                    crit.weave_speed.unwrap()
                } else {
                    crit.capsize_speed.unwrap()
                }
            };
            let fd = central(speed_at, d.value, h);
            let e_fd = d.value / sens.speed * fd;
            assert!(
                (e_fd - d.elasticity).abs() <= TOLERANCE * d.elasticity.abs().max(1.0)
                    && (fd - d.derivative).abs() <= 1e-5 * (1.0 + fd.abs()),
                "{bike}, {which} speed, {}: exact {} (elasticity {}), central difference {fd} (elasticity {e_fd})",
                d.parameter,
                d.derivative,
                d.elasticity
            );
        }
    }
}

#[test]
fn critical_speed_derivatives_of_the_benchmark_match_central_differences() {
    critical_speeds_match_central_differences("benchmark", None);
}

/// In its own (thesis) symbols, through the conversion to the benchmark
/// form, and in the benchmark symbols.
#[test]
fn critical_speed_derivatives_of_the_thesis_bicycle_match_central_differences() {
    let (_, s) = of("thesis", None, None);
    assert_eq!(s.parameter_form, "thesis");
    critical_speeds_match_central_differences("thesis", None);
    critical_speeds_match_central_differences("thesis", Some(Form::Benchmark));
}

/// Euler's theorem on homogeneous functions: a speed scales as
/// `sqrt(g L)` and does not change when every mass and inertia is scaled,
/// so the elasticity to `g` is 1/2, the masses' and inertias' sum to 0, and
/// the lengths' plus twice the inertias' sum to 1/2.
#[test]
fn elasticities_obey_dimensional_analysis() {
    let benchmark: [&[&str]; 3] = [
        &["w", "c", "rR", "rF", "xB", "zB", "xH", "zH"],
        &["mR", "mB", "mH", "mF"],
        &[
            "IRxx", "IRyy", "IBxx", "IByy", "IBzz", "IBxz", "IHxx", "IHyy", "IHzz", "IHxz", "IFxx", "IFyy",
        ],
    ];
    let thesis: [&[&str]; 3] = [
        &["Rt", "Rd", "x3", "z3", "x4", "z4", "x5", "z5", "d4"],
        &["m2", "m3", "m4", "m5"],
        &[
            "I2x", "I2y", "I3x", "I3y", "I3z", "I3zx", "I4x", "I4y", "I4z", "I4xz", "I5x", "I5y",
        ],
    ];
    for (bike, form, [lengths, masses, inertias]) in [
        ("benchmark", Form::Benchmark, benchmark),
        ("thesis", Form::Benchmark, benchmark),
        ("thesis", Form::Thesis, thesis),
        ("benchmark", Form::Thesis, thesis),
    ] {
        let (_, s) = of(bike, Some(form), None);
        for sens in [s.weave_speed.unwrap(), s.capsize_speed.unwrap()] {
            let e = |p: &str| sens.derivatives.iter().find(|d| d.parameter == p).unwrap().elasticity;
            let sum = |ps: &[&str]| ps.iter().map(|p| e(p)).sum::<f64>();
            assert!((e("g") - 0.5).abs() < 1e-12, "{bike}: e_g = {}", e("g"));
            assert!((sum(masses) + sum(inertias)).abs() < 1e-12, "{bike}: mass scaling");
            let l = sum(lengths) + 2.0 * sum(inertias);
            assert!((l - 0.5).abs() < 1e-12, "{bike}: length scaling gives {l}");
        }
    }
}

#[test]
fn eigenvalue_derivatives_match_central_differences() {
    let v = 5.0;
    let (b, s) = of("benchmark", None, Some(v));
    let e = s.eigenvalues.unwrap();
    assert_eq!(e.speed, v);
    let names: Vec<&str> = e.modes.iter().map(|m| m.mode).collect();
    assert_eq!(names, ["weave", "capsize", "castering"]);
    for m in &e.modes {
        let s0 = Complex::new(m.eigenvalue[0], m.eigenvalue[1]);
        for d in &m.derivatives {
            let h = STEP * d.value.abs().max(1e-2);
            let root = |x: f64| {
                let c = b.with_parameter(d.parameter, x).unwrap().canonical().unwrap();
                eigenvalues(&c, v)
                    .unwrap()
                    .into_iter()
                    .min_by(|a, b| (a - s0).norm().total_cmp(&(b - s0).norm()))
                    .unwrap()
            };
            let fd = central(root, d.value, h);
            let exact = Complex::new(d.derivative[0], d.derivative[1]);
            // On the scaled change p ds/dp (1/s), the same margins as above.
            assert!(
                ((fd - exact) * d.value).norm() <= 1e-5 * (1.0 + s0.norm()),
                "{} eigenvalue, {}: exact {exact}, central difference {fd}",
                m.mode,
                d.parameter
            );
        }
    }
}

#[test]
fn a_bicycle_with_an_effect_is_refused_with_the_reason() {
    let b = Bicycle::resolve("benchmark")
        .unwrap()
        .with_parameter("c_steer", 0.3)
        .unwrap();
    let e = sensitivity(&b, &SensitivityOptions::default()).unwrap_err();
    assert!(matches!(e, SensitivityError::NotCanonical { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("canonical form") && text.contains("c_steer"), "{text}");
}

#[test]
fn no_crossing_in_the_searched_speeds_is_an_error_saying_so() {
    let b = Bicycle::resolve("benchmark").unwrap();
    let e = sensitivity(
        &b,
        &SensitivityOptions {
            speed_max: 1.0,
            ..SensitivityOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(e, SensitivityError::NoCrossing { .. }), "{e}");
    // With a speed, the eigenvalues are still differentiated.
    let s = sensitivity(
        &b,
        &SensitivityOptions {
            speed_max: 1.0,
            speed: Some(3.0),
            ..SensitivityOptions::default()
        },
    )
    .unwrap();
    assert!(s.weave_speed.is_none() && s.capsize_speed.is_none() && s.eigenvalues.is_some());
}

/// The speeds' standard deviations from a file's `+/-` values: the first-
/// order sum `sum (dv/dp sd_p)^2` with the exact derivatives, against the
/// same sum with five-point central differences; the shares add to one.
#[test]
fn speed_standard_deviations_propagate_the_files_uncertainties() {
    use bikedyn::sensitivity::speed_uncertainties;
    let file = crate::common::fixture_arg("Balanceassistv1Benchmark.txt");
    let b = Bicycle::resolve(&file).unwrap();
    let u = speed_uncertainties(&b, &SensitivityOptions::default())
        .unwrap()
        .expect("the file gives standard deviations");
    for (which, x) in [("weave", u.weave_speed.unwrap()), ("capsize", u.capsize_speed.unwrap())] {
        let mut variance = 0.0;
        for (symbol, &sd) in &b.uncertainties {
            let p = b.value(symbol).unwrap();
            let h = STEP * p.abs().max(1e-2);
            let speed_at = |x: f64| {
                let c = b.with_parameter(symbol, x).unwrap().canonical().unwrap();
                let crit = critical_speeds(&c, 0.0, 10.0).unwrap();
                if which == "weave" {
                    crit.weave_speed.unwrap()
                } else {
                    crit.capsize_speed.unwrap()
                }
            };
            variance += (central(speed_at, p, h) * sd).powi(2);
        }
        let sd_fd = variance.sqrt();
        assert!(
            (x.standard_deviation - sd_fd).abs() <= 1e-6 * sd_fd,
            "{which}: {} vs {sd_fd}",
            x.standard_deviation
        );
        assert_eq!(x.shares.len(), b.uncertainties.len());
        assert!((x.shares.iter().map(|s| s.share).sum::<f64>() - 1.0).abs() < 1e-12);
    }
    // A bicycle without standard deviations has none.
    let plain = Bicycle::resolve("benchmark").unwrap();
    assert!(speed_uncertainties(&plain, &SensitivityOptions::default())
        .unwrap()
        .is_none());
}

/// A parameter set (a sweep's value, an explorer's edit, Python's
/// `with_parameter`) is set, not measured: the file's `+/-` of that
/// parameter no longer counts, the others do. The speeds' standard
/// deviations equal those of the same file with that line written without
/// its `+/-`.
#[test]
fn a_parameter_set_drops_its_standard_deviation_and_keeps_the_others() {
    use bikedyn::sensitivity::speed_uncertainties;
    let file = crate::common::fixture_arg("BrowserBenchmark.txt");
    let b = Bicycle::resolve(&file).unwrap();
    let set = b.with_parameter("c", 0.1).unwrap();
    assert!(b.uncertainties.contains_key("c"));
    assert!(!set.uncertainties.contains_key("c"));
    assert_eq!(set.uncertainties.len(), b.uncertainties.len() - 1);

    let text = std::fs::read_to_string(&file).unwrap();
    let edited: String = text
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("c =") {
                "c = 0.1".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let dir = crate::common::scratch("set-drops-sd");
    let path = dir.join("BrowserTrail.txt");
    std::fs::write(&path, edited).unwrap();
    let from_file = Bicycle::resolve(path.to_str().unwrap()).unwrap();

    let opts = SensitivityOptions::default();
    let (a, f) = (
        speed_uncertainties(&set, &opts).unwrap().unwrap(),
        speed_uncertainties(&from_file, &opts).unwrap().unwrap(),
    );
    for (x, y) in [
        (a.weave_speed.unwrap(), f.weave_speed.unwrap()),
        (a.capsize_speed.unwrap(), f.capsize_speed.unwrap()),
    ] {
        assert!(
            (x.standard_deviation - y.standard_deviation).abs() <= 1e-12 * y.standard_deviation,
            "{} against {} from the file",
            x.standard_deviation,
            y.standard_deviation
        );
    }
}
