"""The measured-run pipeline from Python: fit and identify on the
committed example set (six runs of the thesis bicycle with steer damping
0.25 N m s/rad hidden, examples/data/README.md), and identification from a
table of measured eigenvalues."""

import json

import numpy as np
import pytest

import bikedyn
from conftest import REPO

SET = REPO / "examples/data/hidden_steer_damping"


def test_fit_returns_the_kicks_and_writes_plots(tmp_path):
    r = bikedyn.fit(SET, bike="thesis")
    assert len(r.kicks) >= 6
    assert r.skipped == ()
    assert r.prediction_model
    truth = json.loads((SET / "truth/run01_truth.json").read_text())
    assert truth  # the runs were made at 4 to 6.5 m/s
    for k in r.kicks:
        assert 3.5 < k.mean_speed < 7.0, k
    d = r.to_dict()
    assert set(d) >= {"kicks", "skipped", "calibration", "prediction_model"}
    r.write_report(tmp_path / "fit")
    assert (tmp_path / "fit/kicks.json").is_file()
    assert any(p.suffix == ".svg" for p in (tmp_path / "fit").iterdir())


def test_fit_of_what_holds_no_kick_raises_with_the_reason():
    # /dev/zero is no run, log or set: nothing is fitted, and the reason is
    # the error (as `bikedyn fit` exits 1), not an empty result.
    with pytest.raises(bikedyn.DataError, match="/dev/zero"):
        bikedyn.fit("/dev/zero", bike="thesis")


def test_fit_reports_progress_and_raises_the_callbacks_exception():
    seen = []
    bikedyn.fit(SET, progress=lambda step, done, total: seen.append((step, done, total)))
    runs = len([p for p in SET.iterdir() if p.name.startswith("run")])
    # Runs are processed in parallel: the counts arrive in any order.
    assert sorted(d for _, d, _ in seen) == list(range(1, runs + 1)), seen
    assert all(t == runs for _, _, t in seen), seen

    calls = []

    def failing(step, done, total):
        calls.append(done)
        raise KeyError("stop")

    with pytest.raises(KeyError):
        bikedyn.fit(SET, progress=failing)
    assert len(calls) == 1, "no call after the exception"


def test_identify_finds_the_hidden_steer_damping(tmp_path):
    seen = []
    r = bikedyn.identify(
        SET,
        bike="thesis",
        effects=["steer_damping"],
        corrections=0,
        progress=lambda step, done, total: seen.append((step, done, total)),
    )
    assert r.selected_effects == ("steer_damping",), r.summary()
    # Each stage counts from 1; the fitted candidate is among the steps.
    assert seen and all(isinstance(s, str) and d >= 1 for s, d, _ in seen), seen
    assert any("steer_damping" in s for s, _, _ in seen), seen
    assert "steer_damping" in r.summary()
    r.write_report(tmp_path / "report")
    assert (tmp_path / "report/report.md").is_file()
    assert json.loads((tmp_path / "report/report.json").read_text())["selected_effects"] == ["steer_damping"]


def test_identify_from_a_measured_eigenvalue_table(tmp_path):
    # The thesis bicycle with c_steer = 0.3 N m s/rad: its weave at nine
    # speeds, perturbed by a fixed +-0.05 1/s, in the authors' own words.
    speeds = np.arange(3.0, 7.01, 0.5)
    weave = bikedyn.Bicycle("thesis").with_parameter("c_steer", 0.3).eig(speeds).mode("weave")
    lines = ["Geschwindigkeit [m/s]; Realteil; Imaginaerteil; sigma Re; sigma Im"]
    for k, (v, z) in enumerate(zip(speeds, weave)):
        d = 0.05 if k % 2 == 0 else -0.05
        lines.append(f"{v}; {z.real + d:.4f}; {z.imag - d:.4f}; 0.05; 0.05")
    table = tmp_path / "weave.csv"
    table.write_text("\n".join(lines) + "\n")
    r = bikedyn.identify(table, bike="thesis")
    assert r.selected == ("steer_damping",), r.summary()
    assert r.parameters["c_steer"].value == pytest.approx(0.3, abs=0.015)
    r.write_report(tmp_path / "table-report")
    assert any((tmp_path / "table-report").iterdir())
    # After the library, the dictionary of generalized forces: steer
    # damping explains the table, so no structured residual is left and
    # the search does not run; discover=False skips it outright.
    assert r.discovery.status == "not_run", r.summary()
    assert "discovery beyond the library not run: the library leaves no structured residual" in r.summary()
    assert bikedyn.identify(table, bike="thesis", discover=False).discovery is None
