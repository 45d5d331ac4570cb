"""The navigation's routing method: at each instant the cheapest route and the speed through water to sail it.

Used by :class:`rhnc.navigation.navigation_participant.NavigationParticipant` with ``method =
"routing"``.  The route comes from the receding route planner (:mod:`rhnc.navigation.route_navigation`);
this module decides the speed and the price of an hour it is searched with: ``speed_kn``
and the running cost, or, with an arrival time, the remaining route over the remaining
time (less the current along it) and the shadow price of time, calibrated once on the
whole passage (:func:`rhnc.routing.weather_routing.optimal_route`).
"""

from __future__ import annotations

import logging

import numpy as np

from orchestrator.geometry import KNOT
from rhnc.ship.energy import EnergyParameters
from rhnc.navigation.route_navigation import (DEFAULT_SWITCH_MARGIN, SPEED_STEP_MPS, RecedingRoutePlanner, RoutePlan,
                                   calm_water_time_price_usd_h)
from rhnc.routing.routing_problem import plane_point
from rhnc.routing.weather_routing import PRICE_MULTIPLES, RoutingProblem, optimal_route, straight_route, time_price_usd_h

log = logging.getLogger(__name__)

#: Lowest planned speed through water of the routing method [m/s] (2 kn).
MIN_PLANNED_SPEED_MPS = 2.0 * KNOT


class RoutingMethod:
    """Route and speed of one navigation participant, instant after instant.

    Parameters
    ----------
    name : str
        The participant's name (for its messages).
    metocean : MetOceanField
    goal : (north, east) [m]
    energy : EnergyParameters
    resolution_nm : float
        Spacing of the route search's grid [nm].
    delta : float
        Navigation step [s]: the reference points are ``delta`` apart.
    horizon_steps : int
        N_L, reference points after the start.
    speed : float
        ``speed_kn`` [m/s]: the speed through water without an arrival time, and the first guess.
    arrival_s : float or None
        Requested arrival time [s].
    max_speed : float
        Upper bound of the planned speed [m/s].
    switch_margin : float
        Least saving, as a fraction, for which the followed route is left for a new one.
    keep_out : Chart, optional
        Land and no-go areas: every route planned keeps their clearance (:mod:`rhnc.chart.chart`).
    """

    def __init__(self, name: str, metocean, goal: tuple[float, float], energy: EnergyParameters,
                 resolution_nm: float, delta: float, horizon_steps: int, speed: float,
                 arrival_s: float | None, max_speed: float, switch_margin: float = DEFAULT_SWITCH_MARGIN,
                 keep_out=None) -> None:
        self.name = name
        self.metocean = metocean
        self.goal = goal
        self.energy = energy
        self.resolution_nm = resolution_nm
        self.delta = delta
        self.horizon_steps = horizon_steps
        self.speed = speed
        self.arrival_s = arrival_s
        self.max_speed = max_speed
        self.keep_out = keep_out
        self.planner = RecedingRoutePlanner(metocean, goal, energy, resolution_nm, switch_margin=switch_margin,
                                            keep_out=keep_out)
        self._route: np.ndarray | None = None
        self._price_scale: float | None = None
        self._planned_speed = speed

    def planned_speed(self, time: float, route: np.ndarray) -> float:
        """Speed through water [m/s] for this instant: ``speed_kn``, or the length of
        ``route`` (start to goal) over the remaining time less the current along it, within
        the bounds."""
        if self.arrival_s is None:
            return self.speed
        remaining_m = float(np.sum(np.hypot(*np.diff(route, axis=0).T)))
        remaining_s = self.arrival_s - time
        if remaining_s <= 0.0:
            return self.max_speed
        wanted = remaining_m / remaining_s - self.planner.mean_current_along_mps(route, time)
        return float(min(max(wanted, MIN_PLANNED_SPEED_MPS), self.max_speed))

    def _calibrate_time_price(self, time: float, point: np.ndarray) -> float:
        """Price of an hour at fixed arrival, as a multiple of the calm-water shadow price.

        The shadow price along a route (v dF/dv - F) only estimates what an hour is worth
        on the best route, so once, at the first plan, the whole passage is routed at the
        requested arrival time (:func:`rhnc.routing.weather_routing.optimal_route`, which tries
        several prices) and the price that found the best route is kept, scaled with the
        calm-water price as the planned speed changes.  When the straight route wins, the
        highest price tried is kept (it keeps the route straightest).  The route found (its
        turning points moved sideways while that pays) is the passage plan the planner
        starts out following (:meth:`RecedingRoutePlanner.follow`)."""
        problem = RoutingProblem(plane_point(point), plane_point(self.goal), self.metocean, self.energy,
                                 resolution_nm=self.resolution_nm, departure_s=time, keep_out=self.keep_out)
        try:
            best = optimal_route(problem, arrival_s=self.arrival_s)
        except ValueError as exc:
            log.warning("participant '%s': no route arrives at %.0f s (%s); pricing hours by the "
                        "calm-water shadow price", self.name, self.arrival_s, exc)
            return 1.0
        self.planner.follow(best.waypoints_m)
        price = best.time_price_usd_h
        if not np.isfinite(price):
            price = max(PRICE_MULTIPLES) * time_price_usd_h(problem, straight_route(problem, arrival_s=self.arrival_s))
        return price / max(calm_water_time_price_usd_h(best.speed_through_water_mps, self.energy), 1e-9)

    def plan(self, time: float, start: tuple[float, float, float, float]) -> RoutePlan:
        """The route from the planning ``start`` (x, y, psi, u) and the reference points along it.

        The route is searched at the previous instant's speed and price (the route hardly
        depends on them), then the speed is planned for the route found."""
        start_x, start_y, start_psi, start_u = start
        x_min, x_max, y_min, y_max = self.metocean.extent
        point = np.array([min(max(start_x, x_min), x_max), min(max(start_y, y_min), y_max)])
        planner = self.planner
        if self._route is None:
            self._planned_speed = self.planned_speed(time, np.vstack([point, self.goal]))
        if self.arrival_s is None:
            price = self.energy.running_cost_usd_day / 24.0
        else:  # hours are fixed: each costs the fuel of the speed-up that saves it
            if self._price_scale is None:
                self._price_scale = self._calibrate_time_price(time, point)
            price = self._price_scale * calm_water_time_price_usd_h(
                round(self._planned_speed / SPEED_STEP_MPS) * SPEED_STEP_MPS, self.energy)
        route = planner.route(time, point, self._planned_speed, price,
                              planner.horizon_m(max(self._planned_speed, self.max_speed), self.delta,
                                                self.horizon_steps),
                              arrival_speed=None if self.arrival_s is None else (
                                  lambda candidate: self.planned_speed(time, candidate)))
        speed = self.planned_speed(time, route)
        plan = None
        if self.arrival_s is not None and self.arrival_s - time > self.delta:
            try:   # speed along the route decided with it: the least-fuel profile that arrives on time
                plan = planner.profiled_plan(route, time, start_u, self.arrival_s, self.delta, self.horizon_steps,
                                             (MIN_PLANNED_SPEED_MPS, self.max_speed))
            except ValueError as exc:   # no profile within the bounds arrives then: as fast as allowed
                log.debug("participant '%s': no speed profile (%s)", self.name, exc)
        if plan is None:
            plan = planner.timed_plan(route, time, start_u, speed, self.delta, self.horizon_steps)
        self._route = plan.route
        self._planned_speed = speed
        return plan
