"""Traffic situations in the maritime-schema JSON format (DNV's ``trafficgen``) as scenario overrides.

A traffic-situation file (``trafficgen gen-situation`` writes them; format version 0.2 of
the maritime-schema) holds an ``ownShip`` and ``targetShips``, each with an ``initial``
state (``position`` {lat, lon} in WGS-84 degrees, ``sog`` [kn], ``cog`` [deg]) and/or
``waypoints`` (each a ``position`` and a ``leg`` with its ``sog`` [kn]), and ``static``
particulars (``dimensions`` in metres).  Field names are camelCase.

What we read, per ship:

* the track: the waypoints, or the initial position alone;
* the speed over ground: ``initial.sog``, else the first waypoint's ``leg.sog``;
* the course: ``initial.cog``, else the direction of the first leg in the projected plane.

Positions are projected with pyproj onto a local **azimuthal equidistant** plane centred
on the own ship's start (WGS-84 ellipsoid): ranges and bearings from the own ship's
start are exact, and over the 10-30 nm of an encounter the distortion elsewhere is below
a metre.  ``x`` is north and ``y`` east, in nautical miles, shifted by ``origin_nm`` so
that the own ship starts where the base scenario wants it (inside its met-ocean map).

Ships keep their last leg's course and speed after their last waypoint (a target that
stopped there would turn into a static obstacle halfway through a run).  The hazard radius
R_i is not part of the format; the caller gives it.

Errors name the file and the field (``ownShip.waypoints[0].position.lat``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import KNOT, NM

#: A target's last leg is extended by this long a sail [h] so that it never stops.
EXTEND_LAST_LEG_H = 3.0


@dataclasses.dataclass(frozen=True)
class SituationShip:
    """One ship of a situation in the local plane.

    Attributes
    ----------
    name : str
    waypoints_nm : numpy.ndarray
        (k, 2) north, east [nm], k >= 1 (the first is the start).
    speed_kn : float
        Speed over ground [kn].
    course_deg : float
        Initial course over ground [deg from north].
    length_m, width_m : float or None
        Particulars, when the file gives them.
    """

    name: str
    waypoints_nm: np.ndarray
    speed_kn: float
    course_deg: float
    length_m: float | None = None
    width_m: float | None = None

    @property
    def start_nm(self) -> tuple[float, float]:
        return float(self.waypoints_nm[0, 0]), float(self.waypoints_nm[0, 1])

    @property
    def velocity_kn(self) -> tuple[float, float]:
        course = math.radians(self.course_deg)
        return self.speed_kn * math.cos(course), self.speed_kn * math.sin(course)


@dataclasses.dataclass(frozen=True)
class TrafficSituation:
    """A loaded situation: the own ship and the targets in the local plane [nm]."""

    path: Path
    title: str
    origin_lat_deg: float
    origin_lon_deg: float
    own_ship: SituationShip
    targets: tuple[SituationShip, ...]


class _Reader:
    """Field access that names the file and the field in every error."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def fail(self, field: str, problem: str) -> ScenarioError:
        return ScenarioError(f"{self.path}: '{field}': {problem}")

    def table(self, node: Any, key: str, where: str, required: bool = True) -> Mapping | None:
        field = f"{where}.{key}" if where else key
        if not isinstance(node, Mapping) or key not in node or node[key] is None:
            if required:
                raise self.fail(field, "missing field")
            return None
        if not isinstance(node[key], Mapping):
            raise self.fail(field, "expected an object")
        return node[key]

    def number(self, node: Any, key: str, where: str, low: float, high: float, required: bool = True) -> float | None:
        field = f"{where}.{key}"
        value = node.get(key) if isinstance(node, Mapping) else None
        if value is None:
            if required:
                raise self.fail(field, "missing field")
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise self.fail(field, f"expected a number, got {value!r}")
        if not low <= value <= high:
            raise self.fail(field, f"{value!r} is outside [{low:g}, {high:g}]")
        return float(value)


def load_traffic_situation(path, origin_nm: tuple[float, float] = (0.0, 0.0), projection=None) -> TrafficSituation:
    """Read a maritime-schema traffic-situation file into the local plane.

    Parameters
    ----------
    path : path-like
        The JSON file.
    origin_nm : (float, float)
        Where the own ship's start lands in the plane (north, east) [nm].
    projection : rhnc.chart.projection.LocalProjection, optional
        A passage's plane (its chart's): every position is put where that projection puts
        its latitude and longitude, and ``origin_nm`` is not used (a situation placed on a
        passage, rather than the own ship's start moved to ``origin_nm``).

    Raises
    ------
    ScenarioError
        For a missing file, invalid JSON, or a missing or malformed field (the message names
        the file and the field).
    """
    from pyproj import Transformer

    path = Path(path)
    reader = _Reader(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise ScenarioError(f"{path}: traffic-situation file not found") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: cannot read the traffic-situation file: {exc}") from None
    except json.JSONDecodeError as exc:
        raise ScenarioError(f"{path}: not valid JSON: {exc.msg} (line {exc.lineno}, column {exc.colno})") from None
    if not isinstance(data, Mapping):
        raise ScenarioError(f"{path}: expected a traffic situation (a JSON object with 'ownShip')")
    own = reader.table(data, "ownShip", "")
    assert own is not None  # a required table: the reader raises where it is missing
    own_raw = _raw_ship(reader, own, "ownShip")
    lat0, lon0 = own_raw["positions"][0]
    transformer = Transformer.from_crs(
        "EPSG:4326", f"+proj=aeqd +lat_0={lat0} +lon_0={lon0} +datum=WGS84 +units=m", always_xy=True)

    def plane(raw: dict, name: str, extend: bool) -> SituationShip:
        lats, lons = np.array(raw["positions"]).T
        if projection is not None:
            north, east = projection.to_local(lats, lons)
            points = np.column_stack([north, east]) / NM
        else:
            east, north = transformer.transform(lons, lats)
            points = np.column_stack([north, east]) / NM + np.asarray(origin_nm, dtype=float)
        if np.any(np.hypot(*np.diff(points, axis=0).T) < 1e-6):
            raise reader.fail(f"{raw['where']}.waypoints", "two consecutive waypoints at the same position")
        course = raw["cog"]
        if course is None:
            if len(points) < 2:
                raise reader.fail(f"{raw['where']}.initial.cog", "missing field (and no second waypoint to take "
                                                                 "the course from)")
            leg = points[1] - points[0]
            course = math.degrees(math.atan2(leg[1], leg[0])) % 360.0
        if extend and len(points) >= 2:
            last = points[-1] - points[-2]
            points = np.vstack([points, points[-1] + last / np.hypot(*last) * raw["sog"] * EXTEND_LAST_LEG_H])
        return SituationShip(name, points, raw["sog"], float(course), raw["length"], raw["width"])

    own_ship = plane(own_raw, _name(own, "own ship"), extend=False)
    targets_node = data.get("targetShips") or []
    if not isinstance(targets_node, list):
        raise reader.fail("targetShips", "expected a list of target ships")
    targets = []
    for i, node in enumerate(targets_node):
        where = f"targetShips[{i}]"
        if not isinstance(node, Mapping):
            raise reader.fail(where, "expected an object")
        targets.append(plane(_raw_ship(reader, node, where), _name(node, f"target {i + 1}"), extend=True))
    title_node = data.get("title")
    title = title_node if isinstance(title_node, str) else path.stem
    return TrafficSituation(path, title, lat0, lon0, own_ship, tuple(targets))


def _name(node: Mapping, default: str) -> str:
    static = node.get("static")
    name = static.get("name") if isinstance(static, Mapping) else None
    return name if isinstance(name, str) and name else default


def _raw_ship(reader: _Reader, node: Mapping, where: str) -> dict:
    """Positions (lat, lon) [deg], SOG [kn], COG [deg] or None, dimensions [m] or None."""
    initial = reader.table(node, "initial", where, required=False)
    waypoints = node.get("waypoints")
    positions = []
    first_leg_sog = None
    if waypoints:
        if not isinstance(waypoints, list):
            raise reader.fail(f"{where}.waypoints", "expected a list of waypoints")
        for k, waypoint in enumerate(waypoints):
            here = f"{where}.waypoints[{k}]"
            position = reader.table(waypoint, "position", here)
            positions.append((reader.number(position, "lat", f"{here}.position", -90.0, 90.0),
                              reader.number(position, "lon", f"{here}.position", -180.0, 180.0)))
        leg = reader.table(waypoints[0], "leg", f"{where}.waypoints[0]", required=False)
        first_leg_sog = reader.number(leg, "sog", f"{where}.waypoints[0].leg", 0.0, 60.0, required=False)
    elif initial is not None and "position" in initial:
        position = reader.table(initial, "position", f"{where}.initial")
        positions.append((reader.number(position, "lat", f"{where}.initial.position", -90.0, 90.0),
                          reader.number(position, "lon", f"{where}.initial.position", -180.0, 180.0)))
    else:
        raise reader.fail(f"{where}.initial.position", "missing field (and no 'waypoints')")
    sog = reader.number(initial, "sog", f"{where}.initial", 0.0, 60.0, required=False) if initial else None
    sog = sog if sog is not None else first_leg_sog
    if sog is None:
        raise reader.fail(f"{where}.initial.sog", "missing field (and no 'waypoints[0].leg.sog')")
    cog = reader.number(initial, "cog", f"{where}.initial", 0.0, 360.0, required=False) if initial else None
    static = node.get("static") if isinstance(node.get("static"), Mapping) else {}
    dimensions = static.get("dimensions") if isinstance(static.get("dimensions"), Mapping) else {}
    length = dimensions.get("length") if isinstance(dimensions.get("length"), (int, float)) else None
    width = dimensions.get("width") if isinstance(dimensions.get("width"), (int, float)) else None
    return {"where": where, "positions": positions, "sog": sog, "cog": cog, "length": length, "width": width}


def scenario_overrides(situation: TrafficSituation, scenario_data: Mapping, radius_nm: float,
                       route_nm: float, plant: str = "ship", traffic: str = "traffic") -> dict[str, Any]:
    """Dotted-key overrides that put a situation into a base scenario.

    * ``participants.<traffic>.options.targets``: each target sailing straight from its
      start (one course) or along its waypoints, radius ``radius_nm``;
    * ``participants.<plant>.parameters.x0``, ``y0`` [m], ``psi0`` [rad] and ``u0`` [m/s]:
      the own ship's start, initial course and speed;
    * every ``reference_path`` participant: ``start_nm``, ``course_deg``, ``speed_kn``;
    * every ``navigation`` participant: ``start_nm``, ``goal_nm`` and ``speed_kn``; every
      ``goal`` participant: ``goal_nm``.  The goal lies ``route_nm`` from the start along
      the own ship's route (its waypoints, then straight on along its last leg).

    Raises
    ------
    ScenarioError
        When the base scenario has no such plant or traffic participant.
    """
    participants = scenario_data.get("participants", {})
    for name, role in ((plant, "plant"), (traffic, "traffic")):
        if not isinstance(participants.get(name), Mapping):
            raise ScenarioError(f"{situation.path}: the base scenario has no participant '{name}' (the {role}); "
                                f"set 'situations.{role}'")
    own = situation.own_ship
    overrides: dict[str, Any] = {
        f"participants.{traffic}.options.targets": [target_entry(target, radius_nm) for target in situation.targets],
        f"participants.{plant}.parameters.x0": round(own.start_nm[0] * NM, 3),
        f"participants.{plant}.parameters.y0": round(own.start_nm[1] * NM, 3),
        f"participants.{plant}.parameters.psi0": round(math.radians(own.course_deg), 9),
        f"participants.{plant}.parameters.u0": round(own.speed_kn * KNOT, 9),
    }
    start = [round(own.start_nm[0], 6), round(own.start_nm[1], 6)]
    goal = [round(v, 6) for v in _along_route(own, route_nm)]
    for name, table in participants.items():
        kind = table.get("type") if isinstance(table, Mapping) else None
        prefix = f"participants.{name}.options"
        if kind == "reference_path":
            overrides.update({f"{prefix}.start_nm": start, f"{prefix}.course_deg": round(own.course_deg, 6),
                              f"{prefix}.speed_kn": own.speed_kn})
        elif kind == "navigation":
            overrides.update({f"{prefix}.start_nm": start, f"{prefix}.goal_nm": goal,
                              f"{prefix}.speed_kn": own.speed_kn})
        elif kind == "goal":
            overrides[f"{prefix}.goal_nm"] = goal
    return overrides


def target_entry(target: SituationShip, radius_nm: float) -> dict[str, Any]:
    """A traffic participant's ``targets`` entry for a situation's ship, radius ``radius_nm``."""
    if len(target.waypoints_nm) <= 2:  # one leg: constant velocity, never stops
        return {"start_nm": [round(v, 6) for v in target.start_nm],
                "velocity_kn": [round(v, 6) for v in target.velocity_kn], "radius_nm": radius_nm}
    return {"waypoints_nm": [[round(float(a), 6), round(float(b), 6)] for a, b in target.waypoints_nm],
            "speed_kn": target.speed_kn, "radius_nm": radius_nm}


def _along_route(ship: SituationShip, distance_nm: float) -> tuple[float, float]:
    """The point ``distance_nm`` along a ship's waypoints, straight on past the last one."""
    points = ship.waypoints_nm
    if len(points) < 2:
        course = math.radians(ship.course_deg)
        return (points[0, 0] + distance_nm * math.cos(course), points[0, 1] + distance_nm * math.sin(course))
    remaining = distance_nm
    for a, b in zip(points[:-1], points[1:]):
        length = float(np.hypot(*(b - a)))
        if remaining <= length:
            return tuple(a + (b - a) * remaining / length)
        remaining -= length
    a, b = points[-2], points[-1]
    return tuple(b + (b - a) / np.hypot(*(b - a)) * remaining)


def situation_document(ships: list[dict], title: str, description: str, latitude_deg: float = 57.0,
                       longitude_deg: float = 3.0) -> dict:
    """A maritime-schema traffic situation of ships sailing straight (the format this module reads).

    ``ships``: the own ship first, each a dict with ``start_nm`` (north, east) [nm] relative to
    the own ship's start, ``course_deg`` and ``speed_kn``.  Positions are written in WGS-84
    through the inverse of the azimuthal equidistant projection about the own ship's start
    at (``latitude_deg``, ``longitude_deg``).
    """
    from pyproj import Transformer

    to_geographic = Transformer.from_crs(
        f"+proj=aeqd +lat_0={latitude_deg} +lon_0={longitude_deg} +datum=WGS84 +units=m", "EPSG:4326",
        always_xy=True)

    def ship(entry: dict, identifier: int, name: str) -> dict:
        lon, lat = to_geographic.transform(entry["start_nm"][1] * NM, entry["start_nm"][0] * NM)
        return {"initial": {"position": {"lat": round(lat, 9), "lon": round(lon, 9)},
                            "sog": entry["speed_kn"], "cog": entry["course_deg"], "heading": entry["course_deg"]},
                "static": {"id": identifier, "name": name}}

    return {
        "schemaVersion": "0.2.0",
        "title": title,
        "description": description,
        "ownShip": ship(ships[0], 1, "own ship"),
        "targetShips": [ship(entry, k + 2, f"target {k + 1}") for k, entry in enumerate(ships[1:])],
    }
