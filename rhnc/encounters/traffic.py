"""Target ships and static obstacles: publishes the ``obstacles`` port (x, y, vx, vy, radius; SI).

Targets sail at constant velocity from a start point, or along waypoints at constant
speed (stopping at the last one), or manoeuvre on a script, or replay a recorded track
(:mod:`rhnc.encounters.target_motion`), or give way and stand on by the rules of the road
(:mod:`rhnc.encounters.rule_following`); static obstacles are circles.  Options are in nautical
miles and knots.  The paper's Eq. 32 head-on target, ``x_T = y_T = 4 - 0.05 t`` nm with
t counted in 20 s steps, is ``start_nm = [4, 4]``, ``velocity_kn = [-9, -9]``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM
from orchestrator.participant import BuildContext, Participant, Value, is_finite_number, reject_unknown_options


TARGET_KEYS = ("start_nm", "start_deg", "velocity_kn", "waypoints_nm", "waypoints_deg", "speed_kn", "radius_nm", "manoeuvres", "track_file",
               "mmsi", "origin_deg", "time_offset_s", "behaviour", "alteration_deg", "give_way_tcpa_s",
               "turn_rate_deg_s")
#: The own ship's state, the inputs of a traffic with a target that reacts to it.
OWN_SHIP_INPUTS = ("x", "y", "psi", "u", "v")
#: Keys of a recorded track (``track_file`` and what goes with it).
RECORDED_KEYS = ("track_file", "mmsi", "origin_deg", "time_offset_s", "radius_nm")
STATIC_KEYS = ("center_nm", "radius_nm")


class Target:
    """A moving obstacle: constant velocity or a waypoint track, all SI inside.

    Parameters
    ----------
    waypoints_m : numpy.ndarray
        (k, 2) track [m]; with k = 1 the start of a constant-velocity target.
    velocity_mps : numpy.ndarray or None
        Constant velocity (vx, vy) [m/s] (k = 1), else None.
    speed_mps : float
        Speed along the waypoints [m/s] (k >= 2).
    radius_m : float
        Hazard radius [m].
    """

    def __init__(self, waypoints_m: np.ndarray, velocity_mps: np.ndarray | None, speed_mps: float, radius_m: float) -> None:
        self.waypoints_m = waypoints_m
        self.velocity_mps = velocity_mps
        self.speed_mps = speed_mps
        self.radius_m = radius_m
        if velocity_mps is None:
            legs = np.diff(waypoints_m, axis=0)
            self._leg_lengths = np.hypot(legs[:, 0], legs[:, 1])
            self._cumulative = np.concatenate([[0.0], np.cumsum(self._leg_lengths)])

    def state(self, elapsed_s: float) -> np.ndarray:
        """Row (x, y, vx, vy, radius) [m, m/s] at ``elapsed_s`` [s] after the start."""
        if self.velocity_mps is not None:
            position = self.waypoints_m[0] + self.velocity_mps * elapsed_s
            return np.r_[position, self.velocity_mps, self.radius_m]
        s = max(elapsed_s, 0.0) * self.speed_mps
        if s >= self._cumulative[-1]:
            return np.r_[self.waypoints_m[-1], 0.0, 0.0, self.radius_m]
        leg = int(np.searchsorted(self._cumulative, s, side="right") - 1)
        direction = (self.waypoints_m[leg + 1] - self.waypoints_m[leg]) / self._leg_lengths[leg]
        position = self.waypoints_m[leg] + direction * (s - self._cumulative[leg])
        return np.r_[position, direction * self.speed_mps, self.radius_m]


class TrafficParticipant(Participant):
    """Other ships and static obstacles of a scenario.

    Options
    -------
    targets : list of tables
        Each with ``radius_nm`` and either ``start_nm = [x, y]`` + ``velocity_kn = [vx, vy]``
        (optionally ``manoeuvres``, or ``behaviour = "rules"``), or ``waypoints_nm = [[x, y], ...]`` + ``speed_kn``, or
        ``track_file`` (+ ``mmsi``, ``origin_deg``, ``time_offset_s``).
        A target's ``start_nm`` or ``waypoints_nm`` may be given in latitude and longitude
        instead, ``start_deg = [lat, lon]`` or ``waypoints_deg = [[lat, lon], ...]``, projected
        by ``chart`` (:mod:`rhnc.chart.positions`).
    static_obstacles : list of tables
        Each with ``center_nm = [x, y]`` and ``radius_nm``.
    chart : str, optional
        A passage's chart file: its projection places the geographic positions of the targets
        and of ``situation``.
    situation : str, optional
        A traffic-situation file (trafficgen's maritime-schema JSON,
        :mod:`rhnc.encounters.traffic_situation`) whose target ships are placed on the passage
        by ``chart``, each where its latitude and longitude lie, after ``targets``; with
        ``situation_radius_nm``, their hazard radius [nm] (the format has none).
    target_behaviour : str, optional
        ``"rules"``: every constant-velocity target without its own ``behaviour`` or
        ``manoeuvres`` follows the rules of the road (so that a batch of traffic situations
        can make every ship autonomous).

    Outputs
    -------
    obstacles : (n, 5) array
        Targets first (in option order), then static obstacles: x, y [m], vx, vy [m/s],
        radius [m], at the step's time.
    target<i>_x, target<i>_y : float
        Position of target i (1-based) [m], for plots and analyses.
    targets : (n, 5) array
        The targets alone (what AIS and radar see).
    static_obstacles : (k, 5) array
        The static obstacles alone (charted: a target tracker passes them on as they are).
    """

    OPTIONS = ("targets", "static_obstacles", "target_behaviour", "chart", "situation", "situation_radius_nm")

    def __init__(self, name: str, targets: Sequence[Target], static: np.ndarray, start_time: float,
                 where: str | None = None) -> None:
        super().__init__(name)
        self.targets = list(targets)
        self.static = static
        self._start_time = start_time
        self._where = where or f"participants.{name}"

    @classmethod
    def from_options(cls, name: str, options: Mapping[str, Any], context: BuildContext) -> "TrafficParticipant":
        """Build from scenario options (see class docstring); errors name the key."""
        where = context.where
        reject_unknown_options(options, cls.OPTIONS, where)
        behaviour = options.get("target_behaviour")
        if behaviour is not None and behaviour != "rules":
            raise ScenarioError(f"{where}: 'target_behaviour' must be \"rules\" (every target follows the rules of "
                                f"the road), got {behaviour!r}")
        entries = _placed_targets(options, where, context)
        if behaviour is not None:
            entries = [{**entry, "behaviour": behaviour} if "start_nm" in entry and "behaviour" not in entry
                       and "manoeuvres" not in entry else entry for entry in entries]
        targets = [_target(entry, f"{where}.targets[{i}]", context) for i, entry in enumerate(entries)]
        static_rows = []
        for i, entry in enumerate(_tables(options, "static_obstacles", where)):
            here = f"{where}.static_obstacles[{i}]"
            reject_unknown_options(entry, STATIC_KEYS, here)
            center = _pair(entry, "center_nm", here) * NM
            static_rows.append([center[0], center[1], 0.0, 0.0, _radius(entry, here)])
        static = np.array(static_rows, dtype=float).reshape(-1, 5)
        return cls(name, targets, static, context.start_time, where)

    @property
    def input_names(self) -> Sequence[str]:
        """None, or the own ship's state when a target reacts to it (``behaviour = "rules"``)."""
        return OWN_SHIP_INPUTS if self._reactive else ()

    def connected(self, sources: Mapping[str, Participant]) -> None:
        """Refuse a reactive target that could not see the own ship (its state not connected)."""
        missing = [port for port in self.input_names if port not in sources]
        if missing:
            raise ScenarioError(f"{self._where}: targets with behaviour = \"rules\" react to the own ship; connect "
                                f"its state to {', '.join(f'{self.name}.{port}' for port in missing)}")

    @property
    def _reactive(self) -> list:
        return [target for target in self.targets if getattr(target, "reactive", False)]

    def _react(self, time: float, inputs: Mapping[str, Value]) -> None:
        """Reactive targets sail to ``time`` on their last decision, then decide on what they see now."""
        elapsed = time - self._start_time
        for target in self._reactive:
            target.advance(elapsed)
        missing = [port for port in OWN_SHIP_INPUTS if port not in inputs]
        if missing:
            return  # at set-up, before the ship has published its state
        psi, u, v = (float(inputs[port]) for port in ("psi", "u", "v"))
        own = np.array([float(inputs["x"]), float(inputs["y"]), u * math.cos(psi) - v * math.sin(psi),
                        u * math.sin(psi) + v * math.cos(psi), 0.0])
        rows = np.array([target.state(elapsed) for target in self.targets]).reshape(-1, 5)
        for i, target in enumerate(self.targets):
            if getattr(target, "reactive", False):
                target.decide(np.vstack([own[None, :], np.delete(rows, i, axis=0)]))

    @property
    def output_names(self) -> Sequence[str]:
        names = ["obstacles"]
        for i in range(1, len(self.targets) + 1):
            names += [f"target{i}_x", f"target{i}_y"]
        return names + ["targets", "static_obstacles"]

    def obstacles_at(self, time: float) -> np.ndarray:
        """The (n, 5) obstacle array at ``time`` [s]."""
        moving = [target.state(time - self._start_time) for target in self.targets]
        return np.vstack([np.array(moving).reshape(-1, 5), self.static])

    def _outputs(self, time: float) -> dict[str, Value]:
        obstacles = self.obstacles_at(time)
        outputs: dict[str, Value] = {"obstacles": obstacles, "targets": obstacles[:len(self.targets)].copy(),
                                     "static_obstacles": self.static.copy()}
        for i in range(len(self.targets)):
            outputs[f"target{i + 1}_x"] = float(obstacles[i, 0])
            outputs[f"target{i + 1}_y"] = float(obstacles[i, 1])
        return outputs

    def setup(self, start_time: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        self._start_time = start_time
        for target in self._reactive:
            target.reset()
        self._react(start_time, inputs)
        return self._outputs(start_time)

    def step(self, time: float, step_size: float, inputs: Mapping[str, Value]) -> dict[str, Value]:
        if self._reactive:
            self._react(time, inputs)
        return self._outputs(time)

    def tables(self) -> dict[str, list[dict[str, Any]]]:
        """``actions``: every decision of a rule-following target to give way or act as stand-on ship."""
        actions = [{"target": i + 1, **action} for i, target in enumerate(self.targets)
                   for action in getattr(target, "actions", [])]
        return {"actions": actions} if actions else {}


def _tables(options: Mapping[str, Any], key: str, where: str) -> list:
    entries = options.get(key, [])
    if not isinstance(entries, list) or not all(isinstance(e, Mapping) for e in entries):
        raise ScenarioError(f"{where}: option '{key}' must be a list of tables ([[...{key}]] or [{{...}}])")
    return entries


def _placed_targets(options: Mapping[str, Any], where: str, context: BuildContext) -> list:
    """The targets of ``targets`` and ``situation``, every position in the plane [nm]."""
    from rhnc.chart.positions import projected_options

    chart = options.get("chart")
    entries = [projected_options(entry, f"{where}.targets[{i}]", context.scenario_dir, ("start", "waypoints"),
                                 chart=chart if chart is not None else "")
               for i, entry in enumerate(_tables(options, "targets", where))]
    uses_chart = "situation" in options or any(f"{name}_deg" in entry for entry in _tables(options, "targets", where)
                                               for name in ("start", "waypoints"))
    if chart is not None and not uses_chart:
        raise ScenarioError(f"{where}: option 'chart' places geographic positions (targets' start_deg or "
                            "waypoints_deg, or 'situation'); give one, or drop 'chart'")
    if "situation_radius_nm" in options and "situation" not in options:
        raise ScenarioError(f"{where}: option 'situation_radius_nm' goes with option 'situation'")
    if "situation" not in options:
        return entries
    situation = options["situation"]
    if not isinstance(situation, str) or not situation:
        raise ScenarioError(f"{where}: option 'situation' must be the name of a traffic-situation file, "
                            f"got {situation!r}"[:300])
    if not isinstance(chart, str) or not chart:
        raise ScenarioError(f"{where}: option 'situation' needs option 'chart' (the chart file whose projection "
                            "places the situation's latitudes and longitudes on the passage)")
    radius = options.get("situation_radius_nm")
    if not is_finite_number(radius) or not radius >= 0:
        raise ScenarioError(f"{where}: option 'situation' needs 'situation_radius_nm', the targets' hazard radius "
                            f"[nm] >= 0, got {radius!r}"[:300])
    from rhnc.chart.positions import chart_projection
    from rhnc.encounters.traffic_situation import load_traffic_situation, target_entry

    placed = load_traffic_situation(context.scenario_dir / situation,
                                    projection=chart_projection(context.scenario_dir, chart))
    return entries + [target_entry(target, float(radius)) for target in placed.targets]


def _target(entry: Mapping[str, Any], where: str, context: BuildContext | None = None):
    reject_unknown_options(entry, TARGET_KEYS, where)
    radius = _radius(entry, where)
    if "track_file" in entry:
        from rhnc.encounters.target_motion import recorded_target

        reject_unknown_options(entry, RECORDED_KEYS, where)
        return recorded_target(entry, radius, context.scenario_dir if context else ".", where)
    for key in RECORDED_KEYS[1:-1]:
        if key in entry:
            raise ScenarioError(f"{where}: '{key}' goes with 'track_file'")
    if "waypoints_nm" in entry:
        if "start_nm" in entry or "velocity_kn" in entry:
            raise ScenarioError(f"{where}: give either 'waypoints_nm' + 'speed_kn' or 'start_nm' + 'velocity_kn'")
        for key in ("manoeuvres", "behaviour"):
            if key in entry:
                raise ScenarioError(f"{where}: '{key}' goes with 'start_nm' + 'velocity_kn', not 'waypoints_nm'")
        try:
            points = np.asarray(entry["waypoints_nm"], dtype=float) * NM
        except (TypeError, ValueError):
            points = np.empty((0,))
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2 or not np.all(np.isfinite(points)):
            raise ScenarioError(f"{where}: 'waypoints_nm' must be >= 2 [x, y] pairs of numbers")
        if np.any(np.hypot(*np.diff(points, axis=0).T) == 0.0):
            raise ScenarioError(f"{where}: 'waypoints_nm' has two equal consecutive points")
        speed = entry.get("speed_kn")
        if not is_finite_number(speed) or not speed > 0:
            raise ScenarioError(f"{where}: 'speed_kn' must be a number > 0 with 'waypoints_nm'")
        return Target(points, None, float(speed) * KNOT, radius)
    for key in ("start_nm", "velocity_kn"):
        if key not in entry:
            raise ScenarioError(f"{where}: missing '{key}' (or give 'waypoints_nm' + 'speed_kn')")
    if "speed_kn" in entry:
        raise ScenarioError(f"{where}: 'speed_kn' goes with 'waypoints_nm'; use 'velocity_kn' = [vx, vy]")
    start = _pair(entry, "start_nm", where) * NM
    velocity = _pair(entry, "velocity_kn", where) * KNOT
    if "behaviour" in entry or any(key in entry for key in ("alteration_deg", "give_way_tcpa_s", "turn_rate_deg_s")):
        from rhnc.encounters.rule_following import rule_following_target

        if "manoeuvres" in entry:
            raise ScenarioError(f"{where}: give either 'manoeuvres' (a script) or 'behaviour' (a reactive target)")
        return rule_following_target(entry, start, velocity, radius, where)
    if "manoeuvres" in entry:
        from rhnc.encounters.target_motion import scripted_target

        duration = (context.stop_time - context.start_time) if context else 0.0
        return scripted_target(start, velocity, entry["manoeuvres"], radius, duration, where)
    return Target(start[None, :], velocity, float(np.hypot(*velocity)), radius)


def _pair(entry: Mapping[str, Any], key: str, where: str) -> np.ndarray:
    value = entry.get(key)
    ok = isinstance(value, (list, tuple)) and len(value) == 2
    ok = ok and all(not isinstance(v, bool) and isinstance(v, (int, float)) and math.isfinite(v) for v in value)
    if not ok:
        raise ScenarioError(f"{where}: '{key}' must be a pair of numbers [x, y], got {value!r}")
    return np.array(value, dtype=float)


def _radius(entry: Mapping[str, Any], where: str) -> float:
    value = entry.get("radius_nm")
    if not is_finite_number(value) or not value >= 0:
        raise ScenarioError(f"{where}: 'radius_nm' must be a finite number >= 0, got {value!r}"[:300])
    return float(value) * NM
