"""Prediction model: parameter sets, RK4 against an independent integrator, CasADi = numpy."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from orchestrator.errors import ScenarioError
from rhnc.ship.ship_model import (
    ShipParameters,
    casadi_derivatives,
    derivatives,
    load_parameter_set,
    rk4_function,
    rk4_step,
)

KNOT = 1852.0 / 3600.0


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def test_default_set_is_full_scale_kcs_and_course_stable(kcs):
    assert kcs.m11 > 1e7 and kcs.tau_u_max > 1e5
    assert kcs.straight_line_stable(18 * KNOT)


def test_paper_table2_is_unstable_at_18_kn():
    paper = load_parameter_set("paper_table2")
    assert paper.m11 == pytest.approx(897.77)
    assert not paper.straight_line_stable(18 * KNOT)
    assert max(np.linalg.eigvals(paper.sway_yaw_matrix(18 * KNOT)).real) == pytest.approx(17.7, abs=0.6)


def test_unknown_set_names_the_valid_ones():
    with pytest.raises(ScenarioError, match=r"unknown parameter set 'kcs_model'.*valid: default, paper_table2"):
        load_parameter_set("kcs_model")


def test_overrides_replace_values_and_reject_unknown_keys(kcs):
    heavier = load_parameter_set("default", {"m11": 2 * kcs.m11})
    assert heavier.m11 == 2 * kcs.m11 and heavier.m22 == kcs.m22
    with pytest.raises(ScenarioError, match="override of unknown key 'm44'"):
        load_parameter_set("default", {"m44": 1.0})


def test_missing_dynamics_key_is_named(tmp_path):
    path = tmp_path / "sets.toml"
    path.write_text("[tiny]\nm11 = 1.0\nm22 = 2.0\nm33 = 3.0\nd11 = 1.0\nd22 = 1.0\ntau_u_max = 1.0\ntau_r_max = 1.0\n")
    with pytest.raises(ScenarioError, match="missing key 'd33'"):
        load_parameter_set("tiny", path=path)
    path.write_text(path.read_text() + "d33 = 1.0\n")
    tiny = load_parameter_set("tiny", path=path)
    assert tiny.d23 == 0.0 and tiny.d32 == 0.0  # the paper's Eq. 11


def test_rk4_matches_solve_ivp_on_a_turning_manoeuvre(kcs):
    state = np.array([100.0, -50.0, 0.3, 18 * KNOT, 0.2, 0.002])
    tau = np.array([0.8 * kcs.tau_u_max, 0.6 * kcs.tau_r_max])
    reference = solve_ivp(lambda t, x: derivatives(x, tau, kcs), (0.0, 120.0), state, rtol=1e-10, atol=1e-10)
    end = rk4_step(state, tau, 120.0, 60, kcs)
    np.testing.assert_allclose(end, reference.y[:, -1], rtol=1e-6, atol=1e-6)
    # and the yaw rate really changed: a test of a turning ship, not of a straight line
    assert abs(end[5] - state[5]) > 1e-3


def test_casadi_model_equals_numpy_model(kcs):
    rng = np.random.default_rng(3)
    f = casadi_derivatives(kcs)
    F = rk4_function(kcs, 20.0, 4, with_substeps=True)
    for _ in range(5):
        state = rng.normal(size=6) * np.array([1e3, 1e3, 1.0, 5.0, 0.5, 0.01])
        tau = rng.uniform(-1, 1, 2) * kcs.tau_max
        np.testing.assert_allclose(np.array(f(state, tau)).ravel(), derivatives(state, tau, kcs), rtol=1e-12)
        x_next, substeps = F(state, tau)
        np.testing.assert_allclose(np.array(x_next).ravel(), rk4_step(state, tau, 20.0, 4, kcs), rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(np.array(substeps)[:, 1], rk4_step(state, tau, 10.0, 2, kcs), rtol=1e-10, atol=1e-9)


def test_equilibrium_tau_holds_speed(kcs):
    u0 = 18 * KNOT
    state = np.array([0.0, 0.0, 0.0, u0, 0.0, 0.0])
    end = rk4_step(state, kcs.equilibrium_tau(u0), 600.0, 120, kcs)
    assert end[3] == pytest.approx(u0, rel=1e-9)
    assert end[0] == pytest.approx(600.0 * u0, rel=1e-9)


def test_parameters_are_frozen(kcs):
    with pytest.raises(AttributeError):
        kcs.m11 = 1.0
    assert isinstance(kcs, ShipParameters)


def test_rk4_is_fourth_order_on_numbers_and_on_casadi_expressions():
    import casadi as ca

    from rhnc.ship.ship_model import rk4_states

    def growth(x, rate):
        return rate * x

    errors = [abs(rk4_states(growth, 1.0, 1.0 / n, n, 1.0)[-1] - math.e) for n in (4, 8)]
    assert 14.0 < errors[0] / errors[1] < 18.0  # halving the step divides the error by 2^4
    symbol = ca.SX.sym("x")
    ends = ca.Function("ends", [symbol], [ca.vertcat(*rk4_states(growth, symbol, 0.25, 4, 1.0))])
    np.testing.assert_array_equal(np.array(ends(1.0)).ravel(), rk4_states(growth, 1.0, 0.25, 4, 1.0))


def test_the_ship_equations_are_integrated_by_one_rk4_only():
    # an RK4 stage written out anywhere but rk4_states is a second integrator to keep in step
    import ast
    from pathlib import Path

    import rhnc

    found = []
    for path in sorted(Path(rhnc.__file__).parent.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef):
                stages = {target.id for statement in ast.walk(node) if isinstance(statement, ast.Assign)
                          for target in statement.targets if isinstance(target, ast.Name)}
                if {"k1", "k2", "k3", "k4"} <= stages:
                    found.append(f"{path.name}:{node.name}")
    assert found == ["ship_model.py:rk4_states"]


def test_speed_scaled_damping_goes_with_the_surge_speed(kcs):
    """With damping_speed_mps the linear sway-yaw damping has its values at that speed and is
    proportional to the surge speed elsewhere (the numpy, CasADi and linearised models alike);
    without it (0, the paper's model) it is constant."""
    import dataclasses

    from rhnc.ship.ship_model import hull_forces

    scaled = dataclasses.replace(kcs, damping_speed_mps=9.26, d23=0.1 * kcs.d22 * 100.0, d32=0.05 * kcs.d33 / 100.0)
    plain = dataclasses.replace(scaled, damping_speed_mps=0.0)
    v, r = 0.3, 0.004
    coriolis = lambda u: (-kcs.m11 * u * r, (kcs.m11 - kcs.m22) * u * v)   # noqa: E731
    for u, factor in ((9.26, 1.0), (4.63, 0.5), (2.0, 2.0 / 9.26)):
        _, sway, yaw = hull_forces(scaled, u, v, r)
        _, sway_plain, yaw_plain = hull_forces(plain, u, v, r)
        assert sway - coriolis(u)[0] == pytest.approx(factor * (sway_plain - coriolis(u)[0]), rel=1e-12)
        assert yaw - coriolis(u)[1] == pytest.approx(factor * (yaw_plain - coriolis(u)[1]), rel=1e-12)
    state, tau = np.array([0.0, 0.0, 0.3, 4.63, v, r]), np.array([1e5, 1e7])
    np.testing.assert_allclose(np.array(casadi_derivatives(scaled)(state, tau)).ravel(),
                               derivatives(state, tau, scaled), rtol=1e-12)
    assert not np.allclose(derivatives(state, tau, scaled), derivatives(state, tau, plain))
    half = dataclasses.replace(plain, d22=0.5 * kcs.d22, d23=0.5 * scaled.d23, d32=0.5 * scaled.d32, d33=0.5 * kcs.d33)
    np.testing.assert_allclose(scaled.sway_yaw_matrix(4.63), half.sway_yaw_matrix(4.63), rtol=1e-12)


def test_a_negative_damping_speed_is_refused(tmp_path):
    path = tmp_path / "sets.toml"
    path.write_text("[tiny]\nm11 = 1.0\nm22 = 2.0\nm33 = 3.0\nd11 = 1.0\nd22 = 1.0\nd33 = 1.0\ntau_u_max = 1.0\n"
                    "tau_r_max = 1.0\ndamping_speed_mps = -2.0\n")
    with pytest.raises(ScenarioError, match=r"\[tiny\]: key 'damping_speed_mps' must be a speed of at least 0 m/s"):
        load_parameter_set("tiny", path=path)
