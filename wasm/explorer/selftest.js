// The self-test (#selftest): the page exercises itself as a user would and
// writes SELFTEST PASS or SELFTEST FAIL: reasons (wasm/tests/explorer.sh
// runs it in headless Chromium).
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const S = ExplorerState;
  const { $, call, showError, benchmarkOrder, applyState, busy } = app;

  // ---- self-test (#selftest): the page exercises itself -------------------------

  async function selftest() {
    const fails = [];
    const check = (ok, what) => {
      if (!ok) fails.push(what);
    };
    const out = $("selftest");
    // Until the debounced update has run.
    const settle = async () => {
      while (busy()) await new Promise((r) => setTimeout(r, 10));
    };
    try {
      // 0. The link's state, restored (the page was opened with it).
      const given = S.decode(location.hash);
      check(S.encode(app.state) === S.encode(given), `the state ${S.encode(app.state)} is not the link's ${S.encode(given)}`);
      check($("bike").value === given.bike, `bicycle ${$("bike").value}, the link says ${given.bike}`);
      check($("error").hidden, `the link's bicycle: ${$("error").textContent}`);
      check(app.eig && app.eig.count === S.speedRange(given).count, "the link's eigenvalues are not drawn");
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
      // A file's [feedback] controller is shown as the file gives it.
      if (given.file && given.file.text.includes("[feedback]")) {
        const shown = $("feedback-table").textContent;
        check(!$("feedback").hidden && shown.includes("kTdel_phid") && shown.includes("-12.48") && shown.includes("1.5 m/s"), `the file's controller is not shown: "${shown}"`);
      } else {
        check($("feedback").hidden, "a controller is shown for a bicycle without one");
      }
      // 1. The benchmark bicycle: Meijaard et al. (2007) give v_w = 4.292 and v_c = 6.024 m/s.
      app.state = Object.assign(S.defaults(), { selftest: true });
      await applyState();
      check($("v-weave").textContent === "4.2924", `weave speed shown ${$("v-weave").textContent}, expected 4.2924`);
      check($("v-capsize").textContent === "6.0243", `capsize speed shown ${$("v-capsize").textContent}, expected 6.0243`);
      // The figures are painted on canvases, which say what they show in
      // data attributes; their SVG downloads must show the same.
      const diagram = () => $("eig-plot").querySelector("canvas").dataset;
      const label = () => diagram().weave || "";
      const before = label();
      check(before === "v_w = 4.292", `the plot's weave label is "${before}"`);
      check(Number(diagram().lines) >= 4, "the eigenvalue plot has no lines");
      check(Number(diagram().bands) >= 1, "the eigenvalue plot has no self-stable band");
      const svg = new DOMParser().parseFromString(app.eigFigureSvg(), "image/svg+xml");
      const svgLabel = svg.querySelector('text[data-critical="weave"]');
      check(svg.querySelectorAll("polyline").length === Number(diagram().lines) && svg.querySelectorAll("rect[data-band]").length === Number(diagram().bands) && svgLabel && svgLabel.textContent === before,
        "the diagram's SVG download is not the diagram shown");
      const points = Number($("locus-plot").querySelector("canvas").dataset.points);
      check(points > 100, "the root locus has no points");
      const locus = new DOMParser().parseFromString(app.locusSvg(), "image/svg+xml");
      check([...locus.querySelectorAll("path[data-locus]")].reduce((n, p) => n + Number(p.dataset.locus), 0) === points, "the root locus's SVG download is not the root locus shown");
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
      const csv = app.eigCsv() || "";
      check(csv.startsWith("v,re_1,im_1,mode_1,roll_amp_1"), `the CSV's header: ${csv.slice(0, 40)}`);
      // 4. An invalid file: the module's message, verbatim.
      const bad = { name: "broken.txt", text: "garbage" };
      let expected = "";
      try {
        app.bd.call({ job: "bicycle", bicycle: { file: bad } });
      } catch (e) {
        expected = e.message;
      }
      check(expected.length > 0, "the invalid file was read");
      // Dropped on the page, as a user would.
      showError("");
      const dt = new DataTransfer();
      dt.items.add(new File([bad.text], bad.name, { type: "text/plain" }));
      app.importing = null;
      document.dispatchEvent(new DragEvent("drop", { dataTransfer: dt, bubbles: true, cancelable: true }));
      check(app.importing, "the drop started no import");
      await app.importing;
      check(!$("error").hidden && $("error").textContent === expected, `the error shown is "${$("error").textContent}", expected "${expected}"`);
      check($("bike").value === "benchmark", "a bad file replaced the bicycle");
      // A valid file, in TOML.
      const ok = app.importFile({ name: "mine.toml", text: app.current.toml.replace("c = 0.1 ", "c = 0.09") });
      await settle();
      check(ok && $("error").hidden, "a valid TOML file was not imported");
      check(location.hash.includes("bike=file&name=mine.toml&file="), `the link lacks the file: ${location.hash.slice(0, 80)}`);
      // The link gives the file's bicycle.
      const linked = S.decode(location.hash);
      check(linked.file && linked.file.text === app.state.file.text, "the link's file is not the file");
      const again = call({ job: "eig", bicycle: S.bicycleSpec(linked, benchmarkOrder()), speeds: S.speedRange(linked), critical_speeds: true });
      check(again.ok && again.ok.weave_speed === app.eig.weave_speed, `the link's bicycle: weave speed ${again.ok ? again.ok.weave_speed : again.error}, the file's ${app.eig.weave_speed}`);
      // 5. A small stability map.
      app.state.map = { x: "c", x0: 0.04, x1: 0.12, nx: 3, y: "lam", y0: 0.2, y1: 0.4, ny: 3, metric: "least_stable_real_part", at: 5 };
      app.writeMapInputs();
      // In the page: Chromium's virtual time, which runs this test's timers
      // at once, does not wait for a worker's answer. The workers' map is
      // checked against the page's module in real time
      // (wasm/tests/explorer_browser.py, step 11).
      const cells = await app.runMap({ inPage: true });
      check(cells && cells.length === 9, `the map has ${cells ? cells.length : 0} cells, expected 9`);
      const mapCanvas = $("map-plot").querySelector("canvas");
      check(mapCanvas && mapCanvas.dataset.cells === "9", "the map's cells are not drawn");
      const mapDownload = new DOMParser().parseFromString(app.mapSvg(), "image/svg+xml");
      check(mapDownload.querySelectorAll("rect[data-cell] > title").length === 9, "the map's SVG download lacks its 9 cells with their values");
      // 6. A kick simulation.
      const sim = app.runSim();
      check(sim && sim.summary.stop === "completed", `the simulation: ${sim ? sim.summary.stop : "failed"}`);
      check(sim && sim.simulation.t.length > 100, "the simulation has too few samples");
      check($("sim-plot").querySelectorAll("polyline").length >= 2, "no roll and steer traces");
      app.setSimTime(2);
      check($("sim-rear").querySelectorAll("polyline").length >= 4 && $("sim-top").querySelectorAll("polyline").length >= 4, "no rear and top views");
    } catch (e) {
      fails.push(`exception: ${e && e.stack ? e.stack : e}`);
    }
    out.hidden = false;
    out.textContent = fails.length ? `SELFTEST FAIL: ${fails.join("; ")}` : "SELFTEST PASS";
    document.title = out.textContent.slice(0, 60);
  }

  // Used by the other files.
  Object.assign(app, { selftest });
})(window.Explorer);
