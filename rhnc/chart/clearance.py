"""Clearance of a sailed track from land and no-go areas: the least distance along the chords, where and when.

The track is the straight chords between consecutive samples (the ship's recorded
positions).  A chord that passes closer to an area than its ends is caught: the distance of
each chord is the least over its whole length (:meth:`rhnc.chart.chart.Chart.leg_distances_m`),
and the closest point is found on the chord itself, its time interpolated linearly between
the samples.  The result says whether the declared clearance was kept and whether the
track touched an area at all (``crossed``): a run that crossed land is never reported as fine.
"""

from __future__ import annotations

import numpy as np

from orchestrator.geometry import NM
from rhnc.chart.chart import Chart


def track_clearance(chart: Chart, time_s, north_m, east_m) -> dict:
    """Least distance of the track to each area and overall, with where and when.

    Parameters
    ----------
    chart : Chart
    time_s, north_m, east_m : array_like (n,)
        Sample times [s] and positions [m] of the track, n >= 1.

    Returns
    -------
    dict
        ``min_clearance_nm`` (overall), ``required_clearance_nm``, ``kept`` (the least
        distance is at least the declared clearance), ``crossed`` (the track touched or
        crossed an area), ``closest`` (``area``, ``kind``, ``time_s``, ``north_m``,
        ``east_m``, ``lat_deg``, ``lon_deg``) and ``per_area`` (name -> least distance [nm]).
    """
    import shapely
    from shapely.ops import nearest_points

    t = np.asarray(time_s, dtype=float)
    points = np.column_stack([np.asarray(north_m, dtype=float), np.asarray(east_m, dtype=float)])
    if points.ndim != 2 or len(points) == 0:
        raise ValueError("a track needs at least one sample")
    if len(points) == 1:
        points, t = np.vstack([points, points]), np.concatenate([t, t])
    a, b = points[:-1], points[1:]
    required_nm = chart.clearance_m / NM
    result = {"required_clearance_nm": required_nm, "chart": chart.source, "areas": len(chart.areas)}
    if not chart.areas:
        return {**result, "min_clearance_nm": float("inf"), "kept": True, "crossed": False, "closest": None,
                "per_area": {}}
    per_area, best = {}, None
    for area in chart.areas:
        distance = chart.leg_distances_m(a, b, area)
        k = int(np.argmin(distance))
        per_area[area.name] = float(distance[k]) / NM
        if best is None or distance[k] < best[0]:
            best = (float(distance[k]), k, area)
    distance_m, k, area = best
    chord = shapely.LineString([a[k], b[k]]) if np.any(a[k] != b[k]) else shapely.Point(a[k])
    length = float(np.hypot(*(b[k] - a[k])))
    if distance_m > 0.0 or length == 0.0:
        on_track = nearest_points(chord, area.geometry)[0]
        fraction = float(np.hypot(on_track.x - a[k][0], on_track.y - a[k][1])) / length if length > 0 else 0.0
    else:  # the chord enters the area: where it first does
        fraction = min(chord.project(shapely.Point(p)) for p in shapely.get_coordinates(
            chord.intersection(area.geometry))) / length
        on_track = chord.interpolate(fraction * length)
    when = float(t[k] + fraction * (t[k + 1] - t[k]))
    lat, lon = chart.to_geographic(on_track.x, on_track.y)
    closest = {"area": area.name, "kind": area.kind, "time_s": when, "north_m": float(on_track.x),
               "east_m": float(on_track.y), "lat_deg": float(lat), "lon_deg": float(lon)}
    min_nm = distance_m / NM
    return {**result, "min_clearance_nm": min_nm, "kept": bool(distance_m >= chart.clearance_m),
            "crossed": bool(distance_m <= 0.0), "closest": closest, "per_area": per_area}
