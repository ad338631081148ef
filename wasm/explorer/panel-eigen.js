// The eigenvalues panel: the eigenvalues over speed (coloured by mode, the
// critical speeds marked, the self-stable band shaded), the speed range and
// the slider, and at the slider's speed the eigenvalue table, the modes'
// roll and steer phasors and the root locus.
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const P = BikedynPlot;
  const { $, DEG, call, fmt, sig, bicycleSpec, withModel, schedule, writeHash } = app;

  // Okabe and Ito's colour-blind-safe colours, one per mode.
  const MODE_COLOURS = { weave: "#0072B2", capsize: "#D55E00", castering: "#009E73", other: "#7f7f7f", extra: "#E69F00" };
  const modeColour = (m) => MODE_COLOURS[m] || "#CC79A7"; // a merged pair's name

  // ---- eigenvalues over speed ------------------------------------------------

  // The diagram's points come as columns of numbers (`eig` with `arrays`,
  // wasm/README.md), not one object per speed: text for 1,000 speeds took
  // longer to write, decode and parse than the eigenvalues to compute.
  // Speed i is v[i]; its four eigenvalues are eigenvalues[8i .. 8i + 8]
  // (re, im in turn), with modes mode_names[modes[4i + k]]; a model's tyre
  // states add extra_per_speed more from extra_eigenvalues.

  /** Calls f(re, im, mode) for each eigenvalue at speed i of the diagram `eig` ("extra": a tyre state's). */
  function eigenvaluesAt(eig, i, f) {
    const { eigenvalues: z, modes, extra_eigenvalues: x } = eig.arrays;
    for (let k = 0; k < 4; k++) f(z[8 * i + 2 * k], z[8 * i + 2 * k + 1], eig.mode_names[modes[4 * i + k]]);
    const e = eig.extra_per_speed;
    for (let k = e * i; k < e * (i + 1); k++) f(x[2 * k], x[2 * k + 1], "extra");
  }

  /** The series of the eig plot: per mode and rank, real and imaginary parts over speed. */
  function eigSeries(eig) {
    const series = new Map(); // key -> {mode, re: [[v, re]], im: [[v, im]]}
    const get = (key, mode) => {
      if (!series.has(key)) series.set(key, { mode, re: [], im: [] });
      return series.get(key);
    };
    const v = eig.arrays.v;
    for (let i = 0; i < eig.count; i++) {
      const groups = {};
      eigenvaluesAt(eig, i, (re, im, mode) => {
        if (im < 0) return; // a conjugate pair is drawn once
        (groups[mode] ||= []).push([re, im]);
      });
      for (const [mode, list] of Object.entries(groups)) {
        list.sort((a, b) => b[0] - a[0]);
        list.forEach(([re, im], k) => {
          const s = get(`${mode}#${k}`, mode);
          // Pad the gap since the series' last point (a pair that merged or split).
          if (s.re.length && s.last !== i - 1) {
            s.re.push([NaN, NaN]);
            s.im.push([NaN, NaN]);
          }
          s.re.push([v[i], re]);
          s.im.push([v[i], im > 1e-9 ? im : NaN]);
          s.last = i;
        });
      }
    }
    return [...series.values()];
  }

  function eigLimits(eig, clip = 10) {
    let lo = Infinity;
    let hi = -Infinity;
    for (let i = 0; i < eig.count; i++) {
      eigenvaluesAt(eig, i, (re, im) => {
        for (const x of [re, Math.abs(im)]) {
          if (!Number.isFinite(x)) continue;
          lo = Math.min(lo, x);
          hi = Math.max(hi, x);
        }
      });
    }
    lo = Math.max(lo, -clip);
    hi = Math.min(hi, clip);
    if (!(hi > lo)) [lo, hi] = [-1, 1];
    return P.niceLimits(lo, hi, 8);
  }

  function eigFigureSvg(width = 760, height = 440) {
    const xlim = [app.state.vmin, app.state.vmax];
    const ylim = eigLimits(app.eig);
    const fig = P.figure({ width, height, xlim, ylim, xlabel: "forward speed v (m/s)", ylabel: "eigenvalue (1/s)", margin: { top: 36 } });
    // The self-stable band(s).
    const band = app.stab ? app.stab.stable_intervals : [];
    for (const [a, b] of band) {
      const x0 = fig.x(Math.max(a, xlim[0]));
      const x1 = fig.x(b === null || b === undefined ? xlim[1] : Math.min(b, xlim[1]));
      fig.add(`<rect data-band="1" x="${P.n(x0)}" y="${P.n(fig.margin.top)}" width="${P.n(Math.max(0, x1 - x0))}" height="${P.n(fig.ph)}" fill="#d9f0d3" stroke="none"/>`);
    }
    const series = eigSeries(app.eig);
    for (const s of series) fig.add(P.line(fig, s.im, { stroke: modeColour(s.mode), "stroke-dasharray": "6 4", "stroke-width": 1.6 }));
    for (const s of series) fig.add(P.line(fig, s.re, { stroke: modeColour(s.mode), "stroke-width": 2 }));
    // Critical speeds.
    const marks = [
      ["v_w", app.eig.weave_speed, "weave"],
      ["v_c", app.eig.capsize_speed, "capsize"],
      ["v_d", app.eig.weave_real_pair_merge_speed, "merge"],
    ];
    let lastRight = -Infinity; // labels that would overlap go up a line
    const shownMarks = marks.filter(([, v]) => v !== null && v !== undefined && Number.isFinite(v) && v >= xlim[0] && v <= xlim[1]);
    shownMarks.sort((a, b) => a[1] - b[1]);
    for (const [label, v, what] of shownMarks) {
      const x = fig.x(v);
      fig.add(`<line x1="${P.n(x)}" y1="${P.n(fig.margin.top)}" x2="${P.n(x)}" y2="${P.n(fig.margin.top + fig.ph)}" stroke="#333" stroke-width="0.9" stroke-dasharray="2 3"/>`);
      const text = `${label} = ${fmt(v, 3)}`;
      const w = text.length * 6;
      // Inside the plot's width: anchored at the start near the left edge, at the end near the right.
      const left = Math.min(Math.max(x - w / 2, fig.margin.left), fig.margin.left + fig.pw - w);
      const row = left < lastRight + 4 ? 1 : 0;
      lastRight = row ? lastRight : left + w;
      fig.over(`<text data-critical="${what}" x="${P.n(left)}" y="${P.n(fig.margin.top - 6 - row * 12)}" font-size="11">${text}</text>`);
    }
    // The slider's speed.
    if (app.state.speed >= xlim[0] && app.state.speed <= xlim[1]) {
      const x = fig.x(app.state.speed);
      fig.add(`<line x1="${P.n(x)}" y1="${P.n(fig.margin.top)}" x2="${P.n(x)}" y2="${P.n(fig.margin.top + fig.ph)}" stroke="#888" stroke-width="1.2"/>`);
    }
    const modes = [...new Set(series.map((s) => s.mode))];
    const items = modes.map((m) => ({ label: m === "extra" ? "tyre states" : m, color: modeColour(m) }));
    items.push({ label: "real part", color: "#000" }, { label: "imaginary part", color: "#000", dash: "6 4" });
    if (band.length) items.push({ label: "self-stable", fill: "#d9f0d3" });
    fig.over(P.legend(fig, items, "bottom-right"));
    return fig.svg();
  }

  function renderCritical() {
    const c = $("critical");
    const v = (x) => fmt(x, 4);
    const bands = app.stab && app.stab.stable_intervals.length
      ? app.stab.stable_intervals.map(([a, b]) => `${fmt(a, 3)}\u2013${b === null || b === undefined ? "\u221e" : fmt(b, 3)}`).join(", ") + " m/s"
      : "none in the range";
    c.innerHTML = `<span>weave speed v<sub>w</sub> = <b id="v-weave"></b> m/s</span>
      <span>capsize speed v<sub>c</sub> = <b id="v-capsize"></b> m/s</span>
      <span>weave pair merge v<sub>d</sub> = <b id="v-merge"></b> m/s</span>
      <span>self-stable: <b id="v-band"></b></span>`;
    $("v-weave").textContent = v(app.eig.weave_speed);
    $("v-capsize").textContent = v(app.eig.capsize_speed);
    $("v-merge").textContent = v(app.eig.weave_real_pair_merge_speed);
    $("v-band").textContent = bands;
  }

  // ---- the slider's speed: table, mode shapes, root locus ------------------

  function updateSpeed() {
    $("speed-out").textContent = `${fmt(app.state.speed, 2)} m/s`;
    const r = call(withModel({ job: "eig", bicycle: bicycleSpec(), speeds: [app.state.speed] }));
    app.atSpeed = r.ok ? r.ok.points[0] : null;
    if (app.eig) {
      $("eig-plot").innerHTML = eigFigureSvg();
      $("locus-plot").innerHTML = locusSvg();
    }
    renderEigTable();
    $("modes").innerHTML = app.atSpeed ? modesSvg() : "";
  }

  function renderEigTable() {
    const tbody = $("eig-table").tBodies[0];
    tbody.innerHTML = "";
    if (!app.atSpeed) return;
    const rows = app.atSpeed.eigenvalues.map((e, k) => [app.atSpeed.modes[k], e]);
    for (const e of app.atSpeed.extra_eigenvalues || []) rows.push(["tyre state", e]);
    for (const [mode, [re, im]] of rows) {
      const tr = document.createElement("tr");
      const f = Math.abs(im) / (2 * Math.PI);
      const cells = [
        mode, sig(re, 5), sig(im, 5), im ? sig(f, 4) : "\u2014", im ? sig(1 / f, 4) : "\u2014",
        re ? `${sig(1 / Math.abs(re), 4)} ${re > 0 ? "(growth)" : "(decay)"}` : "\u2014",
      ];
      tr.innerHTML = cells.map(() => "<td></td>").join("");
      cells.forEach((c, i) => (tr.cells[i].textContent = c));
      tr.cells[0].style.color = modeColour(mode === "tyre state" ? "extra" : mode);
      if (re > 0) tr.classList.add("unstable");
      tbody.appendChild(tr);
    }
  }

  /** Roll and steer phasors of each mode at the slider's speed (a conjugate pair once). */
  function modesSvg() {
    const p = app.atSpeed;
    const shown = p.eigenvalues.map((e, k) => k).filter((k) => p.eigenvalues[k][1] >= 0);
    const size = 200;
    const W = Math.max(size * Math.max(1, shown.length), 560);
    const H = size + 62;
    const g = [`<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H}" viewBox="0 0 ${W} ${H}" font-family="Helvetica, Arial, sans-serif" font-size="12">`, `<rect width="${W}" height="${H}" fill="#fff"/>`,
      `<defs><marker id="arr" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" orient="auto-start-reverse"><path d="M0,0 L10,5 L0,10 z" fill="context-stroke"/></marker></defs>`];
    shown.forEach((k, col) => {
      const cx = col * size + size / 2;
      const cy = 30 + (size - 30) / 2 + 4;
      const R = (size - 50) / 2;
      const sh = p.mode_shapes[k];
      const scale = Math.max(sh.roll_amplitude, sh.steer_amplitude) || 1;
      const [re, im] = p.eigenvalues[k];
      g.push(`<text x="${P.n(cx)}" y="14" text-anchor="middle" font-weight="bold" fill="${modeColour(p.modes[k])}">${P.esc(p.modes[k])}</text>`);
      g.push(`<text x="${P.n(cx)}" y="28" text-anchor="middle">\u03bb = ${P.esc(sig(re, 4))}${im ? ` \u00b1 ${P.esc(sig(im, 4))}i` : ""} 1/s</text>`);
      g.push(`<circle cx="${P.n(cx)}" cy="${P.n(cy)}" r="${P.n(R)}" fill="none" stroke="#ccc"/>`);
      g.push(`<line x1="${P.n(cx - R - 4)}" y1="${P.n(cy)}" x2="${P.n(cx + R + 4)}" y2="${P.n(cy)}" stroke="#ddd"/><line x1="${P.n(cx)}" y1="${P.n(cy - R - 4)}" x2="${P.n(cx)}" y2="${P.n(cy + R + 4)}" stroke="#ddd"/>`);
      const arrow = (amp, phase, colour) => {
        const L = (amp / scale) * R;
        const x = cx + L * Math.cos(phase);
        const y = cy - L * Math.sin(phase);
        return `<line x1="${P.n(cx)}" y1="${P.n(cy)}" x2="${P.n(x)}" y2="${P.n(y)}" stroke="${colour}" stroke-width="2.2" marker-end="url(#arr)"/>`;
      };
      g.push(arrow(sh.roll_amplitude, sh.roll_phase, "#222"));
      g.push(arrow(sh.steer_amplitude, sh.steer_phase, "#CC79A7"));
      g.push(`<text x="${P.n(cx)}" y="${P.n(size + 26)}" text-anchor="middle" fill="#222">roll ${P.esc(sig(sh.roll_amplitude, 3))} \u2220 ${P.esc(fmt(sh.roll_phase * DEG, 0))}\u00b0</text>`);
      g.push(`<text x="${P.n(cx)}" y="${P.n(size + 41)}" text-anchor="middle" fill="#CC79A7">steer ${P.esc(sig(sh.steer_amplitude, 3))} \u2220 ${P.esc(fmt(sh.steer_phase * DEG, 0))}\u00b0</text>`);
    });
    g.push(`<text x="4" y="${H - 6}" fill="#666" font-size="10">v = ${P.esc(fmt(p.v, 2))} m/s; amplitudes relative to roll (benchmark signs: roll and steer positive to the right)</text>`);
    g.push("</svg>");
    return g.join("\n");
  }

  const LOCUS_COLOURS = 48; // the colour bar's steps (plot.js)

  function locusSvg(width = 760, height = 420) {
    const eig = app.eig;
    let xlo = Infinity, xhi = -Infinity, yhi = 0;
    for (let i = 0; i < eig.count; i++) {
      eigenvaluesAt(eig, i, (re, im) => {
        xlo = Math.min(xlo, re);
        xhi = Math.max(xhi, re);
        yhi = Math.max(yhi, Math.abs(im));
      });
    }
    const clip = 12;
    const xlim = P.niceLimits(Math.max(xlo, -clip), Math.min(xhi, clip), 8);
    const ym = P.niceLimits(0, Math.max(1, Math.min(yhi, clip)), 4)[1];
    const fig = P.figure({ width, height, xlim, ylim: [-ym, ym], xlabel: "real part (1/s)", ylabel: "imaginary part (1/s)", zeroX: true, margin: { right: 90 } });
    const [v0, v1] = [app.state.vmin, app.state.vmax];
    // The points as dots (zero-length strokes with round caps), one path
    // per colour, the colour bar's 48 steps: 4,000 circle elements took
    // the browser 36 ms to parse and lay out at every redraw (1,000 speeds,
    // 2026-11-29), more than all else of it.
    const dots = Array.from({ length: LOCUS_COLOURS }, () => []);
    for (let i = 0; i < eig.count; i++) {
      const t = (eig.arrays.v[i] - v0) / (v1 - v0 || 1);
      const k = Math.max(0, Math.min(LOCUS_COLOURS - 1, Math.floor(t * LOCUS_COLOURS)));
      eigenvaluesAt(eig, i, (re, im) => dots[k].push(`M${P.n(fig.x(re))} ${P.n(fig.y(im))}h0`));
    }
    dots.forEach((d, k) => {
      if (d.length) fig.add(`<path data-locus="${d.length}" d="${d.join("")}" fill="none" stroke="${P.viridis((k + 0.5) / LOCUS_COLOURS)}" stroke-width="4.2" stroke-linecap="round"/>`);
    });
    if (app.atSpeed) {
      for (const [re, im] of app.atSpeed.eigenvalues.concat(app.atSpeed.extra_eigenvalues || [])) {
        fig.add(`<circle cx="${P.n(fig.x(re))}" cy="${P.n(fig.y(im))}" r="5.5" fill="none" stroke="#d00" stroke-width="1.6"/>`);
      }
      fig.over(`<text x="${P.n(fig.margin.left + 6)}" y="${P.n(fig.margin.top + 14)}" font-size="11" fill="#d00">\u25cb v = ${fmt(app.state.speed, 2)} m/s</text>`);
    }
    fig.over(P.colorbar(fig, v0, v1, P.viridis, "speed v (m/s)"));
    return fig.svg();
  }

  // ---- the speed range and the slider ------------------------------------------

  function readSpeedInputs() {
    const a = Number($("vmin").value);
    const b = Number($("vmax").value);
    const s = Number($("vstep").value);
    if (!(Number.isFinite(a) && Number.isFinite(b) && Number.isFinite(s) && b > a && s > 0)) return;
    if ((b - a) / s > 5000) return;
    app.state.vmin = a;
    app.state.vmax = b;
    app.state.vstep = s;
    syncSlider();
    schedule();
  }

  function syncSlider() {
    $("speed").min = String(app.state.vmin);
    $("speed").max = String(app.state.vmax);
    $("speed").value = String(app.state.speed);
    $("speed-num").value = String(app.state.speed);
  }

  function setSpeed(v) {
    if (!Number.isFinite(v)) return;
    app.state.speed = v;
    writeHash();
    if (document.activeElement !== $("speed-num")) $("speed-num").value = String(v);
    if (document.activeElement !== $("speed")) $("speed").value = String(v);
    updateSpeed();
  }

  // Used by the other files.
  Object.assign(app, { eigFigureSvg, renderCritical, updateSpeed, modesSvg, locusSvg, readSpeedInputs, syncSlider, setSpeed });
})(window.Explorer);
