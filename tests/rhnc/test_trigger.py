"""Event trigger (Eq. 7) on scripted encounters: transitions at the right ranges."""

import numpy as np
import pytest

from rhnc.metocean import NM
from rhnc.trigger import EventTrigger


def test_static_obstacle_triggers_at_eps2_and_releases_when_passed():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (40 * NM, 0.0)
    obstacle = np.array([[20 * NM, 1 * NM, 0.0, 0.0, 3 * NM]])
    speed = 0.1 * NM  # per step of 1 s, for easy ranges
    history = []
    for k in range(400):
        x = k * speed
        et = trigger.update(float(k), (x, 0.0), (speed, 0.0), goal, obstacle)
        history.append(et)
    on, off, clear = trigger.transitions
    assert on.state == "triggered" and on.et == 1.0 and on.kind == "static"
    # first sample within 6 nm: x = 14.1 nm (range 5.99 nm)
    assert on.time == 141 and on.range_m == pytest.approx(np.hypot(5.9, 1) * NM)
    assert on.range_m <= 6 * NM < np.hypot(6.0, 1) * NM
    # released as soon as the obstacle is behind (x > 20 nm) with the range opening
    assert off.state == "passed" and off.et == 0.0 and off.cause.startswith("passed")
    assert off.time == 201
    assert sum(history) == 201 - 141
    # and the obstacle is clear once beyond 6 nm again (x = 26.0 nm: range 6.08 nm)
    assert clear.state == "clear" and clear.cause == "beyond warning range" and clear.time == 260


def test_ship_uses_eps1_and_releases_beyond_range_if_never_behind():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (100 * NM, 0.0)
    # own ship at rest-ish heading north; a target crosses ahead from west to east, 3 nm ahead
    for k in range(0, 161):
        target_y = (-8 + 0.1 * k) * NM
        obstacle = np.array([[3 * NM, target_y, 0.0, 0.1 * NM, 500.0]])
        trigger.update(float(k), (0.0, 0.0), (0.01, 0.0), goal, obstacle)
    on, off = trigger.transitions
    assert on.kind == "ship" and on.state == "triggered"
    assert on.range_m <= 4.5 * NM
    assert np.hypot(3, -8 + 0.1 * (on.time - 1)) > 4.5  # previous sample was outside eps1
    assert off.state == "clear" and off.cause == "beyond warning range" and off.range_m > 4.5 * NM
    assert trigger.et == 0.0


def test_no_obstacles_means_normal_state():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    assert trigger.update(0.0, (0, 0), (1, 0), (10, 10), None) == 0.0
    assert trigger.update(1.0, (0, 0), (1, 0), (10, 10), np.zeros((0, 5))) == 0.0
    assert trigger.transitions == []


@pytest.mark.parametrize("ship_m, static_m", [(0.0, 1.0), (1.0, 0.0), (-1.0, 1.0), (1.0, -1.0)])
def test_warning_ranges_must_be_positive(ship_m, static_m):
    with pytest.raises(ValueError, match="^warning ranges must be positive$"):
        EventTrigger(ship_m, static_m)


def test_small_positive_ranges_are_accepted_and_kept_apart():
    trigger = EventTrigger(0.5, 0.25, moving_speed=2.0)
    assert (trigger.ship_range_m, trigger.static_range_m, trigger.moving_speed) == (0.5, 0.25, 2.0)
    assert trigger.states == [] and trigger.transitions == [] and trigger.et == 0.0


def test_moving_speed_decides_which_range_applies():
    """At 5 nm, between eps1 = 4.5 nm and eps2 = 6 nm: only an obstacle counted static triggers
    (default threshold 0.1 m/s)."""
    at_5nm = lambda speed: np.array([[5 * NM, 0.0, 0.0, speed, 100.0]])  # noqa: E731
    for speed, moving_speed, expected in ((0.05, None, 1.0), (0.5, None, 0.0), (0.5, 1.0, 1.0), (0.15, 0.2, 1.0)):
        trigger = EventTrigger(4.5 * NM, 6.0 * NM, **({} if moving_speed is None else {"moving_speed": moving_speed}))
        assert trigger.update(0.0, (0.0, 0.0), (1.0, 0.0), (20 * NM, 0.0), at_5nm(speed)) == expected
        if expected:
            assert trigger.transitions[0].kind == "static"
            assert trigger.transitions[0].cause == "within warning range"


def test_states_follow_the_number_of_obstacles():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    far = [50 * NM, 50 * NM, 0.0, 0.0, 100.0]
    near = [1 * NM, 0.0, 0.0, 0.0, 100.0]
    trigger.update(0.0, (0, 0), (1, 0), (20 * NM, 0), np.array([far, near]))
    assert trigger.states == ["clear", "triggered"]
    trigger.update(1.0, (0, 0), (1, 0), (20 * NM, 0), np.array([far, near, far]))
    assert trigger.states == ["clear", "triggered", "clear"]
    trigger.update(2.0, (0, 0), (1, 0), (20 * NM, 0), np.array([near]))
    assert trigger.states == ["triggered"]
    assert trigger.update(3.0, (0, 0), (1, 0), (20 * NM, 0), np.array([far])) == 0.0
    assert trigger.states == ["clear"]


def test_a_passed_obstacle_at_a_constant_range_stays_passed():
    """Re-triggering needs the range to close (rate < 0), not merely to stop opening."""
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (20 * NM, 0.0)
    obstacle = np.array([[0.0, 0.0, 0.0, 0.0, 100.0]])  # static, at the origin
    trigger.update(0.0, (-1 * NM, 0.0), (5.0, 0.0), goal, obstacle)  # ahead, closing: triggered
    trigger.update(1.0, (1 * NM, 0.0), (5.0, 0.0), goal, obstacle)  # behind, opening: passed
    assert trigger.states == ["passed"]
    # the ship now sails across the line of sight: range rate exactly zero, obstacle not behind
    state = trigger.update(2.0, (0.0, 1 * NM), (5.0, 0.0), (0.0, -2 * NM), obstacle)
    assert state == 0.0 and trigger.states == ["passed"]
    # closing again while ahead: triggered again with that cause
    assert trigger.update(3.0, (0.0, 1 * NM), (0.0, -5.0), (0.0, -2 * NM), obstacle) == 1.0
    last = trigger.transitions[-1]
    assert (last.time, last.obstacle, last.kind, last.cause, last.state, last.et) == (
        3.0, 0, "static", "ahead and closing again", "triggered", 1.0)
    assert last.range_m == pytest.approx(1 * NM)
    assert last.as_dict() == {"time": 3.0, "obstacle": 0, "kind": "static", "range_m": last.range_m,
                              "cause": "ahead and closing again", "state": "triggered", "et": 1.0}


def states_after(updates, ranges=(4.5 * NM, 6.0 * NM)):
    """Run ``updates`` = [(position, velocity, goal, obstacle row)] from t = 0; the states after each."""
    trigger = EventTrigger(*ranges)
    seen = []
    for k, (position, velocity, goal, row) in enumerate(updates):
        trigger.update(float(k), position, velocity, goal, np.array([row]))
        seen.append(trigger.states[0])
    return seen


STATIC_AT_ORIGIN = [0.0, 0.0, 0.0, 0.0, 100.0]


def test_release_and_retrigger_at_their_boundaries():
    east, goal = (5.0, 0.0), (20 * NM, 0.0)
    approach = ((-1 * NM, 0.0), east, goal, STATIC_AT_ORIGIN)  # ahead, closing: triggered
    # behind but the range neither opens nor closes: stays triggered
    assert states_after([approach, ((1 * NM, 0.0), (0.0, 5.0), goal, STATIC_AT_ORIGIN)]) == ["triggered"] * 2
    # behind and opening slowly (0.5 m/s): released
    assert states_after([approach, ((1 * NM, 0.0), (0.5, 0.0), goal, STATIC_AT_ORIGIN)]) == ["triggered", "passed"]
    # exactly abeam (neither ahead nor behind) with the range opening: not yet passed
    abeam = ((0.0, -1 * NM), (5.0, -1.0), (20 * NM, -1 * NM), STATIC_AT_ORIGIN)
    assert states_after([approach, abeam]) == ["triggered", "triggered"]
    # passed, then still behind but closing (sailing back towards it): stays passed
    back = ((1 * NM, 0.0), (-5.0, 0.0), goal, STATIC_AT_ORIGIN)
    assert states_after([approach, ((1 * NM, 0.0), east, goal, STATIC_AT_ORIGIN), back]) == [
        "triggered", "passed", "passed"]


def test_behind_is_measured_from_the_ship_towards_the_goal():
    """With the ship west of a goal at the origin, an obstacle further west is behind it."""
    goal, east = (0.0, 0.0), (5.0, 0.0)
    row = [-11 * NM, 0.5 * NM, 0.0, 0.0, 100.0]
    assert states_after([((-10 * NM, 0.0), east, goal, row)] * 2) == ["triggered", "passed"]


def test_an_obstacle_exactly_at_the_warning_range_triggers():
    assert states_after([((0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), [6 * NM, 0.0, 0.0, 0.0, 100.0])]) == ["triggered"]
    assert states_after([((0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), [6.01 * NM, 0.0, 0.0, 0.0, 100.0])]) == ["clear"]


def test_an_obstacle_moving_exactly_at_the_threshold_counts_static():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM, moving_speed=0.5)
    assert trigger.update(0.0, (0, 0), (1, 0), (20 * NM, 0), np.array([[5 * NM, 0.0, 0.5, 0.0, 1.0]])) == 1.0
    assert trigger.transitions[0].kind == "static"


def test_a_target_moving_along_x_is_a_ship_and_its_range_rate_uses_both_components():
    # target on the x axis moving along x only: eps1 applies (a ship) and it triggers; behind
    # the ship but overtaking it (closing at 1 m/s) it stays triggered; moving away, released
    goal = (20 * NM, 0.0)
    updates = [((0.0, 0.0), (5.0, 0.0), goal, [4 * NM, 0.0, 6.0, 0.0, 100.0]),
               ((5 * NM, 0.0), (5.0, 0.0), goal, [4 * NM, 0.0, 6.0, 0.0, 100.0]),
               ((5 * NM, 0.0), (5.0, 0.0), goal, [4 * NM, 0.0, -2.0, 0.0, 100.0])]
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    for k, (position, velocity, goal_, row) in enumerate(updates):
        trigger.update(float(k), position, velocity, goal_, np.array([row]))
    assert [t.kind for t in trigger.transitions] == ["ship", "ship"]
    assert [(t.time, t.state) for t in trigger.transitions] == [(0.0, "triggered"), (2.0, "passed")]
