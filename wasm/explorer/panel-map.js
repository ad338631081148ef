// The stability map panel: a metric (least-stable real part at a speed,
// width of the self-stable range, weave or capsize speed) over any two
// parameters, benchmark or effect, computed row by row (`map_row`) in Web
// Workers, with progress, cancellable.
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const P = BikedynPlot;
  const S = ExplorerState;
  const { $, call, showError, sig, bicycleSpec, withModel, writeHash } = app;

  // ---- stability map --------------------------------------------------------

  let mapRun = null; // {cancelled}

  function paramOptions(select, selected) {
    select.innerHTML = "";
    const g1 = document.createElement("optgroup");
    g1.label = "benchmark parameters";
    for (const [k] of app.base.benchmark) g1.appendChild(new Option(`${k}${app.units[k] ? ` \u2014 ${app.units[k].what}` : ""}`, k));
    const g2 = document.createElement("optgroup");
    g2.label = "effect parameters";
    for (const p of app.effectParams) g2.appendChild(new Option(`${p.name} \u2014 ${p.doc}`, p.name));
    select.append(g1, g2);
    select.value = selected;
  }

  function readMapInputs() {
    const m = app.state.map;
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
    const m = app.state.map;
    for (const k of ["x0", "x1", "nx", "y0", "y1", "ny", "at"]) $(`map-${k}`).value = String(m[k]);
    $("map-metric").value = m.metric;
    if (app.base) {
      paramOptions($("map-x"), m.x);
      paramOptions($("map-y"), m.y);
    }
  }

  // The map's rows are computed in Web Workers, one per core (at most
  // eight), each with its own instance of the page's compiled module: on
  // two cores a 100 x 100 map took 1.2-1.6 s against 1.8-2.0 s in the page
  // (2026-11-30; the page's own rendering shares the cores), and the page
  // stays free to draw. Where no worker starts (an engine without them, or one
  // that refuses a worker's script in a page opened as a file), the rows
  // are computed in the page, which is given back its turn every 50 ms.
  let workers = null; // a promise of the BikedynWorkers, or of null (in the page)
  function mapWorkers() {
    if (!workers) {
      const count = Math.max(1, Math.min(8, navigator.hardwareConcurrency || 2));
      workers = BikedynWorkers.start(app.bd.module, count).then(
        (pool) => pool,
        (e) => {
          app.mapWorkersError = e.message;
          return null;
        },
      );
    }
    return workers;
  }

  /**
   * Computes the map row by row; resolves with the cells (or null, cancelled
   * or failed). `inPage`: compute in the page even where workers start (the
   * self-test's, whose virtual time does not wait for a worker).
   */
  async function runMap({ inPage = false } = {}) {
    cancelMap();
    readMapInputs();
    const m = app.state.map;
    const xs = S.linspace(m.x0, m.x1, m.nx);
    const ys = S.linspace(m.y0, m.y1, m.ny);
    const run = (mapRun = { cancelled: false });
    const req = withModel({
      job: "map_row", bicycle: bicycleSpec(), parameter: { symbol: m.x, values: xs }, second: { symbol: m.y, values: ys },
      row: 0, speed_max: app.state.vmax,
    });
    if (m.metric === "least_stable_real_part") req.at_speed = m.at;
    $("map-cancel").disabled = false;
    $("map-run").disabled = true;
    $("map-progress").value = 0;
    wireHover();
    const t0 = performance.now();
    const pool = inPage ? null : await mapWorkers();
    app.mapWorkerCount = pool ? pool.size : 0;
    const rows = new Array(xs.length);
    let done = 0;
    // The plot is redrawn as rows come, but not after every row: a 100 x
    // 100 map's 10,000 cells drawn again after each of its rows took
    // Chromium 12 of the map's 15 s (2026-11-29). At most a tenth of the
    // time goes to drawing (and at most one drawing a second).
    let drawnAt = performance.now();
    let drawing = 0;
    // The cells so far are gathered for a drawing (and at the end), not
    // after every row.
    const draw = () => {
      const s = performance.now();
      app.mapResult = { xs, ys, cells: rows.flat(), map: Object.assign({}, m), done: false };
      drawMap();
      drawnAt = performance.now();
      drawing = drawnAt - s;
    };
    const rowDone = (i, cells) => {
      rows[i] = cells.map((c) => Object.assign(c, { i }));
      done += 1;
      $("map-progress").value = done / xs.length;
      $("map-status").textContent = `row ${done} of ${xs.length}`;
      if (done < xs.length && performance.now() - drawnAt >= Math.max(1000, 10 * drawing)) draw();
    };
    const fail = (message) => {
      showError(message);
      $("map-status").textContent = "error";
      return null;
    };
    const cancelled = () => {
      $("map-status").textContent = `cancelled after ${done} of ${xs.length} rows`;
      return null;
    };
    try {
      if (run.cancelled) return cancelled();
      if (pool) {
        // Every row is queued at once; a cancel drops those not yet sent.
        const answers = xs.map((_, i) =>
          pool.call(Object.assign({}, req, { row: i }), run).then((ok) => {
            if (!run.cancelled) rowDone(i, ok.cells);
          }),
        );
        const stop = new Promise((resolve) => (run.stop = resolve));
        const outcome = await Promise.race([Promise.all(answers).then(() => "done", (e) => e), stop]);
        if (outcome !== "done") pool.drop(run);
        if (outcome === "cancelled" || run.cancelled) return cancelled();
        if (outcome !== "done") return fail(outcome.message);
      } else {
        // In the page: the page is given back its turn after 50 ms of rows,
        // not after each row (a browser waits at least 4 ms before a timer
        // nested that deep).
        let yieldedAt = performance.now();
        for (let i = 0; i < xs.length; i += 1) {
          if (run.cancelled) return cancelled();
          const r = call(Object.assign({}, req, { row: i }));
          if (r.error) return fail(r.error);
          rowDone(i, r.ok.cells);
          if (performance.now() - yieldedAt >= 50) {
            await new Promise((resolve) => setTimeout(resolve, 0));
            yieldedAt = performance.now();
          }
        }
      }
      const computed = performance.now();
      draw();
      app.mapResult.done = true;
      // What the map's time went to (ms): its rows, and its last drawing.
      app.mapTiming = { rows: computed - t0, lastDrawing: drawing };
      $("map-status").textContent = `${xs.length} \u00d7 ${ys.length} points in ${((performance.now() - t0) / 1000).toFixed(1)} s`;
      return app.mapResult.cells;
    } finally {
      if (mapRun === run) {
        mapRun = null;
        $("map-cancel").disabled = true;
        $("map-run").disabled = false;
      }
    }
  }

  /** Stops the map being computed: the rows being computed finish, no more start. */
  function cancelMap() {
    if (mapRun) {
      mapRun.cancelled = true;
      if (mapRun.stop) mapRun.stop("cancelled");
    }
  }

  const METRIC_LABELS = {
    least_stable_real_part: (m) => `least-stable real part at ${m.at} m/s (1/s)`,
    stable_width: () => "self-stable speed range width (m/s)",
    weave_speed: () => "weave speed (m/s)",
    capsize_speed: () => "capsize speed (m/s)",
  };

  /** A cell's tooltip text. */
  function cellText(c, map) {
    const v = c[map.metric];
    return `${map.x} = ${sig(c.x)}, ${map.y} = ${sig(c.y)}: ${v === null || v === undefined ? (c.error || "none") : sig(v)}`;
  }

  // The page's map is painted on a canvas (plot.js): written as SVG, its
  // 10,000 cells took Chromium 80-210 ms to write, parse and lay out at
  // every drawing of a 100 x 100 map (2026-12-02), twice in a map of two
  // seconds, on the cores the workers compute on. It tells the cell under
  // the pointer in the plot's tooltip; the SVG download gives each cell
  // its value as a title.
  let mapShown = null; // the painted map: {fig, xs, ys, cellOf: (i * ny + j) -> index in cells}
  let hoverWired = false;
  function wireHover() {
    if (hoverWired) return;
    hoverWired = true;
    $("map-plot").addEventListener("mousemove", (e) => {
      const res = app.mapResult;
      const c = e.target.tagName === "CANVAS" ? e.target : null;
      let text = "";
      if (c && res && mapShown) {
        const { fig, xs, ys, cellOf } = mapShown;
        // The pointer in the figure's pixels (the canvas may be shown smaller).
        const r = c.getBoundingClientRect();
        const px = ((e.clientX - r.left) * fig.width) / (r.width || 1);
        const py = ((e.clientY - r.top) * fig.height) / (r.height || 1);
        const [x0, x1] = fig.xlim;
        const [y0, y1] = fig.ylim;
        const x = x0 + ((px - fig.margin.left) / fig.pw) * (x1 - x0);
        const y = y0 + ((fig.margin.top + fig.ph - py) / fig.ph) * (y1 - y0);
        const nearest = (v, t) => {
          let best = 0;
          for (let k = 1; k < v.length; k++) if (Math.abs(v[k] - t) < Math.abs(v[best] - t)) best = k;
          return best;
        };
        if (x >= x0 && x <= x1 && y >= y0 && y <= y1) {
          const k = cellOf.get(nearest(xs, x) * ys.length + nearest(ys, y));
          if (k !== undefined && res.cells[k]) text = cellText(res.cells[k], res.map);
        }
      }
      $("map-plot").title = text;
    });
  }

  /**
   * The map's figure (plot.js): written as SVG for its download, one
   * rectangle per cell with its value as its title (`titles`), or painted
   * on the page, where the cells are one raster (`raster`: 10,000
   * rectangles painted one by one took Chromium longer than their SVG,
   * the raster 10-20 ms, 2026-12-02; the same cells and colours).
   */
  function mapFigure(width = 760, height = 460, { titles = true, raster = false } = {}) {
    const { xs, ys, cells, map } = app.mapResult;
    const half = (v, k) => (v.length > 1 ? Math.abs(v[1] - v[0]) / 2 : 0.5) * (k || 1);
    const xlim = [Math.min(...xs) - half(xs), Math.max(...xs) + half(xs)];
    const ylim = [Math.min(...ys) - half(ys), Math.max(...ys) + half(ys)];
    const unitOf = (k) => (app.units[k] ? ` (${app.units[k].unit})` : "");
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
    const shown = (v) => v !== null && v !== undefined && Number.isFinite(v);
    if (raster) {
      // Cell (i, j) is pixel (i, ny - 1 - j) of the raster, which spans the
      // plot (the axes' limits are the cells' outer edges); a cell not yet
      // computed is left transparent (white), as the SVG leaves it out.
      const nx = xs.length;
      const ny = ys.length;
      const rgba = new Uint8ClampedArray(4 * nx * ny);
      const rgb = [0, 0, 0];
      for (const c of cells) {
        const v = c[map.metric];
        if (shown(v)) cmap.rgb((v - lo) / (hi - lo), rgb);
        else rgb[0] = rgb[1] = rgb[2] = 0xcc;
        const k = 4 * ((ny - 1 - c.j) * nx + c.i);
        rgba[k] = rgb[0];
        rgba[k + 1] = rgb[1];
        rgba[k + 2] = rgb[2];
        rgba[k + 3] = 255;
      }
      fig.add(P.shape("raster", { x: fig.margin.left, y: fig.margin.top, width: fig.pw, height: fig.ph }, { nx, ny, rgba }));
    } else {
      cells.forEach((c, k) => {
        const v = c[map.metric];
        const x0 = fig.x(c.x - half(xs));
        const x1 = fig.x(c.x + half(xs));
        const y0 = fig.y(c.y + half(ys));
        const y1 = fig.y(c.y - half(ys));
        const fill = shown(v) ? cmap((v - lo) / (hi - lo)) : "#cccccc";
        const cell = P.shape("rect", { "data-cell": k, x: x0, y: y0, width: x1 - x0 + 0.5, height: y1 - y0 + 0.5, fill });
        if (titles) cell.title = cellText(c, map);
        fig.add(cell);
      });
    }
    fig.over(P.colorbar(fig, lo, hi, cmap, METRIC_LABELS[map.metric] ? METRIC_LABELS[map.metric](map) : map.metric));
    return fig;
  }

  /** The map as SVG, each cell's value as its title (the download). */
  const mapSvg = () => mapFigure().svg();

  /** Paints the map on its canvas; its number of cells is written on the canvas (for the tests: a canvas keeps no elements). */
  function drawMap() {
    const fig = mapFigure(760, 460, { titles: false, raster: true });
    const host = $("map-plot");
    let c = host.firstElementChild;
    if (!c || c.tagName !== "CANVAS") {
      host.textContent = "";
      c = host.appendChild(document.createElement("canvas"));
    }
    fig.paint(c);
    const { xs, ys, cells } = app.mapResult;
    const cellOf = new Map();
    cells.forEach((cell, k) => cellOf.set(cell.i * ys.length + cell.j, k));
    mapShown = { fig, xs, ys, cellOf };
    c.dataset.cells = String(cells.length);
  }

  // Used by the other files.
  Object.assign(app, { readMapInputs, writeMapInputs, runMap, cancelMap, mapSvg });
})(window.Explorer);
