"""Results are Python: frozen dataclasses with every field of the command
line's JSON, NumPy arrays for sampled quantities, Python complex numbers
for eigenvalues (never ``[re, im]`` lists), and one sign convention for
roll and steer (the benchmark's) beside the models' own columns."""

import dataclasses
import pathlib
import re

import numpy as np
import pytest

import bikedyn
from conftest import REPO

BALANCE_ASSIST = REPO / "tests/data/Balanceassistv1Benchmark.txt"
SET = REPO / "examples/data/hidden_steer_damping"


def fields(obj):
    return {f.name for f in dataclasses.fields(obj)}


def assert_frozen(obj):
    name = dataclasses.fields(obj)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(obj, name, None)


def assert_no_pair_lists(x, where="result"):
    """No ``[re, im]``-like list of two numbers anywhere in a typed result,
    and every eigenvalue-like field complex."""
    if dataclasses.is_dataclass(x):
        for f in dataclasses.fields(x):
            assert_no_pair_lists(getattr(x, f.name), f"{where}.{f.name}")
    elif isinstance(x, list):
        raise AssertionError(f"{where} is a list: {x!r}")
    elif isinstance(x, tuple):
        for i, v in enumerate(x):
            assert_no_pair_lists(v, f"{where}[{i}]")
    if re.search(r"(eigenvalue|weave|speed_derivative|scaled|slope_per_mps)$", where) and x is not None:
        if not dataclasses.is_dataclass(x) and not isinstance(x, (tuple, str)):
            assert isinstance(x, complex), f"{where} = {x!r} is not complex"


# --------------------------------------------------------------------------
# stability


def test_stability_returns_typed_speeds():
    s = bikedyn.Bicycle("benchmark").stability()
    assert isinstance(s, bikedyn.Stability)
    assert_frozen(s)
    assert isinstance(s.weave_speed, float) and isinstance(s.capsize_speed, float)
    assert isinstance(s.weave_real_pair_merge_speed, float)
    assert s.model == "whipple_offset" and s.bike == "benchmark"
    assert isinstance(s.stable_intervals, tuple)
    assert all(isinstance(i, tuple) and len(i) == 2 and all(isinstance(x, float) for x in i) for i in s.stable_intervals)
    assert isinstance(s.crossings, tuple) and all(isinstance(c, bikedyn.Crossing) for c in s.crossings)
    weave = next(c for c in s.crossings if c.mode == "weave")
    assert weave.speed == s.weave_speed and weave.direction == "stabilizing" and weave.kind == "complex_pair"
    # The weave's frequency at its crossing (rad/s) is the eigenvalue's
    # imaginary part there.
    assert weave.frequency == pytest.approx(bikedyn.Bicycle("benchmark").eig([s.weave_speed]).mode("weave")[0].imag, rel=1e-6)
    assert s.is_stable_at(5.0) and not s.is_stable_at(3.0)
    # Without +/- values the uncertainty fields are None.
    assert s.weave_speed_sd is None and s.uncertainty is None and s.monte_carlo is None
    assert_no_pair_lists(s)


def test_stability_keeps_every_field_of_the_json():
    b = bikedyn.Bicycle(str(BALANCE_ASSIST))
    s = b.stability(monte_carlo=20, seed=3)
    d = s.to_dict()
    assert set(d) <= fields(s), set(d) - fields(s)
    assert set(d["uncertainty"]) <= fields(s.uncertainty)
    assert set(d["uncertainty"]["weave_speed"]) <= fields(s.uncertainty.weave_speed)
    assert set(d["monte_carlo"]) <= fields(s.monte_carlo)
    assert set(d["monte_carlo"]["capsize_speed"]) <= fields(s.monte_carlo.capsize_speed)
    assert set(d["crossings"][0]) <= fields(s.crossings[0])
    # The values are the JSON's.
    assert s.weave_speed_sd == d["weave_speed_sd"] and s.capsize_speed_sd == d["capsize_speed_sd"]
    u = s.uncertainty.capsize_speed
    assert isinstance(u, bikedyn.SpeedUncertainty) and u.standard_deviation == s.capsize_speed_sd
    assert all(isinstance(x, bikedyn.VarianceShare) for x in u.shares)
    assert [x.parameter for x in u.shares] == [x["parameter"] for x in d["uncertainty"]["capsize_speed"]["shares"]]
    m = s.monte_carlo
    assert isinstance(m, bikedyn.MonteCarlo) and m.draws == 20 and m.seed == 3
    assert isinstance(m.weave_speed, bikedyn.SampledSpeed) and isinstance(m.weave_speed.draws, int)
    assert m.weave_speed.mean == d["monte_carlo"]["weave_speed"]["mean"]


# --------------------------------------------------------------------------
# canonical, sensitivity, bode


def test_canonical_returns_arrays_and_their_standard_deviations():
    c = bikedyn.Bicycle(str(BALANCE_ASSIST)).canonical()
    assert isinstance(c, bikedyn.Canonical)
    assert_frozen(c)
    for name in ("M", "C1", "K0", "K2"):
        m = getattr(c, name)
        assert isinstance(m, np.ndarray) and m.shape == (2, 2) and m.dtype == float
        sd = getattr(c.standard_deviations, name)
        assert isinstance(sd, np.ndarray) and sd.shape == (2, 2) and np.all(sd >= 0)
    assert c.M0 is c.M and c.standard_deviations.M0 is c.standard_deviations.M
    assert c.standard_deviations.M.max() > 0
    # The canonical form gives the state matrix of state_space.
    v = 4.0
    A, _ = bikedyn.Bicycle(str(BALANCE_ASSIST)).state_space([v])
    Mi = np.linalg.inv(c.M)
    assert np.allclose(A[0][2:, :2], -Mi @ c.stiffness(v), rtol=1e-9, atol=1e-9)
    assert np.allclose(A[0][2:, 2:], -Mi @ c.damping(v), rtol=1e-9, atol=1e-9)


def test_sensitivity_gives_complex_eigenvalues_and_their_derivatives():
    b = bikedyn.Bicycle("benchmark")
    s = b.sensitivity(speed=5.0)
    assert isinstance(s, bikedyn.Sensitivity)
    assert_frozen(s)
    assert set(s.to_dict()) <= fields(s)
    assert isinstance(s.weave_speed, bikedyn.CriticalSpeedSensitivity)
    assert isinstance(s.weave_speed.eigenvalue, complex)
    assert abs(s.weave_speed.eigenvalue.real) < 1e-9 and s.weave_speed.eigenvalue.imag > 3
    weave = next(m for m in s.eigenvalues.modes if m.mode == "weave")
    assert isinstance(weave, bikedyn.ModeSensitivity)
    assert weave.eigenvalue == pytest.approx(b.eig([5.0]).mode("weave")[0], abs=1e-10)
    assert isinstance(weave.speed_derivative, complex)
    d = weave.derivatives[0]
    assert isinstance(d, bikedyn.EigenvalueDerivative)
    assert isinstance(d.derivative, complex) and isinstance(d.scaled, complex)
    assert d.scaled == pytest.approx(d.value * d.derivative, rel=1e-12)
    # The derivative with respect to the parameter, by central differences.
    h = 1e-6 * d.value
    up = b.with_parameter(d.parameter, d.value + h).eig([5.0]).mode("weave")[0]
    down = b.with_parameter(d.parameter, d.value - h).eig([5.0]).mode("weave")[0]
    assert abs((up - down) / (2 * h) - d.derivative) < 1e-5 * abs(d.derivative)
    assert_no_pair_lists(s)


def test_bode_gives_a_complex_array_per_response():
    r = bikedyn.Bicycle("benchmark").bode(5.0, omega_min=0.5, omega_max=20.0, points=7)
    assert isinstance(r, bikedyn.Bode)
    assert_frozen(r)
    assert r.speed == 5.0 and r.stable is True and isinstance(r.units, str)
    assert isinstance(r.omega, np.ndarray) and r.omega.shape == (7,)
    assert len(r.responses) == 4
    for g in r.responses:
        assert isinstance(g, bikedyn.BodeResponse)
        assert g.G.dtype == complex and g.G.shape == (7,)
        assert np.allclose(g.magnitude_db, 20 * np.log10(np.abs(g.G)), atol=1e-9)
        assert isinstance(g.static_gain, float)
    G = r.G
    assert G.shape == (7, 2, 2) and G.dtype == complex
    assert np.array_equal(G[:, 0, 1], r.response("steer_torque", "roll").G)
    with pytest.raises(KeyError):
        r.response("roll", "steer_torque")
    # The JSON's re and im are the complex G.
    d = r.to_dict()
    assert np.array_equal(np.array(d["responses"][1]["re"]) + 1j * np.array(d["responses"][1]["im"]), r.responses[1].G)


# --------------------------------------------------------------------------
# fit and identify


def test_fit_kicks_have_complex_eigenvalues():
    r = bikedyn.fit(SET, bike="thesis")
    assert isinstance(r, bikedyn.FitResult)
    assert_frozen(r)
    assert isinstance(r.kicks, tuple) and len(r.kicks) >= 6
    d = r.to_dict()
    assert set(d) <= fields(r)
    for k, raw in zip(r.kicks, d["kicks"]):
        assert isinstance(k, bikedyn.Kick)
        # Every field of the kick's JSON record is there (the prediction
        # split into the complex value and its ranges).
        assert set(raw) - {"predicted_weave"} <= fields(k), set(raw) - fields(k)
        assert isinstance(k.weave, complex)
        assert k.weave == complex(*raw["weave"])
        assert isinstance(k.weave_stderr, tuple) and all(x > 0 for x in k.weave_stderr)
        assert 0.9 < k.r2 <= 1.0
        assert isinstance(k.predicted_weave, complex)
        assert k.predicted_weave == complex(*raw["predicted_weave"]["at_mean_speed"])
        lo, hi = k.predicted_imag_range
        assert lo <= k.predicted_weave.imag <= hi
        assert k.speed == k.mean_speed and 3.5 < k.speed < 7.0
        assert k.run.startswith(str(SET))
        assert all(isinstance(f, bikedyn.FormFit) and isinstance(f.eigenvalue, complex) for f in k.fits)
        assert k.weave in [f.eigenvalue for f in k.fits]
        assert k.refused is None
        assert_no_pair_lists(k, "kick")
    speeds, weave = r.weave_eigenvalues()
    assert weave.dtype == complex and speeds.shape == weave.shape == (len(r.kicks),)
    # Steer damping hidden in the runs: the measured weave is more damped
    # than the undamped thesis bicycle predicts.
    assert np.all(weave.real < np.array([k.predicted_weave.real for k in r.kicks]))


def test_identify_gives_estimates_with_their_95_percent_interval_and_the_errors():
    r = bikedyn.identify(SET, bike="thesis", effects=["steer_damping"], corrections=0)
    assert isinstance(r, bikedyn.IdentifyResult)
    assert_frozen(r)
    assert r.source == "runs" and r.selected == ("steer_damping",) and r.selected_effects == r.selected
    c = r.parameters["c_steer"]
    assert isinstance(c, bikedyn.Estimate)
    assert c.value == pytest.approx(0.25, abs=0.01) and c.unit == "N m s/rad"
    # The interval is 95 %: value +- 1.96 standard errors.
    assert c.confidence == 0.95
    assert c.low == pytest.approx(c.value - 1.96 * c.stderr, rel=1e-12)
    assert c.high == pytest.approx(c.value + 1.96 * c.stderr, rel=1e-12)
    b, a = r.error_before, r.error_after
    assert isinstance(b, bikedyn.Errors) and isinstance(a.held_out, bikedyn.Errors)
    assert a.eigen_rms < 0.5 * b.eigen_rms and a.held_out.eigen_rms < 0.5 * b.eigen_rms
    assert a.roll_rms < b.roll_rms and a.steer_rms < b.steer_rms
    assert r.roll_channel == "angle" and r.kicks == 6 and r.skipped == ()
    # The values are the JSON's, which keeps everything else.
    d = r.to_dict()
    assert d["error_after"]["eigen_rms"] == a.eigen_rms
    assert d["parameters"]["c_steer"]["high"] == c.high
    assert {"candidates", "findings", "remaining", "state_correlation"} <= set(d)
    assert isinstance(r.discovery, bikedyn.Discovery) and not r.discovery.ran
    assert r.discovery.reason and r.discovery.terms == ()
    assert isinstance(r.time_series_discovery, bikedyn.Discovery)
    assert f"{c.value:.4f}" in r.summary()


def test_identify_from_a_table_discovers_a_typed_term(tmp_path):
    # The thesis bicycle with a steer inertia added that no library effect
    # or correction expresses (as tests/identification/discovery.rs): its
    # weave from the canonical matrices, with seeded scatter of 0.03 1/s.
    bike = bikedyn.Bicycle("thesis")
    c = bike.canonical()
    added = 0.3 * c.M[1, 1]
    M = c.M.copy()
    M[1, 1] += added
    rng = np.random.default_rng(21)
    lines = ["speed,re,im,sd_re,sd_im"]
    for v in np.arange(3.0, 7.01, 0.5):
        Mi = np.linalg.inv(M)
        A = np.block([[np.zeros((2, 2)), np.eye(2)], [-Mi @ c.stiffness(v), -Mi @ c.damping(v)]])
        z = max(np.linalg.eigvals(A), key=lambda z: z.imag)
        e = rng.uniform(-0.5, 0.5, 2) * 0.03 * np.sqrt(12)
        lines.append(f"{v},{z.real + e[0]:.5f},{z.imag + e[1]:.5f},0.03,0.03")
    table = tmp_path / "inertia.csv"
    table.write_text("\n".join(lines) + "\n")
    r = bikedyn.identify(table, bike="thesis", corrections=0)
    assert r.source == "eigenvalue_table" and r.rows == 9 and r.table == str(table)
    assert r.kicks is None and r.roll_channel is None
    d = r.discovery
    assert isinstance(d, bikedyn.Discovery) and d.ran, r.summary()
    t = d.terms[0]
    assert isinstance(t, bikedyn.DiscoveredTerm)
    assert (t.equation, t.signal, t.of, t.speed_power, t.lagged) == ("steer", "acceleration", "steer", 0, False)
    assert t.name == "steer_torque_steer_acceleration" and t.unit == "kg m^2"
    # The term is `theta delta''` on the right: an added inertia is -theta.
    assert -t.coefficient == pytest.approx(added, rel=0.25)
    assert t.coefficient_stderr > 0 and t.time_constant is None
    assert d.rms_held_out <= 0.5 * r.error_before.eigen_rms
    assert len(d.readings) == len(d.terms)
    # The table's estimates carry the same 95 % interval as the runs'.
    for e in r.parameters.values():
        assert e.high - e.value == pytest.approx(1.96 * e.stderr, rel=1e-12)
    assert r.error_after.held_out.eigen_rms == r.to_dict()["error_after"]["held_out"]["eigen_rms"]


# --------------------------------------------------------------------------
# simulation signs


def test_simulation_offers_benchmark_roll_and_steer_with_signs_of_eig():
    # A small roll to the right at 5 m/s (self-stable): the benchmark
    # bicycle steers into the fall, to the right: positive steer in the
    # benchmark's signs, negative gamma in the model's (steer positive to
    # the left).
    bike = bikedyn.Bicycle("benchmark")
    roll0, v = 1e-3, 5.0
    sim = bikedyn.simulate(bike, duration=2.0, speed=v, roll=roll0, dt=0.02)
    assert sim.roles["roll"] == "theta" and sim.roles["steer"] == "gamma"
    assert np.array_equal(sim.roll, sim["theta"]) and np.array_equal(sim.roll_rate, sim["dtheta"])
    assert np.array_equal(sim.steer, -sim["gamma"]) and np.array_equal(sim.steer_rate, -sim["dgamma"])
    assert np.array_equal(sim.coordinate("steer"), sim["gamma"])
    assert np.array_equal(sim.t, sim["t"])
    assert sim.roll[0] == roll0
    early = (sim.t > 0) & (sim.t < 0.3)
    assert np.all(sim.steer[early] > 0) and np.all(sim["gamma"][early] < 0)
    # The linear motion from eig's eigenvalues and eigenvectors (benchmark
    # signs): x(t) = V exp(L t) V^-1 x0 over [roll, steer, roll rate,
    # steer rate]; the nonlinear run follows it to a few parts in 1e3.
    e = bike.eig([v])
    V, L = e.eigenvectors[0], e.eigenvalues[0]
    c = np.linalg.solve(V, np.array([roll0, 0.0, 0.0, 0.0]))
    lin = np.array([(V @ (c * np.exp(L * t))).real for t in sim.t])
    for k, x in enumerate([sim.roll, sim.steer, sim.roll_rate, sim.steer_rate]):
        scale = np.abs(lin[:, k]).max()
        assert np.abs(x - lin[:, k]).max() < 5e-3 * scale, k
    # The model's own steer column is the other sign.
    assert np.abs(sim["gamma"] + lin[:, 1]).max() < 5e-3 * np.abs(lin[:, 1]).max()


def test_simulate_takes_its_initial_steer_in_the_models_signs():
    # The inputs are the command line's (`--steer`, positive turning
    # left); the benchmark-sign steer reads minus it.
    sim = bikedyn.simulate("thesis", duration=0.1, speed=5.0, steer=0.01)
    assert sim.roles["steer"] == "gamma"
    assert sim["gamma"][0] == pytest.approx(0.01) and sim.steer[0] == pytest.approx(-0.01)


# --------------------------------------------------------------------------
# the package


def test_every_result_class_is_exported_frozen_and_documents_each_field_with_units():
    from bikedyn import results

    for name in results.__all__:
        cls = getattr(bikedyn, name)
        assert name in bikedyn.__all__, name
        assert dataclasses.is_dataclass(cls), name
        assert cls.__dataclass_params__.frozen, name
        doc = cls.__doc__ or ""
        assert "Attributes:" in doc, name
        attrs = doc.split("Attributes:", 1)[1]
        for f in dataclasses.fields(cls):
            assert re.search(rf"^\s+{f.name}: \S", attrs, re.M), f"{name}.{f.name} is not documented"
        # Complete annotations: every field has a type.
        assert all(f.type is not None for f in dataclasses.fields(cls)), name


def test_results_compare_by_value():
    a = bikedyn.Bicycle("benchmark").stability()
    b = bikedyn.Bicycle("benchmark").stability()
    assert a == b and a is not b
    assert a != bikedyn.Bicycle("benchmark").stability(speed_max=5)


def test_source_tree_ships_the_typed_marker():
    assert (pathlib.Path(bikedyn.__file__).parent / "py.typed").is_file()


def test_dict_access_of_the_former_dicts_still_works_with_a_deprecation_warning():
    # As docs/design-questions.md's example was written for the dicts.
    b = bikedyn.Bicycle("benchmark")
    with pytest.warns(DeprecationWarning) as seen:
        top = [(d["parameter"], d["elasticity"]) for d in b.sensitivity(speed=5.0)["capsize_speed"]["derivatives"][:3]]
        r = b.bode(5.0, points=5)
        assert np.array_equal(r["responses"][3]["G"], r.responses[3].G)
        assert b.stability()["weave_speed"] == b.stability().weave_speed
        assert np.array_equal(b.canonical()["M0"], b.canonical().M)
        with pytest.raises(KeyError):
            b.stability()["no_such_field"]
    first = b.sensitivity().capsize_speed.derivatives[0]
    assert top[0] == (first.parameter, first.elasticity)
    assert "use .capsize_speed" in str(seen[0].message)
    assert all(w.category is DeprecationWarning for w in seen)
