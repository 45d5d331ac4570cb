"""Positions given in latitude and longitude, projected into a passage's plane by its chart.

A participant's options may give a position either in the plane (``start_nm = [north, east]``
in nautical miles) or geographically (``start_deg = [latitude, longitude]`` in degrees), never
both: the geographic form is projected by the chart the same options name (``chart``), the
projection the chart, the weather and the results share (:mod:`rhnc.chart.projection`).
``waypoints_deg`` is a list of such pairs.  :func:`projected_options` returns the options with
every ``<name>_deg`` replaced by its ``<name>_nm``, so the participant reads one form.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM

#: How far inside the clearance a route's leg may come [m]: the rounding of positions in degrees.
ROUNDING_M = 1e-3
#: Positions that may be given either way: name -> whether it is a list of positions.
POSITIONS = {"start": False, "goal": False, "waypoints": True}


def projected_options(options: Mapping[str, Any], where: str, scenario_dir,
                      names: tuple[str, ...] = tuple(POSITIONS), chart: Any = None,
                      noun: str = "option") -> dict[str, Any]:
    """``options`` with each ``<name>_deg`` of ``names`` (of :data:`POSITIONS`) replaced by ``<name>_nm``.

    ``chart`` is the chart file's name when it is given elsewhere than among ``options``
    (the traffic's targets take their participant's); ``noun`` is what the messages call a
    key (``option``; ``key`` in a comparison's ``[voyage]``).

    Raises
    ------
    ScenarioError
        Both forms of one position given, a geographic one without ``chart``, or not
        ``[latitude, longitude]`` in degrees; the message names the key.
    """
    result = dict(options)
    given = [name for name in names if f"{name}_deg" in options]
    for name in names:
        if f"{name}_deg" in options and f"{name}_nm" in options:
            raise ScenarioError(f"{where}: give either {noun} '{name}_nm' or '{name}_deg', not both")
    if not given:
        return result
    chart = options.get("chart") if chart is None else chart
    if not isinstance(chart, str) or not chart:
        raise ScenarioError(f"{where}: {noun} '{given[0]}_deg' needs {noun} 'chart' (the chart file whose "
                            "projection puts latitude and longitude in the plane)")
    projection = chart_projection(scenario_dir, chart)
    for name in given:
        key = f"{name}_deg"
        pairs = _pairs(options[key], where, key, POSITIONS[name], noun)
        north, east = projection.to_local(pairs[:, 0], pairs[:, 1])
        plane = np.column_stack([north, east]) / NM
        result[f"{name}_nm"] = plane.tolist() if POSITIONS[name] else plane[0].tolist()
        del result[key]
    return result


def refuse_route_inside_clearance(scenario_dir, chart: str, waypoints_m, where: str, key: str) -> None:
    """Stop a route whose legs come within the chart's clearance of land or a no-go area.

    ``waypoints_m``: the route (k, 2), north and east [m]; ``key``: the option the user gave
    it in, named by the message.  The test is the route search's (:meth:`Chart.legs_clear`:
    every point of a leg, a leg from a start already inside the clearance allowed when it
    comes no closer), with a millimetre for the rounding of positions written in degrees.

    Raises
    ------
    ScenarioError
        One line naming ``key``, the first leg that comes too close and how close.
    """
    from rhnc.chart.chart import load_chart

    chart_file = load_chart(Path(scenario_dir) / chart)
    points = np.asarray(waypoints_m, dtype=float).reshape(-1, 2)
    clear = chart_file.legs_clear(points[:-1], points[1:])
    for leg in np.nonzero(~clear)[0]:
        distance = float(chart_file.leg_distances_m(points[leg:leg + 1], points[leg + 1:leg + 2])[0])
        if distance < chart_file.clearance_m - ROUNDING_M:
            raise ScenarioError(
                f"{where}: option '{key}': the leg from point {leg} to point {leg + 1} comes "
                f"{distance / NM:.3f} nm from land or a no-go area, inside the clearance of "
                f"{chart_file.clearance_m / NM:g} nm of chart '{chart}'")


def chart_projection(scenario_dir, chart: str):
    """The projection of the chart file ``chart`` (relative to ``scenario_dir``)."""
    from rhnc.chart.chart import load_chart

    return load_chart(Path(scenario_dir) / chart).projection


def geographic_pair(value: Any, where: str, key: str, noun: str = "option") -> tuple[float, float]:
    """``[latitude, longitude]`` [deg] checked; the message names ``key``."""
    lat, lon = _pairs(value, where, key, False, noun)[0]
    return float(lat), float(lon)


def _pairs(value: Any, where: str, key: str, many: bool, noun: str = "option") -> np.ndarray:
    expected = "a list of [latitude, longitude] pairs" if many else "[latitude, longitude]"
    try:
        pairs = np.asarray(value if many else [value], dtype=float)
    except (TypeError, ValueError):
        pairs = np.zeros((0, 0))
    if (pairs.ndim != 2 or pairs.shape[1:] != (2,) or len(pairs) == 0 or not np.all(np.isfinite(pairs))
            or np.any(np.abs(pairs[:, 0]) > 90.0) or np.any(np.abs(pairs[:, 1]) > 360.0)):
        raise ScenarioError(f"{where}: {noun} '{key}' must be {expected} in degrees, got {value!r}"[:300])
    return pairs


#: The plane keys of a plant's ``[initial]`` table that ``start_deg`` stands for.
PLANE_START_KEYS = ("x_m", "x_nm", "y_m", "y_nm")


def initial_in_plane(table: Mapping[str, Any], scenario_dir, where: str) -> dict[str, Any]:
    """A plant's ``[initial]`` table with ``start_deg = [lat, lon]`` projected by its ``chart``
    into ``x_m`` and ``y_m``, so the start reaches the plant's start parameters through its
    mapping whatever they are called (:func:`orchestrator.port_mapping.initial_start_values`).

    Raises
    ------
    ScenarioError
        ``start_deg`` beside a plane key, without ``chart``, or not ``[latitude, longitude]``;
        ``chart`` without ``start_deg``; the message names the key.
    """
    if "start_deg" not in table and "chart" not in table:
        return dict(table)
    if "start_deg" not in table:
        raise ScenarioError(f"{where}: key 'chart' places 'start_deg'; give start_deg = [latitude, longitude] "
                            "or drop 'chart'")
    for key in PLANE_START_KEYS:
        if key in table:
            raise ScenarioError(f"{where}: give either key '{key}' or 'start_deg', not both")
    chart = table.get("chart")
    if not isinstance(chart, str) or not chart:
        raise ScenarioError(f"{where}: key 'start_deg' needs key 'chart' (the chart file whose projection puts "
                            "latitude and longitude in the plane)")
    lat, lon = geographic_pair(table["start_deg"], where, "start_deg", "key")
    north, east = chart_projection(scenario_dir, chart).to_local(lat, lon)
    result = {key: value for key, value in table.items() if key not in ("start_deg", "chart")}
    result.update({"x_m": float(north), "y_m": float(east)})
    return result
