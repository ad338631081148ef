"""A sweep sharded over processes (examples/shard_sweep.py) gives exactly
the single-process result."""

import pathlib
import sys

import numpy as np

import bikedyn

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "examples"))
from shard_sweep import sharded_sweep  # noqa: E402


def test_sharded_sweep_is_identical_to_one_call():
    trails = np.linspace(0.02, 0.14, 61)
    speeds = np.linspace(0.5, 9.5, 19)
    one = bikedyn.sweep("benchmark", "c", trails, speeds)
    least, weave, capsize = sharded_sweep("benchmark", "c", trails, speeds, processes=3)
    assert np.array_equal(least, one.least_stable_real_part)
    assert np.array_equal(weave, one.weave_speed, equal_nan=True)
    assert np.array_equal(capsize, one.capsize_speed, equal_nan=True)
