//! Sweeps, output files and plots on the benchmark bicycle of
//! Meijaard, Papadopoulos, Ruina & Schwab (2007), "Linearized dynamics
//! equations for the balance and steer of a bicycle: a benchmark and review",
//! Proc. R. Soc. A 463:1955-1982, doi 10.1098/rspa.2007.1857
//! (canonical matrices of section 5.3, critical speeds of Table 2a; copied
//! from shared/reference/meijaard2007.toml, section [canonical]).

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use bikedyn_report::output::{
    eigen_sweep_csv_header, eigen_sweep_json, format_eigen_table, format_parameter_table, format_stability_map_table,
    parameter_sweep_json, save_eigen_sweep_csv, save_eigen_sweep_json, save_parameter_sweep_csv,
    save_stability_map_csv, save_stability_map_json, stability_map_json, write_atomic, write_eigen_sweep_csv,
    write_stability_map_csv, OutputError,
};
use bikedyn_report::plot::{plot_continuation, plot_stability_map, use_font, PlotError, PlotOptions};
use bikedyn_runtime::canonical::CanonicalMatrices;
use bikedyn_runtime::sweep::{
    linspace, no_progress, parameter_sweep, speed_sweep, stability_map, CellStage, MapQuantity, ParamAxis, SweepError,
    SweepOptions,
};
use nalgebra::Matrix2;

/// Canonical matrices of the benchmark bicycle (Meijaard et al. 2007, sec. 5.3).
fn benchmark() -> CanonicalMatrices {
    CanonicalMatrices {
        m0: Matrix2::new(80.81722, 2.31941332208709, 2.31941332208709, 0.29784188199686),
        c1: Matrix2::new(0.0, 33.86641391492494, -0.85035641456978, 1.6854039739756),
        k0: Matrix2::new(-80.95, -2.59951685249872, -2.59951685249872, -0.80329488458618),
        k2: Matrix2::new(0.0, 76.59734589573222, 0.0, 2.65431523794604),
        g: 9.81,
    }
}

// Table 2(a) of Meijaard et al. (2007).
const WEAVE_SPEED: f64 = 4.29238253634111;
const CAPSIZE_SPEED: f64 = 6.02426201538837;

/// Fresh empty directory for one test, removed when dropped.
struct TestDir(PathBuf);

impl std::ops::Deref for TestDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TestDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

fn test_dir(name: &str) -> TestDir {
    let d = std::env::temp_dir().join(format!("bikedyn-sweep-plot-{}-{name}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    TestDir(d)
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Structural JSON equality, numbers to 1e-12 relative (serde_json's default
/// float parser may differ from the printed value in the last bit).
fn assert_json_close(a: &serde_json::Value, b: &serde_json::Value) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-12 * x.abs().max(y.abs()).max(1.0), "{x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len());
            x.iter().zip(y).for_each(|(x, y)| assert_json_close(x, y));
        }
        (Value::Object(x), Value::Object(y)) => {
            assert_eq!(x.keys().collect::<Vec<_>>(), y.keys().collect::<Vec<_>>());
            x.iter().zip(y).for_each(|((_, x), (_, y))| assert_json_close(x, y));
        }
        _ => assert_eq!(a, b),
    }
}

/// Toy model mapping for grids: scale K2 by `a` and C1 by `b`.
fn scaled(a: f64, b: f64) -> Result<CanonicalMatrices, String> {
    if !(a.is_finite() && b.is_finite()) {
        return Err(format!("non-finite scale ({a}, {b})"));
    }
    let mut c = benchmark();
    c.k2 *= a;
    c.c1 *= b;
    Ok(c)
}

fn quiet(speed_min: f64, speed_max: f64) -> SweepOptions {
    SweepOptions::with_speed_range(speed_min, speed_max)
}

#[test]
fn sweep_speed_json_schema() {
    let speeds = linspace(0.0, 10.0, 101);
    let sweep = speed_sweep(&benchmark(), &speeds).unwrap();
    let json = eigen_sweep_json(&sweep);
    let list = json.as_array().expect("top level is a list");
    assert_eq!(list.len(), 101);
    for (obj, v) in list.iter().zip(&speeds) {
        let o = obj.as_object().expect("entries are objects");
        let mut keys: Vec<&str> = o.keys().map(String::as_str).collect();
        keys.sort();
        assert_eq!(keys, ["eigenvalues", "mode_shapes", "modes", "v"]);
        assert_eq!(o["v"].as_f64().unwrap(), *v);
        let ev = o["eigenvalues"].as_array().unwrap();
        let modes = o["modes"].as_array().unwrap();
        assert_eq!(ev.len(), 4);
        assert_eq!(modes.len(), 4);
        for (e, m) in ev.iter().zip(modes) {
            let pair = e.as_array().unwrap();
            assert_eq!(pair.len(), 2);
            assert!(pair.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)));
            assert!(["weave", "capsize", "castering", "other"].contains(&m.as_str().unwrap()));
        }
    }
    // v = 5 m/s (Table 2b): weave -0.77534188219585 +- 4.46486771378823i,
    // capsize -0.32286642900409, castering -14.07838969279820, in that order.
    let p = &list[50];
    let ev: Vec<[f64; 2]> = p["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| [e[0].as_f64().unwrap(), e[1].as_f64().unwrap()])
        .collect();
    let modes: Vec<&str> = p["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_str().unwrap())
        .collect();
    assert_eq!(modes, ["weave", "weave", "capsize", "castering"]);
    let expect = [
        [-0.77534188219585, 4.46486771378823],
        [-0.77534188219585, -4.46486771378823],
        [-0.32286642900409, 0.0],
        [-14.0783896927982, 0.0],
    ];
    for (a, b) in ev.iter().zip(&expect) {
        assert!(
            (a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-9,
            "{a:?} vs {b:?}"
        );
    }

    // File round trip.
    let dir = test_dir("json");
    let path = dir.join("sweep.json");
    save_eigen_sweep_json(&path, &sweep).unwrap();
    let back: serde_json::Value = serde_json::from_str(&fs::read_to_string(&path).unwrap()).unwrap();
    assert_json_close(&back, &json);
    assert_eq!(entries(&dir), ["sweep.json"]);
}

#[test]
fn sweep_speed_csv_header_rows_and_table() {
    let speeds = linspace(0.0, 10.0, 41);
    let sweep = speed_sweep(&benchmark(), &speeds).unwrap();
    let mut header = vec!["v".to_string()];
    for k in 1..=4 {
        for c in ["re", "im", "mode", "roll_amp", "roll_phase", "steer_amp", "steer_phase"] {
            header.push(format!("{c}_{k}"));
        }
    }
    assert_eq!(eigen_sweep_csv_header(), header);
    let mut buf = Vec::new();
    write_eigen_sweep_csv(&mut buf, &sweep).unwrap();
    let mut rd = csv::Reader::from_reader(buf.as_slice());
    assert_eq!(
        rd.headers().unwrap().iter().collect::<Vec<_>>(),
        header.iter().map(String::as_str).collect::<Vec<_>>()
    );
    let rows: Vec<csv::StringRecord> = rd.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 41);
    for (r, v) in rows.iter().zip(&speeds) {
        assert_eq!(r.len(), 29);
        assert_eq!(r[0].parse::<f64>().unwrap(), *v, "speeds round-trip exactly");
        for k in 0..4 {
            assert!(r[1 + 7 * k].parse::<f64>().is_ok() && r[2 + 7 * k].parse::<f64>().is_ok());
        }
    }
    // v = 10 m/s: castering -24.62459635017404 in slot 4.
    let last = &rows[40];
    assert_eq!(&last[24], "castering");
    assert!((last[22].parse::<f64>().unwrap() + 24.62459635017404).abs() < 1e-9);

    let dir = test_dir("csv");
    let path = dir.join("sweep.csv");
    save_eigen_sweep_csv(&path, &sweep).unwrap();
    assert_eq!(fs::read(&path).unwrap(), buf);

    let table = format_eigen_table(&sweep);
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 41 + 2, "header, rule, one line per speed");
    assert!(lines[0].contains("v (m/s)"));
    println!("{table}");
}

#[test]
fn sweep_grid_parallel_and_deterministic() {
    let x = ParamAxis::new("K2 scale", linspace(0.5, 1.5, 9));
    let y = ParamAxis::new("C1 scale", linspace(0.5, 1.5, 7));
    let opts = quiet(0.0, 10.0);
    let a = stability_map(x.clone(), y.clone(), scaled, &opts, &no_progress).unwrap();
    // Same result on a single thread and on several threads.
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let b = one.install(|| stability_map(x.clone(), y.clone(), scaled, &opts, &no_progress).unwrap());
    let four = rayon::ThreadPoolBuilder::new().num_threads(4).build().unwrap();
    let c = four.install(|| stability_map(x.clone(), y.clone(), scaled, &opts, &no_progress).unwrap());
    assert_eq!(a, b);
    assert_eq!(a, c);
    assert_eq!(a.shape(), (9, 7));
    assert_eq!(a.cells.len(), 63);
    assert_eq!(a.failures(), 0);

    // Cell (4, 3) is the unscaled benchmark.
    let s = a.cell(4, 3).unwrap().as_ref().unwrap();
    assert!((s.weave_speed.unwrap() - WEAVE_SPEED).abs() < 1e-6, "{s:?}");
    assert!((s.capsize_speed.unwrap() - CAPSIZE_SPEED).abs() < 1e-6, "{s:?}");
    assert!((s.stable_width - (CAPSIZE_SPEED - WEAVE_SPEED)).abs() < 1e-6, "{s:?}");
    assert!(!s.open_ended);
    assert_eq!(s.stable_intervals.len(), 1);
    // NaN-free.
    for cell in &a.cells {
        let s = cell.as_ref().unwrap();
        assert!(s.stable_width.is_finite() && s.stable_width >= 0.0);
    }

    // CSV (long format, row-major) and JSON.
    let mut buf = Vec::new();
    write_stability_map_csv(&mut buf, &a).unwrap();
    let mut rd = csv::Reader::from_reader(buf.as_slice());
    let h: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(&h[..4], ["K2 scale", "C1 scale", "i", "j"]);
    assert!(h.contains(&"stable_width".to_string()) && h.last().unwrap() == "error");
    let rows: Vec<csv::StringRecord> = rd.records().map(Result::unwrap).collect();
    assert_eq!(rows.len(), 63);
    assert_eq!((&rows[3 * 7 + 2][2], &rows[3 * 7 + 2][3]), ("3", "2"));
    let j = stability_map_json(&a);
    assert_eq!(j["cells"].as_array().unwrap().len(), 63);
    assert_eq!(j["x"]["name"], "K2 scale");
    assert_eq!(j["cells"][4 * 7 + 3]["i"], 4);
    assert_eq!(j["cells"][4 * 7 + 3]["j"], 3);
    assert!(j["cells"][4 * 7 + 3]["error"].is_null());

    let dir = test_dir("grid");
    save_stability_map_csv(dir.join("map.csv"), &a).unwrap();
    save_stability_map_json(dir.join("map.json"), &a).unwrap();
    assert_eq!(entries(&dir), ["map.csv", "map.json"]);
    assert_eq!(format_stability_map_table(&a, &|_| None).lines().count(), 63 + 2);
}

#[test]
fn sweep_failed_cells_are_recorded_not_fatal() {
    let x = ParamAxis::new("a", vec![1.0, f64::NAN, 2.0, -1.0]);
    let y = ParamAxis::new("b", vec![1.0]);
    let map = |a: f64, b: f64| -> Result<CanonicalMatrices, String> {
        if a < 0.0 {
            panic!("negative scale {a}");
        }
        scaled(a, b)
    };
    let m = stability_map(x, y, map, &quiet(0.0, 10.0), &no_progress).unwrap();
    assert!(m.cells[0].is_ok());
    let e = m.cells[1].as_ref().unwrap_err();
    assert_eq!(e.stage, CellStage::Model);
    assert!(e.message.contains("non-finite"));
    assert!(m.cells[2].is_ok());
    let e = m.cells[3].as_ref().unwrap_err();
    assert_eq!(e.stage, CellStage::Panic);
    assert!(e.message.contains("negative scale"));
    assert_eq!(m.failures(), 2);
    assert_eq!(MapQuantity::StableWidth.value(&m.cells[1]), None);

    // A singular mass matrix is an eigen error, recorded in its cell.
    let sing = |s: f64| -> Result<CanonicalMatrices, String> {
        let mut c = benchmark();
        c.m0 *= s;
        Ok(c)
    };
    let p = parameter_sweep(
        ParamAxis::new("mass scale", vec![1.0, 0.0]),
        sing,
        &quiet(0.0, 10.0),
        &no_progress,
    )
    .unwrap();
    assert!(p.points[0].is_ok());
    assert_eq!(p.points[1].as_ref().unwrap_err().stage, CellStage::Eigen);
    let j = parameter_sweep_json(&p);
    assert!(j["points"][1]["weave_speed"].is_null());
    assert_eq!(j["points"][1]["error"]["stage"], "eigen");

    // Invalid speed range rejects the whole sweep.
    let err = parameter_sweep(ParamAxis::new("a", vec![1.0]), sing, &quiet(5.0, 1.0), &no_progress).unwrap_err();
    assert!(matches!(err, SweepError::InvalidSpeedRange { .. }));
}

#[test]
fn sweep_parameter_sweep_outputs() {
    let (cells_done, last_done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let p = parameter_sweep(
        ParamAxis::new("K2 scale", linspace(0.6, 1.4, 17)),
        |a| scaled(a, 1.0),
        &quiet(0.0, 10.0),
        &|done, total| {
            assert_eq!(total, 17);
            cells_done.fetch_add(1, Ordering::Relaxed);
            last_done.fetch_max(done, Ordering::Relaxed);
        },
    )
    .unwrap();
    // The progress callback hears of every cell, and the count reaches the total.
    assert_eq!(cells_done.load(Ordering::Relaxed), 17);
    assert_eq!(last_done.load(Ordering::Relaxed), 17);
    assert_eq!(p.points.len(), 17);
    let s = p.points[8].as_ref().unwrap();
    assert!((s.weave_speed.unwrap() - WEAVE_SPEED).abs() < 1e-6);
    let dir = test_dir("param");
    let path = dir.join("param.csv");
    save_parameter_sweep_csv(&path, &p).unwrap();
    let text = fs::read_to_string(&path).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "K2 scale,weave_speed,capsize_speed,weave_real_pair_merge,stable_width,stable_lo,stable_hi,\
         n_stable_intervals,stable_intervals,open_ended,error"
    );
    assert_eq!(lines.count(), 17);
    let table = format_parameter_table(&p, &|_| None);
    assert_eq!(table.lines().count(), 19);
    println!("{table}");
}

#[test]
fn sweep_output_missing_directory_is_typed_error_without_file() {
    let sweep = speed_sweep(&benchmark(), &[1.0, 2.0]).unwrap();
    let dir = test_dir("missing");
    let target = dir.join("no-such-dir").join("sweep.csv");
    let err = save_eigen_sweep_csv(&target, &sweep).unwrap_err();
    match &err {
        OutputError::NoSuchDirectory { path, dir: d } => {
            assert_eq!(path, &target);
            assert_eq!(d, &dir.join("no-such-dir"));
        }
        other => panic!("unexpected error {other:?}"),
    }
    assert_eq!(err.path(), target.as_path());
    assert!(err.to_string().contains("no-such-dir"));
    assert!(!target.exists());
    assert!(entries(&dir).is_empty(), "no partial file left: {:?}", entries(&dir));

    // Plots report it the same way.
    let err = plot_continuation(dir.join("nope").join("fig.png"), &sweep, None, &PlotOptions::default()).unwrap_err();
    assert!(
        matches!(err, PlotError::Output(OutputError::NoSuchDirectory { .. })),
        "{err:?}"
    );
    assert!(entries(&dir).is_empty());
}

#[test]
fn sweep_output_atomic_write_keeps_old_file_on_failure() {
    let dir = test_dir("atomic");
    let path = dir.join("result.json");
    fs::write(&path, "old contents\n").unwrap();
    let err = write_atomic(&path, |w| -> Result<(), std::io::Error> {
        w.write_all(b"{\"half\": ")?;
        Err(std::io::Error::other("simulated failure mid-write"))
    })
    .unwrap_err();
    assert!(matches!(err, OutputError::Content { .. }), "{err:?}");
    assert!(err.to_string().contains("result.json") && err.to_string().contains("simulated failure"));
    assert_eq!(fs::read_to_string(&path).unwrap(), "old contents\n");
    assert_eq!(entries(&dir), ["result.json"], "temporary file removed");

    // A successful write replaces it completely.
    write_atomic(&path, |w| w.write_all(b"new\n")).unwrap();
    assert_eq!(fs::read_to_string(&path).unwrap(), "new\n");
    assert_eq!(entries(&dir), ["result.json"]);

    // A failed plot does not touch an existing figure either.
    let png = dir.join("fig.png");
    fs::write(&png, b"old figure").unwrap();
    let empty = bikedyn_runtime::eigen::EigenSweep::default();
    assert!(matches!(
        plot_continuation(&png, &empty, None, &PlotOptions::default()),
        Err(PlotError::NoData { .. })
    ));
    assert_eq!(fs::read(&png).unwrap(), b"old figure");
}

#[test]
fn plot_continuation_svg_and_png() {
    let c = benchmark();
    let sweep = speed_sweep(&c, &linspace(0.0, 10.0, 201)).unwrap();
    let crit = bikedyn_runtime::eigen::critical_speeds(&c, 0.0, 10.0).unwrap();
    let dir = test_dir("continuation");
    let opts = PlotOptions::default();
    plot_continuation(dir.join("fig.svg"), &sweep, Some(&crit), &opts).unwrap();
    plot_continuation(dir.join("fig.png"), &sweep, Some(&crit), &opts).unwrap();
    let svg = fs::read_to_string(dir.join("fig.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.len() > 1000);
    for label in [
        "weave",
        "capsize",
        "castering",
        "forward speed v (m/s)",
        "eigenvalue (1/s)",
    ] {
        assert!(svg.contains(label), "SVG lacks {label}");
    }
    let png = fs::read(dir.join("fig.png")).unwrap();
    assert!(png.len() > 1000);
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    // Clipped y range and upper-case extension.
    let clipped = PlotOptions {
        y_range: Some((-10.0, 10.0)),
        title: Some("benchmark".into()),
        ..PlotOptions::default()
    };
    plot_continuation(dir.join("clipped.PNG"), &sweep, Some(&crit), &clipped).unwrap();
    assert_eq!(entries(&dir), ["clipped.PNG", "fig.png", "fig.svg"]);
}

#[test]
fn plot_stability_map_svg_and_png() {
    let x = ParamAxis::new("K2 scale", linspace(0.2, 1.8, 25));
    let y = ParamAxis::new("C1 scale", linspace(0.2, 1.8, 21));
    let m = stability_map(x, y, scaled, &quiet(0.0, 10.0), &no_progress).unwrap();
    let dir = test_dir("map");
    let opts = PlotOptions::default();
    plot_stability_map(dir.join("map.svg"), &m, MapQuantity::StableWidth, None, &opts).unwrap();
    plot_stability_map(dir.join("map.png"), &m, MapQuantity::WeaveSpeed, None, &opts).unwrap();
    let svg = fs::read_to_string(dir.join("map.svg")).unwrap();
    assert!(svg.contains("K2 scale") && svg.contains("C1 scale"));
    let png = fs::read(dir.join("map.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn plot_rejects_unknown_extension_and_bad_font() {
    let sweep = speed_sweep(&benchmark(), &[1.0, 2.0]).unwrap();
    let dir = test_dir("ext");
    let err = plot_continuation(dir.join("fig.pdf"), &sweep, None, &PlotOptions::default()).unwrap_err();
    assert!(matches!(err, PlotError::UnsupportedFormat { .. }), "{err:?}");
    assert!(err.to_string().contains("fig.pdf"));
    let err = plot_continuation(dir.join("fig"), &sweep, None, &PlotOptions::default()).unwrap_err();
    assert!(matches!(err, PlotError::UnsupportedFormat { .. }));
    let err = use_font(dir.join("missing.ttf")).unwrap_err();
    assert!(matches!(err, PlotError::Font { .. }), "{err:?}");
    let not_a_font = dir.join("bad.ttf");
    fs::write(&not_a_font, b"definitely not a font").unwrap();
    assert!(matches!(use_font(&not_a_font), Err(PlotError::Font { .. })));
    assert_eq!(entries(&dir), ["bad.ttf"]);
}

// ---------------------------------------------------------------------------
// Figures read back (issue 20): the drawn SVG and PNG, not only their
// existence.

/// The `<tag ...>` openings of an SVG.
fn tags<'a>(svg: &'a str, tag: &str) -> Vec<&'a str> {
    svg.split(&format!("<{tag}"))
        .skip(1)
        .map(|t| t.split('>').next().unwrap())
        .collect()
}

/// An attribute of a tag.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let start = tag.find(&format!(" {name}=\""))? + name.len() + 3;
    tag[start..].split('"').next()
}

/// The points of a polyline.
fn points(tag: &str) -> Vec<(f64, f64)> {
    attr(tag, "points")
        .unwrap_or("")
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect()
}

/// The texts of an SVG with their positions.
fn texts(svg: &str) -> Vec<(String, f64, f64)> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let head = t.split('>').next().unwrap();
            let body = t.split('>').nth(1).unwrap().split('<').next().unwrap();
            (
                body.to_string(),
                attr(head, "x").unwrap().parse().unwrap(),
                attr(head, "y").unwrap().parse().unwrap(),
            )
        })
        .collect()
}

/// PNG width, height (IHDR) and pixels per metre (pHYs).
fn png_header(bytes: &[u8]) -> (u32, u32, Option<u32>) {
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    let (w, h) = (be(&bytes[16..20]), be(&bytes[20..24]));
    let phys = bytes
        .windows(4)
        .position(|c| c == b"pHYs")
        .map(|k| be(&bytes[k + 4..k + 8]));
    (w, h, phys)
}

/// Issue 20: the continuation diagram has a title (the subject and the
/// figure), real parts solid and imaginary parts dashed (`stroke-dasharray`),
/// curves at sub-pixel coordinates (no pixel steps), v_d, v_w and v_c
/// marked, and a legend box that covers no curve.
#[test]
fn issue_20_continuation_reads_back() {
    let c = benchmark();
    let sweep = speed_sweep(&c, &linspace(0.0, 10.0, 501)).unwrap();
    let crit = bikedyn_runtime::eigen::critical_speeds(&c, 0.0, 10.0).unwrap();
    let dir = test_dir("readback");
    let opts = PlotOptions {
        subject: Some("benchmark bicycle, model whipple_offset".into()),
        ..PlotOptions::default()
    };
    plot_continuation(dir.join("fig.svg"), &sweep, Some(&crit), &opts).unwrap();
    let svg = fs::read_to_string(dir.join("fig.svg")).unwrap();
    let t = texts(&svg);
    assert!(
        t.iter()
            .any(|x| x.0 == "benchmark bicycle, model whipple_offset: eigenvalues over forward speed"),
        "{t:?}"
    );
    let lines = tags(&svg, "polyline");
    let dashed = lines.iter().filter(|l| l.contains("stroke-dasharray")).count();
    let curves: Vec<&&str> = lines.iter().filter(|l| points(l).len() > 50).collect();
    assert!(
        curves.iter().any(|l| l.contains("stroke-dasharray")),
        "dashed imaginary parts"
    );
    assert!(
        curves.iter().any(|l| !l.contains("stroke-dasharray")),
        "solid real parts"
    );
    assert!(
        dashed >= 2,
        "{dashed} dashed lines (imaginary part of the weave, the legend)"
    );
    // Sub-pixel vertices: many coordinates are not whole pixels.
    let frac = curves
        .iter()
        .flat_map(|l| points(l))
        .filter(|p| p.0.fract() != 0.0 || p.1.fract() != 0.0)
        .count();
    assert!(frac > 100, "{frac} vertices off the pixel grid");
    // The three speeds, labelled (subscript d, w, c) with their values.
    let vd = crit.weave_real_pair_merge.unwrap();
    for (sub, v) in [("d", vd), ("w", WEAVE_SPEED), ("c", CAPSIZE_SPEED)] {
        assert!(t.iter().any(|x| x.0 == sub), "v_{sub}");
        let value = format!("= {v:.2} m/s");
        assert!(t.iter().any(|x| x.0 == value), "{value} in {t:?}");
    }
    // Legend box (the white, slightly transparent rectangle) covers no
    // vertex of a curve.
    let legend = tags(&svg, "rect")
        .into_iter()
        .find(|r| attr(r, "fill") == Some("#FFFFFF") && attr(r, "opacity").is_some())
        .expect("legend box");
    let num = |n| attr(legend, n).unwrap().parse::<f64>().unwrap();
    let (x, y, w, h) = (num("x"), num("y"), num("width"), num("height"));
    for l in &curves {
        for p in points(l) {
            assert!(
                !(p.0 > x && p.0 < x + w && p.1 > y && p.1 < y + h),
                "legend ({x}, {y}, {w}, {h}) covers {p:?}"
            );
        }
    }
}

/// Issue 20: labels of close speeds are kept apart (a wide speed range
/// puts v_w and v_c 70 px apart: their labels go on two rows).
#[test]
fn issue_20_close_speed_labels_do_not_overlap() {
    let c = benchmark();
    let sweep = speed_sweep(&c, &linspace(0.0, 60.0, 601)).unwrap();
    let crit = bikedyn_runtime::eigen::critical_speeds(&c, 0.0, 60.0).unwrap();
    let dir = test_dir("labels");
    plot_continuation(dir.join("fig.svg"), &sweep, Some(&crit), &PlotOptions::default()).unwrap();
    let svg = fs::read_to_string(dir.join("fig.svg")).unwrap();
    let t = texts(&svg);
    let find = |v: f64| t.iter().find(|x| x.0 == format!("= {v:.2} m/s")).unwrap().clone();
    let (w, c) = (find(WEAVE_SPEED), find(CAPSIZE_SPEED));
    // Either on different rows or far enough apart across.
    assert!((w.2 - c.2).abs() > 10.0 || (w.1 - c.1).abs() > 100.0, "{w:?} {c:?}");
}

/// Issue 20: size and resolution: a PNG is `width x height` times the
/// scale and records 100 x scale dpi; lines are antialiased.
#[test]
fn issue_20_png_size_and_dpi() {
    let sweep = speed_sweep(&benchmark(), &linspace(0.0, 10.0, 101)).unwrap();
    let dir = test_dir("dpi");
    let opts = PlotOptions {
        size: Some((600, 400)),
        scale: 2.0,
        ..PlotOptions::default()
    };
    plot_continuation(dir.join("fig.png"), &sweep, None, &opts).unwrap();
    let bytes = fs::read(dir.join("fig.png")).unwrap();
    let (w, h, ppm) = png_header(&bytes);
    assert_eq!((w, h), (1200, 800));
    // 200 dpi = 7874 pixels per metre.
    assert_eq!(ppm, Some(7874));
}

/// Issue 20: a map of a signed quantity (the least stable real part at a
/// probe speed) uses a diverging colour map centred on zero (blue and red
/// cells, white at zero), draws the zero contour and says the speed.
#[test]
fn issue_20_signed_map_is_diverging_with_zero_contour() {
    let x = ParamAxis::new("K2 scale", linspace(0.2, 1.8, 17));
    let y = ParamAxis::new("C1 scale", linspace(0.2, 1.8, 15));
    let opts = SweepOptions {
        probe_speed: Some(5.0),
        ..quiet(0.0, 10.0)
    };
    let m = stability_map(x, y, scaled, &opts, &no_progress).unwrap();
    let vals: Vec<f64> = m
        .cells
        .iter()
        .filter_map(|c| MapQuantity::LeastStableRealPart.value(c))
        .collect();
    assert!(
        vals.iter().any(|v| *v < 0.0) && vals.iter().any(|v| *v > 0.0),
        "both signs on the grid"
    );
    let dir = test_dir("signed");
    plot_stability_map(
        dir.join("map.svg"),
        &m,
        MapQuantity::LeastStableRealPart,
        Some(5.0),
        &PlotOptions::default(),
    )
    .unwrap();
    let svg = fs::read_to_string(dir.join("map.svg")).unwrap();
    let fills: Vec<(u8, u8, u8)> = tags(&svg, "rect")
        .iter()
        .filter_map(|r| attr(r, "fill"))
        .filter(|f| f.len() == 7)
        .map(|f| {
            let h = |k: usize| u8::from_str_radix(&f[k..k + 2], 16).unwrap();
            (h(1), h(3), h(5))
        })
        .collect();
    assert!(fills.iter().any(|c| c.2 > c.0 + 80), "blue (stable) cells");
    assert!(fills.iter().any(|c| c.0 > c.2 + 80), "red (unstable) cells");
    let contour = tags(&svg, "polyline")
        .iter()
        .filter(|l| attr(l, "stroke") == Some("#000000") && points(l).len() == 2)
        .count();
    assert!(contour > 5, "{contour} contour segments");
    let t = texts(&svg);
    assert!(t.iter().any(|x| x.0.contains("at v = 5 m/s")), "{t:?}");
}

/// Issue 20: a one-parameter sweep is drawn as the quantity against the
/// parameter, with a point per value.
#[test]
fn issue_20_parameter_sweep_plot() {
    use bikedyn_report::plot::sweep::plot_parameter_sweep;
    let s = parameter_sweep(
        ParamAxis::new("K2 scale", linspace(0.5, 1.5, 11)),
        |a| scaled(a, 1.0),
        &quiet(0.0, 10.0),
        &no_progress,
    )
    .unwrap();
    let dir = test_dir("param");
    plot_parameter_sweep(
        dir.join("s.svg"),
        &s,
        MapQuantity::WeaveSpeed,
        None,
        &PlotOptions::default(),
    )
    .unwrap();
    let svg = fs::read_to_string(dir.join("s.svg")).unwrap();
    let t = texts(&svg);
    assert!(t.iter().any(|x| x.0 == "K2 scale") && t.iter().any(|x| x.0 == "weave speed (m/s)"));
    assert!(t.iter().any(|x| x.0.contains("speeds 0-10 m/s searched")), "{t:?}");
    let line = tags(&svg, "polyline")
        .into_iter()
        .map(points)
        .max_by_key(|p| p.len())
        .unwrap();
    assert_eq!(line.len(), 11);
    // 11 points with a white rim each.
    assert!(tags(&svg, "circle").len() >= 22);
}

/// Issue 20: the root locus draws every eigenvalue at every speed as a
/// point coloured by speed, with a colour bar; the mode shapes draw roll and
/// steer phasors per mode with amplitude and phase.
#[test]
fn issue_20_root_locus_and_mode_shapes() {
    use bikedyn_report::plot::locus::{plot_mode_shapes, plot_root_locus};
    let sweep = speed_sweep(&benchmark(), &linspace(0.0, 10.0, 51)).unwrap();
    let dir = test_dir("locus");
    plot_root_locus(dir.join("l.svg"), &sweep, &PlotOptions::default()).unwrap();
    let svg = fs::read_to_string(dir.join("l.svg")).unwrap();
    let circles = tags(&svg, "circle");
    assert_eq!(circles.len(), 51 * 4);
    let colours: std::collections::HashSet<&str> = circles.iter().filter_map(|c| attr(c, "fill")).collect();
    assert!(colours.len() > 40, "{} colours", colours.len());
    let t = texts(&svg);
    assert!(t.iter().any(|x| x.0 == "forward speed v (m/s)"));
    assert!(t.iter().any(|x| x.0 == "imaginary part (rad/s)"));

    let at5 = speed_sweep(&benchmark(), &[5.0]).unwrap();
    plot_mode_shapes(dir.join("m.png"), &at5.points[0], &PlotOptions::default()).unwrap();
    plot_mode_shapes(dir.join("m.svg"), &at5.points[0], &PlotOptions::default()).unwrap();
    let svg = fs::read_to_string(dir.join("m.svg")).unwrap();
    let t = texts(&svg);
    for m in ["weave", "capsize", "castering"] {
        assert!(t.iter().any(|x| x.0.starts_with(&format!("{m}: "))), "{m} in {t:?}");
    }
    // Three modes, roll and steer each.
    assert_eq!(t.iter().filter(|x| x.0.starts_with("roll: amplitude")).count(), 3);
    assert!(t.iter().filter(|x| x.0.trim_start().starts_with("phase ")).count() == 6);
    assert_eq!(t.iter().filter(|x| x.0.starts_with("steer: amplitude")).count(), 3);
    assert!(t.iter().any(|x| x.0.contains("mode shapes at v = 5 m/s")));
}
