"""How the NMPC spends its solves: a fresh fatrop object per solve, the relaxed problem first
after a step without a clearance-keeping plan, and points the solver stopped at as acceptable
used only when they keep every constraint."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from rhnc.control.nmpc import NMPCController, NMPCSettings, renew_rule
from rhnc.control.nmpc_problem import renew_solver_after
from rhnc.control.solve_pace import CONTINUATION_MIN_ITERATIONS, IterationPace
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set
from rhnc.control.solver_watchdog import FATROP_ACCEPTABLE_FLAG, WALL_TIME_STATUS, BoundedSolver, _outcome
from solver_stand_ins import solvers_replaced

KNOT = 1852.0 / 3600.0
DT = 20.0
N = 15


class StatefulSolver:
    """Counts the calls it has served, as a fatrop object keeps data of its last solve."""

    def __init__(self):
        self.calls = 0

    def __call__(self, **arguments):
        self.calls += 1
        return {"x": np.asarray(arguments["x0"]), "g": np.zeros(1), "f": 0.0}

    def stats(self):
        return {"success": True, "iter_count": self.calls, "return_status": "Solve_Succeeded"}


@pytest.mark.parametrize("wall_time_s", [None, 30.0], ids=["in-process", "worker"])
@pytest.mark.parametrize("renew, served", [(None, [1, 2, 3, 4, 5]), (lambda outcome: True, [1, 1, 1, 1, 1]),
                                           (lambda outcome: outcome.iterations > 2, [1, 2, 3, 1, 2])],
                         ids=["never", "always", "after-2-calls"])
def test_solver_objects_are_renewed_after_the_outcomes_the_rule_names(renew, served, wall_time_s):
    bounded = BoundedSolver({"nlp": StatefulSolver()}, {"nlp": StatefulSolver}, wall_time_s=wall_time_s, renew=renew)
    calls = [bounded.solve("nlp", x0=np.zeros(2)).iterations for _ in range(5)]
    bounded.close()
    assert calls == served


def test_renewed_solvers_need_a_factory_for_each_name():
    with pytest.raises(ValueError, match="none for nlp"):
        BoundedSolver({"nlp": StatefulSolver()}, {}, wall_time_s=None, renew=lambda outcome: True)


@pytest.mark.parametrize("success, iterations, renew", [(True, 6, False), (True, 7, True), (False, 3, True)])
def test_a_new_fatrop_object_follows_a_failed_or_long_solve(success, iterations, renew):
    assert renew_solver_after(SimpleNamespace(success=success, iterations=iterations)) is renew


class Stopped:
    """A solver result with fatrop's statistics of a stop at ``flag``."""

    def __init__(self, flag):
        self.flag = flag

    def stats(self):
        return {"success": self.flag == 0, "iter_count": 7, "return_status": 0 if self.flag == 0 else 1,
                "fatrop": {"return_flag": self.flag}}


@pytest.mark.parametrize("flag, acceptable", [(0, False), (1, False), (FATROP_ACCEPTABLE_FLAG, True)])
def test_fatrop_stop_at_an_acceptable_point_is_reported_apart(flag, acceptable):
    outcome = _outcome(Stopped(flag), {"x": np.zeros(2), "g": np.zeros(1), "f": 0.0}, 0.0, 0.0)
    assert outcome.acceptable is acceptable
    assert outcome.success is (flag == 0)


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


@pytest.fixture(scope="module")
def controller(kcs):
    return NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT, max_obstacles=1,
                                            wall_time_limit_s=None, cpu_time_limit_s=None))


def straight(course=0.3, speed=18 * KNOT):
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    return state, (lambda t: line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed))


class CallLog:
    """Records the names of the solver calls a controller makes."""

    def __init__(self, controller):
        self.names = []
        self.bounded = controller.solvers
        self.solve = self.bounded.solve

        def logged(name, **arguments):
            self.names.append(name)
            return self.solve(name, **arguments)

        self.bounded.solve = logged

    def detach(self):
        del self.bounded.solve


def test_after_a_step_without_a_clearance_keeping_plan_the_relaxed_problem_is_solved_alone(controller):
    state, reference_at = straight()
    course = state[2]
    # an obstacle 300 m off the starboard bow with a 500 m radius: the ship is inside it
    inside = np.array([[300 * math.cos(course + 0.5), 300 * math.sin(course + 0.5), 0.0, 0.0, 500.0]])
    controller.reset()
    log = CallLog(controller)
    try:
        first = controller.solve(0.0, state, reference_at(0.0), inside, et=True)
        assert first.success and first.collision_slack > 0
        assert log.names == ["hard", "relaxed"]
        log.names.clear()
        second = controller.solve(DT, first.states[1], reference_at(DT), inside, et=True)
        assert second.success
        assert log.names == ["relaxed"]  # the hard problem is not tried again
        # once a plan keeps the clearance again (obstacle far away), the hard problem comes first
        far = inside + np.array([[5e4, 5e4, 0.0, 0.0, 0.0]])
        third = controller.solve(2 * DT, second.states[1], reference_at(2 * DT), far, et=True)
        assert third.success and third.collision_slack == 0.0
        log.names.clear()
        controller.solve(3 * DT, third.states[1], reference_at(3 * DT), far, et=True)
        assert log.names == ["hard"]
    finally:
        log.detach()


class AcceptableStop:
    """Wraps a solver: reports fatrop's acceptable stop, optionally moving the point off the
    dynamics (a point that does not keep its constraints)."""

    def __init__(self, solver, offset):
        self.solver, self.offset = solver, offset

    def __call__(self, **arguments):
        result = dict(self.solver(**arguments))
        result["x"] = np.array(result["x"]).ravel() + self.offset
        return result

    def stats(self):
        return {**self.solver.stats(), "success": False, "return_status": 1,
                "fatrop": {"return_flag": FATROP_ACCEPTABLE_FLAG}}


@pytest.mark.parametrize("offset, used", [(0.0, True), (1e-3, False)])
def test_an_acceptable_point_is_used_only_when_it_keeps_the_constraints(controller, offset, used):
    state, reference_at = straight()
    controller.reset()
    # both attempts stop at the same kind of point
    with solvers_replaced(controller, lambda name, solver: AcceptableStop(solver, offset)):
        solution = controller.solve(0.0, state, reference_at(0.0))
    assert solution.success is used and solution.fallback is not used
    if used:
        assert solution.status == "Solved_To_Acceptable_Level"
    else:
        assert solution.constraint_violation > 1e-6


class RefusingSolver:
    """A solver whose call raises, as CasADi does for an option its fatrop does not know."""

    def __call__(self, **arguments):
        raise RuntimeError("Error in Function::call for 'rhnc_nmpc' [FatropInterface]:\n"
                           "Fatrop option not supported: tol_acceptable")


@pytest.mark.parametrize("wall_time_s", [None, 30.0], ids=["in-process", "worker"])
def test_a_solver_that_raises_reports_its_error_with_or_without_the_worker(wall_time_s):
    bounded = BoundedSolver({"nlp": RefusingSolver()}, {"nlp": RefusingSolver}, wall_time_s=wall_time_s)
    for _ in range(2):   # the worker goes on serving after an error
        with pytest.raises(RuntimeError, match="Fatrop option not supported: tol_acceptable"):
            bounded.solve("nlp", x0=np.zeros(2))
    bounded.close()


class OutOfIterations:
    """Wraps a solver: reports a stop at the iteration limit ``cap`` (not converged), optionally
    moving the point off the dynamics."""

    def __init__(self, solver, offset, cap):
        self.solver, self.offset, self.cap = solver, offset, cap

    def __call__(self, **arguments):
        result = dict(self.solver(**arguments))
        result["x"] = np.array(result["x"]).ravel() + self.offset
        return result

    def stats(self):
        return {**self.solver.stats(), "success": False, "return_status": 1, "iter_count": self.cap,
                "fatrop": {"return_flag": 1}}


@pytest.fixture(scope="module")
def budgeted(kcs):
    return NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT, max_obstacles=1,
                                            wall_time_limit_s=None, cpu_time_limit_s=None, iteration_budget=30))


def test_with_a_budget_each_step_is_one_attempt_with_the_whole_budget(budgeted):
    assert budgeted.attempt_iterations["relaxed_alone"] == 30
    state, reference_at = straight()
    budgeted.reset()
    log = CallLog(budgeted)
    try:
        budgeted.solve(0.0, state, reference_at(0.0))
        assert log.names == ["relaxed_alone"]   # never half the budget on a hard attempt first
    finally:
        log.detach()


def test_with_a_budget_a_feasible_step_plans_as_the_hard_problem(budgeted, controller):
    """The relaxed problem's L1 penalty is exact: where the clearance can be kept, its plan
    keeps it (no slack) and is the hard problem's plan."""
    state, reference_at = straight()
    course = state[2]
    # an obstacle 3 km ahead on the track, radius 1 km: a turn keeps clear of it
    ahead = np.array([[3000 * math.cos(course), 3000 * math.sin(course), 0.0, 0.0, 1000.0]])
    budgeted.reset()
    controller.reset()
    relaxed = budgeted.solve(0.0, state, reference_at(0.0), ahead, et=True)
    hard = controller.solve(0.0, state, reference_at(0.0), ahead, et=True)
    assert relaxed.success and hard.success and hard.collision_slack == 0.0
    assert relaxed.collision_slack == 0.0
    assert np.max(np.hypot(*(relaxed.states[:, :2] - hard.states[:, :2]).T)) < 5.0   # metres


@pytest.mark.parametrize("offset, used", [(0.0, True), (1e-3, False)])
def test_a_point_at_the_end_of_the_budget_is_used_only_when_it_keeps_the_constraints(budgeted, offset, used):
    state, reference_at = straight()
    budgeted.reset()
    with solvers_replaced(budgeted, lambda name, solver: OutOfIterations(solver, offset,
                                                                          budgeted.attempt_iterations[name])):
        solution = budgeted.solve(0.0, state, reference_at(0.0))
    assert solution.success is used and solution.fallback is not used
    if used:
        assert solution.status == "Iteration_Budget_Feasible_Point"


def step_with_capped_stand_ins(controller, monkeypatch, stand_in, state, reference):
    """One step of ``controller`` whose solver objects, built with a cap or without, are
    ``stand_in(solver, cap)``; its own objects are back afterwards, also on failure."""
    for name, build in list(controller.solvers.factories.items()):
        monkeypatch.setitem(controller.solvers.factories, name,
                            lambda cap=None, build=build: stand_in(build(cap), cap))
    real, caps = dict(controller.solvers._solvers), dict(controller.solvers._caps)
    try:
        return controller.solve(0.0, state, reference)
    finally:
        controller.solvers._solvers.update(real)
        controller.solvers._caps.update(caps)


def test_a_point_at_the_cap_the_measured_pace_set_is_used_as_at_the_end_of_the_budget(budgeted, monkeypatch):
    """A solve capped below its budget by the processor time per iteration (solve_pace) that
    stops at its cap, at a point keeping the constraints, has found a plan."""
    state, reference_at = straight()
    budgeted.reset()
    asked = []
    monkeypatch.setattr(budgeted.pace, "cap", lambda allowed: asked.append(allowed) or 12)
    solution = step_with_capped_stand_ins(budgeted, monkeypatch, lambda solver, cap: OutOfIterations(solver, 0.0, cap),
                                          state, reference_at(0.0))
    assert asked == [30]
    assert solution.success and solution.status == "Iteration_Budget_Feasible_Point"
    assert solution.iterations == 12


def test_a_solve_stopped_at_the_cap_of_an_estimated_pace_goes_on_from_its_iterate_in_the_step(budgeted,
                                                                                                monkeypatch):
    """With processor time left in the step, an infeasible point at the cap is not the end:
    the same attempt goes on from it, capped at what the time left allows, within the budget."""
    state, reference_at = straight()
    budgeted.reset()
    pace = IterationPace(0.2)
    pace.record(100, 1.0, False, 200)  # 10 ms an iteration: the budget of 30 does not fit
    first_cap = pace.cap(30)
    monkeypatch.setattr(budgeted, "pace", pace)
    calls = []

    class Recording(OutOfIterations):
        def __call__(self, **arguments):
            calls.append((self.cap, np.array(arguments["x0"], dtype=float)))
            result = super().__call__(**arguments)
            calls[-1] += (np.array(result["x"], dtype=float),)
            return result

    solution = step_with_capped_stand_ins(budgeted, monkeypatch, lambda solver, cap: Recording(solver, 1e-3, cap),
                                          state, reference_at(0.0))
    assert first_cap == 17 and len(calls) == 2 and calls[0][0] == 17
    # the second: what the time left allows at 10 ms an iteration, at most the 13 left of the budget of 30
    assert CONTINUATION_MIN_ITERATIONS <= calls[1][0] <= 13
    np.testing.assert_array_equal(calls[1][1], calls[0][2])  # from the first solve's point
    assert solution.fallback and solution.iterations == 17 + calls[1][0]  # still off the constraints


def test_a_going_on_solve_the_timer_ended_leaves_the_point_it_went_on_from(budgeted, monkeypatch):
    """Should the worker's timer end the solve that went on from a point at the cap, that
    point is still the next step's warm start, and the step is flagged as stopped by time."""
    state, reference_at = straight()
    budgeted.reset()
    pace = IterationPace(0.2)
    pace.record(100, 1.0, False, 200)  # 10 ms an iteration: capped at 17, then going on
    monkeypatch.setattr(budgeted, "pace", pace)
    solve, points, kept = budgeted.solvers.solve, [], []

    def timer_ends_the_second(name, **arguments):
        if points:  # the going-on solve: ended by the timer
            stopped = BoundedSolver._stopped(arguments, 0.05, WALL_TIME_STATUS)
            stopped.stopped_by, stopped.cpu_time_s = "cpu", 0.05
            return stopped
        outcome = solve(name, **arguments)
        points.append(outcome.x.copy())
        return outcome

    monkeypatch.setattr(budgeted.solvers, "solve", timer_ends_the_second)
    monkeypatch.setattr(budgeted.memory, "keep_iterate", lambda time_s, states, *rest: kept.append(states))
    solution = step_with_capped_stand_ins(budgeted, monkeypatch, lambda solver, cap: OutOfIterations(solver, 1e-3, cap),
                                          state, reference_at(0.0))
    assert solution.fallback and solution.timed_out and solution.iterations == 17
    assert len(points) == 1 and len(kept) == 1
    first = points[0][budgeted.problem.z_index] * budgeted.state_scale  # heading and speeds: not shifted
    np.testing.assert_allclose(kept[0][:, 2:], first[:, 2:])


def test_without_a_budget_a_point_at_the_iteration_limit_is_not_used(controller):
    state, reference_at = straight()
    controller.reset()
    with solvers_replaced(controller, lambda name, solver: OutOfIterations(solver, 0.0,
                                                                            controller.settings.max_iterations)):
        solution = controller.solve(0.0, state, reference_at(0.0))
    assert solution.fallback


def test_a_budget_outside_its_range_is_refused():
    with pytest.raises(ValueError, match="iteration_budget must be from 2 to max_iterations"):
        NMPCSettings(iteration_budget=1)
    with pytest.raises(ValueError, match="iteration_budget must be from 2 to max_iterations"):
        NMPCSettings(iteration_budget=500)


def test_with_a_budget_a_step_after_a_failed_one_is_again_one_relaxed_attempt(budgeted):
    state, reference_at = straight()
    budgeted.reset()
    log = CallLog(budgeted)
    # the attempt runs out at an infeasible point
    with solvers_replaced(budgeted, lambda name, solver: OutOfIterations(solver, 1e-3,
                                                                          budgeted.attempt_iterations[name])):
        try:
            assert budgeted.solve(0.0, state, reference_at(0.0)).fallback
            assert log.names == ["relaxed_alone"]
            log.names.clear()
            budgeted.solve(DT, state, reference_at(DT))
            assert log.names == ["relaxed_alone"]
        finally:
            log.detach()


def test_a_buffered_solver_call_gives_the_keyword_call_to_the_bit_with_the_defaults_of_inputs_not_given():
    """The NLP solved through CasADi's argument buffers returns what the keyword call returns
    (every output, the status and the iteration count), an input left out taking the solver's
    default: here lbx = -inf lets the minimum lie at x = (-1, -2)."""
    import casadi as ca

    from rhnc.control.solver_watchdog import BufferedCall, _timed_call

    x = ca.SX.sym("x", 2)
    p = ca.SX.sym("p", 2)
    nlp = {"x": x, "p": p, "f": ca.sumsqr(x - p) + 0.1 * x[0] ** 4, "g": x[0] + x[1]}
    solver = ca.nlpsol("s", "ipopt", nlp, {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}})
    arguments = {"x0": np.array([0.5, 0.5]), "p": np.array([-1.0, -2.0]), "ubx": np.array([5.0, 5.0]),
                 "lbg": np.array([-10.0]), "ubg": np.array([10.0])}
    keyword = solver(**arguments)
    stats = solver.stats()
    call = BufferedCall.of(solver)
    buffered = call(arguments)
    for name in ("x", "g", "lam_x", "lam_g"):
        np.testing.assert_array_equal(buffered[name], np.array(keyword[name]).ravel())
    assert buffered["f"] == float(keyword["f"])
    assert buffered["x"][1] < -1.5  # the default lower bound (-inf), not zero
    assert call.stats()["iter_count"] == stats["iter_count"] and call.stats()["success"]
    outcome = _timed_call(solver, arguments)
    assert outcome.success and outcome.iterations == stats["iter_count"]
    np.testing.assert_array_equal(outcome.x, np.array(keyword["x"]).ravel())


def test_with_a_budget_every_solve_gets_a_new_solver_object():
    """A fatrop object kept over a run of short solves ran past its iteration limit (990 of
    90 iterations) on the next step; with a budget, no object serves two solves."""
    short = SimpleNamespace(success=True, iterations=3)
    assert renew_rule("fatrop", True, 90)(short)
    assert not renew_rule("fatrop", True, None)(short)   # without a budget (the paper's mode): unchanged
    assert renew_rule("fatrop", False, 90) is None       # interpreted: a new object costs 0.5 s
