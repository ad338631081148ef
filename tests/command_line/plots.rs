//! Figures from the command line (issue 20), read back: titles naming the
//! bicycle and model, size and resolution, axis limits, the root locus and
//! mode shapes of `eig`, the one-parameter sweep plot, the simulation's
//! markers and shared time label, and option errors that name their flag
//! before any computation.

use crate::common::{bikedyn, scratch, text};
use std::path::PathBuf;

fn tmp(name: &str) -> PathBuf {
    scratch("plots").join(name)
}

/// The texts of an SVG.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .map(|t| t.split('>').nth(1).unwrap().split('<').next().unwrap().to_string())
        .collect()
}

/// The texts of an SVG with their (x, y).
fn svg_texts_at(svg: &str) -> Vec<(String, f64, f64)> {
    svg.split("<text")
        .skip(1)
        .map(|t| {
            let head = t.split('>').next().unwrap();
            let num = |n: &str| -> f64 {
                let s = head.find(&format!(" {n}=\"")).unwrap() + n.len() + 3;
                head[s..].split('"').next().unwrap().parse().unwrap()
            };
            (
                t.split('>').nth(1).unwrap().split('<').next().unwrap().to_string(),
                num("x"),
                num("y"),
            )
        })
        .collect()
}

/// PNG width, height and pixels per metre.
fn png_header(path: &PathBuf) -> (u32, u32, Option<u32>) {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    let phys = b.windows(4).position(|c| c == b"pHYs").map(|k| be(&b[k + 4..k + 8]));
    (be(&b[16..20]), be(&b[20..24]), phys)
}

/// `eig --plot` with `--plot-size` and `--dpi`: the PNG has the pixels and
/// the resolution asked for; the SVG's title names bicycle and model, and
/// `--xlim` sets the axis.
#[test]
fn eig_plot_keeps_size_dpi_title_and_limits() {
    let png = tmp("eig.png");
    let svg = tmp("eig.svg");
    for (p, extra) in [
        (&png, vec!["--plot-size", "4x3", "--dpi", "200"]),
        (&svg, vec!["--xlim", "2:8"]),
    ] {
        let mut args = vec![
            "eig",
            "--bike",
            "benchmark",
            "--speeds",
            "0:10:0.05",
            "--plot",
            p.to_str().unwrap(),
        ];
        args.extend(extra);
        let out = bikedyn(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
    }
    assert_eq!(png_header(&png), (800, 600, Some(7874)));
    let s = std::fs::read_to_string(&svg).unwrap();
    let t = svg_texts(&s);
    assert!(
        t.iter()
            .any(|x| x == "bicycle benchmark, model whipple_offset: eigenvalues over forward speed"),
        "{t:?}"
    );
    // x ticks from 2 to 8 only.
    assert!(t.iter().any(|x| x == "2") && t.iter().any(|x| x == "8"));
    assert!(!t.iter().any(|x| x == "10" || x == "9"), "{t:?}");
    assert!(s.contains("stroke-dasharray"), "imaginary parts dashed");
}

/// `eig --plot-root-locus` and `--plot-mode-shapes --speed`: the two views
/// of bicycleparameters, each titled with bicycle and model.
#[test]
fn eig_draws_the_root_locus_and_mode_shapes() {
    let locus = tmp("locus.svg");
    let modes = tmp("modes.svg");
    let out = bikedyn(&[
        "eig",
        "--bike",
        "benchmark",
        "--speeds",
        "0:10:0.5",
        "--plot-root-locus",
        locus.to_str().unwrap(),
        "--plot-mode-shapes",
        modes.to_str().unwrap(),
        "--speed",
        "5",
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = std::fs::read_to_string(&locus).unwrap();
    // 21 speeds, 4 eigenvalues each: a point per eigenvalue.
    assert_eq!(s.matches("<circle").count(), 21 * 4);
    let t = svg_texts(&s);
    assert!(t
        .iter()
        .any(|x| x.starts_with("bicycle benchmark, model whipple_offset: root locus")));
    let s = std::fs::read_to_string(&modes).unwrap();
    let t = svg_texts(&s);
    assert!(t.iter().any(|x| x.contains("mode shapes at v = 5 m/s")), "{t:?}");
    assert_eq!(t.iter().filter(|x| x.starts_with("steer: amplitude")).count(), 3);
    // --speed without the mode-shape plot, and the plot without --speed.
    let out = bikedyn(&["eig", "--speed", "5"]);
    assert!(
        !out.status.success() && text(&out.stderr).contains("--plot-mode-shapes"),
        "{}",
        text(&out.stderr)
    );
    let out = bikedyn(&["eig", "--plot-mode-shapes", modes.to_str().unwrap()]);
    assert!(
        !out.status.success() && text(&out.stderr).contains("--speed"),
        "{}",
        text(&out.stderr)
    );
}

/// Bad plot options are errors naming the flag, before any output.
#[test]
fn bad_plot_options_name_their_flag() {
    let p = tmp("never.svg");
    for (args, flag) in [
        (vec!["--plot-size", "0x3"], "--plot-size"),
        (vec!["--plot-size", "8by6"], "--plot-size"),
        (vec!["--plot-size", "1x1"], "--plot-size"),
        (vec!["--plot-size", "100x100", "--dpi", "300"], "20000"),
        (vec!["--dpi", "0"], "--dpi"),
        (vec!["--xlim", "5:1"], "--xlim"),
        (vec!["--ylim", "a:b"], "--ylim"),
        (vec!["--ylim=-1:-1"], "--ylim"),
    ] {
        let mut a = vec![
            "eig",
            "--speeds",
            "0:10:0.001",
            "--format",
            "csv",
            "--plot",
            p.to_str().unwrap(),
        ];
        a.extend(args.iter().copied());
        let out = bikedyn(&a);
        assert!(!out.status.success(), "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}: output before the error");
        let e = text(&out.stderr);
        assert!(e.contains(flag) && !e.contains("panicked"), "{args:?}: {e}");
    }
    assert!(!p.exists());
    // The other plotting commands check them too.
    let out = bikedyn(&[
        "simulate",
        "--speed",
        "4",
        "--duration",
        "1",
        "--plot",
        p.to_str().unwrap(),
        "--dpi",
        "-3",
    ]);
    assert!(!out.status.success() && text(&out.stderr).contains("--dpi"));
    let out = bikedyn(&[
        "sweep",
        "--param",
        "c",
        "--values",
        "0:0.1:0.05",
        "--plot",
        p.to_str().unwrap(),
        "--xlim",
        "1:0",
    ]);
    assert!(!out.status.success() && text(&out.stderr).contains("--xlim"));
}

/// `sweep --plot` with one parameter draws the quantity against it; a map
/// of the least stable real part says the speed it was made at.
#[test]
fn sweep_plots_draw_maps_and_curves() {
    let one = tmp("sweep1.svg");
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.04:0.12:0.01",
        "--map",
        "weave",
        "--plot",
        one.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = std::fs::read_to_string(&one).unwrap();
    let t = svg_texts(&s);
    assert!(t.iter().any(|x| x == "weave speed (m/s)"), "{t:?}");
    assert!(t.iter().any(|x| x.starts_with("bicycle benchmark, model")), "{t:?}");
    let longest = s
        .split("<polyline")
        .skip(1)
        .map(|p| {
            p.split("points=\"")
                .nth(1)
                .unwrap()
                .split('"')
                .next()
                .unwrap()
                .split_whitespace()
                .count()
        })
        .max()
        .unwrap();
    assert_eq!(longest, 9, "one vertex per value");
    let map = tmp("map.svg");
    let out = bikedyn(&[
        "sweep",
        "--bike",
        "benchmark",
        "--param",
        "c",
        "--values",
        "0.02:0.14:0.02",
        "--param2",
        "lam",
        "--values2",
        "0.2:0.5:0.05",
        "--map",
        "least-stable",
        "--at-speed",
        "4",
        "--plot",
        map.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t = svg_texts(&std::fs::read_to_string(&map).unwrap());
    assert!(t.iter().any(|x| x.contains("at v = 4 m/s")), "{t:?}");
}

/// `simulate --plot`: a title with bicycle and model, one time label, the
/// kick marked (dashed), a speed axis around the (constant) speed.
#[test]
fn simulation_plot_has_one_time_label_and_the_kick() {
    let svg = tmp("sim.svg");
    let out = bikedyn(&[
        "simulate",
        "--speed",
        "4",
        "--kick",
        "0.5:3",
        "--duration",
        "3",
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let s = std::fs::read_to_string(&svg).unwrap();
    let t = svg_texts_at(&s);
    assert_eq!(t.iter().filter(|x| x.0 == "time t (s)").count(), 1, "one time label");
    assert!(
        t.iter()
            .any(|x| x.0.starts_with("bicycle thesis, model thesis_whipple")),
        "{t:?}"
    );
    assert!(t.iter().any(|x| x.0 == "kick"), "kick in the legend");
    // A vertical dashed line at the kick: two points with the same x.
    assert!(s.split("<polyline").skip(1).any(|p| {
        let pts: Vec<&str> = p
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .split_whitespace()
            .collect();
        p.contains("stroke-dasharray") && pts.len() == 2 && pts[0].split(',').next() == pts[1].split(',').next()
    }));
    // Speed panel (bottom third): its tick labels (right-aligned, left of
    // the axis) near 4 m/s, not from 0.
    let speed_ticks: Vec<f64> = s
        .split("<text")
        .skip(1)
        .zip(&t)
        .filter(|(raw, x)| x.2 > 600.0 && raw.contains("text-anchor=\"end\""))
        .filter_map(|(_, x)| x.0.parse::<f64>().ok())
        .collect();
    assert!(!speed_ticks.is_empty());
    assert!(speed_ticks.iter().all(|v| (3.9..=4.1).contains(v)), "{speed_ticks:?}");
}

/// A size given is kept even when it is the one-panel default: the
/// simulation's three stacked panels are 800x900 by default, and
/// `--plot-size 8x6` makes them 800x600.
#[test]
fn an_explicit_plot_size_is_kept() {
    for (name, extra, size) in [
        ("sim-default.png", vec![], (800, 900)),
        ("sim-8x6.png", vec!["--plot-size", "8x6"], (800, 600)),
    ] {
        let png = tmp(name);
        let mut args = vec![
            "simulate",
            "--speed",
            "4",
            "--duration",
            "1",
            "--plot",
            png.to_str().unwrap(),
        ];
        args.extend(extra);
        let out = bikedyn(&args);
        assert!(out.status.success(), "{}", text(&out.stderr));
        let (w, h, _) = png_header(&png);
        assert_eq!((w, h), size, "{name}");
    }
}
