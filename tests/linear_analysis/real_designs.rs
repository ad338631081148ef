//! Linear analysis of real and random designs: every real parameter file
//! and 10,000 random designs around them against the closed-form oracle of
//! Meijaard et al. (2007), skate wheels, continuous mode labels, mode shapes
//! and derived geometry, and the fast linearization against the two-speed
//! method. The fixtures in `tests/data` name their source and licence in
//! `tests/data/SOURCE.txt`.

use crate::common::*;
use bikedyn::bicycle::files::ParameterFile;
use bikedyn::bicycle::{canonical_of, Bicycle};
use bikedyn::runtime::closed_form::meijaard_canonical;
use bikedyn::runtime::eigen::critical_speeds;
use bikedyn::runtime::parameters::{BenchmarkParameters, ParameterSet, ThesisParameters};
use bikedyn::runtime::random::SplitMix64;
use bikedyn::runtime::CanonicalMatrices;
use nalgebra::Matrix2;
use std::path::PathBuf;

/// The real parameter files (HumanControl and BicycleParameters benchmark
/// sets), or an empty list with a skip message when `../shared` is absent.
fn real_files() -> Vec<PathBuf> {
    let Some(root) = shared("realdata/parameter_sets") else {
        return Vec::new();
    };
    let mut files = Vec::new();
    for entry in std::fs::read_dir(root.join("HumanControl_Par")).unwrap() {
        let p = entry.unwrap().path();
        if p.to_string_lossy().ends_with("Par.txt") {
            files.push(p);
        }
    }
    for entry in std::fs::read_dir(root.join("BicycleParameters_data/bicycles")).unwrap() {
        let dir = entry.unwrap().path();
        let name = dir.file_name().unwrap().to_string_lossy().to_string();
        let p = dir.join("Parameters").join(format!("{name}Benchmark.txt"));
        if p.exists() {
            files.push(p);
        }
    }
    files.sort();
    files
}

/// Benchmark-form bases of the design sweeps: the built-in bicycles, the
/// fixtures and every real file.
fn bases() -> Vec<(String, BenchmarkParameters)> {
    let mut out = vec![
        ("benchmark".to_string(), BenchmarkParameters::benchmark_bicycle()),
        (
            "thesis".to_string(),
            ThesisParameters::thesis_bicycle().to_benchmark().unwrap(),
        ),
    ];
    let mut files = vec![fixture("TmsBenchmark.txt"), fixture("BluenosePar.txt")];
    let real = real_files();
    if !real.is_empty() {
        assert_eq!(real.len(), 37, "37 real parameter files");
    }
    files.extend(real);
    for f in files {
        let (set, _) = ParameterSet::load(&f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        out.push((f.display().to_string(), set.to_benchmark().unwrap()));
    }
    out
}

/// Largest entry difference of two canonical forms relative to the largest
/// entry of each oracle matrix. The model and the closed form are two
/// rounding paths of some hundred operations each, so 1e-9 leaves a wide
/// margin over the ~1e-13 seen while catching any other root (which changes
/// entries at the 10 % level).
fn relative_difference(model: &CanonicalMatrices, oracle: &CanonicalMatrices) -> f64 {
    let pairs: [(&Matrix2<f64>, &Matrix2<f64>); 4] = [
        (&model.m0, &oracle.m0),
        (&model.c1, &oracle.c1),
        (&model.k0, &oracle.k0),
        (&model.k2, &oracle.k2),
    ];
    pairs
        .iter()
        .map(|(a, b)| {
            let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs())).max(1e-12);
            (*a - *b).iter().fold(0.0f64, |m, x| m.max(x.abs())) / scale
        })
        .fold(0.0, f64::max)
}

/// A front wheel of radius 5 m (and everything from 0.5
/// to 5 m) gives Meijaard's closed form, not the matrices of another root.
#[test]
fn large_front_wheel_matches_closed_form() {
    for k in 1..=10 {
        let mut b = BenchmarkParameters::benchmark_bicycle();
        b.front_wheel_radius = 0.5 * k as f64;
        let model = canonical_of(&b.to_thesis().unwrap()).unwrap();
        let oracle = meijaard_canonical(&b);
        let d = relative_difference(&model, &oracle);
        assert!(d < 1e-9, "rF = {}: relative difference {d:e}", b.front_wheel_radius);
    }
    let mut b = BenchmarkParameters::benchmark_bicycle();
    b.front_wheel_radius = 5.0;
    let model = canonical_of(&b.to_thesis().unwrap()).unwrap();
    // The closed-form figures.
    assert!((model.m0[(0, 0)] - 155.44972).abs() < 1e-9);
    assert!((model.k2[(0, 1)] - 88.91073055670).abs() < 1e-8);
}

/// A thesis file with `z5 = +5` (front wheel centre 5 m
/// along the steer axis) is linearized about its physical root.
#[test]
fn thesis_z5_plus_5_matches_closed_form() {
    let mut t = ThesisParameters::thesis_bicycle();
    t.front_wheel_z = 5.0;
    let model = canonical_of(&t).unwrap();
    let oracle = meijaard_canonical(&t.to_benchmark().unwrap());
    let d = relative_difference(&model, &oracle);
    assert!(d < 1e-9, "relative difference {d:e}");
}

/// A random design around `b`, over wide ranges: wheelbase x0.6-1.6, trail
/// -0.2..0.4 m, steer tilt -1.2..1.4 rad, radii x0.2-3 (front up to 5 m; a
/// point-mass skate wheel 5 % of the time), masses and tensors x0.3-3 (which keeps
/// them positive definite), mass centres moved by up to half a wheelbase.
fn random_design(b: &BenchmarkParameters, rng: &mut SplitMix64) -> BenchmarkParameters {
    let mut d = *b;
    d.wheelbase *= rng.uniform(0.6, 1.6);
    d.trail = rng.uniform(-0.2, 0.4);
    d.steer_axis_tilt = rng.uniform(-1.2, 1.4);
    d.rear_wheel_radius = (b.rear_wheel_radius.max(0.2) * rng.uniform(0.2, 3.0)).min(5.0);
    d.front_wheel_radius = if rng.next_f64() < 0.2 {
        rng.uniform(0.02, 5.0)
    } else {
        b.front_wheel_radius.max(0.2) * rng.uniform(0.2, 3.0)
    };
    if rng.next_f64() < 0.05 {
        d.rear_wheel_radius = 0.0;
        d.rear_wheel_ixx = 0.0;
        d.rear_wheel_iyy = 0.0;
    }
    if rng.next_f64() < 0.05 {
        d.front_wheel_radius = 0.0;
        d.front_wheel_ixx = 0.0;
        d.front_wheel_iyy = 0.0;
    }
    let s = rng.uniform(0.3, 3.0);
    d.rear_wheel_mass *= s;
    d.rear_wheel_ixx *= s;
    d.rear_wheel_iyy *= s;
    let s = rng.uniform(0.3, 3.0);
    d.front_wheel_mass *= s;
    d.front_wheel_ixx *= s;
    d.front_wheel_iyy *= s;
    let s = rng.uniform(0.3, 3.0);
    d.rear_frame_mass *= s;
    d.rear_frame_ixx *= s;
    d.rear_frame_iyy *= s;
    d.rear_frame_izz *= s;
    d.rear_frame_ixz *= s;
    let s = rng.uniform(0.3, 3.0);
    d.front_frame_mass *= s;
    d.front_frame_ixx *= s;
    d.front_frame_iyy *= s;
    d.front_frame_izz *= s;
    d.front_frame_ixz *= s;
    let half = 0.5 * d.wheelbase;
    d.rear_frame_com_x += rng.uniform(-half, half);
    d.rear_frame_com_z += rng.uniform(-half, half);
    d.front_frame_com_x += rng.uniform(-half, half);
    d.front_frame_com_z += rng.uniform(-half, half);
    d.g = rng.uniform(1.0, 25.0);
    d
}

/// Property test: 10,000 random designs around the 37
/// real files and the built-in bicycles agree with Meijaard's closed form, or
/// are refused with an error; none is refused here, because every sampled
/// design is a valid bicycle.
#[test]
fn random_designs_match_closed_form() {
    let bases = bases();
    let mut rng = SplitMix64::new(20261123);
    let cases = 10_000;
    let mut worst = (0.0f64, String::new());
    for case in 0..cases {
        let (name, base) = &bases[case % bases.len()];
        let d = random_design(base, &mut rng);
        d.validate()
            .unwrap_or_else(|e| panic!("case {case} around {name}: invalid design {e}: {d:?}"));
        let t = d.to_thesis().unwrap();
        let model = canonical_of(&t).unwrap_or_else(|e| panic!("case {case} around {name}: {e}\n{d:?}"));
        let diff = relative_difference(&model, &meijaard_canonical(&d));
        assert!(
            diff < 1e-9,
            "case {case} around {name}: relative difference {diff:e}\n{d:?}"
        );
        if diff > worst.0 {
            worst = (diff, name.clone());
        }
    }
    eprintln!(
        "{cases} designs: worst relative difference {:e} (around {})",
        worst.0, worst.1
    );
}

/// The two-mass-skate bicycle (zero wheel radii, Kooijman
/// et al. 2011) is supported; its weave speed from the closed form is
/// 2.841008 m/s and it has no capsize speed below 10 m/s.
#[test]
fn two_mass_skate_bicycle() {
    let path = fixture("TmsBenchmark.txt");
    let bike = Bicycle::resolve(path.to_str().unwrap()).unwrap();
    let c = bike.canonical().unwrap();
    let oracle = meijaard_canonical(&bike.parameters.to_benchmark().unwrap());
    let d = relative_difference(&c, &oracle);
    assert!(d < 1e-9, "relative difference {d:e}");
    let crit = critical_speeds(&c, 0.0, 10.0).unwrap();
    let weave = crit.weave_speed.expect("a weave speed");
    assert!((weave - 2.841008).abs() < 5e-7, "weave {weave}");
    let oracle_weave = critical_speeds(&oracle, 0.0, 10.0).unwrap().weave_speed.unwrap();
    assert!((weave - oracle_weave).abs() < 1e-9);
}

/// A skate wheel with spin inertia is refused by name.
#[test]
fn skate_wheel_with_spin_inertia_is_refused() {
    let mut b = BenchmarkParameters::benchmark_bicycle();
    b.front_wheel_radius = 0.0;
    let msg = canonical_of(&b.to_thesis().unwrap()).unwrap_err().to_string();
    assert!(msg.contains("front wheel") && msg.contains("IFyy"), "{msg}");
}

// ------------------------------------------------------------------ point 7

use bikedyn::runtime::eigen::{eigen_sweep, CrossingKind, EigenPoint, Mode};
use nalgebra::Complex;

/// How many of each named mode a point carries: a real root counts 1 for its
/// label, a merged pair's two roots count 1/2 each for both components.
fn mode_census(p: &EigenPoint) -> Option<[f64; 3]> {
    let mut n = [0.0; 3];
    let idx = |m: Mode| match m {
        Mode::Weave => Some(0),
        Mode::Capsize => Some(1),
        Mode::Castering => Some(2),
        _ => None,
    };
    for m in p.modes {
        match m.components() {
            Some((a, b)) => {
                n[idx(a)?] += 0.5;
                n[idx(b)?] += 0.5;
            }
            None => n[idx(m)?] += 1.0,
        }
    }
    Some(n)
}

/// Largest displacement of the best matching (least squared distance) of
/// two equally long root lists.
fn matched_displacement(a: &[Complex<f64>], b: &[Complex<f64>]) -> f64 {
    fn perms(n: usize) -> Vec<Vec<usize>> {
        if n == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for p in perms(n - 1) {
            for k in 0..=p.len() {
                let mut q = p.clone();
                q.insert(k, n - 1);
                out.push(q);
            }
        }
        out
    }
    let mut best = (f64::INFINITY, 0.0);
    for p in perms(a.len()) {
        let cost: f64 = (0..a.len()).map(|i| (a[i] - b[p[i]]).norm_sqr()).sum();
        let dmax = (0..a.len()).map(|i| (a[i] - b[p[i]]).norm()).fold(0.0, f64::max);
        if cost < best.0 {
            best = (cost, dmax);
        }
    }
    best.1
}

/// Check that every named mode's trajectory is continuous over the sweep:
/// between consecutive speeds, the roots carrying a label move no more than
/// 4 times the largest displacement of the whole spectrum under its best
/// matching (the local slope), plus rounding; and every point accounts for
/// two weave roots, one capsize and one castering root (merged pairs count
/// for both). Returns a description of the first violation.
fn check_mode_continuity(points: &[EigenPoint]) -> Result<(), String> {
    for p in points {
        if let Some(n) = mode_census(p) {
            if n != [2.0, 1.0, 1.0] {
                return Err(format!(
                    "v = {}: modes {:?} do not account for every mode",
                    p.v, p.modes
                ));
            }
        }
    }
    for w in points.windows(2) {
        let (p, q) = (&w[0], &w[1]);
        let global = matched_displacement(&p.eigenvalues, &q.eigenvalues);
        let scale = 1.0 + p.eigenvalues.iter().map(|z| z.norm()).fold(0.0, f64::max);
        for label in p.modes {
            let a: Vec<_> = (0..4)
                .filter(|&k| p.modes[k] == label)
                .map(|k| p.eigenvalues[k])
                .collect();
            let b: Vec<_> = (0..4)
                .filter(|&k| q.modes[k] == label)
                .map(|k| q.eigenvalues[k])
                .collect();
            if a.len() != b.len() {
                continue; // a merge or a split at this step
            }
            let d = matched_displacement(&a, &b);
            if d > 4.0 * global + 1e-9 * scale {
                return Err(format!(
                    "{} jumps by {d:.4} between v = {} and v = {} (the spectrum moves by {global:.4}): {:?} -> {:?}",
                    label.name(),
                    p.v,
                    q.v,
                    a,
                    b
                ));
            }
        }
    }
    Ok(())
}

/// On the Bluenose recumbent (HumanControl) the labels
/// used to swap at 0.33-0.34 m/s (capsize +4.02 -> -0.96) and at 9.68-9.69
/// m/s; the root that goes unstable at 3.141 m/s was called weave with
/// frequency 0 and no capsize speed was reported.
#[test]
fn bluenose_labels_are_continuous_and_capsize_is_reported() {
    let bike = Bicycle::resolve(fixture("BluenosePar.txt").to_str().unwrap()).unwrap();
    let c = bike.canonical().unwrap();
    let speeds: Vec<f64> = (0..=1000).map(|k| k as f64 * 0.01).collect();
    let sweep = eigen_sweep(&c, &speeds).unwrap();
    check_mode_continuity(&sweep.points).unwrap();
    let crit = critical_speeds(&c, 0.0, 10.0).unwrap();
    let vc = crit.capsize_speed.expect("a capsize speed");
    assert!((vc - 3.1413834189).abs() < 1e-8, "{vc}");
    let first = &crit.crossings[0];
    assert_eq!((first.mode, first.kind), (Mode::Capsize, CrossingKind::RealRoot));
    // The oscillation that stabilizes at 8.117 m/s is a weave root merged
    // with the capsize root, named as such, and it is the weave speed.
    let hopf = crit
        .crossings
        .iter()
        .find(|x| x.kind == CrossingKind::ComplexPair)
        .unwrap();
    assert_eq!(hopf.mode, Mode::WeaveCapsize);
    assert!((hopf.speed - 8.1174493573).abs() < 1e-8);
    assert_eq!(crit.weave_speed, Some(hopf.speed));
}

/// On the thesis bicycle capsize and castering merge into
/// a complex pair from 0.19 to 2.55 m/s; the pair is `capsize-castering`
/// (it used to be two `capsize` roots, and castering vanished).
#[test]
fn capsize_castering_pair_is_named() {
    let c = Bicycle::resolve("thesis").unwrap().canonical().unwrap();
    let sweep = eigen_sweep(&c, &[0.1, 1.0, 2.5, 2.6]).unwrap();
    let count = |p: &EigenPoint, m: Mode| p.modes.iter().filter(|x| **x == m).count();
    assert_eq!(count(&sweep.points[0], Mode::Castering), 1);
    assert_eq!(count(&sweep.points[1], Mode::CapsizeCastering), 2);
    assert_eq!(count(&sweep.points[1], Mode::Capsize), 0);
    assert_eq!(count(&sweep.points[2], Mode::CapsizeCastering), 2);
    assert_eq!(count(&sweep.points[3], Mode::Castering), 1);
    assert_eq!(Mode::CapsizeCastering.name(), "capsize-castering");
}

/// Property test: over 10,000 random designs around the
/// real files, every named mode's trajectory over 0-10 m/s is continuous and
/// every mode is accounted for at every speed.
#[test]
fn random_designs_have_continuous_mode_labels() {
    let bases = bases();
    let mut rng = SplitMix64::new(720_261_123);
    let speeds: Vec<f64> = (0..=200).map(|k| k as f64 * 0.05).collect();
    let (mut checked, mut refused) = (0, 0);
    for case in 0..10_000 {
        let (name, base) = &bases[case % bases.len()];
        let d = random_design(base, &mut rng);
        let c = meijaard_canonical(&d);
        let sweep = match eigen_sweep(&c, &speeds) {
            Ok(s) => s,
            Err(e) => {
                if refused == 0 {
                    eprintln!("first refusal (case {case} around {name}): {e}");
                }
                refused += 1;
                continue;
            }
        };
        checked += 1;
        if let Err(e) = check_mode_continuity(&sweep.points) {
            panic!("case {case} around {name}: {e}\n{d:?}");
        }
    }
    eprintln!("{checked} designs checked, {refused} refused by the eigen analysis");
    // Before the anchor ladder was extended, the search gave up on 57 of these designs (the
    // quartic solver at an extreme ladder speed); one remains (mode
    // continuation does not converge for a two-mass-skate variant).
    assert!(checked >= 9_990, "{checked}");
}

/// A singular-Jacobian message states the pivot against
/// the matrix scale it was judged by (it used to read "singular ... (pivot
/// 1.000e0)", which contradicts itself without the scale).
#[test]
fn singular_message_states_its_scale() {
    use bikedyn::runtime::constraints::ConstraintError;
    let e = ConstraintError::SingularJacobian {
        what: "holonomic constraints",
        column: 1,
        pivot: 1.0,
        scale: 1e16,
    };
    let msg = e.to_string();
    assert!(
        msg.contains("1.000e0 is below 1e-14 times its largest entry 1.000e16"),
        "{msg}"
    );
    let e = bikedyn::runtime::eigen::EigenError::SingularMassMatrix { det: 1e-20, scale: 1.0 };
    assert!(e.to_string().contains("1e-12 times"), "{e}");
}

/// The mode shapes (roll normalised to 1) are eigenvectors:
/// `(M0 s^2 + v C1 s + g K0 + v^2 K2) [1, steer] = 0` for every eigenvalue of
/// the benchmark bicycle from 0 to 10 m/s.
#[test]
fn mode_shapes_solve_the_eigenproblem() {
    use bikedyn::report::output::mode_shape;
    let c = Bicycle::resolve("benchmark").unwrap().canonical().unwrap();
    let speeds: Vec<f64> = (0..=100).map(|k| k as f64 * 0.1).collect();
    for p in eigen_sweep(&c, &speeds).unwrap().points {
        for k in 0..4 {
            let s = p.eigenvalues[k];
            let shape = mode_shape(&p.eigenvectors[k]);
            assert_eq!((shape.roll_amplitude, shape.roll_phase), (1.0, 0.0));
            let u = [
                Complex::new(1.0, 0.0),
                Complex::from_polar(shape.steer_amplitude, shape.steer_phase),
            ];
            let (kk, cc) = (c.stiffness(p.v), c.damping(p.v));
            for i in 0..2 {
                let r: Complex<f64> = (0..2)
                    .map(|j| (s * s * c.m0[(i, j)] + s * cc[(i, j)] + kk[(i, j)]) * u[j])
                    .sum();
                let scale = (0..2)
                    .map(|j| (s * s * c.m0[(i, j)]).norm() + (s * cc[(i, j)]).norm() + kk[(i, j)].abs())
                    .sum::<f64>()
                    * (1.0 + shape.steer_amplitude);
                assert!(r.norm() <= 1e-9 * scale, "v = {}, s = {s}: residual {}", p.v, r.norm());
            }
        }
    }
}

/// The derived geometry agrees with the canonical matrices
/// of the generated model (an independent route): `M0[1][1] = IAll + 2 mu
/// IAlz + mu^2 ITzz` and `K0[0][0] = -mT hT`, for the built-ins, the
/// fixtures and every real file.
#[test]
fn derived_geometry_matches_the_model() {
    use bikedyn::runtime::geometry::DerivedGeometry;
    for (name, b) in bases() {
        let g = DerivedGeometry::of(&b);
        let c = canonical_of(&b.to_thesis().unwrap()).unwrap();
        let m11 = g.front_steer_inertia
            + 2.0 * g.trail_ratio * g.front_steer_z_product
            + g.trail_ratio * g.trail_ratio * g.total_izz;
        assert!(
            (m11 - c.m0[(1, 1)]).abs() <= 1e-10 * c.m0.amax(),
            "{name}: {m11} vs {}",
            c.m0[(1, 1)]
        );
        let k00 = -g.total_mass * g.total_com_height;
        assert!((k00 - c.k0[(0, 0)]).abs() <= 1e-10 * c.k0.amax(), "{name}");
    }
    let g = DerivedGeometry::of(&BenchmarkParameters::benchmark_bicycle());
    assert_eq!(g.total_mass, 94.0);
    assert!((g.total_com_height - 80.95 / 94.0).abs() < 1e-15);
    assert!((g.steer_axis_tilt_deg - 18.0).abs() < 1e-12);
}

/// The faster linearization (one full dual evaluation at
/// V = 1 plus the gravity-only stiffness at rest) gives the same canonical
/// matrices as the previous two full linearizations, on 500 random designs;
/// so does the standalone gravity-only stiffness at rest (`g K0`).
#[test]
fn fast_linearization_equals_two_speed_method() {
    use bikedyn::generated::{ThesisWhipple, WhippleOffset};
    use bikedyn::runtime::linearize::{
        canonical_matrices, canonical_matrices_two_speeds, parameter_vector, static_stiffness,
    };
    let bases = bases();
    let mut rng = SplitMix64::new(10);
    let mut checked = 0;
    for case in 0..500 {
        let (name, base) = &bases[case % bases.len()];
        let d = random_design(base, &mut rng);
        if d.rear_wheel_radius == 0.0 || d.front_wheel_radius == 0.0 {
            continue;
        }
        let t = d.to_thesis().unwrap();
        let (fast, slow) = if t.fork_com_offset == 0.0 {
            (
                canonical_matrices::<ThesisWhipple>(|s| t.get(s)).unwrap(),
                canonical_matrices_two_speeds::<ThesisWhipple>(|s| t.get(s)).unwrap(),
            )
        } else {
            (
                canonical_matrices::<WhippleOffset>(|s| t.get(s)).unwrap(),
                canonical_matrices_two_speeds::<WhippleOffset>(|s| t.get(s)).unwrap(),
            )
        };
        let diff = relative_difference(&fast, &slow);
        assert!(diff < 1e-12, "case {case} around {name}: {diff:e}");
        // The standalone gravity-only stiffness at rest gives g K0.
        let rest = if t.fork_com_offset == 0.0 {
            static_stiffness::<ThesisWhipple>(&parameter_vector::<ThesisWhipple>(|s| t.get(s), 0.0).unwrap())
        } else {
            static_stiffness::<WhippleOffset>(&parameter_vector::<WhippleOffset>(|s| t.get(s), 0.0).unwrap())
        }
        .unwrap();
        let g = t.g;
        let k0 = Matrix2::new(rest[(0, 0)], -rest[(0, 1)], -rest[(1, 0)], rest[(1, 1)]) / g;
        let scale = slow.k0.amax();
        assert!((k0 - slow.k0).amax() <= 1e-12 * scale, "case {case} around {name}");
        checked += 1;
    }
    assert!(checked > 400);
}
