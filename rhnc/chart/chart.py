"""A passage's chart: its local plane, the land and no-go areas to keep clear of, and the declared clearance.

A chart file (TOML, beside the scenario that names it) reads::

    origin_deg = [51.05, 1.45]            # latitude, longitude of x = y = 0 of the local plane
    clearance_nm = 1.0                    # the least distance kept from every area below
    land = "dover_strait.land.geojson"    # the coastline (scripts/make_passages.py, global-land-mask)
    no_go = ["dover_strait.no_go.geojson"]  # the user's own polygons: islands, restricted areas, lanes

Areas are GeoJSON polygons (``Polygon``/``MultiPolygon`` geometries, bare or in a
``Feature``/``FeatureCollection``; coordinates longitude, latitude in degrees, as GeoJSON
has them).  Each edge is cut into pieces of at most 1/120 deg before it is projected
(:mod:`rhnc.chart.projection`), so a long edge along a parallel keeps its curvature.  Paths
resolve against the chart file.  Every error names the file and the key (or the feature)
and says what would be valid.

Clearance is kept from the union of all areas: a point is *navigable* when it lies at least
``clearance_nm`` from every one of them, a straight leg when every point of it is
(:meth:`Chart.legs_clear`, the route search's test), and the distance of a leg to an area
is the least over the whole leg, not over its ends (:meth:`Chart.leg_distances_m`).
"""

from __future__ import annotations

import json
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from orchestrator.errors import ScenarioError
from orchestrator.geometry import NM, nearest_on_segments
from rhnc.chart.projection import LocalProjection

CHART_KEYS = ("origin_deg", "clearance_nm", "land", "no_go")
#: Longest piece of a polygon edge before projection [deg] (the coastline mask's cell).
EDGE_PIECE_DEG = 1.0 / 120.0


@dataclass(frozen=True)
class Area:
    """One area to keep clear of: its name, kind (``land`` or ``no_go``) and polygon in the plane [m]."""

    name: str
    kind: str
    geometry: Any  # shapely (Multi)Polygon, x north, y east [m]


@dataclass(frozen=True)
class Chart:
    """The local plane, the areas and the clearance of one passage.

    Attributes
    ----------
    projection : LocalProjection
    clearance_m : float
        Declared clearance [m] from every area.
    areas : tuple of Area
    source : str
        The chart file, for results.
    """

    projection: LocalProjection
    clearance_m: float
    areas: tuple[Area, ...]
    source: str = ""

    @property
    def hazard(self):
        """The union of all areas (shapely geometry, plane metres)."""
        import shapely

        return shapely.union_all([area.geometry for area in self.areas]) if self.areas else shapely.Polygon()

    def distances_m(self, north_m, east_m) -> np.ndarray:
        """Distance [m] of points to the nearest area (0 inside one; inf with no areas)."""
        import shapely

        points = shapely.points(np.asarray(north_m, dtype=float), np.asarray(east_m, dtype=float))
        hazard = self.hazard
        if hazard.is_empty:
            return np.full(np.shape(points), np.inf)
        return shapely.distance(points, hazard)

    def leg_distances_m(self, a, b, area: Area | None = None) -> np.ndarray:
        """Least distance [m] of each straight leg ``a[k] -> b[k]`` (arrays (n, 2), north, east [m])
        to ``area`` (default: the union of all areas); 0 where a leg touches or crosses it."""
        import shapely

        geometry = self.hazard if area is None else area.geometry
        legs = shapely.linestrings(np.stack([np.asarray(a, dtype=float), np.asarray(b, dtype=float)], axis=1))
        if geometry.is_empty:
            return np.full(len(legs), np.inf)
        return shapely.distance(legs, geometry)

    def legs_clear(self, a, b, distance_a=None, distance_b=None) -> np.ndarray:
        """Whether each straight leg keeps the declared clearance along its whole length.

        ``distance_a``, ``distance_b``: the ends' distances [m] when already known (the route
        search's nodes); legs whose ends are farther than the clearance plus half the leg
        are clear without a look at the polygons.  A leg that starts inside the clearance
        (a ship pushed there) is clear when it comes no closer than its start: the way out.
        """
        a = np.asarray(a, dtype=float).reshape(-1, 2)
        b = np.asarray(b, dtype=float).reshape(-1, 2)
        if not self.areas or len(a) == 0:
            return np.ones(len(a), dtype=bool)
        if distance_a is None:
            distance_a = self.distances_m(a[:, 0], a[:, 1])
        if distance_b is None:
            distance_b = self.distances_m(b[:, 0], b[:, 1])
        required = np.minimum(self.clearance_m, np.maximum(distance_a, 0.0) * (1.0 - 1e-9))
        ends = np.minimum(distance_a, distance_b)
        half = 0.5 * np.hypot(*(b - a).T)
        clear = ends >= required + half  # every point of a leg lies within half its length of an end
        doubtful = ~clear & (ends >= required)
        if np.any(doubtful):
            clear[doubtful] = self.leg_distances_m(a[doubtful], b[doubtful]) >= required[doubtful]
        return clear

    def to_geographic(self, north_m, east_m):
        """Latitude, longitude [deg] of plane positions [m]."""
        return self.projection.to_geographic(north_m, east_m)


class BoundaryIndex:
    """The edges of a chart's areas in a search tree: the nearest point of any area's edge to
    many positions at once (what the NMPC asks every control step near its predicted track).

    Parameters
    ----------
    chart : Chart
    """

    def __init__(self, chart: Chart) -> None:
        import shapely

        self.clearance_m = chart.clearance_m
        hazard = chart.hazard
        rings = [] if hazard.is_empty else [shapely.get_coordinates(ring) for polygon in shapely.get_parts(hazard)
                                            for ring in (polygon.exterior, *polygon.interiors)]
        self.a = np.concatenate([ring[:-1] for ring in rings]) if rings else np.zeros((0, 2))
        self.b = np.concatenate([ring[1:] for ring in rings]) if rings else np.zeros((0, 2))
        self.tree = shapely.STRtree(shapely.linestrings(np.stack([self.a, self.b], axis=1))) if rings else None
        self.hazard = hazard
        shapely.prepare(hazard)

    def nearest(self, points_m) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The nearest edge point (n, 2) [m] to each of ``points_m`` (n, 2) (north, east [m]), its
        distance [m] (inf without areas) and whether the position lies inside an area."""
        import shapely

        points = np.asarray(points_m, dtype=float).reshape(-1, 2)
        if self.tree is None:
            return np.full(points.shape, np.nan), np.full(len(points), np.inf), np.zeros(len(points), dtype=bool)
        pairs = self.tree.query_nearest(shapely.points(points), all_matches=False)
        edge = np.empty(len(points), dtype=int)
        edge[pairs[0]] = pairs[1]
        nearest, distance = nearest_on_segments(points, self.a[edge], self.b[edge])
        inside = shapely.contains_xy(self.hazard, points[:, 0], points[:, 1])
        return nearest, distance, inside


def load_chart(path) -> Chart:
    """Read a chart file (see the module's header); :class:`ScenarioError` naming file and key."""
    path = Path(path)
    if not path.is_file():
        raise ScenarioError(f"{path}: chart file not found")
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: not a TOML chart file: {exc}") from exc
    for key in table:
        if key not in CHART_KEYS:
            raise ScenarioError(f"{path}: unknown key '{key}' (valid: {', '.join(CHART_KEYS)})")
    origin = table.get("origin_deg")
    if (not isinstance(origin, list) or len(origin) != 2
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in origin)):
        raise ScenarioError(f"{path}: origin_deg: expected [latitude, longitude] in degrees, got {origin!r}")
    try:
        projection = LocalProjection(float(origin[0]), float(origin[1]))
    except ValueError as exc:
        raise ScenarioError(f"{path}: origin_deg: {exc}") from exc
    clearance = table.get("clearance_nm")
    if (not isinstance(clearance, (int, float)) or isinstance(clearance, bool) or not np.isfinite(clearance)
            or clearance < 0):
        raise ScenarioError(f"{path}: clearance_nm: expected a non-negative number of nautical miles, "
                            f"got {clearance!r}")
    areas: list[Area] = []
    if "land" in table:
        areas += read_areas(_file(table["land"], path, "land"), "land", projection)
    no_go = table.get("no_go", [])
    if not isinstance(no_go, list):
        raise ScenarioError(f"{path}: no_go: expected a list of GeoJSON files, got {no_go!r}")
    for k, name in enumerate(no_go):
        areas += read_areas(_file(name, path, f"no_go[{k}]"), "no_go", projection)
    return Chart(projection=projection, clearance_m=float(clearance) * NM, areas=tuple(areas), source=str(path))


def _file(name, chart_path: Path, key: str) -> Path:
    if not isinstance(name, str) or not name:
        raise ScenarioError(f"{chart_path}: {key}: expected the path of a GeoJSON file, got {name!r}")
    file = chart_path.parent / name
    if not file.is_file():
        raise ScenarioError(f"{chart_path}: {key}: GeoJSON file not found: {file}")
    return file


def read_areas(path: Path, kind: str, projection: LocalProjection) -> list[Area]:
    """The polygons of a GeoJSON file, projected; an error names the file and the feature."""
    import shapely
    from shapely.geometry import shape

    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError(f"{path}: not a GeoJSON file: {exc}") from exc
    if not isinstance(document, dict):
        raise ScenarioError(f"{path}: not a GeoJSON object")
    kind_of = document.get("type")
    features = (document.get("features") if kind_of == "FeatureCollection"
                else [document] if kind_of == "Feature" else [{"type": "Feature", "geometry": document}])
    if not isinstance(features, list):
        raise ScenarioError(f"{path}: features: expected a list of GeoJSON features")
    areas = []
    for k, feature in enumerate(features):
        geometry = feature.get("geometry") if isinstance(feature, dict) else None
        properties = (feature.get("properties") or {}) if isinstance(feature, dict) else {}
        label = str(properties.get("name", f"{path.stem} {k}"))
        where = f"{path}: feature {k} ({label})"
        kind_found = geometry.get("type") if isinstance(geometry, dict) else None
        if kind_found not in ("Polygon", "MultiPolygon"):
            raise ScenarioError(f"{where}: expected a Polygon or MultiPolygon geometry, got {kind_found}")
        try:
            polygon = shape(geometry)
        except (ValueError, TypeError, AttributeError, IndexError) as exc:
            raise ScenarioError(f"{where}: not a valid polygon: {exc}") from exc
        coordinates = shapely.get_coordinates(polygon)
        if coordinates.size == 0 or not np.all(np.isfinite(coordinates)) or np.any(np.abs(coordinates[:, 1]) > 90):
            raise ScenarioError(f"{where}: coordinates must be finite [longitude, latitude] in degrees")
        pieces = shapely.segmentize(polygon, EDGE_PIECE_DEG)
        projected = shapely.transform(pieces, lambda lonlat: np.column_stack(
            projection.to_local(lonlat[:, 1], lonlat[:, 0])))
        projected = shapely.make_valid(projected)
        areas.append(Area(name=label, kind=kind, geometry=projected))
    return areas
