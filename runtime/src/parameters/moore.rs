//! J. K. Moore's (2012) parameters of the Whipple bicycle with a leaning
//! rider, as bicycleparameters names them (`MooreRiderLean2012ParameterSet`;
//! without the rider's keys, `Moore2012ParameterSet`), converted on reading
//! to the benchmark form (Meijaard et al. 2007) and the leaning rider's
//! parameters of the `rider_lean` model.
//!
//! Moore's axes (his dissertation, *Human Control of a Bicycle*, UC Davis
//! 2012, and its `RiderLean.al`): ground axes x forward, y right, z down;
//! the rear frame C is pitched from them by the steer-axis tilt `lam` at
//! upright, so its axes `c1` (perpendicular to the steer axis) and `c3`
//! (along the steer axis, down) are the benchmark axes turned by `lam` about
//! y. Lengths from the rear wheel centre:
//!
//! - `d1`: rear wheel centre to the steer axis (along `c1`); `d2`: along the
//!   steer axis between the two offset lines; `d3`: steer axis to the front
//!   wheel centre (fork offset). `rr`, `rf`: wheel radii.
//! - `l1`, `l2`: rear frame (C) mass centre from the rear wheel centre, along
//!   `c1`, `c3`; `l3`, `l4`: front frame (E) mass centre from the front wheel
//!   centre, in the same axes at zero steer.
//! - `ic11, ic22, ic33, ic31`, `ie..`: tensors about the mass centres in
//!   those axes (`ic31` the tensor's entry); `id11, id22`, `if11, if22`:
//!   wheels (D rear, F front). Masses `mc, md, me, mf`.
//! - The rider's upper body G hinges on C about an axis that is horizontal
//!   and forward at upright, through the point `d4` straight below the rear
//!   wheel centre (negative: above it). `l5`, `l6`: G's mass centre from that
//!   point, forward and down; `ig11, ig22, ig33, ig31`: G's tensor in the
//!   upright axes (x forward, y right, z down); `mg` its mass. `k9`, `c9`:
//!   the hinge's passive stiffness (N m/rad) and damping (N m s/rad); the
//!   lean `q9` is positive to the right, like the roll.
//!
//! The conversion: `w`, `lam` from the front wheel centre, which is
//! `(d1 + d3, d2)` from the rear one in C's axes and `(w, rr - rf)` in the
//! ground axes; the trail from `d3 = -cos(lam) (c - rf tan(lam))`; mass
//! centres and tensors turned back by `lam` (`I = R^T I_C R`, `R` the
//! rotation by `lam` about y). The rider in `rider_lean`'s keys (upright
//! axes, x forward, z up): `xL = 0`, `zL = -d4`, `x6 = l5`, `z6 = -l6`,
//! `m6 = mg`, `I6x, I6y, I6z = ig11, ig22, ig33`, `I6xz = -ig31` (z turned
//! over), `k_lean = k9`, `c_lean = c9`. The bicycle it gives has the
//! eigenvalues of bicycleparameters' `MooreRiderLean2012Model` (an
//! independent derivation: Moore's Autolev equations) to about 1e-14
//! (`python/tests/test_bicycleparameters.py`).

use std::collections::BTreeMap;
use std::path::Path;

use super::{BenchmarkParameters, Origin, ParameterError, ParameterWarning, ThesisParameters};

/// The value of `form` that names this parameterization in a TOML file
/// (bicycleparameters' name of it); without it, the form is told by the
/// keys (see [`is_moore_set`]).
pub const MOORE_FORM: &str = "MooreRiderLean2012";

/// Moore's keys of the rigid-rider Whipple bicycle (bicycleparameters'
/// `Moore2012ParameterSet`, without its speed `v`).
pub const MOORE_WHIPPLE_SYMBOLS: [&str; 26] = [
    "d1", "d2", "d3", "g", "ic11", "ic22", "ic31", "ic33", "id11", "id22", "ie11", "ie22", "ie31", "ie33", "if11",
    "if22", "l1", "l2", "l3", "l4", "mc", "md", "me", "mf", "rf", "rr",
];

/// Moore's keys of the leaning rider, given all together (`c9` may be left
/// out: no damping) or not at all (a rigid rider).
pub const MOORE_RIDER_SYMBOLS: [&str; 10] = ["d4", "l5", "l6", "mg", "ig11", "ig22", "ig31", "ig33", "k9", "c9"];

/// The `rider_lean` model's parameters a Moore rider converts to.
pub const RIDER_LEAN_PARAMETERS: [&str; 11] = [
    "xL", "zL", "x6", "z6", "m6", "I6x", "I6y", "I6z", "I6xz", "k_lean", "c_lean",
];

/// Whether `name` is one of Moore's keys (or his speed `v`).
pub fn is_moore_symbol(name: &str) -> bool {
    name == "v" || MOORE_WHIPPLE_SYMBOLS.contains(&name) || MOORE_RIDER_SYMBOLS.contains(&name)
}

/// Whether `name` is a Moore key that names nothing in the benchmark and
/// thesis forms nor among the extra names of bicycleparameters' text files
/// (`g`, `v`, `d1`..`d4` are shared).
fn moore_only(name: &str) -> bool {
    is_moore_symbol(name)
        && !matches!(name, "g" | "v" | "d1" | "d2" | "d3" | "d4")
        && !BenchmarkParameters::SYMBOLS.contains(&name)
        && !ThesisParameters::SYMBOLS.contains(&name)
}

/// Whether a file (or dict) with the keys `names` holds Moore's parameters:
/// it has a key of Moore's alone (`l1`, `ic11`, `mc`, `rr`, `k9`, ...) and
/// no key of the benchmark or thesis forms other than the shared `g` and
/// `d4`. Other names (effect parameters) do not decide. A benchmark file
/// with one stray Moore key is therefore still a benchmark file, refused
/// naming that key.
pub fn is_moore_set<'a>(names: impl IntoIterator<Item = &'a str>) -> bool {
    let mut moore = false;
    for n in names {
        if moore_only(n) {
            moore = true;
        } else if !is_moore_symbol(n)
            && (BenchmarkParameters::SYMBOLS.contains(&n) || ThesisParameters::SYMBOLS.contains(&n))
        {
            return false;
        }
    }
    moore
}

/// The error for a Moore set that cannot be read or converted.
fn bad(path: &Path, line: Option<usize>, why: String) -> ParameterError {
    ParameterError::MooreSet {
        path: path.to_path_buf(),
        line,
        why,
    }
}

/// A Moore set converted: the benchmark-form bicycle (C as its rear body,
/// the lower rider with it) and, when the set has a leaning rider, the
/// `rider_lean` parameters ([`RIDER_LEAN_PARAMETERS`], in that order).
#[derive(Clone, Debug, PartialEq)]
pub struct MooreConversion {
    pub benchmark: BenchmarkParameters,
    pub rider: Option<Vec<(&'static str, f64)>>,
    pub warnings: Vec<ParameterWarning>,
}

/// Convert Moore's values (`name -> (value, line)`, every key one of
/// Moore's; `v` is kept aside with a warning) read from `path`: check them,
/// naming the key and its line, convert, and validate the benchmark set.
pub fn convert(values: &BTreeMap<String, (f64, usize)>, path: &Path) -> Result<MooreConversion, ParameterError> {
    let line_of = |k: &str| values.get(k).map(|&(_, l)| l);
    let origin = |k: &str| Origin::new(path, line_of(k));
    let mut warnings = Vec::new();
    if let Some(&(v, line)) = values.get("v") {
        warnings.push(ParameterWarning::ExtraField {
            field: "v".to_string(),
            value: v,
            line,
            meaning: "the nominal speed of bicycleparameters' sets; speeds are given to each analysis",
        });
    }
    let given_rider: Vec<&str> = MOORE_RIDER_SYMBOLS
        .iter()
        .copied()
        .filter(|k| values.contains_key(*k))
        .collect();
    let has_rider = !given_rider.is_empty();
    let missing: Vec<&str> = MOORE_WHIPPLE_SYMBOLS
        .iter()
        .copied()
        .filter(|k| !values.contains_key(*k))
        .collect();
    let missing_rider: Vec<&str> = MOORE_RIDER_SYMBOLS
        .iter()
        .copied()
        .filter(|k| has_rider && *k != "c9" && !values.contains_key(*k))
        .collect();
    let list = |ks: &[&str]| ks.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
    if !missing.is_empty() {
        return Err(bad(
            path,
            None,
            format!(
                "missing {} of Moore's parameters: {}{}",
                missing.len(),
                list(&missing),
                if missing_rider.is_empty() {
                    String::new()
                } else {
                    format!(", and of the leaning rider's: {}", list(&missing_rider))
                }
            ),
        ));
    }
    if !missing_rider.is_empty() {
        let (first, line) = (given_rider[0], line_of(given_rider[0]));
        return Err(bad(
            path,
            line,
            format!(
                "`{first}` gives a leaning rider, which also needs {} (or give none of the rider's keys {} for the rigid-rider bicycle)",
                list(&missing_rider),
                list(&MOORE_RIDER_SYMBOLS)
            ),
        ));
    }
    let get = |k: &str| values.get(k).map_or(0.0, |&(v, _)| v);
    for (k, &(v, _)) in values {
        if !v.is_finite() {
            return Err(ParameterError::NotFinite {
                field: k.clone(),
                value: v,
                origin: origin(k),
            });
        }
    }
    // Masses, radii, gravity and the diagonal moments: positive.
    let positive = [
        "g", "rr", "rf", "mc", "md", "me", "mf", "ic11", "ic22", "ic33", "id11", "id22", "ie11", "ie22", "ie33",
        "if11", "if22",
    ];
    let rider_positive = ["mg", "ig11", "ig22", "ig33"];
    for k in positive.iter().chain(if has_rider { &rider_positive[..] } else { &[] }) {
        let v = get(k);
        if !(v > 0.0) {
            return Err(ParameterError::NonPositive {
                field: k.to_string(),
                value: v,
                origin: origin(k),
            });
        }
    }
    for k in ["k9", "c9"] {
        let v = get(k);
        if v < 0.0 {
            return Err(bad(
                path,
                line_of(k),
                format!(
                    "`{k}` = {v:?}: a passive hip and trunk neither push the rider over nor feed energy in; it must be >= 0"
                ),
            ));
        }
    }
    let tensors: &[(&'static str, [&str; 3])] = &[
        ("rear frame (C)", ["ic11", "ic33", "ic31"]),
        ("front frame (E)", ["ie11", "ie33", "ie31"]),
        ("rider's upper body (G)", ["ig11", "ig33", "ig31"]),
    ];
    for (body, [xx, zz, xz]) in tensors.iter().take(if has_rider { 3 } else { 2 }) {
        let (ixx, izz, ixz) = (get(xx), get(zz), get(xz));
        let det = ixx * izz - ixz * ixz;
        if !(det > 0.0) {
            return Err(ParameterError::NonPhysicalInertia {
                body,
                ixx,
                izz,
                ixz,
                det,
                origin: origin(xz),
            });
        }
    }

    // Geometry: the front wheel centre is (d1 + d3, d2) from the rear one
    // in C's axes and (w, rr - rf) in the ground axes.
    let (rr, rf) = (get("rr"), get("rf"));
    let (d1, d2, d3) = (get("d1"), get("d2"), get("d3"));
    let (along, across) = (d1 + d3, d2);
    let reach2 = along * along + across * across - (rr - rf) * (rr - rf);
    if !(reach2 > 0.0) || !(along > 0.0) {
        return Err(bad(
            path,
            line_of("d1"),
            format!(
                "d1 + d3 = {along:?}, d2 = {d2:?}, rr = {rr:?}, rf = {rf:?} are no upright bicycle: the front wheel centre must be ahead of the rear one (d1 + d3 > 0), farther from it than the radii differ"
            ),
        ));
    }
    let w = reach2.sqrt();
    let lam = across.atan2(along) - (rr - rf).atan2(w);
    if !(lam.abs() < std::f64::consts::FRAC_PI_2) {
        return Err(bad(
            path,
            line_of("d2"),
            format!("d1, d2, d3 give a steer-axis tilt of {lam:?} rad, not within (-pi/2, pi/2)"),
        ));
    }
    let (s, c) = lam.sin_cos();
    let trail = (rf * s - d3) / c;
    // Ground components of a vector with C components (x', z').
    let back = |x: f64, z: f64| (x * c + z * s, -x * s + z * c);
    // A tensor in C's axes turned back to the ground axes: R^T I R.
    let tensor = |ixx: f64, izz: f64, ixz: f64| {
        (
            c * c * ixx + 2.0 * c * s * ixz + s * s * izz,
            s * s * ixx - 2.0 * c * s * ixz + c * c * izz,
            -c * s * ixx + (c * c - s * s) * ixz + c * s * izz,
        )
    };
    let (xb, zb) = back(get("l1"), get("l2"));
    let (xh, zh) = back(get("l3"), get("l4"));
    let (ibxx, ibzz, ibxz) = tensor(get("ic11"), get("ic33"), get("ic31"));
    let (ihxx, ihzz, ihxz) = tensor(get("ie11"), get("ie33"), get("ie31"));
    let bench: BTreeMap<&str, f64> = BTreeMap::from([
        ("w", w),
        ("c", trail),
        ("lam", lam),
        ("g", get("g")),
        ("rR", rr),
        ("mR", get("md")),
        ("IRxx", get("id11")),
        ("IRyy", get("id22")),
        ("xB", xb),
        ("zB", zb - rr),
        ("mB", get("mc")),
        ("IBxx", ibxx),
        ("IByy", get("ic22")),
        ("IBzz", ibzz),
        ("IBxz", ibxz),
        ("xH", w + xh),
        ("zH", zh - rf),
        ("mH", get("me")),
        ("IHxx", ihxx),
        ("IHyy", get("ie22")),
        ("IHzz", ihzz),
        ("IHxz", ihxz),
        ("rF", rf),
        ("mF", get("mf")),
        ("IFxx", get("if11")),
        ("IFyy", get("if22")),
    ]);
    let benchmark = BenchmarkParameters::from_lookup(|k| Ok::<f64, ParameterError>(bench[k]))?;
    let converted = benchmark
        .validate()
        .map_err(|e| bad(path, None, format!("converted to the benchmark form: {e}")))?;
    warnings.extend(converted);
    let rider = has_rider.then(|| {
        vec![
            ("xL", 0.0),
            ("zL", -get("d4")),
            ("x6", get("l5")),
            ("z6", -get("l6")),
            ("m6", get("mg")),
            ("I6x", get("ig11")),
            ("I6y", get("ig22")),
            ("I6z", get("ig33")),
            // Upright axes with z up: y and z both turn over, so does xz.
            ("I6xz", -get("ig31")),
            ("k_lean", get("k9")),
            ("c_lean", get("c9")),
        ]
    });
    Ok(MooreConversion {
        benchmark,
        rider,
        warnings,
    })
}

/// A Moore set read from a file, joined to the other values it gives
/// (`extras`: effect parameters, by name): its rider's parameters are added
/// to them, which must be among the `accepted` names (the registry's models
/// have a leaning rider) and not given in the file as well.
pub fn join_rider(
    conversion: &MooreConversion,
    extras: &mut BTreeMap<String, f64>,
    accepted: &[&str],
    path: &Path,
) -> Result<(), ParameterError> {
    let Some(rider) = &conversion.rider else {
        return Ok(());
    };
    if let Some(k) = RIDER_LEAN_PARAMETERS.iter().find(|k| extras.contains_key(**k)) {
        return Err(bad(
            path,
            None,
            format!("the file gives the leaning rider twice: in Moore's keys and as `{k}`; give one of them"),
        ));
    }
    if let Some((k, _)) = rider.iter().find(|(k, _)| !accepted.contains(k)) {
        return Err(bad(
            path,
            None,
            format!(
                "its leaning rider becomes the parameters {} of a leaning-rider model, and no model read here has `{k}`",
                RIDER_LEAN_PARAMETERS.join(", ")
            ),
        ));
    }
    for (k, v) in rider {
        extras.insert(k.to_string(), *v);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// bicycleparameters 1.5.2, `parameter_dicts.mooreriderlean2012_browser_jason`
    /// (BSD 2-clause): Moore's rider-lean set of the Browser bicycle with
    /// Jason's legs in C and his upper body as G, `d4` and `l6` evaluated.
    fn browser_jason() -> BTreeMap<String, (f64, usize)> {
        let rr = 0.340958858855;
        let d4 = -1.011421527346159 + rr;
        [
            ("c9", 0.0),
            ("d1", 0.9631492634872098),
            ("d2", 0.4338396131640938),
            ("d3", 0.0705000000001252),
            ("d4", d4),
            ("g", 9.81),
            ("ic11", 2.296859222953584),
            ("ic22", 2.9922715238),
            ("ic31", 0.01594448114273473),
            ("ic33", 1.5101858377464155),
            ("id11", 0.0904106601579),
            ("id22", 0.152467620286),
            ("ie11", 0.2811355367159554),
            ("ie22", 0.246138810935),
            ("ie31", 0.0063377219110826045),
            ("ie33", 0.06782113764394461),
            ("if11", 0.0883819364527),
            ("if22", 0.149389340425),
            ("ig11", 2.038073562525466),
            ("ig22", 1.692108544034995),
            ("ig31", 0.002113501449812),
            ("ig33", 1.100753962972129),
            ("k9", 0.0),
            ("l1", 0.47759794513190806),
            ("l2", -0.1680324796714025),
            ("l3", -0.07654646159268344),
            ("l4", -0.47166687226492093),
            ("l5", 0.231223496809401),
            ("l6", -1.283035074598082 + rr - d4),
            ("mc", 33.044),
            ("md", 3.11),
            ("me", 3.22),
            ("mf", 2.02),
            ("mg", 48.816),
            ("rf", 0.34352982332),
            ("rr", rr),
        ]
        .iter()
        .enumerate()
        .map(|(i, (k, v))| (k.to_string(), (*v, i + 1)))
        .collect()
    }

    #[test]
    fn moores_browser_set_is_bicycleparameters_benchmark_browser_with_legs() {
        // bicycleparameters' `meijaard2007_browser_jasonlegs`: the same
        // bicycle (Browser with Jason's legs) in the benchmark form, from
        // which Moore's set was made (dtk's benchmark_to_moore).
        let expected = [
            ("IBxx", 2.18917391377),
            ("IBxz", -0.27087131147),
            ("IByy", 2.9922715238),
            ("IBzz", 1.61787114693),
            ("IHxx", 0.253379594731),
            ("IHxz", -0.0720452391817),
            ("IHyy", 0.246138810935),
            ("IHzz", 0.0955770796289),
            ("c", 0.0685808540382),
            ("lam", 0.399680398707),
            ("mB", 33.044),
            ("w", 1.121),
            ("xB", 0.374570794542),
            ("xH", 0.866949640247),
            ("zB", -0.681592725778),
            ("zH", -0.748236400835),
            ("rR", 0.340958858855),
            ("rF", 0.34352982332),
        ];
        let c = convert(&browser_jason(), Path::new("browser.txt")).unwrap();
        for (k, v) in expected {
            let got = c.benchmark.get(k).unwrap();
            assert!((got - v).abs() < 1e-10, "{k}: {got} against {v}");
        }
        let rider: BTreeMap<_, _> = c.rider.unwrap().into_iter().collect();
        // The lean axis 1.0114 m above the ground over the rear wheel
        // centre, the upper body's mass centre 1.2830 m up, 0.2312 ahead.
        assert!((rider["zL"] - (1.011421527346159 - 0.340958858855)).abs() < 1e-14);
        assert!((rider["zL"] + rider["z6"] - (1.283035074598082 - 0.340958858855)).abs() < 1e-14);
        assert_eq!(rider["x6"], 0.231223496809401);
        assert_eq!(rider["I6xz"], -0.002113501449812);
    }

    #[test]
    fn a_set_is_moores_by_its_own_keys_alone() {
        let keys: Vec<String> = browser_jason().into_keys().collect();
        assert!(is_moore_set(keys.iter().map(String::as_str)));
        assert!(is_moore_set(["l1", "c_steer", "v", "g"]));
        // A benchmark file with a stray Moore key, or d1..d3 beside the
        // benchmark symbols (bicycleparameters' text files), is not.
        assert!(!is_moore_set(["w", "rR", "l1"]));
        assert!(!is_moore_set(["w", "d1", "d2", "d3"]));
        assert!(!is_moore_set(["Rt", "d4"]));
        assert!(!is_moore_set(["d1", "d4", "g"]));
    }

    #[test]
    fn a_partial_rider_and_a_bad_value_are_refused_naming_the_key_and_line() {
        let mut v = browser_jason();
        v.remove("l5");
        let e = convert(&v, Path::new("rider.txt")).unwrap_err().to_string();
        assert!(
            e.contains("rider.txt") && e.contains("`l5`") && e.contains("rider"),
            "{e}"
        );
        let mut v = browser_jason();
        v.insert("mg".into(), (-1.0, 34));
        let e = convert(&v, Path::new("rider.txt")).unwrap_err().to_string();
        assert!(e.contains("`mg`") && e.contains("line 34"), "{e}");
        let mut v = browser_jason();
        for k in MOORE_RIDER_SYMBOLS {
            v.remove(k);
        }
        let c = convert(&v, Path::new("rigid.txt")).unwrap();
        assert!(c.rider.is_none());
    }
}
