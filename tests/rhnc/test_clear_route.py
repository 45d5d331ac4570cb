"""A route given from outside is made to keep the chart's clearance along every leg, and every
shipped sea-route baseline does (the route the project builds for its baselines)."""

import tomllib
from pathlib import Path

import numpy as np
import pytest
import shapely

from orchestrator.geometry import NM
from rhnc.chart.chart import Area, Chart, load_chart
from rhnc.chart.projection import LocalProjection
from rhnc.routing.clear_route import route_kept_clear

PASSAGES = Path(__file__).resolve().parents[2] / "scenarios" / "passages"
#: Floating-point slack of a leg that touches the clearance [m].
TOUCH_M = 1e-6


def island_chart(clearance_nm=1.0, areas=None):
    # an island 8-12 nm north, 7-13 nm east
    island = shapely.box(8.0 * NM, 7.0 * NM, 12.0 * NM, 13.0 * NM)
    return Chart(LocalProjection(51.0, 1.5), clearance_nm * NM, areas or (Area("island", "land", island),))


def least_leg_distance_nm(chart, route_m):
    return float(np.min(chart.leg_distances_m(route_m[:-1], route_m[1:]))) / NM


def test_a_leg_across_the_island_goes_round_it_at_the_clearance_and_the_clear_legs_stay_as_given():
    chart = island_chart(clearance_nm=1.0)
    given = np.array([[0.0, 2.0], [2.0, 10.0], [18.0, 10.0], [20.0, 18.0]]) * NM
    route = route_kept_clear(chart, given)
    assert least_leg_distance_nm(chart, route) >= 1.0 - TOUCH_M / NM
    np.testing.assert_array_equal(route[:2], given[:2])
    np.testing.assert_array_equal(route[-2:], given[-2:])
    # round the island and its clearance: about 2 x hypot(6, 4) + 4 = 18.4 nm for the 16 nm leg
    repaired_nm = np.sum(np.hypot(*np.diff(route[1:-1], axis=0).T)) / NM
    assert 2 * np.hypot(6.0, 4.0) + 4.0 - 0.3 < repaired_nm < 2 * np.hypot(6.0, 4.0) + 4.0 + 0.5


def test_a_leg_that_grazes_the_clearance_is_moved_out_to_it():
    chart = island_chart(clearance_nm=1.0)
    given = np.array([[2.0, 13.5], [18.0, 13.5]]) * NM  # 0.5 nm off the island's east side
    assert least_leg_distance_nm(chart, given) == pytest.approx(0.5)
    route = route_kept_clear(chart, given)
    assert least_leg_distance_nm(chart, route) >= 1.0 - TOUCH_M / NM
    assert len(route) > 2


def test_an_inner_waypoint_inside_the_clearance_is_left_out():
    chart = island_chart(clearance_nm=1.0)
    given = np.array([[2.0, 5.0], [10.0, 6.5], [18.0, 5.0]]) * NM  # the middle point 0.5 nm off the island
    route = route_kept_clear(chart, given)
    assert not np.any(np.all(route == given[1], axis=1))
    assert least_leg_distance_nm(chart, route) >= 1.0 - TOUCH_M / NM


def test_a_route_already_clear_is_returned_as_it_is():
    chart = island_chart(clearance_nm=1.0)
    given = np.array([[2.0, 2.0], [18.0, 2.0], [18.0, 18.0]]) * NM
    np.testing.assert_array_equal(route_kept_clear(chart, given), given)


def test_a_goal_cut_off_by_land_is_refused_naming_the_clearance():
    ring = shapely.box(-10.0 * NM, -10.0 * NM, 10.0 * NM, 10.0 * NM).difference(
        shapely.box(-5.0 * NM, -5.0 * NM, 5.0 * NM, 5.0 * NM))
    chart = island_chart(areas=(Area("ring", "land", ring),))
    with pytest.raises(ValueError, match=r"no route keeps the clearance of 1 nm between \(0.000, 0.000\)"):
        route_kept_clear(chart, np.array([[0.0, 0.0], [15.0, 15.0]]) * NM)


@pytest.mark.parametrize("name", sorted(path.name.removesuffix("_sea_route.toml")
                                        for path in PASSAGES.glob("*_sea_route.toml")))
def test_every_shipped_sea_route_baseline_keeps_the_declared_clearance_along_its_legs(name):
    scenario = tomllib.loads((PASSAGES / f"{name}_sea_route.toml").read_text())
    options = scenario["participants"]["route"]["options"]
    chart = load_chart(PASSAGES / options["chart"])
    waypoints = np.array(options["waypoints_deg"])
    north, east = chart.projection.to_local(waypoints[:, 0], waypoints[:, 1])
    route = np.stack([north, east], axis=1)
    assert np.min(chart.leg_distances_m(route[:-1], route[1:])) >= chart.clearance_m - TOUCH_M


def sea_route_copy(tmp_path, waypoints):
    """The strait's sea-route baseline in ``tmp_path`` with its files named absolutely and ``waypoints``."""
    text = (PASSAGES / "gibraltar_strait_sea_route.toml").read_text()
    text = text.replace('"weather/', f'"{PASSAGES}/weather/').replace('"gibraltar_strait.chart.toml"',
                                                                      f'"{PASSAGES}/gibraltar_strait.chart.toml"')
    shipped = tomllib.loads(text)["participants"]["route"]["options"]["waypoints_deg"]
    text = text.replace(f"waypoints_deg = {shipped}".replace("'", ""), f"waypoints_deg = {waypoints}")
    assert f"waypoints_deg = {waypoints}" in text
    path = tmp_path / "sea_route.toml"
    path.write_text(text)
    return path


def test_a_reference_path_on_a_chart_inside_its_clearance_stops_the_run_naming_the_leg(tmp_path, capsys):
    from orchestrator.cli import main

    # searoute's own route through the strait: its last leg runs 0.03 nm from the separation zone
    path = sea_route_copy(tmp_path, "[[36.08, -4.95], [35.97289, -5.269383], [35.968819, -5.354867], [35.93, -6.15]]")
    code = main(["run", str(path), "--results", str(tmp_path / "results"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2
    assert ("participants.route: option 'waypoints_deg': the leg from point 2 to point 3 comes 0.033 nm "
            "from land or a no-go area, inside the clearance of 1 nm of chart") in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "results").exists()


def test_a_reference_path_on_a_chart_that_keeps_its_clearance_is_built():
    from orchestrator.participant import BuildContext
    from rhnc.navigation.reference_participant import ReferencePathParticipant

    options = tomllib.loads((PASSAGES / "gibraltar_strait_sea_route.toml").read_text())["participants"]["route"]
    context = BuildContext(where="route", scenario_dir=PASSAGES, step_size=60.0, start_time=0.0, stop_time=600.0)
    assert ReferencePathParticipant.from_options("route", options["options"], context) is not None
