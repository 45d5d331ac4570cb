"""One voyage geometry for every run of a comparison: ``[voyage]`` start, goal and arrival time.

A voyage comparison names its passage once (``[voyage] start_nm``, ``goal_nm`` and,
optionally, ``arrival_time_min``); :func:`geometry_overrides` turns it into the overrides
that give every participant of a run that passage:

* ``navigation``: ``start_nm``, ``goal_nm`` and, for the routing method, ``arrival_time_min``;
* ``goal``: ``goal_nm``;
* the plant (the participant whose ``x`` drives the goal monitor): its initial position at
  the start and its heading along the straight line to the goal, as its own start
  parameters (``x0``, ``y0``, ``psi0`` in SI units) when the scenario gives them there, else
  through the canonical ``[participants.<plant>.initial]`` table;
* ``reference_path``: a straight line (two waypoints, or ``start_nm`` with ``goal_nm`` or
  ``course_deg``) becomes the line from start to goal; a longer polyline must begin at the
  start and end at the goal.

An override in the comparison that sets one of these keys to another value is refused with
one line naming both (:func:`refuse_conflicts`); :func:`check_on_map` refuses a start or goal
outside the met-ocean map.  A goal on or near the map's edge has part of its arrival circle
off the map: :func:`edge_hold_nm` gives the band beyond the edges over which the runs then
hold the edge's weather (``[metocean] hold_edges_nm``), so a ship can sail anywhere in the
circle instead of failing there.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM

#: Two positions this close [m] (or headings [rad], or times [min]) are the same.
SAME = 1e-6
#: Beyond the arrival circle, the band [nm] a ship may still cross before its arrival is seen
#: (a step or two at speed, a minute at 30 kn).
EDGE_ALLOWANCE_NM = 0.5


def bearing_rad(start_m, goal_m) -> float:
    """Heading [rad, clockwise from north] of the straight line from ``start_m`` to ``goal_m``."""
    north, east = np.asarray(goal_m, dtype=float) - np.asarray(start_m, dtype=float)
    return math.atan2(east, north)


def geometry_overrides(loaded, start_m, goal_m, arrival_time_min: float | None, where: str) -> dict[str, Any]:
    """The overrides that give every participant of the loaded scenario this passage.

    Raises ScenarioError (naming ``where`` and the key) for a reference polyline that does
    not run from the start to the goal, which cannot be moved without changing its route.
    """
    start_nm = [float(v) for v in np.asarray(start_m, dtype=float) / NM]
    goal_nm = [float(v) for v in np.asarray(goal_m, dtype=float) / NM]
    heading = bearing_rad(start_m, goal_m)
    result: dict[str, Any] = {}
    for spec in loaded.participants:
        options = f"participants.{spec.name}.options"
        placed: dict[str, Any] = {}
        if spec.type == "navigation":
            placed[f"{options}.start_nm"] = start_nm
            placed[f"{options}.goal_nm"] = goal_nm
            if arrival_time_min is not None and spec.options.get("method", "routing") == "routing":
                placed[f"{options}.arrival_time_min"] = float(arrival_time_min)
        elif spec.type == "goal":
            placed[f"{options}.goal_nm"] = goal_nm
        elif spec.type == "reference_path":
            placed.update(_reference_path(_in_plane(spec, loaded.directory, where), options, start_nm, goal_nm,
                                          heading, where))
        result.update(_in_given_form(placed, spec, loaded.directory))
    plant = _plant(loaded)
    if plant is not None:
        result.update(_plant_start(plant, start_m, heading, _geographic_start(loaded, plant)))
    return result


def refuse_conflicts(geometry: Mapping[str, Any], overrides: Mapping[str, Any], where: str) -> None:
    """Refuse an override of the comparison that gives a geometry key another value."""
    for key, value in geometry.items():
        if key in overrides and not _same(overrides[key], value):
            raise ScenarioError(f"{where}: '{key}' = {overrides[key]!r} (set in the comparison) is not the "
                                f"[voyage] passage's {_rounded(value)!r}; leave it out or make [voyage] agree")


def check_on_map(field, start_m, goal_m, where: str) -> None:
    """Refuse a start or goal outside the met-ocean map ``field`` (a ship sent there would
    meet no weather; a goal on the edge is fine: a run stops as the ship arrives)."""
    x_min, x_max, y_min, y_max = field.extent
    for key, point in (("start_nm", start_m), ("goal_nm", goal_m)):
        if not bool(field.contains(point[0], point[1])):
            shown = [round(float(v) / NM, 6) for v in point]
            raise ScenarioError(f"{where}: voyage.{key} {shown} lies outside the met-ocean map (north "
                                f"{x_min / NM:g}..{x_max / NM:g} nm, east {y_min / NM:g}..{y_max / NM:g} nm)")


def edge_hold_nm(field, goal_m, arrival_radius_nm: float) -> float | None:
    """The band [nm] beyond the map's edges over which a run must hold the edge's weather
    so that the arrival circle about ``goal_m`` (and :data:`EDGE_ALLOWANCE_NM` beyond it)
    lies on the map; None when it already does."""
    x_min, x_max, y_min, y_max = field.extent
    north, east = (float(v) for v in goal_m)
    needed = arrival_radius_nm + EDGE_ALLOWANCE_NM
    nearest_nm = min(north - x_min, x_max - north, east - y_min, y_max - east) / NM
    return needed if nearest_nm < needed else None


def _in_plane(spec, directory, where: str) -> dict[str, Any]:
    """The participant's options with positions given in latitude and longitude in the plane."""
    from rhnc.chart.positions import projected_options

    return projected_options(spec.options, f"{where}: participants.{spec.name}.options", directory)


def _in_given_form(placed: Mapping[str, Any], spec, directory) -> dict[str, Any]:
    """``placed`` (keys ``...<name>_nm``) with each position the participant gives in latitude
    and longitude (``<name>_deg`` among its options) turned back into that form, through the
    chart its options name, so the run's file is overridden in the form it is written in."""
    result = {}
    for key, value in placed.items():
        prefix, _, last = key.rpartition(".")
        name = last[:-3] if last.endswith("_nm") else None
        if name is None or f"{name}_deg" not in spec.options:
            result[key] = value
            continue
        from rhnc.chart.positions import chart_projection

        projection = chart_projection(directory, spec.options["chart"])
        points = np.asarray(value, dtype=float).reshape(-1, 2) * NM
        lat, lon = projection.to_geographic(points[:, 0], points[:, 1])
        pairs = [[float(a), float(b)] for a, b in zip(lat, lon)]
        result[f"{prefix}.{name}_deg"] = pairs if np.ndim(value) == 2 else pairs[0]
    return result


def _reference_path(given: Mapping[str, Any], options: str, start_nm, goal_nm, heading: float,
                    where: str) -> dict[str, Any]:
    if "waypoints_nm" in given:
        points = given["waypoints_nm"]
        if isinstance(points, list) and len(points) == 2:
            return {f"{options}.waypoints_nm": [start_nm, goal_nm]}
        ends_match = (isinstance(points, list) and len(points) > 2
                      and _same(points[0], start_nm) and _same(points[-1], goal_nm))
        if not ends_match:
            first, last = (points[0], points[-1]) if isinstance(points, list) and points else (None, None)
            raise ScenarioError(f"{where}: {options}.waypoints_nm runs from {first} to {last}, not from the "
                                f"[voyage] start {start_nm} to its goal {goal_nm}")
        return {}
    result = {f"{options}.start_nm": start_nm}
    if "goal_nm" in given:
        result[f"{options}.goal_nm"] = goal_nm
    elif "turn_radius_nm" not in given:
        result[f"{options}.course_deg"] = math.degrees(heading) % 360.0
    return result


def _plant(loaded):
    """The FMU whose ``x`` the goal monitor reads (None: no such FMU)."""
    goals = {p.name for p in loaded.participants if p.type == "goal"}
    sources = {c.source for c in loaded.connections if c.target in goals and c.target_port == "x"}
    plants = [p for p in loaded.participants if p.name in sources and p.is_fmu]
    return plants[0] if len(plants) == 1 else None


def _plant_start(plant, start_m, heading: float, geographic: bool = False) -> dict[str, Any]:
    """The plant's initial x, y and heading: its own start parameters where the scenario sets
    them there (SI units, the built-in models' ``x0``, ``y0``, ``psi0``), else ``[initial]``."""
    values = {"x": float(start_m[0]), "y": float(start_m[1]), "psi": heading}
    initial_keys = {"x": ("x_m", "x_nm", NM), "y": ("y_m", "y_nm", NM), "psi": ("psi_rad", "psi_deg", math.pi / 180)}
    result: dict[str, Any] = {}
    initial: dict[str, float] = {}
    for port, value in values.items():
        mapped = plant.mapping.get(port)
        parameter = getattr(mapped, "start", None) or f"{port}0"
        si_key, unit_key, unit = initial_keys[port]
        if parameter in plant.parameters and mapped is None:
            result[f"participants.{plant.name}.parameters.{parameter}"] = value
        elif si_key in plant.initial:
            initial[si_key] = value
        else:
            initial[unit_key] = value / unit
    if geographic:  # the whole table, so that the voyage's start replaces start_deg (and its chart)
        result[f"participants.{plant.name}.initial"] = {**plant.initial, **initial}
    else:
        result.update({f"participants.{plant.name}.initial.{key}": value for key, value in initial.items()})
    return result


def _geographic_start(loaded, plant) -> bool:
    """True when the scenario file gives the plant's start in latitude and longitude (``[initial]``
    ``start_deg``), which the loaded spec holds already in the plane."""
    from orchestrator.toml_input import read_toml

    data, _ = read_toml(loaded.path, "scenario")
    table = data.get("participants", {}).get(plant.name, {}).get("initial", {})
    return isinstance(table, dict) and "start_deg" in table


def _same(a, b) -> bool:
    try:
        return bool(np.allclose(np.asarray(a, dtype=float), np.asarray(b, dtype=float), rtol=0.0, atol=SAME))
    except (TypeError, ValueError):
        return a == b


def _rounded(value):
    if isinstance(value, list):
        return [_rounded(v) for v in value]
    return round(value, 6) if isinstance(value, float) else value
