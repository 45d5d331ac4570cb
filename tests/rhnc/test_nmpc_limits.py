"""NMPC limits: wall time (a runaway solve is stopped, the fallback taken), speed bound, offset-free tracking."""

import math
import time

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from rhnc.control.control_participant import ControlParticipant
from rhnc.control.nmpc import NMPCController, NMPCSettings
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import derivatives, load_parameter_set, rk4_step
from rhnc.control.solver_watchdog import WALL_TIME_STATUS, BoundedSolver

from orchestrator.participant import BuildContext
from pathlib import Path

NM = 1852.0
KNOT = NM / 3600.0
N = 15


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def context():
    return BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 2200.0)


class EndlessSolver:
    """Stands in for a solver that never returns (as fatrop on NaN)."""

    def __call__(self, **arguments):
        while True:
            time.sleep(0.01)


class QuickSolver:
    def __call__(self, **arguments):
        return {"x": np.asarray(arguments["x0"]) + 1.0, "g": np.zeros(1), "f": 2.0}

    def stats(self):
        return {"success": True, "iter_count": 3, "return_status": "Solve_Succeeded"}


class SpinningSolver:
    """Never returns and keeps the processor busy (a solver iterating on NaN)."""

    def __call__(self, **arguments):
        x = 0.0
        while True:
            x = math.sin(x + 1.0)


def test_watchdog_stops_a_runaway_by_processor_time_before_the_wall_cap():
    bounded = BoundedSolver({}, {"spinning": SpinningSolver}, wall_time_s=60.0, cpu_time_s=0.3)
    stopped = bounded.solve("spinning", x0=np.zeros(2), lbg=np.zeros(1))
    assert stopped.timed_out and stopped.status == WALL_TIME_STATUS
    assert stopped.stopped_by == "cpu"  # the processor-time limit, not the wall cap
    bounded.close()


def test_watchdog_stops_an_endless_solve_and_recovers():
    bounded = BoundedSolver({"quick": QuickSolver()}, {"endless": EndlessSolver}, wall_time_s=0.5)
    stopped = bounded.solve("endless", x0=np.zeros(3), lbg=np.zeros(1))
    assert stopped.timed_out and not stopped.success and stopped.status == WALL_TIME_STATUS
    assert stopped.stopped_by == "wall"  # sleeping: no processor time, the wall cap stops it
    assert np.all(np.isnan(stopped.x)) and stopped.x.shape == (3,)
    assert bounded.timeouts == 1
    # a fresh worker serves the next call (under a cap a loaded machine's new worker can start within)
    bounded.wall_time_s = 30.0
    quick = bounded.solve("quick", x0=np.zeros(3))
    assert quick.success and quick.iterations == 3 and not quick.timed_out
    np.testing.assert_allclose(quick.x, 1.0)
    bounded.close()


@pytest.mark.parametrize("yaw_rate, status", [(0.35, WALL_TIME_STATUS), (0.5, "prediction_not_finite")])
def test_out_of_range_state_returns_with_the_fallback_flagged(kcs, yaw_rate, status):
    # r0 = 0.35 rad/s: fatrop iterates on NaN without end (iteration limit or not);
    # r0 = 0.5 rad/s: the model's prediction overflows in the first interval
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=60.0, cpu_time_limit_s=1.0))
    state = np.array([0.0, 0.0, math.radians(45.0), 18 * KNOT, 0.0, yaw_rate])
    reference = line_or_turn_reference(60.0 * np.arange(N + 1), (0.0, 0.0), math.radians(45.0), 18 * KNOT)
    solution = controller.solve(0.0, state, reference, previous_tau=np.array([7e5, 0.0]))
    assert solution.fallback and not solution.success
    assert solution.status == status
    assert solution.timed_out == (status == WALL_TIME_STATUS)
    np.testing.assert_allclose(solution.tau, [7e5, 0.0])  # no previous plan: hold the surge force
    assert controller.timeout_count == int(status == WALL_TIME_STATUS)
    # and the controller goes on: an ordinary state solves again
    calm = controller.solve(60.0, np.array([0.0, 0.0, math.radians(45.0), 18 * KNOT, 0.0, 0.0]), reference)
    assert calm.success and not calm.fallback
    controller.close()


def speed_run(kcs, max_speed_mps, steps=40, dt=20.0):
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt,
                                                  max_speed_mps=max_speed_mps))
    state = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])
    speeds = []
    for k in range(steps):
        t = k * dt
        reference = line_or_turn_reference(t + dt * np.arange(N + 1), (0.0, 0.0), 0.0, 28 * KNOT)  # too fast
        solution = controller.solve(t, state, reference)
        assert solution.success
        assert solution.states[1:, 3].max() <= max_speed_mps + 1e-3
        state = rk4_step(state, solution.tau, dt, 40, kcs)
        speeds.append(state[3])
    controller.close()
    return np.array(speeds)


@pytest.mark.slow
def test_speed_is_bounded_by_the_scenario_maximum(kcs):
    bounded = speed_run(kcs, 24 * KNOT)
    assert bounded.max() <= 24 * KNOT * 1.002
    assert bounded[-1] > 23.5 * KNOT  # it does sail at the bound
    assert speed_run(kcs, 30 * KNOT).max() > 25 * KNOT  # the bound, not the reference, held it


def disturbed_step(state, tau, dt, kcs, disturbance):
    """Plant: the model plus a current (north, east) and body-frame loads, RK4 in 0.5 s steps."""
    current_n, current_e, w_u, w_v, w_r = disturbance

    def f(x):
        extra = np.array([current_n, current_e, 0.0, w_u / kcs.m11, w_v / kcs.m22, w_r / kcs.m33])
        return derivatives(x, tau, kcs) + extra

    h = 0.5
    for _ in range(int(round(dt / h))):
        k1 = f(state)
        k2 = f(state + 0.5 * h * k1)
        k3 = f(state + 0.5 * h * k2)
        k4 = f(state + h * k3)
        state = state + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return state


def steady_offsets(kcs, observer, steps=60, dt=20.0):
    """Cross-track error and along-track lag behind the timed reference [m], averaged over the last 10 min."""
    course = math.radians(45.0)
    speed = 18 * KNOT
    # 0.5 m/s current setting 135 deg (across the track), wind and waves on the starboard bow
    disturbance = (0.5 * math.cos(math.radians(135.0)), 0.5 * math.sin(math.radians(135.0)), -2.0e5, -4.0e5, -2.0e7)
    controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt,
                                                  disturbance_observer=observer))
    state = np.array([0.0, 0.0, course, speed, 0.0, 0.0])
    cross, along_error = [], []
    for k in range(steps):
        t = k * dt
        reference = line_or_turn_reference(t + dt * np.arange(N + 1), (0.0, 0.0), course, speed)
        solution = controller.solve(t, state, reference)
        assert solution.success
        state = disturbed_step(state, solution.tau, dt, kcs, disturbance)
        t_next = t + dt
        cross.append(-math.sin(course) * state[0] + math.cos(course) * state[1])
        along_error.append(math.cos(course) * state[0] + math.sin(course) * state[1] - speed * t_next)
    controller.close()
    last = slice(-int(600 / dt), None)
    return float(np.mean(np.abs(cross[last]))), float(np.mean(along_error[last])), controller.observer


@pytest.mark.slow
def test_disturbance_observer_removes_the_steady_offsets(kcs):
    cross_off, lag_off, _ = steady_offsets(kcs, observer=False)
    cross_on, lag_on, observer = steady_offsets(kcs, observer=True)
    # without the estimate the current sets the ship ~45 m off its track and the loads ~45 m
    # behind its timed reference; with it both shrink to a few metres
    assert cross_off > 30.0 and lag_off < -30.0
    assert cross_on < 5.0 and abs(lag_on) < 5.0
    # the estimate found the current that was acting
    np.testing.assert_allclose(observer.estimate[:2], [0.5 * math.cos(math.radians(135.0)),
                                                       0.5 * math.sin(math.radians(135.0))], atol=0.05)


def test_participant_rejects_bad_new_options():
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'colregs' must be true or false"):
        ControlParticipant.from_options("ctrl", {"colregs": "yes"}, context())
    with pytest.raises(ScenarioError, match=r"participants.ctrl: max_speed_mps must be > 0"):
        ControlParticipant.from_options("ctrl", {"max_speed_kn": -3.0}, context())
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'wall_time_limit_s' must be a finite number"):
        ControlParticipant.from_options("ctrl", {"wall_time_limit_s": "1s"}, context())
    with pytest.raises(ScenarioError, match=r"participants.ctrl: observer_gain must be in \(0, 1\]"):
        ControlParticipant.from_options("ctrl", {"observer_gain": 2.0}, context())
    with pytest.raises(ScenarioError, match=r"participants.ctrl: apparent_alteration_deg must be >= 0"):
        ControlParticipant.from_options("ctrl", {"apparent_alteration_deg": -5.0}, context())
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'give_way_action_tcpa_s' must be a finite"):
        ControlParticipant.from_options("ctrl", {"give_way_action_tcpa_s": "soon"}, context())
    ctrl = ControlParticipant.from_options("ctrl", {"colregs": True, "apparent_alteration_deg": 40.0,
                                                    "give_way_action_tcpa_s": 600.0}, context())
    assert ctrl.controller.domains.settings.alteration_deg == 40.0
    assert ctrl.controller.domains.settings.give_way_action_tcpa_s == 600.0


def test_participant_reports_classes_domains_and_estimate(kcs):
    from rhnc.encounters.colregs import ENCOUNTER_CLASSES

    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10, "colregs": True, "max_obstacles": 3,
                                                    "disturbance_observer": True, "et_default": 1.0}, context())
    first = ctrl.setup(0.0, {})
    assert first["encounter_class"].shape == (3,) and first["disturbance"].shape == (5,)
    times = np.arange(0.0, 600.0, 20.0)
    reference = np.column_stack([times, line_or_turn_reference(times, (0, 0), 0.0, 18 * KNOT)])
    head_on = np.array([[2.5 * NM, 0.1 * NM, -12 * KNOT, 0.0, NM]])  # within reach of the 200 s horizon
    state = {"x": 0.0, "y": 0.0, "psi": 0.0, "u": 18 * KNOT, "v": 0.0, "r": 0.0}
    out = ctrl.step(0.0, 20.0, {**state, "reference": reference, "obstacles": head_on})
    np.testing.assert_array_equal(out["encounter_class"], [ENCOUNTER_CLASSES.index("head_on"), -1, -1])
    np.testing.assert_array_equal(out["domain_active"], [1.0, 0.0, 0.0])
    assert out["timed_out"] == 0.0 and out["solve_cpu_time_s"] > 0.0
    summary = ctrl.summary()
    assert summary["timeout_count"] == 0 and summary["max_speed_kn"] == pytest.approx(18.0)
    ctrl.terminate()


def test_the_dual_warm_start_can_be_turned_off_by_option():
    built = ControlParticipant.from_options("ctrl", {"warm_start_duals": False}, context())
    assert built.controller.settings.warm_start_duals is False
    assert ControlParticipant.from_options("ctrl", {}, context()).controller.settings.warm_start_duals is True
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'warm_start_duals' must be true or false"):
        ControlParticipant.from_options("ctrl", {"warm_start_duals": 0}, context())


def test_a_failed_first_solve_holds_the_surge_force_of_the_measured_speed(kcs):
    # no input has been applied before the first solve: its fallback holds the force that
    # keeps the measured speed (not the zero outputs of set-up, which stop the propeller)
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10, "max_iterations": 1}, context())
    ctrl.setup(0.0, {})
    times = np.arange(0.0, 600.0, 20.0)
    reference = np.column_stack([times, line_or_turn_reference(times, (0, 0), 0.0, 18 * KNOT)])
    state = {"x": 0.0, "y": 0.0, "psi": 0.0, "u": 18 * KNOT, "v": 0.0, "r": 0.0}
    out = ctrl.step(0.0, 20.0, {**state, "reference": reference})
    assert out["fallback"] == 1.0
    assert out["tau_u"] == pytest.approx(ctrl.controller.params.equilibrium_tau(18 * KNOT)[0])
    assert out["tau_u"] > 0.0 and out["tau_r"] == 0.0
    ctrl.terminate()


def test_the_planned_tau_changes_no_faster_than_the_actuators_can(kcs):
    """A hard turn asked of a ship whose steering gear gives 2 MN m/s: the applied moment moves
    at most one interval's worth from the last one, the k-th planned one k intervals' worth."""
    dt = 20.0
    rate = (2.0e4, 2.0e6)
    reference = line_or_turn_reference(np.arange(N + 1) * dt, (0.0, 0.0), 0.0, 18 * KNOT, turn_radius_m=1500.0)
    state = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])
    previous = kcs.equilibrium_tau(18 * KNOT)
    free = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt, codegen=False))
    bounded = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt, codegen=False,
                                               tau_rate_max=rate))
    unbounded = free.solve(0.0, state, reference, previous_tau=previous)
    limited = bounded.solve(0.0, state, reference, previous_tau=previous)
    assert abs(unbounded.tau[1] - previous[1]) > 3 * rate[1] * dt     # the turn wants a fast change
    assert abs(limited.tau[1] - previous[1]) <= rate[1] * dt * 1.001
    assert abs(limited.tau[0] - previous[0]) <= rate[0] * dt * 1.001
    change = np.abs(np.asarray(limited.inputs) - previous)
    assert np.all(change <= np.arange(1, N + 1)[:, None] * dt * np.array(rate) * 1.001)


def test_the_ships_actuator_rates_reach_the_nmpc():
    from rhnc.control.allocation import coefficients_from_ship, tau_rate_limits
    from rhnc.control.control_options import controller_from_options

    _, settings, _, _ = controller_from_options({"actuators_ship": "KCS"}, context())
    expected = tau_rate_limits(coefficients_from_ship("KCS", "x"), settings.max_speed_mps)
    assert settings.tau_rate_max == pytest.approx(expected)
    # the steering gear: dtau_r/ddelta at midships times 2.32 deg/s; the shaft: 0.05 1/s^2 at full revolutions
    assert 5e7 < expected[1] < 1.2e8 and 1e5 < expected[0] < 1.8e6
    with pytest.raises(ScenarioError, match=r"option 'actuators_ship' must be a ship name or a ship file path"):
        controller_from_options({"actuators_ship": 3}, context())


def test_a_propeller_turning_ahead_only_gets_no_astern_thrust_in_the_plan(kcs):
    """Asked to slow from 18 to 8 kn, the NMPC plans full astern force; with the ship's actuators
    declared (the allocation turns the propeller ahead only) it plans no force below zero."""
    from rhnc.control.control_options import controller_from_options

    _, settings, _, _ = controller_from_options({"actuators_ship": "KVLCC2"}, context())
    assert settings.tau_u_min_N == 0.0
    assert controller_from_options({}, context())[1].tau_u_min_N is None
    dt = 20.0
    reference = line_or_turn_reference(np.arange(N + 1) * dt, (0.0, 0.0), 0.0, 8 * KNOT)
    state = np.array([0.0, 0.0, 0.0, 18 * KNOT, 0.0, 0.0])
    plans = {}
    for floor in (None, 0.0):
        controller = NMPCController(kcs, NMPCSettings(horizon_steps=N, control_interval_s=dt, codegen=False,
                                                      tau_u_min_N=floor))
        plans[floor] = np.asarray(controller.solve(0.0, state, reference, previous_tau=kcs.equilibrium_tau(18 * KNOT))
                                  .inputs)
        controller.close()
    assert plans[None][:, 0].min() < -0.5 * kcs.tau_u_max          # astern force to slow down
    assert plans[0.0][:, 0].min() >= -1e-6 * kcs.tau_u_max          # the hull's drag alone
