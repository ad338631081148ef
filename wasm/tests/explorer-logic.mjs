// The explorer's pure logic, without a browser: the link's state (round
// trip, defaults, bad input), the `set` list's order, the speeds, the plot
// ticks and colour maps, and (when the module is built) that the requests
// the page builds from a state are answered.
//
//   node wasm/tests/explorer-logic.mjs
import assert from "node:assert/strict";
import fs from "node:fs";
import path from "node:path";
import { fileURLToPath } from "node:url";
import { ExplorerState as S } from "../explorer/state.js";
import { BikedynPlot as P } from "../explorer/plot.js";
import { Bikedyn } from "../explorer/bikedyn.js";

let count = 0;
function test(name, f) {
  f();
  count += 1;
  console.log(`  ok ${name}`);
}

test("defaults encode to a short hash and decode back", () => {
  const d = S.defaults();
  assert.equal(S.encode(d), "bike=benchmark");
  assert.deepEqual(S.decode("#" + S.encode(d)), d);
  assert.deepEqual(S.decode(""), d);
});

test("a full state round-trips through the hash", () => {
  const s = S.defaults();
  Object.assign(s, {
    bike: "thesis", model: "extended", edits: { c: 0.1, lam: Math.PI / 10, mB: 80 }, effects: { c_steer: 0.4, Kc_roll_rate: -12.5 },
    vmin: 1, vmax: 8, vstep: 0.04, speed: 3.25,
    map: { x: "c_steer", x0: 0, x1: 2, nx: 21, y: "Kc_roll_rate", y0: -10, y1: 0, ny: 11, metric: "stable_width", at: 4 },
    sim: { speed: 4, impulse: -6, time: 1, duration: 3, ahead: 0.3, height: 1, roll_rate: 5 },
  });
  const h = S.encode(s);
  assert.match(h, /set=c:0.1,lam:0.3141592653589793,mB:80/);
  assert.deepEqual(S.decode(h), s);
  // Numbers exactly (shortest round-trip text).
  assert.equal(S.decode(h).edits.lam, Math.PI / 10);
});

test("an imported file travels whole in the link", () => {
  const s = S.defaults();
  const text = "# a bicycle, \u00e9t\u00e9 \u2014 UTF-8\nform = \"benchmark\"\nw = 1.1\n[feedback]\nspeeds = [0.0, 1.5]\n";
  Object.assign(s, { bike: "file", file: { name: "my bike.toml", text } });
  const h = S.encode(s);
  assert.match(h, /^bike=file&name=my\+bike.toml&file=[A-Za-z0-9_-]+$/);
  const d = S.decode(h);
  assert.deepEqual(d, s);
  assert.deepEqual(S.bicycleSpec(d, []), { file: { name: "my bike.toml", text }, set: [] });
  // Another bicycle chosen: the file stays in the page, not in the link.
  assert.equal(S.encode(Object.assign({}, s, { bike: "thesis" })), "bike=thesis");
  assert.equal(S.fromBase64Url(S.toBase64Url(text)), text);
  assert.equal(S.decode("#bike=file&file=%%%").bike, "benchmark");
});

test("bad or unknown hash fields keep the defaults", () => {
  const d = S.decode("#bike=nonsense&v=5:1:0.1&at=abc&set=c:x,lam:0.3,:1&map=1:2&foo=bar");
  assert.equal(d.bike, "benchmark");
  assert.equal(d.vmin, 0);
  assert.equal(d.vmax, 10);
  assert.equal(d.speed, 5);
  assert.deepEqual(d.edits, { lam: 0.3 });
  assert.deepEqual(d.map, S.defaults().map);
  assert.equal(S.decode("#selftest").selftest, true);
});

test("the set list: edits in the table's order, then the effects", () => {
  const s = S.defaults();
  s.edits = { lam: 0.3, w: 1.1, zz: 2 };
  s.effects = { c_steer: 0.4 };
  assert.deepEqual(S.setList(s, ["w", "c", "lam"]), [["w", 1.1], ["lam", 0.3], ["zz", 2], ["c_steer", 0.4]]);
  assert.deepEqual(S.bicycleSpec(s, ["w", "c", "lam"]).builtin, "benchmark");
  assert.deepEqual(S.bicycleSpec(Object.assign(s, { bike: "file", file: { name: "a.txt", text: "x" } }), [], false), { file: { name: "a.txt", text: "x" } });
});

test("speed ranges include both ends", () => {
  assert.deepEqual(S.speedRange(S.defaults()), { start: 0, step: 0.05, count: 201 });
  assert.deepEqual(S.linspace(0, 1, 5), [0, 0.25, 0.5, 0.75, 1]);
  assert.deepEqual(S.linspace(2, 3, 1), [2]);
});

test("ticks are round and cover the range", () => {
  assert.deepEqual(P.niceTicks(0, 10, 5), [0, 2, 4, 6, 8, 10]);
  assert.deepEqual(P.niceTicks(-10, 10, 8), [-10, -8, -6, -4, -2, 0, 2, 4, 6, 8, 10]);
  for (const [lo, hi] of [[0.013, 0.147], [-3.2, 7.9], [4, 4], [1e-4, 3e-4]]) {
    const t = P.niceTicks(lo, hi);
    assert.ok(t.length >= 2, `${lo}..${hi}: ${t}`);
    const step = t[1] - t[0];
    for (let k = 1; k < t.length; k += 1) assert.ok(Math.abs(t[k] - t[k - 1] - step) < step * 1e-9);
    const m = step / Math.pow(10, Math.floor(Math.log10(step)));
    assert.ok([1, 2, 5, 10].some((x) => Math.abs(m - x) < 1e-9), `step ${step}`);
  }
  const [a, b] = P.niceLimits(-3.2, 7.9);
  assert.ok(a <= -3.2 && b >= 7.9);
  assert.equal(P.tickLabel(-0.0000001, 0.5), "0.0");
  assert.equal(P.tickLabel(-0.0000001, 2), "0");
  assert.equal(P.tickLabel(-2.5, 0.5), "\u22122.5");
});

test("colour maps and SVG text", () => {
  assert.equal(P.viridis(0), "#440154");
  assert.equal(P.viridis(1), "#fde725");
  assert.equal(P.diverging(0.5), "#f7f7f7");
  assert.equal(P.viridis(NaN), "#bbbbbb");
  const fig = P.figure({ width: 300, height: 200, xlim: [0, 10], ylim: [-1, 1], xlabel: "v (m/s)", ylabel: "a < b" });
  fig.add(P.line(fig, [0, 0, 5, 1, NaN, NaN, 6, 0, 10, -1]));
  const svg = fig.svg();
  assert.match(svg, /^<svg xmlns="http:\/\/www.w3.org\/2000\/svg"/);
  assert.equal((svg.match(/<polyline/g) || []).length, 2);
  assert.match(svg, /a &lt; b/);
});

// The page's requests, answered by the module (skipped when it is not built).
const here = path.dirname(fileURLToPath(import.meta.url));
const wasm = path.join(here, "..", "explorer", "bikedyn.wasm");
if (fs.existsSync(wasm)) {
  const bd = await Bikedyn.load(fs.readFileSync(wasm));
  test("the page's requests from a state are answered", () => {
    const s = S.decode("#bike=benchmark&set=c:0.08&fx=c_steer:0&v=0:10:0.05");
    const order = bd.call({ job: "bicycle", bicycle: { builtin: "benchmark" } }).benchmark.map(([k]) => k);
    const e = bd.call({ job: "eig", bicycle: S.bicycleSpec(s, order), speeds: S.speedRange(s), critical_speeds: true });
    assert.equal(e.points.length, 201);
    assert.equal(e.weave_speed.toFixed(4), "4.2924");
    assert.equal(e.capsize_speed.toFixed(4), "6.0243");
    // The diagram's request: the same eigenvalues and modes as arrays.
    const a = bd.call({ job: "eig", bicycle: S.bicycleSpec(s, order), speeds: S.speedRange(s), critical_speeds: true, arrays: true });
    assert.equal(a.count, 201);
    assert.ok(a.arrays.eigenvalues instanceof Float64Array && a.arrays.eigenvalues.length === 8 * 201);
    assert.equal(a.weave_speed, e.weave_speed);
    const i = 120;
    assert.deepEqual([...a.arrays.eigenvalues.slice(8 * i, 8 * i + 8)], e.points[i].eigenvalues.flat());
    assert.deepEqual([...a.arrays.modes.slice(4 * i, 4 * i + 4)].map((k) => a.mode_names[k]), e.points[i].modes);
    assert.equal(a.arrays.v[i], e.points[i].v);
  });
} else {
  console.log(`  skipped the module's requests: ${wasm} is not built`);
}
console.log(`${count} tests passed`);
