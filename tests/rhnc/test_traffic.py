"""Traffic (targets, static obstacles) and the reference-path participant."""

import math
from pathlib import Path

import numpy as np
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.participant import BuildContext
from rhnc.navigation.reference_participant import ReferencePathParticipant
from rhnc.encounters.traffic import TrafficParticipant

NM = 1852.0
KNOT = NM / 3600.0


def context(step_size=20.0):
    return BuildContext("exp3b.toml: participants.traffic", Path("."), step_size, 0.0, 1600.0)


def test_head_on_target_follows_eq_32():
    traffic = TrafficParticipant.from_options(
        "traffic", {"targets": [{"start_nm": [4.0, 4.0], "velocity_kn": [-9.0, -9.0], "radius_nm": 1.0}]}, context()
    )
    traffic.setup(0.0, {})
    for step in (0, 1, 10, 80):
        out = traffic.step(20.0 * step, 20.0, {})
        expected = (4.0 - 0.05 * step) * NM
        assert out["target1_x"] == pytest.approx(expected)
        assert out["target1_y"] == pytest.approx(expected)
        np.testing.assert_allclose(out["obstacles"][0], [expected, expected, -9 * KNOT, -9 * KNOT, NM], atol=1e-6)


def test_static_obstacles_follow_targets_and_waypoint_target_stops_at_the_end():
    options = {
        "targets": [{"waypoints_nm": [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]], "speed_kn": 10.0, "radius_nm": 0.5}],
        "static_obstacles": [{"center_nm": [5.0, 5.0], "radius_nm": 2.0}],
    }
    traffic = TrafficParticipant.from_options("traffic", options, context())
    first = traffic.setup(0.0, {})["obstacles"]
    np.testing.assert_allclose(first[1], [5 * NM, 5 * NM, 0.0, 0.0, 2 * NM])
    half_hour = traffic.obstacles_at(1800.0)  # 5 nm sailed: past the 2 nm track's end
    np.testing.assert_allclose(half_hour[0], [NM, NM, 0.0, 0.0, 0.5 * NM])
    ninth = traffic.obstacles_at(540.0)  # 1.5 nm: halfway along the second leg, heading east
    np.testing.assert_allclose(ninth[0], [NM, 0.5 * NM, 0.0, 10 * KNOT, 0.5 * NM], atol=1e-9)
    assert traffic.output_names == ["obstacles", "target1_x", "target1_y", "targets", "static_obstacles"]


def test_traffic_errors_name_the_key():
    with pytest.raises(ScenarioError, match=r"participants.traffic: unknown option 'ships'"):
        TrafficParticipant.from_options("traffic", {"ships": []}, context())
    with pytest.raises(ScenarioError, match=r"targets\[0\]: missing 'velocity_kn'"):
        TrafficParticipant.from_options("traffic", {"targets": [{"start_nm": [1, 1], "radius_nm": 1}]}, context())
    with pytest.raises(ScenarioError, match=r"static_obstacles\[0\]: 'radius_nm' must be a finite number >= 0"):
        TrafficParticipant.from_options("traffic", {"static_obstacles": [{"center_nm": [1, 1]}]}, context())
    with pytest.raises(ScenarioError, match=r"targets\[0\]: 'radius_nm' must be a finite number >= 0, got inf"):
        TrafficParticipant.from_options("traffic", {"targets": [{"start_nm": [1, 1], "velocity_kn": [1, 0],
                                                                 "radius_nm": float("inf")}]}, context())
    with pytest.raises(ScenarioError, match=r"targets\[0\]: 'speed_kn' must be a number > 0"):
        TrafficParticipant.from_options("traffic", {"targets": [{"waypoints_nm": [[0, 0], [1, 1]], "radius_nm": 1,
                                                                 "speed_kn": float("inf")}]}, context())


def test_no_traffic_gives_an_empty_obstacle_array():
    traffic = TrafficParticipant.from_options("traffic", {}, context())
    assert traffic.setup(0.0, {})["obstacles"].shape == (0, 5)


def test_straight_reference_is_timed_from_the_current_step():
    ref = ReferencePathParticipant.from_options(
        "ref", {"start_nm": [0.0, 0.0], "course_deg": 45.0, "speed_kn": 18.0, "horizon_steps": 15}, context()
    )
    ref.setup(0.0, {})
    out = ref.step(200.0, 20.0, {})["reference"]
    assert out.shape == (16, 7)
    np.testing.assert_allclose(out[:, 0], 200.0 + 20.0 * np.arange(16))
    distance = 18 * KNOT * out[:, 0]
    np.testing.assert_allclose(out[:, 1], distance * math.cos(math.pi / 4))
    np.testing.assert_allclose(out[:, 2], distance * math.sin(math.pi / 4))
    np.testing.assert_allclose(out[:, 3:], np.tile([math.pi / 4, 18 * KNOT, 0.0, 0.0], (16, 1)))


def test_turn_reference_satisfies_the_kinematics_of_eq_19():
    ref = ReferencePathParticipant.from_options(
        "ref", {"start_nm": [1.0, 2.0], "course_deg": 90.0, "speed_kn": 12.0, "turn_radius_nm": -1.5, "interval_s": 1.0, "horizon_steps": 600}, context()
    )
    out = ref.setup(0.0, {})["reference"]
    t, x, y, psi, u, v, r = out.T
    np.testing.assert_allclose(np.gradient(x, t)[1:-1], (u * np.cos(psi))[1:-1], rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(np.gradient(y, t)[1:-1], (u * np.sin(psi))[1:-1], rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(np.gradient(psi, t), r, rtol=1e-9)
    assert r[0] == pytest.approx(-12 * KNOT / (1.5 * NM))  # port turn
    centre = np.array([1.0, 2.0]) * NM + 1.5 * NM * np.array([1.0, 0.0])  # to port of an eastbound ship: north
    np.testing.assert_allclose(np.hypot(x - centre[0], y - centre[1]), 1.5 * NM, rtol=1e-9)


def test_waypoint_reference_and_option_errors():
    ref = ReferencePathParticipant.from_options(
        "ref", {"waypoints_nm": [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0]], "speed_kn": 20.0}, context()
    )
    out = ref.reference_at(270.0)  # 1.5 nm: on the second (northbound) leg
    np.testing.assert_allclose(out[0, 1:4], [0.5 * NM, NM, 0.0], atol=1e-9)
    # 2 nm of path at 20 kn take 360 s: afterwards the virtual ship waits at the last waypoint
    late = ref.reference_at(1000.0)
    np.testing.assert_allclose(late[:, 1:3], np.tile([NM, NM], (len(late), 1)), atol=1e-9)
    np.testing.assert_allclose(late[:, 4], 0.0)
    with pytest.raises(ScenarioError, match="participants.traffic: missing option 'course_deg'"):
        ReferencePathParticipant.from_options("ref", {"start_nm": [0, 0], "speed_kn": 10.0}, context())
    with pytest.raises(ScenarioError, match="unknown option 'course'"):
        ReferencePathParticipant.from_options("ref", {"course": 10}, context())
