//! J. K. Moore's (2012) leaning-rider parameter set, as bicycleparameters
//! names it (`MooreRiderLean2012ParameterSet`), read and converted to the
//! benchmark form and the `rider_lean` model's rider
//! (`bikedyn_runtime::parameters::moore`).
//!
//! The independent check: the eigenvalues of bicycleparameters 1.5.2's
//! `MooreRiderLean2012Model` (Moore's own Autolev derivation, its 12-state
//! linear model restricted to roll, steer, lean and their rates) for the
//! committed set `tests/data/MooreRiderLean2012BrowserJason.txt`, quoted
//! below; bikedyn's generated `rider_lean` must give them from the
//! converted parameters. Then the rigid-rider limit, and the errors.

use crate::common::*;
use bikedyn::bicycle::Bicycle;
use bikedyn::runtime::eigen::{eigen_sweep_of, EigenSweep};
use nalgebra::Complex;

const FIXTURE: &str = "MooreRiderLean2012BrowserJason.txt";

/// Eigenvalues (1/s) of `MooreRiderLean2012Model(MooreRiderLean2012ParameterSet(p))`,
/// `p` the fixture's values, from `form_state_space_matrices(v=v)`
/// restricted to the states q4, q7, q9, u4, u7, u9 (the yaw, positions and
/// wheel angles do not enter them), by numpy's `eigvals`, bicycleparameters
/// 1.5.2. Sorted by real, then imaginary part.
const BICYCLEPARAMETERS: [(f64, [(f64, f64); 6]); 5] = [
    (
        1.0,
        [
            (-23.679280706258744, 0.0),
            (-6.819513437643447, 0.0),
            (-2.900681076119194, 0.0),
            (-0.37211891505358424, 0.0),
            (3.4061346893658273, -0.6465916151287774),
            (3.4061346893658273, 0.6465916151287774),
        ],
    ),
    (
        3.0,
        [
            (-22.827080825207233, 0.0),
            (-9.876510402239079, 0.0),
            (-2.880284913783061, 0.0),
            (-0.3751578216927288, 0.0),
            (1.899186268145411, -1.8745770502563563),
            (1.899186268145411, 1.8745770502563563),
        ],
    ),
    (
        5.0,
        [
            (-21.60739568066448, 0.0),
            (-13.31242863636422, 0.0),
            (-1.4316802913863629, 0.0),
            (-0.39718762394152113, 0.0),
            (-0.3066529322813042, -2.471021982448),
            (-0.3066529322813042, 2.471021982448),
        ],
    ),
    (
        7.0,
        [
            (-18.525158847179178, -0.24103833501648506),
            (-18.525158847179178, 0.24103833501648506),
            (-2.5972654482070245, -4.505515079359021),
            (-2.5972654482070245, 4.505515079359021),
            (-0.33968123829001606, 0.0),
            (0.021195061855310497, 0.0),
        ],
    ),
    (
        9.0,
        [
            (-19.475122601712457, -2.474906860570591),
            (-19.475122601712457, 2.474906860570591),
            (-4.323164298509896, -6.391135170646185),
            (-4.323164298509896, 6.391135170646185),
            (-0.3538445702570873, 0.0),
            (0.18574693320672084, 0.0),
        ],
    ),
];

fn sweep(bike: &Bicycle, speeds: &[f64]) -> EigenSweep {
    eigen_sweep_of(&bike.linear_with(None).unwrap(), speeds).unwrap()
}

/// Every eigenvalue at each speed (the four modes and the rider's),
/// sorted by real, then imaginary part.
fn all_sorted(s: &EigenSweep) -> Vec<Vec<Complex<f64>>> {
    s.points
        .iter()
        .map(|p| {
            let mut v: Vec<Complex<f64>> = p.eigenvalues.iter().chain(&p.extra_eigenvalues).copied().collect();
            v.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
            v
        })
        .collect()
}

/// Largest distance, relative to max(1, |lambda|), from the quoted
/// eigenvalues.
fn difference_from_bicycleparameters(bike: &Bicycle) -> f64 {
    let speeds: Vec<f64> = BICYCLEPARAMETERS.iter().map(|(v, _)| *v).collect();
    let ours = all_sorted(&sweep(bike, &speeds));
    let mut worst = 0.0f64;
    for ((v, theirs), mine) in BICYCLEPARAMETERS.iter().zip(&ours) {
        assert_eq!(mine.len(), 6, "{v} m/s: {mine:?}");
        for (&(re, im), m) in theirs.iter().zip(mine) {
            let t = Complex::new(re, im);
            worst = worst.max((m - t).norm() / t.norm().max(1.0));
        }
    }
    worst
}

/// The error of reading `text` as the file `name`.
fn refused(name: &str, text: &str) -> String {
    let read: Result<Bicycle, _> = Bicycle::from_file_text_in(name, text);
    read.unwrap_err().to_string()
}

fn fixture_text() -> String {
    std::fs::read_to_string(fixture(FIXTURE)).unwrap()
}

/// The fixture's `name = value` pairs as numbers: its two sums (`d4`,
/// `l6`, written as the source writes them) computed here in the order the
/// text form and bicycleparameters evaluate them.
fn fixture_values() -> Vec<(String, f64)> {
    let rr = 0.340958858855;
    let d4 = -1.011421527346159 + rr;
    fixture_text()
        .lines()
        .filter_map(|l| {
            let l = l.split('#').next()?.trim();
            let (k, v) = l.split_once('=')?;
            let k = k.trim().to_string();
            let v = match k.as_str() {
                "d4" => d4,
                "l6" => -1.283035074598082 + rr - d4,
                _ => v.trim().parse().unwrap(),
            };
            Some((k, v))
        })
        .collect()
}

#[test]
fn moores_leaning_rider_set_has_the_eigenvalues_of_bicycleparameters_model() {
    let bike = Bicycle::resolve(&fixture_arg(FIXTURE)).unwrap();
    assert_eq!(bike.model(None).unwrap().name, "rider_lean");
    // The rear frame with the legs is the benchmark's rear body.
    assert!((bike.value("mB").unwrap() - 33.044).abs() < 1e-12);
    assert!((bike.value("w").unwrap() - 1.121).abs() < 1e-12);
    assert_eq!(bike.effects["k_lean"], 128.0);
    assert_eq!(bike.effects["c_lean"], 50.0);
    let error = difference_from_bicycleparameters(&bike);
    println!("largest relative difference from bicycleparameters' MooreRiderLean2012Model: {error:.1e}");
    assert!(error < 1e-10, "{error:e}");
}

#[test]
fn moores_set_reads_alike_as_toml_and_as_named_values() {
    let text_form = all_sorted(&sweep(&Bicycle::resolve(&fixture_arg(FIXTURE)).unwrap(), &[2.0, 6.0]));
    let values = fixture_values();
    // TOML, told by its keys, and with the form named.
    for header in ["", "form = \"MooreRiderLean2012\"\n"] {
        let mut toml = header.to_string();
        for (k, v) in &values {
            toml.push_str(&format!("{k} = {v:?}\n"));
        }
        let bike: Bicycle = Bicycle::from_file_text_in("moore.toml", &toml).unwrap();
        assert_eq!(all_sorted(&sweep(&bike, &[2.0, 6.0])), text_form, "{header}");
    }
    // A dict (the Python package's path), with bicycleparameters' `v`.
    let dict: Vec<(String, f64, Option<f64>)> = values.iter().map(|(k, v)| (k.clone(), *v, None)).collect();
    let bike = Bicycle::from_values("moore dict", &dict).unwrap();
    assert_eq!(bike.model(None).unwrap().name, "rider_lean");
    assert_eq!(all_sorted(&sweep(&bike, &[2.0, 6.0])), text_form);
    // Without the rider's keys: Moore's rigid-rider Whipple bicycle
    // (bicycleparameters' Moore2012ParameterSet), the benchmark model.
    let rider = ["d4", "l5", "l6", "mg", "ig11", "ig22", "ig31", "ig33", "k9", "c9"];
    let rigid: Vec<_> = dict
        .iter()
        .filter(|(k, _, _)| !rider.contains(&k.as_str()))
        .cloned()
        .collect();
    let bike = Bicycle::from_values("moore whipple", &rigid).unwrap();
    assert!(bike.effects.is_empty());
    assert_ne!(bike.model(None).unwrap().name, "rider_lean");
}

#[test]
fn a_stiffly_held_moore_rider_gives_the_rigid_rider_bicycle() {
    // Moore's set with k9 = 1e9 N m/rad against the benchmark-form bicycle
    // whose rear body is C and G together (parallel-axis theorem, in the
    // benchmark axes: x forward, z down from the rear contact).
    let mut dict: Vec<(String, f64, Option<f64>)> = fixture_values().into_iter().map(|(k, v)| (k, v, None)).collect();
    for (k, v, _) in dict.iter_mut() {
        match k.as_str() {
            "k9" => *v = 1e9,
            "c9" => *v = 0.0,
            _ => {}
        }
    }
    let stiff = Bicycle::from_values("stiff rider", &dict).unwrap();
    let get = |s: &str| stiff.value(s).unwrap();
    let r = |s: &str| stiff.effects[s];
    let (m1, x1, z1) = (get("mB"), get("xB"), get("zB"));
    // The upper body in benchmark axes: z down, so heights and the xz
    // product change sign.
    let (m2, x2, z2) = (r("m6"), r("xL") + r("x6"), -(get("rR") + r("zL") + r("z6")));
    let m = m1 + m2;
    let (x, z) = ((m1 * x1 + m2 * x2) / m, (m1 * z1 + m2 * z2) / m);
    let shift = |m: f64, dx: f64, dz: f64| (m * dz * dz, m * (dx * dx + dz * dz), m * dx * dx, -m * dx * dz);
    let (s1, s2) = (shift(m1, x1 - x, z1 - z), shift(m2, x2 - x, z2 - z));
    let combined = [
        ("mB", m),
        ("xB", x),
        ("zB", z),
        ("IBxx", get("IBxx") + r("I6x") + s1.0 + s2.0),
        ("IByy", get("IByy") + r("I6y") + s1.1 + s2.1),
        ("IBzz", get("IBzz") + r("I6z") + s1.2 + s2.2),
        ("IBxz", get("IBxz") - r("I6xz") + s1.3 + s2.3),
    ];
    let rigid_values: Vec<(String, f64, Option<f64>)> = bikedyn_runtime::parameters::BenchmarkParameters::SYMBOLS
        .iter()
        .map(|s| {
            let v = combined
                .iter()
                .find(|(k, _)| k == s)
                .map_or_else(|| get(s), |(_, v)| *v);
            (s.to_string(), v, None)
        })
        .collect();
    let rigid = Bicycle::from_values("rigid rider", &rigid_values).unwrap();
    let speeds = [1.0, 3.0, 5.0, 7.0, 9.0];
    let (a, b) = (sweep(&stiff, &speeds), sweep(&rigid, &speeds));
    let mut error = 0.0f64;
    for (p, q) in a.points.iter().zip(&b.points) {
        assert_eq!(p.extra_eigenvalues.len(), 2);
        let sorted = |e: &[Complex<f64>; 4]| {
            let mut v = e.to_vec();
            v.sort_by(|x, y| x.re.total_cmp(&y.re).then(x.im.total_cmp(&y.im)));
            v
        };
        for (x, y) in sorted(&p.eigenvalues).into_iter().zip(sorted(&q.eigenvalues)) {
            error = error.max((x - y).norm());
        }
    }
    println!("stiff Moore rider against the rigid-rider bicycle: {error:.1e} 1/s");
    // The spring's compliance, as in leaning_rider.rs (8.9e-7 at 1e9 there).
    assert!(error < 1e-5, "{error:e}");
}

#[test]
fn files_that_are_not_moore_sets_keep_their_own_errors() {
    // Basu-Mandal's benchmark in Moore's coordinates, with the benchmark's
    // rF, rR, mF beside his d1, l1 and capitalised masses: a benchmark file
    // with unknown keys, the first named with its line and why.
    let e = Bicycle::resolve(&fixture_arg("basu_mandal2007.toml"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("basu_mandal2007.toml:19: unknown parameter `d1`"), "{e}");
    assert!(e.contains("MooreRiderLean2012ParameterSet"), "{e}");
    // A benchmark text file with one stray Moore key: that key, its line.
    let mut text = std::fs::read_to_string(fixture("BluenosePar.txt")).unwrap();
    text.push_str("\nk9 = 100\n");
    let e = refused("Bluenose.txt", &text);
    assert!(e.contains("unknown parameter `k9`"), "{e}");
}

#[test]
fn a_moore_set_with_a_key_missing_or_wrong_is_refused_naming_the_file_line_and_key() {
    let without = |key: &str| -> String {
        fixture_text()
            .lines()
            .filter(|l| !l.starts_with(&format!("{key} =")))
            .collect::<Vec<_>>()
            .join("\n")
    };
    // A rider key missing: the rider is partial.
    let e = refused("rider.txt", &without("l5"));
    assert!(
        e.contains("rider.txt") && e.contains("`l5`") && e.contains("Moore"),
        "{e}"
    );
    // A bicycle key missing.
    let e = refused("rider.txt", &without("ic31"));
    assert!(e.contains("missing 1 of Moore's parameters: `ic31`"), "{e}");
    // An unknown key, a negative mass, an uncertainty: key and line.
    let text = fixture_text();
    let line_of = |key: &str| text.lines().position(|l| l.starts_with(&format!("{key} ="))).unwrap() + 1;
    let e = refused("rider.txt", &format!("{text}lean = 3\n"));
    assert!(
        e.contains(&format!(
            "rider.txt:{}: unknown parameter `lean`",
            text.lines().count() + 1
        )),
        "{e}"
    );
    let e = refused("rider.txt", &text.replace("mg = 48.816", "mg = -48.816"));
    assert!(
        e.contains("`mg`") && e.contains(&format!("line {}", line_of("mg"))),
        "{e}"
    );
    let e = refused("rider.txt", &text.replace("k9 = 128.0", "k9 = 128.0+/-5"));
    assert!(
        e.contains(&format!("rider.txt:{}", line_of("k9"))) && e.contains("`k9`"),
        "{e}"
    );
    // The rider given twice: in Moore's keys and in rider_lean's.
    let e = refused("rider.txt", &format!("{text}k_lean = 100\n"));
    assert!(e.contains("twice") && e.contains("k_lean"), "{e}");
}

#[test]
fn the_command_line_runs_moores_set_through_the_leaning_rider_model() {
    let stability = ok_json(&["stability", "--bike", &fixture_arg(FIXTURE), "--json"]);
    assert_eq!(stability["model"], "rider_lean", "{stability}");
    // As bicycleparameters' eigenvalues have it: the oscillatory mode
    // turns stable between 3 and 5 m/s, a real root unstable between 5 and
    // 7 m/s (4.806 and 6.893 m/s).
    let band = &stability["stable_intervals"][0];
    let (from, to) = (band[0].as_f64().unwrap(), band[1].as_f64().unwrap());
    assert!((3.0..5.0).contains(&from) && (5.0..7.0).contains(&to), "{stability}");
    // Those crossings are the weave's and capsize's (Meijaard et al. 2007's
    // definitions: the oscillatory mode turning stable, the real root
    // turning unstable), whatever the rider's lean does between them (its
    // slow root merges with capsize near 5.5 m/s).
    assert!(
        (stability["weave_speed"].as_f64().unwrap() - from).abs() < 1e-9,
        "{stability}"
    );
    assert!(
        (stability["capsize_speed"].as_f64().unwrap() - to).abs() < 1e-9,
        "{stability}"
    );
    // `params show` writes the converted bicycle, the rider's keys with
    // it, as a file that reads back as the same bicycle.
    let shown = text(&bikedyn(&["params", "show", "--bike", &fixture_arg(FIXTURE)]).stdout);
    assert!(
        shown.contains("k_lean = 128.0") && shown.contains("I6xz = -0.002113501449812"),
        "{shown}"
    );
    let file = scratch("moore-rider-lean").join("converted.toml");
    std::fs::write(&file, &shown).unwrap();
    let again = ok_json(&["stability", "--bike", file.to_str().unwrap(), "--json"]);
    assert_eq!(again["model"], "rider_lean", "{again}");
    let band_again = &again["stable_intervals"][0];
    assert!((band_again[0].as_f64().unwrap() - from).abs() < 1e-9, "{again}");
    assert!((band_again[1].as_f64().unwrap() - to).abs() < 1e-9, "{again}");
}

#[test]
fn moores_leaning_rider_modes_are_named_as_the_rigid_riders_are() {
    // Below the weave speed the oscillatory pair is the weave, the larger
    // real root capsize; at standstill the weave is the two positive real
    // roots that merge into it (as on the benchmark bicycle), and above
    // the capsize speed the root that crossed is capsize.
    let eig = ok_json(&["eig", "--bike", &fixture_arg(FIXTURE), "--speeds", "0:8:0.5", "--json"]);
    let points = eig.as_array().unwrap_or_else(|| panic!("{eig}"));
    for p in points {
        let v = p["v"].as_f64().unwrap();
        let modes: Vec<&str> = p["modes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m.as_str().unwrap())
            .collect();
        let values: Vec<(f64, f64)> = p["eigenvalues"]
            .as_array()
            .unwrap()
            .iter()
            .map(|z| (z[0].as_f64().unwrap(), z[1].as_f64().unwrap()))
            .collect();
        let weave: Vec<(f64, f64)> = (0..4).filter(|&k| modes[k] == "weave").map(|k| values[k]).collect();
        assert_eq!(weave.len(), 2, "{v} m/s: {modes:?} {values:?}");
        if v == 0.0 {
            assert!(
                weave.iter().all(|z| z.0 > 0.0 && z.1 == 0.0),
                "{v} m/s: {modes:?} {values:?}"
            );
        } else if (1.0..=5.0).contains(&v) {
            assert!(weave.iter().all(|z| z.1 != 0.0), "{v} m/s: {modes:?} {values:?}");
            assert!(
                modes.contains(&"capsize") && modes.contains(&"castering"),
                "{v} m/s: {modes:?}"
            );
        } else if v >= 7.0 {
            let k = modes
                .iter()
                .position(|m| *m == "capsize")
                .unwrap_or_else(|| panic!("{v} m/s: {modes:?}"));
            assert!(values[k].0 > 0.0 && values[k].1 == 0.0, "{v} m/s: {modes:?} {values:?}");
        }
    }
}
