"""Event trigger (Eq. 7) on scripted encounters: transitions at the right ranges."""

import numpy as np
import pytest

from orchestrator.geometry import NM
from rhnc.navigation.trigger import EventTrigger


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
    # released once the range opens (x > 20 nm) *and* exceeds the 3 nm domain:
    # x = 22.9 nm, range hypot(2.9, 1) = 3.07 nm (x = 22.8 nm: 2.97 nm, still inside)
    assert off.state == "passed" and off.et == 0.0 and off.cause.startswith("passed")
    assert off.time == 229 and off.range_m > 3 * NM
    assert sum(history) == 229 - 141
    # and the obstacle is clear once beyond 6 nm again (x = 26.0 nm: range 6.08 nm)
    assert clear.state == "clear" and clear.cause == "beyond warning range" and clear.time == 260


def test_ship_uses_eps1_and_is_released_after_its_cpa():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (100 * NM, 0.0)
    # own ship at rest-ish heading north; a target crosses ahead from west to east, 3 nm ahead
    for k in range(0, 161):
        target_y = (-8 + 0.1 * k) * NM
        obstacle = np.array([[3 * NM, target_y, 0.0, 0.1 * NM, 500.0]])
        trigger.update(float(k), (0.0, 0.0), (0.01, 0.0), goal, obstacle)
    on, off, clear = trigger.transitions
    assert on.kind == "ship" and on.state == "triggered"
    assert on.range_m <= 4.5 * NM
    assert np.hypot(3, -8 + 0.1 * (on.time - 1)) > 4.5  # previous sample was outside eps1
    # released right after its CPA (target abeam to port of the goal line at k = 80)
    assert off.state == "passed" and 80 < off.time <= 82
    assert clear.state == "clear" and clear.cause == "beyond warning range" and clear.range_m > 4.5 * NM
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


def states_after(updates, ranges=(4.5 * NM, 6.0 * NM)):
    """Run ``updates`` = [(position, velocity, goal, obstacle row)] from t = 0; the states after each."""
    trigger = EventTrigger(*ranges)
    seen = []
    for k, (position, velocity, goal, row) in enumerate(updates):
        trigger.update(float(k), position, velocity, goal, np.array([row]))
        seen.append(trigger.states[0])
    return seen


STATIC_AT_ORIGIN = [0.0, 0.0, 0.0, 0.0, 100.0]


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


KNOT = NM / 3600.0
CHECK_S = 240.0  # the navigation's 4 min interval


def _velocity(course_deg, speed_kn):
    course = np.radians(course_deg)
    return np.array([np.cos(course), np.sin(course)]) * speed_kn * KNOT


def _converging_run(own_courses_deg, target_course_deg=347.5, bearing_deg=100.0):
    """Own ship 18 kn from (0, 0) towards a goal 30 nm north, following a course per check;
    a same-speed target starting 3 nm away, 10 deg abaft the starboard beam, converging
    12.5 deg (its CPA 0.84 nm, 44 min ahead, if both held course)."""
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = np.array([30 * NM, 0.0])
    own = np.zeros(2)
    target = 3 * NM * np.array([np.cos(np.radians(bearing_deg)), np.sin(np.radians(bearing_deg))])
    target_velocity = _velocity(target_course_deg, 18.0)
    ets, ranges = [], []
    for k, course in enumerate(own_courses_deg):
        own_velocity = _velocity(course, 18.0)
        obstacle = np.array([[*target, *target_velocity, 1.0 * NM]])
        ets.append(trigger.update(k * CHECK_S, own, own_velocity, goal, obstacle))
        ranges.append(float(np.hypot(*(target - own))) / NM)
        own = own + own_velocity * CHECK_S
        target = target + target_velocity * CHECK_S
    return trigger, ets, ranges


def test_converging_same_speed_ship_is_not_released_while_the_own_ship_turns_away():
    # the own ship swings 30 deg to port for one check: the range opens at that check and the
    # target is behind relative to the goal, but on the way back to the route it closes again
    courses = [0.0, 330.0, 330.0] + [0.0] * 12
    trigger, ets, ranges = _converging_run(courses)
    assert trigger.transitions[0].state == "triggered"
    first_passed = next((t for t in trigger.transitions if t.state == "passed"), None)
    # never released while the target can still close (its range keeps falling afterwards)
    closest = int(np.argmin(ranges))
    assert closest > 3 and ranges[closest] < 2.0
    assert all(et == 1.0 for et in ets[: closest + 1])
    assert first_passed is None or first_passed.time > closest * CHECK_S


def test_passed_target_that_closes_again_is_rearmed():
    # a target crossing ahead from port passes and opens; then it turns back towards our track
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (60 * NM, 0.0)
    own_velocity = _velocity(0.0, 18.0)
    own = np.zeros(2)
    target = np.array([3.0 * NM, -1.5 * NM])
    target_velocity = _velocity(90.0, 18.0)
    states = []
    for k in range(12):
        if k == 3:  # the target alters towards the own ship's track ahead
            target_velocity = _velocity(225.0, 18.0)
        obstacle = np.array([[*target, *target_velocity, 0.5 * NM]])
        trigger.update(k * CHECK_S, own, own_velocity, goal, obstacle)
        states.append(trigger.states[0])
        own = own + own_velocity * CHECK_S
        target = target + target_velocity * CHECK_S
    causes = [t.cause for t in trigger.transitions]
    assert states[0] == "triggered"
    assert states[2] == "passed"                       # released after its CPA ...
    assert "closing again" in causes                   # ... and re-armed when it turns back
    rearmed = next(t for t in trigger.transitions if t.cause == "closing again")
    assert rearmed.time == 3 * CHECK_S and rearmed.et == 1.0


def test_target_opening_inside_its_domain_is_not_released():
    # a static obstacle whose 3 nm domain the ship is inside: opening, but not beyond the domain
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    obstacle = np.array([[0.0, 1.0 * NM, 0.0, 0.0, 3.0 * NM]])
    for k in range(4):
        trigger.update(float(k), (k * 0.5 * NM, 0.0), (0.5 * NM, 0.0), (50 * NM, 0.0), obstacle)
    assert trigger.states == ["triggered"] and trigger.et == 1.0


def test_own_hazard_radius_must_not_be_negative():
    for radius in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="^the own hazard radius must not be negative$"):
            EventTrigger(4.5 * NM, 6.0 * NM, own_radius_m=radius)


def _opening_from(distance_m, radius_m, **trigger_options):
    """States of a static obstacle straight astern at ``distance_m``, the ship heading away
    towards its goal: triggered at once (within eps2), then the same geometry again."""
    trigger = EventTrigger(4.5 * NM, 6.0 * NM, **trigger_options)
    row = np.array([[-distance_m, 0.0, 0.0, 0.0, radius_m]])
    for k in range(2):
        trigger.update(float(k), (0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), row)
    return trigger.states[0]


def test_domain_is_the_obstacle_radius_plus_the_own_radius():
    # the own radius defaults to 0: the domain is the obstacle's radius alone
    assert _opening_from(1000.5, 1000.0) == "passed"
    assert _opening_from(1000.5, 1000.0, own_radius_m=1.0) == "triggered"
    # with an own radius the domain is the sum: 1200 m is inside 1000 + 500 m
    assert _opening_from(1200.0, 1000.0, own_radius_m=500.0) == "triggered"
    assert _opening_from(1600.0, 1000.0, own_radius_m=500.0) == "passed"


def test_an_opening_obstacle_exactly_on_its_domain_is_not_released():
    assert _opening_from(1000.0, 1000.0) == "triggered"


def test_an_opening_obstacle_exactly_at_the_warning_range_is_passed_not_cleared():
    # cleared only beyond the warning range; at it (and beyond the domain) it is passed
    assert _opening_from(6 * NM, 100.0) == "passed"
    assert _opening_from(6 * NM + 1.0, 100.0) == "clear"


def test_an_obstacle_abeam_is_at_its_cpa_and_released_beyond_its_domain():
    # a static obstacle right abeam: the range rate is zero, the CPA is now, not ahead
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    row = np.array([[0.0, 2 * NM, 0.0, 0.0, 1 * NM]])
    for k in range(2):
        trigger.update(float(k), (0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), row)
    assert trigger.states == ["passed"] and trigger.et == 0.0


def test_a_target_keeping_station_with_the_own_ship_is_released():
    # same velocity as the own ship, which heads for its goal: the range does not shrink
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    for k in range(2):
        own = (5.0 * k, 0.0)
        trigger.update(float(k), own, (5.0, 0.0), (20 * NM, 0.0), np.array([[own[0], 2 * NM, 5.0, 0.0, 100.0]]))
    assert trigger.states == ["passed"]
    # and an obstacle beside a ship at rest (no relative motion at all) as well
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    for k in range(2):
        trigger.update(float(k), (0.0, 0.0), (0.0, 0.0), (20 * NM, 0.0), np.array([[0.0, 2 * NM, 0.0, 0.0, 100.0]]))
    assert trigger.states == ["passed"]


def test_at_the_goal_an_opening_obstacle_is_released():
    # no direction to the goal is left: only the measured velocity decides (a ship stopped
    # on its goal that an obstacle drifts away from releases it)
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (10 * NM, 0.0)
    for k in range(2):
        trigger.update(float(k), goal, (0.0, 0.0), goal, np.array([[10 * NM + 2000.0 + k, 0.0, 1.0, 0.0, 100.0]]))
    assert trigger.states == ["passed"]


def test_close_to_the_goal_the_way_back_to_it_still_counts():
    # 0.5 m short of the goal, moving away from it and from an obstacle beyond it: the
    # measured velocity opens the range but the way back to the goal closes it
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (0.5, 0.0)
    row = np.array([[2 * NM, 0.0, 0.0, 0.0, 100.0]])
    for k in range(2):
        trigger.update(float(k), (0.0, 0.0), (-5.0, 0.0), goal, row)
    assert trigger.states == ["triggered"]


def test_one_state_per_obstacle_row_and_transitions_name_their_row():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    near, far = [3 * NM, 0.0, 0.0, 0.0, 100.0], [-50 * NM, 0.0, 0.0, 0.0, 100.0]
    trigger.update(0.0, (0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), np.array([far]))
    trigger.update(1.0, (0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), np.array([far, near]))
    assert trigger.states == ["clear", "triggered"]
    assert [(t.obstacle, t.state) for t in trigger.transitions] == [(1, "triggered")]
    trigger.update(2.0, (0.0, 0.0), (5.0, 0.0), (20 * NM, 0.0), np.array([far]))
    assert trigger.states == ["clear"] and trigger.et == 0.0


def test_transition_causes_are_the_documented_ones():
    causes = {t.cause for t in states_and_transitions_of_a_pass()}
    assert causes == {"within warning range", "passed: CPA past and opening beyond the domain",
                      "beyond warning range"}


def states_and_transitions_of_a_pass():
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    row = np.array([[10 * NM, 0.5 * NM, 0.0, 0.0, 100.0]])
    for k in range(30):
        trigger.update(float(k), (k * 1 * NM, 0.0), (1 * NM, 0.0), (50 * NM, 0.0), row)
    return trigger.transitions


def _passed_target_beyond_the_warning_range(cpa_m):
    """A ship target passed (opening) within range, then, beyond eps1, closing on a course
    whose CPA with the own ship (at rest at its goal-ward position) is ``cpa_m``."""
    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    goal = (-20 * NM, 0.0)  # the way to the goal is along -x, away from the target
    trigger.update(0.0, (0.0, 0.0), (0.0, 0.0), goal, np.array([[0.0, 4 * NM, 0.0, 5.0, 100.0]]))
    trigger.update(1.0, (0.0, 0.0), (0.0, 0.0), goal, np.array([[0.0, 4 * NM, 0.0, 5.0, 100.0]]))
    assert trigger.states == ["passed"]
    # now 10 nm to the north-east, heading south: CPA (cpa_m, 0) ahead of the own ship
    trigger.update(2.0, (0.0, 0.0), (0.0, 0.0), goal, np.array([[cpa_m, 10 * NM, 0.0, -5.0, 100.0]]))
    return trigger


def test_a_passed_target_whose_cpa_falls_inside_the_warning_range_is_rearmed_while_still_beyond_it():
    rearmed = _passed_target_beyond_the_warning_range(0.9 * 4.5 * NM)
    assert rearmed.states == ["triggered"] and rearmed.transitions[-1].cause == "closing again"
    assert rearmed.transitions[-1].range_m > 4.5 * NM
    # CPA exactly on the warning range counts as inside (like the range itself)
    assert _passed_target_beyond_the_warning_range(4.5 * NM).states == ["triggered"]
    # a CPA outside the warning range leaves it passed (closing, so not cleared either)
    assert _passed_target_beyond_the_warning_range(1.1 * 4.5 * NM).states == ["passed"]


def test_each_transition_is_logged_in_one_line_a_reader_can_follow(caplog):
    """The log names the time, the obstacle row and kind, its range, the cause, the new state and ET."""
    import logging

    trigger = EventTrigger(4.5 * NM, 6.0 * NM)
    ship = np.array([[10 * NM, 0.0, 0.0, 5.0, 0.2 * NM]])
    static = np.array([[5 * NM, 3 * NM, 0.0, 0.0, 1 * NM]])
    with caplog.at_level(logging.INFO, logger="rhnc.navigation.trigger"):
        trigger.update(125.0, (0.0, 0.0), (5.0, 0.0), (40 * NM, 0.0), np.vstack([static, ship]))
    assert [record.getMessage() for record in caplog.records] == [
        f"t=125 s: obstacle 0 (static) at {np.hypot(5, 3) * NM:.0f} m: within warning range -> triggered, ET=1",
    ]
