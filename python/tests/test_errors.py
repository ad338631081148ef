"""Bad input raises a Python exception with the command line's message
(file, line, field); nothing reaches Python as a Rust panic."""

import math

import numpy as np
import pytest

import bikedyn
from conftest import meijaard2007


def test_missing_file_is_file_not_found():
    with pytest.raises(FileNotFoundError, match="no-such-bike.toml"):
        bikedyn.Bicycle("no-such-bike.toml")
    with pytest.raises(bikedyn.Error):
        bikedyn.Bicycle("no-such-bike.toml")


def test_bad_parameter_file_names_file_line_and_field(tmp_path):
    text = bikedyn.Bicycle("benchmark").to_toml().replace("mB = 85", "mB = -85")
    assert "mB = -85" in text
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(ValueError) as e:
        bikedyn.Bicycle(str(p))
    assert isinstance(e.value, bikedyn.ParameterError)
    msg = str(e.value)
    assert "bad.toml" in msg and "mB" in msg


def test_impossible_thesis_geometry_is_refused_naming_file_and_field(tmp_path):
    # Issue 35, reproducer 7: x4 = -1 (a steer-axis tilt of 2.83 rad) was
    # accepted by everything but `params show`.
    lines = bikedyn.Bicycle("thesis").to_toml().splitlines()
    lines = ["x4 = -1" if l.startswith("x4 ") else l for l in lines]
    p = tmp_path / "tilted.toml"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(bikedyn.ParameterError) as e:
        bikedyn.Bicycle(str(p))
    msg = str(e.value)
    assert "tilted.toml" in msg and "`x4`" in msg and "tilt" in msg


def test_dict_errors_name_the_key():
    par = dict(meijaard2007()["parameters"])
    del par["IHxz"]
    with pytest.raises(bikedyn.ParameterError, match="IHxz"):
        bikedyn.Bicycle(par)
    par = dict(meijaard2007()["parameters"], w=math.nan)
    with pytest.raises(ValueError, match="`w`"):
        bikedyn.Bicycle(par)
    par = dict(meijaard2007()["parameters"], trail=0.08)
    with pytest.raises(ValueError, match="trail"):
        bikedyn.Bicycle(par)
    par = dict(meijaard2007()["parameters"], c="eight")
    with pytest.raises(ValueError, match="`c`"):
        bikedyn.Bicycle(par)


def test_bad_arguments():
    b = bikedyn.Bicycle("benchmark")
    with pytest.raises(ValueError, match=r"speeds\[1\]"):
        b.eig([1.0, float("nan")])
    with pytest.raises(ValueError, match="no speeds"):
        b.eig([])
    with pytest.raises(bikedyn.InvalidArgumentError):
        b.eig(np.zeros((2, 2)))
    with pytest.raises(bikedyn.ModelError, match="unknown model"):
        bikedyn.Bicycle("benchmark", model="no_such_model")
    with pytest.raises(bikedyn.ParameterError, match="did you mean `c_steer`"):
        b.with_parameter("c_stear", 0.1)
    with pytest.raises(ValueError, match="c_steer"):
        bikedyn.Bicycle("thesis").with_parameter("c_steer", -1.0)
    with pytest.raises(ValueError, match="speed range"):
        b.stability(speed_max=-1)
    with pytest.raises(bikedyn.InvalidArgumentError, match="method"):
        bikedyn.simulate(b, duration=0.1, method="euler-forward-please")
    with pytest.raises(FileNotFoundError, match="nowhere"):
        bikedyn.fit(["nowhere"])


def test_sweep_errors_name_the_design():
    with pytest.raises(bikedyn.ParameterError, match="mB = -1"):
        bikedyn.sweep("benchmark", "mB", [85.0, -1.0], [5.0])


def test_sweep_refuses_the_same_parameter_twice():
    # Issue 35, reproducer 15: every cell took the second value.
    with pytest.raises(bikedyn.InvalidArgumentError, match="param and param2 both name `c`"):
        bikedyn.sweep("benchmark", "c", [0.08, 0.1], [5.0], param2="c", values2=[0.08, 0.1])


def test_with_parameters_checks_values_as_a_file_would():
    # Issue 35, reproducer 22: a wheelbase in millimetres and a boolean
    # mass were taken as they came.
    b = bikedyn.Bicycle("benchmark")
    with pytest.raises(bikedyn.ParameterError, match="millimetres"):
        b.with_parameters(w=1020)
    with pytest.raises(bikedyn.InvalidArgumentError, match="mB"):
        b.with_parameters(mB=True)
    assert b.with_parameters(w=1.05).value("w") == pytest.approx(1.05)
    # A NaN was reported as an unknown parameter ("did you mean `c`?").
    with pytest.raises(bikedyn.ParameterError, match="`c` = NaN is not a finite number"):
        bikedyn.sweep("benchmark", "c", [float("nan")], [5.0])


def test_identify_counts_are_checked_and_named():
    # Issue 35, reproducer 26: folds=2**70 and corrections=-1 were an
    # OverflowError that named no argument.
    for kwargs, name in [
        ({"folds": 2**70}, "folds"),
        ({"folds": 1}, "folds"),
        ({"corrections": -1}, "corrections"),
        ({"max_fits_per_step": 0}, "max_fits_per_step"),
    ]:
        with pytest.raises(bikedyn.InvalidArgumentError, match=name):
            bikedyn.identify("no-such-folder", **kwargs)
    # A table's search fits every candidate: a budget there is refused by
    # name, not ignored.
    with pytest.raises(bikedyn.InvalidArgumentError, match="max_fits_per_step"):
        bikedyn.identify("table.csv", bike="thesis", max_fits_per_step=4)
    # So is the family-wise bar (the table's search has its own bars).
    with pytest.raises(bikedyn.InvalidArgumentError, match="family_wise_bar"):
        bikedyn.identify("table.csv", bike="thesis", family_wise_bar=True)


def test_a_rust_panic_is_an_exception_with_its_message():
    from bikedyn import _bikedyn

    with pytest.raises(bikedyn.InternalError, match="deliberate panic") as e:
        _bikedyn._panic_for_tests()
    assert isinstance(e.value, bikedyn.Error) and isinstance(e.value, RuntimeError)
    # The interpreter goes on.
    assert bikedyn.Bicycle("benchmark").stability().weave_speed > 4


def test_a_result_too_large_for_memory_is_refused_before_computing():
    # Issue 35, reproducer 12: ten million speeds peaked at 11.4 GB and
    # aborted the interpreter under a memory limit. Past a million speeds,
    # or fifty million swept values, the call raises a MemoryError that
    # says to split it, at once.
    b = bikedyn.Bicycle("benchmark")
    many = np.full(1_000_001, 5.0)
    for call in (b.eig, b.eigenvalues):
        with pytest.raises(MemoryError) as e:
            call(many)
        assert isinstance(e.value, bikedyn.TooLargeError)
        assert "1000001 speeds" in str(e.value) and "split" in str(e.value)
    grid = np.linspace(0.0, 0.2, 1000)
    with pytest.raises(bikedyn.TooLargeError, match="more than the 50000000"):
        bikedyn.sweep(b, "c", grid, np.linspace(1.0, 8.0, 100), param2="lam", values2=np.linspace(0.2, 0.4, 1000))
    # At the limit, a call still answers.
    assert b.eigenvalues(np.full(1000, 5.0)).shape[0] == 1000
