"""A passage to route and what a route costs: the problem, the timed and costed result, the straight route.

What :mod:`rhnc.routing.weather_routing` optimises and what it measures its candidates with: a
:class:`RoutingProblem` (start, goal, weather, energy model, search resolution, avoided
circles), a polyline timed at a constant speed through water and costed by the energy
model (:func:`costed_route`, :func:`rhnc.routing.track_cost.cost_of_track`), the speed that
arrives at a given time (:func:`speed_for_arrival`), the straight (or shortest
obstacle-free) route every optimum is held against, and the shadow price of time along a
route (:func:`time_price_usd_h`).
"""

from __future__ import annotations

import dataclasses
from typing import Protocol

import numpy as np

from orchestrator.geometry import NM
from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from rhnc.weather.metocean import MetOceanField
from rhnc.weather.metocean_grid import axis_node_count, data_extent
from rhnc.routing.offline_route import shortest_route
from rhnc.routing.track_cost import constant_speed_times, cost_of_track, densify, is_time_varying, sample_weather

#: Bracket of the speed through water solved for a fixed arrival time [m/s].
SPEED_BRACKET_MPS = (0.5, 30.0)
#: How late [s] a ship a head current stops counts as, in the search for the speed that arrives
#: (late past any arrival: the search then looks above that speed).
NEVER_S = 1e12


class KeepOut(Protocol):
    """What the routing asks of areas to keep clear of (a :class:`rhnc.chart.chart.Chart` answers)."""

    clearance_m: float

    def distances_m(self, north_m, east_m) -> np.ndarray:
        """Distance [m] of points to the nearest area."""
        ...

    def legs_clear(self, a, b, distance_a=None, distance_b=None) -> np.ndarray:
        """Whether each straight leg a-b keeps the clearance along its whole length."""
        ...


@dataclasses.dataclass(frozen=True)
class RoutingProblem:
    """A passage to route.

    Attributes
    ----------
    start_m, goal_m : (north, east) [m]
    metocean : MetOceanField
        Weather and current over the map; the search grid spans the extent of its data
        (not a band of held edge values around it).
    energy : EnergyParameters
    resolution_nm : float
        Spacing of the search grid [nm].
    avoid : tuple of (north_m, east_m, radius_m)
        Circles the route must not enter.
    departure_s : float
        Time of departure [s] (the clock of a time-varying field).
    reach : int
        Longest move of the search grid in grid steps (3: 32 headings).
    keep_out : KeepOut, optional
        Land and no-go areas with their clearance (a :class:`rhnc.chart.chart.Chart`): no
        route comes within ``keep_out.clearance_m`` of them along any leg.
    """

    start_m: tuple[float, float]
    goal_m: tuple[float, float]
    metocean: MetOceanField
    energy: EnergyParameters = EnergyParameters()
    resolution_nm: float = 0.5
    avoid: tuple[tuple[float, float, float], ...] = ()
    departure_s: float = 0.0
    reach: int = 3
    keep_out: KeepOut | None = None


def plane_point(point) -> tuple[float, float]:
    """``point`` (north, east) [m], any pair of numbers, as the pair of floats a
    :class:`RoutingProblem` holds."""
    return float(point[0]), float(point[1])


@dataclasses.dataclass(frozen=True)
class RouteResult:
    """A timed route and what it costs.

    Attributes
    ----------
    waypoints_m : ndarray (n, 2)
        North, east [m]; no leg is longer than ``resolution_nm / 2``.
    times_s : ndarray (n,)
        Absolute times at the waypoints [s].
    speed_through_water_mps : float
        The constant speed through water [m/s].
    duration_s, distance_nm, cost_usd, co2_t, fuel_t : float
        From :func:`rhnc.routing.track_cost.cost_of_track`.
    method : str
        ``"optimal"`` or ``"straight"``.
    time_price_usd_h : float
        The price of an hour [USD/h] with which the search found this route (NaN for the
        straight route).
    """

    waypoints_m: np.ndarray
    times_s: np.ndarray
    speed_through_water_mps: float
    duration_s: float
    distance_nm: float
    cost_usd: float
    co2_t: float
    fuel_t: float
    method: str = "optimal"
    time_price_usd_h: float = float("nan")

    @property
    def arrival_s(self) -> float:
        return float(self.times_s[-1])


def check_problem(problem: RoutingProblem, speed_mps, arrival_s) -> None:
    """Refuse a problem that cannot be routed (one line naming the value), before any grid is built."""
    if (speed_mps is None) == (arrival_s is None):
        raise ValueError("give exactly one of speed_mps and arrival_s")
    if speed_mps is not None and not speed_mps > 0:
        raise ValueError(f"speed_mps must be positive, got {speed_mps!r}")
    if arrival_s is not None and not arrival_s > problem.departure_s:
        raise ValueError(f"arrival_s {arrival_s!r} must be after the departure {problem.departure_s!r} s")
    if not problem.resolution_nm > 0:
        raise ValueError(f"resolution_nm must be positive, got {problem.resolution_nm!r}")
    x_min, x_max, y_min, y_max = data_extent(problem.metocean)
    for span in (x_max - x_min, y_max - y_min):  # the search grid, refused before it is built
        axis_node_count(span, problem.resolution_nm * NM, "the route search's resolution_nm")
    for name, point in (("start", problem.start_m), ("goal", problem.goal_m)):
        if not bool(problem.metocean.contains(point[0], point[1])):
            raise ValueError(f"the {name} ({point[0]:.0f}, {point[1]:.0f}) m lies outside the met-ocean map")
        for k, (cx, cy, radius) in enumerate(problem.avoid):
            if np.hypot(point[0] - cx, point[1] - cy) < radius:
                raise ValueError(f"the {name} lies inside avoided circle {k}")
        check_navigable(problem.keep_out, point, name)


def check_navigable(keep_out, point, name: str) -> None:
    """Refuse a point on land or within the declared clearance of an area (one line, naming it)."""
    if keep_out is None:
        return
    distance = float(keep_out.distances_m([point[0]], [point[1]])[0])
    if distance < keep_out.clearance_m:
        where = "on land or in a no-go area" if distance <= 0.0 else (
            f"{distance / NM:.2f} nm from land or a no-go area, inside the clearance of {keep_out.clearance_m / NM:.2f} nm")
        raise ValueError(f"the {name} ({point[0]:.0f}, {point[1]:.0f}) m lies {where}")


def costed_route(problem: RoutingProblem, polyline: np.ndarray, speed_mps: float, method: str) -> RouteResult:
    """``polyline`` densified, timed at ``speed_mps`` through water from the departure, and costed."""
    points = densify(polyline, problem.resolution_nm * NM / 2.0)
    times = constant_speed_times(problem.metocean, points, speed_mps, problem.departure_s)
    account = cost_of_track(problem.metocean, problem.energy, points, times)
    return RouteResult(waypoints_m=points, times_s=times, speed_through_water_mps=float(speed_mps),
                       duration_s=account["duration_s"], distance_nm=account["distance_nm"],
                       cost_usd=account["cost_usd"], co2_t=account["co2_t"], fuel_t=account["fuel_t"],
                       method=method)


def profiled_route(problem: RoutingProblem, polyline: np.ndarray, arrival_s: float, method: str) -> RouteResult:
    """``polyline`` densified, timed by the least-fuel speed profile that arrives at ``arrival_s``
    (:func:`rhnc.routing.speed_profile.profile_times`) and costed; its speed through water
    is the passage's mean."""
    from rhnc.routing.speed_profile import profile_times

    points = densify(polyline, problem.resolution_nm * NM / 2.0)
    times = profile_times(problem.metocean, problem.energy, points, problem.departure_s, arrival_s)
    account = cost_of_track(problem.metocean, problem.energy, points, times)
    return RouteResult(waypoints_m=points, times_s=times,
                       speed_through_water_mps=account["mean_speed_through_water_kn"] * 1852.0 / 3600.0,
                       duration_s=account["duration_s"], distance_nm=account["distance_nm"],
                       cost_usd=account["cost_usd"], co2_t=account["co2_t"], fuel_t=account["fuel_t"],
                       method=method)


def speed_for_arrival(problem: RoutingProblem, polyline: np.ndarray, arrival_s: float) -> float:
    """Constant speed through water [m/s] that sails ``polyline`` to arrive at ``arrival_s``."""
    points = densify(polyline, problem.resolution_nm * NM / 2.0)
    if is_time_varying(problem.metocean):
        def late_s(speed):
            return constant_speed_times(problem.metocean, points, speed, problem.departure_s)[-1] - arrival_s
    else:  # the current along each leg does not depend on the time: sample it once
        legs = np.diff(points, axis=0)
        length = np.hypot(*legs.T)
        course = np.arctan2(legs[:, 1], legs[:, 0])
        weather = problem.metocean.sample(points[:, 0], points[:, 1])
        along = np.cos(course) * weather["current_north"][:-1] + np.sin(course) * weather["current_east"][:-1]
        along = 0.5 * (along + np.cos(course) * weather["current_north"][1:]
                       + np.sin(course) * weather["current_east"][1:])
        moving = length > 0

        def late_s(speed):
            return problem.departure_s + float(np.sum(length[moving] / np.maximum(
                speed + along[moving], 1e-3))) - arrival_s

    def late_or_never_s(speed):  # a head current that stops the ship makes it later than any arrival
        try:
            return late_s(speed)
        except ValueError:
            return NEVER_S

    low, high = SPEED_BRACKET_MPS
    if late_or_never_s(high) > 0:
        raise ValueError(f"arrival at {arrival_s:.0f} s needs more than {high:.0f} m/s through water")
    if late_or_never_s(low) < 0:
        raise ValueError(f"arrival at {arrival_s:.0f} s needs less than {low:.1f} m/s through water")
    from scipy.optimize import brentq  # here: importing scipy.optimize takes 0.1 s, most runs never get here

    return float(brentq(late_or_never_s, low, high, xtol=1e-6, rtol=1e-10))


def straight_route(problem: RoutingProblem, *, speed_mps: float | None = None,
                   arrival_s: float | None = None) -> RouteResult:
    """The shortest obstacle-free route (the straight line without obstacles) at a constant
    speed through water: ``speed_mps``, or the speed that arrives at ``arrival_s``."""
    check_problem(problem, speed_mps, arrival_s)
    polyline = shortest_clear_route(problem)
    if arrival_s is not None:
        speed_mps = speed_for_arrival(problem, polyline, arrival_s)
    assert speed_mps is not None  # check_problem asks for exactly one of the two
    return costed_route(problem, polyline, speed_mps, "straight")


def time_price_usd_h(problem: RoutingProblem, route: RouteResult) -> float:
    """Shadow price of time at fixed arrival [USD/h]: v dF/dv - F averaged along ``route``
    (F the fuel cost rate at the route's courses and weather, v its speed through water)."""
    points = route.waypoints_m
    legs = np.diff(points, axis=0)
    heading = np.arctan2(legs[:, 1], legs[:, 0])
    weather = sample_weather(problem.metocean, points[:-1, 0], points[:-1, 1], route.times_s[:-1])
    v = route.speed_through_water_mps
    rates = [fuel_rate_t_h(brake_power(speed, heading, weather["wind_north"], weather["wind_east"], weather["hs"],
                                       problem.energy), problem.energy) * problem.energy.fuel_price_usd_t
             for speed in (v * 0.99, v, v * 1.01)]
    derivative = (rates[2] - rates[0]) / (0.02 * v)
    return float(max(np.mean(v * derivative - rates[1]), 0.0))


def shortest_clear_route(problem: RoutingProblem) -> np.ndarray:
    """The shortest route from start to goal that keeps clear of the avoided circles and of
    ``keep_out``: the straight line (or its way round the circles) where it is clear and
    turns only over the weather's data (not over a band of held edge values around it),
    else the shortest path on the search grid over the data, shortened wherever a straight
    leg stays clear."""
    from rhnc.routing.clear_route import grid_clear_path

    polyline = shortest_route(problem.start_m, problem.goal_m, problem.avoid)
    keep_out = problem.keep_out
    x_min, x_max, y_min, y_max = extent = data_extent(problem.metocean)
    turns = polyline[1:-1]
    on_data = bool(np.all((turns[:, 0] >= x_min - 1e-6) & (turns[:, 0] <= x_max + 1e-6)
                          & (turns[:, 1] >= y_min - 1e-6) & (turns[:, 1] <= y_max + 1e-6)))
    if on_data and (keep_out is None or np.all(keep_out.legs_clear(polyline[:-1], polyline[1:]))):
        return polyline
    return grid_clear_path(keep_out, problem.start_m, problem.goal_m, extent,
                           problem.resolution_nm, problem.reach, problem.avoid)
