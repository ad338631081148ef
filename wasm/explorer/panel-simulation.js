// The simulation panel: a kick at a speed simulated by the module's
// nonlinear model, roll and steer over time, and an animated rear and top
// view of the bicycle drawn from its thesis geometry.
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const P = BikedynPlot;
  const { $, DEG, call, showError, fmt, sig, bicycleSpec, withModel, writeHash } = app;

  // ---- nonlinear simulation -----------------------------------------------------

  function readSimInputs() {
    const s = app.state.sim;
    const ids = { speed: "sim-speed", impulse: "sim-impulse", time: "sim-time", duration: "sim-duration", ahead: "sim-ahead", height: "sim-height", roll_rate: "sim-roll-rate" };
    for (const [k, id] of Object.entries(ids)) {
      const v = Number($(id).value);
      if ($(id).value.trim() !== "" && Number.isFinite(v)) s[k] = v;
    }
    writeHash();
  }
  function writeSimInputs() {
    const s = app.state.sim;
    const ids = { speed: "sim-speed", impulse: "sim-impulse", time: "sim-time", duration: "sim-duration", ahead: "sim-ahead", height: "sim-height", roll_rate: "sim-roll-rate" };
    for (const [k, id] of Object.entries(ids)) $(id).value = String(s[k]);
  }

  function runSim() {
    readSimInputs();
    const s = app.state.sim;
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
    app.simResult = r.ok;
    app.simResult.thesisParams = Object.fromEntries(app.current.thesis);
    const sum = r.ok.summary;
    $("sim-status").textContent = `${sum.stop}: ${r.ok.simulation.t.length} samples, model ${sum.model}, ${((performance.now() - t0) / 1000).toFixed(2)} s; largest constraint residual ${sig(sum.max_constraint_residual, 2)}`;
    $("sim-plot").innerHTML = simTracesSvg();
    $("sim-play").disabled = false;
    $("sim-t").disabled = false;
    $("sim-t").max = String(r.ok.simulation.t[r.ok.simulation.t.length - 1]);
    $("sim-t").step = "0.01";
    setSimTime(0);
    return app.simResult;
  }

  /** Coordinate `role` of every sample. */
  function roleSeries(role) {
    const sim = app.simResult.simulation;
    const j = sim.coordinates.indexOf(app.simResult.roles[role]);
    return j < 0 ? null : sim.p.map((q) => q[j]);
  }

  let simFig = null;
  function simTracesSvg(width = 760, height = 320) {
    const t = app.simResult.simulation.t;
    // Benchmark signs: roll positive to the right (theta), steer positive to the right (-gamma).
    const roll = roleSeries("roll").map((x) => x * DEG);
    const steer = roleSeries("steer").map((x) => -x * DEG);
    const all = roll.concat(steer).filter(Number.isFinite);
    const ylim = P.niceLimits(Math.min(0, ...all), Math.max(0, ...all), 6);
    const fig = P.figure({ width, height, xlim: [t[0], t[t.length - 1]], ylim, xlabel: "time t (s)", ylabel: "angle (deg)" });
    const s = app.state.sim;
    if (s.impulse && s.time >= t[0] && s.time <= t[t.length - 1]) {
      fig.add(`<line x1="${P.n(fig.x(s.time))}" y1="${P.n(fig.margin.top)}" x2="${P.n(fig.x(s.time))}" y2="${P.n(fig.margin.top + fig.ph)}" stroke="#999" stroke-dasharray="2 3"/>`);
      fig.over(`<text x="${P.n(fig.x(s.time) + 4)}" y="${P.n(fig.margin.top + fig.ph - 6)}" font-size="11" fill="#666">kick ${sig(s.impulse, 3)} N s</text>`);
    }
    fig.add(P.line(fig, t.flatMap((x, i) => [x, roll[i]]), { stroke: "#0072B2" }));
    fig.add(P.line(fig, t.flatMap((x, i) => [x, steer[i]]), { stroke: "#D55E00" }));
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
    const sim = app.simResult.simulation;
    const q = {};
    for (const [role, key] of [["rear_contact_X", "xc"], ["rear_contact_Y", "yc"], ["yaw", "phi"], ["roll", "theta"], ["pitch", "beta"], ["steer", "gamma"]]) {
      const j = sim.coordinates.indexOf(app.simResult.roles[role]);
      q[key] = j < 0 ? 0 : sim.p[i][j];
    }
    return q;
  }

  function viewSvg(g, project, xlim, ylim, extra, width = 370, height = 300) {
    const fig = P.figure({ width, height, xlim, ylim, grid: true, zeroY: false, margin: { left: 44, bottom: 34, top: 10, right: 10 }, xtickCount: 4, ytickCount: 4 });
    const pl = (pts, a) => P.line(fig, pts.flatMap(project), a);
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
    if (!app.simResult) return;
    const t = app.simResult.simulation.t;
    let i = 0;
    while (i < t.length - 1 && t[i + 1] <= time + 1e-9) i += 1;
    $("sim-t").value = String(t[i]);
    const q = simState(i);
    $("sim-t-out").textContent = `t = ${fmt(t[i], 2)} s, roll ${fmt(q.theta * DEG, 1)}\u00b0, steer ${fmt(-q.gamma * DEG, 1)}\u00b0 (right +)`;
    const th = app.simResult.thesisParams;
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
      (fig) => P.line(fig, xs.flatMap((x, k) => [x, ys[k]]), { stroke: "#aaa", "stroke-width": 1.2, "stroke-dasharray": "4 3" }));
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
    if (!app.simResult) return;
    if (playing) {
      cancelAnimationFrame(playing.frame);
      playing = null;
      $("sim-play").textContent = "play";
      return;
    }
    const t = app.simResult.simulation.t;
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

  // Used by the other files.
  Object.assign(app, { readSimInputs, writeSimInputs, runSim, simTracesSvg, setSimTime, play });
})(window.Explorer);
