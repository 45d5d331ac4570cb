"""Real-time NMPC: the compact NLP is the inlined one; multipliers carried over shift like the plan."""

import math

import casadi as ca
import numpy as np
import pytest

from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_problem import StepEvaluator, build_problem
from rhnc.control.nmpc_warm_start import PlanMemory
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

NM = 1852.0
KNOT = NM / 3600.0
COURSE = math.radians(45.0)
SPEED = 18 * KNOT


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


@pytest.mark.parametrize("slots, slack", [(0, None), (2, 1.0e4)])
def test_compact_nlp_is_the_inlined_nlp(kcs, slots, slack):
    """The mapped stage function (what is compiled) gives the inlined NLP's cost and constraints."""
    state_scale = np.array([230.0, 230.0, 1.0, 1.0, 1.0, 1.0 / 230.0])
    problem = build_problem(kcs, 4, 20.0, 2, slots, (0.1, 0.2, 10.0, 1.0, 1.5, 2.0), (0.01, 0.02), (0.03, 0.04),
                            slack, state_scale, kcs.tau_max)
    inlined, compact = problem.nlp, problem.compact_nlp
    assert compact["x"].shape == inlined["x"].shape and compact["p"].shape == inlined["p"].shape
    functions = [ca.Function(name, [nlp["x"], nlp["p"]], [nlp["f"], nlp["g"]])
                 for name, nlp in (("inlined", inlined), ("compact", compact))]
    rng = np.random.default_rng(7)
    for _ in range(3):
        x = rng.normal(size=inlined["x"].shape[0])
        p = rng.uniform(0.5, 1.5, size=inlined["p"].shape[0])
        (f1, g1), (f2, g2) = (function(x, p) for function in functions)
        assert float(f2) == pytest.approx(float(f1), rel=1e-12)
        np.testing.assert_allclose(np.array(g2).ravel(), np.array(g1).ravel(), rtol=1e-12, atol=1e-12)
        assert float(f1) != 0.0


def test_the_buffered_model_step_is_the_casadi_step(kcs):
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=5, control_interval_s=20.0, max_obstacles=1))
    step = controller.problem.step
    evaluate = StepEvaluator(step)
    rng = np.random.default_rng(3)
    results = []
    for _ in range(3):
        z, w, d = rng.normal(size=6), rng.uniform(-1, 1, size=2), rng.normal(size=5) * [0.5, 0.5, 1e5, 1e5, 1e7]
        expected = np.array(step(z, w, d)[0]).ravel()
        results.append((evaluate(z, w, d), expected))
    for got, expected in results:  # each result kept its values after the later calls
        np.testing.assert_allclose(got, expected, rtol=1e-14, atol=0.0)


def test_multipliers_shift_by_whole_stages_like_the_plan():
    memory = PlanMemory(3, 20.0, rollout=None)
    lam_x = np.r_[np.repeat([1.0, 2.0, 3.0], 4), 9.0, 9.0, 9.0, 9.0, 9.0, 9.0]  # 3 stages of 4, then the last state
    lam_g = np.repeat([10.0, 20.0, 30.0], 2)  # 3 stages of 2 constraints
    memory.store(100.0, np.zeros((4, 6)), np.zeros((3, 2)), lam_x, lam_g)
    same_x, same_g = memory.shifted_multipliers(100.0)
    np.testing.assert_array_equal(same_x, lam_x)
    np.testing.assert_array_equal(same_g, lam_g)
    shifted_x, shifted_g = memory.shifted_multipliers(120.0)
    np.testing.assert_array_equal(shifted_x, np.r_[np.repeat([2.0, 3.0, 3.0], 4), [9.0] * 6])
    np.testing.assert_array_equal(shifted_g, [20.0, 20.0, 30.0, 30.0, 30.0, 30.0])
    assert memory.shifted_multipliers(200.0) is None  # past the horizon
    memory.store(120.0, np.zeros((4, 6)), np.zeros((3, 2)))  # a fallback plan carries none
    assert memory.shifted_multipliers(140.0) is None


def test_ipopt_warm_started_from_the_shifted_multipliers_needs_fewer_iterations_for_the_same_plan(kcs):
    """Closed loop past a head-on target with IPOPT: cold, warm options only, warm with multipliers."""
    settings = dict(solver="ipopt", horizon_steps=10, control_interval_s=20.0, max_obstacles=1,
                    collision_slack_weight=None, wall_time_limit_s=None, cpu_time_limit_s=None)
    runs = {}
    for name, warm, multipliers in (("cold", False, False), ("options", True, False), ("warm", True, True)):
        controller = NMPCController(kcs, NMPCSettings(**settings, warm_start_duals=warm))
        if not multipliers:  # the same solver options, but no multipliers handed over
            controller.memory.shifted_multipliers = lambda time_s: None
        state = np.array([0.0, 0.0, COURSE, SPEED, 0.0, 0.0])
        iterations, inputs = [], []
        for k in range(30):
            t = 20.0 * k
            reference = line_or_turn_reference(t + 20.0 * np.arange(11), (0.0, 0.0), COURSE, SPEED)
            target = np.array([[3 * NM - 9 * KNOT * t, 3 * NM - 9 * KNOT * t, -9 * KNOT, -9 * KNOT, NM]])
            solution = controller.solve(t, state, reference, target, et=True)
            assert solution.success, solution.status
            iterations.append(solution.iterations)
            inputs.append(solution.tau / kcs.tau_max)
            for _ in range(40):
                state = rk4_step(state, solution.tau, 0.5, 1, kcs)
        runs[name] = (sum(iterations[1:]), np.array(inputs))
    assert runs["warm"][0] < 0.75 * runs["options"][0], runs
    assert runs["warm"][0] < 0.75 * runs["cold"][0], runs
    # the same closed loop to the solver's tolerance
    np.testing.assert_allclose(runs["warm"][1], runs["cold"][1], rtol=0, atol=1e-4)
