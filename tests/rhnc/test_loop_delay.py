"""The controller's loop delay: the measured state carried over it with the inputs already sent.

In Jacobi order (OSP's libcosim and most FMI masters) a decision made at t reaches the ship
at t + one controller step; the controller plans from the state its input will meet.
"""

from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.participant import BuildContext
from rhnc.control.control_participant import ControlParticipant, check_reference
from rhnc.control.loop_delay import LoopDelay
from rhnc.navigation.reference_participant import line_or_turn_reference
from rhnc.ship.ship_model import load_parameter_set, rk4_step

REPO = Path(__file__).resolve().parents[2]
NM = 1852.0
KNOT = NM / 3600.0
STATE = np.array([0.0, 0.0, 0.3, 9.0, 0.1, 0.002])


@pytest.fixture(scope="module")
def kcs():
    return load_parameter_set("default")


def test_no_delay_returns_the_measured_state(kcs):
    delay = LoopDelay(0.0, kcs)
    delay.hold(0.0, np.zeros(2))
    time, state = delay.predict(40.0, STATE)
    assert time == 40.0
    np.testing.assert_array_equal(state, STATE)


def test_the_state_is_carried_over_the_delay_with_the_input_sent_a_step_earlier(kcs):
    delay = LoopDelay(20.0, kcs)
    delay.hold(0.0, np.zeros(2))           # set-up: zero forces act at once
    first = np.array([7e5, 8e7])
    second = np.array([6e5, -5e7])
    # at t = 0 only the set-up's zero forces act over [0, 20)
    time, state = delay.predict(0.0, STATE)
    assert time == 20.0
    np.testing.assert_allclose(state, rk4_step(STATE, np.zeros(2), 20.0, 4, kcs), rtol=1e-9)
    delay.sent(0.0, first)                 # acts over [20, 40)
    measured = rk4_step(STATE, np.zeros(2), 20.0, 4, kcs)  # the ship did what the model said: no model error
    time, state = delay.predict(20.0, measured)
    np.testing.assert_allclose(delay.model_error, 0.0, atol=1e-9)
    np.testing.assert_allclose(state, rk4_step(measured, first, 20.0, 4, kcs), rtol=1e-9)
    delay.sent(20.0, second)               # acts over [40, 60)
    # a delay of 1.5 steps: [40, 50) under `first`, [50, 60) under `second`
    longer = LoopDelay(30.0, kcs)
    longer.hold(0.0, np.zeros(2))
    longer.sent(0.0, first)
    longer.sent(20.0, second)
    _, state = longer.predict(40.0, STATE)
    expected = rk4_step(rk4_step(STATE, first, 10.0, 2, kcs), second, 20.0, 4, kcs)
    np.testing.assert_allclose(state, expected, rtol=1e-9)
    assert abs(state[5] - rk4_step(STATE, second, 30.0, 6, kcs)[5]) > 1e-4  # the switch matters


def test_the_prediction_is_corrected_by_the_models_error_over_the_last_delay(kcs):
    """A ship slower and set aside (wind, waves, current the model does not know): the error the
    model made over the last delay is added to the next prediction, heading wrapped."""
    delay = LoopDelay(60.0, kcs)
    delay.hold(0.0, np.zeros(2))
    tau = np.array([1.0e6, 0.0])
    delay.sent(0.0, tau)
    state = np.array([0.0, 0.0, np.pi - 0.01, 9.0, 0.0, 0.0])
    _, first = delay.predict(0.0, state)
    np.testing.assert_array_equal(delay.model_error, 0.0)  # nothing predicted for t = 0
    offset = np.array([-20.0, 15.0, 0.03, -0.3, 0.02, 0.0])  # behind, set to starboard, turned past +-pi
    measured = first + offset
    measured[2] -= 2.0 * np.pi  # the plant reports the heading wrapped
    delay.sent(60.0, tau)
    time, second = delay.predict(60.0, measured)
    assert time == 120.0
    np.testing.assert_allclose(delay.model_error, offset, atol=1e-9)
    np.testing.assert_allclose(second, rk4_step(measured, tau, 60.0, 12, kcs) + offset, rtol=1e-9, atol=1e-9)
    delay.reset()
    delay.hold(0.0, np.zeros(2))
    _, again = delay.predict(60.0, measured)  # after a reset nothing was predicted for now
    np.testing.assert_allclose(again, rk4_step(measured, np.zeros(2), 60.0, 12, kcs), rtol=1e-9)


def test_a_negative_or_non_finite_delay_is_refused(kcs):
    with pytest.raises(ValueError, match="loop delay must be a finite number of seconds >= 0"):
        LoopDelay(float("nan"), kcs)
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 600.0)
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'loop_delay_s' must be a number of "
                                            r"seconds >= 0, got -20.0"):
        ControlParticipant.from_options("ctrl", {"loop_delay_s": -20.0}, context)
    with pytest.raises(ScenarioError, match=r"participants.ctrl: option 'obstacle_age_s' must be a finite number"):
        ControlParticipant.from_options("ctrl", {"obstacle_age_s": "5 s"}, context)


def test_the_delay_follows_the_masters_exchange_order():
    from orchestrator.master import CoSimulation
    from orchestrator.scenario import load_scenario

    path = REPO / "scenarios" / "osp" / "exp3b_head_on.toml"
    for order, delay, age in (("jacobi", 20.0, 5.0), ("gauss-seidel", 0.0, 0.0)):
        cosim = CoSimulation(load_scenario(path, {"simulation.exchange": order}))
        try:
            ctrl = cosim.participant("ctrl")
            assert (ctrl.delay.delay_s, ctrl.obstacle_age_s) == (delay, age), order
        finally:
            cosim._terminate_all()
            cosim.close()


def _straight_reference(t0=0.0):
    times = np.arange(t0, t0 + 600.0, 20.0)
    return np.column_stack([times, line_or_turn_reference(times, (0, 0), 0.0, 18 * KNOT)])


def test_the_controller_plans_from_the_state_its_input_will_meet(kcs):
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 600.0, output_delay_s=20.0)
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10}, context)
    try:
        assert ctrl.delay.delay_s == 20.0
        ctrl.setup(0.0, {})
        measured = {"x": 0.0, "y": 0.0, "psi": 0.05, "u": 18 * KNOT, "v": 0.0, "r": 0.001}
        out = ctrl.step(0.0, 20.0, {**measured, "reference": _straight_reference()})
        prediction = out["prediction"]
        assert prediction[0, 0] == 20.0 and prediction[-1, 0] == 220.0
        state = np.array([measured[n] for n in ("x", "y", "psi", "u", "v", "r")])
        expected = rk4_step(state, np.zeros(2), 20.0, 4, kcs)  # the set-up's zero forces over [0, 20)
        np.testing.assert_allclose(prediction[0, 1:], expected, rtol=1e-9, atol=1e-9)
        assert prediction[0, 1] > 150.0  # it sailed on over the delay
        assert ctrl.summary()["loop_delay_s"] == 20.0
    finally:
        ctrl.terminate()


def test_a_reference_of_another_layout_is_refused_naming_the_layout(kcs):
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 600.0)
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10}, context)
    try:
        ctrl.setup(0.0, {})
        measured = {"x": 0.0, "y": 0.0, "psi": 0.0, "u": 18 * KNOT, "v": 0.0, "r": 0.0}
        good = _straight_reference()
        swapped = good[:, [1, 2, 3, 4, 5, 6, 0]]  # (x, y, psi, u, v, r, t): time last
        swapped[:, 0] += np.arange(len(good))     # positions that increase as times do
        with pytest.raises(ModelError, match=r"ctrl: input 'reference' at t = 0.0 s: rows must be \(t \[s\], x \[m\], "
                                             r"y \[m\], psi \[rad\], u \[m/s\], v \[m/s\], r \[rad/s\]\); row \d+ has "
                                             r"r = \d+ rad/s"):
            ctrl.step(0.0, 20.0, {**measured, "reference": swapped})
        stale = _straight_reference(t0=-5000.0)
        with pytest.raises(ModelError, match=r"its times -5000 .. -4420 s do not reach within 200 s of now"):
            ctrl.step(0.0, 20.0, {**measured, "reference": stale})
        out = ctrl.step(0.0, 20.0, {**measured, "reference": good})
        assert abs(out["tau_r"]) < 0.5 * kcs.tau_r_max
    finally:
        ctrl.terminate()


def test_check_reference_accepts_a_ships_reference():
    check_reference(_straight_reference(), 100.0, 300.0)


def test_sign_changes_of_the_yaw_moment_from_its_recorded_samples(kcs):
    context = BuildContext("exp.toml: participants.ctrl", Path("."), 20.0, 0.0, 600.0)
    ctrl = ControlParticipant.from_options("ctrl", {"horizon_steps": 10}, context)
    try:
        bound = kcs.tau_r_max
        figures = ctrl.summary_from_outputs({"tau_r": np.array([0.5, -0.5, 0.001, -0.4, 0.3]) * bound})
        assert figures == {"solves": 5, "tau_r_sign_changes_per_100_solves": 40.0}  # -0.5 -> (0.001 unsigned) -0.4 is no change
        assert ctrl.summary_from_outputs({}) == {}
    finally:
        ctrl.terminate()
