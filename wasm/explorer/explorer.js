// The stability explorer: a static page over bikedyn's WebAssembly module
// (bikedyn.js). Every number comes from the module; this file only asks
// for it, draws it (plot.js) and keeps the page's state in its link
// (state.js). A classic script, so that the page also works as a file.
(function () {
  "use strict";
  const P = BikedynPlot;
  const S = ExplorerState;
  const $ = (id) => document.getElementById(id);

  // Okabe and Ito's colour-blind-safe colours, one per mode.
  const MODE_COLOURS = { weave: "#0072B2", capsize: "#D55E00", castering: "#009E73", other: "#7f7f7f", extra: "#E69F00" };
  const modeColour = (m) => MODE_COLOURS[m] || "#CC79A7"; // a merged pair's name
  const DEG = 180 / Math.PI;

  let bd = null; // the loaded module
  let state = S.decode(location.hash);
  let base = null; // the `bicycle` answer of the bicycle before edits
  let current = null; // ... after edits and effects
  let eig = null; // the `eig` answer over the speed range
  let stab = null; // the `stability` answer (self-stable band)
  let atSpeed = null; // the `eig` answer at the slider's speed
  let effectParams = []; // [{name, default, doc, effect}], the models' effect parameters
  let units = {}; // benchmark symbol -> {unit, what}, from the TOML's comments
  let mapResult = null;
  let simResult = null;

  // ---- module calls ---------------------------------------------------

  /** `{ok: answer}` or `{error: message}` (the module's message, verbatim). */
  function call(request) {
    try {
      return { ok: bd.call(request) };
    } catch (e) {
      return { error: e.message, kind: e.kind };
    }
  }

  function loadScript(src) {
    return new Promise((resolve, reject) => {
      const s = document.createElement("script");
      s.src = src;
      s.onload = resolve;
      s.onerror = () => reject(new Error(`could not load ${src} (build it: bash wasm/build.sh)`));
      document.head.appendChild(s);
    });
  }

  /** The module: fetched when the page is served, else from bikedyn-wasm.js (a file page may not fetch). */
  async function loadModule() {
    if (location.protocol === "http:" || location.protocol === "https:") {
      try {
        const r = await fetch("bikedyn.wasm");
        if (r.ok) return await Bikedyn.load(r);
      } catch (e) {
        // fall back to the script form
      }
    }
    if (typeof BIKEDYN_WASM_BASE64 === "undefined") await loadScript("bikedyn-wasm.js");
    return Bikedyn.load(bikedynBytesFromBase64(BIKEDYN_WASM_BASE64));
  }

  // ---- messages ---------------------------------------------------------

  function showError(message) {
    const e = $("error");
    e.textContent = message;
    e.hidden = !message;
  }
  function status(text) {
    $("status").textContent = text;
  }

  // ---- numbers ----------------------------------------------------------

  const fmt = (x, d = 4) => (x === null || x === undefined || !Number.isFinite(x) ? "\u2014" : x.toFixed(d));
  function sig(x, s = 5) {
    if (x === null || x === undefined || !Number.isFinite(x)) return "\u2014";
    if (x === 0) return "0";
    const a = Math.abs(x);
    if (a >= 1e5 || a < 1e-3) return x.toExponential(s - 1);
    return String(Number(x.toPrecision(s)));
  }

  // ---- the bicycle --------------------------------------------------------

  const benchmarkOrder = () => (base ? base.benchmark.map(([k]) => k) : []);

  /** The `set` list: the table's edits, the effects on, and the file's effects switched off (at their defaults). */
  function setList() {
    const set = S.setList(state, benchmarkOrder());
    if (base) {
      for (const k of Object.keys(base.effects || {})) {
        if (!(k in state.effects)) {
          const p = effectParams.find((q) => q.name === k);
          set.push([k, p && p.default !== null ? p.default : 0]);
        }
      }
    }
    return set;
  }

  function bicycleSpec(withSet = true) {
    const spec = S.bicycleSpec(state, benchmarkOrder(), false);
    if (withSet) spec.set = setList();
    return spec;
  }

  function withModel(req) {
    if (state.model) req.model = state.model;
    return req;
  }

  /** Units and meanings of the benchmark symbols, read from the TOML's comments (`w = 1.02  # wheelbase (m)`). */
  function readUnits(toml) {
    const out = {};
    for (const line of toml.split("\n")) {
      const m = /^(\w+)\s*=\s*\S+\s*#\s*(.*?)\s*(?:\(([^()]*)\))?\s*$/.exec(line);
      if (m) out[m[1]] = { what: m[2], unit: m[3] || "" };
    }
    return out;
  }

  /** The base bicycle (before edits): its values fill the table and mark the edits. */
  function loadBase() {
    const r = call({ job: "bicycle", bicycle: bicycleSpec(false) });
    if (r.error) {
      showError(r.error);
      return false;
    }
    base = r.ok;
    units = readUnits(base.toml);
    // Edits (from a link) that are the bicycle's own values are no edits.
    const values = Object.fromEntries(base.benchmark);
    for (const [k, v] of Object.entries(state.edits)) if (values[k] === v) delete state.edits[k];
    return true;
  }

  // ---- updating ---------------------------------------------------------

  let timer = null;
  let inFlight = false;
  let waiters = [];
  /** Recomputes and redraws in 100 ms (debounced); resolves when done. */
  function schedule() {
    clearTimeout(timer);
    timer = setTimeout(runUpdate, 100);
    return new Promise((resolve) => waiters.push(resolve));
  }
  function runUpdate() {
    timer = null;
    const w = waiters;
    waiters = [];
    // Say so, and let the page paint it, before the module works (a tyre
    // model's 200 speeds take a second).
    status("computing\u2026");
    inFlight = true;
    setTimeout(() => finishUpdate(w), 0);
  }
  function finishUpdate(w) {
    inFlight = false;
    if (timer) {
      // Changed again meanwhile: the next update answers these too.
      waiters.push(...w);
      return;
    }
    try {
      update();
    } catch (e) {
      showError(`explorer: ${e.message}`);
      console.error(e);
    }
    w.forEach((f) => f());
  }

  function writeHash() {
    const h = "#" + S.encode(state);
    if (location.hash !== h) history.replaceState(null, "", h);
  }

  function update() {
    writeHash();
    const spec = bicycleSpec();
    const b = call(withModel({ job: "bicycle", bicycle: spec }));
    if (b.error) {
      showError(b.error);
      status("error");
      markStale(true);
      return;
    }
    current = b.ok;
    const speeds = S.speedRange(state);
    const e = call(withModel({ job: "eig", bicycle: spec, speeds, critical_speeds: true }));
    if (e.error) {
      showError(e.error);
      status("error");
      renderBicycle();
      markStale(true);
      return;
    }
    showError("");
    eig = e.ok;
    const s = call(withModel({ job: "stability", bicycle: spec, speed_min: state.vmin, speed_max: state.vmax }));
    stab = s.ok || null;
    markStale(false);
    renderBicycle();
    renderCritical();
    updateSpeed();
    status(`${current.name} \u00b7 model ${eig.model} \u00b7 ${eig.points.length} speeds`);
  }

  function markStale(stale) {
    for (const id of ["eig-plot", "locus-plot", "modes", "critical"]) $(id).classList.toggle("stale", stale);
  }

  // ---- the parameter table, effects, derived rows -------------------------

  function renderBicycle() {
    $("bike-name").textContent = current ? current.name : "";
    $("bike-model").textContent = current ? current.model : "";
    const w = current && current.warnings.length ? current.warnings : [];
    $("warnings").hidden = !w.length;
    $("warnings").textContent = w.map((x) => `warning: ${x}`).join("\n");
    renderParams();
    renderDerived();
    syncEffects();
  }

  function renderParams() {
    const tbody = $("params").tBodies[0];
    const values = Object.fromEntries((current || base).benchmark);
    if (tbody.dataset.bike !== bikeKey()) {
      tbody.dataset.bike = bikeKey();
      tbody.innerHTML = "";
      for (const [sym, v] of base.benchmark) {
        const tr = document.createElement("tr");
        const u = units[sym] || { unit: "", what: "" };
        tr.innerHTML = `<td class="sym"></td><td><input type="text" inputmode="decimal" spellcheck="false"><button type="button" class="reset" title="back to the bicycle's value">\u21ba</button></td><td class="unit"></td><td class="what"></td>`;
        tr.cells[0].textContent = sym;
        tr.cells[2].textContent = u.unit;
        tr.cells[3].textContent = u.what;
        const input = tr.querySelector("input");
        input.dataset.symbol = sym;
        input.value = String(sym in state.edits ? state.edits[sym] : v);
        input.addEventListener("input", () => onParamInput(sym, input));
        tr.querySelector("button").addEventListener("click", () => {
          delete state.edits[sym];
          input.value = String(Object.fromEntries(base.benchmark)[sym]);
          input.classList.remove("invalid");
          tr.classList.remove("edited");
          schedule();
        });
        tbody.appendChild(tr);
      }
    }
    for (const tr of tbody.rows) {
      const input = tr.querySelector("input");
      const sym = input.dataset.symbol;
      tr.classList.toggle("edited", sym in state.edits);
      // The bicycle's value where not typed in (and not being typed).
      if (!(sym in state.edits) && document.activeElement !== input && sym in values) input.value = String(values[sym]);
    }
  }

  function bikeKey() {
    return `${state.bike}|${state.file ? state.file.name + state.file.text.length : ""}|${base ? base.name : ""}`;
  }

  function onParamInput(sym, input) {
    const text = input.value.trim();
    const v = Number(text);
    if (text === "" || !Number.isFinite(v)) {
      input.classList.add("invalid");
      return;
    }
    input.classList.remove("invalid");
    const original = Object.fromEntries(base.benchmark)[sym];
    if (v === original) delete state.edits[sym];
    else state.edits[sym] = v;
    input.closest("tr").classList.toggle("edited", sym in state.edits);
    schedule();
  }

  function renderDerived() {
    const tbody = $("derived").tBodies[0];
    tbody.innerHTML = "";
    if (!current) return;
    const row = (sym, v, unit, what, computed) => {
      const tr = document.createElement("tr");
      tr.innerHTML = "<td class=sym></td><td class=num></td><td class=unit></td><td class=what></td>";
      tr.cells[0].textContent = sym;
      tr.cells[1].textContent = sig(v, 6);
      tr.cells[2].textContent = unit;
      tr.cells[3].textContent = what + (computed ? " (computed on this page)" : "");
      if (computed) tr.classList.add("computed");
      tbody.appendChild(tr);
    };
    const d = Object.fromEntries(current.derived_geometry.map((r) => [r.symbol, r.value]));
    for (const r of current.derived_geometry) row(r.symbol, r.value, r.unit, r.what, false);
    // Radii of gyration, k = sqrt(I / m): the definition (e.g. Moore 2012,
    // "Human control of a bicycle", and bicycleparameters' bodies), as a
    // body's inertia is often compared across bicycles. The module gives
    // the inertias and masses, not these.
    const b = Object.fromEntries(current.benchmark);
    const k = (I, m) => (I > 0 && m > 0 ? Math.sqrt(I / m) : NaN);
    if ("IAll" in d && "mA" in d) row("kAll", k(d.IAll, d.mA), "m", "front assembly radius of gyration about the steer axis, sqrt(IAll/mA)", true);
    const bodies = [["R", "rear wheel"], ["B", "rear frame"], ["H", "front frame"], ["F", "front wheel"]];
    for (const [body, name] of bodies) {
      for (const ax of ["xx", "yy", "zz"]) {
        const I = b[`I${body}${ax}`];
        if (I === undefined) continue;
        row(`k${body}${ax}`, k(I, b[`m${body}`]), "m", `${name} radius of gyration about ${ax[0]}, sqrt(I${body}${ax}/m${body})`, true);
      }
    }
  }

  // Effects: every effect parameter of the models, grouped by effect.
  function buildEffects(models) {
    const seen = new Set();
    effectParams = [];
    for (const m of models) {
      for (const p of m.parameters) {
        if (!p.effect || seen.has(p.name)) continue;
        seen.add(p.name);
        effectParams.push(p);
      }
    }
    const groups = [];
    for (const p of effectParams) {
      let g = groups.find((x) => x.effect === p.effect);
      if (!g) groups.push((g = { effect: p.effect, params: [] }));
      g.params.push(p);
    }
    const host = $("effects");
    host.innerHTML = "";
    const open = new Set(["steer_damping", "steer_friction", "steer_controller"]);
    for (const g of groups) {
      const det = document.createElement("details");
      det.className = "effect";
      det.dataset.effect = g.effect;
      if (open.has(g.effect)) det.open = true;
      const sum = document.createElement("summary");
      const cb = document.createElement("input");
      cb.type = "checkbox";
      cb.dataset.effect = g.effect;
      const lab = document.createElement("span");
      lab.textContent = ` ${g.effect.replace(/_/g, " ")}`;
      sum.append(cb, lab);
      det.appendChild(sum);
      const table = document.createElement("table");
      table.className = "params";
      for (const p of g.params) {
        const tr = document.createElement("tr");
        tr.innerHTML = "<td class=sym></td><td><input type=text inputmode=decimal spellcheck=false></td><td class=what></td>";
        tr.cells[0].textContent = p.name;
        tr.cells[2].textContent = p.doc;
        const input = tr.querySelector("input");
        input.dataset.effectParam = p.name;
        input.value = String(p.name in state.effects ? state.effects[p.name] : p.default ?? 0);
        input.addEventListener("input", () => {
          const v = Number(input.value.trim());
          const ok = input.value.trim() !== "" && Number.isFinite(v);
          input.classList.toggle("invalid", !ok);
          if (!ok) return;
          if (cb.checked) {
            state.effects[p.name] = v;
            schedule();
          }
        });
        table.appendChild(tr);
      }
      det.appendChild(table);
      cb.addEventListener("change", () => {
        for (const p of g.params) {
          const input = det.querySelector(`input[data-effect-param="${p.name}"]`);
          if (cb.checked) {
            const v = Number(input.value);
            state.effects[p.name] = Number.isFinite(v) ? v : p.default ?? 0;
          } else delete state.effects[p.name];
        }
        det.classList.toggle("on", cb.checked);
        schedule();
      });
      host.appendChild(det);
    }
  }

  /** Checkboxes and values from the state (after a bicycle or a link is loaded). */
  function syncEffects() {
    for (const det of $("effects").querySelectorAll("details.effect")) {
      const inputs = [...det.querySelectorAll("input[data-effect-param]")];
      const on = inputs.some((i) => i.dataset.effectParam in state.effects);
      det.querySelector("input[type=checkbox]").checked = on;
      det.classList.toggle("on", on);
      for (const i of inputs) {
        const k = i.dataset.effectParam;
        if (k in state.effects && document.activeElement !== i) i.value = String(state.effects[k]);
      }
    }
  }

  // ---- eigenvalues over speed ------------------------------------------------

  /** The series of the eig plot: per mode and rank, real and imaginary parts over speed. */
  function eigSeries(points) {
    const series = new Map(); // key -> {mode, re: [[v, re]], im: [[v, im]]}
    const get = (key, mode) => {
      if (!series.has(key)) series.set(key, { mode, re: [], im: [] });
      return series.get(key);
    };
    points.forEach((p, i) => {
      const groups = {};
      p.eigenvalues.forEach(([re, im], k) => {
        if (im < 0) return; // a conjugate pair is drawn once
        (groups[p.modes[k]] ||= []).push([re, im]);
      });
      (p.extra_eigenvalues || []).forEach(([re, im]) => {
        if (im < 0) return;
        (groups.extra ||= []).push([re, im]);
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
          s.re.push([p.v, re]);
          s.im.push([p.v, im > 1e-9 ? im : NaN]);
          s.last = i;
        });
      }
    });
    return [...series.values()];
  }

  function eigLimits(points, clip = 10) {
    let lo = Infinity;
    let hi = -Infinity;
    for (const p of points) {
      for (const [re, im] of p.eigenvalues.concat(p.extra_eigenvalues || [])) {
        for (const x of [re, Math.abs(im)]) {
          if (!Number.isFinite(x)) continue;
          lo = Math.min(lo, x);
          hi = Math.max(hi, x);
        }
      }
    }
    lo = Math.max(lo, -clip);
    hi = Math.min(hi, clip);
    if (!(hi > lo)) [lo, hi] = [-1, 1];
    return P.niceLimits(lo, hi, 8);
  }

  function eigFigureSvg(width = 760, height = 440) {
    const pts = eig.points;
    const xlim = [state.vmin, state.vmax];
    const ylim = eigLimits(pts);
    const fig = P.figure({ width, height, xlim, ylim, xlabel: "forward speed v (m/s)", ylabel: "eigenvalue (1/s)", margin: { top: 36 } });
    // The self-stable band(s).
    const band = stab ? stab.stable_intervals : [];
    for (const [a, b] of band) {
      const x0 = fig.x(Math.max(a, xlim[0]));
      const x1 = fig.x(b === null || b === undefined ? xlim[1] : Math.min(b, xlim[1]));
      fig.add(`<rect data-band="1" x="${P.n(x0)}" y="${P.n(fig.margin.top)}" width="${P.n(Math.max(0, x1 - x0))}" height="${P.n(fig.ph)}" fill="#d9f0d3" stroke="none"/>`);
    }
    const series = eigSeries(pts);
    for (const s of series) fig.add(P.line(fig, s.im, { stroke: modeColour(s.mode), "stroke-dasharray": "6 4", "stroke-width": 1.6 }));
    for (const s of series) fig.add(P.line(fig, s.re, { stroke: modeColour(s.mode), "stroke-width": 2 }));
    // Critical speeds.
    const marks = [
      ["v_w", eig.weave_speed, "weave"],
      ["v_c", eig.capsize_speed, "capsize"],
      ["v_d", eig.weave_real_pair_merge_speed, "merge"],
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
    if (state.speed >= xlim[0] && state.speed <= xlim[1]) {
      const x = fig.x(state.speed);
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
    const bands = stab && stab.stable_intervals.length
      ? stab.stable_intervals.map(([a, b]) => `${fmt(a, 3)}\u2013${b === null || b === undefined ? "\u221e" : fmt(b, 3)}`).join(", ") + " m/s"
      : "none in the range";
    c.innerHTML = `<span>weave speed v<sub>w</sub> = <b id="v-weave"></b> m/s</span>
      <span>capsize speed v<sub>c</sub> = <b id="v-capsize"></b> m/s</span>
      <span>weave pair merge v<sub>d</sub> = <b id="v-merge"></b> m/s</span>
      <span>self-stable: <b id="v-band"></b></span>`;
    $("v-weave").textContent = v(eig.weave_speed);
    $("v-capsize").textContent = v(eig.capsize_speed);
    $("v-merge").textContent = v(eig.weave_real_pair_merge_speed);
    $("v-band").textContent = bands;
  }

  // ---- the slider's speed: table, mode shapes, root locus ------------------

  function updateSpeed() {
    $("speed-out").textContent = `${fmt(state.speed, 2)} m/s`;
    const r = call(withModel({ job: "eig", bicycle: bicycleSpec(), speeds: [state.speed] }));
    atSpeed = r.ok ? r.ok.points[0] : null;
    if (eig) {
      $("eig-plot").innerHTML = eigFigureSvg();
      $("locus-plot").innerHTML = locusSvg();
    }
    renderEigTable();
    $("modes").innerHTML = atSpeed ? modesSvg() : "";
  }

  function renderEigTable() {
    const tbody = $("eig-table").tBodies[0];
    tbody.innerHTML = "";
    if (!atSpeed) return;
    const rows = atSpeed.eigenvalues.map((e, k) => [atSpeed.modes[k], e]);
    for (const e of atSpeed.extra_eigenvalues || []) rows.push(["tyre state", e]);
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
    const p = atSpeed;
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

  function locusSvg(width = 760, height = 420) {
    const pts = eig.points;
    let xlo = Infinity, xhi = -Infinity, yhi = 0;
    for (const p of pts) {
      for (const [re, im] of p.eigenvalues.concat(p.extra_eigenvalues || [])) {
        xlo = Math.min(xlo, re);
        xhi = Math.max(xhi, re);
        yhi = Math.max(yhi, Math.abs(im));
      }
    }
    const clip = 12;
    const xlim = P.niceLimits(Math.max(xlo, -clip), Math.min(xhi, clip), 8);
    const ym = P.niceLimits(0, Math.max(1, Math.min(yhi, clip)), 4)[1];
    const fig = P.figure({ width, height, xlim, ylim: [-ym, ym], xlabel: "real part (1/s)", ylabel: "imaginary part (1/s)", zeroX: true, margin: { right: 90 } });
    const [v0, v1] = [state.vmin, state.vmax];
    const colour = (v) => P.viridis((v - v0) / (v1 - v0 || 1));
    for (const p of pts) {
      const c = colour(p.v);
      for (const [re, im] of p.eigenvalues.concat(p.extra_eigenvalues || [])) {
        fig.add(`<circle cx="${P.n(fig.x(re))}" cy="${P.n(fig.y(im))}" r="2.1" fill="${c}"/>`);
      }
    }
    if (atSpeed) {
      for (const [re, im] of atSpeed.eigenvalues.concat(atSpeed.extra_eigenvalues || [])) {
        fig.add(`<circle cx="${P.n(fig.x(re))}" cy="${P.n(fig.y(im))}" r="5.5" fill="none" stroke="#d00" stroke-width="1.6"/>`);
      }
      fig.over(`<text x="${P.n(fig.margin.left + 6)}" y="${P.n(fig.margin.top + 14)}" font-size="11" fill="#d00">\u25cb v = ${fmt(state.speed, 2)} m/s</text>`);
    }
    fig.over(P.colorbar(fig, v0, v1, P.viridis, "speed v (m/s)"));
    return fig.svg();
  }

  // ---- stability map --------------------------------------------------------

  let mapRun = null; // {cancelled}

  function paramOptions(select, selected) {
    select.innerHTML = "";
    const g1 = document.createElement("optgroup");
    g1.label = "benchmark parameters";
    for (const [k] of base.benchmark) g1.appendChild(new Option(`${k}${units[k] ? ` \u2014 ${units[k].what}` : ""}`, k));
    const g2 = document.createElement("optgroup");
    g2.label = "effect parameters";
    for (const p of effectParams) g2.appendChild(new Option(`${p.name} \u2014 ${p.doc}`, p.name));
    select.append(g1, g2);
    select.value = selected;
  }

  function readMapInputs() {
    const m = state.map;
    m.x = $("map-x").value;
    m.y = $("map-y").value;
    for (const k of ["x0", "x1", "y0", "y1", "at"]) {
      const v = Number($(`map-${k}`).value);
      if (Number.isFinite(v)) m[k] = v;
    }
    for (const k of ["nx", "ny"]) {
      const v = Math.round(Number($(`map-${k}`).value));
      if (Number.isFinite(v) && v >= 2) m[k] = Math.min(200, v);
    }
    m.metric = $("map-metric").value;
    writeHash();
  }

  function writeMapInputs() {
    const m = state.map;
    for (const k of ["x0", "x1", "nx", "y0", "y1", "ny", "at"]) $(`map-${k}`).value = String(m[k]);
    $("map-metric").value = m.metric;
    if (base) {
      paramOptions($("map-x"), m.x);
      paramOptions($("map-y"), m.y);
    }
  }

  /** Computes the map row by row, yielding to the page between rows; resolves with the cells (or null, cancelled). */
  async function runMap() {
    if (mapRun) mapRun.cancelled = true;
    readMapInputs();
    const m = state.map;
    const xs = S.linspace(m.x0, m.x1, m.nx);
    const ys = S.linspace(m.y0, m.y1, m.ny);
    const run = (mapRun = { cancelled: false });
    const req = withModel({
      job: "map_row", bicycle: bicycleSpec(), parameter: { symbol: m.x, values: xs }, second: { symbol: m.y, values: ys },
      row: 0, speed_max: state.vmax,
    });
    if (m.metric === "least_stable_real_part") req.at_speed = m.at;
    const cells = [];
    $("map-cancel").disabled = false;
    $("map-run").disabled = true;
    $("map-progress").value = 0;
    const t0 = performance.now();
    try {
      for (let i = 0; i < xs.length; i += 1) {
        if (run.cancelled) {
          $("map-status").textContent = `cancelled after ${i} of ${xs.length} rows`;
          return null;
        }
        req.row = i;
        const r = call(req);
        if (r.error) {
          showError(r.error);
          $("map-status").textContent = "error";
          return null;
        }
        cells.push(...r.ok.cells.map((c) => Object.assign(c, { i })));
        $("map-progress").value = (i + 1) / xs.length;
        $("map-status").textContent = `row ${i + 1} of ${xs.length}`;
        mapResult = { xs, ys, cells, map: Object.assign({}, m), done: false };
        $("map-plot").innerHTML = mapSvg();
        await new Promise((resolve) => setTimeout(resolve, 0));
      }
      mapResult.done = true;
      $("map-status").textContent = `${xs.length} \u00d7 ${ys.length} points in ${((performance.now() - t0) / 1000).toFixed(1)} s`;
      return cells;
    } finally {
      if (mapRun === run) mapRun = null;
      $("map-cancel").disabled = true;
      $("map-run").disabled = false;
    }
  }

  const METRIC_LABELS = {
    least_stable_real_part: (m) => `least-stable real part at ${m.at} m/s (1/s)`,
    stable_width: () => "self-stable speed range width (m/s)",
    weave_speed: () => "weave speed (m/s)",
    capsize_speed: () => "capsize speed (m/s)",
  };

  function mapSvg(width = 760, height = 460) {
    const { xs, ys, cells, map } = mapResult;
    const half = (v, k) => (v.length > 1 ? Math.abs(v[1] - v[0]) / 2 : 0.5) * (k || 1);
    const xlim = [Math.min(...xs) - half(xs), Math.max(...xs) + half(xs)];
    const ylim = [Math.min(...ys) - half(ys), Math.max(...ys) + half(ys)];
    const unitOf = (k) => (units[k] ? ` (${units[k].unit})` : "");
    const fig = P.figure({ width, height, xlim, ylim, xlabel: `${map.x}${unitOf(map.x)}`, ylabel: `${map.y}${unitOf(map.y)}`, grid: false, zeroY: false, margin: { right: 110 } });
    const vals = cells.map((c) => c[map.metric]).filter((v) => v !== null && v !== undefined && Number.isFinite(v));
    let lo = Math.min(...vals);
    let hi = Math.max(...vals);
    let cmap = P.viridis;
    if (map.metric === "least_stable_real_part") {
      const a = Math.max(Math.abs(lo), Math.abs(hi)) || 1;
      [lo, hi] = [-a, a];
      cmap = P.diverging;
    }
    if (!vals.length) [lo, hi] = [0, 1];
    if (hi === lo) hi = lo + 1;
    for (const c of cells) {
      const v = c[map.metric];
      const x0 = fig.x(c.x - half(xs));
      const x1 = fig.x(c.x + half(xs));
      const y0 = fig.y(c.y + half(ys));
      const y1 = fig.y(c.y - half(ys));
      const fill = v === null || v === undefined || !Number.isFinite(v) ? "#cccccc" : cmap((v - lo) / (hi - lo));
      const title = `${map.x} = ${sig(c.x)}, ${map.y} = ${sig(c.y)}: ${v === null || v === undefined ? (c.error || "none") : sig(v)}`;
      fig.add(`<rect data-cell="1" x="${P.n(x0)}" y="${P.n(y0)}" width="${P.n(x1 - x0 + 0.5)}" height="${P.n(y1 - y0 + 0.5)}" fill="${fill}"><title>${P.esc(title)}</title></rect>`);
    }
    fig.over(P.colorbar(fig, lo, hi, cmap, METRIC_LABELS[map.metric] ? METRIC_LABELS[map.metric](map) : map.metric));
    return fig.svg();
  }

  // ---- nonlinear simulation -----------------------------------------------------

  function readSimInputs() {
    const s = state.sim;
    const ids = { speed: "sim-speed", impulse: "sim-impulse", time: "sim-time", duration: "sim-duration", ahead: "sim-ahead", height: "sim-height", roll_rate: "sim-roll-rate" };
    for (const [k, id] of Object.entries(ids)) {
      const v = Number($(id).value);
      if ($(id).value.trim() !== "" && Number.isFinite(v)) s[k] = v;
    }
    writeHash();
  }
  function writeSimInputs() {
    const s = state.sim;
    const ids = { speed: "sim-speed", impulse: "sim-impulse", time: "sim-time", duration: "sim-duration", ahead: "sim-ahead", height: "sim-height", roll_rate: "sim-roll-rate" };
    for (const [k, id] of Object.entries(ids)) $(id).value = String(s[k]);
  }

  function runSim() {
    readSimInputs();
    const s = state.sim;
    const req = withModel({
      job: "simulate", bicycle: bicycleSpec(), duration: s.duration, output_interval: 0.01,
      initial: { roll: 0, steer: 0, roll_rate: s.roll_rate / DEG, steer_rate: 0, speed: s.speed, yaw: 0 },
      inputs: { kicks: s.impulse ? [{ time: s.time, impulse: s.impulse, ahead: s.ahead, height: s.height }] : [], pulses: [] },
    });
    $("sim-status").textContent = "simulating\u2026";
    const t0 = performance.now();
    const r = call(req);
    if (r.error) {
      showError(r.error);
      $("sim-status").textContent = "error";
      return null;
    }
    simResult = r.ok;
    simResult.thesisParams = Object.fromEntries(current.thesis);
    const sum = r.ok.summary;
    $("sim-status").textContent = `${sum.stop}: ${r.ok.simulation.t.length} samples, model ${sum.model}, ${((performance.now() - t0) / 1000).toFixed(2)} s; largest constraint residual ${sig(sum.max_constraint_residual, 2)}`;
    $("sim-plot").innerHTML = simTracesSvg();
    $("sim-play").disabled = false;
    $("sim-t").disabled = false;
    $("sim-t").max = String(r.ok.simulation.t[r.ok.simulation.t.length - 1]);
    $("sim-t").step = "0.01";
    setSimTime(0);
    return simResult;
  }

  /** Coordinate `role` of every sample. */
  function roleSeries(role) {
    const sim = simResult.simulation;
    const j = sim.coordinates.indexOf(simResult.roles[role]);
    return j < 0 ? null : sim.p.map((q) => q[j]);
  }

  let simFig = null;
  function simTracesSvg(width = 760, height = 320) {
    const t = simResult.simulation.t;
    // Benchmark signs: roll positive to the right (theta), steer positive to the right (-gamma).
    const roll = roleSeries("roll").map((x) => x * DEG);
    const steer = roleSeries("steer").map((x) => -x * DEG);
    const all = roll.concat(steer).filter(Number.isFinite);
    const ylim = P.niceLimits(Math.min(0, ...all), Math.max(0, ...all), 6);
    const fig = P.figure({ width, height, xlim: [t[0], t[t.length - 1]], ylim, xlabel: "time t (s)", ylabel: "angle (deg)" });
    const s = state.sim;
    if (s.impulse && s.time >= t[0] && s.time <= t[t.length - 1]) {
      fig.add(`<line x1="${P.n(fig.x(s.time))}" y1="${P.n(fig.margin.top)}" x2="${P.n(fig.x(s.time))}" y2="${P.n(fig.margin.top + fig.ph)}" stroke="#999" stroke-dasharray="2 3"/>`);
      fig.over(`<text x="${P.n(fig.x(s.time) + 4)}" y="${P.n(fig.margin.top + fig.ph - 6)}" font-size="11" fill="#666">kick ${sig(s.impulse, 3)} N s</text>`);
    }
    fig.add(P.line(fig, t.map((x, i) => [x, roll[i]]), { stroke: "#0072B2" }));
    fig.add(P.line(fig, t.map((x, i) => [x, steer[i]]), { stroke: "#D55E00" }));
    fig.add(`<line data-cursor="1" x1="0" y1="${P.n(fig.margin.top)}" x2="0" y2="${P.n(fig.margin.top + fig.ph)}" stroke="#000" stroke-width="1" stroke-opacity="0.5"/>`);
    fig.over(P.legend(fig, [{ label: "roll \u03c6 (right +)", color: "#0072B2" }, { label: "steer \u03b4 (right +)", color: "#D55E00" }]));
    simFig = fig;
    return fig.svg();
  }

  // Rotations (x forward, y left, z up: the thesis's axes, roll positive to
  // the right, steer and yaw positive to the left).
  const mul = (A, v) => [A[0][0] * v[0] + A[0][1] * v[1] + A[0][2] * v[2], A[1][0] * v[0] + A[1][1] * v[1] + A[1][2] * v[2], A[2][0] * v[0] + A[2][1] * v[1] + A[2][2] * v[2]];
  const mm = (A, B) => A.map((r) => [0, 1, 2].map((j) => r[0] * B[0][j] + r[1] * B[1][j] + r[2] * B[2][j]));
  const Rx = (a) => [[1, 0, 0], [0, Math.cos(a), -Math.sin(a)], [0, Math.sin(a), Math.cos(a)]];
  const Ry = (a) => [[Math.cos(a), 0, Math.sin(a)], [0, 1, 0], [-Math.sin(a), 0, Math.cos(a)]];
  const Rz = (a) => [[Math.cos(a), -Math.sin(a), 0], [Math.sin(a), Math.cos(a), 0], [0, 0, 1]];
  const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
  const scl = (a, s) => [a[0] * s, a[1] * s, a[2] * s];

  /**
   * The bicycle's points in 3-D from the thesis geometry and the simulated
   * coordinates: rear contact (xc, yc), yaw phi, roll theta (the rear
   * wheel's plane), frame pitch beta about the rear axle (frame z is the
   * steer axis: beta = -lambda upright), steer gamma about frame z; rear
   * frame points (x3, z3), steer-axis point G4 (x4, z4) in frame axes,
   * front wheel centre (x5, z5) from G4 in fork axes.
   */
  function bikeGeometry(th, q) {
    const R = mm(Rz(q.phi), Rx(q.theta));
    const Rb = mm(R, Ry(q.beta));
    const Rf = mm(Rb, Rz(q.gamma));
    const o = [q.xc, q.yc, 0];
    const hubR = add(o, mul(R, [0, 0, th.Rt]));
    const frame = (x, z) => add(hubR, mul(Rb, [x, 0, z]));
    const G4 = frame(th.x4, th.z4);
    const hubF = add(G4, mul(Rf, [th.x5, 0, th.z5]));
    const circle = (c, u, w, r) => Array.from({ length: 49 }, (_, k) => add(c, add(scl(u, r * Math.cos((k * Math.PI) / 24)), scl(w, r * Math.sin((k * Math.PI) / 24)))));
    const rear = circle(hubR, mul(R, [1, 0, 0]), mul(R, [0, 0, 1]), th.Rt);
    const front = circle(hubF, mul(Rf, [1, 0, 0]), mul(Rb, [0, 0, 1]), th.Rd);
    const axis = mul(Rb, [0, 0, 1]);
    const top = add(G4, scl(axis, 0.25));
    const bar = mul(Rf, [0, 1, 0]);
    return {
      contact: o, hubR, hubF, G4, top, rear, front,
      com: frame(th.x3, th.z3),
      bars: [add(top, scl(bar, 0.25)), add(top, scl(bar, -0.25))],
      axisLow: add(G4, scl(axis, -0.05)),
    };
  }

  function simState(i) {
    const sim = simResult.simulation;
    const q = {};
    for (const [role, key] of [["rear_contact_X", "xc"], ["rear_contact_Y", "yc"], ["yaw", "phi"], ["roll", "theta"], ["pitch", "beta"], ["steer", "gamma"]]) {
      const j = sim.coordinates.indexOf(simResult.roles[role]);
      q[key] = j < 0 ? 0 : sim.p[i][j];
    }
    return q;
  }

  function viewSvg(g, project, xlim, ylim, extra, width = 370, height = 300) {
    const fig = P.figure({ width, height, xlim, ylim, grid: true, zeroY: false, margin: { left: 44, bottom: 34, top: 10, right: 10 }, xtickCount: 4, ytickCount: 4 });
    const pl = (pts, a) => P.line(fig, pts.map(project), a);
    fig.add(extra(fig));
    fig.add(pl(g.rear, { stroke: "#333", "stroke-width": 2 }));
    fig.add(pl(g.front, { stroke: "#333", "stroke-width": 2 }));
    fig.add(pl([g.hubR, g.com, g.G4, g.hubR], { stroke: "#0072B2", "stroke-width": 2.2 }));
    fig.add(pl([g.axisLow, g.top], { stroke: "#D55E00", "stroke-width": 2.4 }));
    fig.add(pl([g.G4, g.hubF], { stroke: "#D55E00", "stroke-width": 2 }));
    fig.add(pl(g.bars, { stroke: "#D55E00", "stroke-width": 2.4 }));
    const [cx, cy] = project(g.com);
    fig.add(`<circle cx="${P.n(fig.x(cx))}" cy="${P.n(fig.y(cy))}" r="4" fill="#0072B2"/>`);
    return fig.svg();
  }

  function setSimTime(time) {
    if (!simResult) return;
    const t = simResult.simulation.t;
    let i = 0;
    while (i < t.length - 1 && t[i + 1] <= time + 1e-9) i += 1;
    $("sim-t").value = String(t[i]);
    const q = simState(i);
    $("sim-t-out").textContent = `t = ${fmt(t[i], 2)} s, roll ${fmt(q.theta * DEG, 1)}\u00b0, steer ${fmt(-q.gamma * DEG, 1)}\u00b0 (right +)`;
    const th = simResult.thesisParams;
    // Rear view: from behind, along the heading (yaw and position removed); the rider's right to the right.
    const local = bikeGeometry(th, Object.assign({}, q, { xc: 0, yc: 0, phi: 0 }));
    const hmax = Math.max(1.2, local.top[2] + 0.2, local.com[2] + 0.3);
    const half = (hmax + 0.1) * (370 - 54) / (300 - 44) / 2;
    $("sim-rear").innerHTML = viewSvg(local, (p) => [-p[1], p[2]], [-half, half], [-0.1, hmax],
      (fig) => `<rect x="${P.n(fig.margin.left)}" y="${P.n(fig.y(0))}" width="${P.n(fig.pw)}" height="${P.n(fig.y(-0.1) - fig.y(0))}" fill="#e8e4da"/>`);
    // Top view: following the bicycle, with the rear contact's path (x forward at t = 0, y to the left).
    const g = bikeGeometry(th, q);
    const cx = (g.hubR[0] + g.hubF[0]) / 2;
    const cy = (g.hubR[1] + g.hubF[1]) / 2;
    const w = 3.2;
    const h = (w * (300 - 44)) / (370 - 54);
    const xs = roleSeries("rear_contact_X");
    const ys = roleSeries("rear_contact_Y");
    $("sim-top").innerHTML = viewSvg(g, (p) => [p[0], p[1]], [cx - w / 2, cx + w / 2], [cy - h / 2, cy + h / 2],
      (fig) => P.line(fig, xs.map((x, k) => [x, ys[k]]), { stroke: "#aaa", "stroke-width": 1.2, "stroke-dasharray": "4 3" }));
    if (simFig) {
      const cur = $("sim-plot").querySelector("line[data-cursor]");
      if (cur) {
        cur.setAttribute("x1", P.n(simFig.x(t[i])));
        cur.setAttribute("x2", P.n(simFig.x(t[i])));
      }
    }
  }

  let playing = null;
  function play() {
    if (!simResult) return;
    if (playing) {
      cancelAnimationFrame(playing.frame);
      playing = null;
      $("sim-play").textContent = "play";
      return;
    }
    const t = simResult.simulation.t;
    const end = t[t.length - 1];
    let start = Number($("sim-t").value);
    if (start >= end - 1e-9) start = 0;
    const wall = performance.now();
    playing = {};
    $("sim-play").textContent = "pause";
    const step = () => {
      const now = start + (performance.now() - wall) / 1000;
      setSimTime(Math.min(now, end));
      if (now >= end) {
        playing = null;
        $("sim-play").textContent = "play";
        return;
      }
      playing.frame = requestAnimationFrame(step);
    };
    playing.frame = requestAnimationFrame(step);
  }

  // ---- downloads ---------------------------------------------------------------

  function download(name, text, type) {
    const blob = new Blob([text], { type });
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 2000);
  }
  const slug = () => (current ? current.name : "bicycle").replace(/[^A-Za-z0-9_.-]+/g, "_").replace(/^_+|_+$/g, "") || "bicycle";

  /** The eigenvalue table exactly as `bikedyn eig --format csv` writes it. */
  function eigCsv() {
    const r = call(withModel({ job: "eig", bicycle: bicycleSpec(), speeds: S.speedRange(state), csv: true }));
    if (r.error) {
      showError(r.error);
      return null;
    }
    return r.ok.csv;
  }

  // ---- choosing and importing a bicycle ---------------------------------------

  /** The bicycle menu's entry of the imported file (or of the link's). */
  function fileOption() {
    const opt = $("bike").querySelector("option[value=file]");
    opt.disabled = !state.file;
    opt.textContent = state.file ? `imported: ${state.file.name}` : "imported file";
    $("file-name").textContent = state.file ? `imported ${state.file.name}` : "";
  }

  /** Imports a parameter file's text; the module's error (verbatim) if it cannot be read. */
  function importFile(f) {
    const r = call({ job: "bicycle", bicycle: { file: { name: f.name, text: f.text } } });
    if (r.error) {
      showError(r.error);
      return false;
    }
    state.file = { name: f.name, text: f.text };
    state.bike = "file";
    state.edits = {};
    state.effects = Object.assign({}, r.ok.effects); // the file's effects, shown switched on
    base = r.ok;
    units = readUnits(base.toml);
    fileOption();
    $("bike").value = "file";
    showError("");
    afterBaseChange();
    return true;
  }

  function chooseBike(value) {
    const previous = state.bike;
    state.bike = value;
    if (!loadBase()) {
      state.bike = previous;
      $("bike").value = previous;
      return false;
    }
    state.edits = {};
    state.effects = value === "file" ? Object.assign({}, base.effects) : {};
    afterBaseChange();
    return true;
  }

  function afterBaseChange() {
    $("params").tBodies[0].dataset.bike = "";
    writeMapInputs();
    return schedule();
  }

  function readSpeedInputs() {
    const a = Number($("vmin").value);
    const b = Number($("vmax").value);
    const s = Number($("vstep").value);
    if (!(Number.isFinite(a) && Number.isFinite(b) && Number.isFinite(s) && b > a && s > 0)) return;
    if ((b - a) / s > 5000) return;
    state.vmin = a;
    state.vmax = b;
    state.vstep = s;
    syncSlider();
    schedule();
  }

  function syncSlider() {
    $("speed").min = String(state.vmin);
    $("speed").max = String(state.vmax);
    $("speed").value = String(state.speed);
    $("speed-num").value = String(state.speed);
  }

  function setSpeed(v) {
    if (!Number.isFinite(v)) return;
    state.speed = v;
    writeHash();
    if (document.activeElement !== $("speed-num")) $("speed-num").value = String(v);
    if (document.activeElement !== $("speed")) $("speed").value = String(v);
    updateSpeed();
  }

  // ---- wiring -------------------------------------------------------------------

  function wire() {
    $("bike").addEventListener("change", () => chooseBike($("bike").value));
    $("model").addEventListener("change", () => {
      state.model = $("model").value;
      schedule();
    });
    $("file").addEventListener("change", async () => {
      const f = $("file").files[0];
      if (f) importFile({ name: f.name, text: await f.text() });
      $("file").value = "";
    });
    const drop = $("drop");
    document.addEventListener("dragover", (e) => {
      e.preventDefault();
      drop.classList.add("over");
    });
    document.addEventListener("dragleave", (e) => {
      if (!e.relatedTarget) drop.classList.remove("over");
    });
    document.addEventListener("drop", async (e) => {
      e.preventDefault();
      drop.classList.remove("over");
      const f = e.dataTransfer && e.dataTransfer.files[0];
      if (f) importFile({ name: f.name, text: await f.text() });
    });
    $("reset-all").addEventListener("click", () => {
      state.edits = {};
      $("params").tBodies[0].dataset.bike = "";
      schedule();
    });
    for (const id of ["vmin", "vmax", "vstep"]) $(id).addEventListener("input", readSpeedInputs);
    $("speed").addEventListener("input", () => setSpeed(Number($("speed").value)));
    $("speed-num").addEventListener("input", () => setSpeed(Number($("speed-num").value)));
    $("dl-csv").addEventListener("click", () => {
      const csv = eigCsv();
      if (csv) download(`${slug()}-eigenvalues.csv`, csv, "text/csv");
    });
    $("dl-toml").addEventListener("click", () => current && download(`${slug()}.toml`, current.toml, "application/toml"));
    $("dl-eig-svg").addEventListener("click", () => eig && download(`${slug()}-eigenvalues.svg`, eigFigureSvg(), "image/svg+xml"));
    $("dl-locus-svg").addEventListener("click", () => eig && download(`${slug()}-root-locus.svg`, locusSvg(), "image/svg+xml"));
    $("dl-modes-svg").addEventListener("click", () => atSpeed && download(`${slug()}-mode-shapes.svg`, modesSvg(), "image/svg+xml"));
    $("dl-map-svg").addEventListener("click", () => mapResult && download(`${slug()}-stability-map.svg`, mapSvg(), "image/svg+xml"));
    $("dl-sim-svg").addEventListener("click", () => simResult && download(`${slug()}-kick.svg`, simTracesSvg(), "image/svg+xml"));
    $("map-run").addEventListener("click", () => runMap());
    $("map-cancel").addEventListener("click", () => mapRun && (mapRun.cancelled = true));
    for (const id of ["map-x", "map-y", "map-x0", "map-x1", "map-nx", "map-y0", "map-y1", "map-ny", "map-metric", "map-at"]) $(id).addEventListener("change", readMapInputs);
    $("sim-run").addEventListener("click", () => runSim());
    for (const id of ["sim-speed", "sim-impulse", "sim-time", "sim-duration", "sim-ahead", "sim-height", "sim-roll-rate"]) $(id).addEventListener("change", readSimInputs);
    $("sim-play").addEventListener("click", play);
    $("sim-t").addEventListener("input", () => setSimTime(Number($("sim-t").value)));
    window.addEventListener("hashchange", () => {
      // A link pasted into the address bar.
      if (location.hash === "#" + S.encode(state)) return;
      state = S.decode(location.hash);
      applyState();
    });
  }

  /** Inputs from `state` and a recomputation (on load and on a pasted link). */
  function applyState() {
    $("bike").value = state.bike;
    fileOption();
    $("model").value = state.model;
    $("vmin").value = String(state.vmin);
    $("vmax").value = String(state.vmax);
    $("vstep").value = String(state.vstep);
    syncSlider();
    writeSimInputs();
    if (!loadBase()) {
      state = Object.assign(S.defaults(), { selftest: state.selftest });
      loadBase();
    }
    writeMapInputs();
    $("params").tBodies[0].dataset.bike = "";
    return schedule();
  }

  // ---- self-test (#selftest): the page exercises itself -------------------------

  async function selftest() {
    const fails = [];
    const check = (ok, what) => {
      if (!ok) fails.push(what);
    };
    const out = $("selftest");
    // Until the debounced update has run.
    const settle = async () => {
      while (timer || inFlight) await new Promise((r) => setTimeout(r, 10));
    };
    try {
      // 0. The link's state, restored (the page was opened with it).
      const given = S.decode(location.hash);
      check(S.encode(state) === S.encode(given), `the state ${S.encode(state)} is not the link's ${S.encode(given)}`);
      check($("bike").value === given.bike, `bicycle ${$("bike").value}, the link says ${given.bike}`);
      check($("error").hidden, `the link's bicycle: ${$("error").textContent}`);
      check(eig && eig.points.length === S.speedRange(given).count, "the link's eigenvalues are not drawn");
      for (const [k, v] of Object.entries(given.edits)) {
        const input = document.querySelector(`input[data-symbol="${k}"]`);
        check(input && Number(input.value) === v && input.closest("tr").classList.contains("edited"), `the link's ${k} = ${v} is not in the table`);
      }
      for (const [k, v] of Object.entries(given.effects)) {
        const input = document.querySelector(`input[data-effect-param="${k}"]`);
        const det = input && input.closest("details");
        check(input && Number(input.value) === v && det.querySelector("input[type=checkbox]").checked, `the link's effect ${k} = ${v} is not on`);
      }
      check(Math.abs(Number($("speed").value) - given.speed) < 1e-9, `the slider is at ${$("speed").value}, the link says ${given.speed}`);
      // 1. The benchmark bicycle: Meijaard et al. (2007) give v_w = 4.292 and v_c = 6.024 m/s.
      state = Object.assign(S.defaults(), { selftest: true });
      await applyState();
      check($("v-weave").textContent === "4.2924", `weave speed shown ${$("v-weave").textContent}, expected 4.2924`);
      check($("v-capsize").textContent === "6.0243", `capsize speed shown ${$("v-capsize").textContent}, expected 6.0243`);
      const label = () => {
        const t = $("eig-plot").querySelector('text[data-critical="weave"]');
        return t ? t.textContent : "";
      };
      const before = label();
      check(before === "v_w = 4.292", `the plot's weave label is "${before}"`);
      check($("eig-plot").querySelectorAll("polyline").length >= 4, "the eigenvalue plot has no lines");
      check($("eig-plot").querySelector("rect[data-band]"), "the eigenvalue plot has no self-stable band");
      check($("locus-plot").querySelectorAll("circle").length > 100, "the root locus has no points");
      check($("eig-table").tBodies[0].rows.length === 4, "the eigenvalue table has not 4 rows");
      check($("derived").textContent.includes("kAll"), "no radius of gyration of the front assembly");
      // 2. Trail c edited in the table: the weave speed changes, the link says so.
      const c = document.querySelector('input[data-symbol="c"]');
      c.value = "0.1";
      c.dispatchEvent(new Event("input"));
      await settle();
      const after = label();
      check(after && after !== before, `the plot's weave label did not change with the trail (${before} -> ${after})`);
      check($("v-weave").textContent !== "4.2924", "the weave speed did not change with the trail");
      check(location.hash.includes("set=c:0.1"), `the link lacks the edit: ${location.hash}`);
      // 3. Effects: steer damping switched on changes the model.
      const cb = document.querySelector('input[type=checkbox][data-effect="steer_damping"]');
      const damping = document.querySelector('input[data-effect-param="c_steer"]');
      damping.value = "0.3";
      cb.checked = true;
      cb.dispatchEvent(new Event("change"));
      await settle();
      check($("bike-model").textContent === "extended", `steer damping: model ${$("bike-model").textContent}`);
      check(location.hash.includes("fx=c_steer:0.3"), `the link lacks the effect: ${location.hash}`);
      // The CSV download has the command line's columns.
      const csv = eigCsv() || "";
      check(csv.startsWith("v,re_1,im_1,mode_1,roll_amp_1"), `the CSV's header: ${csv.slice(0, 40)}`);
      // 4. An invalid file: the module's message, verbatim.
      const bad = { name: "broken.txt", text: "garbage" };
      let expected = "";
      try {
        bd.call({ job: "bicycle", bicycle: { file: bad } });
      } catch (e) {
        expected = e.message;
      }
      check(expected.length > 0, "the invalid file was read");
      // Dropped on the page, as a user would.
      showError("");
      const dt = new DataTransfer();
      dt.items.add(new File([bad.text], bad.name, { type: "text/plain" }));
      document.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
      for (let k = 0; k < 100 && $("error").hidden; k += 1) await new Promise((r) => setTimeout(r, 20));
      check(!$("error").hidden && $("error").textContent === expected, `the error shown is "${$("error").textContent}", expected "${expected}"`);
      check($("bike").value === "benchmark", "a bad file replaced the bicycle");
      // A valid file, in TOML.
      const ok = importFile({ name: "mine.toml", text: current.toml.replace("c = 0.1 ", "c = 0.09") });
      await settle();
      check(ok && $("error").hidden, "a valid TOML file was not imported");
      check(location.hash.includes("bike=file&name=mine.toml&file="), `the link lacks the file: ${location.hash.slice(0, 80)}`);
      // The link gives the file's bicycle.
      const linked = S.decode(location.hash);
      check(linked.file && linked.file.text === state.file.text, "the link's file is not the file");
      const again = call({ job: "eig", bicycle: S.bicycleSpec(linked, benchmarkOrder()), speeds: S.speedRange(linked), critical_speeds: true });
      check(again.ok && again.ok.weave_speed === eig.weave_speed, `the link's bicycle: weave speed ${again.ok ? again.ok.weave_speed : again.error}, the file's ${eig.weave_speed}`);
      // 5. A small stability map.
      state.map = { x: "c", x0: 0.04, x1: 0.12, nx: 3, y: "lam", y0: 0.2, y1: 0.4, ny: 3, metric: "least_stable_real_part", at: 5 };
      writeMapInputs();
      const cells = await runMap();
      check(cells && cells.length === 9, `the map has ${cells ? cells.length : 0} cells, expected 9`);
      check($("map-plot").querySelectorAll("rect[data-cell]").length === 9, "the map's cells are not drawn");
      // 6. A kick simulation.
      const sim = runSim();
      check(sim && sim.summary.stop === "completed", `the simulation: ${sim ? sim.summary.stop : "failed"}`);
      check(sim && sim.simulation.t.length > 100, "the simulation has too few samples");
      check($("sim-plot").querySelectorAll("polyline").length >= 2, "no roll and steer traces");
      setSimTime(2);
      check($("sim-rear").querySelectorAll("polyline").length >= 4 && $("sim-top").querySelectorAll("polyline").length >= 4, "no rear and top views");
    } catch (e) {
      fails.push(`exception: ${e && e.stack ? e.stack : e}`);
    }
    out.hidden = false;
    out.textContent = fails.length ? `SELFTEST FAIL: ${fails.join("; ")}` : "SELFTEST PASS";
    document.title = out.textContent.slice(0, 60);
  }

  // ---- start ---------------------------------------------------------------------

  async function start() {
    const t0 = performance.now();
    try {
      bd = await loadModule();
    } catch (e) {
      status("the module could not be loaded");
      showError(`The WebAssembly module could not be loaded: ${e.message}`);
      if (state.selftest) {
        $("selftest").hidden = false;
        $("selftest").textContent = `SELFTEST FAIL: module not loaded: ${e.message}`;
      }
      return;
    }
    status(`module loaded in ${((performance.now() - t0) / 1000).toFixed(2)} s`);
    const models = call({ job: "models" }).ok || [];
    for (const m of models) $("model").appendChild(new Option(`${m.name}${m.free_speed ? " (free speed)" : ""}`, m.name));
    buildEffects(models);
    wire();
    await applyState();
    if (state.selftest) await selftest();
  }

  start();
})();
