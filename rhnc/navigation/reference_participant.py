"""Reference trajectory for scenarios without navigation: a line, a constant-radius turn or waypoints.

Output ``reference`` is an (N+1, 7) array (t [s], x [m], y [m], psi [rad], u [m/s],
v [m/s], r [rad/s]) on the instants ``t, t + delta, ..., t + N delta`` of the current step,
from a "virtual ship" that left ``start_nm`` at the simulation's start time and sails the
path at constant speed (the paper's Eq. 19 states: v_d = 0, psi_d the path's course,
r_d its turn rate).

A virtual ship on a timed schedule runs away from a ship that cannot keep up with it (a
gale on the bow): the reference then lies miles ahead, and at the destination it stops
there (u_d = 0) while the ship is still miles short, and the NMPC, whose speed error costs
more than its position error, stops the ship short of it.  With ``max_lead_nm`` (waypoint
paths, inputs ``x`` and ``y`` connected) the virtual ship keeps its speed but waits for the
ship: it is never farther along the path than the ship's own progress (its nearest point on
the path, never going back) plus the lead.  A lead under the goal's arrival radius brings
the ship into it whenever the virtual ship arrives.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from orchestrator.errors import ModelError, ScenarioError
from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext, Participant, Value, is_finite_number, reject_unknown_options
from rhnc.chart.positions import projected_options, refuse_route_inside_clearance



def line_or_turn_reference(
    elapsed_s: np.ndarray, start_m: Sequence[float], course_rad: float, speed_mps: float, turn_radius_m: float | None = None
) -> np.ndarray:
    """Reference states (len, 6) of a straight line or a constant-radius turn.

    Parameters
    ----------
    elapsed_s : numpy.ndarray
        Times since the virtual ship left ``start_m`` [s].
    start_m : sequence of float
        Start position (x north, y east) [m].
    course_rad : float
        Initial course [rad], clockwise from north.
    speed_mps : float
        Speed along the path [m/s].
    turn_radius_m : float, optional
        Radius of a constant turn [m]: > 0 to starboard, < 0 to port; None or 0 for a line.
    """
    t = np.asarray(elapsed_s, dtype=float)
    x0, y0 = float(start_m[0]), float(start_m[1])
    if not turn_radius_m:
        psi = np.full_like(t, course_rad)
        x = x0 + speed_mps * t * math.cos(course_rad)
        y = y0 + speed_mps * t * math.sin(course_rad)
        r = np.zeros_like(t)
    else:
        rate = speed_mps / turn_radius_m  # rad/s, > 0 turning clockwise (starboard)
        psi = course_rad + rate * t
        # integral of (cos psi, sin psi) * U dt
        x = x0 + turn_radius_m * (np.sin(psi) - math.sin(course_rad))
        y = y0 - turn_radius_m * (np.cos(psi) - math.cos(course_rad))
        r = np.full_like(t, rate)
    return np.column_stack([x, y, psi, np.full_like(t, speed_mps), np.zeros_like(t), r])


def waypoint_reference(elapsed_s: np.ndarray, waypoints_m: np.ndarray, speed_mps: float) -> np.ndarray:
    """Reference states (len, 6) sailing the polyline ``waypoints_m`` (k, 2) [m] at ``speed_mps``.

    Legs are straight with the heading of the leg (r_d = 0, corners are sharp).  The last
    waypoint is the destination: the virtual ship arrives there and stops (u_d = 0,
    heading of the last leg), so the tracked ship stops at the goal instead of sailing on.
    """
    points = np.asarray(waypoints_m, dtype=float)
    legs = np.diff(points, axis=0)
    lengths = np.hypot(legs[:, 0], legs[:, 1])
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    s = np.clip(np.asarray(elapsed_s, dtype=float) * speed_mps, 0.0, cumulative[-1])
    leg = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(legs) - 1)
    along = s - cumulative[leg]
    direction = legs[leg] / lengths[leg, None]
    position = points[leg] + direction * along[:, None]
    psi = np.arctan2(direction[:, 1], direction[:, 0])
    zeros = np.zeros_like(s)
    speed = np.where(s < cumulative[-1], speed_mps, 0.0)
    return np.column_stack([position, psi, speed, zeros, zeros])


def path_progress_m(position_m: np.ndarray, waypoints_m: np.ndarray, at_least_m: float = 0.0) -> float:
    """Arc length [m] along the polyline ``waypoints_m`` of its nearest point to ``position_m``,
    among the legs that end past ``at_least_m`` (progress never goes back), at least ``at_least_m``."""
    points = np.asarray(waypoints_m, dtype=float)
    a, legs = points[:-1], np.diff(points, axis=0)
    lengths = np.hypot(legs[:, 0], legs[:, 1])
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    share = np.clip(np.einsum("ij,ij->i", np.asarray(position_m, dtype=float)[:2] - a, legs) / lengths**2, 0.0, 1.0)
    distance = np.hypot(*(a + share[:, None] * legs - np.asarray(position_m, dtype=float)[:2]).T)
    ahead = cumulative[1:] > at_least_m
    if not np.any(ahead):
        return float(cumulative[-1])
    leg = int(np.argmin(np.where(ahead, distance, np.inf)))
    return float(max(at_least_m, cumulative[leg] + share[leg] * lengths[leg]))


#: Most points of one reference horizon (the NMPC's horizon is at most 400 intervals).
MAX_HORIZON_STEPS = 10_000

class ReferencePathParticipant(Participant):
    """Publishes a timed reference trajectory; options in nm, kn and degrees.

    Options
    -------
    start_nm : [x, y]
        Start position (north, east) [nm] (straight line or turn).
    course_deg : float
        Initial course [deg] clockwise from north.
    turn_radius_nm : float, optional
        Constant-radius turn [nm]; > 0 starboard, < 0 port; absent: straight line.
    waypoints_nm : list of [x, y]
        Instead of start/course: a polyline sailed from its first point.
    goal_nm : [x, y]
        Instead of course or waypoints: with ``start_nm``, the shortest obstacle-free route
        from start to goal, planned once before departure (Offline-SPNC,
        :mod:`rhnc.routing.offline_route`) around the circles of ``avoid``.
    avoid : list of tables
        Static obstacles for ``goal_nm``: ``{ center_nm = [x, y], radius_nm = r }``.
    avoid_margin_nm : float
        Added to every radius in ``avoid`` (own hazard radius, a safety margin; default 0).
    speed_kn : float
        Speed along the path [kn].
    horizon_steps : int
        N, the reference has N + 1 points (default 15, the NMPC's N_c).
    interval_s : float
        Spacing of the points [s] (default: this participant's step size).
    start_deg, goal_deg, waypoints_deg : [lat, lon] or list of them
        Instead of ``start_nm``, ``goal_nm``, ``waypoints_nm``: latitude and longitude
        [deg], projected by the chart of option ``chart``.
    chart : str
        A chart file (relative to the scenario) whose projection puts the ``_deg``
        positions in the plane.  A path of waypoints (or start and goal) on a chart must
        keep its declared clearance from land and no-go areas along every leg; one that
        does not is refused, naming the option and the leg.
    max_lead_nm : float
        With ``waypoints_nm`` or ``goal_nm``: the virtual ship is never more than this far
        along the path ahead of the ship (inputs ``x``, ``y`` [m]); default: no limit, the
        timed schedule.
    """

    OPTIONS = ("start_nm", "course_deg", "turn_radius_nm", "waypoints_nm", "goal_nm", "avoid", "avoid_margin_nm",
               "speed_kn", "horizon_steps", "interval_s", "max_lead_nm", "chart", "start_deg", "goal_deg",
               "waypoints_deg")

    def __init__(self, name: str, path, horizon_steps: int, interval_s: float, start_time: float,
                 lead: tuple[np.ndarray, float, float] | None = None) -> None:
        super().__init__(name)
        self._path = path
        self.horizon_steps = horizon_steps
        self.interval_s = interval_s
        self._start_time = start_time
        #: (waypoints [m], speed [m/s], largest lead [m]) of a virtual ship that waits, or None
        self._lead = lead
        self._virtual_s = 0.0  # the virtual ship's sailing time along the path [s] (with a lead)
        self._ship_progress_m = 0.0
        self._last_time = start_time

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "ReferencePathParticipant":
        """Build from scenario options (see class docstring); errors name the key."""
        where = context.where
        reject_unknown_options(options, cls.OPTIONS, where)
        given = options
        options = projected_options(options, where, context.scenario_dir)
        if "speed_kn" not in options:
            raise ScenarioError(f"{where}: missing option 'speed_kn'")
        speed = _number(options, "speed_kn", where) * KNOT
        if speed <= 0.0:
            raise ScenarioError(f"{where}: option 'speed_kn' must be > 0")
        if "goal_nm" in options:
            waypoints = _planned_route(options, where)
        if "waypoints_nm" in options:
            if any(k in options for k in ("start_nm", "course_deg", "turn_radius_nm", "goal_nm")):
                raise ScenarioError(f"{where}: give either 'waypoints_nm', 'start_nm' + 'course_deg' "
                                    "or 'start_nm' + 'goal_nm'")
            waypoints = _points(options["waypoints_nm"], where, "waypoints_nm") * NM
        if "waypoints_nm" in options or "goal_nm" in options:
            if len(waypoints) < 2 or np.any(np.hypot(*np.diff(waypoints, axis=0).T) == 0.0):
                raise ScenarioError(f"{where}: option 'waypoints_nm' needs >= 2 distinct consecutive points")
            if isinstance(options.get("chart"), str) and options["chart"]:  # a route on a chart keeps its clearance
                key = next(k for k in ("waypoints_deg", "waypoints_nm", "goal_deg", "goal_nm") if k in given)
                refuse_route_inside_clearance(context.scenario_dir, options["chart"], waypoints, where, key)

            def path(elapsed):
                return waypoint_reference(elapsed, waypoints, speed)

        else:
            for key in ("start_nm", "course_deg"):
                if key not in options:
                    raise ScenarioError(f"{where}: missing option '{key}' (or give 'waypoints_nm')")
            start = _points([options["start_nm"]], where, "start_nm")[0] * NM
            course = math.radians(_number(options, "course_deg", where))
            radius = _number(options, "turn_radius_nm", where) * NM if "turn_radius_nm" in options else None

            def path(elapsed):
                return line_or_turn_reference(elapsed, start, course, speed, radius)

        horizon = options.get("horizon_steps", 15)
        if isinstance(horizon, bool) or not isinstance(horizon, int) or not 1 <= horizon <= MAX_HORIZON_STEPS:
            raise ScenarioError(f"{where}: option 'horizon_steps' must be an integer from 1 to {MAX_HORIZON_STEPS}")
        interval = _number(options, "interval_s", where) if "interval_s" in options else context.step_size
        if interval <= 0.0:
            raise ScenarioError(f"{where}: option 'interval_s' must be > 0")
        lead = None
        if "max_lead_nm" in options:
            if "waypoints_nm" not in options and "goal_nm" not in options:
                raise ScenarioError(f"{where}: option 'max_lead_nm' needs a path of waypoints ('waypoints_nm' or "
                                    "'goal_nm')")
            lead_m = _number(options, "max_lead_nm", where) * NM
            if lead_m <= 0.0:
                raise ScenarioError(f"{where}: option 'max_lead_nm' must be > 0")
            lead = (waypoints, speed, lead_m)
        return cls(name, path, horizon, interval, context.start_time, lead)

    @property
    def input_names(self) -> Sequence[str]:
        return ("x", "y") if self._lead is not None else ()

    @property
    def output_names(self) -> Sequence[str]:
        return ("reference",)

    def reference_at(self, time: float) -> np.ndarray:
        """The (N+1, 7) reference published at ``time`` [s]."""
        times = time + self.interval_s * np.arange(self.horizon_steps + 1)
        elapsed = (self._virtual_s if self._lead is not None else time - self._start_time) + (times - time)
        return np.column_stack([times, self._path(elapsed)])

    def _wait_for(self, time: float, inputs: Mapping[str, Value]) -> None:
        """Advance the virtual ship to ``time``, no farther than the lead ahead of the ship."""
        if self._lead is None:
            return
        missing = [name for name in ("x", "y") if name not in inputs]
        if missing:
            raise ModelError(f"{self.name}: option 'max_lead_nm' needs the inputs {', '.join(missing)} connected "
                             f"(the ship's position)")
        waypoints, speed, lead_m = self._lead
        self._ship_progress_m = path_progress_m(np.array([float(inputs["x"]), float(inputs["y"])]), waypoints,
                                                self._ship_progress_m)
        ahead = self._virtual_s + (time - self._last_time)
        self._virtual_s = max(self._virtual_s, min(ahead, (self._ship_progress_m + lead_m) / speed))
        self._last_time = time

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._start_time = self._last_time = start_time
        self._virtual_s = self._ship_progress_m = 0.0
        return {"reference": self.reference_at(start_time)}

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._wait_for(time, inputs)
        return {"reference": self.reference_at(time)}


def _planned_route(options: Mapping[str, Any], where: str) -> np.ndarray:
    """The shortest obstacle-free route [m] for ``start_nm`` + ``goal_nm`` + ``avoid``."""
    from rhnc.routing.offline_route import shortest_route

    if "start_nm" not in options or any(k in options for k in ("course_deg", "turn_radius_nm")):
        raise ScenarioError(f"{where}: option 'goal_nm' goes with 'start_nm' (and no 'course_deg')")
    start = _points([options["start_nm"]], where, "start_nm")[0] * NM
    goal = _points([options["goal_nm"]], where, "goal_nm")[0] * NM
    avoid = options.get("avoid", [])
    if not isinstance(avoid, list):
        raise ScenarioError(f"{where}: option 'avoid' must be a list of {{ center_nm, radius_nm }} tables")
    circles = []
    for i, entry in enumerate(avoid):
        if not isinstance(entry, Mapping):
            raise ScenarioError(f"{where}.avoid[{i}]: expected {{ center_nm = [x, y], radius_nm = r }}")
        reject_unknown_options(entry, ("center_nm", "radius_nm"), f"{where}.avoid[{i}]")
        centre = _points([entry.get("center_nm")], f"{where}.avoid[{i}]", "center_nm")[0]
        if "radius_nm" not in entry:
            raise ScenarioError(f"{where}.avoid[{i}]: missing 'radius_nm'")
        circles.append([*(centre * NM), _number(entry, "radius_nm", f"{where}.avoid[{i}]") * NM])
    margin = _number(options, "avoid_margin_nm", where) * NM if "avoid_margin_nm" in options else 0.0
    try:
        return shortest_route(start, goal, circles, margin)
    except ValueError as error:
        raise ScenarioError(f"{where}: {error}") from None


def _number(options: Mapping[str, Any], key: str, where: str) -> float:
    value = options[key]
    if not is_finite_number(value):
        raise ScenarioError(f"{where}: option '{key}' must be a finite number, got {value!r}")
    return float(value)


def _points(value: Any, where: str, key: str) -> np.ndarray:
    try:
        points = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ScenarioError(f"{where}: option '{key}' must be [x, y] pairs of numbers") from None
    if points.ndim != 2 or points.shape[1] != 2 or not np.all(np.isfinite(points)):
        raise ScenarioError(f"{where}: option '{key}' must be [x, y] pairs of numbers")
    return points
