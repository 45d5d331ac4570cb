"""The ``[voyage]`` table of a comparison file, checked: start, goal, arrival, the baselines.

Errors name the comparison file and the key (``<file>: voyage.equal_arrival.systems: ...``);
:class:`rhnc.voyage.voyage_comparison.VoyageComparison` builds itself from what is read here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM
from orchestrator.participant import is_finite_number
from orchestrator.scenario import load_scenario

VOYAGE_KEYS = ("start_nm", "goal_nm", "start_deg", "goal_deg", "chart", "arrival_time_min", "arrival_radius_nm", "max_duration_h", "equal_arrival",
               "optimal_route")
EQUAL_ARRIVAL_KEYS = ("scenario", "speed_key", "systems", "max_trials", "same_control")
OPTIMAL_ROUTE_KEYS = ("resolution_nm", "avoid")


@dataclass(frozen=True)
class EqualArrivalSettings:
    """``[voyage.equal_arrival]``: which scenario, which speed key, for which systems."""

    scenario: Path
    speed_key: str
    systems: tuple[str, ...]
    max_trials: int = 8
    #: the baseline's control participant takes each system's control options (same NMPC
    #: settings on both sides of the comparison)
    same_control: bool = True


@dataclass(frozen=True)
class OptimalRouteSettings:
    """``[voyage.optimal_route]``: grid resolution [nm] and circles to avoid [m]."""

    resolution_nm: float = 0.5
    avoid_m: tuple[tuple[float, float, float], ...] = ()


def reject_unknown(table: Mapping[str, Any], allowed, where: str) -> None:
    for key in table:
        if key not in allowed:
            raise ScenarioError(f"{where}: unknown key '{key}' (valid: {', '.join(allowed)})")


def point(table: Mapping[str, Any], key: str, where: str) -> np.ndarray:
    value = table.get(key)
    if not isinstance(value, list) or len(value) != 2 or not all(is_finite_number(v) for v in value):
        other = f" (or {key[:-3]}_deg = [latitude, longitude] with chart)" if key in ("start_nm", "goal_nm") else ""
        raise ScenarioError(f"{where}.{key}: expected [north, east] in nm{other}, got {value!r}")
    return np.asarray(value, dtype=float)


def plane_positions(table: Mapping[str, Any], path: Path) -> dict[str, Any]:
    """``[voyage]`` with ``start_deg`` and ``goal_deg`` projected by its ``chart`` into
    ``start_nm`` and ``goal_nm`` (:mod:`rhnc.chart.positions`); errors name the key."""
    from rhnc.chart.positions import projected_options

    where = f"{path}: voyage"
    if "chart" in table and not any(f"{name}_deg" in table for name in ("start", "goal")):
        raise ScenarioError(f"{where}: key 'chart' places start_deg and goal_deg; give one of them, or drop 'chart'")
    result = projected_options(table, where, path.parent, ("start", "goal"), noun="key")
    result.pop("chart", None)
    return result


def positive(table: Mapping[str, Any], key: str, where: str, default: float) -> float:
    value = table.get(key, default)
    if not is_finite_number(value) or value <= 0:
        raise ScenarioError(f"{where}.{key}: expected a positive number, got {value!r}")
    return float(value)


def equal_arrival(table, path: Path, labels: tuple[str, ...], overrides: Mapping[str, Any]) -> EqualArrivalSettings:
    where = f"{path}: voyage.equal_arrival"
    if not isinstance(table, Mapping):
        raise ScenarioError(f"{where}: expected a table ([voyage.equal_arrival])")
    reject_unknown(table, EQUAL_ARRIVAL_KEYS, where)
    if not isinstance(table.get("scenario"), str):
        raise ScenarioError(f"{where}.scenario: expected the baseline scenario file (relative to the comparison)")
    scenario = path.parent / table["scenario"]
    if not scenario.is_file():
        raise ScenarioError(f"{where}.scenario: scenario file not found: {scenario}")
    systems = table.get("systems", list(labels))
    if not isinstance(systems, list) or not all(isinstance(s, str) for s in systems):
        raise ScenarioError(f"{where}.systems: expected a list of run labels")
    for label in systems:
        if label not in labels:
            raise ScenarioError(f"{where}.systems: '{label}' is not a run label ({', '.join(labels)})")
    trials = table.get("max_trials", 8)
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise ScenarioError(f"{where}.max_trials: expected a positive integer, got {trials!r}")
    same_control = table.get("same_control", True)
    if not isinstance(same_control, bool):
        raise ScenarioError(f"{where}.same_control: expected true or false, got {same_control!r}")
    speed_key = table.get("speed_key")
    if speed_key is None:
        loaded = load_scenario(scenario, dict(overrides))
        routes = [p for p in loaded.participants if p.type == "reference_path"]
        if len(routes) != 1:
            raise ScenarioError(f"{where}.speed_key: the baseline scenario has {len(routes)} reference_path "
                                "participants; name the reference speed's dotted key")
        speed_key = f"participants.{routes[0].name}.options.speed_kn"
    if not isinstance(speed_key, str) or not all(speed_key.split(".")):
        raise ScenarioError(f"{where}.speed_key: expected a dotted scenario key, got {speed_key!r}")
    return EqualArrivalSettings(scenario, speed_key, tuple(systems), trials, same_control)


def optimal_route(table, where: str) -> OptimalRouteSettings:
    if not isinstance(table, Mapping):
        raise ScenarioError(f"{where}: expected a table ([voyage.optimal_route])")
    reject_unknown(table, OPTIMAL_ROUTE_KEYS, where)
    resolution = positive(table, "resolution_nm", where, 0.5)
    avoid = table.get("avoid", [])
    if not isinstance(avoid, list):
        raise ScenarioError(f"{where}.avoid: expected a list of {{ center_nm = [x, y], radius_nm = r }}")
    circles = []
    for i, entry in enumerate(avoid):
        here = f"{where}.avoid[{i}]"
        if not isinstance(entry, Mapping):
            raise ScenarioError(f"{here}: expected {{ center_nm = [x, y], radius_nm = r }}")
        reject_unknown(entry, ("center_nm", "radius_nm"), here)
        centre = point(entry, "center_nm", here)
        radius: Any = entry.get("radius_nm")  # a TOML value, checked next
        if not is_finite_number(radius) or radius <= 0:
            raise ScenarioError(f"{here}.radius_nm: expected a positive number, got {radius!r}")
        circles.append((float(centre[0] * NM), float(centre[1] * NM), float(radius * NM)))
    return OptimalRouteSettings(resolution, tuple(circles))
