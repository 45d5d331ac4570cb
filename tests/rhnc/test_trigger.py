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
