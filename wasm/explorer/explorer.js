// The stability explorer: a static page over bikedyn's WebAssembly module
// (bikedyn.js). Every number comes from the module; the page's scripts only
// ask for it, draw it (plot.js) and keep the page's state in its link
// (state.js). Classic scripts, so that the page also works as a file.
//
// This file is the page's core: the shared state, the module's calls, the
// bicycle of a request, updating after a change, the wiring of the inputs
// and the start. The rest, loaded after it (index.html), one concern a file:
//
//   panel-bicycle.js     the bicycle, parameter table, effects, derived rows, import
//   panel-eigen.js       eigenvalues over speed, the slider's speed, root locus
//   panel-map.js         the stability map
//   panel-simulation.js  the nonlinear simulation of a kick
//   downloads.js         CSV, TOML and SVG downloads
//   selftest.js          the page's self-test (#selftest)
//
// They share one namespace, `window.Explorer` (`app` in each file): the
// data below and the functions each file hands to the others. A file copies
// this file's helpers into locals (this file runs first); the data and the
// other files' functions it reads as `app.x` when used, as they change or
// are defined later.
(function () {
  "use strict";
  const S = ExplorerState;
  const $ = (id) => document.getElementById(id);

  const DEG = 180 / Math.PI;

  const app = (window.Explorer = {
    bd: null, // the loaded module
    state: S.decode(location.hash),
    base: null, // the `bicycle` answer of the bicycle before edits
    current: null, // ... after edits and effects
    eig: null, // the `explore` answer: the eigenvalues over the speed range (arrays)
    stableIntervals: null, // the self-stable speeds [[from, to]] in the range
    atSpeed: null, // the eigenvalues and mode shapes at the slider's speed
    effectParams: [], // [{name, default, doc, effect}], the models' effect parameters
    units: {}, // benchmark symbol -> {unit, what}, from the TOML's comments
    mapResult: null,
    simResult: null,
  });

  // ---- module calls ---------------------------------------------------

  /** `{ok: answer}` or `{error: message}` (the module's message, verbatim). */
  function call(request) {
    try {
      return { ok: app.bd.call(request) };
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

  const benchmarkOrder = () => (app.base ? app.base.benchmark.map(([k]) => k) : []);

  /** The `set` list: the table's edits, the effects on, and the file's effects switched off (at their defaults). */
  function setList() {
    const set = S.setList(app.state, benchmarkOrder());
    if (app.base) {
      for (const k of Object.keys(app.base.effects || {})) {
        if (!(k in app.state.effects)) {
          const p = app.effectParams.find((q) => q.name === k);
          set.push([k, p && p.default !== null ? p.default : 0]);
        }
      }
    }
    return set;
  }

  function bicycleSpec(withSet = true) {
    const spec = S.bicycleSpec(app.state, benchmarkOrder(), false);
    if (withSet) spec.set = setList();
    return spec;
  }

  function withModel(req) {
    if (app.state.model) req.model = app.state.model;
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
    app.base = r.ok;
    app.units = readUnits(app.base.toml);
    // Edits (from a link) that are the bicycle's own values are no edits.
    const values = Object.fromEntries(app.base.benchmark);
    for (const [k, v] of Object.entries(app.state.edits)) if (values[k] === v) delete app.state.edits[k];
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

  /** Whether an update is waiting or running (the self-test waits for it). */
  const busy = () => Boolean(timer || inFlight);

  function writeHash() {
    const h = "#" + S.encode(app.state);
    if (location.hash !== h) history.replaceState(null, "", h);
  }

  // The times of the last update, for the status line and the browser
  // test: `redrawMs` from the request to the diagram painted (the module's
  // one answer, which also brings the bicycle, the self-stable band and
  // the slider's speed, and the eigenvalue diagram drawn on its canvas),
  // `updateMs` to everything the change updates on the page (also the
  // parameter and derived tables, the critical speeds' text, the slider's
  // table and mode shapes, the root locus and the link). Both stop before
  // the browser lays out and paints the page.
  function update() {
    const started = performance.now();
    const spec = bicycleSpec();
    const range = S.speedRange(app.state);
    const r = call(withModel({ job: "explore", bicycle: spec, speeds: range, speed_min: app.state.vmin, speed_max: app.state.vmax, speed: app.state.speed }));
    if (r.error) {
      // The bicycle is shown as long as it can be made: the module's
      // message is that of the first job that failed.
      const b = r.kind === "job" ? call(withModel({ job: "bicycle", bicycle: spec })) : null;
      showError(r.error);
      status("error");
      if (b && b.ok) {
        app.current = b.ok;
        app.renderBicycle();
      }
      markStale(true);
      writeHash();
      return;
    }
    showError("");
    const answer = r.ok;
    app.eig = answer;
    app.current = answer.bicycle;
    app.stableIntervals = answer.stable_intervals;
    app.atSpeed = answer.at_speed;
    app.drawDiagram();
    app.redrawMs = performance.now() - started;
    markStale(false);
    app.renderBicycle();
    app.renderCritical();
    app.showSpeed();
    writeHash();
    app.updateMs = performance.now() - started;
    status(`${app.current.name} \u00b7 model ${app.eig.model} \u00b7 ${app.eig.count} speeds \u00b7 diagram ${fmt(app.redrawMs, 1)} ms, whole update ${fmt(app.updateMs, 1)} ms`);
  }

  function markStale(stale) {
    for (const id of ["eig-plot", "locus-plot", "modes", "critical"]) $(id).classList.toggle("stale", stale);
  }

  // ---- wiring -------------------------------------------------------------------

  function wire() {
    $("bike").addEventListener("change", () => app.chooseBike($("bike").value));
    $("model").addEventListener("change", () => {
      app.state.model = $("model").value;
      schedule();
    });
    // Reading a file is asynchronous: `app.importing` is the import in
    // flight, for whoever must wait for it (the self-test; a slow machine
    // reads a file later than any fixed wait).
    $("file").addEventListener("change", () => {
      const f = $("file").files[0];
      if (f) app.importing = f.text().then((text) => app.importFile({ name: f.name, text }));
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
    document.addEventListener("drop", (e) => {
      e.preventDefault();
      drop.classList.remove("over");
      const f = e.dataTransfer && e.dataTransfer.files[0];
      if (f) app.importing = f.text().then((text) => app.importFile({ name: f.name, text }));
    });
    $("reset-all").addEventListener("click", () => {
      app.state.edits = {};
      $("params").tBodies[0].dataset.bike = "";
      schedule();
    });
    for (const id of ["vmin", "vmax", "vstep"]) $(id).addEventListener("input", app.readSpeedInputs);
    $("speed").addEventListener("input", () => app.setSpeed(Number($("speed").value)));
    $("speed-num").addEventListener("input", () => app.setSpeed(Number($("speed-num").value)));
    $("dl-csv").addEventListener("click", () => {
      const csv = app.eigCsv();
      if (csv) app.download(`${app.slug()}-eigenvalues.csv`, csv, "text/csv");
    });
    $("dl-toml").addEventListener("click", () => app.current && app.download(`${app.slug()}.toml`, app.current.toml, "application/toml"));
    $("dl-eig-svg").addEventListener("click", () => app.eig && app.download(`${app.slug()}-eigenvalues.svg`, app.eigFigureSvg(), "image/svg+xml"));
    $("dl-locus-svg").addEventListener("click", () => app.eig && app.download(`${app.slug()}-root-locus.svg`, app.locusSvg(), "image/svg+xml"));
    $("dl-modes-svg").addEventListener("click", () => app.atSpeed && app.download(`${app.slug()}-mode-shapes.svg`, app.modesSvg(), "image/svg+xml"));
    $("dl-map-svg").addEventListener("click", () => app.mapResult && app.download(`${app.slug()}-stability-map.svg`, app.mapSvg(), "image/svg+xml"));
    $("dl-sim-svg").addEventListener("click", () => app.simResult && app.download(`${app.slug()}-kick.svg`, app.simTracesSvg(), "image/svg+xml"));
    $("map-run").addEventListener("click", () => app.runMap());
    $("map-cancel").addEventListener("click", () => app.cancelMap());
    for (const id of ["map-x", "map-y", "map-x0", "map-x1", "map-nx", "map-y0", "map-y1", "map-ny", "map-metric", "map-at"]) $(id).addEventListener("change", app.readMapInputs);
    $("sim-run").addEventListener("click", () => app.runSim());
    for (const id of ["sim-speed", "sim-impulse", "sim-time", "sim-duration", "sim-ahead", "sim-height", "sim-roll-rate"]) $(id).addEventListener("change", app.readSimInputs);
    $("sim-play").addEventListener("click", app.play);
    $("sim-t").addEventListener("input", () => app.setSimTime(Number($("sim-t").value)));
    window.addEventListener("hashchange", () => {
      // A link pasted into the address bar.
      if (location.hash === "#" + S.encode(app.state)) return;
      app.state = S.decode(location.hash);
      applyState();
    });
  }

  /** Inputs from `state` and a recomputation (on load and on a pasted link). */
  function applyState() {
    $("bike").value = app.state.bike;
    app.fileOption();
    $("model").value = app.state.model;
    $("vmin").value = String(app.state.vmin);
    $("vmax").value = String(app.state.vmax);
    $("vstep").value = String(app.state.vstep);
    app.syncSlider();
    app.writeSimInputs();
    if (!loadBase()) {
      app.state = Object.assign(S.defaults(), { selftest: app.state.selftest });
      loadBase();
    }
    app.writeMapInputs();
    $("params").tBodies[0].dataset.bike = "";
    return schedule();
  }

  // ---- start ---------------------------------------------------------------------

  async function start() {
    const t0 = performance.now();
    try {
      app.bd = await loadModule();
    } catch (e) {
      status("the module could not be loaded");
      showError(`The WebAssembly module could not be loaded: ${e.message}`);
      if (app.state.selftest) {
        $("selftest").hidden = false;
        $("selftest").textContent = `SELFTEST FAIL: module not loaded: ${e.message}`;
      }
      return;
    }
    status(`module loaded in ${((performance.now() - t0) / 1000).toFixed(2)} s`);
    const models = call({ job: "models" }).ok || [];
    for (const m of models) $("model").appendChild(new Option(`${m.name}${m.free_speed ? " (free speed)" : ""}`, m.name));
    app.buildEffects(models);
    wire();
    await applyState();
    if (app.state.selftest) await app.selftest();
  }

  // Used by the other files.
  Object.assign(app, { $, DEG, call, showError, fmt, sig, benchmarkOrder, bicycleSpec, withModel, readUnits, loadBase, schedule, writeHash, busy, applyState });

  // Once every script of the page has run (deferred scripts run, in order,
  // before DOMContentLoaded).
  document.addEventListener("DOMContentLoaded", start);
})();
