"""What a failed NMPC step leaves for the next ones: the unfinished iterate of a solve stopped
at its iteration budget is the next warm start (never the applied plan), and a fallback with
no plan left opens the range from a target inside its clearance, or keeps making a held
alteration, instead of holding the course."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_alteration import alteration_steering
from rhnc.control.nmpc_warm_start import PlanMemory
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set
from solver_stand_ins import solvers_replaced

KNOT = 1852.0 / 3600.0
DT = 20.0
N = 15
TAU_MAX = np.array([1e6, 3e8])


def yawing_rollout(state, inputs, disturbance=None):
    """A toy ship: straight on at its speed, yaw rate = tau_r / 1e10 rad/s (first order is enough)."""
    rows = [np.asarray(state, dtype=float)]
    for tau in np.asarray(inputs):
        x = rows[-1].copy()
        x[5] = tau[1] / 1e10
        x[2] += x[5] * DT
        x[0] += x[3] * math.cos(x[2]) * DT
        x[1] += x[3] * math.sin(x[2]) * DT
        rows.append(x)
    return np.array(rows)


def plan(heading=0.0, n=N):
    states = np.zeros((n + 1, 6))
    states[:, 2] = heading
    states[:, 3] = 9.0
    states[:, 0] = 9.0 * DT * np.arange(n + 1)
    return states, np.tile([5e5, 0.0], (n, 1))


def test_an_unfinished_iterate_is_the_next_warm_start_and_a_stored_plan_replaces_it():
    memory = PlanMemory(N, DT, yawing_rollout)
    states, inputs = plan()
    memory.store(0.0, states, inputs, np.ones(6 + 8 * N), np.ones(6 * N))
    iterate_states, iterate_inputs = plan(heading=0.4)
    memory.keep_iterate(0.0, iterate_states, iterate_inputs, np.full(6 + 8 * N, 2.0), np.full(6 * N, 3.0))
    guess_states, guess_inputs = memory.guess(DT)
    np.testing.assert_array_equal(guess_states[:N, 2], 0.4)   # the iterate, shifted by one interval
    np.testing.assert_array_equal(memory.shifted(DT)[0][:N, 2], 0.0)   # the plan (the fallback's) is kept
    duals = memory.dual_guess(DT)
    assert np.all(duals["lam_x0"] == 2.0) and np.all(duals["lam_g0"] == 3.0)
    memory.store(DT, *plan(heading=0.1))   # a new plan (solved or fallback) replaces the iterate
    np.testing.assert_array_equal(memory.guess(2 * DT)[0][:N, 2], 0.1)


def test_an_iterate_with_a_number_that_is_not_finite_is_not_kept():
    memory = PlanMemory(N, DT, yawing_rollout)
    states, inputs = plan(heading=0.4)
    states[3, 0] = np.nan
    memory.keep_iterate(0.0, states, inputs, None, None)
    assert memory.guess(DT) is None


class OutOfIterations:
    """Wraps a solver: a stop at the iteration limit ``cap`` at a point moved off the dynamics
    (so never accepted as a plan); records the guesses it was started from."""

    def __init__(self, solver, cap, starts):
        self.solver, self.cap, self.starts = solver, cap, starts

    def __call__(self, **arguments):
        self.starts.append(np.array(arguments["x0"]).ravel())
        result = dict(self.solver(**arguments))
        result["x"] = np.array(result["x"]).ravel() + 0.05
        return result

    def stats(self):
        return {**self.solver.stats(), "success": False, "return_status": 1, "iter_count": self.cap,
                "fatrop": {"return_flag": 1}}


@pytest.fixture(scope="module")
def budgeted():
    kcs = load_parameter_set("default")
    return NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT, max_obstacles=1,
                                            wall_time_limit_s=None, cpu_time_limit_s=None, iteration_budget=30))


def test_a_step_stopped_at_its_budget_hands_its_iterate_to_the_next_step(budgeted):
    course, speed = 0.3, 18 * KNOT
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    budgeted.reset()
    starts = []
    with solvers_replaced(budgeted, lambda name, solver: OutOfIterations(solver, budgeted.attempt_iterations[name],
                                                                          starts)):
        first = budgeted.solve(0.0, state, reference_at(0.0))
        iterate_states, _ = budgeted.memory.guess(DT)
        second = budgeted.solve(DT, first.states[1], reference_at(DT))
    assert first.fallback and second.fallback
    z = budgeted.problem.z_index
    # the second solve started from the first one's iterate (shifted), not from the applied plan
    started = starts[1][z[2:N, 0]] * budgeted.state_scale[0] + first.states[1][0]
    np.testing.assert_allclose(started, iterate_states[2:N, 0], atol=1e-6)
    assert np.max(np.abs(iterate_states[2:N, 0] - budgeted.memory.shifted(DT)[0][2:N, 0])) > 10.0   # 0.05 L


def held(floor=None, ceiling=None, escape=None):
    return SimpleNamespace(alteration_floor=floor, alteration_ceiling=ceiling, escape_heading=escape)


@pytest.mark.parametrize("report, turn", [(held(floor=(0.0, 0.0, math.radians(35.0))), 1.0),
                                          (held(ceiling=(0.0, 0.0, math.radians(-35.0))), -1.0),
                                          (held(escape=math.radians(35.0)), 1.0),
                                          (held(floor=(0.0, 0.0, 0.6), escape=math.radians(-35.0)), -1.0),
                                          (held(), 0.0)], ids=["starboard", "port", "escape", "escape-first", "none"])
def test_a_fallback_without_a_plan_steers_to_the_held_alteration(report, turn):
    memory = PlanMemory(N, DT, yawing_rollout)
    state = np.array([0.0, 0.0, 0.0, 9.0, 0.0, 0.0])
    states, inputs = memory.fallback_plan(0.0, state, np.array([5e5, 0.0]), TAU_MAX, np.zeros(5),
                                          alteration_steering(report, TAU_MAX[1]))
    assert np.sign(inputs[0, 1]) == turn
    if turn:
        assert inputs[0, 1] == pytest.approx(turn * TAU_MAX[1])   # full moment 35 deg off
        assert states[-1, 2] == pytest.approx(turn * math.radians(35.0), abs=math.radians(5.0))
    np.testing.assert_array_equal(inputs[:, 0], 5e5)   # the surge force is held
    # kept as the plan the next failure shifts
    np.testing.assert_array_equal(memory.fallback_inputs(DT, np.zeros(2), TAU_MAX)[0], inputs[1])


def test_a_fallback_with_a_plan_left_shifts_that_plan_even_with_an_alteration_held():
    memory = PlanMemory(N, DT, yawing_rollout)
    states, inputs = plan()
    inputs[:, 1] = -1e7
    memory.store(0.0, states, inputs)
    _, applied = memory.fallback_plan(DT, states[1], inputs[0], TAU_MAX, np.zeros(5),
                                      alteration_steering(held(floor=(0.0, 0.0, 0.6)), TAU_MAX[1]))
    assert applied[0, 1] == -1e7


def test_the_controllers_fallback_without_a_plan_steers_to_the_held_alteration(budgeted):
    budgeted.reset()
    state = np.array([0.0, 0.0, 0.3, 18 * KNOT, 0.0, 0.0])
    report = SimpleNamespace(alteration_floor=(0.0, 0.3, 0.3 + math.radians(35.0)), alteration_ceiling=None,
                             escape_heading=None, class_codes=np.zeros(1), active=np.zeros(1))
    failed = budgeted._fail(0.0, state, np.array([5e5, 0.0]), 0.1, 30, "fatrop_return_code_1", -1.0, -1.0, False,
                            np.zeros(5), report)
    assert failed.fallback and failed.tau[1] == pytest.approx(budgeted.params.tau_max[1])
    assert failed.states[-1, 2] > 0.3 + math.radians(25.0)
