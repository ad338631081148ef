// The explorer's speed and weight, against issue 34's targets: a
// 1,000-speed eigenvalue diagram after a parameter change (< 5 ms), a
// 100 x 100 stability map (< 2 s), page and module (< 2 MB). Node.js runs
// the module with the V8 engine of Chromium; the page adds its drawing.
// Prints figures; asserts nothing (targets are checked by reading them).
//
//   node wasm/tests/bench.mjs   (after bash wasm/build.sh)

import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import zlib from "node:zlib";
import { fileURLToPath } from "node:url";
import { Bikedyn } from "../explorer/bikedyn.js";

const explorer = path.join(path.dirname(fileURLToPath(import.meta.url)), "..", "explorer");
const module = fs.readFileSync(path.join(explorer, "bikedyn.wasm"));
const bikedyn = await Bikedyn.load(module);

// Medians of the wall time and of the process's CPU time (ms): on a
// machine shared with other jobs the wall time includes waiting for a
// core, the CPU time does not.
function median(f, n) {
  const t = [];
  const c = [];
  for (let k = 0; k < n; k++) {
    const s = performance.now();
    const u = process.cpuUsage();
    f(k);
    const d = process.cpuUsage(u);
    t.push(performance.now() - s);
    c.push((d.user + d.system) / 1000);
  }
  const mid = (x) => x.sort((a, b) => a - b)[n >> 1];
  return { wall: mid(t), cpu: mid(c), toString() { return `${this.wall.toFixed(2)} ms median of ${n} (CPU ${this.cpu.toFixed(2)} ms)`; } };
}
const mb = (n) => (n / 1e6).toFixed(2);
console.log(`machine: ${os.cpus().length} cores, load average ${os.loadavg()[0].toFixed(2)} (1 min)`);

// Weight: what a browser loads served (the module fetched) and as a file
// (the module in base64).
const page = [
  "index.html", "style.css", "bikedyn.js", "plot.js", "state.js",
  "explorer.js", "panel-bicycle.js", "panel-eigen.js", "panel-map.js", "panel-simulation.js", "downloads.js", "selftest.js",
].map((f) => fs.readFileSync(path.join(explorer, f)));
const pageBytes = page.reduce((s, b) => s + b.length, 0);
const gz = (b) => zlib.gzipSync(b, { level: 9 }).length;
const pageGz = page.reduce((s, b) => s + gz(b), 0);
console.log(`weight: module ${mb(module.length)} MB (${mb(gz(module))} MB gzip), page ${mb(pageBytes)} MB; served ${mb(module.length + pageBytes)} MB (${mb(gz(module) + pageGz)} MB gzip) [target < 2 MB]`);

// A parameter change: the page's one request (`explore`: the bicycle, the
// diagram's eigenvalues and modes as arrays with the critical speeds, the
// self-stable speeds and the slider's speed) with a new trail each time;
// then the diagram's eigenvalues alone (`eig` with `arrays`), and the same
// points as JSON objects, without and with every speed's mode shapes (as
// `eig --format json` writes them).
const speeds = { start: 0, step: 0.01, count: 1001 };
const bicycle = (k) => ({ builtin: "benchmark", set: [["c", 0.08 + 1e-4 * k]] });
// The engine compiles a module's hot functions again, optimized, once
// they have run a while (in the background: later on a loaded machine):
// thirty requests first, as the page has answered as many by the time a
// parameter is edited in the browser test (the first took 6 ms at load 6.8
// where the later ones took 2, 2026-11-30).
for (let k = 0; k < 30; k++) bikedyn.call({ job: "explore", bicycle: bicycle(k), speeds, speed_min: 0, speed_max: 10, speed: 5 });
const explore = median((k) => bikedyn.call({ job: "explore", bicycle: bicycle(k), speeds, speed_min: 0, speed_max: 10, speed: 5 }), 21);
console.log(`1,001-speed diagram after a parameter change, the page's request (explore: request JSON, the answer with the points as arrays): ${explore} [target < 5 ms with the drawing; wasm/tests/explorer_browser.sh step 10]`);
const diagramOf = (options) => median((k) => bikedyn.call({ job: "eig", bicycle: bicycle(k), speeds, critical_speeds: true, ...options }), 21);
console.log(`  the diagram's eigenvalues alone (eig with modes and critical speeds, as arrays): ${diagramOf({ arrays: true })}`);
console.log(`  the same points as JSON, without mode shapes: ${diagramOf({ mode_shapes: false })}; with them: ${diagramOf({ mode_shapes: true })}`);
const stability = median((k) => bikedyn.call({ job: "stability", bicycle: bicycle(k) }), 21);
console.log(`weave and capsize speeds after a parameter change: ${stability}`);

// A 100 x 100 map, row by row as the page computes it.
const values = (a, b, n) => Array.from({ length: n }, (_, k) => a + ((b - a) * k) / (n - 1));
const request = {
  job: "map_row", bicycle: { builtin: "benchmark" }, at_speed: 5,
  parameter: { symbol: "c", values: values(0.02, 0.14, 100) },
  second: { symbol: "lam", values: values(0.1, 0.5, 100) },
};
const start = performance.now();
const cpuStart = process.cpuUsage();
let slowest = 0;
for (let row = 0; row < 100; row++) {
  const s = performance.now();
  bikedyn.call({ ...request, row });
  slowest = Math.max(slowest, performance.now() - s);
}
const cpu = process.cpuUsage(cpuStart);
console.log(`100 x 100 stability map (critical speeds on 0-10 m/s and the least-stable real part at 5 m/s per design): ${((performance.now() - start) / 1000).toFixed(2)} s (CPU ${((cpu.user + cpu.system) / 1e6).toFixed(2)} s), slowest row ${slowest.toFixed(0)} ms (the page's longest pause) [target < 2 s]`);
