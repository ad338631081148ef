//! Text and JSON of the analysis commands (stability, canonical matrices,
//! state-space matrices, model listings, parameter files), shared by the
//! commands that print them and by `report`.

use anyhow::Result;
use bikedyn::bicycle::files::ParameterFile;
use bikedyn::bicycle::Bicycle;
use bikedyn::canonical::CanonicalMatrices;
use bikedyn::report::output;
use bikedyn::stability::{CriticalSpeeds, CrossingDirection, CrossingKind};

/// The stability of bicycle `name` in words; `controlled`: its file's
/// `[feedback]` closes the loop, so it is stable with it, not self-stable.
pub fn stability_text(name: &str, c: &CriticalSpeeds, controlled: bool) -> String {
    let stable = if controlled {
        "stable with its [feedback] controller"
    } else {
        "self-stable"
    };
    let f = |x: Option<f64>| {
        x.map(|v| format!("{v:.10} m/s"))
            .unwrap_or_else(|| "none in range".into())
    };
    let mut s = format!("bicycle: {name}\n");
    s += &format!("  weave speed v_w:   {}\n", f(c.weave_speed));
    s += &format!("  capsize speed v_c: {}\n", f(c.capsize_speed));
    s += &format!("  weave real-pair merge v_d: {}\n", f(c.weave_real_pair_merge));
    if c.stable_intervals.is_empty() {
        s += &format!("  {stable}: never in the searched range\n");
    }
    for [lo, hi] in &c.stable_intervals {
        s += &format!("  {stable} from {lo:.4} to {hi:.4} m/s\n");
    }
    if !c.crossings.is_empty() {
        s += "  stability crossings (speed, mode, direction):\n";
    }
    for x in &c.crossings {
        let dir = match x.direction {
            CrossingDirection::Destabilizing => "becomes unstable",
            CrossingDirection::Stabilizing => "becomes stable",
        };
        let kind = match x.kind {
            CrossingKind::RealRoot => "real root through zero".to_string(),
            CrossingKind::ComplexPair => format!("oscillation, {:.4} rad/s", x.frequency),
        };
        s += &format!("    {:.10} m/s  {:<17}  {dir} ({kind})\n", x.speed, x.mode.name());
    }
    s
}

pub fn models_text(ms: &[bikedyn::registry::ModelInfo]) -> String {
    let mut s = String::new();
    for m in ms {
        s += &format!("{}\n  {}\n", m.name, m.doc);
        s += &format!(
            "  base {}, {} speed; effects: {}\n",
            m.base,
            if m.free_speed { "free" } else { "driven" },
            if m.effects.is_empty() {
                "none".to_string()
            } else {
                m.effects.join(", ")
            }
        );
        let coords: Vec<String> = m
            .coordinates
            .iter()
            .enumerate()
            .map(|(i, c)| {
                if m.independent.contains(&i) {
                    format!("{c}*")
                } else {
                    c.to_string()
                }
            })
            .collect();
        s += &format!("  coordinates (* independent): {}\n", coords.join(" "));
        let params: Vec<&str> = m.parameters.iter().map(|p| p.name).collect();
        s += &format!("  parameters: {}\n\n", params.join(" "));
    }
    s
}

/// A bicycle's parameters as TOML (its own form), followed by the effect
/// parameters of its model with their values, defaults and units.
pub fn params_show_text(b: &Bicycle, model: Option<&str>) -> Result<String> {
    let info = b.model(model)?;
    let mut s = b.parameters.to_toml_string();
    let effects: Vec<_> = info.parameters.iter().filter(|p| p.effect.is_some()).collect();
    // The parameters of the bodies the model adds (a leaning rider's),
    // which neither form's table holds: without them the file would not
    // read back as the same bicycle.
    let added: Vec<_> = info
        .parameters
        .iter()
        .enumerate()
        .filter(|&(i, p)| {
            p.effect.is_none()
                && info.forward_speed_parameter != Some(i)
                && !bikedyn::bicycle::ThesisParameters::SYMBOLS.contains(&p.name)
        })
        .map(|(_, p)| p)
        .collect();
    s += &format!("# model: {} ({})\n", info.name, info.doc);
    for p in &added {
        let v = b.effects.get(p.name).copied().or(p.default).unwrap_or(f64::NAN);
        let line = format!("{} = {v:?}", p.name);
        s += &format!("{line:<32} # {} [added body]\n", p.doc);
    }
    if effects.is_empty() {
        s += "# this model has no effect parameters (see `bikedyn models`)\n";
    }
    for p in effects {
        let v = b.effects.get(p.name).copied().or(p.default).unwrap_or(f64::NAN);
        let line = format!("{} = {v:?}", p.name);
        s += &format!("{line:<32} # {} [effect {}]\n", p.doc, p.effect.unwrap_or(""));
    }
    if !b.uncertainties.is_empty() {
        s += "# standard deviations the file gives (`value+/-std`, in the file's symbols and units; identification uses them as priors):\n";
        for (sym, std) in &b.uncertainties {
            let value = b.value(sym).or_else(|| b.effects.get(sym).copied());
            let value = value.map_or(String::new(), |v| format!("{} ", output::format_significant(v, 6)));
            s += &format!("#   {sym:<8} = {value}+/- {}\n", output::format_significant(*std, 3));
        }
    }
    Ok(s)
}

/// Canonical matrices for people: 12 significant digits relative to each
/// matrix's largest entry, no negative zero (the JSON keeps full precision).
pub fn canonical_text(c: &CanonicalMatrices) -> String {
    let m = |name: &str, x: &nalgebra::Matrix2<f64>| {
        let e = output::format_matrix_entries(&[x[(0, 0)], x[(0, 1)], x[(1, 0)], x[(1, 1)]], 12);
        let w = e.iter().map(String::len).max().unwrap_or(0);
        format!(
            "{name} = [[{:>w$}, {:>w$}],\n      [{:>w$}, {:>w$}]]\n",
            e[0], e[1], e[2], e[3]
        )
    };
    format!(
        "{}{}{}{}g = {}\n",
        m("M0", &c.m0),
        m("C1", &c.c1),
        m("K0", &c.k0),
        m("K2", &c.k2),
        c.g
    )
}

/// `NAME = [[a, b],\n       [c, d]]`: a matrix given row by row
/// (`entries`, `cols` per row), 10 significant digits, columns aligned.
pub fn matrix_text(name: &str, cols: usize, entries: &[f64]) -> String {
    let e = output::format_matrix_entries(entries, 10);
    let w = e.iter().map(String::len).max().unwrap_or(0);
    let rows = entries.len() / cols.max(1);
    let mut s = String::new();
    for i in 0..rows {
        let open = if i == 0 {
            format!("{name} = [[")
        } else {
            format!("{}[", " ".repeat(name.len() + 4))
        };
        let close = if i + 1 == rows { "]]" } else { "]," };
        let cells: Vec<String> = e[cols * i..cols * (i + 1)].iter().map(|c| format!("{c:>w$}")).collect();
        s += &format!("{open}{}{close}\n", cells.join(", "));
    }
    s
}
