#!/usr/bin/env python3
"""Peak memory of bikedyn on large and hostile inputs (issue 35, item 4).

Each case runs the release binary as a child process and prints its peak
resident set size (from the kernel's accounting of that child, os.wait4),
its exit status and its wall time. The cases:

- `fit` of a set whose runs carry long reed-switch records (SIZE MiB each,
  the example set's records continued at 1 kHz), with one run and with
  four: runs are read and processed one at a time, so four runs peak as
  one does;
- `identify --eigenvalues /dev/zero`: a device, refused before reading;
- a sparse 1 GiB TU Delft log: refused from its size before reading;
- a 100 MiB log of one line: refused from its size;
- with --python PY (an interpreter with bikedyn installed): `eig` over a
  million speeds (the most one call takes) and over ten million (refused
  with a MemoryError before computing).

Usage: python3 scripts/memory_bench.py [--bikedyn target/release/bikedyn]
       [--size MIB] [--work DIR] [--python PY]
Needs a Unix system (os.wait4). Writes about 4 x SIZE MiB under --work
(default: a temporary folder, removed at the end).
"""

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EXAMPLE = os.path.join(ROOT, "examples", "data", "hidden_steer_damping")
LOG_BIKE = os.path.join(ROOT, "tests", "data", "tudelft_sbw_bicycle.toml")


def peak(cmd):
    """Run cmd; return (exit status, peak RSS in MiB, seconds). Linux counts
    the forking parent's resident set in the child's peak, so the figures
    include this script's own (about 10 MiB)."""
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(p.pid, 0)
    # ru_maxrss is in KiB on Linux.
    return os.waitstatus_to_exitcode(status), usage.ru_maxrss / 1024.0, time.monotonic() - t0


def long_set(folder, runs, size_mib):
    """The example set's calibration and `runs` runs, each speed_switch.csv
    continued at 1 kHz with the wheel at rest until it holds size_mib."""
    os.makedirs(folder)
    for name in ["calibration"] + runs:
        shutil.copytree(os.path.join(EXAMPLE, name), os.path.join(folder, name))
    for name in runs:
        path = os.path.join(folder, name, "speed_switch.csv")
        with open(path) as f:
            last = f.read().splitlines()[-1].split(",")
        t_last, volts = float(last[0]), last[1]
        target = size_mib << 20
        k = 1
        with open(path, "a") as f:
            size = os.path.getsize(path)
            while size < target:
                chunk = "".join(f"{t_last + 0.001 * (k + i):.3f},{volts}\n" for i in range(100_000))
                f.write(chunk)
                size += len(chunk)
                k += 100_000


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bikedyn", default=os.path.join(ROOT, "target", "release", "bikedyn"))
    ap.add_argument("--size", type=int, default=100, help="MiB per reed-switch record (default 100)")
    ap.add_argument("--work", help="folder for the inputs (default: a temporary one)")
    ap.add_argument("--python", help="a Python with the bikedyn package, for its cases")
    a = ap.parse_args()
    if not os.path.exists(a.bikedyn):
        sys.exit(f"error: {a.bikedyn} not found: build it with cargo build --release --bin bikedyn")
    work = a.work or tempfile.mkdtemp(prefix="bikedyn-memory-")
    os.makedirs(work, exist_ok=True)
    try:
        one, four = os.path.join(work, "one-run"), os.path.join(work, "four-runs")
        for d in (one, four):
            shutil.rmtree(d, ignore_errors=True)
        long_set(one, ["run01"], a.size)
        long_set(four, ["run01", "run02", "run03", "run04"], a.size)
        sparse = os.path.join(work, "sparse-1GiB.csv")
        with open(sparse, "wb") as f:
            f.truncate(1 << 30)
        one_line = os.path.join(work, "one-line-100MiB.csv")
        with open(one_line, "w") as f:
            # In 1 MiB pieces: a child's peak RSS counts its parent's at the
            # fork, so this script stays small.
            for _ in range(100):
                f.write("x" * (1 << 20))
        cases = [
            (f"fit, 1 run with a {a.size} MiB switch record", [a.bikedyn, "fit", one]),
            (f"fit, 4 runs with {a.size} MiB switch records", [a.bikedyn, "fit", four]),
            ("identify --eigenvalues /dev/zero", [a.bikedyn, "identify", "--eigenvalues", "/dev/zero", "--bike", "benchmark"]),
            ("fit of a sparse 1 GiB log", [a.bikedyn, "fit", sparse, "--bike", LOG_BIKE]),
            ("fit of a 100 MiB one-line log", [a.bikedyn, "fit", one_line, "--bike", LOG_BIKE]),
        ]
        if a.python:
            for n in (1_000_000, 10_000_000):
                code = (
                    "import sys, numpy as np, bikedyn\n"
                    "b = bikedyn.Bicycle('benchmark')\n"
                    "try:\n"
                    f"    b.eig(np.linspace(0.0, 10.0, {n}))\n"
                    "except MemoryError:\n"
                    "    sys.exit(1)\n"
                )
                cases.append((f"Python eig over {n:,} speeds", [a.python, "-c", code]))
        print(f"{'case':<48} {'exit':>4} {'peak RSS (MiB)':>15} {'time (s)':>9}")
        for label, cmd in cases:
            code, rss, secs = peak(cmd)
            print(f"{label:<48} {code:>4} {rss:>15.1f} {secs:>9.2f}")
    finally:
        if not a.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
