"""Optimal weather routing on hand-solvable cases."""

import numpy as np
import pytest

from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from orchestrator.geometry import KNOT, NM
from rhnc.routing.route_search import segment_clearance
from rhnc.routing.track_cost import constant_speed_times, cost_of_track
from rhnc.routing.routing_problem import costed_route, speed_for_arrival, time_price_usd_h
from rhnc.routing.weather_routing import (RouteSearch, RoutingProblem, _corners, _refine, cost_rate, optimal_route,
                                          straight_route)
from weather_fixtures import storm_field, switched_field

SPEED = 18 * KNOT


def offset_from_line_nm(points, a, b):
    """Signed distance [nm] of points from the line a-b (positive to the left)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = (b - a) / np.hypot(*(b - a))
    rel = np.asarray(points) - a
    return (rel[:, 0] * d[1] - rel[:, 1] * d[0]) / NM


@pytest.mark.parametrize("start_nm, goal_nm", [((0, 0), (20, 20)), ((2, 15), (19, 4)), ((1, 1), (19, 7))])
def test_uniform_weather_gives_the_straight_line(start_nm, goal_nm):
    field = storm_field(base_wind_ms=8.0, wind_from_deg=20.0, current_ms=(0.2, -0.1))
    problem = RoutingProblem(tuple(np.multiply(start_nm, NM)), tuple(np.multiply(goal_nm, NM)), field)
    straight = straight_route(problem, speed_mps=SPEED)
    for kwargs in ({"speed_mps": SPEED}, {"arrival_s": straight.arrival_s}):
        route = optimal_route(problem, **kwargs)
        offsets = offset_from_line_nm(route.waypoints_m, problem.start_m, problem.goal_m)
        assert np.max(np.abs(offsets)) < 1e-6
        assert route.cost_usd == pytest.approx(straight.cost_usd, rel=1e-7)


def test_a_storm_on_the_line_is_passed_around():
    # a strong storm centred on the diagonal, slightly to its east: the cheap side is west
    field = storm_field(storms=[(10.0, 10.6, 2.5, 20.0)])
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    straight = straight_route(problem, speed_mps=SPEED)
    route = optimal_route(problem, speed_mps=SPEED)
    offsets = offset_from_line_nm(route.waypoints_m, problem.start_m, problem.goal_m)
    assert np.max(offsets) > 2.0  # left of the line = north-west, away from the storm
    assert np.min(offsets) > -0.5
    assert route.cost_usd < 0.97 * straight.cost_usd
    assert route.distance_nm > straight.distance_nm
    # the hours count at the running cost: the fuel-only optimum sails further and costs more
    search = RouteSearch(problem)
    for hourly_usd in (0.0, 4 * problem.energy.running_cost_usd_day / 24.0):
        other = search.route(SPEED, hourly_usd, passes=1)
        other_times = constant_speed_times(field, other, SPEED)
        assert route.cost_usd < 0.999 * cost_of_track(field, problem.energy, other, other_times)["cost_usd"]
    # and at the straight line's arrival time, with the speed that arrives then
    timed = optimal_route(problem, arrival_s=straight.arrival_s)
    assert abs(timed.arrival_s - straight.arrival_s) < 1.0
    assert timed.speed_through_water_mps > SPEED
    assert np.max(offset_from_line_nm(timed.waypoints_m, problem.start_m, problem.goal_m)) > 1.0
    assert timed.cost_usd < 0.98 * straight.cost_usd


def test_an_avoided_circle_is_never_entered():
    field = storm_field(base_wind_ms=6.0)
    island = (10 * NM, 10 * NM, 2 * NM)
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, avoid=(island,))
    route = optimal_route(problem, speed_mps=SPEED)
    clearance = segment_clearance(route.waypoints_m[:-1], route.waypoints_m[1:], island[:2])
    assert np.min(clearance) >= island[2] * (1 - 1e-9)
    # in uniform weather the cheapest way around is the shortest: the tangent path
    d, r = np.hypot(10, 10), 2.0
    tangent_nm = 2 * np.sqrt(d**2 - r**2) + r * (np.pi - 2 * np.arccos(r / d))
    assert tangent_nm <= route.distance_nm <= 1.01 * tangent_nm
    assert straight_route(problem, speed_mps=SPEED).distance_nm <= 1.005 * tangent_nm


def test_the_arrival_time_is_met_and_later_is_cheaper_in_fuel():
    field = storm_field(storms=[(12.0, 8.0, 3.0, 12.0)])
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, departure_s=600.0)
    results = []
    for hours in (1.6, 2.0):
        arrival = 600.0 + hours * 3600.0
        route = optimal_route(problem, arrival_s=arrival)
        assert route.times_s[0] == 600.0
        assert abs(route.arrival_s - arrival) < 1.0
        results.append(route)
    assert results[1].fuel_t < results[0].fuel_t


def test_the_reported_cost_is_the_cost_of_the_returned_track():
    field = storm_field(storms=[(6.0, 14.0, 3.0, 15.0)], current_ms=(0.3, 0.2))
    problem = RoutingProblem((0.0, 0.0), (18 * NM, 20 * NM), field)
    speed = 15 * KNOT
    route = optimal_route(problem, speed_mps=speed)
    # the cost integrated here on its own, not through cost_of_track: midpoint rule over
    # 40 pieces a leg, at the route's speed through water and each leg's course; the time of a
    # piece is its length over the speed over ground (speed through water + current along)
    energy = problem.energy
    fuel_t = hours = 0.0
    for a, b in zip(route.waypoints_m[:-1], route.waypoints_m[1:]):
        leg = b - a
        course = np.arctan2(leg[1], leg[0])
        middles = a + ((np.arange(40) + 0.5) / 40)[:, None] * leg
        weather = field.sample(middles[:, 0], middles[:, 1])
        along = weather["current_north"] * np.cos(course) + weather["current_east"] * np.sin(course)
        piece_h = np.hypot(*leg) / 40 / (speed + along) / 3600.0
        power = brake_power(speed, course, weather["wind_north"], weather["wind_east"], weather["hs"], energy)
        fuel_t += float(np.sum(fuel_rate_t_h(power, energy) * piece_h))
        hours += float(np.sum(piece_h))
    expected = fuel_t * energy.fuel_price_usd_t + energy.running_cost_usd_day / 24.0 * hours
    assert route.duration_s == pytest.approx(hours * 3600.0, rel=1e-6)
    assert route.fuel_t == pytest.approx(fuel_t, rel=1e-5)
    assert route.cost_usd == pytest.approx(expected, rel=1e-5)
    # the route really goes round the storm (a straight line would check less)
    assert np.max(np.abs(offset_from_line_nm(route.waypoints_m, problem.start_m, problem.goal_m))) > 0.5
    account = cost_of_track(field, problem.energy, route.waypoints_m, route.times_s)
    assert account["mean_speed_through_water_kn"] == pytest.approx(15.0, rel=2e-3)


def offset_profile_nm(route, problem, stations_nm):
    """Offset from the start-goal line [nm] at stations along it [nm]."""
    a, b = np.asarray(problem.start_m), np.asarray(problem.goal_m)
    along = (route.waypoints_m - a) @ ((b - a) / np.hypot(*(b - a))) / NM
    return np.interp(stations_nm, along, offset_from_line_nm(route.waypoints_m, a, b))


def test_a_storm_changes_the_route_only_where_the_ship_is_while_it_blows():
    # two storms on the diagonal, a quarter and three quarters of the way.  In the
    # time-varying fields one of them blows only while the ship is elsewhere.
    early_storm, late_storm = (5.0, 5.4, 1.5, 20.0), (15.0, 15.4, 1.5, 20.0)
    calm = storm_field()
    both = storm_field(storms=[early_storm, late_storm])
    start, goal = (0.0, 0.0), (20 * NM, 20 * NM)
    passage_s = straight_route(RoutingProblem(start, goal, both), speed_mps=SPEED).arrival_s
    stations = np.linspace(0.5, 27.5, 55)

    def profile(field):
        problem = RoutingProblem(start, goal, field)
        route = optimal_route(problem, speed_mps=SPEED)
        assert route.cost_usd == pytest.approx(
            cost_of_track(field, problem.energy, route.waypoints_m, route.times_s)["cost_usd"], rel=1e-12)
        return offset_profile_nm(route, problem, stations)

    static_both = profile(both)
    static_late = profile(storm_field(storms=[late_storm]))
    static_early = profile(storm_field(storms=[early_storm]))
    # storms from half way on: the early one blows only after the ship has passed it
    blowing_late = profile(switched_field(calm, both, switch_s=0.5 * passage_s))
    # storms until half way: the late one has gone before the ship gets there
    blowing_early = profile(switched_field(both, calm, switch_s=0.5 * passage_s))
    assert np.max(np.abs(blowing_late - static_late)) < 0.3
    assert np.max(np.abs(blowing_early - static_early)) < 0.3
    assert np.max(np.abs(static_both - static_late)) > 0.8
    assert np.max(np.abs(static_both - static_early)) > 0.8


@pytest.mark.parametrize("kwargs, message", [
    ({}, "exactly one of speed_mps and arrival_s"),
    ({"speed_mps": 9.0, "arrival_s": 3600.0}, "exactly one of speed_mps and arrival_s"),
    ({"speed_mps": -1.0}, "speed_mps must be positive"),
    ({"arrival_s": -5.0}, "must be after the departure"),
    ({"arrival_s": 60.0}, "needs more than 30 m/s"),
])
def test_bad_arguments(kwargs, message):
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), storm_field())
    with pytest.raises(ValueError, match=message):
        optimal_route(problem, **kwargs)


def test_start_outside_the_map_or_inside_an_avoided_circle():
    field = storm_field()
    with pytest.raises(ValueError, match="the start .* lies outside the met-ocean map"):
        optimal_route(RoutingProblem((-NM, 0.0), (20 * NM, 20 * NM), field), speed_mps=SPEED)
    with pytest.raises(ValueError, match="the goal lies inside avoided circle 0"):
        straight_route(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, avoid=((20 * NM, 19 * NM, 2 * NM),)),
                       speed_mps=SPEED)


@pytest.mark.parametrize("goal_nm", [(20, 20), (19, 7), (3, 18)])
def test_the_search_itself_gives_the_straight_line_in_uniform_weather(goal_nm):
    # the graph alone zig-zags between its 32 headings; the shortening must straighten it
    field = storm_field(base_wind_ms=8.0, wind_from_deg=200.0)
    problem = RoutingProblem((NM, 0.0), tuple(np.multiply(goal_nm, NM)), field)
    polyline = RouteSearch(problem).route(SPEED, 500.0, passes=1)
    np.testing.assert_allclose(polyline, [problem.start_m, problem.goal_m], atol=1e-6)


def test_edge_weights_are_the_energy_model_cost_of_the_edge_sailed_on_its_course():
    # uniform wind from the north: every edge's weight is exactly the cost of sailing it,
    # and a northbound edge (head wind) costs more than a southbound one of the same length
    field = storm_field(base_wind_ms=15.0, wind_from_deg=0.0, current_ms=(0.3, 0.1))
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    search = RouteSearch(problem)
    hourly = problem.energy.running_cost_usd_day / 24.0
    weight, duration = search.weights(SPEED, hourly, None)
    graph = search.graph
    centre = graph.nearest_free_node((10 * NM, 10 * NM))
    costs = {}
    for edge in range(graph.indptr[centre], graph.indptr[centre + 1]):
        track = search.nodes[[graph.source[edge], graph.target[edge]]]
        times = constant_speed_times(field, track, SPEED)
        assert duration[edge] == pytest.approx(times[-1], rel=1e-12)
        assert weight[edge] == pytest.approx(cost_of_track(field, problem.energy, track, times)["cost_usd"], rel=1e-9)
        costs[tuple(graph.moves[graph.move[edge]])] = weight[edge]
    assert len(costs) == 32
    # head wind on the KCS's 1000 m2 frontal area: about 5.6 % dearer, although the current
    # (0.3 m/s north) shortens the northbound edge; a course-blind cost would make it cheaper
    assert costs[(1, 0)] > 1.03 * costs[(-1, 0)]


def test_a_detour_does_not_pay_when_time_is_dear_enough():
    # the storm of the detour test, but each hour at sea costs 50 times the default
    field = storm_field(storms=[(10.0, 10.6, 2.5, 20.0)])
    energy = EnergyParameters(running_cost_usd_day=600_000.0)
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, energy=energy)
    polyline = RouteSearch(problem).route(SPEED, energy.running_cost_usd_day / 24.0, passes=1)
    offsets = offset_from_line_nm(polyline, problem.start_m, problem.goal_m)
    assert np.max(np.abs(offsets)) < 0.5
    route = optimal_route(problem, speed_mps=SPEED)
    assert route.distance_nm == pytest.approx(straight_route(problem, speed_mps=SPEED).distance_nm, rel=2e-3)


def hours_at_sea(legs, current_ms=(0.3, 0.2)):
    """Hours [h] each leg (north, east [m]) takes at SPEED through water in a uniform current."""
    course = np.arctan2(legs[:, 1], legs[:, 0])
    along = current_ms[0] * np.cos(course) + current_ms[1] * np.sin(course)
    return np.hypot(*legs.T) / (SPEED + along) / 3600.0


def test_a_shortcut_is_priced_with_the_hours_it_takes():
    # the objective of a straight segment is fuel plus the price of each hour it takes: the
    # difference between two prices is that price times the segment's duration, at the speed
    # over ground (speed through water plus the current along the segment)
    field = storm_field(storms=[(10.0, 10.0, 3.0, 15.0)], current_ms=(0.3, 0.2))
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    search = RouteSearch(problem)
    start = np.array([1.0, 2.0]) * NM
    ends = np.array([[15.0, 3.0], [10.0, 12.0], [2.0, 18.0]]) * NM
    price = 1000.0
    fuel_only = search.segment_costs(start, ends, 0.0, SPEED, 0.0)
    assert np.all(fuel_only > 0)
    priced = search.segment_costs(start, ends, 0.0, SPEED, price)
    assert priced - fuel_only == pytest.approx(price * hours_at_sea(ends - start), rel=1e-9)
    polyline = np.vstack([start, ends])
    leg_priced = search.leg_costs(polyline, 0.0, SPEED, price) - search.leg_costs(polyline, 0.0, SPEED, 0.0)
    leg_hours = hours_at_sea(np.diff(polyline, axis=0))
    assert leg_priced == pytest.approx(price * leg_hours, rel=1e-9)
    # the grid search's rates too: each hour at the price on top of the fuel
    priced_rate, _ = search.node_rates(SPEED, price, slice(None), None)
    fuel_rate, _ = search.node_rates(SPEED, 0.0, slice(None), None)
    assert priced_rate - fuel_rate == pytest.approx(np.full_like(fuel_rate, price), rel=1e-12)


def test_refining_moves_the_last_turning_point_too():
    # a storm on the last leg, three quarters of the way along it: only moving the turning
    # point inserted midway along that leg takes the route off the storm's centre
    last_from, goal = np.array([10.0, 15.0]), np.array([20.0, 20.0])
    centre = last_from + 0.75 * (goal - last_from)
    field = storm_field(storms=[(*centre, 1.0, 20.0)])
    problem = RoutingProblem((0.0, 0.0), tuple(goal * NM), field)
    polyline = np.array([[0.0, 0.0], last_from, goal]) * NM

    def evaluate(points):
        return costed_route(problem, points, SPEED, "optimal")

    before = evaluate(polyline)
    after = _refine(problem, polyline, before, evaluate)
    assert after.cost_usd < before.cost_usd
    clearance_nm = np.min(np.hypot(*(after.waypoints_m - centre * NM).T)) / NM
    assert clearance_nm > 0.7


def test_one_cost_rate_for_the_grid_its_segments_and_its_legs():
    # the rate is the energy model's fuel cost with the course sailed plus the price of the
    # hour, and the current counts along the course; the grid's node rates, a segment's cost
    # and a leg's cost all come from it, so one straight leg costs the same either way
    field = storm_field(storms=[(8.0, 12.0, 3.0, 15.0)], base_wind_ms=9.0, wind_from_deg=70.0, current_ms=(0.4, -0.3))
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    weather = field.sample(np.array([3.0, 8.0]) * NM, np.array([5.0, 12.0]) * NM)
    heading = np.radians([30.0, 200.0])
    rate, along = cost_rate(weather, heading, SPEED, 250.0, problem.energy)
    power = brake_power(SPEED, heading, weather["wind_north"], weather["wind_east"], weather["hs"], problem.energy)
    assert rate == pytest.approx(fuel_rate_t_h(power, problem.energy) * problem.energy.fuel_price_usd_t + 250.0, rel=1e-12)
    assert along == pytest.approx([0.4 * np.cos(heading[0]) - 0.3 * np.sin(heading[0]),
                                   0.4 * np.cos(heading[1]) - 0.3 * np.sin(heading[1])], rel=1e-12)
    search = RouteSearch(problem)
    node = search.graph.nearest_free_node((8 * NM, 12 * NM))
    node_rate, over_ground = search.node_rates(SPEED, 250.0, np.array([node]), None)
    at_node = field.sample(search.nodes[[node], 0], search.nodes[[node], 1])
    expected, expected_along = cost_rate(at_node, search.graph.heading_rad, SPEED, 250.0, problem.energy)
    np.testing.assert_array_equal(node_rate[0], expected)
    np.testing.assert_array_equal(over_ground[0], SPEED + expected_along)
    start, end = np.array([2.0, 3.0]) * NM, np.array([14.0, 17.0]) * NM
    segment = search.segment_costs(start, end[None, :], 60.0, SPEED, 250.0)
    leg = search.leg_costs(np.vstack([start, end]), 60.0, SPEED, 250.0)
    assert segment[0] == pytest.approx(leg[0], rel=1e-12)


def test_refining_never_moves_a_turning_point_into_an_avoided_circle():
    # the storm of the test above; a circle where the refinement, left alone, puts its turning point
    last_from, goal = np.array([10.0, 15.0]), np.array([20.0, 20.0])
    field = storm_field(storms=[(*(last_from + 0.75 * (goal - last_from)), 1.0, 20.0)])
    island = (16.9 * NM, 15.2 * NM, 0.6 * NM)
    problem = RoutingProblem((0.0, 0.0), tuple(goal * NM), field, avoid=(island,))
    polyline = np.array([[0.0, 0.0], last_from, goal]) * NM
    free = RoutingProblem((0.0, 0.0), tuple(goal * NM), field)

    def refined(routing):
        def evaluate(points):
            return costed_route(routing, points, SPEED, "optimal")
        return _refine(routing, polyline, evaluate(polyline), evaluate)

    unconstrained = refined(free).waypoints_m
    assert np.min(segment_clearance(unconstrained[:-1], unconstrained[1:], island[:2])) < 0.5 * island[2]
    after = refined(problem)
    assert np.min(segment_clearance(after.waypoints_m[:-1], after.waypoints_m[1:], island[:2])) >= island[2]
    assert after.cost_usd < costed_route(problem, polyline, SPEED, "optimal").cost_usd


class _KeepOutEast:
    """A stand-in chart: a leg is clear unless it ends east of ``east_m``; records what it was asked."""

    clearance_m = 0.0

    def __init__(self, east_m):
        self.east_m, self.asked = east_m, []

    def distances_m(self, north, east):
        return np.full(np.shape(north), 1e9)

    def legs_clear(self, starts, ends, *_):
        self.asked.append((np.array(starts), np.array(ends)))
        return np.asarray(ends)[..., 1] <= self.east_m


def test_leg_costs_close_the_legs_entering_an_avoided_circle_or_refused_by_the_chart():
    field = storm_field(base_wind_ms=6.0)
    island = (10 * NM, 14 * NM, 1 * NM)
    polyline = np.array([[2.0, 2.0], [10.0, 4.0], [10.0, 18.0], [18.0, 18.0]]) * NM  # only the middle leg enters
    open_costs = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)).leg_costs(polyline, 0.0, SPEED, 0.0)
    assert np.all(np.isfinite(open_costs)) and np.all(open_costs > 0)
    with_island = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, avoid=(island,)))
    costs = with_island.leg_costs(polyline, 0.0, SPEED, 0.0)
    assert np.isinf(costs[1]) and costs[[0, 2]] == pytest.approx(open_costs[[0, 2]], rel=1e-12)
    chart = _KeepOutEast(east_m=10 * NM)  # refuses the legs ending at 18 nm east
    charted = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, keep_out=chart))
    chart.asked.clear()  # (the search grid asked it too)
    costs = charted.leg_costs(polyline, 0.0, SPEED, 0.0)
    assert np.isinf(costs[1:]).all() and costs[0] == pytest.approx(open_costs[0], rel=1e-12)
    starts, ends = chart.asked[-1]
    np.testing.assert_array_equal(starts, polyline[:-1])
    np.testing.assert_array_equal(ends, polyline[1:])


def test_a_path_costs_its_legs_each_from_the_time_it_is_reached():
    calm, storm = storm_field(base_wind_ms=4.0), storm_field(base_wind_ms=4.0, storms=[(10.0, 10.0, 6.0, 20.0)])
    field = switched_field(calm, storm, switch_s=2900.0, ramp_s=600.0)  # the storm rises as the second leg begins
    search = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field))
    polyline = np.array([[1.0, 1.0], [8.0, 12.0], [19.0, 19.0]]) * NM
    legs = search.leg_costs(polyline, 600.0, SPEED, 300.0)
    first_leg_s = np.hypot(*(polyline[1] - polyline[0])) / SPEED
    later = search.leg_costs(polyline[1:], 600.0 + first_leg_s, SPEED, 300.0)
    assert legs[1] == pytest.approx(later[0], rel=1e-9)
    assert legs[1] != pytest.approx(search.leg_costs(polyline[1:], 600.0, SPEED, 300.0)[0], rel=1e-3)
    # the path's cost is its legs' sum, and an hour's price adds the hours sailed
    total = search.path_cost(polyline, 600.0, SPEED, 300.0)
    assert total == pytest.approx(legs.sum(), rel=1e-12)
    hours = np.hypot(*np.diff(polyline, axis=0).T).sum() / SPEED / 3600.0
    assert total - search.path_cost(polyline, 600.0, SPEED, 0.0) == pytest.approx(300.0 * hours, rel=1e-9)


class _KeepOutBox:
    """A stand-in chart refusing every leg with an end in a box (north, east ranges [m]); it checks that
    what it is asked about are the consecutive legs of one polyline."""

    def __init__(self, north_m, east_m):
        self.north_m, self.east_m, self.calls = north_m, east_m, 0

    def legs_clear(self, starts, ends):
        starts, ends = np.asarray(starts), np.asarray(ends)
        assert starts.shape == ends.shape and np.array_equal(starts[1:], ends[:-1])
        self.calls += 1

        def inside(p):
            return ((self.north_m[0] < p[:, 0]) & (p[:, 0] < self.north_m[1])
                    & (self.east_m[0] < p[:, 1]) & (p[:, 1] < self.east_m[1]))
        return ~(inside(starts) | inside(ends))


def test_refining_asks_the_chart_about_each_candidate_and_keeps_out_of_what_it_refuses():
    last_from, goal = np.array([10.0, 15.0]), np.array([20.0, 20.0])
    field = storm_field(storms=[(*(last_from + 0.75 * (goal - last_from)), 1.0, 20.0)])
    chart = _KeepOutBox((14.0 * NM, 18.5 * NM), (13.0 * NM, 16.5 * NM))  # where the free refinement turns
    problem = RoutingProblem((0.0, 0.0), tuple(goal * NM), field, keep_out=chart)
    polyline = np.array([[0.0, 0.0], last_from, goal]) * NM

    def evaluate(points):
        return costed_route(problem, points, SPEED, "optimal")

    before = evaluate(polyline)
    after = _refine(problem, polyline, before, evaluate)
    assert chart.calls > 0 and after.cost_usd < before.cost_usd
    corners = _corners(after.waypoints_m)  # (the stand-in judges a leg by its ends)
    inside = ((14.0 * NM < corners[:, 0]) & (corners[:, 0] < 18.5 * NM)
              & (13.0 * NM < corners[:, 1]) & (corners[:, 1] < 16.5 * NM))
    assert not inside.any()


def test_an_optimal_route_says_so():
    field = storm_field(storms=[(10.0, 10.6, 2.5, 20.0)])
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    route = optimal_route(problem, speed_mps=SPEED)
    assert len(route.waypoints_m) > 2 and route.method == "optimal"
    assert straight_route(problem, speed_mps=SPEED).method == "straight"


def test_the_speed_that_arrives_is_found_against_a_head_current_faster_than_the_slowest_speed_tried():
    # 0.8 m/s against a northbound passage of 16 nm in 2 h, in weather that changes in time (a tidal
    # stream's files): the slowest speed tried (0.5 m/s) is stopped by the current, and counts as late
    from weather_fixtures import storm_field, switched_field

    stream = storm_field(current_ms=(-0.8, 0.0))
    problem = RoutingProblem((2.0 * NM, 10.0 * NM), (18.0 * NM, 10.0 * NM), switched_field(stream, stream, 1e5))
    polyline = np.array([problem.start_m, problem.goal_m])
    assert speed_for_arrival(problem, polyline, 7200.0) == pytest.approx(16.0 * NM / 7200.0 + 0.8, rel=1e-6)
    result = straight_route(problem, arrival_s=7200.0)
    assert result.arrival_s == pytest.approx(7200.0, abs=1e-3)


def test_routes_turn_only_over_the_weather_data_not_over_the_held_band_round_it():
    # an island on the north edge of the data: round it to the north is shorter, but only
    # over the band of held edge values (no data there); every route goes round to the south
    field = storm_field(base_wind_ms=6.0).with_edges_held(10 * NM)
    island = (16 * NM, 10 * NM, 6 * NM)
    problem = RoutingProblem((17 * NM, 2 * NM), (17 * NM, 18 * NM), field, avoid=(island,))
    x_min, x_max, y_min, y_max = field.data_extent
    assert field.extent[1] > x_max + 9 * NM          # the band is there to go round by
    straight = straight_route(problem, speed_mps=SPEED)
    routes = {"search": RouteSearch(problem).route(SPEED, 500.0, passes=1),
              "straight": straight.waypoints_m,
              "optimal": optimal_route(problem, speed_mps=SPEED).waypoints_m,
              "timed": optimal_route(problem, arrival_s=straight.arrival_s).waypoints_m}
    for name, route in routes.items():
        turns = route[1:-1]
        assert len(turns), name
        assert np.all((turns[:, 0] >= x_min - 1e-6) & (turns[:, 0] <= x_max + 1e-6)), name
        assert np.all((turns[:, 1] >= y_min - 1e-6) & (turns[:, 1] <= y_max + 1e-6)), name
        assert np.min(turns[:, 0]) < island[0] - island[2] + 1e-6, name   # south of the island
        assert np.min(segment_clearance(route[:-1], route[1:], island[:2])) >= island[2] * (1 - 1e-9), name


def test_refining_keeps_the_turning_points_over_the_weather_data():
    # a storm just south of a route along the north edge of the data: moving the turning
    # points north pays, up to the edge; the band of held edge values beyond it is no data
    field = storm_field(storms=[(16.0, 10.0, 3.0, 20.0)]).with_edges_held(10 * NM)
    problem = RoutingProblem((19 * NM, 2 * NM), (19 * NM, 18 * NM), field)
    polyline = np.array([[19.0, 2.0], [19.5, 10.0], [19.0, 18.0]]) * NM

    def evaluate(points):
        return costed_route(problem, points, SPEED, "optimal")

    before = evaluate(polyline)
    after = _refine(problem, polyline, before, evaluate)
    assert after.cost_usd < before.cost_usd
    assert np.max(after.waypoints_m[:, 0]) == pytest.approx(field.data_extent[1], abs=1e-6)


def test_the_search_grid_has_the_requested_spacing_over_the_data():
    field = storm_field(size_nm=20.0, resolution_nm=0.5)
    for resolution_nm in (0.5, 1.0, 2.5):
        graph = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field, resolution_nm=resolution_nm)).graph
        for axis in (graph.x_m, graph.y_m):
            np.testing.assert_allclose(np.diff(axis), resolution_nm * NM)
            np.testing.assert_allclose(axis[[0, -1]], [0.0, 20 * NM])


def test_an_hour_is_priced_at_the_running_cost_or_at_the_multiples_of_the_shadow_price_given():
    field = storm_field(storms=[(10.0, 10.6, 2.5, 20.0)])          # the storm above: a detour pays
    problem = RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), field)
    at_speed = optimal_route(problem, speed_mps=SPEED)
    assert at_speed.time_price_usd_h == pytest.approx(problem.energy.running_cost_usd_day / 24.0, rel=1e-12)
    arrival_s = straight_route(problem, speed_mps=SPEED).arrival_s
    shadow_price = time_price_usd_h(problem, straight_route(problem, arrival_s=arrival_s))
    for multiple in (0.3, 1.4):
        timed = optimal_route(problem, arrival_s=arrival_s, price_multiples=(multiple,))
        assert timed.time_price_usd_h == pytest.approx(multiple * shadow_price, rel=1e-12)


def test_a_head_current_that_stops_the_ship_closes_segments_and_legs_however_short():
    # 10 m/s towards the south against 9.3 m/s through water: no way north
    search = RouteSearch(RoutingProblem((0.0, 0.0), (20 * NM, 20 * NM), storm_field(current_ms=(-10.0, 0.0))))
    a = np.array([5 * NM, 5 * NM])
    segments = search.segment_costs(a, a + np.array([[5 * NM, 0.0], [0.0, 5 * NM], [-5 * NM, 0.0]]), 0.0, SPEED, 100.0)
    assert np.isposinf(segments[0]) and np.all(np.isfinite(segments[1:]))
    legs = search.leg_costs(np.array([a, a + [0.5, 0.0], a + [0.5, 5 * NM]]), 0.0, SPEED, 100.0)   # half a metre north
    assert np.isposinf(legs[0]) and np.isfinite(legs[1])


def test_a_circle_or_chart_that_bars_only_dearer_moves_leaves_the_refinement_as_it_is():
    # a storm just east of a northbound route: the refinement moves it west; an island
    # further east, or a chart refusing legs that end east of the route, bars only moves
    # east, which cost more anyway, so the route is the same
    field = storm_field(storms=[(10.0, 11.0, 2.0, 20.0)])
    polyline = np.array([[0.0, 10.0], [10.0, 10.0], [20.0, 10.0]]) * NM
    island = (10 * NM, 14 * NM, 2.5 * NM)
    refined = []
    for avoid, keep_out in (((), None), ((island,), None), ((), _KeepOutEast(10.5 * NM))):
        problem = RoutingProblem((0.0, 10 * NM), (20 * NM, 10 * NM), field, avoid=avoid, keep_out=keep_out)

        def evaluate(points, problem=problem):
            return costed_route(problem, points, SPEED, "optimal")

        refined.append(_refine(problem, polyline, evaluate(polyline), evaluate).waypoints_m)
    assert np.min(refined[0][:, 1]) < 9.0 * NM                           # moved west, off the storm
    assert np.min(segment_clearance(refined[0][:-1], refined[0][1:], island[:2])) > island[2]
    np.testing.assert_array_equal(refined[1], refined[0])
    np.testing.assert_array_equal(refined[2], refined[0])
