"""The weave shift each cause of a set keeps when the set's other causes
take all of the shift they can: what is left for a method to find it by.

Run by `oracle_scorecard.py` with the oracle's interpreter (numpy, scipy):

    python3 own_signal.py --oracle DIR --truth DIR/truth/SET --effects c_steer=0.1,dI3x_rel=0.25 [--thesis I3z=1.6]

It prints a JSON object: for each cause (the oracle's name of the knob),
the root of the sum over the set's runs of |weave shift|^2 (1/s) that is
left when that cause is set back to nominal and the other causes are
refitted (least squares over the same runs, the oracle's own linearisation
at each run's mean speed after the kick), or null for a cause that acts
only through the nonlinear response (Coulomb friction, a lateral offset).

Why: with two causes in a set, the larger can absorb part of the smaller's
shift (steer damping lowers the weave frequency as a larger yaw inertia
does). The set's total signal then says nothing about whether the smaller
cause can be found; this residual shift does. Every number here comes from
the oracle and its truth; nothing from bikedyn.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys

# Causes whose effect the linearisation does not carry.
NONLINEAR = {"T_coul", "yB"}
# The speed decay every set carries: in the model as the truth had it, but
# never refitted (it does not move the frozen-speed weave).
DECAY = ("Crr", "CdA")


def pairs(text):
    out = {}
    for item in filter(None, (text or "").split(",")):
        key, value = item.split("=")
        out[key.strip()] = float(value)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--oracle", required=True)
    ap.add_argument("--truth", required=True, help="the set's truth folder (set_truth.json and one folder per run)")
    ap.add_argument("--effects", default="")
    ap.add_argument("--thesis", default="")
    args = ap.parse_args()
    sys.path.insert(0, os.path.abspath(args.oracle))
    import numpy as np
    from scipy.optimize import minimize
    from make_runs import linear_eigs
    from model import Bicycle
    from params import Effects, model_vector, thesis_params, thesis_to_model

    with open(os.path.join(args.truth, "set_truth.json")) as fh:
        set_truth = json.load(fh)
    effects, thesis = pairs(args.effects), pairs(args.thesis)
    knobs = [(k, v, "effect") for k, v in effects.items() if k not in DECAY]
    knobs += [(k, v, "thesis") for k, v in thesis.items()]
    nominal_thesis = thesis_params()
    decay = {k: set_truth["effects"][k] for k in DECAY if k in set_truth["effects"]}

    runs = []
    for run in sorted(os.listdir(args.truth)):
        path = os.path.join(args.truth, run, "truth.json")
        if not os.path.isfile(path):
            continue
        with open(path) as fh:
            t = json.load(fh)
        if t.get("kind") != "run":
            continue
        e = t["eigenvalues_at_mean_speed"]["true_model_with_effects"]
        if e.get("weave") is None:
            continue
        runs.append((e["speed"], complex(e["weave"][0], abs(e["weave"][1]))))

    def weaves(values):
        """The weave at each run's speed with the knobs at `values`."""
        eff = dict(decay)
        th = dict(nominal_thesis)
        for (name, _, kind), value in zip(knobs, values):
            if kind == "effect":
                eff[name] = value
            else:
                th[name] = value
        bike = Bicycle(model_vector(thesis_to_model(th), Effects(**eff)))
        out = []
        for v, _ in runs:
            w = linear_eigs(bike, v)["weave"]
            out.append(None if w is None else complex(w[0], abs(w[1])))
        return out

    def misfit(values):
        total = 0.0
        for (_, truth), w in zip(runs, weaves(values)):
            # A model with no weave at a run's speed misses it by its whole
            # eigenvalue: a large misfit, not a skipped run.
            total += abs(truth - (w if w is not None else 0.0)) ** 2
        return total

    # The construction must give the truth's own eigenvalues at the true
    # values: otherwise the knobs are not what the oracle applied.
    true_values = [v for _, v, _ in knobs]
    check = math.sqrt(misfit(true_values))
    if check > 1e-6:
        sys.exit(f"error: the oracle's true model is not reproduced from --effects/--thesis (weave misfit {check:.3g} 1/s)")

    nominal_of = {k: (0.0 if kind == "effect" else nominal_thesis[k]) for k, _, kind in knobs}
    out = {}
    for i, (name, value, _) in enumerate(knobs):
        if name in NONLINEAR:
            out[name] = None
            continue
        others = [j for j in range(len(knobs)) if j != i]
        if any(knobs[j][0] in NONLINEAR for j in others):
            # A nonlinear cause beside it: its share of the shift is not in
            # the linearisation, so the split is not defined.
            out[name] = None
            continue

        def with_others(x):
            values = list(true_values)
            values[i] = nominal_of[name]
            for j, xj in zip(others, x):
                values[j] = xj
            return values

        if not others:
            out[name] = math.sqrt(misfit(with_others([])))
            continue
        # Each other cause refitted from its true value, in units of that
        # value's size (or 1 where it is 0) so the simplex steps are alike.
        scale = [abs(true_values[j]) or 1.0 for j in others]
        res = minimize(lambda z: misfit(with_others([zj * s for zj, s in zip(z, scale)])),
                       [true_values[j] / s for j, s in zip(others, scale)],
                       method="Nelder-Mead", options={"xatol": 1e-6, "fatol": 1e-10, "maxiter": 400})
        out[name] = math.sqrt(res.fun)
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
