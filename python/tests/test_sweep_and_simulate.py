"""Sweeps agree with the per-design analysis; simulations return the CSV's
columns and behave physically."""

import numpy as np
import pytest

import bikedyn


def test_one_parameter_sweep_agrees_with_each_design():
    trails = np.linspace(0.04, 0.12, 5)
    speeds = np.linspace(1.0, 9.0, 9)
    s = bikedyn.sweep("benchmark", "c", trails, speeds)
    assert s.least_stable_real_part.shape == (5, 9)
    assert s.weave_speed.shape == (5,) and s.capsize_speed.shape == (5,)
    for i, c in enumerate(trails):
        b = bikedyn.Bicycle("benchmark").with_parameter("c", c)
        e = b.eig(speeds)
        assert np.allclose(s.least_stable_real_part[i], e.eigenvalues.real.max(axis=1), rtol=0, atol=1e-12)
        st = b.stability(speed_min=1.0, speed_max=9.0)
        if st.weave_speed is None:
            assert np.isnan(s.weave_speed[i])
        else:
            assert s.weave_speed[i] == pytest.approx(st.weave_speed, abs=1e-9)


def test_two_parameter_map_shape_and_values():
    s = bikedyn.sweep("benchmark", "c", [0.06, 0.08], [4.0, 5.0, 6.0], param2="lam", values2=[0.3, 0.31416])
    assert s.least_stable_real_part.shape == (2, 2, 3)
    assert s.weave_speed.shape == (2, 2)
    b = bikedyn.Bicycle("benchmark").with_parameters(c=0.08, lam=0.31416)
    assert np.allclose(s.least_stable_real_part[1, 1], b.eig([4.0, 5.0, 6.0]).eigenvalues.real.max(axis=1), atol=1e-12)


def test_simulation_columns_and_physics():
    # Free speed: no motor holds it, so the energy is conserved.
    sim = bikedyn.simulate("benchmark", duration=3.0, speed=5.0, roll_rate=0.2, free_speed=True)
    for name in ["t", "speed", "kinetic_energy", "potential_energy", "constraint_residual"]:
        assert name in sim
    assert sim["t"][0] == 0 and sim["t"][-1] == pytest.approx(3.0)
    assert sim.stats["relative_energy_change"] < 1e-6
    assert sim.stats["free_speed"]
    # The stats are the job's summary, as the command line prints it.
    assert sim.stats["model"] == sim.model and sim.stats["simulated_seconds"] == pytest.approx(3.0)
    assert sim.stats["rhs_evaluations"] > 0 and sim.stats["stop"] == sim.stop
    assert set(sim.roles) >= {"roll", "steer", "yaw"}
    r = sim.coordinate("roll")
    # Self-stable at 5 m/s (between v_w 4.29 and v_c 6.02): the roll
    # oscillation decays.
    early = np.abs(r[sim["t"] < 1.0]).max()
    late = np.abs(r[sim["t"] > 2.0]).max()
    assert late < early
    # Same call, same numbers.
    again = bikedyn.simulate("benchmark", duration=3.0, speed=5.0, roll_rate=0.2, free_speed=True)
    assert all(np.array_equal(sim[k], again[k]) for k in sim)


def test_small_perturbation_follows_the_linear_equations():
    # A 1e-4 rad/s roll-rate perturbation at 5 m/s: the nonlinear roll
    # angle equals the linear response exp(A t) x0 to a few parts in 1e4.
    bike = bikedyn.Bicycle("benchmark")
    sim = bikedyn.simulate(bike, duration=2.0, speed=5.0, roll_rate=1e-4, dt=0.05)
    A, _ = bike.state_space([5.0])
    w, V = np.linalg.eig(A[0])
    x0 = np.array([0, 0, 1e-4, 0])
    c = np.linalg.solve(V, x0)
    lin = np.array([(V @ (c * np.exp(w * t))).real for t in sim["t"]])
    err = np.abs(sim.coordinate("roll") - lin[:, 0]).max()
    assert err < 1e-3 * np.abs(lin[:, 0]).max(), err


def test_kicks_and_pulses():
    quiet = bikedyn.simulate("benchmark", duration=2.0, speed=5.0)
    kicked = bikedyn.simulate("benchmark", duration=2.0, speed=5.0, kicks=[(0.5, 2.0)], pulses=[("steer", 1.0, 0.1, 0.5)])
    assert np.abs(quiet.coordinate("roll")).max() < 1e-12
    assert np.abs(kicked.coordinate("roll")[kicked["t"] > 0.6]).max() > 1e-4
