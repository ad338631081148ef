"""Agreement with bicycleparameters' Meijaard2007Model.calc_eigen (when
bicycleparameters is installed) on the benchmark and three real bicycles:
the Bluenose recumbent, the TU Delft balance-assist e-bike and the TU
Delft steer-by-wire bicycle without its assist (committed copies in
tests/data, with their sources and licences in tests/data/SOURCE.txt)."""

import re

import numpy as np
import pytest

import bikedyn
from conftest import REPO, meijaard2007

bp = pytest.importorskip("bicycleparameters", reason="bicycleparameters is not installed")
from bicycleparameters.models import Meijaard2007Model  # noqa: E402
from bicycleparameters.parameter_sets import Meijaard2007ParameterSet  # noqa: E402

REAL = ["BluenosePar.txt", "Balanceassistv1Benchmark.txt", "tudelft_sbw_bicycle.toml"]
SYMBOLS = list(meijaard2007()["parameters"])


def nominal_values(path):
    """Table 1 values of a bicycleparameters text file (value+/-std)."""
    out = {}
    for line in path.read_text().splitlines():
        m = re.match(r"\s*(\w+)\s*=\s*([-+]?[0-9.]+(?:[eE][-+]?[0-9]+)?)", line)
        if m and m.group(1) in SYMBOLS:
            out[m.group(1)] = float(m.group(2))
    return out


def calc_eigen(par, speeds):
    model = Meijaard2007Model(Meijaard2007ParameterSet(dict(par, v=0.0), True))
    evals, _evecs = model.calc_eigen(v=speeds)
    return np.asarray(evals)


@pytest.mark.parametrize("name", ["benchmark"] + REAL)
def test_eig_agrees_with_calc_eigen(name):
    if name == "benchmark":
        par = dict(meijaard2007()["parameters"])
        ours = bikedyn.Bicycle("benchmark")
    elif name.endswith(".toml"):
        # The Whipple part of a bicycle with effects: its Table 1 values,
        # given to both as a dict.
        b = bikedyn.Bicycle(str(REPO / "tests/data" / name))
        par = {k: b.value(k) for k in SYMBOLS}
        ours = bikedyn.Bicycle(par, name=name)
    else:
        path = REPO / "tests/data" / name
        par = nominal_values(path)
        ours = bikedyn.Bicycle(str(path))
    speeds = np.linspace(0.0, 10.0, 51)
    theirs = calc_eigen(par, speeds)
    mine = ours.eig(speeds).eigenvalues
    for i in range(len(speeds)):
        a = np.sort_complex(np.round(mine[i], 12))
        b = np.sort_complex(np.round(theirs[i], 12))
        assert np.abs(a - b).max() < 1e-10 * max(1.0, np.abs(b).max()), (name, speeds[i], a, b)


@pytest.mark.parametrize("name", ["Browser", "Crescendo", "Fisher"])
def test_eig_agrees_on_the_shared_real_bicycles(shared, name):
    path = shared / "realdata/parameter_sets/BicycleParameters_data/bicycles" / name / "Parameters" / f"{name}Benchmark.txt"
    speeds = np.linspace(0.0, 10.0, 51)
    theirs = calc_eigen(nominal_values(path), speeds)
    mine = bikedyn.Bicycle(str(path)).eig(speeds).eigenvalues
    for i in range(len(speeds)):
        a = np.sort_complex(np.round(mine[i], 12))
        b = np.sort_complex(np.round(theirs[i], 12))
        assert np.abs(a - b).max() < 1e-10 * max(1.0, np.abs(b).max()), (name, speeds[i], a, b)


def test_canonical_standard_deviations_agree_with_canonical_nominal_false(tmp_path):
    """The measured +/- of a bicycleparameters file propagated to the
    canonical matrices: bicycleparameters' ``Bicycle.canonical(nominal=
    False)`` (the ``uncertainties`` package, first order) against bikedyn's
    exact first-order propagation, entry by entry, to 1e-10."""
    import shutil

    from uncertainties import unumpy

    name = "Balanceassistv1"
    folder = tmp_path / "bicycles" / name / "Parameters"
    folder.mkdir(parents=True)
    shutil.copy(REPO / "tests/data" / f"{name}Benchmark.txt", folder)
    theirs = bp.Bicycle(name, pathToData=str(tmp_path)).canonical(nominal=False)
    ours = bikedyn.Bicycle(str(REPO / "tests/data" / f"{name}Benchmark.txt")).canonical()
    for key, m in zip(("M", "C1", "K0", "K2"), theirs):
        sd = unumpy.std_devs(m)
        assert np.abs(getattr(ours.standard_deviations, key) - sd).max() < 1e-10 * max(1.0, np.abs(sd).max()), key
        assert np.abs(getattr(ours, key) - unumpy.nominal_values(m)).max() < 1e-10 * max(1.0, np.abs(getattr(ours, key)).max()), key
    assert bikedyn.Bicycle("benchmark").canonical().standard_deviations is None


@pytest.mark.parametrize("name", ["benchmark"] + REAL[:2])
def test_bode_agrees_with_bicycleparameters_state_space(name):
    """bikedyn's frequency response against C (i omega I - A)^-1 B built
    from bicycleparameters' own A and B (``form_state_space_matrices``) of
    the same bicycle, every input-output pair, to 1e-10."""
    if name == "benchmark":
        par = dict(meijaard2007()["parameters"])
        ours = bikedyn.Bicycle("benchmark")
    else:
        path = REPO / "tests/data" / name
        par = nominal_values(path)
        ours = bikedyn.Bicycle(str(path))
    model = Meijaard2007Model(Meijaard2007ParameterSet(dict(par, v=0.0), True))
    C = np.hstack([np.eye(2), np.zeros((2, 2))])
    inputs, outputs = ["roll_torque", "steer_torque"], ["roll", "steer"]
    for v in (2.0, 5.0, 8.0):
        A, B = model.form_state_space_matrices(v=v)
        r = ours.bode(v, omega_min=0.3, omega_max=30.0, points=9)
        for k, w in enumerate(r.omega):
            G = C @ np.linalg.solve(1j * w * np.eye(4) - A, B)
            for g in r.responses:
                i, j = outputs.index(g.output), inputs.index(g.input)
                assert abs(g.G[k] - G[i, j]) < 1e-10 * abs(G).max(), (name, v, w, g.input, g.output)
