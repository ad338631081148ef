// The bicycle panel: its name and warnings, the parameter table (each
// benchmark parameter editable, edits marked, each with a reset), the
// effects and controllers (grouped by effect, switched on with their
// values), the derived rows, and choosing or importing a bicycle.
// Shares the page's state through `Explorer` (explorer.js).
(function (app) {
  "use strict";
  const { $, call, showError, sig, readUnits, loadBase, schedule } = app;

  // ---- the parameter table, effects, derived rows -------------------------

  function renderBicycle() {
    $("bike-name").textContent = app.current ? app.current.name : "";
    $("bike-model").textContent = app.current ? app.current.model : "";
    const w = app.current && app.current.warnings.length ? app.current.warnings : [];
    $("warnings").hidden = !w.length;
    $("warnings").textContent = w.map((x) => `warning: ${x}`).join("\n");
    renderParams();
    renderDerived();
    renderFeedback();
    syncEffects();
  }

  // The file's [feedback] gain schedule, read only: a gain per row (its
  // name as in the file, e.g. kTdel_phid = steer torque from roll rate),
  // a knot speed per column.
  function renderFeedback() {
    const f = app.current && app.current.feedback;
    $("feedback").hidden = !f;
    const table = $("feedback-table");
    // A parameter edit leaves the file's controller as it is.
    const key = f ? JSON.stringify(f) : "";
    if (table.dataset.shown === key) return;
    table.dataset.shown = key;
    table.tHead.innerHTML = "";
    table.tBodies[0].innerHTML = "";
    if (!f) return;
    const head = document.createElement("tr");
    for (const t of ["gain", ...f.speeds.map((v) => `${sig(v, 4)} m/s`)]) {
      const th = document.createElement("th");
      th.textContent = t;
      head.appendChild(th);
    }
    table.tHead.appendChild(head);
    for (const [name, values] of f.gains) {
      const tr = document.createElement("tr");
      const td = document.createElement("td");
      td.className = "sym";
      td.textContent = name;
      tr.appendChild(td);
      for (const v of values) {
        const c = document.createElement("td");
        c.className = "num";
        c.textContent = sig(v, 5);
        tr.appendChild(c);
      }
      table.tBodies[0].appendChild(tr);
    }
  }

  function renderParams() {
    const tbody = $("params").tBodies[0];
    const values = Object.fromEntries((app.current || app.base).benchmark);
    if (tbody.dataset.bike !== bikeKey()) {
      tbody.dataset.bike = bikeKey();
      tbody.innerHTML = "";
      for (const [sym, v] of app.base.benchmark) {
        const tr = document.createElement("tr");
        const u = app.units[sym] || { unit: "", what: "" };
        tr.innerHTML = `<td class="sym"></td><td><input type="text" inputmode="decimal" spellcheck="false"><button type="button" class="reset" title="back to the bicycle's value">\u21ba</button></td><td class="unit"></td><td class="what"></td>`;
        tr.cells[0].textContent = sym;
        tr.cells[2].textContent = u.unit;
        tr.cells[3].textContent = u.what;
        const input = tr.querySelector("input");
        input.dataset.symbol = sym;
        input.value = String(sym in app.state.edits ? app.state.edits[sym] : v);
        input.addEventListener("input", () => onParamInput(sym, input));
        tr.querySelector("button").addEventListener("click", () => {
          delete app.state.edits[sym];
          input.value = String(Object.fromEntries(app.base.benchmark)[sym]);
          input.classList.remove("invalid");
          tr.classList.remove("edited");
          schedule();
        });
        tbody.appendChild(tr);
      }
    }
    for (const tr of tbody.rows) {
      const input = tr.querySelector("input");
      const sym = input.dataset.symbol;
      tr.classList.toggle("edited", sym in app.state.edits);
      // The bicycle's value where not typed in (and not being typed); a
      // row whose value is the same is left alone.
      if (!(sym in app.state.edits) && document.activeElement !== input && sym in values) {
        const v = String(values[sym]);
        if (input.value !== v) input.value = v;
      }
    }
  }

  function bikeKey() {
    return `${app.state.bike}|${app.state.file ? app.state.file.name + app.state.file.text.length : ""}|${app.base ? app.base.name : ""}`;
  }

  function onParamInput(sym, input) {
    const text = input.value.trim();
    const v = Number(text);
    if (text === "" || !Number.isFinite(v)) {
      input.classList.add("invalid");
      return;
    }
    input.classList.remove("invalid");
    const original = Object.fromEntries(app.base.benchmark)[sym];
    if (v === original) delete app.state.edits[sym];
    else app.state.edits[sym] = v;
    input.closest("tr").classList.toggle("edited", sym in app.state.edits);
    schedule();
  }

  function renderDerived() {
    const tbody = $("derived").tBodies[0];
    if (!app.current) {
      tbody.innerHTML = "";
      delete tbody.dataset.symbols;
      return;
    }
    // The rows are those of the last bicycle but for their values (a
    // parameter edit): only the values are written then.
    const rows = [];
    const row = (sym, v, unit, what, computed) => rows.push([sym, sig(v, 6), unit, what, computed]);
    const d = Object.fromEntries(app.current.derived_geometry.map((r) => [r.symbol, r.value]));
    for (const r of app.current.derived_geometry) row(r.symbol, r.value, r.unit, r.what, false);
    // Radii of gyration, k = sqrt(I / m): the definition (e.g. Moore 2012,
    // "Human control of a bicycle", and bicycleparameters' bodies), as a
    // body's inertia is often compared across bicycles. The module gives
    // the inertias and masses, not these.
    const b = Object.fromEntries(app.current.benchmark);
    const k = (I, m) => (I > 0 && m > 0 ? Math.sqrt(I / m) : NaN);
    if ("IAll" in d && "mA" in d) row("kAll", k(d.IAll, d.mA), "m", "front assembly radius of gyration about the steer axis, sqrt(IAll/mA)", true);
    const bodies = [["R", "rear wheel"], ["B", "rear frame"], ["H", "front frame"], ["F", "front wheel"]];
    for (const [body, name] of bodies) {
      for (const ax of ["xx", "yy", "zz"]) {
        const I = b[`I${body}${ax}`];
        if (I === undefined) continue;
        row(`k${body}${ax}`, k(I, b[`m${body}`]), "m", `${name} radius of gyration about ${ax[0]}, sqrt(I${body}${ax}/m${body})`, true);
      }
    }
    const symbols = rows.map((r) => r[0]).join(" ");
    if (tbody.dataset.symbols === symbols) {
      rows.forEach((r, i) => {
        const cell = tbody.rows[i].cells[1];
        if (cell.textContent !== r[1]) cell.textContent = r[1];
      });
      return;
    }
    tbody.dataset.symbols = symbols;
    tbody.innerHTML = "";
    for (const [sym, value, unit, what, computed] of rows) {
      const tr = document.createElement("tr");
      tr.innerHTML = "<td class=sym></td><td class=num></td><td class=unit></td><td class=what></td>";
      tr.cells[0].textContent = sym;
      tr.cells[1].textContent = value;
      tr.cells[2].textContent = unit;
      tr.cells[3].textContent = what + (computed ? " (computed on this page)" : "");
      if (computed) tr.classList.add("computed");
      tbody.appendChild(tr);
    }
  }

  // Effects: every effect parameter of the models, grouped by effect.
  function buildEffects(models) {
    const seen = new Set();
    app.effectParams = [];
    for (const m of models) {
      for (const p of m.parameters) {
        if (!p.effect || seen.has(p.name)) continue;
        seen.add(p.name);
        app.effectParams.push(p);
      }
    }
    const groups = [];
    for (const p of app.effectParams) {
      let g = groups.find((x) => x.effect === p.effect);
      if (!g) groups.push((g = { effect: p.effect, params: [] }));
      g.params.push(p);
    }
    const host = $("effects");
    host.innerHTML = "";
    const open = new Set(["steer_damping", "steer_friction", "steer_controller"]);
    for (const g of groups) {
      const det = document.createElement("details");
      det.className = "effect";
      det.dataset.effect = g.effect;
      if (open.has(g.effect)) det.open = true;
      const sum = document.createElement("summary");
      const cb = document.createElement("input");
      cb.type = "checkbox";
      cb.dataset.effect = g.effect;
      const lab = document.createElement("span");
      lab.textContent = ` ${g.effect.replace(/_/g, " ")}`;
      sum.append(cb, lab);
      det.appendChild(sum);
      const table = document.createElement("table");
      table.className = "params";
      for (const p of g.params) {
        const tr = document.createElement("tr");
        tr.innerHTML = "<td class=sym></td><td><input type=text inputmode=decimal spellcheck=false></td><td class=what></td>";
        tr.cells[0].textContent = p.name;
        tr.cells[2].textContent = p.doc;
        const input = tr.querySelector("input");
        input.dataset.effectParam = p.name;
        input.value = String(p.name in app.state.effects ? app.state.effects[p.name] : p.default ?? 0);
        input.addEventListener("input", () => {
          const v = Number(input.value.trim());
          const ok = input.value.trim() !== "" && Number.isFinite(v);
          input.classList.toggle("invalid", !ok);
          if (!ok) return;
          if (cb.checked) {
            app.state.effects[p.name] = v;
            schedule();
          }
        });
        table.appendChild(tr);
      }
      det.appendChild(table);
      cb.addEventListener("change", () => {
        for (const p of g.params) {
          const input = det.querySelector(`input[data-effect-param="${p.name}"]`);
          if (cb.checked) {
            const v = Number(input.value);
            app.state.effects[p.name] = Number.isFinite(v) ? v : p.default ?? 0;
          } else delete app.state.effects[p.name];
        }
        det.classList.toggle("on", cb.checked);
        schedule();
      });
      host.appendChild(det);
    }
  }

  /** Checkboxes and values from the state (after a bicycle or a link is loaded). */
  function syncEffects() {
    for (const det of $("effects").querySelectorAll("details.effect")) {
      const inputs = [...det.querySelectorAll("input[data-effect-param]")];
      const on = inputs.some((i) => i.dataset.effectParam in app.state.effects);
      det.querySelector("input[type=checkbox]").checked = on;
      det.classList.toggle("on", on);
      for (const i of inputs) {
        const k = i.dataset.effectParam;
        if (k in app.state.effects && document.activeElement !== i) i.value = String(app.state.effects[k]);
      }
    }
  }

  // ---- choosing and importing a bicycle ---------------------------------------

  /** The bicycle menu's entry of the imported file (or of the link's). */
  function fileOption() {
    const opt = $("bike").querySelector("option[value=file]");
    opt.disabled = !app.state.file;
    opt.textContent = app.state.file ? `imported: ${app.state.file.name}` : "imported file";
    $("file-name").textContent = app.state.file ? `imported ${app.state.file.name}` : "";
  }

  /** Imports a parameter file's text; the module's error (verbatim) if it cannot be read. */
  function importFile(f) {
    const r = call({ job: "bicycle", bicycle: { file: { name: f.name, text: f.text } } });
    if (r.error) {
      showError(r.error);
      return false;
    }
    app.state.file = { name: f.name, text: f.text };
    app.state.bike = "file";
    app.state.edits = {};
    app.state.effects = Object.assign({}, r.ok.effects); // the file's effects, shown switched on
    app.base = r.ok;
    app.units = readUnits(app.base.toml);
    fileOption();
    $("bike").value = "file";
    showError("");
    afterBaseChange();
    return true;
  }

  function chooseBike(value) {
    const previous = app.state.bike;
    app.state.bike = value;
    if (!loadBase()) {
      app.state.bike = previous;
      $("bike").value = previous;
      return false;
    }
    app.state.edits = {};
    app.state.effects = value === "file" ? Object.assign({}, app.base.effects) : {};
    afterBaseChange();
    return true;
  }

  function afterBaseChange() {
    $("params").tBodies[0].dataset.bike = "";
    app.writeMapInputs();
    return schedule();
  }

  // Used by the other files.
  Object.assign(app, { renderBicycle, buildEffects, fileOption, importFile, chooseBike });
})(window.Explorer);
