"""Receding-horizon route planning with course-dependent energy costs (navigation method "routing").

At each navigation instant the ship needs the next N_L steps of a route to the goal.  This
planner keeps, over a grid of the whole map (the weather-routing graph of
:mod:`rhnc.routing.weather_routing`: 32 headings, edge weight = fuel cost of the edge sailed on
its own course + the price of the hours it takes), the **cost-to-go** of every node: the
cost of the cheapest route from it to the goal, by one Dijkstra search towards the goal.
Every quantity is in US dollars, so a detour is taken exactly when the fuel it saves is
worth more than the hours it adds; calm or uniform weather leaves the route straight (the
shortening of :func:`rhnc.routing.route_search.shortcut_path`), and a breeze moves it only as far
as it pays.  No min-max normalisation is involved.

One planning update:

1. from the start point, every free node within ``2 * reach`` grid steps is a candidate
   first node; the one minimising (cost of the straight segment to it) + (its cost-to-go)
   is taken, and the route follows the search tree from it to the goal (the goal itself
   is a candidate once it is that near, so the last leg runs straight to it);
2. the grid path is straightened where it only staircases (within half a grid step) and
   then shortened wherever a straight segment costs no more than the legs it replaces;
3. **commitment**: the route followed so far, rejoined from the start (straight to its
   next turning point), is kept unless the route just found, or the straight line to the
   goal, is cheaper by more than ``switch_margin`` (0.1 % by default) of the kept route's
   objective.  All are costed alike, as they would be sailed: at a requested arrival time
   each by its fuel at the speed through water that arrives on time along it (the search's
   price of an hour is only an estimate, and a detour it finds can cost more than the
   line).  Two routes round either side of a gale often cost nearly the
   same, and replanned every 4 min from a slightly different start the search alone
   would flip between them, sailing an S round the gale that costs more than either side;
4. the reference points are placed along it at the times k delta, at the planned speed
   through water (speed over ground = that + the current along the route), the first
   interval at the mean of the ship's predicted speed and the planned one; points past
   the goal stay on the goal.

Reuse between updates: for a static field the cost-to-go depends only on the speed and
the price of time, so it is kept until the planned speed moves to another 0.25 kn step
(the tree's successors make each update a walk, not a search).  For a field that changes
in time the weights are evaluated at the time each node would be reached from the start
(distance / speed), and searched again as soon as the last search is done.  Every search
after the first is spread over several updates (:mod:`rhnc.routing.cost_to_go`) so that no update
takes long; the last finished tree is used meanwhile.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np

from rhnc.ship.energy import EnergyParameters, brake_power, fuel_rate_t_h
from orchestrator.geometry import KNOT, NM
from rhnc.routing.cost_to_go import DEFAULT_PIECES, IncrementalCostToGo
from rhnc.routing.route_search import shortcut_path, simplify_polyline
from rhnc.routing.track_cost import constant_speed_times, densify, is_time_varying, sample_weather
from rhnc.routing.weather_routing import RouteSearch, RoutingProblem

log = logging.getLogger(__name__)

#: Planned speeds are rounded to this step [m/s] for the cost-to-go (0.25 kn).
SPEED_STEP_MPS = 0.25 * KNOT

#: Default least saving, as a fraction of the remaining passage's objective, for which the
#: planner leaves the route it follows for a new one (0.1 %).
DEFAULT_SWITCH_MARGIN = 1e-3
#: The point a ship off its route is steered back to lies this many grid steps along the
#: route beyond the ship (2 nm on the 1 nm grid: 7 min at 17 kn; a ship 0.5 nm off turns
#: 14 deg towards the route).
LOOKAHEAD_GRID_STEPS = 2.0


@dataclasses.dataclass(frozen=True)
class RoutePlan:
    """One planning update.

    Attributes
    ----------
    points : ndarray (N_L + 1, 2)
        Reference path points timed delta apart [m]; row 0 is the start.
    route : ndarray (m, 2)
        The whole route from the start to the goal [m] (shortened over the horizon).
    remaining_nm : float
        Length of ``route`` [nm].
    reached_goal : bool
        The reference ends on the goal.
    speed_through_water_mps : float
        Planned speed through water [m/s].
    """

    points: np.ndarray
    route: np.ndarray
    remaining_nm: float
    reached_goal: bool
    speed_through_water_mps: float


def calm_water_time_price_usd_h(speed_mps: float, energy: EnergyParameters) -> float:
    """Shadow price of time at fixed arrival [USD/h]: v dF/dv - F in calm water.

    F is the fuel cost rate [USD/h] at speed through water v: sailing an hour less of a
    fixed passage means sailing faster, at this extra fuel cost per hour saved.
    """
    speeds = speed_mps * np.array([0.99, 1.0, 1.01])
    rates = fuel_rate_t_h(brake_power(speeds, 0.0, 0.0, 0.0, 0.0, energy), energy) * energy.fuel_price_usd_t
    return float(max(speed_mps * (rates[2] - rates[0]) / (0.02 * speed_mps) - rates[1], 0.0))


class RecedingRoutePlanner:
    """Cost-to-go planner over the map; see the module docstring.

    Parameters
    ----------
    metocean : MetOceanField
    goal_m : (north, east) [m]
    energy : EnergyParameters
    resolution_nm : float
        Grid spacing [nm].
    reach : int
        Longest move in grid steps (3: 32 headings).
    """

    def __init__(self, metocean, goal_m: tuple[float, float], energy: EnergyParameters = EnergyParameters(),
                 resolution_nm: float = 1.0, reach: int = 3, switch_margin: float = DEFAULT_SWITCH_MARGIN,
                 search_pieces: int = DEFAULT_PIECES, keep_out=None):
        self.metocean = metocean
        self.goal = np.asarray(goal_m, dtype=float)
        self.energy = energy
        problem = RoutingProblem(start_m=tuple(self.goal), goal_m=tuple(self.goal), metocean=metocean,
                                 energy=energy, resolution_nm=resolution_nm, reach=reach, keep_out=keep_out)
        self.search = RouteSearch(problem)
        self.graph = self.search.graph
        self.resolution_m = resolution_nm * NM
        self.reach = reach
        self.time_varying = is_time_varying(metocean)
        self.switch_margin = float(switch_margin)
        self.incremental = IncrementalCostToGo(self.search, search_pieces)
        self._committed: np.ndarray | None = None
        #: distance along the followed route to the point the ship is steered back to [m]
        self.lookahead_m = LOOKAHEAD_GRID_STEPS * self.resolution_m
        #: updates that left the followed route for a cheaper one / that kept it
        self.switches = 0
        self.kept = 0

    @property
    def searches(self) -> int:
        """Cost-to-go searches finished."""
        return self.incremental.searches

    def cost_to_go(self, time_s: float, start: np.ndarray, speed_mps: float, price_usd_h: float):
        """Every node's cost to the goal (a :class:`rhnc.routing.route_search.ShortestPathTree`).

        Searched at ``speed_mps`` rounded to 0.25 kn.  The first tree is searched at once;
        afterwards a new search (static weather: when the speed step or the price changed;
        weather that changes in time: continuously, with the weather at the time each node
        would be reached from this start) advances by one piece per call
        (:class:`rhnc.routing.cost_to_go.IncrementalCostToGo`) while the last finished tree is used.
        """
        key = (round(speed_mps / SPEED_STEP_MPS), round(price_usd_h, 3))
        speed = key[0] * SPEED_STEP_MPS
        incremental = self.incremental

        def node_times():
            if not self.time_varying:
                return None
            nodes = self.search.nodes
            return time_s + np.hypot(nodes[:, 0] - start[0], nodes[:, 1] - start[1]) / speed

        if incremental.tree is None:
            incremental.begin(key, speed, price_usd_h, node_times())
            incremental.complete()
        elif self.time_varying or key != incremental.key:
            if incremental.pending_key is None or (not self.time_varying and incremental.pending_key != key):
                incremental.begin(key, speed, price_usd_h, node_times())
            incremental.advance()
        return incremental.tree

    def route(self, time_s: float, start_m, speed_mps: float, price_usd_h: float,
              horizon_m: float, arrival_speed=None) -> np.ndarray:
        """The route from ``start_m`` to the goal (``horizon_m`` is not used: the whole route
        is shortened).

        Candidates: the route of the cost-to-go and the straight line to the goal.  The route
        the ship follows is kept (rejoined from the start) unless the cheaper candidate costs
        less by more than ``switch_margin`` of the kept route's objective, all costed alike
        by :meth:`RouteSearch.path_cost`: at ``speed_mps`` and
        ``price_usd_h``, or, given ``arrival_speed`` (route -> speed through water [m/s]
        that arrives on time along it), each at its own arrival speed, by its fuel alone
        (the hours are the same)."""
        start = np.asarray(start_m, dtype=float)
        fresh = self.tree_route(time_s, start, speed_mps, price_usd_h)
        if len(fresh) == 2 and self._committed is None:
            self._committed = fresh
            return fresh

        def objective(candidate):
            if arrival_speed is None:
                return self.search.path_cost(candidate, time_s, speed_mps, price_usd_h)
            return self.search.path_cost(candidate, time_s, arrival_speed(candidate), 0.0)

        # the straight line to the goal is always a candidate: the search's price of time is
        # an estimate, and a detour it finds may cost more than the line when sailed
        candidates = [fresh] if len(fresh) == 2 else [fresh, np.vstack([start, self.goal])]
        costs = [objective(candidate) for candidate in candidates]
        best = int(np.argmin(costs))
        route = candidates[best]
        kept = None if self._committed is None else self.rejoin(self._committed, start)
        if kept is not None:
            kept_usd = objective(kept)
            if costs[best] >= (1.0 - self.switch_margin) * kept_usd:
                self.kept += 1
                return kept                 # the followed route keeps its geometry
            self.switches += 1
            log.debug("t = %.0f s: new route, %.1f USD below the followed one (%.1f USD)",
                      time_s, kept_usd - costs[best], kept_usd)
        self._committed = route
        return route

    def follow(self, route: np.ndarray) -> None:
        """Take ``route`` (start to goal, (n, 2) [m]) as the route followed, e.g. a passage
        planned before departure; the updates keep it as long as nothing is found cheaper."""
        self._committed = np.asarray(route, dtype=float).copy()

    def rejoin(self, route: np.ndarray, start: np.ndarray) -> np.ndarray | None:
        """``route`` continued from ``start``: straight to the point of the route
        ``lookahead_m`` beyond the start's projection on it, then along the route; None when
        the route has fewer than two points.

        The route keeps its geometry from update to update, so a ship set off it (a gale's
        yaw moment holds the NMPC's heading off its reference) is steered back to it,
        line-of-sight fashion, instead of being re-aimed from wherever it drifted to: aiming
        anew at a turning point 50 nm ahead at every update, a ship set 17 deg off its course
        sailed a curve 1 nm longer than the route."""
        if len(route) < 2:
            return None
        a, b = route[:-1], route[1:]
        ab = b - a
        length = np.hypot(*ab.T)
        t = np.clip(np.sum((start - a) * ab, axis=1) / np.maximum(length ** 2, 1e-12), 0.0, 1.0)
        distance = np.hypot(*(start - (a + t[:, None] * ab)).T)
        leg = int(np.argmin(distance))
        along = np.concatenate([[0.0], np.cumsum(length)])
        aim_along = along[leg] + t[leg] * length[leg] + self.lookahead_m
        if aim_along >= along[-1] or np.hypot(*(route[-1] - start)) <= self.lookahead_m:
            return np.vstack([start, route[-1]])
        beyond = int(np.searchsorted(along, aim_along, side="right"))   # first vertex past the aim
        aim = np.array([np.interp(aim_along, along, route[:, 0]), np.interp(aim_along, along, route[:, 1])])
        return np.vstack([start, aim, route[beyond:]])

    def tree_route(self, time_s: float, start: np.ndarray, speed_mps: float, price_usd_h: float) -> np.ndarray:
        """The cheapest route from ``start`` by the cost-to-go: the grid path straightened
        where it only staircases, then shortened wherever a straight segment costs no more."""
        if np.hypot(*(self.goal - start)) < 1.0:
            return np.vstack([start, self.goal])
        tree = self.cost_to_go(time_s, start, speed_mps, price_usd_h)
        nodes = self.search.nodes
        radius = 2 * self.reach * self.resolution_m
        near = np.flatnonzero((np.hypot(nodes[:, 0] - start[0], nodes[:, 1] - start[1]) <= radius)
                              & self.graph.free & np.isfinite(tree.cost) & (tree.cost < 1e29))
        candidates = np.vstack([nodes[near], self.goal])
        to_go = np.concatenate([tree.cost[near], [0.0 if np.hypot(*(self.goal - start)) <= radius else np.inf]])
        first = self.search.segment_costs(start, candidates, time_s, speed_mps, price_usd_h)
        best = int(np.argmin(first + to_go))
        if not np.isfinite(first[best] + to_go[best]):
            log.warning("no route from (%.0f, %.0f) m to the goal on the grid: heading straight for it", *start)
            return np.vstack([start, self.goal])
        if best == len(near):
            return np.vstack([start, self.goal])
        chain = [int(near[best])]
        while chain[-1] != tree.source:
            chain.append(int(tree.predecessor[chain[-1]]))
        # the grid's staircase straightened (within half a grid step), then the path
        # shortened wherever a straight segment costs no more than the legs it replaces
        vertices = simplify_polyline(np.vstack([start, nodes[chain], self.goal]), 0.5 * self.resolution_m)
        keep = np.concatenate([[True], np.hypot(*np.diff(vertices, axis=0).T) > 1e-6])
        vertices = vertices[keep]
        if len(vertices) >= 3:
            legs = self.search.leg_costs(vertices, time_s, speed_mps, price_usd_h)
            passed_s = time_s + np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(vertices, axis=0).T))]) / speed_mps
            kept = shortcut_path(len(vertices), lambda i, js: self.search.segment_costs(
                vertices[i], vertices[js], passed_s[i], speed_mps, price_usd_h), consecutive_costs=legs)
            vertices = vertices[kept]
        return vertices

    def plan(self, time_s: float, start_m, start_speed_mps: float, speed_mps: float, price_usd_h: float,
             delta_s: float, horizon_steps: int) -> RoutePlan:
        """Reference points for the next ``horizon_steps`` intervals of ``delta_s``.

        Parameters
        ----------
        time_s : float
            Time of the start [s].
        start_m : (north, east) [m]
        start_speed_mps : float
            The ship's (predicted) speed at the start [m/s].
        speed_mps : float
            Planned speed through water [m/s].
        price_usd_h : float
            Price of an hour at sea in the route's objective [USD/h].
        delta_s : float
            Interval between reference points [s].
        horizon_steps : int
            N_L.
        """
        route = self.route(time_s, start_m, speed_mps, price_usd_h, self.horizon_m(speed_mps, delta_s, horizon_steps))
        return self.timed_plan(route, time_s, start_speed_mps, speed_mps, delta_s, horizon_steps)

    @staticmethod
    def horizon_m(speed_mps: float, delta_s: float, horizon_steps: int) -> float:
        """Length of route the reference may need [m] (with 20 % for a following current)."""
        return speed_mps * delta_s * horizon_steps * 1.2

    def timed_plan(self, route: np.ndarray, time_s: float, start_speed_mps: float, speed_mps: float,
                   delta_s: float, horizon_steps: int) -> RoutePlan:
        """Reference points along ``route`` (from :meth:`route`) at ``speed_mps`` through water."""
        horizon_m = self.horizon_m(speed_mps, delta_s, horizon_steps)
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(route, axis=0).T))])
        head = min(int(np.searchsorted(along, horizon_m)) + 1, len(route))
        dense = densify(route[:head], min(self.resolution_m / 2.0, speed_mps * delta_s / 2.0))
        times = constant_speed_times(self.metocean, dense, speed_mps, time_s)
        ramp_s = 0.5 * delta_s * (speed_mps - min(max(start_speed_mps, 0.0), speed_mps)) / speed_mps
        wanted = time_s + delta_s * np.arange(horizon_steps + 1) - np.where(np.arange(horizon_steps + 1) > 0,
                                                                             ramp_s, 0.0)
        points = np.column_stack([np.interp(wanted, times, dense[:, 0]), np.interp(wanted, times, dense[:, 1])])
        reached = bool(head == len(route) and wanted[-1] >= times[-1])
        return RoutePlan(points=points, route=route, remaining_nm=float(along[-1]) / NM, reached_goal=reached,
                         speed_through_water_mps=float(speed_mps))

    def profiled_plan(self, route: np.ndarray, time_s: float, start_speed_mps: float, arrival_s: float,
                      delta_s: float, horizon_steps: int, bounds_mps: tuple[float, float]) -> RoutePlan:
        """Reference points along ``route`` timed by the least-fuel speed profile that arrives
        at ``arrival_s`` (:func:`rhnc.routing.speed_profile.profile_times`): speed along the
        route decided with it, easing where the weather makes speed dear and making the time
        up where it is cheap or a current helps.  The plan's speed through water is that of
        its first interval."""
        from rhnc.routing.speed_profile import profile_times

        dense = densify(route, self.resolution_m / 2.0)
        times = profile_times(self.metocean, self.energy, dense, time_s, arrival_s, bounds_mps)
        first = min(delta_s, times[-1] - time_s)
        reach = np.interp(time_s + first, times, np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(dense, axis=0).T))]))
        start = np.array([np.interp(time_s + first, times, dense[:, 0]), np.interp(time_s + first, times, dense[:, 1])])
        along = self.mean_current_along_mps(np.vstack([dense[0], start]), time_s) if reach > 1.0 else 0.0
        speed_mps = float(min(max(reach / max(first, 1e-9) - along, bounds_mps[0]), bounds_mps[1]))
        ramp_s = 0.5 * delta_s * (speed_mps - min(max(start_speed_mps, 0.0), speed_mps)) / max(speed_mps, 1e-9)
        wanted = time_s + delta_s * np.arange(horizon_steps + 1) - np.where(np.arange(horizon_steps + 1) > 0,
                                                                             ramp_s, 0.0)
        points = np.column_stack([np.interp(wanted, times, dense[:, 0]), np.interp(wanted, times, dense[:, 1])])
        total = float(np.sum(np.hypot(*np.diff(route, axis=0).T)))
        return RoutePlan(points=points, route=route, remaining_nm=total / NM, reached_goal=bool(wanted[-1] >= times[-1]),
                         speed_through_water_mps=speed_mps)

    def time_price_usd_h(self, route: np.ndarray, speed_mps: float, time_s: float) -> float:
        """Shadow price of time at fixed arrival [USD/h] along ``route``: v dF/dv - F,
        F the fuel cost rate with each leg's course and weather, averaged over the legs'
        lengths, rounded to 50 USD/h (so the cost-to-go is kept while it holds)."""
        if len(route) < 2:
            return calm_water_time_price_usd_h(speed_mps, self.energy)
        points = densify(route, 2.0 * self.resolution_m)
        legs = np.diff(points, axis=0)
        length = np.hypot(*legs.T)
        heading = np.arctan2(legs[:, 1], legs[:, 0])
        weather = sample_weather(self.metocean, points[:-1, 0], points[:-1, 1],
                                 time_s + np.concatenate([[0.0], np.cumsum(length[:-1])]) / speed_mps)
        speeds = speed_mps * np.array([0.99, 1.0, 1.01])[:, None]
        rates = fuel_rate_t_h(brake_power(speeds, heading, weather["wind_north"], weather["wind_east"],
                                          weather["hs"], self.energy), self.energy) * self.energy.fuel_price_usd_t
        price = speed_mps * (rates[2] - rates[0]) / (0.02 * speed_mps) - rates[1]
        price = float(np.sum(price * length) / max(np.sum(length), 1e-9))
        return max(round(price / 50.0) * 50.0, 0.0)

    def mean_current_along_mps(self, route: np.ndarray, time_s: float) -> float:
        """Current component along ``route`` [m/s], averaged over its length.

        Sampled every half grid step along the legs: taken at the turning points alone, a
        straight leg from inside a current jet to the goal was credited with the jet's
        current all the way, looked cheaper than staying in the jet, and the ship left
        the jet's core early."""
        if len(route) < 2:
            return 0.0
        route = densify(np.asarray(route, dtype=float), 0.5 * self.resolution_m)
        legs = np.diff(route, axis=0)
        length = np.hypot(*legs.T)
        weather = sample_weather(self.metocean, route[:-1, 0], route[:-1, 1], time_s)
        along = (weather["current_north"] * legs[:, 0] + weather["current_east"] * legs[:, 1]) / np.maximum(length, 1e-9)
        return float(np.sum(along * length) / max(np.sum(length), 1e-9))
