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

#: Positions that may be given either way: name -> whether it is a list of positions.
POSITIONS = {"start": False, "goal": False, "waypoints": True}


def projected_options(options: Mapping[str, Any], where: str, scenario_dir,
                      names: tuple[str, ...] = tuple(POSITIONS)) -> dict[str, Any]:
    """``options`` with each ``<name>_deg`` of ``names`` (of :data:`POSITIONS`) replaced by ``<name>_nm``.

    Raises
    ------
    ScenarioError
        Both forms of one position given, a geographic one without ``chart``, or not
        ``[latitude, longitude]`` in degrees; the message names the option.
    """
    result = dict(options)
    given = [name for name in names if f"{name}_deg" in options]
    for name in names:
        if f"{name}_deg" in options and f"{name}_nm" in options:
            raise ScenarioError(f"{where}: give either option '{name}_nm' or '{name}_deg', not both")
    if not given:
        return result
    if not isinstance(options.get("chart"), str) or not options["chart"]:
        raise ScenarioError(f"{where}: option '{given[0]}_deg' needs option 'chart' (the chart file whose "
                            "projection puts latitude and longitude in the plane)")
    from rhnc.chart.chart import load_chart

    projection = load_chart(Path(scenario_dir) / options["chart"]).projection
    for name in given:
        key = f"{name}_deg"
        pairs = _pairs(options[key], where, key, POSITIONS[name])
        north, east = projection.to_local(pairs[:, 0], pairs[:, 1])
        plane = np.column_stack([north, east]) / NM
        result[f"{name}_nm"] = plane.tolist() if POSITIONS[name] else plane[0].tolist()
        del result[key]
    return result


def _pairs(value: Any, where: str, key: str, many: bool) -> np.ndarray:
    expected = "a list of [latitude, longitude] pairs" if many else "[latitude, longitude]"
    try:
        pairs = np.asarray(value if many else [value], dtype=float)
    except (TypeError, ValueError):
        pairs = np.zeros((0, 0))
    if (pairs.ndim != 2 or pairs.shape[1:] != (2,) or len(pairs) == 0 or not np.all(np.isfinite(pairs))
            or np.any(np.abs(pairs[:, 0]) > 90.0) or np.any(np.abs(pairs[:, 1]) > 360.0)):
        raise ScenarioError(f"{where}: option '{key}' must be {expected} in degrees, got {value!r}"[:300])
    return pairs
