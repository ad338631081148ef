"""Speed of the Python package (issue 18, point 4), printed as figures:

* ``Bicycle.eig`` over 10^4 speeds in one call, per speed point, beside the
  command line's figure for the same work (``bikedyn bench``'s
  "eigenvalues of the 4x4 state matrix per speed point", when the CLI is
  built: target/release/bikedyn or $BIKEDYN_CLI); target: within 2x.
* ``bikedyn.sweep`` over 10^6 design-speed points (1000 trails x 1000
  speeds); target: under 1 s on 2 cores.
* bicycleparameters' ``Meijaard2007Model.calc_eigen`` on the same bicycle
  and speeds, when it is installed.

Run:  python python/bench.py
"""

import os
import pathlib
import re
import subprocess
import tempfile
import time

import sys

import numpy as np

# Run as `python python/bench.py`, this folder (which holds the package's
# source, without its compiled extension) would shadow the installed
# package.
HERE = pathlib.Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if pathlib.Path(p or ".").resolve() != HERE]

import bikedyn  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[1]


def best_of(n, f):
    """Median wall-clock time of ``n`` calls (s)."""
    times = []
    for _ in range(n):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return float(np.median(times))


def cli():
    exe = os.environ.get("BIKEDYN_CLI") or str(REPO / "target/release/bikedyn")
    return exe if os.path.exists(exe) else None


def cli_eig_ns(exe):
    """``bikedyn bench``'s eigenvalues-only figure (ns per speed point)."""
    out = subprocess.run([exe, "bench", "--quick"], capture_output=True, text=True, check=False).stdout
    m = re.search(r"eigenvalues of the 4x4 state matrix per speed point:\s*([0-9.]+) ns", out)
    return float(m.group(1)) if m else None


def cli_eig_command_ns(exe, n):
    """``bikedyn eig`` over ``n`` speeds (labels, vectors, CSV to a file),
    per speed point, less the time of a two-point run (start-up)."""
    with tempfile.TemporaryDirectory() as d:
        out = os.path.join(d, "eig.csv")

        def run(k):
            cmd = [exe, "eig", "--bike", "benchmark", "--speeds", f"0:10:{10.0 / (k - 1)}", "--format", "csv", "--output", out]
            return lambda: subprocess.run(cmd, capture_output=True, check=True)

        return (best_of(5, run(n)) - best_of(5, run(2))) / n * 1e9


def main():
    bike = bikedyn.Bicycle("benchmark")
    speeds = np.linspace(0.0, 10.0, 10_000)
    bike.eig(speeds[:10])
    t_eig = best_of(20, lambda: bike.eig(speeds))
    per_point = t_eig / len(speeds) * 1e9
    bike.eigenvalues(speeds[:10])
    t_fast = best_of(20, lambda: bike.eigenvalues(speeds))
    fast = t_fast / len(speeds) * 1e9
    print(f"bikedyn.Bicycle.eig, 10^4 speeds in one call: {t_eig * 1e3:.2f} ms, {per_point:.0f} ns per speed point "
          "(eigenvalues, mode labels tracked along speed, eigenvectors)")
    print(f"bikedyn.Bicycle.eigenvalues, 10^4 speeds in one call: {t_fast * 1e3:.2f} ms, {fast:.0f} ns per speed point "
          f"(eigenvalues only, {os.cpu_count()} cores)")
    exe = cli()
    if exe is None:
        print("  command line figures: not available (build it with `cargo build --release` or set BIKEDYN_CLI)")
    else:
        one = cli_eig_ns(exe)
        cmd = cli_eig_command_ns(exe, len(speeds))
        if one is not None:
            print(f"  command line `bikedyn bench`, eigenvalues per speed point (one core): {one:.0f} ns; "
                  f"eigenvalues() is {fast / one:.2f}x that (target <= 2)")
        print(f"  command line `bikedyn eig --format csv`, same work as eig() plus the CSV: {cmd:.0f} ns per speed point; "
              f"eig() is {per_point / cmd:.2f}x that (target <= 2)")

    trails = np.linspace(0.0, 0.2, 1000)
    sweep_speeds = np.linspace(0.0, 10.0, 1000)
    bikedyn.sweep(bike, "c", trails[:4], sweep_speeds)
    t_sweep = best_of(3, lambda: bikedyn.sweep(bike, "c", trails, sweep_speeds))
    print(f"bikedyn.sweep, 10^6 design-speed points (1000 trails x 1000 speeds): {t_sweep:.3f} s "
          f"on {os.cpu_count()} cores (target < 1 s on 2 cores)")

    try:
        from bicycleparameters.models import Meijaard2007Model
        from bicycleparameters.parameter_sets import Meijaard2007ParameterSet
    except ImportError:
        print("bicycleparameters is not installed: no comparison (pip install bicycleparameters)")
        return
    par = {k: v for k, v in bike.parameters.items()}
    par["v"] = 0.0
    model = Meijaard2007Model(Meijaard2007ParameterSet(par, True))
    model.calc_eigen(v=speeds[:10])
    t_bp = best_of(3, lambda: model.calc_eigen(v=speeds))
    print(f"bicycleparameters Meijaard2007Model.calc_eigen, same 10^4 speeds: {t_bp * 1e3:.1f} ms, "
          f"{t_bp / len(speeds) * 1e9:.0f} ns per speed point; bikedyn is {t_bp / t_eig:.0f}x faster")


if __name__ == "__main__":
    main()
