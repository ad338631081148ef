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


# J. K. Moore's (2012) leaning-rider set, bicycleparameters'
# MooreRiderLean2012ParameterSet: its dict given to bikedyn.Bicycle as it is,
# converted to the benchmark form and the rider_lean model's rider, against
# the eigenvalues of MooreRiderLean2012Model (Moore's own Autolev equations)
# restricted to roll, steer, lean and their rates (q4, q7, q9, u4, u7, u9: the
# yaw, positions and wheel angles do not enter them).
MOORE_LATERAL = [3, 5, 7, 8, 10, 11]


def moore_rider_lean():
    try:
        from bicycleparameters.models import MooreRiderLean2012Model
        from bicycleparameters.parameter_dicts import mooreriderlean2012_browser_jason
        from bicycleparameters.parameter_sets import MooreRiderLean2012ParameterSet
    except ImportError:
        pytest.skip("this bicycleparameters has no MooreRiderLean2012Model")
    return MooreRiderLean2012Model, MooreRiderLean2012ParameterSet, mooreriderlean2012_browser_jason


def moore_eigenvalues(par, speeds):
    Model, ParameterSet, _ = moore_rider_lean()
    model = Model(ParameterSet(dict(par)))
    out = []
    for v in speeds:
        A, _B = model.form_state_space_matrices(v=float(v))
        out.append(np.linalg.eigvals(A[np.ix_(MOORE_LATERAL, MOORE_LATERAL)]))
    return out


def largest_relative_difference(ours, par, speeds):
    e = ours.eig(speeds)
    theirs = moore_eigenvalues(par, speeds)
    worst = 0.0
    for i in range(len(speeds)):
        a = np.sort_complex(np.round(e.eigenvalues[i], 12))  # the four modes and the rider's
        b = np.sort_complex(np.round(theirs[i], 12))
        assert len(a) == len(b) == 6, (speeds[i], a, b)
        worst = max(worst, np.abs(a - b).max() / max(1.0, np.abs(b).max()))
    return worst


@pytest.mark.parametrize(
    "changes",
    [
        {},  # as bicycleparameters ships it: no lean stiffness nor damping
        {"k9": 128.0, "c9": 50.0},  # the dissertation's stiff and damped rider
        {"k9": 1000.0, "c9": 10.0},
        # A rider whose every key matters: an upper body with a large
        # product of inertia, its mass centre farther ahead, a lower axis.
        {"ig31": 0.4, "l5": 0.15, "d4": -0.8, "k9": 300.0, "c9": 20.0},
    ],
)
def test_moore_rider_lean_dict_agrees_with_moore_rider_lean_2012_model(changes):
    _, _, browser_jason = moore_rider_lean()
    par = dict(browser_jason, **changes)
    ours = bikedyn.Bicycle(par, name="Moore rider lean")
    assert ours.model == "rider_lean"
    speeds = np.array([0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0])
    worst = largest_relative_difference(ours, par, speeds)
    assert worst < 1e-10, (changes, worst)


def test_moore_rider_lean_file_agrees_with_moore_rider_lean_2012_model():
    """The committed text file (tests/data/MooreRiderLean2012BrowserJason.txt:
    bicycleparameters' set with the dissertation's k9 = 128, c9 = 50)."""
    _, _, browser_jason = moore_rider_lean()
    par = dict(browser_jason, k9=128.0, c9=50.0)
    ours = bikedyn.Bicycle(str(REPO / "tests/data/MooreRiderLean2012BrowserJason.txt"))
    assert ours.model == "rider_lean"
    assert largest_relative_difference(ours, par, np.linspace(0.5, 10.0, 20)) < 1e-10


def test_moore_rider_lean_dict_with_a_sign_turned_disagrees():
    """The comparison can fail: the rider's product of inertia given with
    the other sign (as if Moore's z-down entry were bikedyn's z-up one)
    moves the eigenvalues far beyond the tolerance."""
    _, _, browser_jason = moore_rider_lean()
    par = dict(browser_jason, ig31=0.4, k9=300.0, c9=20.0)
    ours = bikedyn.Bicycle(par)
    wrong = bikedyn.Bicycle({k: ours.value(k) for k in SYMBOLS} | {
        k: ours.value(k) for k in ("xL", "zL", "x6", "z6", "m6", "I6x", "I6y", "I6z", "k_lean", "c_lean")
    } | {"I6xz": -ours.value("I6xz")})
    assert wrong.model == "rider_lean"
    assert largest_relative_difference(wrong, par, np.array([2.0, 5.0])) > 1e-3
