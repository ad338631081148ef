// A small plotting library for the stability explorer: axes with nice
// ticks, lines, markers, shaded bands, colour maps. A figure is drawn as
// SVG text with inline attributes only (no CSS), so that a downloaded
// figure looks as it does on the page and goes into a paper as it is, or
// painted on a canvas from the same shapes.
//
// A classic script: in a page it defines the global `BikedynPlot`; in
// Node.js it is a CommonJS module (the tests import it).
(function (root, factory) {
  const api = factory();
  if (typeof module === "object" && module && module.exports) {
    module.exports.BikedynPlot = api;
  } else {
    root.BikedynPlot = api;
  }
})(typeof globalThis !== "undefined" ? globalThis : this, function () {
  "use strict";

  const FONT = "Helvetica, Arial, sans-serif";

  /** Escapes text for SVG/XML. */
  function esc(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
  }

  /** A number for an SVG attribute (two decimals are a hundredth of a pixel). */
  function n(x) {
    return Number.isFinite(x) ? String(Math.round(x * 100) / 100) : "0";
  }

  /** About `count` round tick values covering [lo, hi] (1, 2, 5 times a power of ten). */
  function niceTicks(lo, hi, count = 6) {
    if (!(Number.isFinite(lo) && Number.isFinite(hi))) return [];
    if (hi < lo) [lo, hi] = [hi, lo];
    if (hi === lo) {
      const d = Math.abs(lo) > 0 ? Math.abs(lo) * 0.1 : 1;
      lo -= d;
      hi += d;
    }
    const raw = (hi - lo) / Math.max(1, count);
    const p = Math.pow(10, Math.floor(Math.log10(raw)));
    const f = raw / p;
    const step = (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
    const first = Math.ceil(lo / step - 1e-9) * step;
    const ticks = [];
    for (let t = first; t <= hi + step * 1e-9; t += step) ticks.push(Math.abs(t) < step * 1e-9 ? 0 : t);
    return ticks;
  }

  /** Axis limits widened to round values: [lo, hi] from the data's range. */
  function niceLimits(lo, hi, count = 6) {
    const t = niceTicks(lo, hi, count);
    if (t.length < 2) return [lo - 1, hi + 1];
    const step = t[1] - t[0];
    return [Math.min(t[0], Math.floor(lo / step + 1e-9) * step), Math.max(t[t.length - 1], Math.ceil(hi / step - 1e-9) * step)];
  }

  /** A tick label: as few decimals as the step needs. */
  function tickLabel(t, step) {
    const decimals = Math.max(0, Math.min(6, -Math.floor(Math.log10(step) + 1e-9)));
    const s = t.toFixed(decimals);
    // No "-0.0"; a true minus sign.
    return Number(s) === 0 ? (0).toFixed(decimals) : s.replace(/^-/, "\u2212");
  }

  // ---- shapes: one description, drawn as SVG text or on a canvas ----------
  //
  // A figure is a list of shapes in pixels: `{tag, a, pts, text, rotate,
  // title}`, with `tag` an SVG element's name, `a` its SVG attributes
  // (numbers or strings), `pts` a polyline's or dots' coordinates (x, y in
  // turn), `text` a text's and `title` an element's tooltip (SVG only).
  // The same list is written as SVG (a download, the figures of other
  // panels) or painted on a canvas (the figures redrawn after every change
  // or as they come: writing, parsing and laying out the SVG of a
  // 1,000-speed diagram took the browser longer than the module took to
  // compute it, 2026-11-29). A figure may also take SVG text (`add` of a
  // string): such a figure is SVG only.

  const shape = (tag, a, more) => Object.assign({ tag, a }, more);
  /** A text shape at (x, y) (its baseline; `text-anchor` as in SVG). */
  const text = (x, y, s, a = {}) => shape("text", Object.assign({ x, y }, a), { text: String(s) });

  function attrText(a) {
    let out = "";
    for (const k in a) out += ` ${k}="${typeof a[k] === "number" ? n(a[k]) : esc(a[k])}"`;
    return out;
  }

  /** A shape (or SVG text) as SVG text. */
  function shapeSvg(s) {
    if (typeof s === "string") return s;
    const p = s.pts;
    switch (s.tag) {
      case "polyline": {
        const xy = [];
        for (let i = 0; i < p.length; i += 2) xy.push(`${n(p[i])},${n(p[i + 1])}`);
        return `<polyline points="${xy.join(" ")}"${attrText(s.a)}/>`;
      }
      case "dots": {
        // Zero-length strokes with round caps: one path for many dots.
        let d = "";
        for (let i = 0; i < p.length; i += 2) d += `M${n(p[i])} ${n(p[i + 1])}h0`;
        return `<path d="${d}" fill="none" stroke-linecap="round"${attrText(s.a)}/>`;
      }
      case "raster":
        throw new Error("plot.js: a raster is painted on a canvas only");
      case "text": {
        if (!s.rotate) return `<text${attrText(s.a)}>${esc(s.text)}</text>`;
        const { x, y, ...rest } = s.a;
        return `<text transform="translate(${n(x)} ${n(y)}) rotate(${s.rotate})"${attrText(rest)}>${esc(s.text)}</text>`;
      }
      default:
        // A shape's `title` is its SVG tooltip (a canvas has none).
        if (s.title !== undefined) return `<${s.tag}${attrText(s.a)}><title>${esc(s.title)}</title></${s.tag}>`;
        return `<${s.tag}${attrText(s.a)}/>`;
    }
  }

  const ALIGN = { start: "left", middle: "center", end: "right" };

  // A canvas strokes a polyline's points as they are, and the browser's
  // time goes to them: for the eigenvalue diagram's 1,001-speed lines,
  // more than half of its drawing (Chromium, 2026-12-02). A canvas
  // therefore strokes the fewest of a polyline's points that keep every
  // other one within a tenth of a pixel of the line drawn (a smooth curve
  // with a point per pixel or more needs a few in twenty); the SVG keeps
  // every point.
  const SIMPLIFY_TOLERANCE = 0.1; // pixels

  /**
   * The points of the polyline `p` (x, y in turn, pixels) to stroke on a
   * canvas: its first and last, and in between the fewest, chosen from the
   * start, such that every point left out lies within `tol` pixels (in y,
   * so at most that far) of the segment between the kept ones on either
   * side of it. Only points going right (x increasing, as over speed) are
   * left out; a new array, or `p` itself when none can go. One pass: the
   * slopes from the last kept point that pass within `tol` of every point
   * since are an interval, narrowed by each point.
   */
  function simplified(p, tol = SIMPLIFY_TOLERANCE) {
    const n = p.length >> 1;
    if (n < 3) return p;
    const out = new Float64Array(p.length);
    out[0] = p[0];
    out[1] = p[1];
    let k = 2;
    let ax = p[0];
    let ay = p[1];
    let lo = -Infinity;
    let hi = Infinity;
    let fresh = true; // the point is the first after the one kept
    for (let b = 1; b < n; b++) {
      let dx = p[2 * b] - ax;
      let dy = p[2 * b + 1] - ay;
      if (!fresh) {
        const s = dy / dx;
        if (!(dx > 0 && s >= lo && s <= hi)) {
          // The segment to b would pass too far from a point left out: the
          // point before b is kept.
          ax = p[2 * b - 2];
          ay = p[2 * b - 1];
          out[k++] = ax;
          out[k++] = ay;
          lo = -Infinity;
          hi = Infinity;
          dx = p[2 * b] - ax;
          dy = p[2 * b + 1] - ay;
        }
      }
      fresh = false;
      if (dx > 0) {
        lo = Math.max(lo, (dy - tol) / dx);
        hi = Math.min(hi, (dy + tol) / dx);
      } else {
        lo = Infinity; // going left or straight up: b is kept
      }
    }
    out[k++] = p[2 * n - 2];
    out[k++] = p[2 * n - 1];
    return k === p.length ? p : out.subarray(0, k);
  }

  /**
   * Paints a shape as the browser draws its SVG (the attributes the figures
   * use). `pass` is what the painting of one figure keeps between shapes:
   * the font last set (setting a canvas's font parses it, every time).
   */
  function paintShape(ctx, s, pass) {
    if (typeof s === "string") throw new Error("plot.js: a figure with SVG text is drawn as SVG only");
    const a = s.a;
    const p = s.pts;
    ctx.lineWidth = a["stroke-width"] ?? 1;
    ctx.setLineDash(a["stroke-dasharray"] ? String(a["stroke-dasharray"]).split(/[ ,]+/).map(Number) : []);
    ctx.lineCap = a["stroke-linecap"] || "butt";
    ctx.lineJoin = a["stroke-linejoin"] || "miter";
    const fill = a.fill ?? "#000"; // SVG's default fill
    const stroke = a.stroke ?? "none";
    const paint = () => {
      if (fill !== "none") {
        ctx.globalAlpha = a["fill-opacity"] ?? 1;
        ctx.fillStyle = fill;
        ctx.fill();
        ctx.globalAlpha = 1;
      }
      if (stroke !== "none") {
        ctx.strokeStyle = stroke;
        ctx.stroke();
      }
    };
    ctx.beginPath();
    switch (s.tag) {
      case "line":
        ctx.moveTo(a.x1, a.y1);
        ctx.lineTo(a.x2, a.y2);
        if (stroke !== "none") {
          ctx.strokeStyle = stroke;
          ctx.stroke();
        }
        return;
      case "polyline": {
        const q = simplified(p);
        ctx.moveTo(q[0], q[1]);
        for (let i = 2; i < q.length; i += 2) ctx.lineTo(q[i], q[i + 1]);
        return paint();
      }
      case "dots":
        // Strokes with round caps, discs as wide as the stroke: in
        // Chromium a quarter of the time of as many arcs (2026-11-30).
        // Unlike SVG, the canvas standard prunes zero-length segments
        // before stroking ("Zero-length line segments must be pruned"),
        // so each is a hundredth of a pixel long, which every engine
        // strokes, rather than relying on one that draws caps anyway.
        for (let i = 0; i < p.length; i += 2) {
          ctx.moveTo(p[i], p[i + 1]);
          ctx.lineTo(p[i] + 0.01, p[i + 1]);
        }
        ctx.lineCap = "round";
        ctx.strokeStyle = stroke;
        ctx.stroke();
        return;
      case "rect":
        ctx.rect(a.x, a.y, a.width, a.height);
        return paint();
      case "circle":
        ctx.arc(a.cx, a.cy, a.r, 0, 2 * Math.PI);
        return paint();
      case "raster": {
        // A grid of `nx` x `ny` cells, `rgba` their colours (the top row
        // first), stretched over the rectangle without smoothing: every
        // cell a rectangle of one colour, as many SVG rectangles would be,
        // in one drawing (canvas only).
        const grid = document.createElement("canvas");
        grid.width = s.nx;
        grid.height = s.ny;
        grid.getContext("2d").putImageData(new ImageData(s.rgba, s.nx, s.ny), 0, 0);
        ctx.imageSmoothingEnabled = false;
        ctx.drawImage(grid, a.x, a.y, a.width, a.height);
        ctx.imageSmoothingEnabled = true;
        return;
      }
      case "text": {
        const font = `${a["font-weight"] || "normal"} ${a["font-size"] ?? 12}px ${FONT}`;
        if (pass.font !== font) ctx.font = pass.font = font;
        ctx.textAlign = ALIGN[a["text-anchor"] || "start"];
        ctx.fillStyle = fill;
        if (!s.rotate) {
          ctx.fillText(s.text, a.x, a.y);
          return;
        }
        ctx.save();
        ctx.translate(a.x, a.y);
        ctx.rotate((s.rotate * Math.PI) / 180);
        ctx.fillText(s.text, 0, 0);
        ctx.restore();
        return;
      }
      default:
        throw new Error(`plot.js: no painting for <${s.tag}>`);
    }
  }

  /**
   * A figure: `figure({width, height, xlim, ylim, xlabel, ylabel, title})`
   * returns an object with `x(v)`, `y(v)` (data to pixels), `add(shapes)`
   * to draw in the plotting area (clipped), `over(shapes)` to draw above
   * the axes (each a shape, a list of them, or SVG text), `svg()` for the
   * finished SVG text and `paint(canvas)` to draw the same on a canvas.
   */
  function figure(o) {
    const width = o.width ?? 640;
    const height = o.height ?? 400;
    const m = Object.assign({ left: 62, right: 16, top: o.title ? 30 : 14, bottom: 48 }, o.margin || {});
    const [x0, x1] = o.xlim;
    const [y0, y1] = o.ylim;
    const pw = width - m.left - m.right;
    const ph = height - m.top - m.bottom;
    const x = (v) => m.left + ((v - x0) / (x1 - x0)) * pw;
    const y = (v) => m.top + ph - ((v - y0) / (y1 - y0)) * ph;
    const body = [];
    const above = [];
    const push = (list, s) => {
      if (Array.isArray(s)) for (const t of s) list.push(t);
      else list.push(s);
    };

    /** The grid (under the data) and the axes (over it). */
    function axes() {
      const xt = o.xticks ?? niceTicks(x0, x1, o.xtickCount ?? Math.max(3, Math.round(pw / 80)));
      const yt = o.yticks ?? niceTicks(y0, y1, o.ytickCount ?? Math.max(3, Math.round(ph / 50)));
      const xs = xt.length > 1 ? xt[1] - xt[0] : 1;
      const ys = yt.length > 1 ? yt[1] - yt[0] : 1;
      const grid = [];
      const over = [];
      const seg = (x1_, y1_, x2_, y2_, stroke, w) => shape("line", Object.assign({ x1: x1_, y1: y1_, x2: x2_, y2: y2_, stroke }, w === undefined ? {} : { "stroke-width": w }));
      if (o.grid !== false) {
        for (const t of xt) if (t >= x0 && t <= x1) grid.push(seg(x(t), m.top, x(t), m.top + ph, "#e6e6e6", 1));
        for (const t of yt) if (t >= y0 && t <= y1) grid.push(seg(m.left, y(t), m.left + pw, y(t), "#e6e6e6", 1));
      }
      if (o.zeroY !== false && y0 < 0 && y1 > 0) over.push(seg(m.left, y(0), m.left + pw, y(0), "#000", 0.8));
      if (o.zeroX && x0 < 0 && x1 > 0) over.push(seg(x(0), m.top, x(0), m.top + ph, "#000", 0.8));
      over.push(shape("rect", { x: m.left, y: m.top, width: pw, height: ph, fill: "none", stroke: "#000", "stroke-width": 1 }));
      for (const t of xt) {
        if (t < x0 || t > x1) continue;
        over.push(seg(x(t), m.top + ph, x(t), m.top + ph + 5, "#000"));
        over.push(text(x(t), m.top + ph + 18, tickLabel(t, xs), { "text-anchor": "middle" }));
      }
      for (const t of yt) {
        if (t < y0 || t > y1) continue;
        over.push(seg(m.left - 5, y(t), m.left, y(t), "#000"));
        over.push(text(m.left - 8, y(t) + 4, tickLabel(t, ys), { "text-anchor": "end" }));
      }
      if (o.xlabel) over.push(text(m.left + pw / 2, height - 10, o.xlabel, { "text-anchor": "middle", "font-size": 13 }));
      if (o.ylabel) over.push(Object.assign(text(15, m.top + ph / 2, o.ylabel, { "text-anchor": "middle", "font-size": 13 }), { rotate: -90 }));
      if (o.title) over.push(text(m.left, 19, o.title, { "font-size": 13, "font-weight": "bold" }));
      return { grid, over };
    }

    const fig = {
      x, y, width, height, margin: m, pw, ph, xlim: o.xlim, ylim: o.ylim,
      add(s) { push(body, s); return fig; },
      over(s) { push(above, s); return fig; },
      /** The shapes added (not the axes'). */
      shapes() { return body.concat(above); },
      svg() {
        const clip = `clip${Math.random().toString(36).slice(2, 9)}`;
        const { grid, over } = axes();
        const g = [];
        g.push(`<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" font-family="${FONT}" font-size="12">`);
        g.push(`<rect x="0" y="0" width="${width}" height="${height}" fill="#ffffff"/>`);
        g.push(`<defs><clipPath id="${clip}"><rect x="${n(m.left)}" y="${n(m.top)}" width="${n(pw)}" height="${n(ph)}"/></clipPath></defs>`);
        for (const s of grid) g.push(shapeSvg(s));
        g.push(`<g clip-path="url(#${clip})">`);
        for (const s of body) g.push(shapeSvg(s));
        g.push(`</g>`);
        for (const s of over.concat(above)) g.push(shapeSvg(s));
        g.push(`</svg>`);
        return g.join("\n");
      },
      /** Draws the figure on `canvas` (sized to the figure; sharp on a high-density screen). */
      paint(canvas) {
        const dpr = (typeof window !== "undefined" && window.devicePixelRatio) || 1;
        if (canvas.width !== Math.round(width * dpr) || canvas.height !== Math.round(height * dpr)) {
          canvas.width = Math.round(width * dpr);
          canvas.height = Math.round(height * dpr);
          canvas.style.width = `${width}px`; // the height follows (CSS: auto)
        }
        // The plot area, in CSS pixels, for a test reading the canvas.
        canvas.dataset.plotArea = [m.left, m.top, pw, ph].map(n).join(",");
        const ctx = canvas.getContext("2d");
        ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
        ctx.fillStyle = "#ffffff";
        ctx.fillRect(0, 0, width, height);
        const { grid, over } = axes();
        const pass = { font: "" };
        for (const s of grid) paintShape(ctx, s, pass);
        ctx.save();
        ctx.beginPath();
        ctx.rect(m.left, m.top, pw, ph);
        ctx.clip();
        for (const s of body) paintShape(ctx, s, pass);
        ctx.restore();
        pass.font = ""; // as it was before the clip
        for (const s of over) paintShape(ctx, s, pass);
        for (const s of above) paintShape(ctx, s, pass);
        return fig;
      },
    };
    return fig;
  }

  /**
   * Polylines through the points [x0, y0, x1, y1, ...] in data coordinates
   * (the first `n` numbers of `pts`), a list of shapes; breaks at
   * non-finite points. The pixels go to one typed array that the shapes
   * share, `px`, which may be `pts` itself (a point is read before it is
   * overwritten): a diagram's lines have thousands of points, redrawn after
   * every change, and making lists of them kept the garbage collector busy.
   */
  function line(fig, pts, attrs = {}, n = pts.length, px = new Float64Array(n)) {
    const a = Object.assign({ fill: "none", stroke: "#000", "stroke-width": 1.8, "stroke-linejoin": "round", "stroke-linecap": "round" }, attrs);
    const out = [];
    let start = 0;
    let k = 0;
    const end = () => {
      if (k - start > 2) out.push(shape("polyline", a, { pts: px.subarray(start, k) }));
      start = k;
    };
    // fig.x and fig.y written out.
    const [x0, x1] = fig.xlim;
    const [y0, y1] = fig.ylim;
    const { left, top } = fig.margin;
    const { pw, ph } = fig;
    for (let i = 0; i < n; i += 2) {
      const u = pts[i];
      const v = pts[i + 1];
      if (Number.isFinite(u) && Number.isFinite(v)) {
        px[k++] = left + ((u - x0) / (x1 - x0)) * pw;
        px[k++] = top + ph - ((v - y0) / (y1 - y0)) * ph;
      } else end();
    }
    end();
    return out;
  }

  /** A legend box (a list of shapes): items [{label, color, dash, marker, fill}] at the top right (or `where`). */
  function legend(fig, items, where = "right") {
    const lh = 17;
    const w = Math.max(...items.map((i) => i.label.length)) * 6.6 + 40;
    const h = items.length * lh + 8;
    // `where`: "right" (top right), "left" (top left), "bottom-right", "bottom-left".
    const x0 = /left/.test(where) ? fig.margin.left + 8 : fig.margin.left + fig.pw - w - 8;
    const y0 = /bottom/.test(where) ? fig.margin.top + fig.ph - h - 8 : fig.margin.top + 8;
    const g = [shape("rect", { x: x0, y: y0, width: w, height: h, fill: "#ffffff", "fill-opacity": 0.9, stroke: "#999", "stroke-width": 0.6 })];
    items.forEach((it, k) => {
      const yy = y0 + 4 + lh * k + lh / 2;
      if (it.marker) g.push(shape("circle", { cx: x0 + 17, cy: yy, r: 3.5, fill: it.color }));
      else if (it.fill) g.push(shape("rect", { x: x0 + 7, y: yy - 5, width: 20, height: 10, fill: it.fill, stroke: "none" }));
      else g.push(shape("line", Object.assign({ x1: x0 + 7, y1: yy, x2: x0 + 27, y2: yy, stroke: it.color, "stroke-width": 2 }, it.dash ? { "stroke-dasharray": it.dash } : {})));
      g.push(text(x0 + 33, yy + 4, it.label, { "font-size": 11.5 }));
    });
    return g;
  }

  // Colour maps: viridis (sequential) and a blue-white-red diverging map,
  // as lists of stops interpolated linearly.
  const VIRIDIS = ["#440154", "#482878", "#3e4989", "#31688e", "#26828e", "#1f9e89", "#35b779", "#6ece58", "#b5de2b", "#fde725"];
  const DIVERGING = ["#2166ac", "#4393c3", "#92c5de", "#d1e5f0", "#f7f7f7", "#fddbc7", "#f4a582", "#d6604d", "#b2182b"];
  function hex(c) {
    return [1, 3, 5].map((i) => parseInt(c.slice(i, i + 2), 16));
  }
  /**
   * A colour map over [0, 1] from its stops: `map(t)` is a colour
   * (`#rrggbb`; grey for a value that is not finite), `map.rgb(t, out)` the
   * same colour's red, green and blue (0-255) written to `out` (a canvas's
   * pixels, without writing and parsing the colour's text).
   */
  function colormap(stops) {
    const rgb = stops.map(hex);
    const into = (t, out) => {
      if (!Number.isFinite(t)) {
        out[0] = out[1] = out[2] = 0xbb;
        return out;
      }
      t = Math.max(0, Math.min(1, t));
      const f = t * (stops.length - 1);
      const i = Math.min(stops.length - 2, Math.floor(f));
      const a = rgb[i];
      const b = rgb[i + 1];
      const u = f - i;
      for (let k = 0; k < 3; k++) out[k] = Math.round(a[k] + (b[k] - a[k]) * u);
      return out;
    };
    const map = (t) => "#" + Array.from(into(t, [0, 0, 0]), (v) => v.toString(16).padStart(2, "0")).join("");
    map.rgb = into;
    return map;
  }
  const viridis = colormap(VIRIDIS);
  const diverging = colormap(DIVERGING);

  /** A vertical colour bar (a list of shapes) at the right of `fig` for values [lo, hi]. */
  function colorbar(fig, lo, hi, map, label) {
    const x0 = fig.margin.left + fig.pw + 14;
    const w = 14;
    const g = [];
    const steps = 48;
    for (let k = 0; k < steps; k += 1) {
      const t0 = k / steps;
      const yy = fig.margin.top + fig.ph * (1 - (k + 1) / steps);
      g.push(shape("rect", { x: x0, y: yy, width: w, height: fig.ph / steps + 0.6, fill: map(t0 + 0.5 / steps) }));
    }
    g.push(shape("rect", { x: x0, y: fig.margin.top, width: w, height: fig.ph, fill: "none", stroke: "#000", "stroke-width": 0.8 }));
    const ticks = niceTicks(lo, hi, 5);
    const step = ticks.length > 1 ? ticks[1] - ticks[0] : 1;
    for (const t of ticks) {
      if (t < lo || t > hi) continue;
      const yy = fig.margin.top + fig.ph * (1 - (t - lo) / (hi - lo || 1));
      g.push(shape("line", { x1: x0 + w, y1: yy, x2: x0 + w + 4, y2: yy, stroke: "#000" }));
      g.push(text(x0 + w + 7, yy + 4, tickLabel(t, step), { "font-size": 11 }));
    }
    if (label) g.push(Object.assign(text(x0 + w + 52, fig.margin.top + fig.ph / 2, label, { "text-anchor": "middle", "font-size": 12 }), { rotate: -90 }));
    return g;
  }

  return { esc, n, niceTicks, niceLimits, tickLabel, shape, text, figure, line, simplified, legend, viridis, diverging, colorbar };
});
