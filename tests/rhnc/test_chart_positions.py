"""Positions in latitude and longitude (``start_deg``, ``goal_deg``, ``waypoints_deg``), projected by the chart."""

import re
from pathlib import Path

import numpy as np
import pytest

from orchestrator.cli import main
from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM
from orchestrator.participant import BuildContext
from rhnc.chart.chart import load_chart
from rhnc.chart.positions import projected_options
from rhnc.navigation.goal import GoalMonitor
from rhnc.navigation.reference_participant import ReferencePathParticipant

PASSAGES = Path(__file__).resolve().parents[2] / "scenarios" / "passages"
CHART = str(PASSAGES / "gibraltar_strait.chart.toml")
TARIFA = (35.96, -5.62)  # a position in the strait (lat, lon)


def plane_nm(lat, lon):
    north, east = load_chart(CHART).projection.to_local(lat, lon)
    return [float(north) / NM, float(east) / NM]


def context(name):
    return BuildContext(f"passage.toml: participants.{name}", PASSAGES, 60.0, 0.0, 3600.0)


def test_a_goal_in_latitude_and_longitude_is_the_chart_projections_point():
    monitor = GoalMonitor.from_options("goal", {"goal_deg": list(TARIFA), "chart": CHART}, context("goal"))
    expected = np.array(plane_nm(*TARIFA)) * NM
    assert monitor.goal_m == pytest.approx(tuple(expected), abs=1e-6)
    # the strait's goal as scripts/make_passages.py wrote it in the plane (to 0.001 nm)
    strait_goal = GoalMonitor.from_options("goal", {"goal_deg": [35.93, -6.15], "chart": CHART}, context("goal"))
    assert np.array(strait_goal.goal_m) / NM == pytest.approx([16.797, 14.618], abs=6e-4)


def test_waypoints_in_latitude_and_longitude_are_sailed_in_the_plane():
    # the strait's sea route (a route on a chart must keep its clearance: a straighter one crosses the zone)
    waypoints = [[36.08, -4.95], [35.97289, -5.269383], [35.968819, -5.354867], [35.94791430721023, -5.447368093662533],
                 [35.93, -6.15]]
    participant = ReferencePathParticipant.from_options(
        "route", {"waypoints_deg": waypoints, "chart": CHART, "speed_kn": 12.0}, context("route"))
    reference = participant.reference_at(0.0)
    assert reference[0, 1:3] == pytest.approx(np.array(plane_nm(*waypoints[0])) * NM, abs=1e-6)
    options = projected_options({"waypoints_deg": waypoints, "start_deg": waypoints[0], "chart": CHART}, "here",
                                PASSAGES)
    assert np.allclose(options["waypoints_nm"], [plane_nm(*p) for p in waypoints], atol=1e-9)
    assert options["start_nm"] == pytest.approx(plane_nm(*waypoints[0]))
    assert "waypoints_deg" not in options and "start_deg" not in options


@pytest.mark.parametrize("options, message", [
    ({"goal_deg": [35.96, -5.62], "goal_nm": [1.0, 2.0], "chart": CHART},
     r"^here: give either option 'goal_nm' or 'goal_deg', not both$"),
    ({"start_deg": [35.96, -5.62]}, r"^here: option 'start_deg' needs option 'chart'"),
    ({"goal_deg": [95.0, -5.62], "chart": CHART},
     r"^here: option 'goal_deg' must be \[latitude, longitude\] in degrees, got \[95.0, -5.62\]$"),
    ({"waypoints_deg": [35.96, -5.62], "chart": CHART},
     r"^here: option 'waypoints_deg' must be a list of \[latitude, longitude\] pairs in degrees"),
    ({"goal_deg": ["north", 1], "chart": CHART}, r"^here: option 'goal_deg' must be \[latitude, longitude\]"),
])
def test_bad_geographic_positions_are_refused_naming_the_option(options, message):
    with pytest.raises(ScenarioError, match=message):
        projected_options(options, "here", PASSAGES)


@pytest.mark.parametrize("old, new, where", [
    ("arrival_radius_nm = 0.5\n", "arrival_radius_nm = 0.5\ngoal_nm = [16.797, 14.618]\n", "participants.goal"),
    ("arrival_time_min = 270.0\n", "arrival_time_min = 270.0\ngoal_nm = [16.797, 14.618]\n",
     "participants.nav.options"),
])
def test_a_scenario_giving_a_position_both_ways_stops_with_one_line_naming_the_key(tmp_path, capsys, old, new, where):
    text = (PASSAGES / "gibraltar_strait.toml").read_text()
    text = text.replace('"weather/', f'"{PASSAGES}/weather/').replace('"gibraltar_strait.chart.toml"', f'"{CHART}"')
    assert old in text
    text = text.replace(old, new, 1)
    path = tmp_path / "passage.toml"
    path.write_text(text)
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1
    assert re.search(rf"passage.toml: {where}: give either option 'goal_nm' or 'goal_deg', not both", err)
    assert not (tmp_path / "results").exists()
