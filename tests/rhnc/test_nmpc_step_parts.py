"""More of the NMPC's parts checked alone, without solving: the fallback plan kept in the plan
memory, the terminal weight's linearisation, the speed it is taken at, the attempts the acados
backend is given, the SQP method's options, a settings message and the end of an alteration;
the time limit and status of a step's attempts (with stand-in solvers), the shortest horizon,
the collision slack, the multipliers' warm start, which obstacles get the slots, the domain of
a target inside its clearance and the fallback's steering law.

The controllers are small (4 intervals, the NLP interpreted, no compiler); the plan memory gets a
toy rollout of its own.
"""

import math
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from rhnc.control import nmpc_acados
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.control.nmpc_alteration import STEERING_BAND_DEG, YAW_TIME_CONSTANT_S, alteration_steering
from rhnc.control.nmpc_actions import ALTERATION_CLEAR_FACTOR
from rhnc.control.nmpc_colregs import INSIDE_OPENING_MPS, INSIDE_RESPONSE_S, CollisionDomains, DomainSettings
from rhnc.control.nmpc_problem import DISTURBANCE_SIZE, OBSTACLE_FIELDS, solver_options, stage_function
from rhnc.control.nmpc_warm_start import PlanMemory
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set

NM = 1852.0
KNOT = NM / 3600.0
N = 4
DT = 20.0
SPEED = 12 * KNOT
L_SHIP = 230.0


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


def test_the_sqp_method_stops_only_once_the_constraints_hold():
    # from x = 0 the constraint x = 0.5 is violated by 0.5 while the objective has nothing to
    # say (zero gradient): the method must go on to x = 0.5, not stop at the start
    x = ca.SX.sym("x")
    solver = ca.nlpsol("feasible_sqp", "sqpmethod", {"x": x, "f": 0 * x, "g": x},
                       solver_options("sqpmethod", [], 50, None))
    result = solver(x0=0.0, lbg=0.5, ubg=0.5)
    assert float(result["x"]) == pytest.approx(0.5, abs=1e-6)


def test_a_single_integration_substep_is_a_valid_setting():
    assert NMPCSettings(substeps=1).substeps == 1
    with pytest.raises(ValueError, match="substeps"):
        NMPCSettings(substeps=0)


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


# ------------------------------------------------------------------ the attempts of a step

class RecordingSolvers:
    """Stands in for the controller's bounded solvers: hands out the given outcomes in turn and
    records the wall-time limit each attempt was given."""

    def __init__(self, outcomes):
        self.outcomes = list(outcomes)
        self.factories = {"hard": None, "relaxed": None, "relaxed_alone": None}
        self.wall_time_s = None
        self.limits: list = []
        self.attempts: list = []

    def solve(self, attempt, **_):
        self.limits.append(self.wall_time_s)
        self.attempts.append(attempt)
        return self.outcomes.pop(0)


def outcome(problem, *, success=False, acceptable=False, wall_time_s=0.1, iterations=10, status="Infeasible"):
    """A solver's answer at a point that keeps every bound (zeros: the dynamics rows hold, the
    clearances are not negative)."""
    return SimpleNamespace(x=np.zeros(problem.size), g=np.zeros(problem.lbg.size), f=1.0, success=success,
                           acceptable=acceptable, timed_out=False, wall_time_s=wall_time_s, cpu_time_s=0.0,
                           preparation_cpu_s=0.0, build_cpu_s=0.0, iterations=iterations, status=status, stopped_by="",
                           lam_x=np.zeros(problem.size), lam_g=np.zeros(problem.lbg.size))


def step_of(problem):
    return SimpleNamespace(lbx=np.full(problem.size, -np.inf), ubx=np.full(problem.size, np.inf),
                           x0=np.zeros(problem.size), p=np.zeros(1), report=SimpleNamespace(danger=False))


@pytest.mark.parametrize("first_s, second_limit", [(0.2, 0.3), (0.5, 1e-3), (0.7, 1e-3)])
def test_the_relaxed_attempt_gets_what_the_hard_one_left_of_the_time_limit_or_a_millisecond(first_s, second_limit):
    nmpc = controller(wall_time_limit_s=0.5)
    problem = nmpc.problem
    nmpc.solvers = RecordingSolvers([outcome(problem, wall_time_s=first_s),
                                     outcome(problem, success=True, status="Solve_Succeeded")])
    tally = nmpc._attempts(0.0, step_of(problem))
    assert nmpc.solvers.attempts == ["hard", "relaxed"]
    assert nmpc.solvers.limits[0] == pytest.approx(0.5)
    assert nmpc.solvers.limits[1] == pytest.approx(second_limit)
    assert tally.success and tally.relaxed


def test_an_acceptable_point_that_keeps_the_constraints_is_reported_as_solved_to_an_acceptable_level():
    nmpc = controller()
    problem = nmpc.problem
    nmpc.solvers = RecordingSolvers([outcome(problem, acceptable=True, status="Maximum_Iterations_Exceeded")])
    tally = nmpc._attempts(0.0, step_of(problem))
    assert tally.accepted and tally.success
    assert tally.status == "Solved_To_Acceptable_Level"


def test_a_point_at_the_end_of_the_iteration_budget_that_keeps_the_constraints_is_reported_as_such():
    nmpc = controller(iteration_budget=20)
    problem = nmpc.problem
    limit = nmpc.attempt_iterations["relaxed_alone"]
    nmpc.solvers = RecordingSolvers([outcome(problem, iterations=limit, status="Maximum_Iterations_Exceeded")])
    tally = nmpc._attempts(0.0, step_of(problem))
    assert nmpc.solvers.attempts == ["relaxed_alone"]  # with a budget, the relaxed problem alone
    assert tally.out_of_budget and tally.accepted
    assert tally.status == "Iteration_Budget_Feasible_Point"


def test_a_horizon_of_one_interval_is_accepted_and_none_refused_with_the_setting_named():
    one = NMPCController(load_parameter_set("default"), NMPCSettings(horizon_steps=1, control_interval_s=DT,
                                                                     codegen=False))
    assert one.problem.z_index.size == 12  # the measured state and one more
    with pytest.raises(ValueError, match="horizon_steps"):
        NMPCSettings(horizon_steps=0)


# ------------------------------------------------------------------ the slack, the multipliers

def test_a_collision_slack_relaxes_every_clearance_of_its_interval_by_its_value_and_no_dynamics_row():
    stage = stage_function(load_parameter_set("default"), DT, 2, 2, [1.0] * 6, [1.0] * 2, [1.0] * 2, 10.0,
                           np.ones(6), np.ones(2))
    obs = np.zeros((OBSTACLE_FIELDS, 2))
    # one slot in use (cx, cy, vx, vy, offset, rho, growth, inflation, active), the other not
    obs[:, 0] = [500.0, 100.0, -3.0, 0.0, 0.0, 0.0, 200.0, 1.0, 0.1, 1.0]
    obs[:, 1] = [900.0, 100.0, 0.0, 0.0, 0.0, 0.0, 200.0, 1.0, 0.1, 0.0]
    args = [np.array([0.0, 0.0, 0.0, 5.0, 0.0, 0.0]), np.zeros(2), None, np.zeros(6), np.zeros(2), np.zeros(6),
            np.zeros(2), np.zeros(DISTURBANCE_SIZE), obs, 0.0, 1.0]

    def g(sigma):
        args[2] = [sigma]
        return np.array(stage(*args)[1]).ravel()

    difference = g(0.3) - g(0.0)
    np.testing.assert_allclose(difference[:6], 0.0, atol=1e-12)
    assert difference.size == 6 + 2 * 2  # a clearance per substep and slot
    np.testing.assert_allclose(difference[6:], 0.3, atol=1e-12)
    assert g(0.0)[7] == g(0.0)[9] == 1.0  # the inactive slot: 1 >= 0
    assert g(0.0)[6] != g(0.0)[8]  # the target and the ship move between the substeps


def test_the_multipliers_of_the_last_solve_are_the_next_step_s_dual_guess_shifted_by_the_steps_since():
    memory = memory_with_a_plan()
    # N stage blocks of 3 bound multipliers and the last state's 6; N blocks of 2 constraint ones
    lam_x = np.r_[np.repeat(np.arange(1.0, N + 1), 3), np.full(6, 9.0)]
    lam_g = np.repeat(np.arange(10.0, 10.0 + N), 2)
    memory.store(0.0, memory.states, memory.inputs, lam_x, lam_g)
    guess = memory.dual_guess(DT)
    np.testing.assert_array_equal(guess["lam_x0"], np.r_[np.repeat([2.0, 3.0, 4.0, 4.0], 3), np.full(6, 9.0)])
    np.testing.assert_array_equal(guess["lam_g0"], np.repeat([11.0, 12.0, 13.0, 13.0], 2))
    assert memory.dual_guess((N + 1) * DT) == {}  # past the plan's horizon: no guess


# ------------------------------------------------------------------ domains and steering

def test_the_obstacle_slots_go_to_the_nearest_rims_measured_from_the_problem_s_origin():
    # the own ship at 3 km north, 1 km east: a large domain's rim is nearer than a small
    # domain's centre, and a target abeam at the own ship's north is farther than one that
    # only looks near when the north and east offsets are mixed up
    state = np.array([3000.0, 1000.0, 0.0, SPEED, 0.0, 0.0])
    large = [3000.0, 5500.0, 0.0, 0.0, 2000.0]  # centre 4.5 km off, rim 2.5 km
    small = [3000.0, -1000.0, 0.0, 0.0, 10.0]  # centre 2 km off, rim 1.99 km
    decoy = [1000.0, 3000.0, 0.0, 0.0, 10.0]  # 2.83 km off; 2 km if the east offset took the north
    for rows, nearest in (([large, [3000.0, 4200.0, 0.0, 0.0, 10.0]], 0), ([small, decoy], 0)):
        domains = CollisionDomains(DomainSettings(colregs=False), max_obstacles=1)
        # the problem's origin is the own ship's position, as the controller sets it
        _, report = domains.parameters(np.array(rows), state, state[:2].copy(), SPEED, 5.0, L_SHIP, et=True)
        assert list(report.active).index(1.0) == nearest


def test_a_target_inside_its_clearance_keeps_at_least_a_quarter_of_the_present_range():
    domains = CollisionDomains(DomainSettings(colregs=True), max_obstacles=1)
    row = np.array([400.0, 0.0, -30.0, 0.0, 200.0])
    # closing at 30 m/s: the range less what it closes in the response time would be negative
    offset, radius, growth = domains._domain(row, 300.0, "head_on", np.zeros(2), 400.0, -30.0, inside=True)
    np.testing.assert_array_equal(offset, [0.0, 0.0])
    assert radius == pytest.approx(0.25 * 400.0)
    assert growth == INSIDE_OPENING_MPS
    # closing slowly: the range less what it closes in the response time
    _, radius, _ = domains._domain(row, 300.0, "head_on", np.zeros(2), 400.0, -1.0, inside=True)
    assert radius == pytest.approx(400.0 - INSIDE_RESPONSE_S)


def test_the_fallback_steering_eases_its_moment_by_the_yaw_rate_towards_the_goal():
    report = SimpleNamespace(escape_heading=0.3, alteration_floor=None, alteration_ceiling=None)
    steer = alteration_steering(report, 100.0)
    band = math.radians(STEERING_BAND_DEG)
    error = 0.05  # the goal 0.05 rad to starboard
    assert steer(0.25, 0.0) == pytest.approx(100.0 * error / band)
    turning = 0.002  # already turning towards it
    assert steer(0.25, turning) == pytest.approx(100.0 * (error - YAW_TIME_CONSTANT_S * turning) / band)
    assert steer(0.25, -turning) == pytest.approx(100.0 * (error + YAW_TIME_CONSTANT_S * turning) / band)
