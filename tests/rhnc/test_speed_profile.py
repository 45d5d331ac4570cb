"""Speed along the route as a decision: the least-fuel profile that arrives on time."""

import numpy as np
import pytest

from orchestrator.geometry import KNOT, NM
from rhnc.ship.energy import EnergyParameters
from rhnc.routing.speed_profile import profile_times
from rhnc.routing.track_cost import constant_speed_times, cost_of_track, densify
from rhnc.routing.weather_routing import RoutingProblem, optimal_route, straight_route
from rhnc.weather.routing_weather_set import current_jet

ENERGY = EnergyParameters()


def jet_on_the_line(peak_kn=2.5):
    """A 40 nm route north along east = 10 nm, a jet with the passage on the line itself."""
    return current_jet(x_range_nm=(0.0, 40.0), y_range_nm=(0.0, 20.0), resolution_nm=1.0,
                       route_start_nm=(0.0, 10.0), route_goal_nm=(40.0, 10.0), offset_nm=0.0,
                       width_nm=3.0, peak_kn=peak_kn, background_wind_ms=6.0, wind_from_deg=0.0)


def line(field):
    return densify(np.array([[0.0, 5.0 * NM], [40.0 * NM, 15.0 * NM]]), 0.25 * NM)


def test_in_a_uniform_weather_the_profile_is_the_constant_speed():
    field = jet_on_the_line(peak_kn=0.0)
    points = line(field)
    constant = constant_speed_times(field, points, 16.0 * KNOT)
    times = profile_times(field, ENERGY, points, 0.0, constant[-1])
    assert times[-1] == pytest.approx(constant[-1])
    speeds = np.hypot(*np.diff(points, axis=0).T) / np.diff(times)
    assert np.ptp(speeds) < 0.05   # one speed, to the search's grid


def test_the_profile_arrives_on_time_cheaper_and_is_locally_optimal():
    # the diagonal line crosses the jet: a constant speed cannot use where the current helps
    field = jet_on_the_line()
    points = line(field)
    constant = constant_speed_times(field, points, 16.0 * KNOT)
    times = profile_times(field, ENERGY, points, 0.0, constant[-1])
    assert times[-1] == pytest.approx(constant[-1], abs=1e-6)
    cost = cost_of_track(field, ENERGY, points, times)["cost_usd"]
    assert cost < cost_of_track(field, ENERGY, points, constant)["cost_usd"] - 1.0
    # moving a minute from any leg to another does not make it cheaper (to the grid's step)
    duration = np.diff(times)
    rng = np.random.default_rng(0)
    for _ in range(20):
        i, j = rng.choice(len(duration), 2, replace=False)
        moved = duration.copy()
        shift = 0.05 * min(moved[i], moved[j])
        moved[i] += shift
        moved[j] -= shift
        other = cost_of_track(field, ENERGY, points, np.concatenate([[0.0], np.cumsum(moved)]))["cost_usd"]
        assert other > cost - 0.05


def test_no_speed_within_the_bounds_is_refused():
    field = jet_on_the_line()
    with pytest.raises(ValueError, match="needs more than"):
        profile_times(field, ENERGY, line(field), 0.0, 3600.0)


def test_route_and_speed_together_are_never_dearer_than_route_alone():
    field = jet_on_the_line()
    problem = RoutingProblem((0.0, 5.0 * NM), (40.0 * NM, 15.0 * NM), field, energy=ENERGY, resolution_nm=1.0)
    arrival = straight_route(problem, speed_mps=16.0 * KNOT).arrival_s
    route_alone = optimal_route(problem, arrival_s=arrival)
    together = optimal_route(problem, arrival_s=arrival, speed_profile=True)
    assert together.arrival_s == pytest.approx(arrival, abs=1e-3)
    assert together.cost_usd < route_alone.cost_usd
    assert together.cost_usd == pytest.approx(cost_of_track(field, ENERGY, together.waypoints_m,
                                                            together.times_s)["cost_usd"])
