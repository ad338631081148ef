"""Linear analysis from Python against the published benchmark
(Meijaard et al. 2007, Proc. R. Soc. A 463:1955-1982, Tables 1-2 and
section 5.3), and invariants that tie the arrays together."""

import numpy as np
import pytest

import bikedyn
from conftest import meijaard2007


def test_canonical_matrices_match_the_paper():
    ref = meijaard2007()["canonical"]
    c = bikedyn.Bicycle("benchmark").canonical()
    for key in ["M", "C1", "K0", "K2"]:
        want = np.array(ref[key])
        scale = np.abs(want).max()
        got = getattr(c, key)
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12 * scale), (key, got, want)
    assert isinstance(c.model, str)


def test_stability_gives_the_published_speeds():
    ref = meijaard2007()["critical_speeds"]
    s = bikedyn.Bicycle("benchmark").stability(speed_max=10)
    assert abs(s.weave_speed - ref["weave_speed"]) < 1e-10
    assert abs(s.capsize_speed - ref["capsize_speed"]) < 1e-10
    assert abs(s.weave_real_pair_merge_speed - ref["weave_real_pair_merge"]) < 1e-8
    assert s.stable_intervals[0][0] == pytest.approx(ref["weave_speed"], abs=1e-10)
    assert {c.mode for c in s.crossings} >= {"weave", "capsize"}
    # Out of range: None, as the command line's JSON has null.
    assert bikedyn.Bicycle("benchmark").stability(speed_max=3).weave_speed is None


def test_eig_gives_table2_and_labels_the_modes():
    ref = meijaard2007()
    rows = [r for r in ref["eigenvalues"] if "weave" in r]
    speeds = np.array([r["v"] for r in rows])
    e = bikedyn.Bicycle("benchmark").eig(speeds)
    assert e.eigenvalues.shape == (len(speeds), 4) and e.eigenvalues.dtype == complex
    assert e.modes.shape == (len(speeds), 4)
    assert e.eigenvectors.shape == (len(speeds), 4, 4)
    weave = e.mode("weave")
    for i, r in enumerate(rows):
        re, im = r["weave"]
        assert abs(weave[i] - complex(re, im)) < 1e-10, (r["v"], weave[i])
        cap = e.eigenvalues[i, e.modes[i] == "capsize"]
        assert abs(cap[0].real - r["capsize"]) < 1e-10


def test_eigenvectors_are_right_eigenvectors_of_the_state_matrix():
    bike = bikedyn.Bicycle("benchmark")
    speeds = np.linspace(0.5, 9.5, 7)
    A, B = bike.state_space(speeds)
    assert A.shape == (7, 4, 4) and B.shape == (7, 4, 2)
    e = bike.eig(speeds)
    for i in range(len(speeds)):
        for j in range(4):
            v = e.eigenvectors[i, :, j]
            lam = e.eigenvalues[i, j]
            assert np.linalg.norm(A[i] @ v - lam * v) < 1e-8 * max(1, abs(lam)) * np.linalg.norm(v)
        # The eigenvalues of A are those of eig.
        assert np.allclose(np.sort_complex(np.linalg.eigvals(A[i])), np.sort_complex(e.eigenvalues[i]), atol=1e-9)
    # B is [0; M0^-1] (inputs roll and steer torque).
    m0 = bike.canonical().M
    assert np.allclose(B[0, 2:], np.linalg.inv(m0), rtol=1e-12)
    assert np.all(B[:, :2] == 0)


def test_a_dict_bicycle_is_the_file_bicycle():
    # The dict of bicycleparameters' Meijaard2007ParameterSet: Table 1
    # symbols plus the speed v, which is no bicycle parameter.
    par = dict(meijaard2007()["parameters"])
    par["v"] = 5.0
    a = bikedyn.Bicycle(par, name="Meijaard2007ParameterSet")
    b = bikedyn.Bicycle("benchmark")
    v = np.linspace(0, 10, 41)
    assert np.array_equal(a.eig(v).eigenvalues, b.eig(v).eigenvalues)
    assert a.form == "benchmark" and a.parameters["mB"] == 85.0
    # Thesis symbols make a thesis-form bicycle with the same dynamics.
    t = bikedyn.Bicycle("thesis")
    t2 = bikedyn.Bicycle(t.parameters, name="thesis dict")
    assert t2.form == "thesis"
    assert np.array_equal(t.eig(v).eigenvalues, t2.eig(v).eigenvalues)


def test_uncertainties_of_ufloats_are_kept():
    class UFloat:  # what `uncertainties.ufloat` offers
        def __init__(self, n, s):
            self.nominal_value, self.std_dev = n, s

    par = dict(meijaard2007()["parameters"])
    par["c"] = UFloat(0.08, 0.002)
    b = bikedyn.Bicycle(par)
    assert b.uncertainties == {"c": 0.002}
    assert b.value("c") == 0.08


def test_effects_and_models():
    names = [m["name"] for m in bikedyn.models()]
    assert len(names) >= 3
    bike = bikedyn.Bicycle("thesis").with_parameter("c_steer", 0.3)
    assert bike.model != bikedyn.Bicycle("thesis").model
    # Steer damping stabilises the weave at a lower speed (Sharp 2008;
    # it is the premise of the damping tests of the Rust suite).
    assert bike.stability().weave_speed != bikedyn.Bicycle("thesis").stability().weave_speed
    with pytest.raises(bikedyn.ModelError, match="canonical"):
        bike.canonical()
    # Without a canonical form, eig and state_space still work.
    e = bike.eig([3.0, 5.0])
    A, B = bike.state_space([3.0, 5.0])
    for i in range(2):
        assert np.allclose(np.sort_complex(np.linalg.eigvals(A[i])), np.sort_complex(e.eigenvalues[i]), atol=1e-8)


def test_geometry_names_the_benchmark_trail():
    g = bikedyn.Bicycle("benchmark").geometry()
    assert g["c"] == pytest.approx(0.08, abs=1e-12)
    assert g["w"] == pytest.approx(1.02, abs=1e-12)
    assert "mT" in g


def test_the_fast_eigenvalues_are_eigs_sorted():
    for bike in [bikedyn.Bicycle("benchmark"), bikedyn.Bicycle("thesis").with_parameter("c_steer", 0.2)]:
        v = np.linspace(-2.0, 12.0, 3001)
        fast = bike.eigenvalues(v)
        full = bike.eig(v).eigenvalues
        assert fast.shape == full.shape
        for i in range(len(v)):
            assert np.allclose(np.sort_complex(fast[i]), np.sort_complex(full[i]), atol=1e-9)
            assert np.all(np.diff(fast[i].real) <= 0)


def test_sensitivity_is_exact_and_ranked():
    s = bikedyn.Bicycle("benchmark").sensitivity(speed=5.0)
    assert s.parameter_form == "benchmark"
    w = s.weave_speed
    assert abs(w.speed - meijaard2007()["critical_speeds"]["weave_speed"]) < 1e-10
    e = [d.elasticity for d in w.derivatives]
    assert len(e) == 26 and all(abs(a) >= abs(b) for a, b in zip(e, e[1:]))
    # A speed scales as sqrt(g L): its elasticity to g is 1/2 exactly.
    assert s.capsize_speed.derivative("g").elasticity == pytest.approx(0.5, abs=1e-12)
    assert [m.mode for m in s.eigenvalues.modes] == ["weave", "capsize", "castering"]
    assert bikedyn.Bicycle("thesis").sensitivity().parameter_form == "thesis"
    assert bikedyn.Bicycle("thesis").sensitivity(form="benchmark").parameter_form == "benchmark"


def test_sensitivity_refuses_what_it_cannot_differentiate():
    with pytest.raises(bikedyn.ModelError, match="canonical form"):
        bikedyn.Bicycle("benchmark").with_parameters(c_steer=0.3).sensitivity()
    with pytest.raises(bikedyn.InvalidArgumentError, match="no weave or capsize crossing"):
        bikedyn.Bicycle("benchmark").sensitivity(speed_max=1.0)
    with pytest.raises(bikedyn.InvalidArgumentError):
        bikedyn.Bicycle("benchmark").sensitivity(form="metric")


def test_bode_equals_the_state_space_transfer_function():
    b = bikedyn.Bicycle("benchmark")
    r = b.bode(5.0, omega_min=0.5, omega_max=20.0, points=7)
    A, B = b.state_space([5.0])
    A, B = A[0], B[0]
    C = np.hstack([np.eye(2), np.zeros((2, 2))])
    inputs, outputs = ["roll_torque", "steer_torque"], ["roll", "steer"]
    for k, w in enumerate(r.omega):
        G = C @ np.linalg.solve(1j * w * np.eye(4) - A, B)
        for g in r.responses:
            i, j = outputs.index(g.output), inputs.index(g.input)
            assert abs(g.G[k] - G[i, j]) < 1e-10 * abs(G).max()
    for g in r.responses:
        i, j = outputs.index(g.output), inputs.index(g.input)
        assert g.static_gain == pytest.approx((-C @ np.linalg.solve(A, B))[i, j], rel=1e-10)
    with pytest.raises(bikedyn.InvalidArgumentError):
        b.bode(float("nan"))


def test_stability_gives_standard_deviations_from_a_files_uncertainties(tmp_path):
    import pathlib
    src = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "Balanceassistv1Benchmark.txt"
    s = bikedyn.Bicycle(str(src)).stability()
    assert s.weave_speed_sd > 0 and s.capsize_speed_sd > 0
    shares = s.uncertainty.weave_speed.shares
    assert abs(sum(x.share for x in shares) - 1) < 1e-12
    plain = bikedyn.Bicycle("benchmark").stability()
    assert plain.weave_speed_sd is None and plain.uncertainty is None
    # As the command line's JSON: no key at all without +/- values.
    assert "weave_speed_sd" not in plain.to_dict()


def test_stability_monte_carlo_draws_about_a_files_uncertainties():
    import pathlib
    src = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "Balanceassistv1Benchmark.txt"
    b = bikedyn.Bicycle(str(src))
    s = b.stability(monte_carlo=500, seed=7)
    m = s.monte_carlo
    assert m.draws == 500 and m.seed == 7
    # The capsize speed is near linear over this file's spread: the drawn
    # deviation is the first order's within four of its standard errors.
    c = m.capsize_speed
    assert abs(c.standard_deviation - s.capsize_speed_sd) < 4 * c.standard_error_of_sd
    assert b.stability(monte_carlo=500, seed=7).monte_carlo == m
    with pytest.raises(bikedyn.InvalidArgumentError, match=r"\+/-"):
        bikedyn.Bicycle("benchmark").stability(monte_carlo=10)


def test_eigenvalue_standard_deviations_are_the_first_order_propagation():
    import pathlib
    src = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "Balanceassistv1Benchmark.txt"
    b = bikedyn.Bicycle(str(src))
    speeds = [3.0, 4.5]
    sd = b.eigenvalue_standard_deviations(speeds)
    assert sd.shape == (2, 4, 2)
    # Central differences over every parameter the file gives a +/- for.
    var = np.zeros((2, 4, 2))
    for line in src.read_text().splitlines():
        if "+/-" not in line:
            continue
        symbol, rest = (x.strip() for x in line.split("=", 1))
        value, s = (float(x) for x in rest.split("+/-"))
        h = 1e-5 * max(abs(value), 1e-2)
        up = b.with_parameters(**{symbol: value + h}).eig(speeds).eigenvalues[:, :4]
        down = b.with_parameters(**{symbol: value - h}).eig(speeds).eigenvalues[:, :4]
        d = (up - down) / (2 * h) * s
        var += np.stack([d.real ** 2, d.imag ** 2], axis=-1)
    np.testing.assert_allclose(sd, np.sqrt(var), rtol=1e-5, atol=1e-8)
    assert bikedyn.Bicycle("benchmark").eigenvalue_standard_deviations([4.0]) is None


def test_a_files_feedback_closes_the_loop_in_the_linear_analyses_and_the_simulation():
    import pathlib
    src = pathlib.Path(__file__).resolve().parents[2] / "tests" / "data" / "balance_assist_gain_8.toml"
    b = bikedyn.Bicycle(str(src))
    s = b.stability()
    # With its steer motor the balance-assist bicycle is stable from about
    # 1.04 m/s (bicycleparameters' A - B K: -1.50 +- 8.48i, -0.83, -1.73
    # at 1.66 m/s); the open loop is not below its weave speed.
    lo, hi = s.stable_intervals[0]
    assert 1.0 < lo < 1.1 and 4.3 < hi < 4.4
    weave = max(b.eig([1.66]).eigenvalues[0], key=lambda z: z.imag)
    assert abs(weave - complex(-1.5025818770340327, 8.47937107316705)) < 1e-9
    # The nonlinear simulation closes the same loop: a small roll rate at
    # 3 m/s follows the closed-loop exp(A t) x0 (A - B K in state space).
    sim = bikedyn.simulate(b, duration=2.0, speed=3.0, roll_rate=1e-4, dt=0.05)
    A, _ = b.state_space([3.0])
    w, V = np.linalg.eig(A[0])
    c = np.linalg.solve(V, np.array([0, 0, 1e-4, 0]))
    lin = np.array([(V @ (c * np.exp(w * t))).real for t in sim["t"]])
    err = np.abs(sim.coordinate("roll") - lin[:, 0]).max()
    assert err < 1e-3 * np.abs(lin[:, 0]).max(), err


def test_a_leaning_rider_stiffly_held_is_the_rigid_rider_bicycle():
    # The benchmark's rear body B split by the parallel-axis theorem into
    # a lower part and a 40 kg upper body hinged on a stiff lean spring
    # (the leaning-rider model): the benchmark's eigenvalues come back.
    par = dict(meijaard2007()["parameters"])
    m_b, x_b, z_b = par["mB"], par["xB"], par["zB"]
    m_u, x_u, z_u = 40.0, x_b + 0.02, -1.1
    u = dict(xx=2.5, yy=2.8, zz=1.0, xz=1.0)
    m_l = m_b - m_u
    x_l, z_l = (m_b * x_b - m_u * x_u) / m_l, (m_b * z_b - m_u * z_u) / m_l

    def shift(m, dx, dz):
        return dict(xx=m * dz * dz, yy=m * (dx * dx + dz * dz), zz=m * dx * dx, xz=-m * dx * dz)

    su, sl = shift(m_u, x_u - x_b, z_u - z_b), shift(m_l, x_l - x_b, z_l - z_b)
    for k in ("xx", "yy", "zz", "xz"):
        par["IB" + k] = par["IB" + k] - u[k] - su[k] - sl[k]
    par.update(mB=m_l, xB=x_l, zB=z_l)
    h_lean = 0.9
    par.update(xL=x_b, zL=h_lean - par["rR"], x6=x_u - x_b, z6=-z_u - h_lean, m6=m_u,
               I6x=u["xx"], I6y=u["yy"], I6z=u["zz"], I6xz=-u["xz"], k_lean=1e9)
    rider = bikedyn.Bicycle(par, name="split benchmark")
    assert rider.model == "rider_lean"
    v = np.array([2.0, 4.0, 5.0, 6.0])
    e = rider.eig(v)
    # The four roll-steer modes first, then the rider's own pair.
    assert e.eigenvalues.shape == (len(v), 6) and e.modes.shape == (len(v), 4)
    a = e.eigenvalues[:, :4]
    b = bikedyn.Bicycle("benchmark").eig(v).eigenvalues
    for i in range(len(v)):
        assert np.max(np.abs(np.sort_complex(a[i]) - np.sort_complex(b[i]))) < 3e-6, (v[i], a[i], b[i])
