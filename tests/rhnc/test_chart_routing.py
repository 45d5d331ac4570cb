"""Routes keep the declared clearance from land and no-go areas along every leg."""

import numpy as np
import pytest
import shapely

from orchestrator.geometry import KNOT, NM
from rhnc.chart.chart import Area, Chart
from rhnc.chart.projection import LocalProjection
from rhnc.routing.routing_problem import RoutingProblem, straight_route
from rhnc.routing.weather_routing import optimal_route
from weather_fixtures import storm_field

SPEED = 14.0 * KNOT


def island_chart(clearance_nm=1.0):
    # an island across the straight line from (2, 10) nm to (18, 10) nm: 8-12 nm north, 7-13 nm east
    island = shapely.box(8.0 * NM, 7.0 * NM, 12.0 * NM, 13.0 * NM)
    return Chart(LocalProjection(51.0, 1.5), clearance_nm * NM, (Area("island", "land", island),))


def problem(chart, start_nm=(2.0, 10.0), goal_nm=(18.0, 10.0)):
    return RoutingProblem(tuple(np.multiply(start_nm, NM)), tuple(np.multiply(goal_nm, NM)),
                          storm_field(base_wind_ms=8.0, wind_from_deg=20.0), resolution_nm=0.5, keep_out=chart)


def least_leg_distance_nm(chart, waypoints):
    return float(np.min(chart.leg_distances_m(waypoints[:-1], waypoints[1:]))) / NM


@pytest.mark.parametrize("route", ["optimal", "straight"])
def test_routes_go_round_the_island_at_the_clearance(route):
    chart = island_chart(clearance_nm=1.0)
    routed = problem(chart)
    result = (optimal_route(routed, speed_mps=SPEED) if route == "optimal"
              else straight_route(routed, speed_mps=SPEED))
    assert least_leg_distance_nm(chart, result.waypoints_m) >= 1.0 - 1e-9
    # round the island and its clearance: 4 nm to the side, about 2 x hypot(6, 4) + 4 = 18.4 nm (16 straight)
    round_it_nm = 2 * np.hypot(6.0, 4.0) + 4.0
    assert round_it_nm - 0.3 < result.distance_nm < round_it_nm + 0.5


def test_without_the_chart_the_route_crosses_the_island():
    chart = island_chart()
    free = problem(None)
    result = optimal_route(free, speed_mps=SPEED)
    assert least_leg_distance_nm(chart, result.waypoints_m) == 0.0


@pytest.mark.parametrize("start_nm, message", [
    ((10.0, 10.0), r"the start \(18520, 18520\) m lies on land or in a no-go area"),
    ((10.0, 13.5), r"the start .* lies 0.50 nm from land or a no-go area, inside the clearance of 1.00 nm"),
])
def test_a_start_on_land_or_inside_the_clearance_is_refused(start_nm, message):
    with pytest.raises(ValueError, match=message):
        optimal_route(problem(island_chart(), start_nm=start_nm), speed_mps=SPEED)
