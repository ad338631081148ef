// A small SVG plotting library for the stability explorer: axes with nice
// ticks, lines, markers, shaded bands, colour maps. Figures are SVG text
// with inline attributes only (no CSS), so that a downloaded figure looks
// as it does on the page and goes into a paper as it is.
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

  /**
   * A figure: `figure({width, height, xlim, ylim, xlabel, ylabel, title})`
   * returns an object with `x(v)`, `y(v)` (data to pixels), `add(svgText)`
   * to draw in the plotting area (clipped), `over(svgText)` to draw above
   * the axes, and `svg()` for the finished SVG text.
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
    const clip = `clip${Math.random().toString(36).slice(2, 9)}`;
    const body = [];
    const above = [];
    const fig = {
      x, y, width, height, margin: m, pw, ph, xlim: o.xlim, ylim: o.ylim,
      add(s) { body.push(s); return fig; },
      over(s) { above.push(s); return fig; },
      svg() {
        const xt = o.xticks ?? niceTicks(x0, x1, o.xtickCount ?? Math.max(3, Math.round(pw / 80)));
        const yt = o.yticks ?? niceTicks(y0, y1, o.ytickCount ?? Math.max(3, Math.round(ph / 50)));
        const xs = xt.length > 1 ? xt[1] - xt[0] : 1;
        const ys = yt.length > 1 ? yt[1] - yt[0] : 1;
        const g = [];
        g.push(`<svg xmlns="http://www.w3.org/2000/svg" width="${width}" height="${height}" viewBox="0 0 ${width} ${height}" font-family="${FONT}" font-size="12">`);
        g.push(`<rect x="0" y="0" width="${width}" height="${height}" fill="#ffffff"/>`);
        g.push(`<defs><clipPath id="${clip}"><rect x="${n(m.left)}" y="${n(m.top)}" width="${n(pw)}" height="${n(ph)}"/></clipPath></defs>`);
        // Grid.
        if (o.grid !== false) {
          for (const t of xt) if (t >= x0 && t <= x1) g.push(`<line x1="${n(x(t))}" y1="${n(m.top)}" x2="${n(x(t))}" y2="${n(m.top + ph)}" stroke="#e6e6e6" stroke-width="1"/>`);
          for (const t of yt) if (t >= y0 && t <= y1) g.push(`<line x1="${n(m.left)}" y1="${n(y(t))}" x2="${n(m.left + pw)}" y2="${n(y(t))}" stroke="#e6e6e6" stroke-width="1"/>`);
        }
        g.push(`<g clip-path="url(#${clip})">`, ...body, `</g>`);
        // Zero lines.
        if (o.zeroY !== false && y0 < 0 && y1 > 0) g.push(`<line x1="${n(m.left)}" y1="${n(y(0))}" x2="${n(m.left + pw)}" y2="${n(y(0))}" stroke="#000" stroke-width="0.8"/>`);
        if (o.zeroX && x0 < 0 && x1 > 0) g.push(`<line x1="${n(x(0))}" y1="${n(m.top)}" x2="${n(x(0))}" y2="${n(m.top + ph)}" stroke="#000" stroke-width="0.8"/>`);
        // Frame, ticks, labels.
        g.push(`<rect x="${n(m.left)}" y="${n(m.top)}" width="${n(pw)}" height="${n(ph)}" fill="none" stroke="#000" stroke-width="1"/>`);
        for (const t of xt) {
          if (t < x0 || t > x1) continue;
          g.push(`<line x1="${n(x(t))}" y1="${n(m.top + ph)}" x2="${n(x(t))}" y2="${n(m.top + ph + 5)}" stroke="#000"/>`);
          g.push(`<text x="${n(x(t))}" y="${n(m.top + ph + 18)}" text-anchor="middle">${tickLabel(t, xs)}</text>`);
        }
        for (const t of yt) {
          if (t < y0 || t > y1) continue;
          g.push(`<line x1="${n(m.left - 5)}" y1="${n(y(t))}" x2="${n(m.left)}" y2="${n(y(t))}" stroke="#000"/>`);
          g.push(`<text x="${n(m.left - 8)}" y="${n(y(t) + 4)}" text-anchor="end">${tickLabel(t, ys)}</text>`);
        }
        if (o.xlabel) g.push(`<text x="${n(m.left + pw / 2)}" y="${n(height - 10)}" text-anchor="middle" font-size="13">${esc(o.xlabel)}</text>`);
        if (o.ylabel) g.push(`<text transform="translate(15 ${n(m.top + ph / 2)}) rotate(-90)" text-anchor="middle" font-size="13">${esc(o.ylabel)}</text>`);
        if (o.title) g.push(`<text x="${n(m.left)}" y="19" font-size="13" font-weight="bold">${esc(o.title)}</text>`);
        g.push(...above, `</svg>`);
        return g.join("\n");
      },
    };
    return fig;
  }

  /** A polyline through [[x, y], ...] in data coordinates; breaks at non-finite points. */
  function line(fig, pts, attrs = {}) {
    const parts = [];
    let cur = [];
    for (const [a, b] of pts) {
      if (Number.isFinite(a) && Number.isFinite(b)) cur.push(`${n(fig.x(a))},${n(fig.y(b))}`);
      else if (cur.length) { parts.push(cur); cur = []; }
    }
    if (cur.length) parts.push(cur);
    const at = Object.entries(Object.assign({ fill: "none", stroke: "#000", "stroke-width": 1.8, "stroke-linejoin": "round", "stroke-linecap": "round" }, attrs))
      .map(([k, v]) => `${k}="${esc(v)}"`).join(" ");
    return parts.filter((p) => p.length > 1).map((p) => `<polyline points="${p.join(" ")}" ${at}/>`).join("\n");
  }

  function attrs(a) {
    return Object.entries(a).map(([k, v]) => `${k}="${esc(v)}"`).join(" ");
  }

  /** A legend box: items [{label, color, dash, marker, fill}] at the top right (or `where`). */
  function legend(fig, items, where = "right") {
    const lh = 17;
    const w = Math.max(...items.map((i) => i.label.length)) * 6.6 + 40;
    const h = items.length * lh + 8;
    // `where`: "right" (top right), "left" (top left), "bottom-right", "bottom-left".
    const x0 = /left/.test(where) ? fig.margin.left + 8 : fig.margin.left + fig.pw - w - 8;
    const y0 = /bottom/.test(where) ? fig.margin.top + fig.ph - h - 8 : fig.margin.top + 8;
    const g = [`<rect x="${n(x0)}" y="${n(y0)}" width="${n(w)}" height="${n(h)}" fill="#ffffff" fill-opacity="0.9" stroke="#999" stroke-width="0.6"/>`];
    items.forEach((it, k) => {
      const yy = y0 + 4 + lh * k + lh / 2;
      if (it.marker) g.push(`<circle cx="${n(x0 + 17)}" cy="${n(yy)}" r="3.5" fill="${esc(it.color)}"/>`);
      else if (it.fill) g.push(`<rect x="${n(x0 + 7)}" y="${n(yy - 5)}" width="20" height="10" fill="${esc(it.fill)}" stroke="none"/>`);
      else g.push(`<line x1="${n(x0 + 7)}" y1="${n(yy)}" x2="${n(x0 + 27)}" y2="${n(yy)}" stroke="${esc(it.color)}" stroke-width="2" ${it.dash ? `stroke-dasharray="${esc(it.dash)}"` : ""}/>`);
      g.push(`<text x="${n(x0 + 33)}" y="${n(yy + 4)}" font-size="11.5">${esc(it.label)}</text>`);
    });
    return g.join("\n");
  }

  // Colour maps: viridis (sequential) and a blue-white-red diverging map,
  // as lists of stops interpolated linearly.
  const VIRIDIS = ["#440154", "#482878", "#3e4989", "#31688e", "#26828e", "#1f9e89", "#35b779", "#6ece58", "#b5de2b", "#fde725"];
  const DIVERGING = ["#2166ac", "#4393c3", "#92c5de", "#d1e5f0", "#f7f7f7", "#fddbc7", "#f4a582", "#d6604d", "#b2182b"];
  function hex(c) {
    return [1, 3, 5].map((i) => parseInt(c.slice(i, i + 2), 16));
  }
  function colormap(stops, t) {
    if (!Number.isFinite(t)) return "#bbbbbb";
    t = Math.max(0, Math.min(1, t));
    const f = t * (stops.length - 1);
    const i = Math.min(stops.length - 2, Math.floor(f));
    const a = hex(stops[i]);
    const b = hex(stops[i + 1]);
    const u = f - i;
    return "#" + a.map((v, k) => Math.round(v + (b[k] - v) * u).toString(16).padStart(2, "0")).join("");
  }
  const viridis = (t) => colormap(VIRIDIS, t);
  const diverging = (t) => colormap(DIVERGING, t);

  /** A vertical colour bar at the right of `fig` for values [lo, hi]. */
  function colorbar(fig, lo, hi, map, label) {
    const x0 = fig.margin.left + fig.pw + 14;
    const w = 14;
    const g = [];
    const steps = 48;
    for (let k = 0; k < steps; k += 1) {
      const t0 = k / steps;
      const yy = fig.margin.top + fig.ph * (1 - (k + 1) / steps);
      g.push(`<rect x="${n(x0)}" y="${n(yy)}" width="${w}" height="${n(fig.ph / steps + 0.6)}" fill="${map(t0 + 0.5 / steps)}"/>`);
    }
    g.push(`<rect x="${n(x0)}" y="${n(fig.margin.top)}" width="${w}" height="${n(fig.ph)}" fill="none" stroke="#000" stroke-width="0.8"/>`);
    const ticks = niceTicks(lo, hi, 5);
    const step = ticks.length > 1 ? ticks[1] - ticks[0] : 1;
    for (const t of ticks) {
      if (t < lo || t > hi) continue;
      const yy = fig.margin.top + fig.ph * (1 - (t - lo) / (hi - lo || 1));
      g.push(`<line x1="${n(x0 + w)}" y1="${n(yy)}" x2="${n(x0 + w + 4)}" y2="${n(yy)}" stroke="#000"/>`);
      g.push(`<text x="${n(x0 + w + 7)}" y="${n(yy + 4)}" font-size="11">${tickLabel(t, step)}</text>`);
    }
    if (label) g.push(`<text transform="translate(${n(x0 + w + 52)} ${n(fig.margin.top + fig.ph / 2)}) rotate(-90)" text-anchor="middle" font-size="12">${esc(label)}</text>`);
    return g.join("\n");
  }

  return { esc, n, niceTicks, niceLimits, tickLabel, figure, line, attrs, legend, viridis, diverging, colorbar };
});
