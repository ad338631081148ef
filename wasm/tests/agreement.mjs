// The WebAssembly module gives the numbers of the native build: every job
// of the module against the command line (the same library, compiled for
// the machine) on built-in and real bicycles, every built-in model, a
// controller, sweeps, a stability map row by row, and nonlinear
// simulations. Numbers must agree to 1e-12 relative (or absolutely below
// 1); strings, keys and errors exactly. The simulations are read from the
// command line's CSV, whose 13 significant digits add their rounding
// (5e-13) to the tolerance. Prints how many numbers were compared and how
// many are bit for bit the same: they differ where the two builds' sine,
// cosine and the other elementary functions round a last bit differently
// (the host's C library against Rust's own in WebAssembly).
//
//   node wasm/tests/agreement.mjs WASM BIKEDYN
//
// WASM: target/wasm32-unknown-unknown/release/bikedyn_wasm.wasm
// BIKEDYN: target/release/bikedyn (run from the repository root: the real
// bicycles are read from tests/data/).

import { execFileSync, spawnSync } from "node:child_process";
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { Bikedyn, BikedynError } from "../explorer/bikedyn.js";

const [wasmPath, cli] = process.argv.slice(2);
if (!wasmPath || !cli) {
  console.error("usage: node wasm/tests/agreement.mjs WASM BIKEDYN");
  process.exit(2);
}
for (const [what, p] of [
  ["the WebAssembly module (build it: see wasm/README.md)", wasmPath],
  ["the command line (cargo build --release --bin bikedyn)", cli],
]) {
  if (!fs.existsSync(p)) {
    console.error(`error: ${p}: no such file: ${what}`);
    process.exit(2);
  }
}

const deg = (x) => x * (Math.PI / 180); // f64::to_radians, as the command line
const TOL = Number(process.env.TOL ?? 1e-12);
const tally = { numbers: 0, identical: 0, maxRelative: 0, cases: 0, failures: [] };
// The JSON outputs against the CSV's rounded ones, counted apart.
const json = { numbers: 0, identical: 0, maxRelative: 0 };
// Whether the native side is a CSV, written to 13 significant digits with
// times to 6 decimals (so to 5e-13 relative, and 5e-7 s).
let csv = false;
const CSV_ROUNDING = 5e-13;
const bikedyn = await Bikedyn.load(fs.readFileSync(wasmPath));

function native(args) {
  const r = spawnSync(cli, args, { encoding: "utf8", maxBuffer: 1 << 28 });
  if (r.status === 0) return { ok: r.stdout };
  // The command line prints `error: MESSAGE` (and perhaps hints after).
  const line = r.stderr.split("\n").find((l) => l.startsWith("error: ")) ?? r.stderr;
  return { error: line.replace(/^error: /, "").trim() };
}

function wasm(request) {
  try {
    return { ok: bikedyn.call(request) };
  } catch (e) {
    if (e instanceof BikedynError) return { error: e.message };
    throw e;
  }
}

function compare(a, b, where) {
  if (typeof a === "number" && typeof b === "number") {
    for (const t of csv ? [tally] : [tally, json]) t.numbers += 1;
    if (Object.is(a, b)) {
      for (const t of csv ? [tally] : [tally, json]) t.identical += 1;
      return;
    }
    const rel = Math.abs(a - b) / Math.max(1, Math.abs(a), Math.abs(b));
    if (csv && /\.t\[\d+\]$/.test(where)) {
      if (!(Math.abs(a - b) <= 5e-7)) throw new Error(`${where}: time ${a} (native, 6 decimals) against ${b} (WebAssembly)`);
      return;
    }
    for (const t of csv ? [tally] : [tally, json]) t.maxRelative = Math.max(t.maxRelative, rel);
    // A CSV number is itself known only to its rounding.
    if (!(rel <= TOL + (csv ? CSV_ROUNDING : 0))) throw new Error(`${where}: ${a} (native) against ${b} (WebAssembly)`);
    return;
  }
  if (Array.isArray(a) && Array.isArray(b)) {
    if (a.length !== b.length) throw new Error(`${where}: ${a.length} entries against ${b.length}`);
    a.forEach((x, i) => compare(x, b[i], `${where}[${i}]`));
    return;
  }
  if (a && b && typeof a === "object" && typeof b === "object") {
    const ka = Object.keys(a).sort().join(",");
    const kb = Object.keys(b).sort().join(",");
    if (ka !== kb) throw new Error(`${where}: fields ${ka} against ${kb}`);
    for (const k of Object.keys(a)) compare(a[k], b[k], `${where}.${k}`);
    return;
  }
  if (a !== b) throw new Error(`${where}: ${JSON.stringify(a)} against ${JSON.stringify(b)}`);
}

/** One case: the native output (parsed by `read`) against the module's. */
function check(name, args, request, read = JSON.parse, pick = (x) => x) {
  tally.cases += 1;
  try {
    const n = native(args);
    const w = wasm(request(n));
    if (n.error !== undefined || w.error !== undefined) {
      if (n.error === undefined || w.error === undefined) {
        throw new Error(`native ${n.error ? `error: ${n.error}` : "ok"}, WebAssembly ${w.error ? `error: ${w.error}` : "ok"}`);
      }
      // The command line shortens a long message to its start and says by
      // how much; the module gives it whole.
      const short = /^([\s\S]*)\.\.\. \((\d+) more characters\)$/.exec(n.error);
      if (short && w.error.startsWith(short[1]) && w.error.length === short[1].length + Number(short[2])) {
        console.log(`  ${name}: the same error`);
        return;
      }
      if (n.error !== w.error) throw new Error(`error ${JSON.stringify(n.error)} against ${JSON.stringify(w.error)}`);
      console.log(`  ${name}: the same error`);
      return;
    }
    const before = tally.numbers;
    compare(read(n.ok), pick(w.ok), name);
    console.log(`  ${name}: ${tally.numbers - before} numbers agree`);
  } catch (e) {
    tally.failures.push(`${name}: ${e.message}`);
  }
}

// A bicycle as the command line takes it, and as the module does.
const bicycles = [
  ["benchmark", { builtin: "benchmark" }],
  ["thesis", { builtin: "thesis" }],
  ...[
    "BluenosePar.txt", // bicycleparameters' text form with +/- values
    "TmsBenchmark.txt",
    "Balanceassistv1Benchmark.txt",
    "basu_mandal2007.toml",
    "tudelft_sbw_bicycle.toml",
    "balance_assist_gain_8.toml", // a roll-rate controller, gain-scheduled
  ].map((f) => {
    const file = path.join("tests", "data", f);
    return [file, { file: { name: file, text: fs.readFileSync(file, "utf8") } }];
  }),
];
const speedsOf = (text) => JSON.parse(text).map((p) => p.v);

for (const [bike, spec] of bicycles) {
  check(`eig ${bike}`, ["eig", "--bike", bike, "--speeds", "0:10:0.25", "--format", "json"],
    (n) => ({ job: "eig", bicycle: spec, speeds: n.ok ? speedsOf(n.ok) : [0] }), JSON.parse, (w) => w.points);
  check(`stability ${bike}`, ["stability", "--bike", bike, "--json"], () => ({ job: "stability", bicycle: spec }));
  check(`canonical ${bike}`, ["canonical", "--bike", bike, "--json"],
    () => ({ job: "canonical", bicycle: spec, speeds: [0, 2, 4, 6, 8, 10] }));
}

// The explorer's diagram asks without mode shapes: the same points, less
// their `mode_shapes`.
const withoutModeShapes = (text) => JSON.parse(text).map(({ mode_shapes, ...rest }) => rest);
for (const [bike, spec] of [bicycles[0], bicycles[2], bicycles[bicycles.length - 1]]) {
  check(`eig without mode shapes ${bike}`, ["eig", "--bike", bike, "--speeds", "0:10:0.25", "--format", "json"],
    (n) => ({ job: "eig", bicycle: spec, speeds: n.ok ? speedsOf(n.ok) : [0], mode_shapes: false }), withoutModeShapes, (w) => w.points);
}

// The explorer's diagram asks for its eigenvalues and modes as arrays of
// numbers (`eig` with `arrays`; no mode shapes or standard deviations):
// the same points, as columns, bit for bit those of the module's JSON (so
// to the command line's as the JSON is).
const pair = (a, k) => [a[2 * k], a[2 * k + 1]];
const eigenvaluesAndModes = (points) => points.map(({ mode_shapes, standard_deviations, ...rest }) => rest);
const fromArrays = (w) =>
  Array.from({ length: w.count }, (_, i) => {
    const a = w.arrays;
    const p = {
      eigenvalues: [0, 1, 2, 3].map((k) => pair(a.eigenvalues, 4 * i + k)),
      modes: [0, 1, 2, 3].map((k) => w.mode_names[a.modes[4 * i + k]]),
      v: a.v[i],
    };
    const e = w.extra_per_speed;
    if (e) p.extra_eigenvalues = Array.from({ length: e }, (_, k) => pair(a.extra_eigenvalues, e * i + k));
    return p;
  });
const arraysCheck = (name, args, request) => {
  check(name, args, (n) => ({ ...request(n), arrays: true, critical_speeds: true }), (t) => eigenvaluesAndModes(JSON.parse(t)), (w) => {
    // The critical speeds beside the arrays are those of the JSON answer.
    const j = wasm({ ...request({}), critical_speeds: true, mode_shapes: false }).ok;
    for (const k of ["weave_speed", "capsize_speed", "weave_real_pair_merge_speed", "model"]) {
      if (!Object.is(j[k], w[k])) throw new Error(`${k}: ${j[k]} (JSON) against ${w[k]} (arrays)`);
    }
    const points = fromArrays(w);
    compare(eigenvaluesAndModes(j.points), points, `${name} (JSON against arrays)`);
    return points;
  });
};
for (const [bike, spec] of [bicycles[0], bicycles[2], bicycles[bicycles.length - 1]]) {
  arraysCheck(`eig arrays ${bike}`, ["eig", "--bike", bike, "--speeds", "0:10:0.25", "--format", "json"],
    () => ({ job: "eig", bicycle: spec, speeds: { start: 0, step: 0.25, count: 41 } }));
}

// The explorer's one request after a change (`explore`): the bicycle, the
// diagram's arrays, the self-stable speeds and the slider's speed, each
// the numbers of the job that gave it alone (the command line's, and for
// the bicycle and the critical speeds the module's own `bicycle` and `eig`).
const exploreRequest = (spec, model) => ({
  job: "explore", bicycle: spec, ...(model ? { model } : {}),
  speeds: { start: 0, step: 0.25, count: 41 }, speed_min: 0, speed_max: 10, speed: 5,
});
const withoutDeviations = (t) => JSON.parse(t).map(({ standard_deviations, ...rest }) => rest);
for (const [bike, spec] of [bicycles[0], bicycles[2], bicycles[bicycles.length - 1]]) {
  check(`explore ${bike}: diagram`, ["eig", "--bike", bike, "--speeds", "0:10:0.25", "--format", "json"],
    () => exploreRequest(spec), (t) => eigenvaluesAndModes(JSON.parse(t)), fromArrays);
  check(`explore ${bike}: self-stable speeds`, ["stability", "--bike", bike, "--json"],
    () => exploreRequest(spec), (t) => JSON.parse(t).stable_intervals, (w) => w.stable_intervals);
  check(`explore ${bike}: at 5 m/s`, ["eig", "--bike", bike, "--speeds", "5:5:1", "--format", "json"],
    () => exploreRequest(spec), withoutDeviations, (w) => [w.at_speed]);
  tally.cases += 1;
  try {
    const w = wasm(exploreRequest(spec)).ok;
    compare(wasm({ job: "bicycle", bicycle: spec }).ok, w.bicycle, `explore ${bike}: bicycle`);
    const j = wasm({ job: "eig", bicycle: spec, speeds: exploreRequest(spec).speeds, critical_speeds: true, arrays: true }).ok;
    for (const k of ["weave_speed", "capsize_speed", "weave_real_pair_merge_speed", "model"]) {
      if (!Object.is(j[k], w[k])) throw new Error(`${k}: ${j[k]} (eig) against ${w[k]} (explore)`);
    }
    console.log(`  explore ${bike}: the bicycle and critical speeds of \`bicycle\` and \`eig\``);
  } catch (e) {
    tally.failures.push(`explore ${bike}: ${e.message}`);
  }
}

// The eigenvalue table as `eig --format csv` writes it (the explorer's
// download): the same header, and each cell the same text or number.
const table = (t) => t.trim().split("\n").map((r) => r.split(",").map((c) => (c === "" || isNaN(Number(c)) ? c : Number(c))));
for (const [bike, spec] of [bicycles[0], bicycles[2], bicycles[bicycles.length - 1]]) {
  check(`eig csv ${bike}`, ["eig", "--bike", bike, "--speeds", "0:10:0.5", "--format", "csv"],
    () => ({ job: "eig", bicycle: spec, speeds: { start: 0, step: 0.5, count: 21 }, csv: true }), table, (w) => table(w.csv));
}

// Every built-in model, through the thesis bicycle (a model that cannot
// represent it must fail with the same message).
const models = JSON.parse(native(["models", "--json"]).ok).map((m) => m.name);
for (const model of models) {
  check(`eig thesis --model ${model}`,
    ["eig", "--bike", "thesis", "--model", model, "--speeds", "0.5:9.5:1", "--format", "json"],
    (n) => ({ job: "eig", bicycle: { builtin: "thesis" }, model, speeds: n.ok ? speedsOf(n.ok) : [0.5] }),
    JSON.parse, (w) => w.points);
  arraysCheck(`eig arrays thesis --model ${model}`,
    ["eig", "--bike", "thesis", "--model", model, "--speeds", "0.5:9.5:1", "--format", "json"],
    () => ({ job: "eig", bicycle: { builtin: "thesis" }, model, speeds: { start: 0.5, step: 1, count: 10 } }));
  check(`stability thesis --model ${model}`, ["stability", "--bike", "thesis", "--model", model, "--json"],
    () => ({ job: "stability", bicycle: { builtin: "thesis" }, model }));
}

// A parameter set on the command line's file, and an effect (steer
// damping through `extended`).
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), "bikedyn-wasm-agreement-"));
try {
  const damped = path.join(tmp, "damped.toml");
  // The module's TOML of the benchmark bicycle, read back by the command line.
  const benchmarkToml = wasm({ job: "bicycle", bicycle: { builtin: "benchmark" } }).ok.toml;
  fs.writeFileSync(damped, benchmarkToml + "\nc_steer = 0.4\n");
  const unnamed = (r) => ({ ...r, bike: null }); // a file's path, a set value's name
  check("stability with steer damping", ["stability", "--bike", damped, "--json"],
    () => ({ job: "stability", bicycle: { builtin: "benchmark", set: [["c_steer", 0.4]] } }),
    (t) => unnamed(JSON.parse(t)), unnamed);
  // A leaning rider's upper body on the benchmark bicycle (the models
  // rider_lean and rider_lean_free): lean axis 0.9 m high above the rear
  // frame's mass centre, a 30 kg upper body 0.3 m above it.
  const rider = [["xL", 0.3], ["zL", 0.6], ["x6", 0.0], ["z6", 0.3], ["m6", 30.0], ["I6x", 1.0], ["I6y", 1.1],
    ["I6z", 0.4], ["I6xz", 0.1], ["k_lean", 400.0], ["c_lean", 20.0]];
  const leaning = path.join(tmp, "leaning.toml");
  fs.writeFileSync(leaning, benchmarkToml + "\n" + rider.map(([k, v]) => `${k} = ${v}`).join("\n") + "\n");
  const riderSpec = { builtin: "benchmark", set: rider };
  check("eig leaning rider", ["eig", "--bike", leaning, "--speeds", "0:10:0.5", "--format", "json"],
    (n) => ({ job: "eig", bicycle: riderSpec, speeds: n.ok ? speedsOf(n.ok) : [0] }), JSON.parse, (w) => w.points);
  check("stability leaning rider", ["stability", "--bike", leaning, "--json"],
    () => ({ job: "stability", bicycle: riderSpec }), (t) => unnamed(JSON.parse(t)), unnamed);
  simulation("simulate leaning rider", leaning, riderSpec, { speed: 5, rollRate: 10, duration: 2 });
  simulation("simulate leaning rider free speed", leaning, riderSpec, { speed: 5, rollRate: 10, duration: 2, free: true });
} finally {
  fs.rmSync(tmp, { recursive: true, force: true });
}

// Sweeps and a stability map, whole and row by row.
const values = (a, b, s) => Array.from({ length: Math.round((b - a) / s) + 1 }, (_, k) => a + k * s);
check("sweep benchmark c", ["sweep", "--bike", "benchmark", "--param", "c", "--values", "0.02:0.12:0.02", "--format", "json"],
  (n) => ({ job: "sweep", bicycle: { builtin: "benchmark" }, parameter: { symbol: "c", values: n.ok ? JSON.parse(n.ok).points.map((p) => p.value) : [] } }));
const mapArgs = ["sweep", "--bike", "benchmark", "--param", "c", "--values", "0.04:0.12:0.04", "--param2", "lam",
  "--values2", "0.25:0.4:0.05", "--at-speed", "5", "--format", "json"];
const nativeMap = native(mapArgs);
const axes = nativeMap.ok ? JSON.parse(nativeMap.ok) : { x: { values: [] }, y: { values: [] } };
const mapRequest = {
  bicycle: { builtin: "benchmark" },
  parameter: { symbol: "c", values: axes.x.values },
  second: { symbol: "lam", values: axes.y.values },
  at_speed: 5,
};
check("stability map benchmark c x lam", mapArgs, () => ({ job: "sweep", ...mapRequest }));
axes.x.values.forEach((_, i) => {
  check(`stability map row ${i}`, mapArgs, () => ({ job: "map_row", row: i, ...mapRequest }),
    (t) => {
      const m = JSON.parse(t);
      const ny = m.y.values.length;
      return m.cells.slice(i * ny, (i + 1) * ny).map((c) => ({ ...c, i: 0 }));
    },
    (w) => w.cells);
});

// Nonlinear simulations: the command line's CSV (13 significant digits)
// against the module's samples, so to the CSV's rounding (5e-13).
function simulation(name, bike, spec, o) {
  csv = true;
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), "bikedyn-wasm-sim-"));
  const out = path.join(dir, "run.csv");
  const args = ["simulate", "--bike", bike, "--speed", String(o.speed), "--roll-rate", String(o.rollRate),
    "--duration", String(o.duration), "--out", out, ...(o.free ? ["--free-speed"] : []),
    ...(o.kick ? ["--kick", o.kick.join(":")] : []), ...(o.model ? ["--model", o.model] : [])];
  check(name, args,
    () => ({
      job: "simulate", bicycle: spec, model: o.model ?? null, free_speed: !!o.free, duration: o.duration,
      initial: { roll: 0, steer: 0, roll_rate: deg(o.rollRate), steer_rate: 0, speed: o.speed, yaw: 0 },
      inputs: { kicks: o.kick ? [{ time: o.kick[0], impulse: o.kick[1], ahead: 0.25, height: 0.95 }] : [], pulses: [] },
    }),
    () => {
      const [header, ...rows] = fs.readFileSync(out, "utf8").trim().split("\n");
      const names = header.split(",");
      return Object.fromEntries(names.map((c, j) => [c, rows.map((r) => Number(r.split(",")[j]))]));
    },
    (w) => {
      const s = w.simulation;
      const cols = { t: s.t };
      s.coordinates.forEach((c, j) => {
        cols[c] = s.p.map((p) => p[j]);
        cols[`d${c}`] = s.dp.map((p) => p[j]);
      });
      Object.assign(cols, {
        speed: s.speed, kinetic_energy: s.kinetic_energy, potential_energy: s.potential_energy,
        constraint_residual: s.constraint_residual,
      });
      s.states.forEach((c, j) => (cols[c] = s.z.map((z) => z[j])));
      return cols;
    });
  fs.rmSync(dir, { recursive: true, force: true });
  csv = false;
}
simulation("simulate benchmark", "benchmark", { builtin: "benchmark" }, { speed: 4.6, rollRate: 20, duration: 3 });
simulation("simulate thesis kick", "thesis", { builtin: "thesis" }, { speed: 5, rollRate: 0, duration: 3, kick: [0.5, 8] });
simulation("simulate thesis free speed", "thesis", { builtin: "thesis" }, { speed: 5, rollRate: 10, duration: 3, free: true });
simulation("simulate extended", "thesis", { builtin: "thesis" }, { speed: 5, rollRate: 10, duration: 2, model: "extended" });

// Errors: the same messages.
check("unknown parameter", ["sweep", "--bike", "benchmark", "--param", "wheelbase", "--values", "1:2:1", "--json"],
  () => ({ job: "sweep", bicycle: { builtin: "benchmark" }, parameter: { symbol: "wheelbase", values: [1, 2] } }));
check("parameter file with too few values",
  ["stability", "--bike", "tests/data/SOURCE.txt", "--json"],
  () => ({ job: "stability", bicycle: { file: { name: "tests/data/SOURCE.txt", text: fs.readFileSync("tests/data/SOURCE.txt", "utf8") } } }));

const share = (t) => (t.numbers ? ((100 * t.identical) / t.numbers).toFixed(1) : "0");
console.log(
  `${tally.cases} cases, ${tally.numbers} numbers, largest relative difference ${tally.maxRelative.toExponential(2)} (tolerance ${TOL}); ` +
    `of the ${json.numbers} numbers outside the simulations (whose CSV is rounded), ${json.identical} bit for bit the same ` +
    `(${share(json)} %), largest relative difference ${json.maxRelative.toExponential(2)}`,
);
if (tally.failures.length) {
  for (const f of tally.failures) console.error(`FAILED ${f}`);
  process.exit(1);
}
