"""Shard a large parameter study over processes, then over machines.

Each design (one value of the swept parameter) is independent of the
others, so a sweep splits into shards of parameter values whose results
are concatenated: the result is identical, to the bit, to one call over
all values (tests/test_sharding.py checks it). Within a process bikedyn
already uses every core (set RAYON_NUM_THREADS=1 when each process should
use one, as below).

Run:  python examples/shard_sweep.py [processes]
"""

import multiprocessing
import os
import sys
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import bikedyn


def one_thread():
    """Worker initializer: one bikedyn thread per process (set before the
    worker's first sweep starts its thread pool)."""
    os.environ["RAYON_NUM_THREADS"] = "1"


def sweep_shard(args):
    """One shard: the sweep over a slice of the parameter values."""
    bike, param, values, speeds = args
    s = bikedyn.sweep(bike, param, values, speeds)
    return s.least_stable_real_part, s.weave_speed, s.capsize_speed


def sharded_sweep(bike, param, values, speeds, processes=2):
    """``bikedyn.sweep`` over ``processes`` processes (standard library)."""
    shards = np.array_split(np.asarray(values, dtype=float), processes)
    jobs = [(bike, param, s, speeds) for s in shards if len(s)]
    # Workers are spawned, not forked: a fork of a process whose thread
    # pool is running (bikedyn's, NumPy's) can hang in the child.
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(
        max_workers=processes,
        mp_context=spawn,
        initializer=one_thread,
    ) as pool:
        parts = list(pool.map(sweep_shard, jobs))
    return tuple(np.concatenate([p[k] for p in parts]) for k in range(3))


# The same shard function on a cluster (neither is a dependency of
# bikedyn; each worker needs `pip install ./python`):
#
#   Ray:   import ray; ray.init()
#          task = ray.remote(sweep_shard)
#          parts = ray.get([task.remote(job) for job in jobs])
#
#   Dask:  from dask.distributed import Client; client = Client()
#          parts = client.gather(client.map(sweep_shard, jobs))
#
# then concatenate `parts` as sharded_sweep does.

if __name__ == "__main__":
    processes = int(sys.argv[1]) if len(sys.argv) > 1 else 2
    trails = np.linspace(0.0, 0.2, 2001)  # trail c (m)
    speeds = np.linspace(0.5, 10.0, 96)  # forward speed (m/s)
    least, weave, capsize = sharded_sweep("benchmark", "c", trails, speeds, processes)
    stable = (least < 0).any(axis=1)  # self-stable at some speed of the grid
    print(f"{least.size} design-speed points on {processes} processes")
    print(f"{stable.sum()} of {len(trails)} trails from {trails[0]} to {trails[-1]} m are self-stable at some speed up to {speeds[-1]} m/s")
    if stable.any():
        print(f"  those trails: {trails[stable].min():.4f} to {trails[stable].max():.4f} m")
