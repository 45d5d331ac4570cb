"""The NMPC's step before the solver: parameters, bounds and warm start from the measured state,
the coastline's slots from the previous plan, the settings' limits and the solver's options.

Each test builds its own small controller (4 intervals, the NLP interpreted, no compiler) and
calls the step's parts directly, without solving.
"""

import json

import casadi as ca
import numpy as np
import pytest

from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_bounds import SLOW_DOWN_MPS2
from rhnc.control.nmpc_problem import OBSTACLE_FIELDS, solver_options
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
N = 4
DT = 20.0


def controller(**settings) -> NMPCController:
    return NMPCController(load_parameter_set("default"),
                          NMPCSettings(horizon_steps=N, control_interval_s=DT, codegen=False, **settings))


def northbound(speed_mps=14 * KNOT, start=(0.0, 0.0)):
    """Reference states (N+1, 6) from ``start`` northwards at ``speed_mps``, from t = 0."""
    return line_or_turn_reference(DT * np.arange(N + 1), start, 0.0, speed_mps)


def no_obstacles(ctrl):
    slots = np.zeros((OBSTACLE_FIELDS, ctrl.settings.max_obstacles + ctrl.settings.coastline_slots))
    slots[6, :] = 1.0
    return slots


def test_a_previous_input_beyond_the_actuators_enters_the_problem_at_their_limit():
    # an input applied by another controller (or measured past the limits): the rate cost and
    # the rate bounds start from the limit, never from outside it (bounds lbx > ubx otherwise)
    ctrl = controller(tau_rate_max=(1.0e4, 1.0e6))
    tau_max = ctrl.params.tau_max
    state = np.array([0.0, 0.0, 0.0, 14 * KNOT, 0.0, 0.0])
    for factor, limit in ((-3.0, -1.0), (3.0, 1.0)):
        previous = np.array([factor * tau_max[0], 0.5 * tau_max[1]])
        step = ctrl._prepare(0.0, state, northbound(), None, False, previous)
        at = 6 * (N + 1) + 2 * N  # the parameters: reference, feed-forward inputs, then the previous input
        np.testing.assert_allclose(step.p[at:at + 2], [limit, 0.5])
        w = ctrl.problem.w_index
        assert np.all(step.lbx[w] <= step.ubx[w])
        reach = DT * 1.0e4 / tau_max[0]  # surge force within one interval's rate from the limit
        assert (step.lbx[w[0, 0]], step.ubx[w[0, 0]]) == pytest.approx(
            (-1.0, -1.0 + reach) if limit < 0 else (1.0 - reach, 1.0))
    ctrl.close()


def test_a_ship_faster_than_the_speed_bound_may_slow_down_at_the_deceleration_limit():
    ctrl = controller()
    s = ctrl.settings
    u_index = ctrl.problem.z_index[1:, 3]
    for excess in (3.0, 0.5):  # the second solve reuses the bounds built for the first
        u0 = s.max_speed_mps + excess
        state = np.array([0.0, 0.0, 0.0, u0, 0.0, 0.0])
        lbx, ubx = ctrl._bounds(state, state[:2])
        k = np.arange(1, N + 1)
        expected = np.maximum(s.max_speed_mps, u0 - SLOW_DOWN_MPS2 * k * DT)
        np.testing.assert_allclose(ubx[u_index] * ctrl.speed_scale, expected)
        assert expected[0] > s.max_speed_mps  # the bound falls over the horizon
        np.testing.assert_allclose(lbx[ctrl.problem.z_index[0]] * ctrl.state_scale, [0.0, 0.0, *state[2:]])
    ctrl.close()


def test_the_warm_start_is_moved_by_the_whole_turns_its_first_node_lies_off_the_measured_heading():
    # the plant wraps the heading at +-pi, a stored plan does not: the plan is moved by whole
    # turns judged at its first node (the measured state's instant), its shape kept, whatever
    # it turns through after that node
    ctrl = controller()
    measured = np.array([0.0, 0.0, 0.0, 14 * KNOT, 0.0, 0.0])
    headings = 2.0 * np.pi + 2.9 + 0.3 * np.arange(N + 1)  # first node 2.9 rad (+ one turn) off, turning on
    states = np.zeros((N + 1, 6))
    states[:, 0] = 14 * KNOT * DT * np.arange(N + 1)
    states[:, 2] = headings
    states[:, 3] = 14 * KNOT
    inputs = np.tile(ctrl.params.equilibrium_tau(14 * KNOT), (N, 1))
    ctrl.memory.store(0.0, states, inputs)
    reference = northbound()
    ref_scaled = (reference / ctrl.state_scale).T
    guess = ctrl._initial_guess(0.0, measured, ref_scaled, np.zeros((2, N)), measured[:2], no_obstacles(ctrl),
                                np.zeros(ctrl._no_disturbance.size))
    guessed = guess[ctrl.problem.z_index[:, 2]]
    assert guessed[0] == 0.0  # the measured state
    np.testing.assert_allclose(guessed[1:], headings[1:] - 2.0 * np.pi)
    ctrl.close()


def headland_chart(tmp_path):
    """A chart with one triangular area whose nearest edge lies 0.5 nm east of the line east = 1 nm."""
    from rhnc.chart.chart import load_chart
    from rhnc.chart.projection import LocalProjection

    origin = (51.0, 1.5)
    corners = [(-3000.0, 2800.0), (3000.0, 2800.0), (0.0, 6000.0), (-3000.0, 2800.0)]
    lat, lon = LocalProjection(*origin).to_geographic(*np.array(corners).T)
    (tmp_path / "land.geojson").write_text(json.dumps(
        {"type": "Polygon", "coordinates": [[[float(x), float(y)] for x, y in zip(lon, lat)]]}))
    path = tmp_path / "land.chart.toml"
    path.write_text(f"origin_deg = [{origin[0]}, {origin[1]}]\nclearance_nm = 0.5\nno_go = [\"land.geojson\"]\n")
    return load_chart(path)


def test_the_coastline_slots_look_along_the_previous_plan_as_well_as_the_reference(tmp_path):
    # the reference runs far west of the land; the previous plan (a detour) runs 1000 m off its
    # edge: the land's constraint comes from the plan's track
    ctrl = controller(coastline_slots=2)
    ctrl.use_chart(headland_chart(tmp_path))
    state = np.array([0.0, 1800.0, 0.0, 14 * KNOT, 0.0, 0.0])
    reference = northbound(start=(0.0, -8000.0))
    closing = 1.25 * 14 * KNOT
    empty = no_obstacles(ctrl)[:, :ctrl.settings.max_obstacles]
    without_plan = ctrl._with_coastline(empty, 0.0, state, state[:2], reference, closing)
    assert not np.any(without_plan[9, ctrl.settings.max_obstacles:])  # the reference alone: out of reach
    plan = np.zeros((N + 1, 6))
    plan[:, 0] = 14 * KNOT * DT * np.arange(N + 1)
    plan[:, 1] = 1800.0
    ctrl.memory.store(0.0, plan, np.zeros((N, 2)))
    land = ctrl._with_coastline(empty, 0.0, state, state[:2], reference, closing)[:, ctrl.settings.max_obstacles:]
    assert land[9, 0] == 1.0
    # the circle's centre lies a quarter of the clearance behind the edge east = 2800 m
    centre_east = land[1, 0] * ctrl.length_scale + state[1]
    assert centre_east == pytest.approx(2800.0 + 0.25 * 0.5 * NM, abs=1.0)
    ctrl.close()


@pytest.mark.parametrize("name", ["cpu_time_limit_s", "wall_time_limit_s"])
def test_a_solve_time_limit_must_be_positive_or_none(name):
    for bad in (0.0, -1.0):
        with pytest.raises(ValueError, match=f"{name} must be > 0 or None, got {bad}"):
            NMPCSettings(**{name: bad})
    assert getattr(NMPCSettings(**{name: None}), name) is None
    assert getattr(NMPCSettings(**{name: 0.5}), name) == 0.5


def test_ipopt_stops_at_its_processor_time_limit():
    # a 50-variable Rosenbrock takes IPOPT some 90 iterations; a limit of 1 ns stops it at once
    x = ca.SX.sym("x", 50)
    nlp = {"x": x, "f": ca.sum1(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2)}
    statuses = []
    for cpu_time_s in (None, 1e-9):
        solver = ca.nlpsol("rosenbrock", "ipopt", nlp, solver_options("ipopt", [], 3000, None, cpu_time_s=cpu_time_s))
        solver(x0=np.full(50, -1.2))
        statuses.append(solver.stats()["return_status"])
    assert statuses == ["Solve_Succeeded", "Maximum_CpuTime_Exceeded"]
