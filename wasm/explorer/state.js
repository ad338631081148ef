// The explorer's state and its URL hash, so that a link shares a
// configuration: which bicycle, the parameters edited, the effects switched
// on, the speeds, the slider's speed, the map's and the simulation's
// settings. Pure functions (no page): the node test checks the round trip.
//
// The hash reads like a query: `#bike=benchmark&set=c:0.1,lam:0.3&fx=c_steer:0.4&v=0:10:0.05&at=5`.
// An imported file travels whole (`bike=file&name=bike.toml&file=BASE64URL`
// of its UTF-8 text), so that the link gives exactly the file's bicycle:
// its uncertainties, effects and feedback tables too, which its values
// alone would not.
(function (root, factory) {
  const api = factory();
  if (typeof module === "object" && module && module.exports) {
    module.exports.ExplorerState = api;
  } else {
    root.ExplorerState = api;
  }
})(typeof globalThis !== "undefined" ? globalThis : this, function () {
  "use strict";

  function defaults() {
    return {
      bike: "benchmark", // "benchmark", "thesis" or "file"
      file: null, // an imported file {name, text}, kept when another bicycle is chosen
      model: "", // "" = the bicycle's own model
      edits: {}, // {symbol: value}: parameters changed in the table
      effects: {}, // {symbol: value}: effect parameters switched on
      vmin: 0,
      vmax: 10,
      vstep: 0.05,
      speed: 5, // the slider's
      map: { x: "c", x0: 0.02, x1: 0.14, nx: 13, y: "lam", y0: 0.1, y1: 0.5, ny: 11, metric: "least_stable_real_part", at: 5 },
      sim: { speed: 5, impulse: 8, time: 0.5, duration: 5, ahead: 0.25, height: 0.95, roll_rate: 0 },
      selftest: false,
    };
  }

  // A number as its shortest round-trip text.
  const num = (x) => String(x);
  const pairs = (obj) => Object.entries(obj).map(([k, v]) => `${k}:${num(v)}`).join(",");
  function readPairs(text) {
    const out = {};
    if (!text) return out;
    for (const item of text.split(",")) {
      const k = item.lastIndexOf(":");
      if (k <= 0) continue;
      const v = Number(item.slice(k + 1));
      if (Number.isFinite(v)) out[item.slice(0, k)] = v;
    }
    return out;
  }

  /** The hash text (without `#`) of `state`; defaults are left out. */
  function encode(state) {
    const d = defaults();
    const p = new URLSearchParams();
    const file = state.bike === "file" && state.file;
    p.set("bike", file ? "file" : state.bike === "thesis" ? "thesis" : "benchmark");
    if (file) {
      p.set("name", state.file.name);
      p.set("file", toBase64Url(state.file.text));
    }
    if (state.model) p.set("model", state.model);
    if (Object.keys(state.edits).length) p.set("set", pairs(state.edits));
    if (Object.keys(state.effects).length) p.set("fx", pairs(state.effects));
    if (state.vmin !== d.vmin || state.vmax !== d.vmax || state.vstep !== d.vstep) p.set("v", `${num(state.vmin)}:${num(state.vmax)}:${num(state.vstep)}`);
    if (state.speed !== d.speed) p.set("at", num(state.speed));
    const m = state.map;
    if (JSON.stringify(m) !== JSON.stringify(d.map)) {
      p.set("map", [m.x, m.x0, m.x1, m.nx, m.y, m.y0, m.y1, m.ny, m.metric, m.at].map(String).join(":"));
    }
    const s = state.sim;
    if (JSON.stringify(s) !== JSON.stringify(d.sim)) p.set("sim", pairs(s));
    if (state.selftest) p.set("selftest", "1");
    // Readable: keep `:` and `,` as they are.
    return p.toString().replace(/%3A/g, ":").replace(/%2C/g, ",");
  }

  /** The state of hash text `hash` (with or without `#`); unknown or bad fields keep their defaults. */
  function decode(hash) {
    const s = defaults();
    const text = String(hash || "").replace(/^#/, "");
    if (!text) return s;
    const p = new URLSearchParams(text);
    if (p.has("selftest") || text === "selftest") s.selftest = true;
    const bike = p.get("bike");
    if (bike === "benchmark" || bike === "thesis") s.bike = bike;
    if (bike === "file" && p.get("file")) {
      try {
        s.file = { name: p.get("name") || "bicycle.toml", text: fromBase64Url(p.get("file")) };
        s.bike = "file";
      } catch (e) {
        // not base64 text: the default bicycle
      }
    }
    s.model = p.get("model") || "";
    s.edits = readPairs(p.get("set"));
    s.effects = readPairs(p.get("fx"));
    const v = (p.get("v") || "").split(":").map(Number);
    if (v.length === 3 && v.every(Number.isFinite) && v[1] > v[0] && v[2] > 0) [s.vmin, s.vmax, s.vstep] = v;
    const at = Number(p.get("at"));
    if (p.has("at") && Number.isFinite(at)) s.speed = at;
    const m = (p.get("map") || "").split(":");
    if (m.length === 10) {
      const [x, x0, x1, nx, y, y0, y1, ny, metric, atm] = m;
      const nums = [x0, x1, nx, y0, y1, ny, atm].map(Number);
      if (nums.every(Number.isFinite)) {
        s.map = { x, x0: nums[0], x1: nums[1], nx: nums[2], y, y0: nums[3], y1: nums[4], ny: nums[5], metric, at: nums[6] };
      }
    }
    Object.assign(s.sim, readPairs(p.get("sim")));
    return s;
  }

  /** The request's `bicycle` of `state`, with the `set` list (`order`: the table's symbols) unless `withSet` is false. */
  function bicycleSpec(state, order, withSet = true) {
    let spec;
    if (state.bike === "file" && state.file) spec = { file: { name: state.file.name, text: state.file.text } };
    else spec = { builtin: state.bike === "thesis" ? "thesis" : "benchmark" };
    if (withSet) spec.set = setList(state, order);
    return spec;
  }

  /** The `set` pairs: edited parameters in the table's order, then the effects. */
  function setList(state, order = []) {
    const set = [];
    const seen = new Set();
    for (const k of order) if (k in state.edits) { set.push([k, state.edits[k]]); seen.add(k); }
    for (const k of Object.keys(state.edits)) if (!seen.has(k)) set.push([k, state.edits[k]]);
    for (const [k, v] of Object.entries(state.effects)) set.push([k, v]);
    return set;
  }

  /** The speeds `{start, step, count}` of `vmin:vmax:vstep` (both ends included). */
  function speedRange(state) {
    const count = Math.max(2, Math.min(5001, Math.round((state.vmax - state.vmin) / state.vstep) + 1));
    return { start: state.vmin, step: state.vstep, count };
  }

  /** `count` values from `a` to `b`, both included. */
  function linspace(a, b, count) {
    const c = Math.max(1, Math.round(count));
    if (c === 1) return [a];
    return Array.from({ length: c }, (_, k) => a + ((b - a) * k) / (c - 1));
  }

  /** UTF-8 text as base64url (no padding), and back. */
  function toBase64Url(text) {
    const bytes = new TextEncoder().encode(text);
    let binary = "";
    for (let i = 0; i < bytes.length; i += 0x8000) binary += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    return btoa(binary).replace(/\+/g, "-").replace(/\//g, "_").replace(/=+$/, "");
  }
  function fromBase64Url(b64) {
    const binary = atob(b64.replace(/-/g, "+").replace(/_/g, "/"));
    const bytes = Uint8Array.from(binary, (c) => c.charCodeAt(0));
    return new TextDecoder("utf-8", { fatal: true }).decode(bytes);
  }

  return { defaults, encode, decode, bicycleSpec, setList, speedRange, linspace, toBase64Url, fromBase64Url };
});
