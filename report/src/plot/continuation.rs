//! The eigenvalue continuation diagram (Meijaard et al. 2007, Fig. 3):
//! real and imaginary parts of every mode against forward speed, coloured
//! by mode ([`mode_class`], [`CLASS_COLORS`], shared with the root locus),
//! with the self-stable band and the critical speeds marked and labelled
//! (subscripted labels kept apart, [`layout_mark_labels`]).
//!
//! Apart because it is the library's main figure and the largest: the
//! curves' construction from a sweep and the marks' layout belong to it
//! alone.

use std::path::Path;

use plotters::prelude::*;

use super::style::{self, Area, Frame, Icon, Legend, Stroke};
use super::{de, padded, render, DrawErr, Figure, ImageFormat, PlotError, PlotOptions};
use bikedyn_runtime::eigen::{CriticalSpeeds, EigenSweep, Mode};

const BAND: RGBColor = style::GREEN;

/// Class of a mode label in the diagrams: each single mode, each merged
/// pair and the unclassified modes have their own colour.
pub(crate) fn mode_class(m: Mode) -> usize {
    match m {
        Mode::Weave => 0,
        Mode::Capsize => 1,
        Mode::Castering => 2,
        Mode::WeaveCapsize => 3,
        Mode::WeaveCastering => 4,
        Mode::CapsizeCastering => 5,
        Mode::Other(_) => 6,
    }
}

pub(crate) const CLASS_NAMES: [&str; 7] = [
    "weave",
    "capsize",
    "castering",
    "weave-capsize pair",
    "weave-castering pair",
    "capsize-castering pair",
    "other",
];
/// Single modes: blue, vermilion, purple; merged pairs: pink, sky blue,
/// olive (none close to a single mode's colour); others grey.
pub(crate) const CLASS_COLORS: [RGBColor; 7] = [
    style::BLUE,
    style::VERMILION,
    style::PURPLE,
    style::PINK,
    style::SKY,
    style::OLIVE,
    style::GREY,
];

struct Curve {
    class: usize,
    imag: bool,
    points: Vec<(f64, f64)>,
}

/// Real parts per mode (one branch per distinct root, conjugates merged) and
/// the positive imaginary part per mode, as continuous pieces.
fn continuation_curves(sweep: &EigenSweep) -> Vec<Curve> {
    let mut curves = Vec::new();
    for class in 0..CLASS_NAMES.len() {
        let per_point: Vec<Vec<f64>> = sweep
            .points
            .iter()
            .map(|p| {
                let mut re: Vec<f64> = (0..4)
                    .filter(|&k| mode_class(p.modes[k]) == class && p.eigenvalues[k].im >= 0.0)
                    .map(|k| p.eigenvalues[k].re)
                    .collect();
                re.sort_by(|a, b| b.total_cmp(a));
                re
            })
            .collect();
        let branches = per_point.iter().map(Vec::len).max().unwrap_or(0);
        for b in 0..branches {
            let mut cur = Vec::new();
            for (p, re) in sweep.points.iter().zip(&per_point) {
                match re.get(b) {
                    Some(&r) => cur.push((p.v, r)),
                    None => {
                        if !cur.is_empty() {
                            curves.push(Curve {
                                class,
                                imag: false,
                                points: std::mem::take(&mut cur),
                            });
                        }
                    }
                }
            }
            if !cur.is_empty() {
                curves.push(Curve {
                    class,
                    imag: false,
                    points: cur,
                });
            }
        }
        // Imaginary part: largest positive imaginary part of the class; pieces
        // start/end at the neighbouring samples where it is zero.
        let im: Vec<Option<f64>> = sweep
            .points
            .iter()
            .map(|p| {
                let ks: Vec<usize> = (0..4).filter(|&k| mode_class(p.modes[k]) == class).collect();
                if ks.is_empty() {
                    None
                } else {
                    Some(ks.iter().map(|&k| p.eigenvalues[k].im.abs()).fold(0.0, f64::max))
                }
            })
            .collect();
        let n = im.len();
        let positive = |k: usize| im[k].is_some_and(|x| x > 0.0);
        let mut cur: Vec<(f64, f64)> = Vec::new();
        for k in 0..n {
            let include =
                positive(k) || (im[k].is_some() && ((k > 0 && positive(k - 1)) || (k + 1 < n && positive(k + 1))));
            if include {
                cur.push((sweep.points[k].v, im[k].unwrap_or(0.0)));
                if !positive(k) && cur.len() > 1 {
                    curves.push(Curve {
                        class,
                        imag: true,
                        points: std::mem::take(&mut cur),
                    });
                    // A zero sample can also start the next piece.
                    if k + 1 < n && positive(k + 1) {
                        cur.push((sweep.points[k].v, 0.0));
                    }
                }
            } else if !cur.is_empty() {
                if cur.len() > 1 {
                    curves.push(Curve {
                        class,
                        imag: true,
                        points: std::mem::take(&mut cur),
                    });
                }
                cur.clear();
            }
        }
        if cur.len() > 1 {
            curves.push(Curve {
                class,
                imag: true,
                points: cur,
            });
        }
    }
    curves
}

struct Continuation<'a> {
    critical: Option<&'a CriticalSpeeds>,
    curves: Vec<Curve>,
    xr: (f64, f64),
    yr: (f64, f64),
}

/// Draw the continuation diagram of `sweep` (real parts solid, imaginary parts
/// dashed, one colour per mode and per merged pair) to `path` (`.svg` or
/// `.png`).
///
/// With `critical`, the self-stable speed intervals are shaded and `v_d`,
/// `v_w`, `v_c` are marked and labelled above the plot, in rows when they are
/// close (if in the plotted range and [`PlotOptions::show_stable_band`] is
/// set).
pub fn plot_continuation(
    path: impl AsRef<Path>,
    sweep: &EigenSweep,
    critical: Option<&CriticalSpeeds>,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    if sweep.points.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let curves = continuation_curves(sweep);
    let xr = opts.x_range.unwrap_or_else(|| {
        let lo = sweep.points.iter().map(|p| p.v).fold(f64::INFINITY, f64::min);
        let hi = sweep.points.iter().map(|p| p.v).fold(f64::NEG_INFINITY, f64::max);
        if hi > lo {
            (lo, hi)
        } else {
            padded(lo, hi, 0.0)
        }
    });
    let yr = opts.y_range.unwrap_or_else(|| {
        let vals = curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|p| p.0 >= xr.0 && p.0 <= xr.1)
            .map(|p| p.1)
            .chain([0.0]);
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| (l.min(y), h.max(y)));
        padded(lo, hi, 0.05)
    });
    render(
        path,
        opts,
        &Continuation {
            critical,
            curves,
            xr,
            yr,
        },
    )
}

/// Layout of "main, subscript, rest" (e.g. "v", "w", " = 4.29 m/s"): x
/// offsets of the three parts and the total width. Leading spaces of the rest
/// become an explicit gap (SVG viewers drop leading whitespace in text).
pub(crate) fn subscript_layout(
    root: &Area<'_>,
    parts: (&str, &str, &str),
    o: &PlotOptions,
) -> Result<([i32; 3], i32), DrawErr> {
    let main = o.font(1.0);
    let small = o.font(0.72);
    let w1 = root.estimate_text_size(parts.0, &main).map_err(de)?.0 as i32;
    let w2 = root.estimate_text_size(parts.1, &small).map_err(de)?.0 as i32;
    let rest = parts.2.trim_start();
    let gap = if rest.len() < parts.2.len() {
        o.pxi(o.font_size * 0.3)
    } else {
        o.pxi(1.0)
    };
    let w3 = root.estimate_text_size(rest, &main).map_err(de)?.0 as i32;
    Ok(([0, w1, w1 + w2 + gap], w1 + w2 + gap + w3))
}

/// Draw a subscripted label (see [`subscript_layout`]) with its top-left at `(x, y)`.
pub(crate) fn draw_subscripted(
    root: &Area<'_>,
    (x, y): (i32, i32),
    parts: (&str, &str, &str),
    o: &PlotOptions,
) -> Result<(), DrawErr> {
    let (off, _) = subscript_layout(root, parts, o)?;
    let main = o.font(1.0);
    root.draw(&Text::new(parts.0.to_string(), (x + off[0], y), main.clone()))
        .map_err(de)?;
    root.draw(&Text::new(
        parts.1.to_string(),
        (x + off[1], y + o.pxi(o.font_size * 0.45)),
        o.font(0.72),
    ))
    .map_err(de)?;
    root.draw(&Text::new(parts.2.trim_start().to_string(), (x + off[2], y), main))
        .map_err(de)?;
    Ok(())
}

/// Labels of marked speeds, placed in rows above the plot: each centred on
/// its line when it can be, moved to the next row when it would overlap a
/// label already placed. `marks` are `(pixel x, label width)`; `(x0, x1)`
/// the plot's pixel range. Returns each label's left edge and row.
pub(crate) fn layout_mark_labels(marks: &[(i32, i32)], (x0, x1): (i32, i32), gap: i32) -> Vec<(i32, usize)> {
    let mut order: Vec<usize> = (0..marks.len()).collect();
    order.sort_by_key(|&k| marks[k].0);
    let mut placed: Vec<(i32, i32, usize)> = Vec::new();
    let mut out = vec![(0, 0); marks.len()];
    for k in order {
        let (x, w) = marks[k];
        let left = (x - w / 2).clamp(x0, (x1 - w).max(x0));
        let mut row = 0;
        while placed
            .iter()
            .any(|&(a, b, r)| r == row && left < b + gap && left + w + gap > a)
        {
            row += 1;
        }
        placed.push((left, left + w, row));
        out[k] = (left, row);
    }
    out
}

impl Figure for Continuation<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let (xr, yr) = (self.xr, self.yr);
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "eigenvalues over forward speed")?;

        let band = o.show_stable_band.then_some(self.critical).flatten();
        let stable: Vec<(f64, f64)> = band
            .map(|cs| {
                cs.stable_intervals
                    .iter()
                    .map(|[lo, hi]| (lo.max(xr.0), hi.min(xr.1)))
                    .filter(|(lo, hi)| hi > lo)
                    .collect()
            })
            .unwrap_or_default();
        // Marked speeds: v_d (at the double real root when known), v_w, v_c.
        let marks: Vec<(f64, &str, Option<f64>)> = band
            .map(|cs| {
                [
                    (cs.weave_real_pair_merge, "d", cs.weave_merge_eigenvalue),
                    (cs.weave_speed, "w", Some(0.0)),
                    (cs.capsize_speed, "c", Some(0.0)),
                ]
                .into_iter()
                .filter_map(|(v, s, y)| v.filter(|v| *v >= xr.0 && *v <= xr.1).map(|v| (v, s, y)))
                .collect()
            })
            .unwrap_or_default();

        let mut legend = Legend::default();
        let mut classes: Vec<usize> = self.curves.iter().map(|c| c.class).collect();
        classes.sort();
        classes.dedup();
        for &cl in &classes {
            legend.add(CLASS_NAMES[cl], Icon::Line(Stroke::solid(CLASS_COLORS[cl])));
        }
        legend.add("real part", Icon::Line(Stroke::solid(style::DATA)));
        if self.curves.iter().any(|c| c.imag) {
            legend.add("imaginary part", Icon::Line(Stroke::dashed(style::DATA)));
        }
        if !stable.is_empty() {
            legend.add("self-stable", Icon::Patch(BAND, 0.25));
        }
        let data: Vec<&[(f64, f64)]> = self.curves.iter().map(|c| c.points.as_slice()).collect();

        // Mark labels above the plot: rows as needed.
        let texts: Vec<String> = marks
            .iter()
            .map(|(v, _, _)| format!(" = {} m/s", fmt_speed(*v)))
            .collect();
        let widths: Vec<i32> = marks
            .iter()
            .zip(&texts)
            .map(|((_, sub, _), t)| subscript_layout(root, ("v", sub, t), o).map(|l| l.1))
            .collect::<Result<_, _>>()?;
        let row_h = o.font_size * 1.35;
        let gap = o.pxi(10.0);
        let layout_on = |chart: &style::Chart<'_, '_>| {
            let r = chart.plotting_area().get_pixel_range();
            let pos: Vec<(i32, i32)> = marks
                .iter()
                .zip(&widths)
                .map(|((v, _, _), w)| (chart.backend_coord(&(*v, yr.1)).0, *w))
                .collect();
            layout_mark_labels(&pos, (r.0.start, r.0.end), gap)
        };
        let rows_of = |l: &[(i32, usize)]| l.iter().map(|p| p.1 + 1).max().unwrap_or(0);
        let first = style::chart(&area, o, xr, yr, Frame::default())?;
        let rows = rows_of(&layout_on(&first));
        drop(first);
        let frame = Frame {
            top: rows as f64 * row_h,
            ..Frame::default()
        };
        let (mut chart, place, frame) = style::chart_with_legend(&area, o, xr, yr, frame, &legend, &data, &[])?;
        let mut layout = layout_on(&chart);
        if rows_of(&layout) > rows {
            let f = Frame {
                top: rows_of(&layout) as f64 * row_h,
                ..frame
            };
            chart = style::chart(&area, o, xr, yr, f)?;
            layout = layout_on(&chart);
        }
        let xl = o.x_label.clone().unwrap_or_else(|| "forward speed v (m/s)".into());
        let yl = o.y_label.clone().unwrap_or_else(|| "eigenvalue (1/s)".into());
        style::mesh(&mut chart, o, &xl, &yl)?;
        for (lo, hi) in &stable {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(*lo, yr.0), (*hi, yr.1)],
                    BAND.mix(0.13).filled(),
                )))
                .map_err(de)?;
        }
        if yr.0 <= 0.0 && yr.1 >= 0.0 {
            style::hline(&mut chart, o, 0.0)?;
        }
        for (v, _, _) in &marks {
            style::vline(&mut chart, o, *v, style::MARK)?;
        }
        // Curves: imaginary (dashed) first so real parts are on top.
        for imag in [true, false] {
            for c in self.curves.iter().filter(|c| c.imag == imag) {
                let s = if imag {
                    Stroke::dashed(CLASS_COLORS[c.class])
                } else {
                    Stroke::solid(CLASS_COLORS[c.class])
                };
                style::curve(&mut chart, o, &c.points, s)?;
            }
        }
        style::frame(&mut chart, o)?;
        for (v, _, y) in &marks {
            if let Some(y) = y.filter(|y| *y >= yr.0 && *y <= yr.1) {
                chart
                    .draw_series(std::iter::once(Circle::new((*v, y), o.pxu(4.0), BLACK.filled())))
                    .map_err(de)?;
            }
        }
        // Labels above the plot, bottom row nearest to it.
        let top = chart.plotting_area().get_pixel_range().1.start;
        let (ox, oy) = {
            let r = root.get_pixel_range();
            (r.0.start, r.1.start)
        };
        let total = rows_of(&layout);
        for (((_, sub, _), t), (left, row)) in marks.iter().zip(&texts).zip(&layout) {
            let y = top - (total - row) as i32 * o.pxi(row_h) - o.pxi(2.0);
            draw_subscripted(root, (left - ox, y - oy), ("v", sub, t), o)?;
        }
        legend.draw(root, &chart, o, place)
    }
}

fn fmt_speed(v: f64) -> String {
    format!("{v:.2}")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 20: the colours of merged pairs differ from every single
    /// mode's (and from one another).
    #[test]
    fn issue_20_merged_pair_colours_are_distinct() {
        let d = |a: RGBColor, b: RGBColor| {
            ((a.0 as f64 - b.0 as f64).powi(2) + (a.1 as f64 - b.1 as f64).powi(2) + (a.2 as f64 - b.2 as f64).powi(2))
                .sqrt()
        };
        for merged in 3..6 {
            for other in 0..7 {
                if other != merged {
                    let dist = d(CLASS_COLORS[merged], CLASS_COLORS[other]);
                    assert!(dist > 60.0, "{} vs {}: {dist}", CLASS_NAMES[merged], CLASS_NAMES[other]);
                }
            }
        }
    }

    /// Issue 20: labels of close speeds go on separate rows; distant ones
    /// share the first.
    #[test]
    fn issue_20_mark_labels_keep_apart() {
        let l = layout_mark_labels(&[(100, 80), (130, 80), (400, 80)], (0, 800), 10);
        assert_eq!(l[0].1, 0);
        assert_eq!(l[1].1, 1);
        assert_eq!(l[2].1, 0);
        // Clamped inside the plot.
        assert_eq!(layout_mark_labels(&[(5, 80)], (0, 800), 10)[0].0, 0);
    }
}
