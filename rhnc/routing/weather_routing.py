"""Optimal weather routing: the cheapest route through the met-ocean field, the baseline a
weather-routing user would hold a navigation system against.

Two questions are answered, both for a ship keeping a constant speed through water:

* **fixed speed** (``speed_mps``): the route that minimises the passage's cost EC (fuel
  plus running cost C_c / 24 per hour) at that speed through water; a detour is paid for
  by its fuel and by the hours it adds;
* **fixed arrival time** (``arrival_s``): the route and the one constant speed through
  water that arrive at that time at least cost.  The running cost is then the same for
  every candidate, so the cheapest is the one burning least fuel.

The cost of any candidate comes from the project's energy model with the course of each
leg (:func:`rhnc.routing.track_cost.cost_of_track`).  The search (:mod:`rhnc.routing.route_search`) runs
Dijkstra's algorithm on a grid at ``resolution_nm`` with 32 headings; an edge weighs the
trapezoid of the cost rate at its two ends (heading = the edge's course) over its
duration.  At fixed arrival time each hour counts at a multiple of the shadow price of
time along the straight route, lambda = v dF/dv - F (F the fuel cost rate): what one hour
less at sea would cost in extra fuel for the speed-up it forces; as that is only an
estimate of the price along the best route, several multiples are searched.  Each route
found is shortened where straight segments cost no more
(:func:`rhnc.routing.route_search.shortcut_path`), timed at constant speed (for a fixed arrival
time, at the speed that arrives on time) and costed; the cheapest one's turning points
are then moved sideways while the cost falls.  The straight (or shortest obstacle-free)
route is always a candidate, so the optimum is never dearer than it.  The problem, the
costing of a candidate and the straight route: :mod:`rhnc.routing.routing_problem`.

Time-dependent weather: node times come from the previous search (first from the
distance to the start at the planned speed); the weights are re-evaluated with the
weather at those times and the search repeated.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from orchestrator.geometry import NM
from rhnc.ship.energy import brake_power, fuel_rate_t_h
from rhnc.weather.metocean_grid import axis_node_count, data_extent
from rhnc.routing.route_search import (IMPASSABLE, GridGraph, build_grid_graph, segment_clearance, shortcut_path,
                               shortest_path_tree, times_along_tree)
from rhnc.routing.routing_problem import (RouteResult, RoutingProblem, check_problem, costed_route, profiled_route,
                                          shortest_clear_route, speed_for_arrival, straight_route, time_price_usd_h)
from rhnc.routing.track_cost import constant_speed_times, cost_of_track, is_time_varying, sample_weather

log = logging.getLogger(__name__)

__all__ = ["RoutingProblem", "RouteResult", "RouteSearch", "cost_rate", "optimal_route", "straight_route", "cost_of_track",
           "time_price_usd_h"]


def cost_rate(weather, heading_rad, speed_mps: float, time_price_usd_h: float, energy):
    """Objective rate [USD/h] and current along the course [m/s] of a ship on ``heading_rad``.

    The one costing of the search, its segments and its legs: the fuel cost rate of the
    energy model's brake power at ``speed_mps`` through water with the course sailed,
    plus ``time_price_usd_h`` for each hour.

    Parameters
    ----------
    weather : mapping of str to ndarray
        ``wind_north``, ``wind_east`` [m/s], ``hs`` [m], ``current_north``, ``current_east``
        [m/s], broadcastable against ``heading_rad``.
    heading_rad : ndarray
        Course sailed [rad] (north = 0, east = pi / 2).
    speed_mps : float
        Speed through water [m/s].
    time_price_usd_h : float
        Price of an hour [USD/h].
    energy : EnergyParameters

    Returns
    -------
    rate, along : ndarray
        Objective rate [USD/h] and current along the course [m/s] (speed over ground is
        ``speed_mps + along``).
    """
    along = weather["current_north"] * np.cos(heading_rad) + weather["current_east"] * np.sin(heading_rad)
    power = brake_power(speed_mps, heading_rad, weather["wind_north"], weather["wind_east"], weather["hs"], energy)
    return fuel_rate_t_h(power, energy) * energy.fuel_price_usd_t + time_price_usd_h, along


class RouteSearch:
    """The search grid of one problem and the weights of its edges at a speed and a price of time.

    The objective of a route at constant speed through water v is the integral over the
    passage of ``F + lambda``: F the fuel cost rate [USD/h] with the course sailed,
    lambda the price of an hour [USD/h] (the running cost C_c / 24 at fixed speed, the
    shadow price of time at fixed arrival).
    """

    def __init__(self, problem: RoutingProblem):
        self.problem = problem
        x_min, x_max, y_min, y_max = data_extent(problem.metocean)   # not the held band round it
        step = problem.resolution_nm * NM
        what = "the route search's resolution_nm"
        x = np.linspace(x_min, x_max, axis_node_count(x_max - x_min, step, what))  # refused beyond the limit
        y = np.linspace(y_min, y_max, axis_node_count(y_max - y_min, step, what))
        self.graph: GridGraph = build_grid_graph(x, y, problem.reach, problem.avoid, problem.keep_out)
        self.nodes = self.graph.node_points()
        self.source = self.graph.nearest_free_node(problem.start_m)
        self.target = self.graph.nearest_free_node(problem.goal_m)
        moves = len(self.graph.moves)
        self._source_move = self.graph.source * moves + self.graph.move
        self._target_move = self.graph.target * moves + self.graph.move
        self._edge_length = self.graph.move_length_m[self.graph.move]
        self.static_weather = None if is_time_varying(problem.metocean) else problem.metocean.sample(
            self.nodes[:, 0], self.nodes[:, 1])

    def node_rates(self, speed_mps: float, time_price_usd_h: float, nodes, node_times_s: np.ndarray | None):
        """Objective rate [USD/h] and speed over ground [m/s] of every move leaving ``nodes``.

        Parameters
        ----------
        speed_mps : float
            Speed through water [m/s].
        time_price_usd_h : float
            Price of an hour [USD/h], added to the fuel cost rate.
        nodes : array of int or slice
            Node ids.
        node_times_s : ndarray or None
            Time [s] each of ``nodes`` is passed (a field that changes in time), else None.

        Returns
        -------
        rate, over_ground : ndarray (len(nodes), moves)
        """
        p = self.problem
        if self.static_weather is not None:
            weather = {name: values[nodes] for name, values in self.static_weather.items()}
        else:
            weather = sample_weather(p.metocean, self.nodes[nodes, 0], self.nodes[nodes, 1], node_times_s)
        per_node = {name: values[:, None] for name, values in weather.items()}
        rate, along = cost_rate(per_node, self.graph.heading_rad[None, :], speed_mps, time_price_usd_h, p.energy)
        return rate, speed_mps + along

    def edge_weights(self, rate: np.ndarray, over_ground: np.ndarray):
        """Edge weights [USD] and durations [s] from the rates of :meth:`node_rates` at every node:
        the trapezoid of the rate at the edge's two ends over the time the edge takes at the
        mean of their speeds over ground (``IMPASSABLE`` where a head current stops the ship)."""
        over_ground = over_ground.ravel()
        rate = rate.ravel()
        edge_speed = 0.5 * (over_ground[self._source_move] + over_ground[self._target_move])
        passable = edge_speed > 1e-3
        duration = np.where(passable, self._edge_length / np.maximum(edge_speed, 1e-3), IMPASSABLE)
        weight = np.where(passable, (rate[self._source_move] + rate[self._target_move]) * (duration / 7200.0),
                          IMPASSABLE)
        return weight, duration

    def weights(self, speed_mps: float, time_price_usd_h: float, node_times_s: np.ndarray | None):
        """Edge weights [USD] and durations [s] at constant speed through water."""
        rate, over_ground = self.node_rates(speed_mps, time_price_usd_h, slice(None), node_times_s)
        return self.edge_weights(rate, over_ground)

    def route(self, speed_mps: float, time_price_usd_h: float, passes: int) -> np.ndarray:
        """Cheapest polyline start -> goal on the grid, shortened where straight segments pay."""
        p = self.problem
        times = None
        if is_time_varying(p.metocean):
            distance = np.hypot(self.nodes[:, 0] - p.start_m[0], self.nodes[:, 1] - p.start_m[1])
            times = p.departure_s + distance / speed_mps
        for _ in range(passes if times is not None else 1):
            weight, duration = self.weights(speed_mps, time_price_usd_h, times)
            tree = shortest_path_tree(self.graph, weight, self.source)
            if times is not None:
                times = times_along_tree(tree, duration, self.graph, p.departure_s)
        path = self.nodes[tree.path_to(self.target)]
        polyline = np.vstack([np.asarray(p.start_m, dtype=float), path, np.asarray(p.goal_m, dtype=float)])
        keep = np.concatenate([[True], np.hypot(*np.diff(polyline, axis=0).T) > 1e-6])
        polyline = polyline[keep]
        if len(polyline) < 2:
            return np.vstack([polyline, polyline])
        vertex_times = constant_speed_times(p.metocean, polyline, speed_mps, p.departure_s)
        kept = shortcut_path(len(polyline), lambda i, js: self.segment_costs(
            polyline[i], polyline[js], vertex_times[i], speed_mps, time_price_usd_h))
        return polyline[kept]

    def segment_costs(self, a: np.ndarray, ends: np.ndarray, start_s: float, speed_mps: float,
                      time_price_usd_h: float) -> np.ndarray:
        """Objective [USD] of straight segments from ``a`` to each of ``ends`` at constant speed."""
        p = self.problem
        legs = ends - a
        length = np.hypot(*legs.T)
        spacing = p.resolution_nm * NM / 2.0
        pieces = np.maximum(np.ceil(length / spacing).astype(int), 1)
        owner = np.repeat(np.arange(len(ends)), pieces + 1)
        first = np.concatenate([[0], np.cumsum(pieces + 1)[:-1]])
        fraction = (np.arange(owner.size) - first[owner]) / pieces[owner]
        points = a + fraction[:, None] * legs[owner]
        heading = np.arctan2(legs[:, 1], legs[:, 0])[owner]
        weather = sample_weather(p.metocean, points[:, 0], points[:, 1],
                                 start_s + fraction * length[owner] / speed_mps)
        rate, along = cost_rate(weather, heading, speed_mps, time_price_usd_h, p.energy)
        over_ground = speed_mps + along
        same = owner[1:] == owner[:-1]
        sub_speed = 0.5 * (over_ground[1:] + over_ground[:-1])
        sub_length = (length / pieces)[owner[:-1]]
        blocked = same & (sub_speed <= 1e-3)
        hours = np.where(same & ~blocked, sub_length / np.maximum(sub_speed, 1e-3), 0.0) / 3600.0
        cost = np.bincount(owner[:-1], weights=0.5 * (rate[1:] + rate[:-1]) * hours, minlength=len(ends))
        cost[np.bincount(owner[:-1], weights=blocked, minlength=len(ends)) > 0] = np.inf
        for cx, cy, radius in p.avoid:
            cost[segment_clearance(np.broadcast_to(a, ends.shape), ends, (cx, cy)) < radius] = np.inf
        if p.keep_out is not None:
            cost[~p.keep_out.legs_clear(np.broadcast_to(a, ends.shape), ends)] = np.inf
        return cost

    def leg_costs(self, polyline: np.ndarray, start_s: float, speed_mps: float, time_price_usd_h: float) -> np.ndarray:
        """Objective [USD] of each leg of ``polyline`` sailed at constant speed through water
        from ``start_s``.

        The measure of :meth:`segment_costs`, leg after leg: sub-legs no longer than half a
        grid step, each costed by the trapezoid of the rate at its ends with its own course,
        the weather sampled at the time each end is passed (distance / speed through water).
        Infinite where a head current stops the ship or a leg enters an avoided circle.
        """
        p = self.problem
        vertices = np.asarray(polyline, dtype=float)
        legs = np.diff(vertices, axis=0)
        pieces = np.maximum(np.ceil(np.hypot(*legs.T) / (p.resolution_nm * NM / 2.0) - 1e-9).astype(int), 1)
        leg_of = np.repeat(np.arange(len(legs)), pieces)
        fractions = np.concatenate([np.arange(n) / n for n in pieces]) if len(legs) else np.zeros(0)
        points = np.vstack([vertices[leg_of] + fractions[:, None] * legs[leg_of], vertices[-1:]])
        sub = np.diff(points, axis=0)
        length = np.hypot(*sub.T)
        passed_s = start_s + np.concatenate([[0.0], np.cumsum(length)]) / speed_mps
        heading = np.tile(np.arctan2(legs[:, 1], legs[:, 0])[leg_of], 2)
        ends = np.vstack([points[:-1], points[1:]])
        weather = sample_weather(p.metocean, ends[:, 0], ends[:, 1], np.concatenate([passed_s[:-1], passed_s[1:]]))
        rate, along = cost_rate(weather, heading, speed_mps, time_price_usd_h, p.energy)
        count = length.size
        sub_speed = speed_mps + 0.5 * (along[:count] + along[count:])
        hours = np.where(length > 0, length / np.maximum(sub_speed, 1e-3), 0.0) / 3600.0
        cost = np.bincount(leg_of, weights=0.5 * (rate[:count] + rate[count:]) * hours, minlength=len(legs))
        cost[np.bincount(leg_of, weights=(sub_speed <= 1e-3) & (length > 0), minlength=len(legs)) > 0] = np.inf
        for cx, cy, radius in p.avoid:
            cost[segment_clearance(vertices[:-1], vertices[1:], (cx, cy)) < radius] = np.inf
        if p.keep_out is not None and len(vertices) > 1:
            cost[~p.keep_out.legs_clear(vertices[:-1], vertices[1:])] = np.inf
        return cost

    def path_cost(self, polyline: np.ndarray, start_s: float, speed_mps: float, time_price_usd_h: float) -> float:
        """Objective [USD] of sailing ``polyline`` at constant speed through water from
        ``start_s``: the sum of :meth:`leg_costs`."""
        if len(polyline) < 2:
            return 0.0
        return float(np.sum(self.leg_costs(polyline, start_s, speed_mps, time_price_usd_h)))


#: Multiples of the shadow price of time (along the straight route) tried at fixed arrival.
PRICE_MULTIPLES = (0.2, 0.3, 0.45, 0.65, 1.0, 1.4)


def optimal_route(problem: RoutingProblem, *, speed_mps: float | None = None,
                  arrival_s: float | None = None, price_multiples=PRICE_MULTIPLES, time_passes: int = 2,
                  refine: bool = True, speed_profile: bool = False) -> RouteResult:
    """The cheapest route at a constant speed through water.

    Parameters
    ----------
    problem : RoutingProblem
    speed_mps : float, optional
        Fixed speed through water [m/s]: minimise EC (fuel plus running cost).
    arrival_s : float, optional
        Fixed arrival time [s]: minimise the cost over routes and the one constant speed
        through water that arrives then.  Give exactly one of the two.
    price_multiples : sequence of float
        Fixed arrival time: the searches price an hour at these multiples of the shadow
        price of time along the straight route (it is only an estimate of the price along
        the best route); each route found gets its own arrival speed and the cheapest wins.
    time_passes : int
        Time-varying weather: searches per price with node times from the previous one.
    refine : bool
        Move the turning points of the best route sideways while that lowers the cost.
    speed_profile : bool
        Fixed arrival time: speed along the route is a decision too; every candidate
        (the straight route among them) is sailed at its least-fuel speed profile that
        arrives on time (:mod:`rhnc.routing.speed_profile`) instead of one constant speed.

    Returns
    -------
    RouteResult
        Never dearer than :func:`straight_route` with the same argument.
    """
    check_problem(problem, speed_mps, arrival_s)
    search = RouteSearch(problem)
    straight = straight_route(problem, speed_mps=speed_mps, arrival_s=arrival_s)

    def evaluate(polyline):
        speed = speed_mps if speed_mps is not None else speed_for_arrival(problem, polyline, arrival_s)
        return costed_route(problem, polyline, speed, "optimal")

    if speed_mps is not None:
        prices = [problem.energy.running_cost_usd_day / 24.0]
    else:
        base_price = time_price_usd_h(problem, straight)
        prices = [base_price * multiple for multiple in price_multiples]
    best, best_polyline, best_price = straight, None, float("nan")
    candidates = [(shortest_clear_route(problem), float("nan"))]
    for price in prices:
        polyline = search.route(straight.speed_through_water_mps, price, time_passes)
        candidates.append((polyline, price))
        result = evaluate(polyline)
        if result.cost_usd < best.cost_usd:
            best, best_polyline, best_price = result, polyline, price
    if refine and best_polyline is not None and len(best_polyline) > 2:
        best = _refine(problem, best_polyline, best, evaluate)
        candidates.append((_corners(best.waypoints_m), best_price))
    if speed_profile and arrival_s is not None:
        # speed as a decision: each route found (and the straight one) at its least-fuel profile
        for polyline, price in candidates:
            profiled = profiled_route(problem, polyline, arrival_s, "optimal")
            if profiled.cost_usd < best.cost_usd:
                best, best_price = profiled, price
    if best is straight:
        best = dataclasses.replace(straight, method="optimal")
    return dataclasses.replace(best, time_price_usd_h=best_price)


def _corners(points: np.ndarray) -> np.ndarray:
    """The turning points of a densified polyline (its ends and where the course changes)."""
    legs = np.diff(points, axis=0)
    course = np.arctan2(legs[:, 1], legs[:, 0])
    turns = np.flatnonzero(np.abs(np.angle(np.exp(1j * np.diff(course)))) > 1e-6) + 1
    return points[np.concatenate([[0], turns, [len(points) - 1]])]


def _refine(problem: RoutingProblem, polyline: np.ndarray, best: RouteResult, evaluate,
            max_evaluations: int = 200) -> RouteResult:
    """Move each turning point (and a new one midway along each leg) across the route by
    halving steps (4 grid steps down to a quarter) while the cost falls, at most ``max_evaluations`` candidates; points that
    would enter an avoided circle stay."""
    # a turning point between each pair lets a straight leg bend
    polyline = np.vstack([np.column_stack([polyline[:-1], 0.5 * (polyline[:-1] + polyline[1:])]).reshape(-1, 2),
                          polyline[-1]])
    step = 4.0 * problem.resolution_nm * NM
    x_min, x_max, y_min, y_max = data_extent(problem.metocean)
    evaluations = 0
    while step >= 0.25 * problem.resolution_nm * NM and evaluations < max_evaluations:
        improved = False
        for k in range(1, len(polyline) - 1):
            chord = polyline[k + 1] - polyline[k - 1]
            normal = np.array([-chord[1], chord[0]]) / max(np.hypot(*chord), 1e-9)
            for sign in (1.0, -1.0):
                moved = polyline.copy()
                moved[k] = np.clip(polyline[k] + sign * step * normal, (x_min, y_min), (x_max, y_max))
                if any(np.min(segment_clearance(moved[:-1], moved[1:], (cx, cy))) < radius
                       for cx, cy, radius in problem.avoid):
                    continue
                if problem.keep_out is not None and not np.all(problem.keep_out.legs_clear(moved[:-1], moved[1:])):
                    continue
                result = evaluate(moved)
                evaluations += 1
                if result.cost_usd < best.cost_usd:
                    best, polyline, improved = result, moved, True
                    break
        if not improved:
            step /= 2.0
    return best
