"""NMPC: tracking (line, turn), input bounds, collision constraint between samples, fallback."""

import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.control.control_participant import ControlParticipant, interpolate_reference
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

NM = 1852.0
KNOT = NM / 3600.0
DT = 20.0
N = 15


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


@pytest.fixture(scope="module")
def controller(kcs):
    return NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT))


def closed_loop(controller, kcs, reference_at, state, steps, obstacles=None, plant_dt=0.5):
    """Run NMPC + numpy plant; return states at plant_dt, applied inputs and solutions."""
    controller.reset()
    trajectory, inputs, solutions = [state.copy()], [], []
    for k in range(steps):
        t = k * DT
        obs = None if obstacles is None else obstacles(t)
        solution = controller.solve(t, state, reference_at(t), obs, et=obstacles is not None)
        solutions.append(solution)
        inputs.append(solution.tau)
        for _ in range(int(round(DT / plant_dt))):
            state = rk4_step(state, solution.tau, plant_dt, 1, kcs)
            trajectory.append(state.copy())
    return np.array(trajectory), np.array(inputs), solutions


def test_tracks_a_straight_line_from_a_lateral_offset(controller, kcs, raw_nmpc_inputs):
    raw_nmpc_inputs.attach(controller)
    course = math.radians(45.0)
    speed = 18 * KNOT

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    start = np.array([-300.0 * math.sin(course), 300.0 * math.cos(course), course, 14 * KNOT, 0.0, 0.0])
    trajectory, inputs, solutions = closed_loop(controller, kcs, reference_at, start, 50)
    cross_track = -np.sin(course) * trajectory[:, 0] + np.cos(course) * trajectory[:, 1]
    assert abs(cross_track[0]) == pytest.approx(300.0)
    after_transient = cross_track[int(500.0 / 0.5) :]  # after 500 s (25 control intervals)
    assert np.max(np.abs(after_transient)) < 0.05 * NM
    assert abs(cross_track[-1]) < 15.0
    assert raw_nmpc_inputs.largest() <= 1.0 + 1e-6  # the optimiser's own plans, before the clip
    assert trajectory[-1, 3] == pytest.approx(speed, rel=0.02)
    assert all(s.success and not s.fallback for s in solutions)


def test_tracks_a_constant_radius_turn(controller, kcs, raw_nmpc_inputs):
    raw_nmpc_inputs.attach(controller)
    radius = 2.0 * NM  # starboard turn at 18 kn, well inside the ship's turning ability
    speed = 18 * KNOT

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), 0.0, speed, radius)

    start = reference_at(0.0)[0]
    start[5] = 0.0  # entering the turn from straight motion
    trajectory, inputs, _ = closed_loop(controller, kcs, reference_at, start, 45)
    centre = np.array([0.0, radius])
    radial_error = np.hypot(trajectory[:, 0] - centre[0], trajectory[:, 1] - centre[1]) - radius
    assert np.max(np.abs(radial_error[len(radial_error) // 3 :])) < 0.05 * NM
    assert trajectory[-1, 2] > 2.0  # really turned (> 115 deg)
    assert raw_nmpc_inputs.largest() <= 1.0 + 1e-6  # the optimiser's own plans, before the clip


def test_passes_a_static_obstacle_on_the_track_outside_its_radius(kcs, raw_nmpc_inputs):
    own_radius = 0.2 * NM
    controller = NMPCController(kcs, NMPCSettings(own_radius_m=own_radius))
    course, speed = math.radians(45.0), 18 * KNOT
    centre = 2.0 * NM * np.array([math.cos(course), math.sin(course)])
    obstacle = np.array([[centre[0], centre[1], 0.0, 0.0, 0.5 * NM]])

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    start = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    trajectory, inputs, solutions = closed_loop(controller, kcs, reference_at, start, 45, lambda t: obstacle)
    distance = np.hypot(trajectory[:, 0] - centre[0], trajectory[:, 1] - centre[1])
    assert distance.min() >= own_radius + 0.5 * NM  # checked every 0.5 s, not only at samples
    assert distance.min() < own_radius + 0.5 * NM + 0.1 * NM  # and it did pass close, not stop
    along = trajectory[-1, 0] * math.cos(course) + trajectory[-1, 1] * math.sin(course)
    assert along > 3.0 * NM  # got past the obstacle
    assert raw_nmpc_inputs.largest() <= 1.0 + 1e-6  # the optimiser's own plans, before the clip
    assert all(s.success for s in solutions)


def test_infeasible_solve_falls_back_to_the_shifted_plan(kcs):
    # hard collision constraints: an obstacle on the ship makes the problem infeasible
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT,
                                                  collision_slack_weight=None))
    course, speed = 0.3, 18 * KNOT

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    controller.reset()
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    first = controller.solve(0.0, state, reference_at(0.0))
    assert first.success and not first.fallback
    assert (controller.fallback_count, controller.failure_count) == (0, 0)  # a fresh controller's counts
    state = rk4_step(state, first.tau, DT, 40, kcs)
    before = controller.fallback_count
    on_the_ship = np.array([[state[0], state[1], 0.0, 0.0, 500.0]])
    second = controller.solve(DT, state, reference_at(DT), on_the_ship, et=True)
    assert not second.success and second.fallback
    assert controller.fallback_count == before + 1 and controller.failure_count == 1
    np.testing.assert_allclose(second.tau, first.inputs[1])  # next input of the previous plan
    # with no previous plan: hold the surge force, zero yaw moment
    controller.reset()
    third = controller.solve(2 * DT, state, reference_at(2 * DT), on_the_ship, et=True, previous_tau=np.array([7e5, 1e8]))
    assert third.fallback
    np.testing.assert_allclose(third.tau, [7e5, 0.0])


def test_soft_constraints_give_the_least_violating_plan_instead_of_failing(controller, kcs):
    course, speed = 0.3, 18 * KNOT
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    reference = line_or_turn_reference(DT * np.arange(N + 1), (0.0, 0.0), course, speed)
    controller.reset()
    # an obstacle 300 m off the starboard bow with a 500 m radius: already inside it
    ahead = np.array([[300 * math.cos(course + 0.5), 300 * math.sin(course + 0.5), 0.0, 0.0, 500.0]])
    solution = controller.solve(0.0, state, reference, ahead, et=True)
    assert solution.success and not solution.fallback
    assert solution.collision_slack > 0
    # the plan opens the distance to the obstacle over the horizon
    distance = np.hypot(solution.states[:, 0] - ahead[0, 0], solution.states[:, 1] - ahead[0, 1])
    assert distance[-1] > distance[0] + 200.0
    # with the obstacle far away the slack is zero: the soft problem is the hard one
    far = ahead + np.array([[5e4, 5e4, 0.0, 0.0, 0.0]])
    controller.reset()
    assert controller.solve(0.0, state, reference, far, et=True).collision_slack < 1e-6


def test_heading_error_is_wrapped(controller, kcs):
    """A reference whose heading is wrapped into (-pi, pi] mid-horizon is the same reference.

    A course just short of pi, turning to starboard through it: written with wrapped
    headings, the reference jumps from about +pi to about -pi part-way along the horizon.
    The second solve starts from the first one's optimum (same time, same previous input):
    with the heading error wrapped in the stage and terminal costs, that plan is still
    optimal and comes back unchanged; with a plain squared error each stage past the jump
    would cost (2 pi)^2 and the solver would move away from it.
    """
    course, speed = math.pi - 0.02, 18 * KNOT
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    reference = line_or_turn_reference(DT * np.arange(N + 1), (0.0, 0.0), course, speed, 3.0 * NM)
    assert reference[-1, 2] > math.pi  # the starboard turn (radius 3 nm) crosses pi
    jumped = reference.copy()
    jumped[:, 2] = np.pi - np.mod(np.pi - jumped[:, 2], 2.0 * np.pi)  # wrapped to (-pi, pi]
    assert jumped[0, 2] > 3.0 and jumped[-1, 2] < -2.0  # the wrapped reference jumps by 2 pi
    held = kcs.equilibrium_tau(speed)
    controller.reset()
    plain = controller.solve(0.0, state, reference, previous_tau=held)
    wrapped = controller.solve(0.0, state, jumped, previous_tau=held)  # warm start: plain's plan
    assert plain.success and wrapped.success
    assert wrapped.cost == pytest.approx(plain.cost, rel=1e-4)
    np.testing.assert_allclose(wrapped.inputs / kcs.tau_max, plain.inputs / kcs.tau_max, atol=1e-3)


def _linearised_scaled_step(controller, speed_mps, delta=1e-6):
    """A, B of the controller's scaled one-interval map about straight motion, by central differences."""
    z0 = np.array([0.0, 0.0, 0.0, speed_mps / controller.speed_scale, 0.0, 0.0])
    w0 = controller.params.equilibrium_tau(speed_mps) / controller.input_scale

    from rhnc.control.nmpc_problem import DISTURBANCE_SIZE

    calm = np.zeros(DISTURBANCE_SIZE)  # no disturbance estimate

    def step(z, w):
        return np.array(controller._F_scaled(z, w, calm)[0]).ravel()

    A = np.column_stack([(step(z0 + delta * e, w0) - step(z0 - delta * e, w0)) / (2 * delta) for e in np.eye(6)])
    B = np.column_stack([(step(z0, w0 + delta * e) - step(z0, w0 - delta * e)) / (2 * delta) for e in np.eye(2)])
    return A, B


def test_terminal_weight_is_the_dare_solution(controller):
    """P solves the discrete Riccati equation of the scaled model linearised at the speed."""
    speed = 9.25  # m/s, on a 0.25 m/s bin of the cache (about 18 kn)
    P = controller.terminal_weight(speed)
    A, B = _linearised_scaled_step(controller, speed)
    Q, R = np.diag(controller.settings.q), np.diag(controller.settings.r)
    gain_term = A.T @ P @ B @ np.linalg.solve(R + B.T @ P @ B, B.T @ P @ A)
    residual = A.T @ P @ A - gain_term + Q - P
    assert np.max(np.abs(residual)) < 1e-5 * np.max(np.abs(P))
    assert np.allclose(P, P.T)
    assert np.all(np.linalg.eigvalsh(P) > 0)
    # the weight follows the speed it is linearised at (a cached P of another speed is wrong)
    slow = controller.terminal_weight(4.0)
    A8, B8 = _linearised_scaled_step(controller, 4.0)
    residual8 = A8.T @ slow @ A8 - A8.T @ slow @ B8 @ np.linalg.solve(R + B8.T @ slow @ B8, B8.T @ slow @ A8) + Q - slow
    assert np.max(np.abs(residual8)) < 1e-5 * np.max(np.abs(slow))


def test_interpolated_reference_holds_last_velocity():
    reference = np.array([[0.0, 0.0, 0.0, 0.0, 5.0, 0.0, 0.0], [10.0, 50.0, 0.0, 0.0, 5.0, 0.0, 0.01]])
    states = interpolate_reference(reference, np.array([5.0, 10.0, 30.0]))
    np.testing.assert_allclose(states[:, 0], [25.0, 50.0, 150.0])
    assert states[2, 5] == 0.0


def context(step_size=20.0):
    return BuildContext("exp.toml: participants.ctrl", Path("."), step_size, 0.0, 2200.0)


def test_participant_rejects_unknown_option():
    with pytest.raises(ScenarioError, match=r"participants.ctrl: unknown option 'horizon' \(valid: .*horizon_steps"):
        ControlParticipant.from_options("ctrl", {"horizon": 15}, context())


def test_participant_rejects_unknown_parameter_set():
    with pytest.raises(ScenarioError, match="participants.ctrl: .*unknown parameter set 'kcs'.*valid: default"):
        ControlParticipant.from_options("ctrl", {"parameter_set": "kcs"}, context())


def test_the_solver_worker_is_started_at_set_up_not_in_the_first_step():
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10}, context())
    assert ctrl.controller.solvers.in_worker and ctrl.controller.solvers._pid is None
    try:
        ctrl.setup(0.0, {})
        assert ctrl.controller.solvers._pid is not None, "the first solve would pay for forking the worker"
    finally:
        ctrl.terminate()


def test_participant_step_outputs(kcs):
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10, "solver": "ipopt"}, context())
    ctrl.setup(0.0, {})
    reference = np.column_stack([np.arange(0.0, 400.0, 20.0), line_or_turn_reference(np.arange(0.0, 400.0, 20.0), (0, 0), 0.0, 9.0)])
    state = {"x": 0.0, "y": 50.0, "psi": 0.0, "u": 9.0, "v": 0.0, "r": 0.0}
    out = ctrl.step(100.0, 20.0, {**state, "reference": reference})
    assert out["prediction"].shape == (11, 7)
    np.testing.assert_allclose(out["prediction"][:, 0], 100.0 + 20.0 * np.arange(11))
    assert out["solver_ok"] == 1.0 and out["fallback"] == 0.0
    assert out["tau_r"] < 0.0  # 50 m east (starboard) of a northbound track: turn to port
    summary = ctrl.summary()
    assert summary["solves"] == 1
    # the whole step's processor time: the solve and the controller's work around it
    assert summary["step_cpu_time_median_s"] >= summary["solve_cpu_time_median_s"] > 0.0


def test_without_a_previous_input_given_the_previous_plans_first_input_is_taken(kcs):
    """The input-rate term starts from the input applied last: the stored plan's first input,
    the same as passing it as ``previous_tau`` (not the equilibrium force of the speed)."""
    course, speed = 0.3, 14 * KNOT
    state = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])  # off course and too fast: inputs far from equilibrium

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    remembered, told = (NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=DT)) for _ in range(2))
    first = remembered.solve(0.0, state, reference_at(0.0))
    told.solve(0.0, state, reference_at(0.0))
    state = rk4_step(state, first.tau, DT, 40, kcs)
    second = remembered.solve(DT, state, reference_at(DT))
    given = told.solve(DT, state, reference_at(DT), previous_tau=first.inputs[0])
    assert second.success and given.success
    np.testing.assert_allclose(second.tau, given.tau, rtol=1e-6)
    remembered.close()
    told.close()


@pytest.mark.parametrize("speed_kn, course, reference_kn, bound", [(24, -1.5, 6, -1.0), (6, 1.5, 24, 1.0)])
def test_applied_inputs_stay_within_the_actuator_limits_exactly(controller, speed_kn, course, reference_kn, bound):
    """The solver meets its bounds to its tolerance (about 1e-8 beyond them); the inputs it
    hands on are clipped to the limits themselves."""
    controller.reset()
    state = np.array([0.0, 0.0, 0.0, speed_kn * KNOT, 0.0, 0.0])  # too fast or slow, the course far to one side
    reference = line_or_turn_reference(DT * np.arange(N + 1), (0.0, 0.0), course, reference_kn * KNOT)
    solution = controller.solve(0.0, state, reference)
    assert solution.success
    assert np.all(np.abs(solution.inputs) <= controller.input_scale)
    assert np.any(solution.inputs == bound * controller.input_scale)  # saturated: the bound itself


def test_the_warm_start_follows_the_measured_heading_across_the_wrap(controller):
    # a ship on 180 deg: the plant reports its heading as +pi - 0.01, then (turned a little to
    # starboard) as -pi + 0.01; the previous plan, on headings near +pi, must be brought onto
    # the measured heading's turn, or the guess begins 2 pi away from its first step
    course, speed = math.pi - 0.01, 18 * KNOT

    def reference_at(t):
        return line_or_turn_reference(t + DT * np.arange(N + 1), (0.0, 0.0), course, speed)

    controller.reset()
    controller.solve(0.0, np.array([0.0, 0.0, course, speed, 0.0, 0.0]), reference_at(0.0), None, et=False)
    state = np.array([-speed * DT, 0.0, -math.pi + 0.01, speed, 0.0, 0.0])
    step = controller._prepare(DT, state, reference_at(DT), None, False, None)
    headings = step.x0[controller.problem.z_index[:, 2]] * controller.state_scale[2]
    assert headings[0] == pytest.approx(-math.pi + 0.01)
    assert np.max(np.abs(np.diff(headings))) < 0.2
