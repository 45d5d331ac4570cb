"""Offline-SPNC's route: shortest obstacle-free path around circles."""

import math
import textwrap

import numpy as np
import pandas as pd
import pytest

from orchestrator.errors import ScenarioError
from orchestrator.run import run_scenario
from rhnc.offline_route import shortest_route

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


SCENARIO = """
connections = [
  "route.reference -> ctrl.reference",
  "ship.x -> ctrl.x", "ship.y -> ctrl.y", "ship.psi -> ctrl.psi",
  "ship.u -> ctrl.u", "ship.v -> ctrl.v", "ship.r -> ctrl.r",
  "ctrl.tau_u -> ship.tau_u", "ctrl.tau_r -> ship.tau_r",
]
[simulation]
steps = 110
dt_s = 20.0
[participants.route]
type = "reference_path"
[participants.route.options]
start_nm = [0.0, 0.0]
goal_nm = [10.0, 10.0]
speed_kn = 18.0
avoid = [{{ center_nm = [5.0, 5.0], radius_nm = 2.0 }}]
avoid_margin_nm = {margin}
[participants.ctrl]
type = "control"
[participants.ship]
fmu = "KCS"
[participants.ship.parameters]
u0 = 9.26
psi0 = 0.785398
[outputs]
figures = []
"""


def test_offline_spnc_tracks_the_planned_route_around_an_island(tmp_path):
    path = tmp_path / "spnc.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(margin=0.3)))
    report = run_scenario(path, tmp_path, progress=False)
    assert report.ok, report.reason
    frame = pd.read_parquet(report.folder / "timeseries.parquet")
    distance = np.hypot(frame["ship.x"] - 5 * NM, frame["ship.y"] - 5 * NM)
    assert distance.min() >= 2.0 * NM  # no collision constraints needed: the route goes round
    assert distance.min() <= 2.6 * NM  # and it is the short way round, not a wide berth


def test_route_option_errors(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(textwrap.dedent(SCENARIO.format(margin=0.3)).replace(
        'avoid = [{ center_nm = [5.0, 5.0], radius_nm = 2.0 }]', 'avoid = [{ center_nm = [0.0, 0.0], radius_nm = 2.0 }]'))
    with pytest.raises(ScenarioError, match=r"participants.route: the start lies inside obstacle 0"):
        run_scenario(path, tmp_path, progress=False)
    path.write_text(textwrap.dedent(SCENARIO.format(margin=0.3)).replace("radius_nm = 2.0 }]", "size = 2.0 }]"))
    with pytest.raises(ScenarioError, match=r"participants.route.avoid\[0\]: unknown option 'size'"):
        run_scenario(path, tmp_path, progress=False)
