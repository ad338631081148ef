#!/usr/bin/env python3
"""The stability explorer driven from outside, as a user would (issue 34).

Selenium 4 drives the distribution's headless Chromium through the
distribution's chromedriver (both paths given: Selenium Manager downloads
nothing) over the page served by `python3 -m http.server` on a free
localhost port, and checks what the page shows against the command line:

  1. load the page (the benchmark bicycle) until the eigenvalue plot is drawn;
  2. import tests/data/BrowserBenchmark.txt (bicycleparameters text, with +/- values) through the
     page's file input;
  3. the weave and capsize speeds shown = `bikedyn stability --json`, to the
     digits shown;
  4. type a new trail c into its field: the new speeds = the command line's
     on the same file with that trail;
  5. move the speed slider with the keyboard: the eigenvalues-at-speed table
     = `bikedyn eig --speeds V:V:1 --format json`, row by row, as the page
     formats them;
  6. simulate a kick: it completes, the traces and views are drawn, no error;
  7. download the eigenvalue CSV with the page's button: the same header
     as `bikedyn eig --format csv` and the numbers to 1e-12 relative; then
     the diagram's and the root locus's SVG: the lines, band, labels and
     points that their canvases on the page say they show;
  8. choose a garbage file: the page shows the module's message, keeps the
     bicycle, and still works (the trail reset gives the file's speeds back);
  9. screenshots after the main steps, into wasm/tests/artifacts/ (ARTIFACTS).

Run it with explorer_browser.sh (which installs Chromium, chromedriver and
Selenium when missing). Environment: CHROMIUM, CHROMEDRIVER, BIKEDYN,
ARTIFACTS. Exits 1 on a failed check (with the step and the numbers), 2 when
something it needs is missing.
"""

import base64
import csv
import io
import json
import math
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
import xml.etree.ElementTree as ET

os.environ.setdefault("SE_OFFLINE", "true")  # Selenium Manager must not download anything

try:
    from selenium import webdriver
    from selenium.common.exceptions import StaleElementReferenceException, TimeoutException, WebDriverException
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError as e:  # pragma: no cover
    print(f"explorer browser test: Selenium 4 is missing ({e}); run wasm/tests/explorer_browser.sh", file=sys.stderr)
    sys.exit(2)

TESTS = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(TESTS, "..", ".."))
EXPLORER = os.path.join(ROOT, "wasm", "explorer")
BIKE_FILE = os.path.join(ROOT, "tests", "data", "BrowserBenchmark.txt")


def file_value(path, symbol):
    """A symbol's value as the file writes it (`name = value[+/-sd]`)."""
    with open(path) as f:
        for line in f:
            name, _, value = line.partition("=")
            if name.strip() == symbol:
                return value.split("+/-")[0].strip()
    raise SystemExit(f"{path}: no `{symbol}`")


FILE_TRAIL = file_value(BIKE_FILE, "c")
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("CHROMEDRIVER", "/usr/bin/chromedriver")
BIKEDYN = os.environ.get("BIKEDYN", os.path.join(ROOT, "target", "release", "bikedyn"))
ARTIFACTS = os.path.abspath(os.environ.get("ARTIFACTS", os.path.join(TESTS, "artifacts")))

NEW_TRAIL = "0.1"  # the edit typed into the trail's field (the file's is 0.0686)
SLIDER_SPEED = "8.95"  # End, Page Down, then 5 x Left from the slider's 0..10 m/s, step 0.01
SIM_SPEED = "9"  # the kick simulation's speed (m/s): Bluenose with c = 0.1 is self-stable there
SIM_KICK = "1"  # N s (the page's default 8 N s makes this bicycle fall, as on the command line)
WAIT = 30  # seconds, the longest wait for anything on the page
CSV_RTOL = 1e-12


class Failure(Exception):
    pass


def log(text):
    print(text, flush=True)


def ok(text):
    log(f"  ok  {text}")


def check(cond, message):
    if not cond:
        raise Failure(message)


# ---- numbers as the page writes them ------------------------------------------------


def js_string(x):
    """JavaScript's String(x) of a double in [1e-6, 1e21): the shortest round trip, no `.0`."""
    if x == int(x):
        return str(int(x))
    return repr(x)


def js_exponential(x, digits):
    """x.toExponential(digits): `1.2346e-4`, `1.2346e+5`."""
    mant, exp = f"{x:.{digits}e}".split("e")
    e = int(exp)
    return f"{mant}e{'+' if e >= 0 else '-'}{abs(e)}"


def js_sig(x, s=5):
    """explorer.js's sig(): `s` significant digits."""
    if x is None or not math.isfinite(x):
        return "\u2014"
    if x == 0:
        return "0"
    a = abs(x)
    if a >= 1e5 or a < 1e-3:
        return js_exponential(x, s - 1)
    return js_string(float(f"{x:.{s - 1}e}"))


def js_fixed(x, d=4):
    """explorer.js's fmt(): `d` decimals."""
    if x is None or not math.isfinite(x):
        return "\u2014"
    return f"{x:.{d}f}"


def table_row(mode, re_, im):
    """A row of the eigenvalues-at-speed table as panel-eigen.js's renderEigTable writes it."""
    f = abs(im) / (2 * math.pi)
    return [
        mode,
        js_sig(re_, 5),
        js_sig(im, 5),
        js_sig(f, 4) if im else "\u2014",
        js_sig(1 / f, 4) if im else "\u2014",
        f"{js_sig(1 / abs(re_), 4)} {'(growth)' if re_ > 0 else '(decay)'}" if re_ else "\u2014",
    ]


# ---- the command line -------------------------------------------------------------------


def cli(*args, cwd=None):
    r = subprocess.run([BIKEDYN, *args], capture_output=True, text=True, cwd=cwd, timeout=60)
    if r.returncode != 0:
        raise Failure(f"`bikedyn {' '.join(args)}` failed ({r.returncode}): {r.stderr.strip()}")
    return r.stdout


def cli_json(*args):
    return json.loads(cli(*args))


def cli_error(*args, cwd=None):
    """The message of a command that must fail."""
    r = subprocess.run([BIKEDYN, *args], capture_output=True, text=True, cwd=cwd, timeout=60)
    if r.returncode == 0:
        raise Failure(f"`bikedyn {' '.join(args)}` did not fail")
    return r.stderr.strip()


# ---- the page -------------------------------------------------------------------------------


class Page:
    def __init__(self, driver, url, shots):
        self.d = driver
        self.url = url
        self.shots = shots

    def js(self, script, *args):
        return self.d.execute_script(script, *args)

    def el(self, css):
        return self.d.find_element(By.CSS_SELECTOR, css)

    def text(self, elem_id):
        return self.js("const e = document.getElementById(arguments[0]); return e ? e.textContent : null;", elem_id)

    def error(self):
        """The page's error box: its text if shown, else None."""
        return self.js("const e = document.getElementById('error'); return e.hidden ? null : e.textContent;")

    def wait(self, cond, what, timeout=WAIT):
        def probe(_):
            try:
                return cond()
            except StaleElementReferenceException:
                return False

        try:
            return WebDriverWait(self.d, timeout, poll_frequency=0.05).until(probe)
        except TimeoutException:
            err = self.error()
            raise Failure(f"timed out after {timeout} s waiting for {what} (status: {self.text('status')!r}"
                          f"{'; error shown: ' + repr(err) if err else ''})") from None

    def settled(self):
        s = self.text("status") or ""
        return not s.startswith("loading") and "computing" not in s

    @staticmethod
    def stale(elem):
        try:
            elem.is_enabled()
            return False
        except StaleElementReferenceException:
            return True

    def wait_redraw(self, old_weave, what, extra=lambda: True):
        """Until the update after a change has run: the critical speeds redrawn (the old element gone), settled."""
        self.wait(lambda: self.stale(old_weave) and self.settled() and extra(), f"the page to redraw after {what}")

    def hash(self):
        return self.js("return decodeURIComponent(location.hash);")

    def screenshot(self, name):
        """The whole page (beyond the window) as a PNG in the artifacts folder."""
        path = os.path.join(ARTIFACTS, f"{name}.png")
        w, h = self.js("const e = document.documentElement; return [Math.max(e.scrollWidth, e.clientWidth), Math.max(e.scrollHeight, e.clientHeight)];")
        try:
            r = self.d.execute_cdp_cmd("Page.captureScreenshot", {
                "format": "png", "captureBeyondViewport": True,
                "clip": {"x": 0, "y": 0, "width": w, "height": h, "scale": 1},
            })
            with open(path, "wb") as f:
                f.write(base64.b64decode(r["data"]))
        except WebDriverException:
            self.d.save_screenshot(path)
        self.shots.append(path)
        return path


# ---- the steps ------------------------------------------------------------------------------


def canvas_data(p, elem_id):
    """What a figure's canvas says it shows (its data attributes: a canvas keeps no elements)."""
    return p.js("const c = document.querySelector(`#${arguments[0]} canvas`); return c ? Object.assign({}, c.dataset) : {};", elem_id)


def diagram_lines(p):
    return int(canvas_data(p, "eig-plot").get("lines", 0))


def step_load(p):
    """1. The page, the benchmark bicycle, the eigenvalue plot drawn."""
    p.d.get(p.url)
    p.wait(lambda: diagram_lines(p) >= 4 and p.settled() and p.text("v-weave"), "the eigenvalue plot of the benchmark bicycle")
    check(p.error() is None, f"the page shows an error after loading: {p.error()!r}")
    check(p.el("#bike").get_attribute("value") == "benchmark", "the page did not open on the benchmark bicycle")
    n = diagram_lines(p)
    ok(f"page loaded ({p.text('status')}); eigenvalue plot drawn with {n} lines")
    ref = cli_json("stability", "--bike", "benchmark", "--json")
    for elem_id, key in (("v-weave", "weave_speed"), ("v-capsize", "capsize_speed")):
        shown, want = p.text(elem_id), js_fixed(ref[key])
        check(shown == want, f"benchmark {key}: page shows {shown}, `bikedyn stability --bike benchmark` gives {ref[key]} ({want})")
    ok(f"benchmark weave {p.text('v-weave')} and capsize {p.text('v-capsize')} m/s = the CLI's "
       f"{ref['weave_speed']:.10g} and {ref['capsize_speed']:.10g}")
    p.screenshot("01-loaded-benchmark")


def step_import(p):
    """2. A real parameter file, through the page's file input."""
    old = p.el("#v-weave")
    p.el("#file").send_keys(BIKE_FILE)
    name = os.path.basename(BIKE_FILE)
    p.wait_redraw(old, f"importing {name}", lambda: p.el("#bike").get_attribute("value") == "file")
    check(p.error() is None, f"importing {name}: the page shows an error: {p.error()!r}")
    check(p.text("file-name") == f"imported {name}", f"the page says {p.text('file-name')!r} after importing {name}")
    check("bike=file" in p.hash() and f"name={name}" in p.hash(), f"the link does not carry the file: {p.hash()[:80]}")
    c = p.el('input[data-symbol="c"]').get_attribute("value")
    check(c == FILE_TRAIL, f"the trail in the parameter table is {c}, the file's is {FILE_TRAIL}")
    ok(f"imported {name}: bicycle {p.text('bike-name')!r}, model {p.text('bike-model')}, trail c = {c} in the table")
    p.screenshot("02-imported-file")


def step_file_speeds(p):
    """3. The weave and capsize speeds shown, against the command line."""
    ref = cli_json("stability", "--bike", BIKE_FILE, "--json")
    check(p.text("bike-model") == ref["model"], f"model: page {p.text('bike-model')}, CLI {ref['model']}")
    for elem_id, key in (("v-weave", "weave_speed"), ("v-capsize", "capsize_speed"), ("v-merge", "weave_real_pair_merge_speed")):
        shown, want = p.text(elem_id), js_fixed(ref[key])
        check(shown == want, f"{key} of {os.path.basename(BIKE_FILE)}: page shows {shown}, "
                             f"`bikedyn stability --bike {BIKE_FILE} --json` gives {ref[key]} ({want})")
        ok(f"{key}: page {shown} m/s = CLI {ref[key]!r}")
    return ref


def edited_file(tmp):
    """The same file with the new trail (as a user would edit it), for the command line."""
    with open(BIKE_FILE, newline="") as f:
        text = f.read()
    new, n = re.subn(r"(?m)^c\s*=\s*[^\r\n]*", f"c = {NEW_TRAIL}", text)
    check(n == 1, f"the trail line of {BIKE_FILE} not found once ({n})")
    path = os.path.join(tmp, os.path.basename(BIKE_FILE).replace(".txt", f"-c{NEW_TRAIL}.txt"))
    with open(path, "w", newline="") as f:
        f.write(new)
    return path


def step_edit(p, edited):
    """4. Type a new trail into its field; the new speeds against the command line."""
    field = p.el('input[data-symbol="c"]')
    old = p.el("#v-weave")
    before = p.text("v-weave")
    field.click()
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(NEW_TRAIL)
    p.wait_redraw(old, f"typing c = {NEW_TRAIL}", lambda: re.search(rf"set=c:{re.escape(NEW_TRAIL)}(&|,|$)", p.hash()))
    check(p.error() is None, f"after the edit the page shows an error: {p.error()!r}")
    edited_row = p.js("return document.querySelector('input[data-symbol=\"c\"]').closest('tr').classList.contains('edited')")
    check(edited_row, "the trail's row is not marked as edited")
    ref = cli_json("stability", "--bike", edited, "--json")
    sweep = cli_json("sweep", "--bike", BIKE_FILE, "--param", "c", "--values", f"{NEW_TRAIL}:{NEW_TRAIL}:1", "--json")["points"][0]
    check(sweep["weave_speed"] == ref["weave_speed"],
          f"the CLI disagrees with itself: sweep {sweep['weave_speed']}, edited file {ref['weave_speed']}")
    for elem_id, key in (("v-weave", "weave_speed"), ("v-capsize", "capsize_speed")):
        shown, want = p.text(elem_id), js_fixed(ref[key])
        check(shown == want, f"{key} with c = {NEW_TRAIL}: page shows {shown}, `bikedyn stability` on the edited file "
                             f"gives {ref[key]} ({want})")
    check(p.text("v-weave") != before, f"the weave speed did not change with the trail ({before})")
    ok(f"typed c = {NEW_TRAIL}: weave {before} -> {p.text('v-weave')} m/s, capsize {p.text('v-capsize')} m/s = CLI "
       f"{ref['weave_speed']!r} and {ref['capsize_speed']!r} (edited file; `sweep --param c` the same)")
    p.screenshot("03-edited-trail")
    return ref


def step_slider(p, edited):
    """5. The slider moved with the keyboard; the table at that speed against the command line."""
    slider = p.el("#speed")
    slider.send_keys(Keys.END)
    slider.send_keys(Keys.PAGE_DOWN)
    for _ in range(5):
        slider.send_keys(Keys.ARROW_LEFT)
    p.wait(lambda: p.text("speed-out") == f"{float(SLIDER_SPEED):.2f} m/s", f"the speed shown to follow the slider to {SLIDER_SPEED}")
    value = slider.get_attribute("value")
    check(value == SLIDER_SPEED, f"the slider is at {value} after End, Page Down and 5 x Left; expected {SLIDER_SPEED}")
    check(p.el("#speed-num").get_attribute("value") == SLIDER_SPEED, "the speed field does not follow the slider")
    rows = p.js("return [...document.querySelectorAll('#eig-table tbody tr')].map((tr) => [...tr.cells].map((c) => c.textContent));")
    ref = cli_json("eig", "--bike", edited, "--speeds", f"{SLIDER_SPEED}:{SLIDER_SPEED}:1", "--format", "json")[0]
    check(abs(ref["v"] - float(SLIDER_SPEED)) < 1e-12, f"the CLI's speed {ref['v']}")
    want = [table_row(m, re_, im) for m, (re_, im) in zip(ref["modes"], ref["eigenvalues"])]
    want += [table_row("tyre state", re_, im) for re_, im in ref.get("extra_eigenvalues") or []]
    check(len(rows) == len(want), f"the table at {SLIDER_SPEED} m/s has {len(rows)} rows, the CLI {len(want)} eigenvalues")
    for k, (got, exp) in enumerate(zip(rows, want)):
        check(got == exp, f"row {k + 1} of the table at {SLIDER_SPEED} m/s: page {got}, from `bikedyn eig --speeds "
                          f"{SLIDER_SPEED}:{SLIDER_SPEED}:1` {exp} (eigenvalue {ref['eigenvalues'][k]})")
        ok(f"table row {k + 1} at {SLIDER_SPEED} m/s: {' | '.join(got)}  (CLI {ref['eigenvalues'][k][0]!r} "
           f"{'+-' if ref['eigenvalues'][k][1] else '+'} {abs(ref['eigenvalues'][k][1])!r}i)")
    check(f"at={SLIDER_SPEED}" in p.hash(), f"the link lacks the slider's speed: {p.hash()[:120]}")
    p.screenshot("04-slider")


def type_into(p, css, text):
    """Select a field's text and type over it, then Tab away (its change event)."""
    field = p.el(css)
    field.click()
    field.send_keys(Keys.CONTROL, "a")
    field.send_keys(text, Keys.TAB)


def step_simulate(p, edited, tmp):
    """6. A kick simulation with the page's controls; it completes as the command line's does."""
    type_into(p, "#sim-speed", SIM_SPEED)
    type_into(p, "#sim-impulse", SIM_KICK)
    p.wait(lambda: f"sim=speed:{SIM_SPEED},impulse:{SIM_KICK}," in p.hash(), f"the simulation's speed {SIM_SPEED} and kick {SIM_KICK} in the link")
    t0 = time.monotonic()
    p.el("#sim-run").click()
    p.wait(lambda: (p.text("sim-status") or "").split(":")[0] not in ("", "simulating\u2026"), "the simulation to finish", timeout=60)
    status = p.text("sim-status")
    check(status.startswith("completed:"), f"the simulation did not complete: {status!r}; error: {p.error()!r}")
    check(p.error() is None, f"the simulation shows an error: {p.error()!r}")
    counts = p.js("return ['sim-plot', 'sim-rear', 'sim-top'].map((id) => document.querySelectorAll(`#${id} svg polyline`).length);")
    check(counts[0] >= 2, f"the simulation's roll and steer traces are not drawn ({counts[0]} lines)")
    check(counts[1] >= 4 and counts[2] >= 4, f"the rear and top views are not drawn ({counts[1]}, {counts[2]} lines)")
    check(p.el("#sim-play").is_enabled(), "the play button stays disabled after the simulation")
    samples = int(re.search(r"(\d+) samples", status).group(1))
    ok(f"kick simulation ({time.monotonic() - t0:.1f} s): {status}; traces {counts[0]} lines, "
       f"rear view {counts[1]}, top view {counts[2]}")
    # The same run on the command line, with the page's settings.
    v = {k: p.el(f"#sim-{k}").get_attribute("value") for k in ("speed", "impulse", "time", "ahead", "height", "roll-rate", "duration")}
    out = os.path.join(tmp, "kick.csv")
    cli("simulate", "--bike", edited, "--speed", v["speed"], "--duration", v["duration"], "--roll-rate", v["roll-rate"],
        "--kick", f"{v['time']}:{v['impulse']}:{v['ahead']}:{v['height']}", "--dt", "0.01", "--out", out)
    with open(out, newline="") as f:
        rows = list(csv.DictReader(f))
    check(samples == len(rows), f"the page's simulation has {samples} samples, `bikedyn simulate` {len(rows)}")
    # Scrub the animation's time slider to the end, as a user would: the angles shown there against the CLI's last row.
    p.el("#sim-t").send_keys(Keys.END)
    last = rows[-1]
    want = (f"t = {float(last['t']):.2f} s, roll {math.degrees(float(last['theta'])):.1f}\u00b0, "
            f"steer {math.degrees(-float(last['gamma'])):.1f}\u00b0 (right +)")
    p.wait(lambda: p.text("sim-t-out") == want, f"the views at the end of the simulation to show {want!r} (shown: {p.text('sim-t-out')!r})")
    ok(f"= `bikedyn simulate --speed {v['speed']} --kick {v['time']}:{v['impulse']}:{v['ahead']}:{v['height']} "
       f"--duration {v['duration']}`: {len(rows)} samples; at the end the page shows {p.text('sim-t-out')!r} "
       f"(CLI roll {float(last['theta'])!r} rad, steer {float(last['gamma'])!r} rad)")
    p.screenshot("05-simulation")


def parse_csv(text):
    return list(csv.reader(io.StringIO(text)))


def step_csv(p, edited, downloads):
    """7. The eigenvalue CSV downloaded with the page's button, against the command line; then the figures' SVG."""
    name, got = download(p, downloads, "#dl-csv", ".csv")
    vmin, vmax, vstep = (p.el(f"#{i}").get_attribute("value") for i in ("vmin", "vmax", "vstep"))
    speeds = f"{vmin}:{vmax}:{vstep}"
    want = cli("eig", "--bike", edited, "--speeds", speeds, "--format", "csv")
    g, w = parse_csv(got), parse_csv(want)
    check(g and w and g[0] == w[0], f"the CSV's header: page {g[0][:8] if g else None}..., CLI {w[0][:8]}...")
    check(len(g) == len(w), f"the CSV has {len(g) - 1} rows, `bikedyn eig --speeds {speeds} --format csv` {len(w) - 1}")
    worst, where, numbers = 0.0, None, 0
    for i, (rg, rw) in enumerate(zip(g[1:], w[1:]), start=2):
        check(len(rg) == len(rw), f"CSV line {i}: {len(rg)} fields, the CLI's {len(rw)}")
        for j, (a, b) in enumerate(zip(rg, rw)):
            try:
                x, y = float(a), float(b)
            except ValueError:
                check(a == b, f"CSV line {i}, column {g[0][j]}: page {a!r}, CLI {b!r}")
                continue
            numbers += 1
            if x == y:
                continue
            rel = abs(x - y) / max(abs(x), abs(y))
            if rel > worst:
                worst, where = rel, (i, g[0][j], a, b)
    check(worst <= CSV_RTOL, f"CSV line {where[0] if where else '?'}, column {where[1] if where else '?'}: page {where[2] if where else ''}, "
                             f"CLI {where[3] if where else ''}: relative difference {worst:.3g} > {CSV_RTOL}")
    ok(f"downloaded {name}: {len(g) - 1} speeds ({speeds}) x {len(g[0])} columns, header = CLI's, {numbers} numbers "
       f"within {CSV_RTOL} relative of `bikedyn eig --format csv` (largest difference {worst:.3g})")
    step_figure_downloads(p, downloads)


def download(p, downloads, button, ext):
    """The file that a download button saves (the folder emptied first): its name and text."""
    for f in os.listdir(downloads):
        os.remove(os.path.join(downloads, f))
    p.el(button).click()

    def done():
        files = os.listdir(downloads)
        found = [f for f in files if f.endswith(ext)]
        return found[0] if found and not any(f.endswith(".crdownload") for f in files) else None

    name = p.wait(done, f"the download of {button} in {downloads}")
    time.sleep(0.2)
    with open(os.path.join(downloads, name), encoding="utf-8") as f:
        text = f.read()
    keep = os.path.join(ARTIFACTS, "downloaded-" + name)
    shutil.copyfile(os.path.join(downloads, name), keep)
    p.shots.append(keep)
    return name, text


def step_figure_downloads(p, downloads):
    """The diagram's and the root locus's SVG downloads: what their canvases show on the page."""
    svg = "{http://www.w3.org/2000/svg}"
    shown = canvas_data(p, "eig-plot")
    name, text = download(p, downloads, "#dl-eig-svg", ".svg")
    root = ET.fromstring(text)
    lines = len(root.findall(f".//{svg}polyline"))
    labels = {t.get("data-critical"): t.text for t in root.iter(f"{svg}text") if t.get("data-critical")}
    bands = len([r for r in root.iter(f"{svg}rect") if r.get("data-band")])
    check(lines == int(shown["lines"]), f"{name}: {lines} lines, the page's diagram {shown['lines']}")
    check(bands == int(shown["bands"]), f"{name}: {bands} self-stable bands, the page's diagram {shown['bands']}")
    for what in ("weave", "capsize", "merge"):
        check(labels.get(what) == shown.get(what), f"{name}: the {what} label {labels.get(what)!r}, the page's {shown.get(what)!r}")
    ok(f"downloaded {name}: {lines} lines, {bands} self-stable band(s), labels {', '.join(labels.values())}: the page's diagram")
    points = int(canvas_data(p, "locus-plot")["points"])
    name, text = download(p, downloads, "#dl-locus-svg", ".svg")
    dots = sum(int(e.get("data-locus")) for e in ET.fromstring(text).iter(f"{svg}path") if e.get("data-locus"))
    check(dots == points, f"{name}: {dots} points, the page's root locus {points}")
    # The canvas's dots painted, not only counted: the pixels of a colour in
    # its plot area (where the axes, grid and text are grey, and the colour
    # bar is not), at least one per point.
    coloured = p.js("""
        const c = document.querySelector('#locus-plot canvas');
        const s = c.width / parseFloat(c.style.width);
        const [x, y, w, h] = c.dataset.plotArea.split(',').map((v) => Math.round(Number(v) * s));
        const px = c.getContext('2d').getImageData(x, y, w, h).data;
        let n = 0;
        for (let k = 0; k < px.length; k += 4) {
          if (Math.max(px[k], px[k + 1], px[k + 2]) - Math.min(px[k], px[k + 1], px[k + 2]) > 48) n += 1;
        }
        return n;""")
    check(coloured >= points, f"the root locus's canvas has {coloured} coloured pixels in its plot area for {points} points: "
          "its dots are not painted")
    ok(f"downloaded {name}: {dots} points, the page's root locus (its canvas: {coloured} coloured pixels in the plot area)")


def module_message(p, name, text):
    """The module's own message for a file, from a second instance of the module loaded in the page."""
    return p.d.execute_async_script("""
        const [name, text, done] = arguments;
        (async () => {
          const bd = await Bikedyn.load(await fetch('bikedyn.wasm'));
          try { bd.call({job: 'bicycle', bicycle: {file: {name, text}}}); done('(no error)'); }
          catch (e) { done(e.message); }
        })().catch((e) => done('(could not load the module: ' + e.message + ')'));
    """, name, text)


def step_bad_file(p, tmp, file_ref):
    """8. A garbage file: the module's message in the page; the bicycle kept and still working."""
    bad = os.path.join(tmp, "broken.txt")
    text = "this is not a bicycle\nwheels = round\n"
    with open(bad, "w") as f:
        f.write(text)
    expected = module_message(p, "broken.txt", text)
    cli_says = cli_error("stability", "--bike", "broken.txt", cwd=tmp)
    weave_before, capsize_before = p.text("v-weave"), p.text("v-capsize")
    p.el("#file").send_keys(bad)
    p.wait(lambda: p.error() is not None, "the page to show the bad file's error")
    shown = p.error()
    check(shown == expected, f"the error shown is {shown!r}; the module says {expected!r}")
    check(shown in cli_says, f"the page's error {shown!r} is not the command line's {cli_says!r}")
    ok(f"bad file: the page shows the module's message {shown!r} (the CLI: {cli_says!r})")
    check(p.el("#bike").get_attribute("value") == "file", "the bad file changed the bicycle menu")
    check(p.text("file-name") == f"imported {os.path.basename(BIKE_FILE)}", f"the bad file replaced the import: {p.text('file-name')!r}")
    check(p.text("v-weave") == weave_before and p.text("v-capsize") == capsize_before,
          f"the speeds changed with the bad file: {weave_before} -> {p.text('v-weave')}")
    check(f"set=c:{NEW_TRAIL}" in p.hash() and "name=BrowserBenchmark.txt" in p.hash(), f"the link lost the bicycle: {p.hash()[:120]}")
    ok(f"after the bad file: still {p.text('file-name')!r}, weave {p.text('v-weave')} and capsize {p.text('v-capsize')} m/s unchanged")
    p.screenshot("06-bad-file")
    # The previous bicycle still works: the trail's reset button gives the file's own speeds back.
    old = p.el("#v-weave")
    p.el('input[data-symbol="c"]').find_element(By.XPATH, "./following-sibling::button").click()
    p.wait_redraw(old, "resetting the trail")
    check(p.error() is None, f"the error stays shown after a good update: {p.error()!r}")
    c = p.el('input[data-symbol="c"]').get_attribute("value")
    check(c == FILE_TRAIL, f"the trail after its reset is {c}, the file's is {FILE_TRAIL}")
    for elem_id, key in (("v-weave", "weave_speed"), ("v-capsize", "capsize_speed")):
        shown, want = p.text(elem_id), js_fixed(file_ref[key])
        check(shown == want, f"{key} after the reset: page {shown}, CLI {file_ref[key]} ({want})")
    ok(f"then the trail reset to {c}: weave {p.text('v-weave')} and capsize {p.text('v-capsize')} m/s, the file's again; error cleared")
    p.screenshot("07-after-reset")


def step_redraw_time(p):
    """10. The redraw's time after a parameter change on 1,001 speeds (issue 34's figure: printed, not checked)."""
    type_into(p, "#vstep", "0.01")
    p.wait(lambda: "1001 speeds" in (p.text("status") or "") and p.settled(), "the page to redraw on 1,001 speeds")
    field = p.el('input[data-symbol="c"]')
    diagram, whole = [], []
    for k in range(11):
        old = p.el("#v-weave")
        field.click()
        field.send_keys(Keys.CONTROL, "a")
        field.send_keys(f"0.{k + 70}")
        p.wait_redraw(old, f"typing c = 0.{k + 70}")
        d, w = p.js("return [window.Explorer.redrawMs, window.Explorer.updateMs];")
        diagram.append(d)
        whole.append(w)

    def spread(t):
        t = sorted(t)
        return f"{t[len(t) // 2]:.1f} ms median of {len(t)} (fastest {t[0]:.1f}, slowest {t[-1]:.1f})"

    ok(f"redraw after a parameter change, 1,001 speeds: the diagram (the module's one answer and the eigenvalue "
       f"diagram painted on its canvas, before the browser's layout and paint) {spread(diagram)} [issue 34's target: < 5 ms]; "
       f"the whole update (also the tables, the critical speeds' text, the slider's mode shapes, the root locus "
       f"and the link) {spread(whole)}")
    # Where the diagram's time goes, in the page: the module's answer to
    # the same request alone (a new trail each time, as typed) and the
    # diagram drawn again from the last answer alone, 21 times each.
    answer, drawing = p.js("""
        const app = window.Explorer, S = window.ExplorerState, answer = [], drawing = [];
        const spec = app.bicycleSpec();
        for (let k = 0; k < 21; k++) {
          const set = (spec.set || []).filter(([s]) => s !== "c").concat([["c", 0.07 + 0.0001 * k]]);
          const req = app.withModel({ job: "explore", bicycle: Object.assign({}, spec, { set }), speeds: S.speedRange(app.state),
            speed_min: app.state.vmin, speed_max: app.state.vmax, speed: app.state.speed });
          const t = performance.now();
          app.call(req);
          answer.push(performance.now() - t);
        }
        for (let k = 0; k < 21; k++) {
          const t = performance.now();
          app.drawDiagram();
          drawing.push(performance.now() - t);
        }
        return [answer, drawing];""")
    ok(f"of the diagram's redraw, in the page: the module's answer alone {spread(answer)}; the diagram drawn alone {spread(drawing)}")


def map_rows_agree(p, rows):
    """The map's cells of `rows`, computed in the page's workers, against the page's own module (bit for bit)."""
    workers, why = p.js("return [window.Explorer.mapWorkerCount, window.Explorer.mapWorkersError || ''];")
    check(workers and workers > 0, f"the map was computed in the page, not in Web Workers ({why or 'no reason given'})")
    differ = p.js("""
        const app = window.Explorer, res = app.mapResult, m = res.map;
        const differ = [];
        for (const i of arguments[0]) {
          const own = app.call(app.withModel({ job: 'map_row', bicycle: app.bicycleSpec(), parameter: { symbol: m.x, values: res.xs },
            second: { symbol: m.y, values: res.ys }, row: i, speed_max: app.state.vmax, at_speed: m.at }));
          // The page numbers a cell's row itself (`i`; the module's answer for one row says 0).
          const theirs = JSON.stringify(res.cells.filter((c) => c.i === i));
          const mine = own.ok ? JSON.stringify(own.ok.cells.map((c) => Object.assign(c, { i }))) : own.error;
          if (mine !== theirs) {
            let k = 0;
            while (k < mine.length && mine[k] === theirs[k]) k += 1;
            differ.push(`row ${i}: the module's ...${mine.slice(Math.max(0, k - 60), k + 60)}... the workers' ...${theirs.slice(Math.max(0, k - 60), k + 60)}...`);
          }
        }
        return differ;""", rows)
    check(not differ, "the workers' map differs from the page's module: " + "; ".join(differ))
    return workers


def step_map_time(p):
    """11. A 100 x 100 stability map's time in the page (issue 34's figure: printed, not checked), computed in workers."""
    type_into(p, "#map-nx", "100")
    type_into(p, "#map-ny", "100")
    p.el("#map-run").click()
    p.wait(lambda: " points in " in (p.text("map-status") or ""), "the 100 x 100 map", timeout=120)
    status = p.text("map-status")
    check(status.startswith("100 \u00d7 100 points"), f"the map is not 100 x 100: {status!r}")
    cells = p.js("return window.Explorer.mapResult.cells.length;")
    check(cells == 10000, f"the map has {cells} cells, not 10,000")
    workers = map_rows_agree(p, [0, 37, 99])
    ok(f"stability map in the page, rows computed in {workers} Web Workers and drawn as they come: {status} "
       f"[issue 34's target: < 2 s]; rows 0, 37 and 99 bit for bit the page's own module")


def step_map_as_file(p):
    """12. The page opened as a file (file://) computes its map in workers too."""
    p.d.get("file://" + os.path.join(EXPLORER, "index.html") + "#map=c:0.02:0.12:6:lam:0.2:0.5:5:least_stable_real_part:5")
    p.wait(lambda: p.settled() and p.text("v-weave") not in (None, "", "\u2014"), "the page opened as a file to load")
    p.el("#map-run").click()
    p.wait(lambda: " points in " in (p.text("map-status") or ""), "the map of the page opened as a file", timeout=60)
    workers = map_rows_agree(p, [0, 3, 5])
    ok(f"the page opened as a file: its {p.text('map-status')} computed in {workers} Web Workers, "
       f"bit for bit the page's own module")


def step_console(p):
    """No script errors in the browser's console."""
    try:
        entries = p.d.get_log("browser")
    except WebDriverException:
        log("  (the browser's console log is not available)")
        return
    severe = [e["message"] for e in entries if e.get("level") == "SEVERE" and "favicon.ico" not in e.get("message", "")]
    check(not severe, "errors in the browser's console:\n    " + "\n    ".join(severe))
    others = [f"{e.get('level')}: {e.get('message')}" for e in entries if e["message"] not in severe]
    ok(f"no errors in the browser's console ({len(entries)} entries{': ' if others else ''}{'; '.join(others)[:300]})")


# ---- running it -------------------------------------------------------------------------------


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def serve(tmp):
    port = free_port()
    logf = open(os.path.join(tmp, "server.log"), "w")
    proc = subprocess.Popen([sys.executable, "-m", "http.server", str(port), "--bind", "127.0.0.1", "--directory", EXPLORER],
                            stdout=logf, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}/index.html"
    for _ in range(100):
        try:
            urllib.request.urlopen(url, timeout=1).read()
            return proc, url
        except OSError:
            if proc.poll() is not None:
                break
            time.sleep(0.05)
    proc.kill()
    raise Failure(f"the server on port {port} did not answer (see {tmp}/server.log)")


def browser(tmp, downloads):
    opts = Options()
    opts.binary_location = CHROMIUM
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1400,1000",
              f"--user-data-dir={tmp}/profile", "--no-first-run", "--no-default-browser-check"):
        opts.add_argument(a)
    opts.add_experimental_option("prefs", {
        "download.default_directory": downloads,
        "download.prompt_for_download": False,
        "download.directory_upgrade": True,
        "safebrowsing.enabled": True,
    })
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    service = Service(executable_path=CHROMEDRIVER, log_output=os.path.join(tmp, "chromedriver.log"))
    return webdriver.Chrome(service=service, options=opts)


def main():
    for path, what in ((CHROMIUM, "Chromium (CHROMIUM)"), (CHROMEDRIVER, "chromedriver (CHROMEDRIVER)"),
                       (BIKEDYN, "the command line (BIKEDYN; cargo build --release)"), (BIKE_FILE, "the parameter file"),
                       (os.path.join(EXPLORER, "bikedyn.wasm"), "the module (bash wasm/build.sh)")):
        if not os.path.exists(path):
            print(f"explorer browser test: {what} is missing: {path}", file=sys.stderr)
            return 2
    os.makedirs(ARTIFACTS, exist_ok=True)
    for f in os.listdir(ARTIFACTS):  # this test's own files of an earlier run
        if re.match(r"^\d\d-.*\.png$|^downloaded-.*\.(csv|svg)$|^FAILED-.*\.png$", f):
            os.remove(os.path.join(ARTIFACTS, f))
    t_start = time.monotonic()
    tmp = tempfile.mkdtemp(prefix="explorer-browser-")
    downloads = os.path.join(tmp, "downloads")
    os.makedirs(downloads)
    shots = []
    server = driver = None
    step = "starting"
    status = 0
    try:
        server, url = serve(tmp)
        driver = browser(tmp, downloads)
        caps = driver.capabilities
        log(f"explorer browser test: {caps.get('browserName')} {caps.get('browserVersion')} ({CHROMIUM}), "
            f"chromedriver {caps.get('chrome', {}).get('chromedriverVersion', '?').split(' ')[0]} ({CHROMEDRIVER}), {url}")
        p = Page(driver, url, shots)
        edited = edited_file(tmp)
        state = {}
        steps = [
            ("1 load the page", lambda: step_load(p)),
            ("2 import a parameter file", lambda: step_import(p)),
            ("3 weave and capsize speeds against the CLI", lambda: state.update(file_ref=step_file_speeds(p))),
            ("4 edit the trail", lambda: step_edit(p, edited)),
            ("5 move the speed slider", lambda: step_slider(p, edited)),
            ("6 simulate a kick", lambda: step_simulate(p, edited, tmp)),
            ("7 download the eigenvalue CSV and the figures' SVG", lambda: step_csv(p, edited, downloads)),
            ("8 a bad file", lambda: step_bad_file(p, tmp, state["file_ref"])),
            ("9 the browser's console", lambda: step_console(p)),
            ("10 the redraw's time", lambda: step_redraw_time(p)),
            ("11 the map's time", lambda: step_map_time(p)),
            ("12 the map in a page opened as a file", lambda: step_map_as_file(p)),
        ]
        for step, run in steps:
            t0 = time.monotonic()
            log(f"step {step}")
            run()
            log(f"      ({time.monotonic() - t0:.1f} s)")
    except Failure as e:
        status = 1
        log(f"explorer browser test: FAIL at step {step}: {e}")
    except (WebDriverException, OSError) as e:
        status = 1
        log(f"explorer browser test: FAIL at step {step}: {type(e).__name__}: {str(e).strip().splitlines()[0] if str(e).strip() else e!r}")
        for name in ("chromedriver.log", "server.log"):
            path = os.path.join(tmp, name)
            if os.path.exists(path):
                with open(path, errors="replace") as f:
                    tail = f.read().splitlines()[-15:]
                log(f"  {name} (last lines):\n    " + "\n    ".join(tail))
    finally:
        if driver is not None:
            if status:
                try:
                    Page(driver, None, shots).screenshot(f"FAILED-{step.split(' ')[0]}")
                except Exception:  # noqa: BLE001 - the failure is reported already
                    pass
            driver.quit()
        if server is not None:
            server.terminate()
            server.wait(5)
        shutil.rmtree(tmp, ignore_errors=True)
    log(f"artifacts ({ARTIFACTS}):")
    for s in shots:
        log(f"  {s}")
    elapsed = time.monotonic() - t_start
    if status == 0:
        log(f"explorer browser test: PASS ({elapsed:.1f} s)")
    else:
        log(f"explorer browser test: FAILED ({elapsed:.1f} s)")
    return status


if __name__ == "__main__":
    sys.exit(main())
