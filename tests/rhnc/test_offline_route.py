"""Offline-SPNC's route: shortest obstacle-free path around circles."""

import math

import numpy as np
import pandas as pd
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.run import run_scenario
from rhnc.routing.offline_route import shortest_route

NM = 1852.0


def length(points):
    return float(np.sum(np.hypot(*np.diff(points, axis=0).T)))


def test_without_obstacles_it_is_the_straight_line():
    route = shortest_route((0, 0), (1000, 1000), [])
    np.testing.assert_allclose(route, [[0, 0], [1000, 1000]])


def test_around_a_circle_on_the_line_it_is_the_tangent_path():
    D, R = 5000.0, 2000.0
    route = shortest_route((-D, 0.0), (D, 0.0), [(0.0, 0.0, R)])
    tangent_path = 2 * math.sqrt(D**2 - R**2) + R * (math.pi - 2 * math.acos(R / D))
    assert tangent_path <= length(route) <= 1.005 * tangent_path
    # every leg keeps out of the circle
    for a, b in zip(route[:-1], route[1:]):
        s = np.linspace(0, 1, 200)[:, None]
        assert np.min(np.hypot(*(a + s * (b - a)).T)) >= R * (1 - 1e-9)


def test_margin_and_a_circle_off_the_line():
    route = shortest_route((0, 0), (10000, 0), [(5000, 3000, 1000)])
    np.testing.assert_allclose(route, [[0, 0], [10000, 0]])  # the line already clears it
    detour = shortest_route((0, 0), (10000, 0), [(5000, 3000, 1000)], margin=2500)
    assert len(detour) > 2 and length(detour) > 10000


def test_start_inside_an_obstacle():
    with pytest.raises(ValueError, match="the start lies inside obstacle 0"):
        shortest_route((0, 0), (10, 0), [(0, 0, 5)])


ROUTE = """
start_nm = [0.0, 0.0]
goal_nm = [10.0, 10.0]
speed_kn = 18.0
avoid = [{{ center_nm = [5.0, 5.0], radius_nm = 2.0 }}]
avoid_margin_nm = {margin}
"""
SHIP = "u0 = 9.26\npsi0 = 0.785398"


def test_offline_spnc_tracks_the_planned_route_around_an_island(tmp_path, tracking_scenario):
    path = tracking_scenario("spnc", 110, ROUTE.format(margin=0.3), SHIP)
    report = run_scenario(path, tmp_path, progress=False)
    assert report.ok, report.reason
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    distance = np.hypot(frame["ship.x"] - 5 * NM, frame["ship.y"] - 5 * NM)
    assert distance.min() >= 2.0 * NM  # no collision constraints needed: the route goes round
    assert distance.min() <= 2.6 * NM  # and it is the short way round, not a wide berth


def test_route_option_errors(tmp_path, tracking_scenario):
    inside = ROUTE.format(margin=0.3).replace("center_nm = [5.0, 5.0]", "center_nm = [0.0, 0.0]")
    with pytest.raises(ScenarioError, match=r"participants.ref: the start lies inside obstacle 0"):
        run_scenario(tracking_scenario("inside", 10, inside, SHIP), tmp_path, progress=False)
    unknown = ROUTE.format(margin=0.3).replace("radius_nm = 2.0 }]", "size = 2.0 }]")
    with pytest.raises(ScenarioError, match=r"participants.ref.avoid\[0\]: unknown option 'size'"):
        run_scenario(tracking_scenario("unknown", 10, unknown, SHIP), tmp_path, progress=False)
