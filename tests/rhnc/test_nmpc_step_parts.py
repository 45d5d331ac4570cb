"""More of the NMPC's parts checked alone, without solving: the fallback plan kept in the plan
memory, the terminal weight's linearisation, the speed it is taken at, the attempts the acados
backend is given, the SQP method's options, a settings message and the end of an alteration.

The controllers are small (4 intervals, the NLP interpreted, no compiler); the plan memory gets a
toy rollout of its own.
"""

from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from rhnc.control import nmpc_acados
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_colregs import ALTERATION_CLEAR_FACTOR, CollisionDomains, DomainSettings
from rhnc.control.nmpc_problem import solver_options
from rhnc.control.nmpc_warm_start import PlanMemory
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
N = 4
DT = 20.0


def controller(**settings) -> NMPCController:
    return NMPCController(load_parameter_set("default"),
                          NMPCSettings(horizon_steps=N, control_interval_s=DT, codegen=False, **settings))


# ------------------------------------------------------------------ the fallback plan

def toy_rollout(state, inputs, disturbance=None):
    """Each interval adds its inputs to north and east and the disturbance's first two entries."""
    d = np.zeros(2) if disturbance is None else np.asarray(disturbance, dtype=float)[:2]
    rows = [np.asarray(state, dtype=float)]
    for w in np.asarray(inputs, dtype=float):
        step = np.zeros(6)
        step[:2] = w + d
        rows.append(rows[-1] + step)
    return np.array(rows)


PLAN_INPUTS = np.array([[1.0, 10.0], [2.0, 20.0], [3.0, 30.0], [4.0, 40.0]])
TAU_MAX = np.array([3.5, 100.0])


def memory_with_a_plan() -> PlanMemory:
    memory = PlanMemory(N, DT, toy_rollout)
    memory.store(0.0, toy_rollout(np.zeros(6), PLAN_INPUTS), PLAN_INPUTS)
    return memory


def test_the_fallback_inputs_are_the_previous_plan_shifted_extended_by_its_last_input_within_the_limits():
    # two intervals after the plan: its last two inputs, then the last one twice more, the
    # surge force clipped to its limit
    inputs = memory_with_a_plan().fallback_inputs(2 * DT, np.array([9.0, 9.0]), TAU_MAX)
    np.testing.assert_array_equal(inputs, [[3.0, 30.0], [3.5, 40.0], [3.5, 40.0], [3.5, 40.0]])


def test_the_fallback_plan_rolls_the_fallback_inputs_out_from_the_measured_state_and_keeps_them():
    memory = memory_with_a_plan()
    state = np.array([100.0, 200.0, 0.1, 5.0, 0.0, 0.0])
    disturbance = np.array([0.5, -0.5, 0.0, 0.0, 0.0])
    states, inputs = memory.fallback_plan(2 * DT, state, np.array([9.0, 9.0]), TAU_MAX, disturbance)
    expected = np.array([[3.0, 30.0], [3.5, 40.0], [3.5, 40.0], [3.5, 40.0]])
    np.testing.assert_array_equal(inputs, expected)
    np.testing.assert_allclose(states, toy_rollout(state, expected, disturbance))
    assert memory.time_s == 2 * DT  # kept as the next warm start and fallback
    np.testing.assert_array_equal(memory.inputs, expected)
    np.testing.assert_allclose(memory.states, states)


# ------------------------------------------------------------------ the terminal weight

def test_the_terminal_weight_solves_the_riccati_equation_of_straight_motion_at_its_speed():
    # a speed scale other than 1 m/s (the default): the point is then scaled, z = U / scale
    ctrl = controller(speed_scale_mps=5.0)
    weight = ctrl.terminal_weight
    speed = 7.0  # a bin of its own (0.25 m/s bins)
    P = weight(speed)
    z0 = np.array([0.0, 0.0, 0.0, speed / weight.speed_scale, 0.0, 0.0])
    w0 = ctrl.params.equilibrium_tau(speed) / ctrl.input_scale
    A, B = (np.array(m) for m in weight._linearised(z0, w0))
    Q, R = np.diag(weight.q), np.diag(weight.r)
    residual = A.T @ P @ A - P - A.T @ P @ B @ np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A) + Q
    assert np.max(np.abs(residual)) < 1e-6 * np.max(np.abs(P))
    ctrl.close()


def test_the_terminal_weight_is_taken_at_the_reference_speed_not_the_ship_s():
    ctrl = controller(disturbance_observer=False)
    reference = line_or_turn_reference(DT * np.arange(N + 1), (0.0, 0.0), 0.0, 14 * KNOT)
    state = np.array([0.0, 0.0, 0.0, 8 * KNOT, 0.0, 0.0])
    step = ctrl._prepare(0.0, state, reference, None, False, None)
    at = 6 * (N + 1) + 2 * N + 2  # the parameters: reference, feed-forward inputs, previous input, then P
    P = step.p[at:at + 36].reshape(6, 6, order="F")
    np.testing.assert_allclose(P, ctrl.terminal_weight(14 * KNOT))
    for other in (8 * KNOT, 0.0):  # the ship's speed, no speed at all: other weights
        assert not np.allclose(P, ctrl.terminal_weight(other))
    ctrl.close()


# ------------------------------------------------------------------ the acados backend's attempts

@pytest.mark.parametrize("slack, budget, attempts", [
    (1.0e4, 20, {"hard", "relaxed", "relaxed_alone"}),
    (1.0e4, None, {"hard", "relaxed"}),
    (None, 20, {"hard"}),  # hard constraints: no relaxed problem to start from alone
])
def test_the_acados_backend_gets_the_problem_and_one_solver_per_attempt(monkeypatch, slack, budget, attempts):
    # acados itself is not needed: its library, layout and solvers are stood in for, recording
    # what the controller passes them
    seen = {}

    def library(params, settings, state_scale, input_scale, nlp):
        seen["nlp"] = nlp
        return "library"

    def solvers(library, problem, layout, iterations):
        seen["iterations"] = iterations
        return "solvers"

    monkeypatch.setattr(nmpc_acados, "AcadosLibrary", library)
    monkeypatch.setattr(nmpc_acados, "AcadosLayout", SimpleNamespace(of=lambda *args: "layout"))
    monkeypatch.setattr(nmpc_acados, "AcadosSolvers", solvers)
    ctrl = controller(collision_slack_weight=slack, iteration_budget=budget)
    assert ctrl._acados_solvers() == ("library", "solvers")
    assert seen["nlp"] is ctrl.problem.nlp  # its cache key is made from the problem
    assert set(seen["iterations"]) == attempts
    ctrl.close()


# ------------------------------------------------------------------ options and settings

def test_the_sqp_method_takes_its_options_and_solves_quietly(capfd):
    # CasADi refuses an option name it does not know, in the SQP method and in its QP solver
    x = ca.SX.sym("x", 2)
    nlp = {"x": x, "f": (x[0] - 1.0) ** 2 + (x[1] - 2.0) ** 2, "g": x[0] + x[1]}
    solver = ca.nlpsol("quiet_sqp", "sqpmethod", nlp, solver_options("sqpmethod", [], 50, None))
    result = solver(x0=[0.0, 0.0], lbg=-np.inf, ubg=2.0)
    assert solver.stats()["success"]
    np.testing.assert_allclose(np.array(result["x"]).ravel(), [0.5, 1.5], atol=1e-6)
    assert capfd.readouterr().out == ""


def test_real_time_iterations_outside_acados_are_refused_with_the_setting_named():
    with pytest.raises(ValueError, match="real_time_iterations needs solver = 'acados', got solver = 'fatrop'"):
        NMPCSettings(solver="fatrop", real_time_iterations=True)


# ------------------------------------------------------------------ the end of an alteration

@pytest.mark.parametrize("tcpa_s, range_factor, ends", [
    (0.0, 1.0, True),  # past, at exactly the clear range: "at least" it
    (-60.0, 1.5, True),
    (0.0, 0.999, False),  # past but not yet clear
    (1.0, 1.5, False),  # clear but still closing
])
def test_an_alteration_ends_once_the_target_is_past_and_at_least_the_clear_range_off(tcpa_s, range_factor, ends):
    separation = 2.0 * NM
    clear = ALTERATION_CLEAR_FACTOR * separation
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    domains._altering[0] = (0.0, 0.0, np.radians(35.0), 1)
    encounter = SimpleNamespace(tcpa_s=tcpa_s, range_m=range_factor * clear, encounter_class="crossing_give_way")
    domains._update_alteration(0, encounter, 0.0, np.radians(35.0), 600.0, separation)
    assert (0 in domains._altered) == ends
    assert (0 in domains._altering) == (not ends)


def test_a_fallback_plan_whose_rollout_fails_holds_the_measured_state_and_forgets_the_plan():
    # the model's evaluation failing (CasADi raises RuntimeError): the fallback inputs are still
    # applied, the predicted states hold the measured one, and no warm start is kept from them
    def failing_rollout(state, inputs, disturbance=None):
        raise RuntimeError("evaluation failed")

    memory = memory_with_a_plan()
    memory.rollout = failing_rollout
    state = np.array([100.0, 200.0, 0.1, 5.0, 0.0, 0.0])
    states, inputs = memory.fallback_plan(2 * DT, state, np.array([9.0, 9.0]), TAU_MAX, np.zeros(5))
    np.testing.assert_array_equal(inputs, [[3.0, 30.0], [3.5, 40.0], [3.5, 40.0], [3.5, 40.0]])
    np.testing.assert_array_equal(states, np.repeat(state[None, :], N + 1, axis=0))
    assert memory.states is None and memory.inputs is None
