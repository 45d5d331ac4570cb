"""The NMPC's objective term by term, evaluated on the nonlinear program itself: each state
error weighed by its own Q entry (heading through 2 (1 - cos e)), not at the first node."""

import casadi as ca
import numpy as np
import pytest

from rhnc.control.nmpc_problem import DISTURBANCE_SIZE, OBSTACLE_FIELDS, build_problem
from rhnc.ship.ship_model import load_parameter_set

N = 2
Q = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]


@pytest.fixture
def objective():  # built per test (mutation testing attributes a fixture's calls to the test that built it)
    problem = build_problem(load_parameter_set("default"), N, 20.0, 1, 1, Q, [0.0, 0.0], [0.0, 0.0], None,
                            np.ones(6), np.ones(2))
    cost = ca.Function("cost", [problem.nlp["x"], problem.nlp["p"]], [problem.nlp["f"]])
    reference = np.tile(np.array([[100.0], [50.0], [0.3], [8.0], [0.1], [0.01]]), (1, N + 1))

    def evaluate(errors_by_node):
        x = np.zeros(problem.size)
        for k in range(N + 1):
            x[problem.z_index[k]] = reference[:, k] + errors_by_node.get(k, 0.0)
        p = problem.parameters(reference, np.zeros((2, N)), np.zeros(2), np.zeros((6, 6)),
                               np.zeros(DISTURBANCE_SIZE), np.zeros((OBSTACLE_FIELDS, 1)))
        return float(cost(x, p))

    return evaluate


@pytest.mark.parametrize("state", range(6))
def test_each_state_error_is_weighed_by_its_own_q(objective, state):
    error = np.zeros(6)
    error[state] = 0.5
    expected = Q[state] * (2.0 * (1.0 - np.cos(0.5)) if state == 2 else 0.25)
    assert objective({1: error}) == pytest.approx(expected, rel=1e-12)


def test_the_first_node_is_the_measured_state_and_costs_nothing(objective):
    assert objective({0: np.full(6, 0.5)}) == 0.0


def test_a_heading_error_of_a_whole_turn_costs_nothing(objective):
    assert objective({1: np.array([0.0, 0.0, 2.0 * np.pi, 0.0, 0.0, 0.0])}) == pytest.approx(0.0, abs=1e-12)
