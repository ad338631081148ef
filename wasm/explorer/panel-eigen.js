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

  // The diagram's points come as columns of numbers (`explore`, as `eig`
  // with `arrays`, wasm/README.md), not one object per speed: text for
  // 1,000 speeds took longer to write, decode and parse than the
  // eigenvalues to compute.
  // Speed i is v[i]; its four eigenvalues are eigenvalues[8i .. 8i + 8]
  // (re, im in turn), with modes mode_names[modes[4i + k]]; a model's tyre
  // states add extra_per_speed more from extra_eigenvalues.

  // The figures read the eigenvalues straight from these arrays, without
  // an object or a callback per eigenvalue: the diagram is redrawn after
  // every change, and its 1,000 speeds were drawn in more time than the
  // module took to compute them otherwise (2026-11-30).

  /** Eigenvalue k of speed i in the arrays of `eig` (its four, then its tyre states'): the index of its real part in `z` or `x`. */
  const at = (e, i, k) => (k < 4 ? 8 * i + 2 * k : 2 * (e * i + k - 4));

  /**
   * The series of the diagram: per mode and rank (by real part, the largest
   * first), the real and imaginary parts over speed as flat lists
   * (`[v, re, v, re, ...]`, the first `n` numbers of `re` and `im`; a NaN
   * pair breaks the line). A series has a point and at most one break per
   * speed: its lists are made that long at once. Modes are handled by their
   * index in `mode_names` (a tyre state's is one past them, "extra"), not
   * by name: the diagram is redrawn after every change.
   */
  function eigSeries(eig) {
    const { v, eigenvalues: z, extra_eigenvalues: x, modes } = eig.arrays;
    const e = eig.extra_per_speed;
    const names = eig.mode_names.concat(["extra"]);
    const EXTRA = names.length - 1;
    const series = []; // in the order first met
    const byMode = names.map(() => null); // mode index -> its series by rank
    // One speed's eigenvalues in the upper half plane (a conjugate pair is drawn once).
    const re = [], im = [], mode = [], done = [], group = [];
    for (let i = 0; i < eig.count; i++) {
      let n = 0;
      for (let k = 0; k < 4 + e; k++) {
        const w = k < 4 ? z : x;
        const j = at(e, i, k);
        if (w[j + 1] < 0) continue;
        re[n] = w[j];
        im[n] = w[j + 1];
        mode[n] = k < 4 ? modes[4 * i + k] : EXTRA;
        done[n] = false;
        n += 1;
      }
      for (let j = 0; j < n; j++) {
        if (done[j]) continue;
        // This mode's eigenvalues, the largest real part first (on a tie, in their order).
        let g = 0;
        for (let l = j; l < n; l++) {
          if (mode[l] !== mode[j]) continue;
          done[l] = true;
          let q = g++;
          for (; q > 0 && re[group[q - 1]] < re[l]; q--) group[q] = group[q - 1];
          group[q] = l;
        }
        const ranks = byMode[mode[j]] || (byMode[mode[j]] = []);
        for (let r = 0; r < g; r++) {
          if (!ranks[r]) series.push((ranks[r] = { mode: names[mode[j]], re: new Float64Array(4 * eig.count), im: new Float64Array(4 * eig.count), n: 0, last: -1 }));
          const s = ranks[r];
          // Pad the gap since the series' last point (a pair that merged or split).
          if (s.n && s.last !== i - 1) {
            s.re[s.n] = s.im[s.n] = s.re[s.n + 1] = s.im[s.n + 1] = NaN;
            s.n += 2;
          }
          const l = group[r];
          s.re[s.n] = s.im[s.n] = v[i];
          s.re[s.n + 1] = re[l];
          s.im[s.n + 1] = im[l] > 1e-9 ? im[l] : NaN;
          s.n += 2;
          s.last = i;
        }
      }
    }
    return series;
  }

  function eigLimits(eig, clip = 10) {
    let lo = Infinity;
    let hi = -Infinity;
    // Every real part and every imaginary part's size, finite.
    for (const w of [eig.arrays.eigenvalues, eig.arrays.extra_eigenvalues]) {
      for (let j = 0; j < w.length; j++) {
        const x = j % 2 ? Math.abs(w[j]) : w[j];
        if (!Number.isFinite(x)) continue;
        lo = Math.min(lo, x);
        hi = Math.max(hi, x);
      }
    }
    lo = Math.max(lo, -clip);
    hi = Math.min(hi, clip);
    if (!(hi > lo)) [lo, hi] = [-1, 1];
    return P.niceLimits(lo, hi, 8);
  }

  /** The eigenvalue diagram's figure (plot.js): painted on the page, written as SVG for its download. */
  function eigFigure(width = 760, height = 440) {
    const xlim = [app.state.vmin, app.state.vmax];
    const ylim = eigLimits(app.eig);
    const fig = P.figure({ width, height, xlim, ylim, xlabel: "forward speed v (m/s)", ylabel: "eigenvalue (1/s)", margin: { top: 36 } });
    const top = fig.margin.top;
    const bottom = top + fig.ph;
    // The self-stable band(s).
    const band = app.stableIntervals || [];
    for (const [a, b] of band) {
      const x0 = fig.x(Math.max(a, xlim[0]));
      const x1 = fig.x(b === null || b === undefined ? xlim[1] : Math.min(b, xlim[1]));
      fig.add(P.shape("rect", { "data-band": 1, x: x0, y: top, width: Math.max(0, x1 - x0), height: fig.ph, fill: "#d9f0d3", stroke: "none" }));
    }
    const series = eigSeries(app.eig);
    // Each series' lists become its lines' pixels (they are the figure's own).
    for (const s of series) fig.add(P.line(fig, s.im, { stroke: modeColour(s.mode), "stroke-dasharray": "6 4", "stroke-width": 1.6 }, s.n, s.im));
    for (const s of series) fig.add(P.line(fig, s.re, { stroke: modeColour(s.mode), "stroke-width": 2 }, s.n, s.re));
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
      fig.add(P.shape("line", { x1: x, y1: top, x2: x, y2: bottom, stroke: "#333", "stroke-width": 0.9, "stroke-dasharray": "2 3" }));
      const text = `${label} = ${fmt(v, 3)}`;
      const w = text.length * 6;
      // Inside the plot's width: anchored at the start near the left edge, at the end near the right.
      const left = Math.min(Math.max(x - w / 2, fig.margin.left), fig.margin.left + fig.pw - w);
      const row = left < lastRight + 4 ? 1 : 0;
      lastRight = row ? lastRight : left + w;
      fig.over(P.text(left, top - 6 - row * 12, text, { "data-critical": what, "font-size": 11 }));
    }
    // The slider's speed.
    if (app.state.speed >= xlim[0] && app.state.speed <= xlim[1]) {
      const x = fig.x(app.state.speed);
      fig.add(P.shape("line", { x1: x, y1: top, x2: x, y2: bottom, stroke: "#888", "stroke-width": 1.2 }));
    }
    const modes = [...new Set(series.map((s) => s.mode))];
    const items = modes.map((m) => ({ label: m === "extra" ? "tyre states" : m, color: modeColour(m) }));
    items.push({ label: "real part", color: "#000" }, { label: "imaginary part", color: "#000", dash: "6 4" });
    if (band.length) items.push({ label: "self-stable", fill: "#d9f0d3" });
    fig.over(P.legend(fig, items, "bottom-right"));
    return fig;
  }

  const eigFigureSvg = () => eigFigure().svg();

  /** The canvas of figure `id`'s element (made on first use). */
  function canvasOf(id) {
    const host = $(id);
    let c = host.firstElementChild;
    if (!c || c.tagName !== "CANVAS") {
      host.textContent = "";
      c = host.appendChild(document.createElement("canvas"));
    }
    return c;
  }

  /**
   * Paints the eigenvalue diagram. What it shows is also written on its
   * canvas as data attributes (the number of lines and bands, the critical
   * speeds' labels), for the page's tests: a canvas keeps no elements.
   */
  function drawDiagram() {
    const fig = eigFigure();
    const c = canvasOf("eig-plot");
    fig.paint(c);
    let lines = 0;
    let bands = 0;
    const labels = {};
    for (const s of fig.shapes()) {
      if (s.tag === "polyline") lines += 1;
      else if (s.a["data-band"]) bands += 1;
      else if (s.a["data-critical"]) labels[s.a["data-critical"]] = s.text;
    }
    c.dataset.lines = String(lines);
    c.dataset.bands = String(bands);
    for (const what of ["weave", "capsize", "merge"]) {
      if (what in labels) c.dataset[what] = labels[what];
      else delete c.dataset[what];
    }
  }

  function renderCritical() {
    const c = $("critical");
    const v = (x) => fmt(x, 4);
    const bands = app.stableIntervals && app.stableIntervals.length
      ? app.stableIntervals.map(([a, b]) => `${fmt(a, 3)}\u2013${b === null || b === undefined ? "\u221e" : fmt(b, 3)}`).join(", ") + " m/s"
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

  /** The slider's speed: its eigenvalues and mode shapes asked for, then shown. */
  function updateSpeed() {
    const r = call(withModel({ job: "eig", bicycle: bicycleSpec(), speeds: [app.state.speed], standard_deviations: false }));
    app.atSpeed = r.ok ? r.ok.points[0] : null;
    if (app.eig) drawDiagram();
    showSpeed();
  }

  /** The panels of the slider's speed (`app.atSpeed`): its text, table, mode shapes and the root locus. */
  function showSpeed() {
    $("speed-out").textContent = `${fmt(app.state.speed, 2)} m/s`;
    if (app.eig) drawLocus();
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

  /** The root locus's figure (plot.js): painted on the page, written as SVG for its download. */
  function locusFigure(width = 760, height = 420) {
    const eig = app.eig;
    const { eigenvalues: z, extra_eigenvalues: x } = eig.arrays;
    const e = eig.extra_per_speed;
    let xlo = Infinity, xhi = -Infinity, yhi = 0;
    for (const w of [z, x]) {
      for (let j = 0; j < w.length; j += 2) {
        xlo = Math.min(xlo, w[j]);
        xhi = Math.max(xhi, w[j]);
        yhi = Math.max(yhi, Math.abs(w[j + 1]));
      }
    }
    const clip = 12;
    const xlim = P.niceLimits(Math.max(xlo, -clip), Math.min(xhi, clip), 8);
    const ym = P.niceLimits(0, Math.max(1, Math.min(yhi, clip)), 4)[1];
    const fig = P.figure({ width, height, xlim, ylim: [-ym, ym], xlabel: "real part (1/s)", ylabel: "imaginary part (1/s)", zeroX: true, margin: { right: 90 } });
    const [v0, v1] = [app.state.vmin, app.state.vmax];
    // The points as dots, one shape per colour, the colour bar's 48 steps
    // (in SVG one path each: 4,000 circle elements took the browser 36 ms
    // to parse and lay out, 2026-11-29); the colours' points in one typed
    // array, counted first.
    const colour = new Int32Array(eig.count);
    const start = new Int32Array(LOCUS_COLOURS + 1);
    for (let i = 0; i < eig.count; i++) {
      const t = (eig.arrays.v[i] - v0) / (v1 - v0 || 1);
      colour[i] = Math.max(0, Math.min(LOCUS_COLOURS - 1, Math.floor(t * LOCUS_COLOURS)));
      start[colour[i] + 1] += 2 * (4 + e);
    }
    for (let k = 0; k < LOCUS_COLOURS; k++) start[k + 1] += start[k];
    const pts = new Float64Array(start[LOCUS_COLOURS]);
    const end = start.slice(0, LOCUS_COLOURS);
    for (let i = 0; i < eig.count; i++) {
      for (let m = 0; m < 4 + e; m++) {
        const w = m < 4 ? z : x;
        const j = at(e, i, m);
        pts[end[colour[i]]++] = fig.x(w[j]);
        pts[end[colour[i]]++] = fig.y(w[j + 1]);
      }
    }
    for (let k = 0; k < LOCUS_COLOURS; k++) {
      const n = end[k] - start[k];
      if (n) fig.add(P.shape("dots", { "data-locus": n / 2, stroke: P.viridis((k + 0.5) / LOCUS_COLOURS), "stroke-width": 4.2 }, { pts: pts.subarray(start[k], end[k]) }));
    }
    if (app.atSpeed) {
      for (const [re, im] of app.atSpeed.eigenvalues.concat(app.atSpeed.extra_eigenvalues || [])) {
        fig.add(P.shape("circle", { cx: fig.x(re), cy: fig.y(im), r: 5.5, fill: "none", stroke: "#d00", "stroke-width": 1.6 }));
      }
      fig.over(P.text(fig.margin.left + 6, fig.margin.top + 14, `\u25cb v = ${fmt(app.state.speed, 2)} m/s`, { "font-size": 11, fill: "#d00" }));
    }
    fig.over(P.colorbar(fig, v0, v1, P.viridis, "speed v (m/s)"));
    return fig;
  }

  const locusSvg = () => locusFigure().svg();

  /** Paints the root locus; its number of points is written on its canvas (as the diagram's, for the tests). */
  function drawLocus() {
    const fig = locusFigure();
    const c = canvasOf("locus-plot");
    fig.paint(c);
    c.dataset.points = String(fig.shapes().reduce((n, s) => n + (s.tag === "dots" ? s.a["data-locus"] : 0), 0));
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
  Object.assign(app, { eigFigureSvg, drawDiagram, renderCritical, showSpeed, modesSvg, locusSvg, readSpeedInputs, syncSlider, setSpeed });
})(window.Explorer);
