#!/usr/bin/env python3
"""Score `bikedyn identify` on sets it did not make.

The sets come from ../shared/oracle-sim (sympy.physics.mechanics equations,
SciPy integration, its own IMU, reed-switch and clock models; no code shared
with bikedyn). For every row of `matrix.toml` the set is generated (once;
kept under --work), `bikedyn identify` runs on its data folder, and the
outcome is scored against the truth the oracle wrote apart:

* right cause: every cause in the set is selected, or reported as not
  separable from a selected candidate that is plausible under its prior
  (the report's `confounded` list; a correction within three prior
  standard deviations of its measured value, or an effect); a cause named
  as not separable from a selected correction beyond its prior is missed,
  and the table says so apart from a cause the report does not name;
* false causes: selected candidates that are neither a cause nor speed decay
  (rolling resistance and drag are in every set), and every term the
  search in the time series discovers beyond the library (the oracle's
  causes are all named by the library);
* parameter error: for an effect, |fitted - true| / |true|; for a
  correction, the error of the fitted shift from the nominal value relative
  to the true shift;
* errors before and after on the fitted and on the held-out runs: the weave
  eigenvalue RMS (1/s) and the median run's roll RMS (deg);
* time of the identification (s);
* signal: how far the cause moves the weave, from the oracle's own
  linearisation of its nominal and true models at each run's speed (root
  sum of squares over the runs), in units of one kick's scatter about the
  model (the controls' eigenvalue RMS): a cause with a signal below about 2
  cannot be told from the scatter of that many runs by any method. With
  two causes, each cause's own signal follows in brackets: what is left of
  the truth's weave shift when that cause is set back to nominal and the
  other cause is refitted (`own_signal.py`), since one cause can take
  over part of the other's shift; below 2 the weaves alone do not tell
  that cause from the other (the time series and the priors of measured
  parameters may still: a parameter error may have to go far beyond its
  measurement to mimic steer damping).

Targets (issue 33): the right cause on at least 90 % of the sets with a
cause, nothing but speed decay on the controls, parameters within 25 %, and
the weave eigenvalue or the median run's roll error at least halved on the
held-out runs where there is a cause.

Usage:
    python3 scorecard/oracle_scorecard.py [--subset ci] [--sets A,B] [--work DIR]
        [--oracle DIR] [--python PY] [--bikedyn BIN] [--seed-base N] [--json FILE]

The oracle needs numpy and scipy in --python (default: this interpreter).
The exit status is 0 when the scorecard was made (whatever it scores), 1 when
a set could not be made or identified, or with --require-targets when a
target is missed (on the sets scored: with --time-left, a set that the time
left would not hold is listed as not scored).
"""
from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import time
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# Oracle effects -> (bikedyn candidate, symbol, how the true value follows
# from the oracle's value and the nominal thesis parameters).
EFFECT_CAUSES = {
    "c_steer": ("steer_damping", "c_steer", lambda v, nom: v),
    "T_coul": ("steer_friction", "T_steer", lambda v, nom: v),
    # The oracle's yB is positive to the right; bikedyn's y3 to the left.
    "yB": ("lateral_mass_offset", "y3", lambda v, nom: -v),
    "dI3x_rel": ("correct I3x", "I3x", lambda v, nom: nom["I3x"] * (1.0 + v)),
    # The front assembly's inertia about its local z axis is the thesis's I4z.
    "dIE33_rel": ("correct I4z", "I4z", lambda v, nom: nom["I4z"] * (1.0 + v)),
    "dbz": ("correct z3", "z3", lambda v, nom: nom["z3"] + v),
}
SPEED_DECAY = {"rolling_resistance", "aero_drag"}
TARGET_RIGHT = 0.90
TARGET_PARAMETER = 0.25
# bikedyn's mark of a plausible correction (PLAUSIBLE_PRIOR_SDS): a cause
# named as not separable from a selected correction beyond it is not found
# (issue 33: "not separable from a selected one that is plausible under its
# prior").
PLAUSIBLE_PRIOR_SDS = 3.0


def pairs(text: str) -> dict[str, float]:
    out = {}
    for item in filter(None, (text or "").split(",")):
        key, value = item.split("=")
        out[key.strip()] = float(value)
    return out


def seed_of(name: str, base: int) -> int:
    """A seed nobody picked: a hash of the set's name and the base."""
    return int(hashlib.sha256(f"{base}:{name}".encode()).hexdigest()[:8], 16) % 1_000_000


def make_set(row, decay, args, seed):
    data = os.path.join(args.work, "data", row["name"])
    stamp = os.path.join(args.work, "stamps", row["name"] + ".json")
    want = {"effects": row.get("effects", ""), "thesis": row.get("thesis", ""), "decay": decay, "seed": seed}
    if os.path.isdir(data) and os.path.exists(stamp):
        with open(stamp) as fh:
            if json.load(fh) == want:
                return
    effects = ",".join(filter(None, [decay, row.get("effects", "")]))
    cmd = [args.python, os.path.join(args.oracle, "make_runs.py"), "--out", args.work,
           "--name", row["name"], "--seed", str(seed), "--effects", effects]
    if row.get("thesis"):
        cmd += ["--thesis", row["thesis"]]
    for sub in ("data", "truth"):
        shutil.rmtree(os.path.join(args.work, sub, row["name"]), ignore_errors=True)
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    os.makedirs(os.path.dirname(stamp), exist_ok=True)
    with open(stamp, "w") as fh:
        json.dump(want, fh)


def causes_of(row, truth):
    """The set's causes: (candidate, symbol, nominal, true value)."""
    nom = truth["nominal_thesis_parameters"]
    out = []
    for key, value in pairs(row.get("effects", "")).items():
        cand, symbol, true_of = EFFECT_CAUSES[key]
        nominal = nom.get(symbol, 0.0)
        out.append((cand, symbol, nominal, true_of(value, nom)))
    for key, value in pairs(row.get("thesis", "")).items():
        out.append((f"correct {key}", key, nom[key], value))
    return out


# Causes whose effect on the weave the oracle's own linearisation gives
# (viscous damping and parameter errors); Coulomb friction and a lateral
# offset act through the nonlinear response, and are not scored for signal.
NONLINEAR_CAUSES = {"T_coul", "yB"}


def weave_shift(row, work):
    """The cause's shift of the weave eigenvalue at each run's mean speed,
    from the oracle's truth (its nominal and its true linearised model; no
    bikedyn number): the root of the sum over runs of |shift|^2 (1/s), or
    None where a cause acts only through the nonlinear response."""
    if not (row.get("effects") or row.get("thesis")):
        return None
    if NONLINEAR_CAUSES & set(pairs(row.get("effects", ""))):
        return None
    folder = os.path.join(work, "truth", row["name"])
    total = 0.0
    for run in sorted(os.listdir(folder)):
        path = os.path.join(folder, run, "truth.json")
        if not os.path.isfile(path):
            continue
        with open(path) as fh:
            t = json.load(fh)
        if t.get("kind") != "run":
            continue
        e = t["eigenvalues_at_mean_speed"]
        a, b = e["nominal_whipple"]["weave"], e["true_model_with_effects"]["weave"]
        total += (a[0] - b[0]) ** 2 + (abs(a[1]) - abs(b[1])) ** 2
    return math.sqrt(total)


def own_shifts(row, args):
    """Each cause's own weave shift (1/s): what is left of the set's shift
    when that cause is set back to nominal and the set's other causes are
    refitted to the truth's weave (`own_signal.py`, run with the oracle's
    interpreter; the oracle's numbers only). Keyed by bikedyn candidate;
    None for a cause that acts through the nonlinear response."""
    effects = pairs(row.get("effects", ""))
    thesis = pairs(row.get("thesis", ""))
    if len(effects) + len(thesis) < 2:
        return None
    cmd = [args.python, os.path.join(HERE, "own_signal.py"), "--oracle", args.oracle,
           "--truth", os.path.join(args.work, "truth", row["name"]),
           "--effects", ",".join(f"{k}={v}" for k, v in effects.items()),
           "--thesis", ",".join(f"{k}={v}" for k, v in thesis.items())]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"own_signal.py exited {done.returncode}: {done.stderr.strip().splitlines()[-1:]}")
    shifts = json.loads(done.stdout)
    out = {}
    for key, value in shifts.items():
        name = EFFECT_CAUSES[key][0] if key in EFFECT_CAUSES else f"correct {key}"
        out[name] = value
    return out


def base_name(selected: str) -> str:
    return selected.split(" (")[0]


def score(row, truth, report, seconds):
    causes = causes_of(row, truth)
    selected = [base_name(s) for s in report["selected_effects"]]
    # Terms the search in the time series adds beyond the library: the
    # oracle's causes are all effects and corrections the library names,
    # so every such term is a false cause.
    ts = report.get("time_series_discovery") or {}
    discovered = [f"discovered {t}" for t in ts.get("selected", [])] if ts.get("status") == "ran" else []
    def plausible(candidate):
        if not candidate.startswith("correct "):
            return True
        p = report["parameters"].get(candidate[len("correct "):]) or {}
        return p.get("prior_sds") is None or abs(p["prior_sds"]) <= PLAUSIBLE_PRIOR_SDS

    named = [(c["chosen"], c["rival"]) for c in report.get("confounded", []) if c.get("confounded")]
    confounded = [(ch, rv) for ch, rv in named if plausible(ch)]
    cause_names = {c[0] for c in causes}
    found = []
    found_via = []  # (cause, selected candidate it is reported not separable from)
    # Causes not found that the report names as not separable from a
    # selected correction beyond its prior: the runs called for a gross
    # correction without telling which. Still a miss (the rule above), but
    # a different one from a cause the report does not name at all.
    missed_via = []
    param_errors = []
    for cand, symbol, nominal, true in causes:
        hit = cand in selected
        via = None
        if not hit:
            via = next((ch for ch, rv in confounded if rv == cand and ch in selected), None)
        found.append(hit or via is not None)
        if via is not None:
            found_via.append((cand, via))
        elif not hit:
            beyond = next((ch for ch, rv in named if rv == cand and ch in selected), None)
            if beyond is not None:
                missed_via.append((cand, beyond))
        p = report["parameters"].get(symbol)
        if hit and p is not None:
            if cand.startswith("correct "):
                shift_true = true - nominal
                err = abs((p["value"] - nominal) - shift_true) / abs(shift_true)
            else:
                err = abs(p["value"] - true) / abs(true)
            param_errors.append((symbol, p["value"], true, err))
    # A candidate named as not separable from a cause stands in for it,
    # unless the cause is selected too: then it is one more term.
    false = [s for s in selected if s not in cause_names and s not in SPEED_DECAY
             and not any(rv in cause_names and rv not in selected for ch, rv in confounded if ch == s)] + discovered
    before, after = report["error_before"], report["error_after"]
    ho_b, ho_a = before["held_out"], after["held_out"]

    def ratio(a, b):
        return a / b if b and math.isfinite(a) and math.isfinite(b) else float("nan")

    # Held-out figures: the weave eigenvalue RMS, and the median run's roll
    # RMS from the per-run held-out values.
    def median_held_roll(err):
        xs = sorted(r["held_out_roll_rms"] for r in err["per_run"] if r.get("held_out_roll_rms") is not None)
        return xs[len(xs) // 2] if xs else float("nan")

    figures = {
        "eigen_rms": (before["eigen_rms"], after["eigen_rms"]),
        "eigen_rms_held_out": (ho_b["eigen_rms"], ho_a["eigen_rms"]),
        "median_run_roll_deg": (math.degrees(before["median_run_roll_rms"]), math.degrees(after["median_run_roll_rms"])),
        "median_run_roll_held_out_deg": (math.degrees(median_held_roll(before)), math.degrees(median_held_roll(after))),
    }
    halved = (ratio(*figures["eigen_rms_held_out"][::-1]) <= 0.5
              or ratio(*figures["median_run_roll_held_out_deg"][::-1]) <= 0.5)
    return {
        "set": row["name"],
        "causes": [f"{c[0]}" for c in causes],
        "selected": report["selected_effects"] + discovered,
        "right": all(found) if causes else None,
        "right_via": [{"cause": c, "not_separable_from": v} for c, v in found_via],
        "missed_via": [{"cause": c, "not_separable_from": v} for c, v in missed_via],
        "control_clean": (not false) if not causes else None,
        "false": false,
        "parameters": [{"symbol": s, "fitted": v, "true": t, "relative_error": e} for s, v, t, e in param_errors],
        "parameters_within": all(e <= TARGET_PARAMETER for *_, e in param_errors) if param_errors else None,
        "figures": figures,
        "halved": halved if causes else None,
        "seconds": seconds,
    }


def fmt(x, digits=3):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.{digits}f}"


def print_table(rows, out=sys.stdout):
    print("| set | causes | signal | selected | right | false | parameter error | eigen RMS held-out (1/s) | median-run roll held-out (deg) | s |", file=out)
    print("|---|---|---|---|---|---|---|---|---|---|", file=out)
    for r in rows:
        if "error" in r:
            print(f"| {r['set']} | | | error: {r['error']} | no | | | | | |", file=out)
            continue
        causes = ", ".join(r["causes"]) or "none (control)"
        sel = ", ".join(r["selected"]) or "nothing"
        right = "yes" if r["right"] else ("no" if r["right"] is False else ("clean" if r["control_clean"] else "no"))
        if r["right"] and r.get("right_via"):
            right += " (" + "; ".join(f"{v['cause']} not separable from {v['not_separable_from']}" for v in r["right_via"]) + ")"
        if r["right"] is False and r.get("missed_via"):
            right += " (" + "; ".join(f"{v['cause']} not separable from {v['not_separable_from']}, beyond its prior"
                                      for v in r["missed_via"]) + ")"
        perr = ", ".join(f"{p['symbol']} {100 * p['relative_error']:.0f} %" for p in r["parameters"]) or "-"
        e, m = r["figures"]["eigen_rms_held_out"], r["figures"]["median_run_roll_held_out_deg"]
        signal = fmt(r.get("signal"), 1)
        if r.get("own_signal") and any(v is not None for v in r["own_signal"].values()):
            signal += " (" + ", ".join(f"{c.removeprefix('correct ')} {fmt(v, 1)}" for c, v in r["own_signal"].items()) + ")"
        print(f"| {r['set']} | {causes} | {signal} | {sel} | {right} | {', '.join(r['false']) or '-'} | {perr} | "
              f"{fmt(e[0])} -> {fmt(e[1])} | {fmt(m[0])} -> {fmt(m[1])} | {r['seconds']:.0f} |", file=out)


def summary(rows):
    with_cause = [r for r in rows if r.get("right") is not None or ("error" in r and r.get("has_cause"))]
    controls = [r for r in rows if r.get("control_clean") is not None or ("error" in r and not r.get("has_cause"))]
    right = sum(1 for r in with_cause if r.get("right"))
    right_via = sum(1 for r in with_cause if r.get("right") and r.get("right_via"))
    missed_via = sum(1 for r in with_cause if r.get("right") is False and r.get("missed_via"))
    clean = sum(1 for r in controls if r.get("control_clean"))
    params = [p for r in rows for p in r.get("parameters", [])]
    within = sum(1 for p in params if p["relative_error"] <= TARGET_PARAMETER)
    halved = sum(1 for r in with_cause if r.get("halved"))
    false = sum(len(r.get("false", [])) for r in with_cause)
    return {
        "sets": len(rows),
        "right_causes": right, "sets_with_cause": len(with_cause),
        "right_via_not_separable": right_via,
        "missed_named_beside_a_correction_beyond_its_prior": missed_via,
        "clean_controls": clean, "controls": len(controls),
        "false_causes_on_sets_with_cause": false,
        "parameters_within_25pct": within, "parameters_scored": len(params),
        "errors_halved": halved,
        "seconds": sum(r.get("seconds", 0.0) for r in rows),
        "targets_met": (len(with_cause) == 0 or right >= TARGET_RIGHT * len(with_cause)) and clean == len(controls),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--matrix", default=os.path.join(HERE, "matrix.toml"))
    ap.add_argument("--oracle", default=os.path.join(ROOT, "..", "shared", "oracle-sim"))
    ap.add_argument("--work", default=os.path.join(ROOT, "target", "scorecard"))
    ap.add_argument("--python", default=sys.executable, help="interpreter with numpy and scipy for the oracle")
    ap.add_argument("--bikedyn", default=os.path.join(ROOT, "target", "release", "bikedyn"))
    ap.add_argument("--subset", choices=["all", "ci"], default="all")
    ap.add_argument("--sets", default="", help="comma-separated set names (default: the subset)")
    ap.add_argument("--seed-base", type=int, default=0, help="another base draws other seeds for every set")
    ap.add_argument("--identify-args", default="", help="extra arguments for bikedyn identify")
    ap.add_argument("--json", help="write the scorecard as JSON here")
    ap.add_argument("--markdown", help="write the table and summary as Markdown here")
    ap.add_argument("--require-targets", action="store_true", help="exit 1 when a target is missed")
    ap.add_argument("--time-left", type=float, default=None,
                    help="seconds this scorecard may take (CI's time left): a set is scored only when the time "
                         "left holds half again the longest set so far, or --set-seconds before the first; the "
                         "others are listed as not scored for want of time")
    ap.add_argument("--set-seconds", type=float, default=0.0,
                    help="with --time-left: the seconds one set is expected to take before any has run")
    ap.add_argument("--rescore", action="store_true",
                    help="score the reports already under --work/reports again (after a change of the scoring) "
                         "instead of running identify; the time is the one each report recorded")
    args = ap.parse_args()

    if not os.path.isfile(os.path.join(args.oracle, "make_runs.py")):
        sys.exit(f"error: no oracle simulator at {args.oracle} (--oracle names the folder with make_runs.py)")
    if not os.access(args.bikedyn, os.X_OK):
        sys.exit(f"error: no bikedyn binary at {args.bikedyn} (build it with `cargo build --release`, or pass --bikedyn)")
    with open(args.matrix, "rb") as fh:
        matrix = tomllib.load(fh)
    decay = matrix.get("decay", "")
    rows = matrix["set"]
    if args.sets:
        names = args.sets.split(",")
        unknown = [n for n in names if n not in {r["name"] for r in rows}]
        if unknown:
            sys.exit(f"error: --sets names sets not in {args.matrix}: {', '.join(unknown)}")
        rows = [r for r in rows if r["name"] in names]
    elif args.subset == "ci":
        rows = [r for r in rows if r.get("ci")]
    os.makedirs(args.work, exist_ok=True)

    results = []
    failed = False
    began = time.time()
    longest_set = None  # seconds of the longest set so far (make and identify)
    not_scored = []
    for i, row in enumerate(rows, 1):
        seed = seed_of(row["name"], args.seed_base)
        # Within a time budget (CI's), a set is started only when the time
        # left holds half again the longest one so far: a scorecard cut
        # short by the budget's end would take the whole run with it.
        if args.time_left is not None:
            left = args.time_left - (time.time() - began)
            expected = args.set_seconds if longest_set is None else longest_set
            if 1.5 * expected > left:
                print(f"[{i}/{len(rows)}] {row['name']}: not scored for want of time ({left:.0f} s left; "
                      f"{'a set is expected to take' if longest_set is None else 'the longest set so far took'} "
                      f"{expected:.0f} s)", file=sys.stderr, flush=True)
                not_scored.append(row["name"])
                continue
        set_began = time.time()
        print(f"[{i}/{len(rows)}] {row['name']} (seed {seed})", file=sys.stderr, flush=True)
        has_cause = bool(row.get("effects") or row.get("thesis"))
        try:
            make_set(row, decay, args, seed)
            with open(os.path.join(args.work, "truth", row["name"], "set_truth.json")) as fh:
                truth = json.load(fh)
            report_dir = os.path.join(args.work, "reports", row["name"])
            if args.rescore:
                if not os.path.exists(os.path.join(report_dir, "report.json")):
                    raise RuntimeError(f"--rescore: no report at {report_dir}")
            else:
                # The scorecard's own folder: an earlier scorecard's report
                # goes (bikedyn replaces only reports it marked as its own).
                shutil.rmtree(report_dir, ignore_errors=True)
                os.makedirs(os.path.dirname(report_dir), exist_ok=True)
                t0 = time.time()
                cmd = [args.bikedyn, "identify", os.path.join(args.work, "data", row["name"]),
                       "--report", report_dir] + args.identify_args.split()
                done = subprocess.run(cmd, capture_output=True, text=True)
                seconds = time.time() - t0
                if done.returncode not in (0, 1) or not os.path.exists(os.path.join(report_dir, "report.json")):
                    raise RuntimeError(f"identify exited {done.returncode}: {done.stderr.strip().splitlines()[-1:]}")
            with open(os.path.join(report_dir, "report.json")) as fh:
                report = json.load(fh)
            if args.rescore:
                seconds = float(report.get("seconds", float("nan")))
            results.append(score(row, truth, report, seconds))
            r = results[-1]
            r["weave_shift"] = weave_shift(row, args.work)
            r["own_shift"] = own_shifts(row, args)
            print(f"    selected {', '.join(r['selected']) or 'nothing'}; right {r['right']}; false {r['false']}; "
                  f"{seconds:.0f} s", file=sys.stderr, flush=True)
            longest_set = max(longest_set or 0.0, time.time() - set_began)
        except (subprocess.CalledProcessError, RuntimeError, OSError, KeyError) as e:
            failed = True
            results.append({"set": row["name"], "error": str(e), "has_cause": has_cause})
            print(f"    error: {e}", file=sys.stderr, flush=True)
    # The signal of each cause: its weave shift over all runs against the
    # scatter of one kick's measured weave about the model, taken from the
    # controls (their eigenvalue RMS after the speed decay is modelled).
    scatter = sorted(r["figures"]["eigen_rms"][1] for r in results
                     if r.get("control_clean") is not None and "figures" in r)
    kick_scatter = scatter[len(scatter) // 2] if scatter else None
    for r in results:
        shift = r.get("weave_shift")
        r["signal"] = shift / kick_scatter if shift is not None and kick_scatter else None
        own = r.get("own_shift")
        r["own_signal"] = ({c: (v / kick_scatter if v is not None else None) for c, v in own.items()}
                           if own and kick_scatter else None)
    print_table(results)
    s = summary(results)
    s["kick_scatter"] = kick_scatter
    def mark(ok):
        return "met" if ok else "missed"

    n = max(s["sets_with_cause"], 1)
    print(f"\nright cause: {s['right_causes']} of {s['sets_with_cause']} sets with a cause "
          f"({100 * s['right_causes'] / n:.0f} %; target 90 %: {mark(s['right_causes'] >= TARGET_RIGHT * s['sets_with_cause'])}"
          f"{'; of them ' + str(s['right_via_not_separable']) + ' reported as not separable from a selected candidate' if s.get('right_via_not_separable') else ''})")
    if s["missed_named_beside_a_correction_beyond_its_prior"]:
        print(f"of the {s['sets_with_cause'] - s['right_causes']} missed, {s['missed_named_beside_a_correction_beyond_its_prior']} named as not "
              f"separable from a selected correction beyond its prior (the runs call for a gross correction "
              f"without telling which; counted as missed)")
    print(f"controls with nothing but speed decay: {s['clean_controls']} of {s['controls']} "
          f"(target all: {mark(s['clean_controls'] == s['controls'])})")
    print(f"false causes beside the right ones: {s['false_causes_on_sets_with_cause']}")
    print(f"parameters within 25 %: {s['parameters_within_25pct']} of {s['parameters_scored']} "
          f"(target all: {mark(s['parameters_within_25pct'] == s['parameters_scored'])})")
    print(f"held-out weave eigenvalue or median-run roll error at least halved: {s['errors_halved']} of "
          f"{s['sets_with_cause']} (target all: {mark(s['errors_halved'] == s['sets_with_cause'])})")
    # The held-out roll error cannot fall below the sensors' and the runs'
    # own floor, which the controls show once the speed decay is modelled:
    # where a cause's error before is under twice that floor, halving it
    # is out of reach of any model. The part above the floor is the cause's.
    floors = sorted(r["figures"]["median_run_roll_held_out_deg"][1] for r in results
                    if r.get("control_clean") is not None and "figures" in r)
    floor = floors[len(floors) // 2] if floors else None
    if floor is not None:
        def excess_halved(r):
            b, a = r["figures"]["median_run_roll_held_out_deg"]
            return b > floor and (a - floor) <= 0.5 * (b - floor)
        with_cause = [r for r in results if r.get("right") is not None]
        s["roll_floor_deg"] = floor
        s["excess_over_floor_halved"] = sum(1 for r in with_cause if excess_halved(r))
        print(f"held-out median-run roll error above the controls' floor ({floor:.3f} deg, their median after) "
              f"at least halved: {s['excess_over_floor_halved']} of {len(with_cause)}")
    if kick_scatter:
        weak = [r for r in results if r.get("signal") is not None and r["signal"] < 2.0]
        print(f"signal: the cause's weave shift over the set's runs, in units of one kick's scatter about the model "
              f"({kick_scatter:.3f} 1/s, the controls' median); below 2 in "
              f"{len(weak)} set(s){': ' + ', '.join(r['set'] + ' (' + fmt(r['signal'], 1) + ')' for r in weak) if weak else ''}"
              f"{' (right on ' + str(sum(1 for r in weak if r.get('right'))) + ')' if weak else ''}")
    # With two causes, the set's signal is the pair's; each cause's own
    # signal is what the other cannot take over. Below 2 the runs' weaves
    # alone do not tell that cause from the other (the time series and the
    # priors of measured parameters may still).
    hidden = [(r, c, v) for r in results for c, v in (r.get("own_signal") or {}).items() if v is not None and v < 2.0]

    def found(r, c):
        if c in [base_name(x) for x in r["selected"]]:
            return "found"
        via = next((v["not_separable_from"] for v in r.get("right_via", []) if v["cause"] == c), None)
        return f"not separable from {via}" if via else "not found"

    if hidden:
        print("own signal of a cause beside another (what the other cause, refitted, leaves of its weave shift, in "
              "kick scatters; below 2 the weaves alone do not tell it from the other): below 2 for " + ", ".join(
                  f"{c} in {r['set']} ({fmt(v, 1)}; {found(r, c)})"
                  for r, c, v in hidden))
        s["causes_below_own_signal_2"] = [{"set": r["set"], "cause": c, "own_signal": v} for r, c, v in hidden]
    print(f"identify time: {s['seconds']:.0f} s in all")
    if not_scored:
        s["not_scored_for_want_of_time"] = not_scored
        print(f"not scored for want of time: {', '.join(not_scored)} ({len(not_scored)} of {len(rows)} sets)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"summary": s, "sets": results, "seed_base": args.seed_base}, fh, indent=1)
    if args.markdown:
        with open(args.markdown, "w") as fh:
            print_table(results, fh)
    if failed or (args.require_targets and not s["targets_met"]):
        sys.exit(1)


if __name__ == "__main__":
    main()
