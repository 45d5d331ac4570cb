"""The goal monitor: distance, arrival latch, option errors."""

import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.navigation.goal import GoalMonitor
from orchestrator.geometry import NM


def context():
    return BuildContext("s.toml: participants.goal", None, 60.0, 0.0, 600.0)


def test_distance_and_arrival_latch():
    goal = GoalMonitor.from_options("goal", {"goal_nm": [1.0, 0.0], "arrival_radius_nm": 0.5}, context())
    assert goal.setup(0.0, {"x": 0.0, "y": 0.0}) == {"goal_distance_m": NM, "arrived": 0.0}
    assert goal.step(60.0, 60.0, {"x": 0.6 * NM, "y": 0.0})["arrived"] == 1.0
    # overshooting the goal does not un-arrive
    out = goal.step(120.0, 60.0, {"x": 2.0 * NM, "y": 0.0})
    assert out == {"goal_distance_m": pytest.approx(NM), "arrived": 1.0}
    assert goal.summary() == {"arrived": True, "arrival_time_s": 60.0}


@pytest.mark.parametrize("options, message", [
    ({}, r"s.toml: missing key 'participants.goal.options.goal_nm'"),
    ({"goal_nm": [1, float("inf")]}, r"'participants.goal.options.goal_nm' must be \[north, east\] in nm, got \[1, inf\]"),
    ({"goal_nm": [1, 2], "arrival_radius_nm": 0}, r"'participants.goal.options.arrival_radius_nm' must be positive"),
    ({"goal_nm": [1, 2], "radius": 1}, r"unknown key 'participants.goal.options.radius' \(valid: goal_nm, "
                                       r"arrival_radius_nm, chart\)"),
])
def test_option_errors(options, message):
    with pytest.raises(ScenarioError, match=message):
        GoalMonitor.from_options("goal", options, context())
