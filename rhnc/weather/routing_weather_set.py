"""The routing weather set: drawn gales, moving gales and current jets about any route and map.

The routing navigation is measured on weathers fixed before any of its results: member k
of the set drawn from ``seed`` is one of three kinds, in turn (``k % 3``):

* 0, a **gale**: :func:`rhnc.weather.weather_generators.storm_off_route` beside the route
  (:data:`GALE_DRAWS`);
* 1, a **moving gale**: a Holland vortex (:func:`rhnc.weather.weather_generators.cyclone`)
  that crosses the route near where and when a ship sailing it at ``nominal_speed_kn``
  passes (:data:`MOVING_GALE_DRAWS`), hourly steps over ``duration_h``;
* 2, a **current jet**: a band of current parallel to the route, off it or on it, with or
  against the passage, under a light uniform wind (:func:`current_jet`, :data:`JET_DRAWS`).

Everything is placed relative to ``route_start_nm`` -> ``route_goal_nm``, so the same set
serves any heading and map.  Each member draws from its own stream
``numpy.random.default_rng([seed, member])``, in the order of its table.  The tables were
fixed on 2026-11-26, before any routing result on them was seen (``docs/weather.md``).
The generator ``routing_set`` (:func:`rhnc.weather.weather_generators.routing_set`) builds a
member's field from :func:`routing_set_member`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from orchestrator.geometry import KNOT, NM
from rhnc.weather.metocean import MetOceanField, fetch_limited_hs
from rhnc.weather.metocean_grid import map_axis

#: Gale: as the storm set's draws, over a wider offset.
GALE_DRAWS = {
    "along_route": (0.25, 0.75),       # fraction of the route from start to goal
    "cross_route_nm": (-35.0, 35.0),   # to starboard (+) or port (-) of the route
    "radius_nm": (10.0, 30.0),
    "peak_wind_ms": (15.0, 28.0),
    "background_wind_ms": (4.0, 10.0),
    "wind_from_deg": (0.0, 360.0),
}
#: Moving gale: where it crosses the route, from which side, how fast, how strong.
MOVING_GALE_DRAWS = {
    "crossing_along_route": (0.3, 0.7),   # where the centre's track crosses the route
    "side": (-1.0, 1.0),                  # it comes from starboard (> 0) or port of the route
    "track_angle_deg": (-30.0, 30.0),     # its track against the route's normal
    "meeting_lag_h": (-1.5, 1.5),         # it crosses this long after the ship passes there
    "translation_kn": (5.0, 12.0),
    "max_wind_ms": (18.0, 28.0),
    "radius_max_wind_nm": (8.0, 20.0),
}
#: Current jet: a Gaussian band of current parallel to the route.
JET_DRAWS = {
    "offset_nm": (4.0, 20.0),          # distance of its core from the route
    "side": (-1.0, 1.0),               # to starboard (> 0) or port of the route
    "width_nm": (2.0, 6.0),            # Gaussian half-width (standard deviation)
    "peak_kn": (1.5, 3.0),             # current at the core
    "with_passage": (0.0, 1.0),        # below 0.75: it runs with the passage, else against it
    "background_wind_ms": (4.0, 10.0),
    "wind_from_deg": (0.0, 360.0),
}
KINDS = ("gale", "moving gale", "current jet")


def current_jet(x_range_nm=(0.0, 100.0), y_range_nm=(0.0, 100.0), resolution_nm: float = 1.0,
                route_start_nm=(0.0, 0.0), route_goal_nm=(100.0, 100.0), offset_nm: float = 12.0,
                width_nm: float = 4.0, peak_kn: float = 2.5, towards_goal: bool = True,
                background_wind_ms: float = 7.0, wind_from_deg: float = 45.0, fetch_km: float = 100.0,
                source: str = "generated: current_jet") -> MetOceanField:
    """A jet of current parallel to the route under a uniform wind.

    The current runs along the route's direction (or against it, ``towards_goal = False``)
    at ``peak_kn exp(-(d - offset)^2 / (2 w^2))``, with ``d`` the signed distance from the
    straight route (positive: to starboard looking from start to goal).

    Parameters
    ----------
    route_start_nm, route_goal_nm : (float, float)
        The straight route the jet follows, north and east [nm].
    offset_nm : float
        Signed distance of the jet's core from the route [nm] (positive: to starboard).
    width_nm : float
        w, the Gaussian half-width [nm].
    peak_kn : float
        Current at the core [kn].
    background_wind_ms, wind_from_deg : float
        The uniform wind [m/s] and where it comes from [deg].
    """
    if not width_nm > 0:
        raise ValueError(f"width_nm must be positive, got {width_nm}")
    if not peak_kn >= 0:
        raise ValueError(f"peak_kn must not be negative, got {peak_kn}")
    along, starboard = _route_frame(route_start_nm, route_goal_nm)
    x, y = map_axis(x_range_nm, resolution_nm), map_axis(y_range_nm, resolution_nm)
    north = x[:, None] / NM - route_start_nm[0]
    east = y[None, :] / NM - route_start_nm[1]
    cross_nm = north * starboard[0] + east * starboard[1]
    speed = peak_kn * KNOT * np.exp(-((cross_nm - offset_nm) ** 2) / (2.0 * width_nm ** 2))
    sense = 1.0 if towards_goal else -1.0
    shape = (x.size, y.size)
    wind = np.full(shape, float(background_wind_ms))
    towards = math.radians(wind_from_deg) + math.pi
    return MetOceanField(x, y, {
        "wind_north": wind * math.cos(towards), "wind_east": wind * math.sin(towards),
        "hs": fetch_limited_hs(wind, fetch_km * 1000.0),
        "current_north": sense * speed * along[0] * np.ones(shape),
        "current_east": sense * speed * along[1] * np.ones(shape),
    }, source=source)


def routing_set_member(seed: int, member: int, route_start_nm=(0.0, 0.0), route_goal_nm=(100.0, 100.0),
                       nominal_speed_kn: float = 18.0) -> tuple[str, dict[str, Any]]:
    """Kind and generator arguments of member ``member`` of the routing set from ``seed``."""
    if member < 0 or seed < 0:
        raise ValueError(f"seed and member must not be negative, got seed {seed}, member {member}")
    kind = KINDS[member % len(KINDS)]
    table = {"gale": GALE_DRAWS, "moving gale": MOVING_GALE_DRAWS, "current jet": JET_DRAWS}[kind]
    rng = np.random.default_rng([int(seed), int(member)])
    draw = {name: float(rng.uniform(low, high)) for name, (low, high) in table.items()}
    start = np.asarray(route_start_nm, dtype=float)
    along, starboard = _route_frame(route_start_nm, route_goal_nm)
    length = float(np.hypot(*(np.asarray(route_goal_nm, dtype=float) - start)))
    if kind == "gale":
        centre = start + draw["along_route"] * length * along + draw["cross_route_nm"] * starboard
        return kind, {"centre_nm": _point(centre),
                      **{k: round(draw[k], 6) for k in ("radius_nm", "peak_wind_ms", "background_wind_ms",
                                                        "wind_from_deg")}}
    if kind == "moving gale":
        side = 1.0 if draw["side"] > 0 else -1.0
        crossing = start + draw["crossing_along_route"] * length * along
        # its track: from the `side` of the route towards the other, turned by the drawn angle
        normal = -side * starboard
        angle = math.radians(draw["track_angle_deg"])
        track = np.array([normal[0] * math.cos(angle) - normal[1] * math.sin(angle),
                          normal[0] * math.sin(angle) + normal[1] * math.cos(angle)])
        crossing_h = draw["crossing_along_route"] * length / nominal_speed_kn + draw["meeting_lag_h"]
        centre = crossing - track * draw["translation_kn"] * crossing_h
        heading = math.degrees(math.atan2(track[1], track[0])) % 360.0
        return kind, {"centre_nm": _point(centre), "heading_deg": round(heading, 6),
                      "translation_kn": round(draw["translation_kn"], 6),
                      "max_wind_ms": round(draw["max_wind_ms"], 6),
                      "radius_max_wind_nm": round(draw["radius_max_wind_nm"], 6),
                      "duration_h": 16.0, "time_step_h": 1.0}
    side = 1.0 if draw["side"] > 0 else -1.0
    return kind, {"route_start_nm": tuple(float(v) for v in route_start_nm),
                  "route_goal_nm": tuple(float(v) for v in route_goal_nm),
                  "offset_nm": round(side * draw["offset_nm"], 6), "width_nm": round(draw["width_nm"], 6),
                  "peak_kn": round(draw["peak_kn"], 6), "towards_goal": draw["with_passage"] < 0.75,
                  "background_wind_ms": round(draw["background_wind_ms"], 6),
                  "wind_from_deg": round(draw["wind_from_deg"], 6)}


def _route_frame(start_nm, goal_nm) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors (north, east) along the route and to its starboard (right, looking ahead)."""
    along = np.asarray(goal_nm, dtype=float) - np.asarray(start_nm, dtype=float)
    length = float(np.hypot(*along))
    if not length > 0:
        raise ValueError("route_start_nm and route_goal_nm must differ")
    along = along / length
    return along, np.array([-along[1], along[0]])


def _point(p) -> tuple[float, float]:
    return (round(float(p[0]), 6), round(float(p[1]), 6))
